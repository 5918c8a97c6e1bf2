"""A run whose loop diverges before the summary's samples (an outside check, 2026-12-07):
`simulate` said "--duration = 0.00571 [s]: expected ≥ 0.015 [s]" of a 120-s run (exit 2,
blaming a setting the user never gave), and the explorer showed the cut trace as "done" and
"undecided … a longer simulated time decides".  Now: the verdict unstable, where it stopped,
exit status 3; the explorer's verdict unstable with the time reached."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.cli import app
from feeddrive.cli._common import EXIT_UNSTABLE
from feeddrive.engine.budget import SUMMARY_SAMPLES

# velocity_integral_gain 1e9 (the top of the explorer's range): the CDFS loop diverges within
# a few ms
WILD = fd.preset("wang2021").replace_path("controller.velocity_integral_gain", 1e9)


def test_the_summary_says_unstable_and_where() -> None:
    r = fd.simulate(fd.DriveSystem(WILD, "cdfs", 0.4), fd.ConstantSpeed(1e-3), 120.0)
    assert r.solver_stats["diverged"] and r.time.size < SUMMARY_SAMPLES
    s = r.summary()
    assert s["verdict"] == "unstable" and s["too_short"]
    assert s["diverged_at_s"] == pytest.approx(float(r.time[-1]))
    assert "diverged at" in s["warnings"][0]


def test_simulate_exits_unstable_naming_the_time(tmp_path: Path) -> None:
    params = tmp_path / "wild.toml"
    params.write_text('extends = "wang2021"\n[controller]\nvelocity_integral_gain = 1e9\n',
                      encoding="utf-8")
    args = ["simulate", "--drive", "cdfs", "--table-speed", "1", "--duration", "120",
            "--params", str(params)]
    text = CliRunner().invoke(app, args)
    assert text.exit_code == EXIT_UNSTABLE, text.output
    assert "--duration" not in text.output and "diverged at" in text.output
    data = CliRunner().invoke(app, [*args, "--json"])
    assert data.exit_code == EXIT_UNSTABLE
    body = json.loads(data.stdout)
    assert body["verdict"] == "unstable" and body["diverged_at_s"] < 0.1


@pytest.mark.parametrize("extra", [{"velocity_integral_gain": "1e9"},
                                   {"position_gain": "100000"}])
def test_the_explorer_calls_a_diverged_run_unstable(extra: dict[str, str]) -> None:
    from feeddrive.explore import compute, settings

    checked = settings.check({"duration": "120", **extra})
    assert not checked.errors
    out = compute.run_simulation(checked, lambda *a: None)
    assert out["verdict"]["verdict"] == out["verdict"]["kind"] == "unstable"
    assert out["reached_s"] < 1.0 and out["duration_s"] == 120.0
    assert out["summary"]["solver"]["diverged"] is True
    assert f"{out['reached_s']:.3g} s of the 120 s" in out["verdict"]["text"]
