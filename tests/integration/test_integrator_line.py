"""The run summary's integrator line states the tolerances each part ran at, in the CLI's
units (an outside check, 2026-12-06: a DDFS's line said "scaled to 16.5 mm/s" beside the
table's tolerances, which are scaled to the table's 0.5 mm/s; and gave them in m, m/s)."""

from __future__ import annotations

import feeddrive as fd
from feeddrive.cli._solver_report import integrator_line
from feeddrive.cli._units import number


def test_a_ddfs_line_gives_the_table_and_the_motors_each_with_its_scale() -> None:
    r = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "ddfs", 0.4),
                    fd.ConstantSpeed(0.5e-3, 16e-3), 0.2)
    s = r.solver_stats
    assert s["table_speed_scale"] == 0.5e-3 and s["speed_scale"] == 16.5e-3  # [m/s]
    line = integrator_line(s)
    table = (f"table positions {number(s['position_tolerance'] * 1e3, 3)} mm, speeds "
             f"{number(s['speed_tolerance'] * 1e3, 3)} mm/s (scaled to 0.5 mm/s)")
    motors = (f"motors positions {number(s['motor_position_tolerance'] * 1e3, 3)} mm, speeds "
              f"{number(s['motor_speed_tolerance'] * 1e3, 3)} mm/s (scaled to 16.5 mm/s)")
    assert table in line and motors in line, line


def test_a_cdfs_line_has_one_set_of_tolerances() -> None:
    r = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4), fd.ConstantSpeed(2e-3),
                    0.2)
    line = integrator_line(r.solver_stats)
    assert "(scaled to 2 mm/s)" in line and "motors" not in line, line
