"""The shipped wang2021 reading against the paper (Wang2021 Sect. 5.2, Fig. 6, Table 3)."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.analysis.critical import critical_speed_from_rest
from feeddrive.cli import app
from feeddrive.engine.simulate import DriveSystem

runner = CliRunner()


@pytest.mark.slow
def test_cdfs_critical_speed_mid_screw_is_the_fitted_value() -> None:
    # wang2021's velocity integral gain is fitted to Wang2021 Sect. 5.2 / Fig. 6: 1.56 mm/s.
    # A regression guard on the calibration (fitted, not predicted).
    res = critical_speed_from_rest(DriveSystem(fd.preset("wang2021"), "cdfs", 0.4),
                                   speed_range=(1.0e-3, 2.0e-3), coarse_step=0.2e-3)
    assert res.status == "found"
    assert res.critical_speed == pytest.approx(1.56e-3, abs=0.011e-3)
    assert res.kind == "oscillation"  # the 5.4-Hz loop mode, not stick-slip (issue 15)


@pytest.mark.slow
def test_literal_reading_does_not_creep_at_paper_speed() -> None:
    # seed README: Table 2 read literally (stiff motor velocity loop) gives no stick-slip at
    # 1.5 mm/s once the table mode has some axial damping.
    from feeddrive.analysis.critical import creep_trial
    p = fd.preset("wang2021-literal").replace_path("stiffness.axial_damping", 2500.0)
    assert creep_trial(DriveSystem(p, "cdfs", 0.4), 1.5e-3).kind == "smooth"


@pytest.mark.slow
def test_creep_cli_prints_critical_speed() -> None:
    res = runner.invoke(app, ["creep", "--drive", "cdfs", "--position", "400", "--method",
                              "bisect", "--low", "1.0", "--high", "2.0", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert out["critical_speed_mm_s"] == pytest.approx(1.56, abs=0.011)
    # issue 15: the band(s), the kind and the verdict rule are stated
    assert out["kind"] == "oscillation"
    top = out["bands"][-1]
    assert (top["kind"], top["above_mm_s"], top["above_kind"]) == ("oscillation",
                                                                   pytest.approx(1.56), "smooth")
    assert top["upper_mm_s"] == pytest.approx(1.55)
    rule = out["verdict_rule"]
    from feeddrive.analysis import protocol

    assert rule["max_duration"] == protocol.TRIAL_MAX_DURATION
    assert "undecided" in rule["description"]


@pytest.mark.slow
def test_reproduce_writes_report_with_every_paper_number(full_reproduction) -> None:
    tmp_path = full_reproduction[0]  # `feeddrive reproduce --out DIR` (conftest.py)
    md = (tmp_path / "report.md").read_text()
    html = (tmp_path / "report.html").read_text()
    # Wang2021: Sect. 5.2, Fig. 8, Table 3 (both drives, k_sa), K_eq
    for number in ["1.56", "0.50", "1.66", "0.52", "1.21", "1.58", "1.59", "1.23", "0.35",
                   "0.47", "0.46", "0.36", "276.13", "220.90", "207.10", "21.60"]:
        assert number in md, number
        assert number in html, number
    pngs = sorted(p.name for p in tmp_path.glob("*.png"))
    assert len(pngs) == 7  # Figs. 6–10, 14 and the sensitivity chart (issue 22)
    for csv in ("table3_position.csv", "fig7_nut_speed.csv", "figs9_10_reversal.csv",
                "paper_comparison.csv", "critical_speeds.csv"):
        assert (tmp_path / csv).exists()
