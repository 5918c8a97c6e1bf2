"""The ball-screw drive's parameter classes and its mechanism kind ``"ball-screw"``.

Sections ``[screw]`` (:class:`BallScrew`), ``[coupling]`` (:class:`Coupling`),
``[stiffness]`` (:class:`StiffnessModel`) and ``[friction]`` (:class:`FrictionSites`: the
screw-shaft, hollow-shaft and guide sites, each with its law), registered in
:mod:`feeddrive.registry` (group ``feeddrive.sections``), and the kind's
:class:`~feeddrive.parameters.Composition` (group ``feeddrive.mechanism_kinds``): the parts a
``mechanism = "ball-screw"`` file — and every parameter file written before the composition —
is made of.  The mechanism itself (the CDFS and DDFS equations) is
:mod:`feeddrive.model.mechanisms.ball_screw`; this module stays apart from it so that the
stiffness chain (:mod:`feeddrive.model.mechanisms.ball_screw_stiffness`), which the
mechanism uses, can read these classes.

Source: Z. Wang, X. Feng, H. Yang, H. Jin, "Research on low-speed characteristics of
differential double-drive feed system", Mech. Sci. 12 (2021) 791–800, Tables 1–2,
Eqs. (2)–(8).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ... import registry
from ...parameters import Component, Composition, SiteParameters
from ...parameters.validation import choice, flag, quantity
from ..disturbances import Disturbances
from ..loops import default_controller
from .shared import Motor, Table

_MM_HINT = "looks like millimetres; give metres"


@dataclass(frozen=True)
class FrictionSites(Component):
    """Friction at the three sites of Wang2021 Sect. 4, each with its law.

    ``ball_nut_share`` f: the fraction of the screw-shaft friction (Table 1, identified on the
    CDFS with the nut fixed) that acts at the ball–nut contact, i.e. at the *relative* speed
    H(ω_s − ω_n) between screw and nut, with its reaction on the nut; the rest (1 − f) acts
    between screw shaft and ground (support bearings) at the screw speed.  f = 0 is the paper's
    reading (every friction at its own shaft's speed); with the nut held (CDFS) f has no effect.

    Parameters
    ----------
    screw : SiteParameters
        Screw-shaft friction (force form: torque ÷ H).
    nut : SiteParameters
        Hollow (nut) shaft friction (force form).
    guide : SiteParameters
        Linear-guide friction.
    ball_nut_share : float, default 0.0
        The share f of the screw-shaft friction acting at the ball–nut contact [-].

    References
    ----------
    .. [1] Wang2021 Sect. 4, Table 1.
    """

    screw: SiteParameters
    nut: SiteParameters
    guide: SiteParameters
    ball_nut_share: float = quantity("-", low=0, high=1, low_inclusive=True, default=0.0,
                                     hint="a fraction between 0 and 1")
    _label = "friction"


@dataclass(frozen=True)
class BallScrew(Component):
    """Ball screw, its supports and nut.  Wang2021 Table 2 and Eqs. (2)–(5).

    Parameters
    ----------
    length : float
        Length l between the supports [m].
    diameter : float
        Screw diameter d [m].
    lead : float
        Lead p_h [m].
    youngs_modulus : float
        Young's modulus E of the screw [Pa].
    torsional_stiffness : float
        Torsional stiffness of the screw shaft K_sθ [N m/rad].
    nut_axial_stiffness : float
        Axial stiffness of the nut K_na [N/m].
    nut_bearing_axial_stiffness : float
        Axial stiffness of the nut's bearing K_nba [N/m].
    support_bearing_axial_stiffness : float
        Axial stiffness of one support bearing K_ba [N/m].
    efficiency : float
        Transmission efficiency η [-].
    shaft_inertia : float
        Inertia of the screw shaft [kg m^2].
    nut_inertia : float
        Inertia of the nut and hollow shaft [kg m^2].

    References
    ----------
    .. [1] Wang2021 Table 2, Eqs. (2)–(5).
    """

    length: float = quantity("m", low=0.01, high=20, hint=_MM_HINT)
    diameter: float = quantity("m", low=1e-3, high=0.5, hint=_MM_HINT)
    lead: float = quantity("m", low=1e-4, high=0.1, hint=_MM_HINT)
    youngs_modulus: float = quantity("Pa", low=1e9, high=1e12, hint="206 GPa = 2.06e11 Pa")
    torsional_stiffness: float = quantity("N m/rad", low=1, high=1e9)
    nut_axial_stiffness: float = quantity(
        "N/m", low=1e5, high=1e11, hint="1 N/µm = 1e6 N/m"
    )
    nut_bearing_axial_stiffness: float = quantity(
        "N/m", low=1e5, high=1e11, hint="1 N/µm = 1e6 N/m"
    )
    support_bearing_axial_stiffness: float = quantity(
        "N/m", low=1e5, high=1e11, hint="1 N/µm = 1e6 N/m"
    )
    efficiency: float = quantity(
        "-", low=0, high=1.0, hint="transmission efficiency η is a fraction"
    )
    shaft_inertia: float = quantity("kg m^2", low=0, high=10, low_inclusive=True)
    nut_inertia: float = quantity("kg m^2", low=0, high=10, low_inclusive=True)
    _label = "screw"

    @property
    def transmission_ratio(self) -> float:
        """H = p_h / 2π: table travel per screw radian [m/rad].

        References
        ----------
        .. [1] Wang2021 Eq. (8).
        """
        return self.lead / (2.0 * math.pi)


@dataclass(frozen=True)
class Coupling(Component):
    """The motor–screw coupling.

    Parameters
    ----------
    torsional_stiffness : float
        Torsional stiffness K_c [N m/rad] (Wang2021 Eq. (2)).

    References
    ----------
    .. [1] Wang2021 Table 2, Eq. (2).
    """
    torsional_stiffness: float = quantity("N m/rad", low=1, high=1e9)
    _label = "coupling"


@dataclass(frozen=True)
class StiffnessModel(Component):
    """How Eqs. (2)–(5) are read, and the structural damping the paper does not give.

    ``equivalent_stiffness`` set to a positive value overrides the chain (e.g. the paper's
    stated 2.16e7 N/m); 0 means "compute from Eqs. (2)–(5) at the table position".

    Parameters
    ----------
    screw_support : str, default "fixed-fixed"
        ``"fixed-fixed"`` (Wang2021 Eq. (4)) or ``"fixed-free"``.
    support_bearing_count : float, default 2.0
        Support bearings in series in Eq. (3) [-].
    include_torsion : bool, default True
        Keep the torsion term of Eq. (5).
    equivalent_stiffness : float, default 0.0
        A fixed K_eq overriding the chain; 0 computes it [N/m].
    axial_damping : float, default 0.0
        Structural axial damping c_ax of the screw–nut–table chain [N s/m].
    position_dependent : bool, default True
        Whether K_eq follows the table position during a run.

    References
    ----------
    .. [1] Wang2021 Eqs. (2)–(5).
    """

    screw_support: str = choice(("fixed-fixed", "fixed-free"), default="fixed-fixed")
    support_bearing_count: float = quantity("-", low=0, high=8, default=2.0)
    include_torsion: bool = flag(default=True)
    equivalent_stiffness: float = quantity(
        "N/m", low=0, high=1e11, low_inclusive=True, default=0.0, hint="1 N/µm = 1e6 N/m"
    )
    axial_damping: float = quantity("N s/m", low=0, high=1e8, low_inclusive=True, default=0.0)
    position_dependent: bool = flag(default=True)
    _label = "stiffness"



for _name, _cls in (("screw", BallScrew), ("coupling", Coupling), ("stiffness", StiffnessModel),
                    ("friction", FrictionSites)):
    registry.register(registry.SECTIONS, _name, _cls)

#: the ball-screw drive's parts: what ``mechanism = "ball-screw"`` (the default) is made of
BALL_SCREW = registry.register(registry.MECHANISM_KINDS, "ball-screw", Composition(
    required=("screw", "coupling", "screw_motor", "hollow_motor", "table", "friction"),
    defaults=(("stiffness", StiffnessModel), ("controller", default_controller),
              ("disturbances", Disturbances)),
    description="ball screw with a screw motor and a hollow (nut) motor (Wang2021): the "
    "cdfs and ddfs drives; the linear-motor and rack-pinion drives read its table, guide "
    "friction and controller with their own section",
    file_note="Friction forces at the screw and hollow shafts are torques divided by "
    "H = lead/2π."))

__all__ = ["BALL_SCREW", "BallScrew", "Coupling", "FrictionSites", "Motor", "StiffnessModel",
           "Table"]
