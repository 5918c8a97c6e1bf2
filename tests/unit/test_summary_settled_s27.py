"""A constant-speed run's summary says whether it has settled (an outside check, 2026-12-07).

A 2-s DDFS run at 0.5 mm/s with the hollow motor at 16 mm/s (Wang2021 Sect. 5.3's DDFS, whose
critical speed is far below 0.5 mm/s: reproduce's Fig. 8 search) was summarised "creeping":
its steady window (1.2–2 s) held the start-up ringing of the 5.4-Hz servo mode, ripple 0.83.
The same run over 10 s is smooth.  The summary now also judges the run as `feeddrive creep`
judges a trial — the limit-cycle rule (feeddrive.analysis.cycle_verdict), which decides only
on a repeating cycle or a decay — and marks a run it leaves undecided as not settled.
"""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.cli import app
from feeddrive.cli.simulate_cmd import UNSETTLED


def _ddfs(duration: float) -> dict:
    system = fd.DriveSystem(fd.preset("wang2021"), drive="ddfs")
    return fd.simulate(system, fd.ConstantSpeed(0.5e-3, nut_speed=16e-3), duration).summary()


def test_a_short_run_is_not_settled_and_its_window_verdict_not_firm() -> None:
    short = _ddfs(2.0)
    assert short["verdict"] == "creeping"  # the window rule, on the ringing start-up
    assert short["settled"] is False
    assert short["limit_cycle_verdict"] == "undecided"
    assert short["limit_cycle_reason"]


def test_the_long_run_settles_and_both_rules_agree() -> None:
    long = _ddfs(10.0)
    assert long["settled"] is True
    assert long["limit_cycle_verdict"] == "smooth" and long["verdict"] == "smooth"


def test_a_sticking_run_is_settled_by_its_cycle() -> None:
    """CDFS at 1 mm/s, below Table 3's 1.56 mm/s: a stick-slip limit cycle within 10 s."""
    system = fd.DriveSystem(fd.preset("wang2021"), drive="cdfs")
    s = fd.simulate(system, fd.ConstantSpeed(1e-3), 10.0).summary()
    assert s["settled"] is True
    assert s["limit_cycle_verdict"] == "stick-slip" and s["verdict"] == "creeping"


@pytest.mark.parametrize(("duration", "settled"), [("2", False), ("10", True)])
def test_the_command_line_marks_the_verdict(duration: str, settled: bool) -> None:
    args = ["simulate", "--drive", "ddfs", "--table-speed", "0.5", "--nut-speed", "16",
            "--duration", duration]
    text = CliRunner().invoke(app, args)
    assert text.exit_code == 0, text.output
    verdict = next(line for line in text.stdout.splitlines() if "  verdict  " in line)
    assert (UNSETTLED in verdict) is not settled
    assert "limit-cycle rule" in text.stdout
    data = json.loads(CliRunner().invoke(app, [*args, "--json"]).stdout)
    assert data["settled"] is settled
