"""The named readings beyond the paper (issue 14), as docs/model-reading.md describes them."""

from __future__ import annotations

from pathlib import Path

import feeddrive as fd
from feeddrive.analysis import protocol
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


def test_reading_figures_rows_name_each_reading_and_metric() -> None:
    """Issue 14 item 3: Figs. 7/9/10 metrics per reading, shown in the report."""
    from feeddrive.reproduce.beyond_section import reading_figure_rows
    from feeddrive.reproduce.forced_study import FIGURE_READINGS

    for _, preset, _ in FIGURE_READINGS:
        fd.preset(preset)  # every reading is a shipped preset (with documented changes)
    record = {"reading": "r", "fig7": [{"multiple": k, "overshoot": 0.5, "settling_time": 1.0,
                                        "kind": "smooth"} for k in (0.0, 1.0, 10.0, 20.0)],
              "sine": [{"table_amplitude": 1.56e-3, "nut_amplitude": vn,
                        "reversal_overshoot": 0.25} for vn in (0.0, 2e-3, 10e-3, 16e-3)]}
    (row,) = reading_figure_rows([record])
    assert row["Fig. 7 overshoot at v_n = 0 / 1 / 10 / 20 × [%]"] == "50 / 50 / 50 / 50"
    assert row["Figs. 9–10 reversal overshoot, v_np = 0 / 2 / 10 / 16 mm/s [%]"] == \
        "25 / 25 / 25 / 25"
