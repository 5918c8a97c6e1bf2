"""The named readings beyond the paper (issue 14), as docs/model-reading.md describes them."""

from __future__ import annotations

from pathlib import Path

import feeddrive as fd
from feeddrive import protocol
from feeddrive.analysis.critical import critical_speed_from_rest
from feeddrive.parameters import dumps, loads
from feeddrive.presets import wang2021

DOC = (Path(__file__).resolve().parents[2] / "docs" / "model-reading.md").read_text()


def test_drive_preset_holds_the_documented_values_and_round_trips() -> None:
    p = fd.preset("wang2021-drive")
    c = p.controller
    assert (c.current_limit, c.voltage_limit) == (17.0, 300.0)
    assert (c.current_period, c.velocity_period, c.position_period) == (1.25e-4, 2.5e-4, 5e-4)
    assert c.encoder_counts == 2**20 and c.grating_resolution == 5e-8
    assert loads(dumps(p)) == p
    assert {a.id for a in wang2021.DRIVE_ASSUMPTIONS} == {"drive-limits", "drive-sampling",
                                                          "drive-feedback"}


def test_drive_preset_cdfs_critical_speed_is_the_documented_one() -> None:
    crit = critical_speed_from_rest(fd.DriveSystem(fd.preset("wang2021-drive"), "cdfs", 0.4),
                                    speed_range=protocol.SPEED_RANGE,
                                    coarse_step=protocol.COARSE_STEP)
    shown = f"{1e3 * crit.critical_speed:.2f}"  # type: ignore[operator]
    assert "| real drive (`wang2021-drive`)" in DOC
    row = next(line for line in DOC.splitlines() if line.startswith("| real drive"))
    assert f"| {shown} |" in row
