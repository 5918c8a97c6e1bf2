"""Named simulation cases shared by the Radau references, the accuracy tests and the benchmark.

Parameter sets are built from ``wang2021-literal`` by changing documented knobs only:

``damped``
    ``stiffness.axial_damping = 2000`` N s/m (the literal set has none, and its 200-Hz table
    mode then self-excites) and ``controller.velocity_gain_basis = "table"`` (K_vp acts on
    table-equivalent m/s, about 3.1e4 N s/m at the table).  Smooth at every paper speed.
``creeping``
    ``damped`` plus ``controller.kv_placement = "position_output"`` (K_v multiplies the
    position-loop output: a 2000-1/s position gain).  The CDFS stick-slips at 19–20 Hz from
    0.5 to 1.5 mm/s and runs smoothly from 2 mm/s.  The DDFS creeps with v_n = 0.5 mm/s; with
    a fast nut (v_n ≳ 2 mm/s) its hollow-motor loop is unstable (a property of this reading,
    not of the integrator: the reference model shows it too), so DDFS benchmarks use
    ``damped``.

The suggested ``kv_placement = "velocity_error"`` (K_vp/K_v) leaves about 120 N s/m of velocity
gain at the table: the table does not break away at all within 10 s at 1 mm/s, so it is not
a creeping case.
"""

from __future__ import annotations

from dataclasses import dataclass

import feeddrive
from feeddrive.model.reference import ConstantSpeed
from feeddrive.parameters import DriveParameters

MID_SCREW = 0.4  # m, Wang2021 Sect. 5.2 (table in the middle of the screw)


def damped_parameters(axial_damping: float = 2000.0) -> DriveParameters:
    """``wang2021-literal`` with axial damping [N s/m] and table-basis velocity gains."""
    return (feeddrive.preset("wang2021-literal")
            .replace_path("stiffness.axial_damping", axial_damping)
            .replace_path("controller.velocity_gain_basis", "table"))


def creeping_parameters(axial_damping: float = 2000.0) -> DriveParameters:
    """:func:`damped_parameters` with K_v on the position-loop output (stick-slips)."""
    return damped_parameters(axial_damping).replace_path("controller.kv_placement",
                                                         "position_output")


@dataclass(frozen=True)
class Case:
    """A constant-speed run from rest: which parameters, drive, speeds [m/s], duration [s]."""

    name: str
    parameter_set: str  # "damped" or "creeping"
    axial_damping: float  # N s/m
    drive: str
    table_speed: float
    nut_speed: float
    duration: float
    window_start: float  # s, start of the steady window for ripple and period

    def parameters(self) -> DriveParameters:
        make = {"damped": damped_parameters, "creeping": creeping_parameters}[self.parameter_set]
        return make(self.axial_damping)

    def profile(self) -> ConstantSpeed:
        return ConstantSpeed(table_speed=self.table_speed, nut_speed=self.nut_speed)


# Creeping cases with Radau references in tests/data/
RADAU_CASES = (
    Case("cdfs_creep_1p0", "creeping", 2000.0, "cdfs", 1.0e-3, 0.0, 3.0, 1.5),
    Case("cdfs_creep_1p5", "creeping", 5000.0, "cdfs", 1.5e-3, 0.0, 3.0, 1.5),
    Case("ddfs_creep_0p5", "creeping", 2000.0, "ddfs", 0.5e-3, 0.5e-3, 3.0, 1.5),
)

# Benchmark scenarios, 10 s each
BENCH_CASES = (
    Case("cdfs_1p5", "damped", 2000.0, "cdfs", 1.5e-3, 0.0, 10.0, 7.0),
    Case("cdfs_creep_1p0", "creeping", 2000.0, "cdfs", 1.0e-3, 0.0, 10.0, 7.0),
    Case("ddfs_0p5_vn16", "damped", 2000.0, "ddfs", 0.5e-3, 16e-3, 10.0, 7.0),
)

#: the trials that decide the ``reproduce`` report's critical speeds and band edges
#: (``wang2021`` at mid-screw; its store: the CDFS's 1.55 mm/s oscillation and 1.56 smooth,
#: decided at 12 and 24 s, 1.42 the stick-slip/oscillation edge, 1.0 inside the stick-slip
#: band; the DDFS's lowest trial, 0.02 mm/s at v_n = 16 mm/s, which decides "below range"):
#: (drive, table speed [mm/s], nut speed [mm/s], the trial's length [s]).  Their Radau
#: references: tests/data/radau_deciding_trials.npz (``reference/make_radau_reference.py
#: deciding``), read by :func:`deciding_reference`.
DECIDING = (("cdfs", 1.0, 0.0, 12.0), ("cdfs", 1.42, 0.0, 12.0), ("cdfs", 1.55, 0.0, 12.0),
            ("cdfs", 1.56, 0.0, 24.0), ("ddfs", 0.02, 16.0, 12.0))

#: (rtol, × the former absolute tolerances) of the deciding trials' Radau references.  Measured
#: 2026-12-06 on an "AMD EPYC" host (radau_states at the three settings, session 21), the
#: largest table-speed change from (1e-11, 1e-4) and (1e-12, 1e-5) to these: 1.2e-10 and
#: 3.4e-13 m/s (DDFS 0.02/16 mm/s), 2.9e-11 and 4.2e-12 (CDFS 1.0 mm/s), ≤ 1.7e-12 and
#: ≤ 3.4e-12 on the other three.
#: The (1e-11, 1e-4) used until then had moved by ≤ 2e-12 on the host it was chosen on; on
#: that one its DDFS reference was 1.2e-10 m/s off, four times the run's own error, and the
#: shadow's ratio to it failed (0.065).  Radau's LU (LAPACK) rounds with the CPU's kernels,
#: so a reference is only as host-independent as it is converged.
DECIDING_SETTINGS = (1e-13, 1e-6)


def trial_profile(speed_mm_s: float, nut_mm_s: float) -> ConstantSpeed:
    """A creep trial's reference profile (``creep_trial``'s: a 0.1-s start ramp)."""
    return ConstantSpeed(speed_mm_s * 1e-3, nut_mm_s * 1e-3, ramp_time=0.1)


def deciding_name(trial: tuple[str, float, float, float]) -> str:
    """The key of a deciding trial in tests/data/radau_deciding_trials.npz."""
    drive, speed, nut, duration = trial
    return f"{drive}_{speed:g}_{nut:g}_{duration:g}".replace(".", "p")
