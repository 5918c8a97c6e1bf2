"""The stiffness chain of the ball-screw drive as a function of table position.

Wang2021 Eqs. (2)–(5).  Positions are the distance a from the motor-side screw support [m].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...parameters import BallScrew, Coupling, DriveParameters, ParameterError, StiffnessModel


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
    """k_sa [N/m] of the screw shaft with the nut at distance ``position`` [m].

    fixed-fixed: π d² E l / (4 a (l − a))  (Wang2021 Eq. 4);
    fixed-free:  π d² E / (4 a)            (screw loaded over a only).
    """
    a = _check_positions(position, screw.length)
    area_E = math.pi * screw.diameter**2 / 4.0 * screw.youngs_modulus
    if support == "fixed-fixed":
        return area_E * screw.length / (a * (screw.length - a))
    if support == "fixed-free":
        return area_E / a
    raise ParameterError("stiffness.screw_support", support, "expected fixed-fixed or fixed-free")


def torsional_stiffness(coupling: Coupling, screw: BallScrew) -> float:
    """K_t1 = (1/K_c + 1/K_sθ)⁻¹ [N m/rad].  Wang2021 Eq. (2)."""
    return 1.0 / (1.0 / coupling.torsional_stiffness + 1.0 / screw.torsional_stiffness)


def axial_stiffness(screw_axial: object, screw: BallScrew,
                    bearing_count: float = 2.0) -> np.ndarray:
    """K_a = (n/K_ba + 1/K_sa + 1/K_na + 1/K_nba)⁻¹ [N/m], n = 2 in Wang2021 Eq. (3)."""
    k_sa = np.asarray(screw_axial, dtype=float)
    return 1.0 / (bearing_count / screw.support_bearing_axial_stiffness + 1.0 / k_sa
                  + 1.0 / screw.nut_axial_stiffness + 1.0 / screw.nut_bearing_axial_stiffness)


def equivalent_stiffness_chain(axial: object, torsional: float, screw: BallScrew,
                               include_torsion: bool = True) -> np.ndarray:
    """K_eq = (1/K_a + H²/η · 1/K_t1)⁻¹ [N/m].  Wang2021 Eq. (5)."""
    inv = 1.0 / np.asarray(axial, dtype=float)
    if include_torsion:
        inv = inv + screw.transmission_ratio**2 / screw.efficiency / torsional
    return 1.0 / inv


@dataclass(frozen=True)
class StiffnessChain:
    """Every link of the chain at the requested table positions (SI)."""

    position: np.ndarray  # [m]
    screw_axial: np.ndarray  # k_sa [N/m]
    axial: np.ndarray  # K_a [N/m]
    torsional: float  # K_t1 [N m/rad]
    equivalent: np.ndarray  # K_eq [N/m] used by the simulation (override applied)
    equivalent_chain: np.ndarray  # K_eq [N/m] from Eq. (5), before any override


def stiffness_chain(params: DriveParameters, position: object) -> StiffnessChain:
    """Evaluate Eqs. (2)–(5) at table ``position`` [m] under ``params.stiffness``'s reading."""
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
    """K_eq [N/m] at table ``position`` [m] (the override if set)."""
    return float(stiffness_chain(params, position).equivalent)


# The value Wang2021 Sect. 5.2 states for K_eq at mid-screw.
PAPER_MID_SCREW_K_EQ = 2.16e7  # N/m

# Wang2021 Table 3: the five measurement points (table position x_t, taken as a in Eq. 4) and
# the screw-shaft axial stiffness k_sa the paper prints for them.
TABLE3_POSITIONS = (0.2, 0.3, 0.4, 0.5, 0.6)  # m
TABLE3_SCREW_AXIAL_STIFFNESS = (276.13e6, 220.9e6, 207.1e6, 220.9e6, 276.13e6)  # N/m


def mid_screw_position(screw: BallScrew) -> float:
    """a = l/2 [m], the table position at which Wang2021 Sect. 5.2 quotes K_eq."""
    return screw.length / 2.0


@dataclass(frozen=True)
class Reading:
    """One reading of Eqs. (2)–(5) and the K_eq [N/m] it gives at mid-screw."""

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
    """K_eq at mid-screw under every reading of Eqs. (2)–(5) we could defend, best first.

    Varies: the screw support (fixed–fixed Eq. 4, or fixed–free with the load at a, or over the
    whole span l), the number of support bearings in series (1, 2, 4), η (0.9, 0.95, 1) and
    whether the torsion term is kept.  With the torsion term dropped η plays no part, so those
    readings are listed once, with the parameter set's η.
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
