"""The parameters of a LuGre-type friction site: a Stribeck branch per direction and the
bristle σ0, σ1 (Wang2021 Table 1).  The class of the ``lugre``, ``stribeck``, ``dahl`` and
``none`` laws' sites (:attr:`feeddrive.model.friction.FrictionLaw.parameters_class`); GMS
keeps its own class beside its law (:mod:`feeddrive.model.friction.gms`).

Sources: the LuGre model of C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky,
"A new model for control of systems with friction", IEEE Trans. Autom. Control 40 (1995)
419–425, with the values of Z. Wang, X. Feng, H. Yang, H. Jin, "Research on low-speed
characteristics of differential double-drive feed system", Mech. Sci. 12 (2021) 791–800,
Table 1.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ... import registry
from ...parameters import Component, ParameterError, SiteParameters
from ...parameters.validation import quantity


@dataclass(frozen=True)
class FrictionBranch(Component):
    """One direction of a LuGre/Stribeck friction law, as magnitudes.  Wang2021 Table 1.

    Table 1 prints the negative branch with minus signs on F_c, F_s and v_s; here every branch
    is stored as magnitudes and the sign comes from the direction of motion.

    Parameters
    ----------
    coulomb_force : float
        Coulomb (sliding) friction F_c, magnitude [N].
    static_force : float
        Breakaway (static) friction F_s ≥ F_c, magnitude [N].
    stribeck_velocity : float
        Stribeck velocity v_s, magnitude [m/s].
    viscous_coefficient : float
        Viscous coefficient σ2 [N s/m].

    References
    ----------
    .. [1] Wang2021 Table 1.
    """

    coulomb_force: float = quantity(
        "N", low=0, high=1e5, hint="give the magnitude; the sign comes from the branch"
    )
    static_force: float = quantity(
        "N", low=0, high=1e5, hint="give the magnitude; the sign comes from the branch"
    )
    stribeck_velocity: float = quantity(
        "m/s", low=1e-7, high=0.1, hint="give the magnitude in m/s (1 mm/s = 0.001 m/s)"
    )
    viscous_coefficient: float = quantity("N s/m", low=0, high=1e7, low_inclusive=True)
    _label = "friction_branch"

    def _check(self) -> None:
        if self.static_force < self.coulomb_force:
            raise ParameterError(
                f"{self._label}.static_force",
                self.static_force,
                f"F_s must be ≥ F_c = {self.coulomb_force} [N] "
                "(breakaway exceeds sliding friction)",
            )


@dataclass(frozen=True)
class LuGreParameters(SiteParameters):
    """LuGre friction at one site, linear (force) form.  Wang2021 Eqs. (9)–(11), Table 1.

    Rotary sites (screw and hollow shafts) are stored as the paper does: torques divided by
    H = p_h/2π, angles multiplied by H, so forces in N and speeds in m/s of the equivalent
    nut/table motion.  σ0 and σ1 are shared by both branches, as in Table 1.

    Parameters
    ----------
    positive : FrictionBranch
        The + branch (v ≥ 0).
    negative : FrictionBranch
        The − branch, as magnitudes.
    bristle_stiffness : float
        σ0 [N/m].
    bristle_damping : float
        σ1 [N s/m].
    law : str, default "lugre"
        The site's friction law (``"lugre"``, ``"stribeck"``, ``"dahl"``, ``"none"``).
    smoothing_velocity : float, default 1e-6
        Sign-function smoothing v_ε of the static law only [m/s].

    References
    ----------
    .. [1] Wang2021 Eqs. (9)–(11), Table 1.
    .. [2] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    """

    positive: FrictionBranch
    negative: FrictionBranch
    bristle_stiffness: float = quantity("N/m", low=0, high=1e12)
    bristle_damping: float = quantity("N s/m", low=0, high=1e8, low_inclusive=True)
    law: str = "lugre"
    smoothing_velocity: float = quantity(
        "m/s", low=0, high=0.1, default=1e-6,
        hint="sign-function smoothing of the static law only; 1 µm/s = 1e-6 m/s")
    _label = "friction"

    def _check(self) -> None:
        if not isinstance(self.law, str):
            raise ParameterError(f"{self._label}.law", self.law, "expected a law name")
        laws = registry.table(registry.FRICTION_LAWS)
        if self.law not in laws:
            raise ParameterError(f"{self._label}.law", self.law,
                                 f"unknown friction law; expected one of {', '.join(laws)}")
        own = getattr(laws[self.law], "parameters_class", None)
        if own is not LuGreParameters:
            own_name = getattr(own, "__name__", own)
            raise ParameterError(f"{self._label}.law", self.law,
                                 f"this law takes the parameters of {own_name}, not "
                                 "LuGre's (give the site's table in that form)")

    def mismatched(self, coulomb: float, static: float, stribeck_velocity: float,
                   viscous: float) -> LuGreParameters:
        """The site as a compensator with model errors sees it: F_c, F_s, v_s and σ2 of both
        branches times the given factors (σ0, σ1 unchanged).

        Parameters
        ----------
        coulomb : float
            Factor on F_c [-].
        static : float
            Factor on F_s [-].
        stribeck_velocity : float
            Factor on v_s [-].
        viscous : float
            Factor on σ2 [-].

        Returns
        -------
        LuGreParameters
            The mismatched site.
        """
        def br(b: FrictionBranch) -> FrictionBranch:
            return replace(b, coulomb_force=b.coulomb_force * coulomb,
                           static_force=b.static_force * static,
                           stribeck_velocity=b.stribeck_velocity * stribeck_velocity,
                           viscous_coefficient=b.viscous_coefficient * viscous)
        return replace(self, positive=br(self.positive), negative=br(self.negative))

    def scaled(self, factor: float) -> LuGreParameters:
        """This site with every force and coefficient times ``factor`` (0 < factor ≤ 1); the
        Stribeck velocities and the bristle dynamics (z, ż) are unchanged, the force scales.

        Parameters
        ----------
        factor : float
            The share of the site's friction, 0 < factor ≤ 1 [-].

        Returns
        -------
        LuGreParameters
            The scaled site.
        """
        def br(b: FrictionBranch) -> FrictionBranch:
            return replace(b, coulomb_force=b.coulomb_force * factor,
                           static_force=b.static_force * factor,
                           viscous_coefficient=b.viscous_coefficient * factor)
        return replace(self, positive=br(self.positive), negative=br(self.negative),
                       bristle_stiffness=self.bristle_stiffness * factor,
                       bristle_damping=self.bristle_damping * factor)

    def as_array(self) -> np.ndarray:
        """Pack as float64[10]: (F_c, F_s, v_s, σ2) for +, then −, then σ0, σ1.

        Returns
        -------
        numpy.ndarray
            The ten values [SI, per slot].
        """
        p, n = self.positive, self.negative
        return np.array(
            [
                p.coulomb_force, p.static_force, p.stribeck_velocity, p.viscous_coefficient,
                n.coulomb_force, n.static_force, n.stribeck_velocity, n.viscous_coefficient,
                self.bristle_stiffness, self.bristle_damping,
            ],
            dtype=np.float64,
        )

    def branch(self, name: str) -> FrictionBranch:
        """One direction branch by name.

        Parameters
        ----------
        name : str
            ``"positive"`` or ``"negative"``.

        Returns
        -------
        FrictionBranch
            The branch.

        Raises
        ------
        ParameterError
            For another name.
        """
        if name not in ("positive", "negative"):
            raise ParameterError("branch", name, "expected positive or negative")
        return self.positive if name == "positive" else self.negative
