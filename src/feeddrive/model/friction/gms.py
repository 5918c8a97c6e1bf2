"""Generalized Maxwell-slip (GMS) friction: N elementary slip blocks in parallel.

Al-Bender, Lampaert & Swevers, "The generalized Maxwell-slip model: a novel model for friction
simulation and compensation", IEEE Trans. Autom. Control 50 (2005) 1883–1887.  Element i has
a stiffness k_i [N/m], a weight α_i (Σα_i = 1) and a deflection δ_i [m] (force F_i = k_i·δ_i):

    sticking:  dδ_i/dt = v
    slipping:  dF_i/dt = sgn(v)·C·(α_i − F_i / s(v))          (s(v) signed)
    F = Σ_i F_i + σ2·v,   s(v) = sgn(v)·(F_c + (F_s − F_c)·exp(−(v/v_s)²))

An element slips once its force in the direction of motion has reached its share of the
Stribeck curve, F_i·sgn(v) ≥ α_i·|s(v)| (less a small ``slip_margin``, see
:class:`GMSParameters`), and sticks again when the motion reverses; C [N/s]
is the attraction rate of a slipping element to α_i·s(v).  In steady sliding every element
slips at α_i·s(v), so the steady force is the Stribeck curve plus viscous friction; under slow
motion the pre-sliding force follows the elastoplastic (Masing) hysteresis of the elements —
the virgin curve F(x) = Σ min(k_i·x, α_i·F_s) and, after a reversal at (x_r, F_r),
F = F_r − Σ min(k_i·|x − x_r|, 2α_i·F_s)·sgn(x_r − x) (Al-Bender et al. 2005, Sect. II).

The element states are the deflections (position tolerance, like the LuGre bristle).  The
right-hand side switches at each element's slip limit; an integrator with error control steps
onto it, as onto the sampled controller's breakpoints.  At v = 0 it switches for every element
at once: a slipping element's rate jumps from sgn(v)·C·(α_i − F_i/s(v))/k_i to 0 and the
direction branch (F_c, F_s, v_s, σ2) changes, so the law declares ``kink_at_zero_speed`` and
the dense-output methods land on each reversal (:mod:`feeddrive.solvers.events`); a sticking
element's rate is the sliding speed (dδ_i/dt = v at δ = 0), the row those events read.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..._jit import kernel
from ...parameters import ParameterError, SiteParameters
from ...parameters.validation import quantities, quantity
from .base import FrictionLaw, LinearFriction, register_friction_law
from .lugre import NEGATIVE, SLOTS, VISCOUS, branch, stribeck_magnitude
from .lugre_parameters import FrictionBranch

# the block: the Stribeck branches (LuGre's first 8 slots), then C, the slip margin, N,
# k_1..k_N, α_1..α_N
ATTRACTION = NEGATIVE + 4
MARGIN = ATTRACTION + 1
COUNT = MARGIN + 1
FIRST = COUNT + 1
MAX_ELEMENTS = 64


@dataclass(frozen=True)
class GMSParameters(SiteParameters):
    """Parameters of a GMS friction site (``law = "gms"``).

    Parameters
    ----------
    positive : FrictionBranch
        Stribeck curve of the + direction: F_c, F_s [N], v_s [m/s], σ2 [N s/m].
    negative : FrictionBranch
        Stribeck curve of the − direction (magnitudes).
    attraction : float
        Attraction rate C of a slipping element to its share of the Stribeck curve [N/s].
    element_stiffness : tuple of float
        Stiffness k_i of each element [N/m].
    element_weight : tuple of float
        Weight α_i of each element in the Stribeck force [-]; they sum to 1.
    slip_margin : float, default 1e-3
        An element starts to slip at (1 − margin) of its share of the Stribeck force [-]
        and is then attracted to it at rate C: the steady slip force lies inside the slip
        region rather than on its edge, so the integrator does not chatter across the switch
        in steady sliding (0: the switch exactly at the limit).  The pre-sliding force
        deviates from the exact elastoplastic curve by at most this fraction.
    law : str, default "gms"
        The law (always ``"gms"`` for this class).
    """

    positive: FrictionBranch
    negative: FrictionBranch
    attraction: float = quantity("N/s", low=0, high=1e12,
                                 hint="C of dF_i/dt = sgn(v)·C·(α_i − F_i/s(v))")
    element_stiffness: tuple[float, ...] = quantities("N/m", low=0, high=1e12,
                                                      hint="1 N/µm = 1e6 N/m")
    element_weight: tuple[float, ...] = quantities("-", low=0, high=1)
    slip_margin: float = quantity("-", low=0, high=0.1, low_inclusive=True, default=1e-3,
                                  hint="a fraction of each element's slip force")
    law: str = "gms"
    _label = "friction"

    def _check(self) -> None:
        if self.law != "gms":
            raise ParameterError(f"{self._label}.law", self.law, "expected gms for a GMS site")
        n = len(self.element_stiffness)
        if not 1 <= n <= MAX_ELEMENTS:
            raise ParameterError(f"{self._label}.element_stiffness", self.element_stiffness,
                                 f"expected 1 to {MAX_ELEMENTS} elements [N/m]")
        if len(self.element_weight) != n:
            raise ParameterError(f"{self._label}.element_weight", self.element_weight,
                                 f"expected {n} weights, one per element stiffness")
        if abs(math.fsum(self.element_weight) - 1.0) > 1e-9:
            raise ParameterError(f"{self._label}.element_weight", self.element_weight,
                                 "expected weights that sum to 1 [-]")

    def scaled(self, factor: float) -> GMSParameters:
        """This site with every force, stiffness and rate times ``factor`` (0 < factor ≤ 1):
        the deflections are unchanged, the force scales.

        Parameters
        ----------
        factor : float
            The share of the site's friction [-].

        Returns
        -------
        GMSParameters
            The scaled site.
        """
        def br(b: FrictionBranch) -> FrictionBranch:
            return b.with_values(coulomb_force=b.coulomb_force * factor,
                                 static_force=b.static_force * factor,
                                 viscous_coefficient=b.viscous_coefficient * factor)
        return self.with_values(positive=br(self.positive), negative=br(self.negative),
                                element_stiffness=tuple(k * factor
                                                        for k in self.element_stiffness),
                                attraction=self.attraction * factor)


@kernel
def gms_kernel(v: float, y: np.ndarray, k: int, P: np.ndarray, o: int,
               dy: np.ndarray) -> float:
    """Kernel of the GMS law: N elements that stick (dδ_i/dt = v) or slip toward α_i·s(v).

    An element slips once F_i·sgn(v) ≥ (1 − margin)·α_i·|s(v)|; the force is Σ k_i·δ_i + σ2·v.

    Parameters
    ----------
    v : float
        Sliding speed [m/s].
    y : numpy.ndarray
        The model's state vector; this law's states are ``y[k : k + n_states]`` [m].
    k : int
        Index of the law's first state in ``y``.
    P : numpy.ndarray
        The model's packed parameter vector [SI, per slot].
    o : int
        Offset of this site's parameter block in ``P``.
    dy : numpy.ndarray
        The state-rate vector; the kernel writes its states' rates at ``dy[k : k + n_states]``
        [m/s].

    Returns
    -------
    float
        Friction force [N].

    References
    ----------
    .. [1] F. Al-Bender, V. Lampaert, J. Swevers, "The generalized Maxwell-slip model: a
       novel model for friction simulation and compensation", IEEE Trans. Autom. Control
       50 (2005) 1883–1887.
    """
    n = int(P[o + COUNT])
    s = stribeck_magnitude(v, P, o)
    sgn = 1.0 if v >= 0.0 else -1.0
    c = P[o + ATTRACTION]
    onset = 1.0 - P[o + MARGIN]
    force = 0.0
    for i in range(n):
        k_i = P[o + FIRST + i]
        a_i = P[o + FIRST + n + i]
        f_i = k_i * y[k + i]
        if v != 0.0 and f_i * sgn >= onset * a_i * s:
            dy[k + i] = sgn * c * (a_i - f_i * sgn / s) / k_i
        else:
            dy[k + i] = v
        force += f_i
    return force + P[branch(v, o) + VISCOUS] * v


class GMS(FrictionLaw):
    """Generalized Maxwell-slip friction (see the module docstring).

    References
    ----------
    .. [1] F. Al-Bender, V. Lampaert, J. Swevers, "The generalized Maxwell-slip model: a
       novel model for friction simulation and compensation", IEEE Trans. Autom. Control
       50 (2005) 1883–1887.
    """

    name = "gms"
    state_unit = "m"
    citation = "Al-Bender, Lampaert, Swevers, IEEE TAC 50 (2005) 1883-1887"
    kernel = gms_kernel
    parameters_class = GMSParameters
    kink_at_zero_speed = True

    @property
    def first_state(self) -> str:
        """``element0``: every GMS site has at least one element (:class:`GMSParameters`)."""
        return "element0"

    def states(self, site: Any) -> tuple[str, ...]:
        """One deflection state per slip element.

        Parameters
        ----------
        site : GMSParameters
            The friction site's parameters.

        Returns
        -------
        tuple of str
            ``element0`` … ``element{N-1}``.
        """
        return tuple(f"element{i}" for i in range(len(site.element_stiffness)))

    def site_slots(self, site: Any) -> tuple[str, ...]:
        """Names of the packed values: the Stribeck branches, C, the slip margin, N, each element's
        stiffness and weight.

        Parameters
        ----------
        site : GMSParameters
            The friction site's parameters.

        Returns
        -------
        tuple of str
            Parameter paths below ``friction.<site>``, in ``P`` order.
        """
        n = len(site.element_stiffness)
        return (*SLOTS[:ATTRACTION], "attraction", "slip_margin", "element_count",
                *(f"element_stiffness[{i}]" for i in range(n)),
                *(f"element_weight[{i}]" for i in range(n)))

    def pack(self, site: Any) -> np.ndarray:
        """The site's parameters in the kernel's order.

        Parameters
        ----------
        site : GMSParameters
            The friction site's parameters.

        Returns
        -------
        numpy.ndarray
            (F_c, F_s, v_s, σ2)±, C [N/s], slip margin [-], N [-], k_1..k_N [N/m], α_1..α_N [-].
        """
        p, m = site.positive, site.negative
        return np.array([p.coulomb_force, p.static_force, p.stribeck_velocity,
                         p.viscous_coefficient, m.coulomb_force, m.static_force,
                         m.stribeck_velocity, m.viscous_coefficient, site.attraction,
                         site.slip_margin, float(len(site.element_stiffness)),
                         *site.element_stiffness,
                         *site.element_weight], dtype=float)

    def steady_state(self, v: float, site: Any) -> np.ndarray:
        """Element deflections in steady sliding: every element slips at δ_i = α_i·s(v)/k_i.

        Parameters
        ----------
        v : float
            Constant sliding speed [m/s].
        site : GMSParameters
            The friction site's parameters.

        Returns
        -------
        numpy.ndarray
            The N deflections [m]; zeros at v = 0.

        References
        ----------
        .. [1] F. Al-Bender, V. Lampaert, J. Swevers, "The generalized Maxwell-slip model: a
           novel model for friction simulation and compensation", IEEE Trans. Autom. Control
           50 (2005) 1883–1887.
        """
        if v == 0.0:
            return np.zeros(len(site.element_stiffness))
        s = math.copysign(float(stribeck_magnitude(v, self.pack(site), 0)), v)
        return np.array([a * s / k for k, a in zip(site.element_stiffness,
                                                   site.element_weight, strict=True)])

    def linearise(self, v: float, site: Any) -> LinearFriction:
        """Analytic linearisation at steady sliding, every element slipping.

        δδ̇_i = −(C/|s|)·δδ_i + C·α_i·|s|'(v)·sgn(v)/(k_i·|s|)·δv, δF = Σ k_i·δδ_i + σ2·δv.  A
        perturbation that unloads an element makes it stick; the slip branch is the one steady
        sliding is on.

        Parameters
        ----------
        v : float
            Steady sliding speed of the operating point [m/s], v ≠ 0.
        site : GMSParameters
            The friction site's parameters.

        Returns
        -------
        LinearFriction
            (A, B, C, D) of the small-signal model at ``v``.

        Raises
        ------
        ValueError
            At v = 0, where the elements have no steady slipping state.

        References
        ----------
        .. [1] F. Al-Bender, V. Lampaert, J. Swevers, "The generalized Maxwell-slip model: a
           novel model for friction simulation and compensation", IEEE Trans. Autom. Control
           50 (2005) 1883–1887.
        """
        if v == 0.0:
            raise ValueError("speed: the GMS law is linearised at steady sliding (v ≠ 0)")
        b = site.positive if v >= 0 else site.negative
        s = float(stribeck_magnitude(v, self.pack(site), 0))
        u = v / b.stribeck_velocity
        ds = -(b.static_force - b.coulomb_force) * 2.0 * u / b.stribeck_velocity * math.exp(-u * u)
        k = np.asarray(site.element_stiffness, dtype=float)
        a = np.asarray(site.element_weight, dtype=float)
        c = site.attraction
        return LinearFriction(A=np.diag(np.full(k.size, -c / s)),
                              B=c * a * ds * math.copysign(1.0, v) / (k * s),
                              C=k.copy(), D=b.viscous_coefficient)


register_friction_law(GMS())
