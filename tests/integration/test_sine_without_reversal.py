"""A sine run whose measured window holds no reversal states none (an outside check,
2026-12-06: ``simulate --profile sine --duration 2`` reported a reversal overshoot of 0 % and a
stick time of 0 s, "mean of 0 reversals" — a perfect reversal where there was none)."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from feeddrive.cli import app

runner = CliRunner()


def _run(duration: str, *extra: str) -> str:
    out = runner.invoke(app, ["simulate", "--profile", "sine", "--table-speed", "2",
                              "--duration", duration, *extra], terminal_width=200)
    assert out.exit_code == 0, out.output
    return out.output


def test_no_reversal_in_the_window_gives_none_not_zero() -> None:
    s = json.loads(_run("2", "--json"))
    assert s["reversals"] == 0
    assert s["reversal_overshoot"] is None and s["stick_time_at_reversals_s"] is None
    text = _run("2")
    assert "none in the measured window" in text and "reversal overshoot" not in text


def test_with_a_reversal_the_numbers_are_given() -> None:
    s = json.loads(_run("6", "--json"))
    assert s["reversals"] >= 1 and 0.0 < s["reversal_overshoot"] < 1.0
    assert s["stick_time_at_reversals_s"] > 0.0
    assert "reversal overshoot" in _run("6")
