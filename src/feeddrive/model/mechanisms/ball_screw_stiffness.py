"""The stiffness chain of the ball-screw drive as a function of table position.

Wang2021 Eqs. (2)–(5).  Positions are the distance a from the motor-side screw support [m].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...parameters import DriveParameters, ParameterError
from .ball_screw_parameters import BallScrew, Coupling, StiffnessModel


def _check_positions(position: object, length: float) -> np.ndarray:
    a = np.asarray(position, dtype=float)
    if not np.all(np.isfinite(a)):
        raise ParameterError("table_position", position, "not finite; expected metres")
    if np.any(a <= 0.0) or np.any(a >= length):
        raise ParameterError(
            "table_position", position,
            f"expected 0 < a < {length:g} [m] (strictly between the screw supports)",
        )
    return a


def screw_axial_stiffness(position: object, screw: BallScrew,
                          support: str = "fixed-fixed") -> np.ndarray:
    """Axial stiffness k_sa of the screw shaft with the nut at distance a from the support.

    fixed–fixed: π d² E l / (4 a (l − a)) (Wang2021 Eq. (4)); fixed–free: π d² E / (4 a), the
    screw loaded over a only.

    Parameters
    ----------
    position : array_like
        Nut distance a from the fixed support, strictly between the supports [m].
    screw : BallScrew
        The ball screw (diameter, length, E, stiffnesses, lead, efficiency).
    support : str, default "fixed-fixed"
        ``"fixed-fixed"`` or ``"fixed-free"``.

    Returns
    -------
    numpy.ndarray
        k_sa at each position [N/m].

    Raises
    ------
    ParameterError
        For a position outside the supports or an unknown support.

    References
    ----------
    .. [1] Wang2021 Eq. (4), Table 3.
    """
    a = _check_positions(position, screw.length)
    area_E = math.pi * screw.diameter**2 / 4.0 * screw.youngs_modulus
    if support == "fixed-fixed":
        return area_E * screw.length / (a * (screw.length - a))
    if support == "fixed-free":
        return area_E / a
    raise ParameterError("stiffness.screw_support", support, "expected fixed-fixed or fixed-free")


def torsional_stiffness(coupling: Coupling, screw: BallScrew) -> float:
    """Torsional stiffness of coupling and screw in series, K_t1 = (1/K_c + 1/K_sθ)⁻¹.

    Parameters
    ----------
    coupling : Coupling
        The motor coupling (its torsional stiffness K_c).
    screw : BallScrew
        The ball screw (diameter, length, E, stiffnesses, lead, efficiency).

    Returns
    -------
    float
        K_t1 [N m/rad].

    References
    ----------
    .. [1] Wang2021 Eq. (2).
    """
    return 1.0 / (1.0 / coupling.torsional_stiffness + 1.0 / screw.torsional_stiffness)


def axial_stiffness(screw_axial: object, screw: BallScrew,
                    bearing_count: float = 2.0) -> np.ndarray:
    """Axial stiffness of the chain, K_a = (n/K_ba + 1/K_sa + 1/K_na + 1/K_nba)⁻¹.

    Parameters
    ----------
    screw_axial : array_like
        Screw-shaft axial stiffness k_sa [N/m].
    screw : BallScrew
        The ball screw (diameter, length, E, stiffnesses, lead, efficiency).
    bearing_count : float, default 2.0
        Support bearings in series n (2 in Wang2021 Eq. (3)) [-].

    Returns
    -------
    numpy.ndarray
        K_a [N/m].

    References
    ----------
    .. [1] Wang2021 Eq. (3).
    """
    k_sa = np.asarray(screw_axial, dtype=float)
    return 1.0 / (bearing_count / screw.support_bearing_axial_stiffness + 1.0 / k_sa
                  + 1.0 / screw.nut_axial_stiffness + 1.0 / screw.nut_bearing_axial_stiffness)


def equivalent_stiffness_chain(axial: object, torsional: float, screw: BallScrew,
                               include_torsion: bool = True) -> np.ndarray:
    """Equivalent axial stiffness at the table, K_eq = (1/K_a + H²/η · 1/K_t1)⁻¹.

    Parameters
    ----------
    axial : array_like
        Axial stiffness K_a [N/m].
    torsional : float
        Torsional stiffness K_t1 [N m/rad].
    screw : BallScrew
        The ball screw (diameter, length, E, stiffnesses, lead, efficiency).
    include_torsion : bool, default True
        Keep the torsion term H²/(η K_t1).

    Returns
    -------
    numpy.ndarray
        K_eq [N/m].

    References
    ----------
    .. [1] Wang2021 Eq. (5).
    """
    inv = 1.0 / np.asarray(axial, dtype=float)
    if include_torsion:
        inv = inv + screw.transmission_ratio**2 / screw.efficiency / torsional
    return 1.0 / inv


@dataclass(frozen=True)
class StiffnessChain:
    """Every link of the stiffness chain at the requested table positions, in SI.

    Parameters
    ----------
    position : numpy.ndarray
        Table positions [m].
    screw_axial : numpy.ndarray
        k_sa at each position [N/m].
    axial : numpy.ndarray
        K_a at each position [N/m].
    torsional : float
        K_t1 [N m/rad].
    equivalent : numpy.ndarray
        K_eq the simulation uses, the override applied [N/m].
    equivalent_chain : numpy.ndarray
        K_eq from Eq. (5), before any override [N/m].
    """

    position: np.ndarray  # [m]
    screw_axial: np.ndarray  # k_sa [N/m]
    axial: np.ndarray  # K_a [N/m]
    torsional: float  # K_t1 [N m/rad]
    equivalent: np.ndarray  # K_eq [N/m] used by the simulation (override applied)
    equivalent_chain: np.ndarray  # K_eq [N/m] from Eq. (5), before any override


def stiffness_chain(params: DriveParameters, position: object) -> StiffnessChain:
    """Evaluate Wang2021 Eqs. (2)–(5) at table positions under the parameter set's reading.

    Parameters
    ----------
    params : DriveParameters
        The parameter set (its screw, coupling and ``stiffness`` reading).
    position : array_like
        Table positions [m].

    Returns
    -------
    StiffnessChain
        Every link at each position.

    References
    ----------
    .. [1] Wang2021 Eqs. (2)–(5).
    """
    model: StiffnessModel = params.stiffness
    k_sa = screw_axial_stiffness(position, params.screw, model.screw_support)
    k_t1 = torsional_stiffness(params.coupling, params.screw)
    k_a = axial_stiffness(k_sa, params.screw, model.support_bearing_count)
    k_eq_chain = equivalent_stiffness_chain(k_a, k_t1, params.screw, model.include_torsion)
    k_eq = (np.full_like(k_eq_chain, model.equivalent_stiffness)
            if model.equivalent_stiffness > 0 else k_eq_chain)
    return StiffnessChain(position=np.asarray(position, dtype=float), screw_axial=k_sa,
                          axial=k_a, torsional=k_t1, equivalent=k_eq,
                          equivalent_chain=k_eq_chain)


def equivalent_stiffness(params: DriveParameters, position: float) -> float:
    """K_eq at one table position, the parameter set's override if it sets one.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    position : float
        Table position [m].

    Returns
    -------
    float
        K_eq [N/m].
    """
    return float(stiffness_chain(params, position).equivalent)


# The value Wang2021 Sect. 5.2 states for K_eq at mid-screw.
PAPER_MID_SCREW_K_EQ = 2.16e7  # N/m

# Wang2021 Table 3: the five measurement points (table position x_t, taken as a in Eq. 4) and
# the screw-shaft axial stiffness k_sa the paper prints for them.
TABLE3_POSITIONS = (0.2, 0.3, 0.4, 0.5, 0.6)  # m
TABLE3_SCREW_AXIAL_STIFFNESS = (276.13e6, 220.9e6, 207.1e6, 220.9e6, 276.13e6)  # N/m


def mid_screw_position(screw: BallScrew) -> float:
    """The table position a = l/2 at which Wang2021 Sect. 5.2 quotes K_eq.

    Parameters
    ----------
    screw : BallScrew
        The ball screw (diameter, length, E, stiffnesses, lead, efficiency).

    Returns
    -------
    float
        l/2 [m].

    References
    ----------
    .. [1] Wang2021 Sect. 5.2.
    """
    return screw.length / 2.0


@dataclass(frozen=True)
class Reading:
    """One reading of Wang2021 Eqs. (2)–(5) and the K_eq it gives at mid-screw.

    Parameters
    ----------
    description : str
        The reading in words.
    screw_support : str
        ``"fixed-fixed"`` or ``"fixed-free"``.
    screw_span : str
        Where the screw is loaded (a = l/2, or the full span).
    bearing_count : float
        Support bearings in series [-].
    efficiency : float
        Screw efficiency η [-].
    include_torsion : bool
        Whether the torsion term is kept.
    equivalent_stiffness : float
        K_eq at mid-screw [N/m].

    References
    ----------
    .. [1] Wang2021 Eqs. (2)–(5), Sect. 5.2 (2.16e7 N/m).
    """

    description: str
    screw_support: str
    screw_span: str
    bearing_count: float
    efficiency: float
    include_torsion: bool
    equivalent_stiffness: float

    @property
    def deviation(self) -> float:
        """Relative deviation from the paper's 2.16e7 N/m."""
        return self.equivalent_stiffness / PAPER_MID_SCREW_K_EQ - 1.0


def mid_screw_readings(params: DriveParameters) -> list[Reading]:
    """K_eq at mid-screw under every reading of Wang2021 Eqs. (2)–(5) that can be defended, best
    first.

    Varies the screw support (fixed–fixed Eq. (4), or fixed–free with the load at a, or over the
    whole span l), the number of support bearings in series (1, 2, 4), η (0.9, 0.95, 1) and
    whether the torsion term is kept.  With the torsion term dropped η plays no part, so those
    readings are listed once, with the parameter set's η.

    Parameters
    ----------
    params : DriveParameters
        The parameter set (screw and coupling).

    Returns
    -------
    list of Reading
        Sorted by distance from the paper's 2.16e7 N/m.

    References
    ----------
    .. [1] Wang2021 Eqs. (2)–(5), Sect. 5.2.
    """
    screw = params.screw
    mid = mid_screw_position(screw)
    k_t1 = torsional_stiffness(params.coupling, screw)
    spans = {
        "fixed-fixed, a = l/2 (Eq. 4)": ("fixed-fixed", mid),
        "fixed-free, a = l/2": ("fixed-free", mid),
        "fixed-free, over the full span l": ("fixed-free", screw.length * (1 - 1e-12)),
    }
    out = []
    for span_name, (support, a) in spans.items():
        k_sa = float(screw_axial_stiffness(a, screw, support))
        for n in (1.0, 2.0, 4.0):
            k_a = float(axial_stiffness(k_sa, screw, n))
            for tors in (True, False):
                for eta in (0.9, 0.95, 1.0) if tors else (screw.efficiency,):
                    s = screw.with_values(efficiency=eta)
                    k = float(equivalent_stiffness_chain(k_a, k_t1, s, tors))
                    detail = f"η = {eta:g}; torsion kept" if tors else "torsion dropped"
                    out.append(Reading(
                        description=f"{span_name}; {n:g} support bearing(s); {detail}",
                        screw_support=support, screw_span=span_name, bearing_count=n,
                        efficiency=eta, include_torsion=tors, equivalent_stiffness=k))
    out.sort(key=lambda r: abs(r.deviation))
    return out
