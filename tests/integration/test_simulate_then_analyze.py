"""Issue acceptance: `feeddrive analyze` on `feeddrive simulate --output x.csv` gives the
simulation's own verdict and ripple within 5 %."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from feeddrive.cli import app

runner = CliRunner()


@pytest.mark.parametrize("speed", ["1.2", "2.5"])  # creeping and smooth for wang2021 CDFS
def test_analyze_reproduces_simulation_summary(tmp_path, speed: str) -> None:
    csv = tmp_path / "x.csv"
    sim = runner.invoke(app, ["simulate", "--drive", "cdfs", "--table-speed", speed,
                              "--duration", "12", "--output", str(csv), "--json"])
    assert sim.exit_code == 0, sim.output
    s = json.loads(sim.output)
    ana = runner.invoke(app, ["analyze", str(csv), "--command-speed", speed, "--json"])
    assert ana.exit_code == 0, ana.output
    m = json.loads(ana.output)["segments"][0]["metrics"]
    assert m["verdict"] == s["verdict"]
    if s["verdict"] == "creeping":
        assert m["ripple_ratio"] == pytest.approx(s["ripple_ratio"], rel=0.05)
    else:
        # a smooth run has (near) zero ripple; compare on the command's scale
        assert abs(m["ripple_ratio"] - s["ripple_ratio"]) < 0.05
