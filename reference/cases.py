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
