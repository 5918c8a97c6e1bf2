"""A critical-speed search tests the top (and bottom) of its range whatever its width (session 26).

The coarse grid started at the range's bottom and stopped at its last whole step: with the
protocol's 0.2-mm/s scan, ``creep --method bisect --high 1.61`` tested nothing above 1.42 mm/s
and answered "> 1.61 mm/s (creeps at every tested speed…)", while ``--high 1.7`` answered
1.56 mm/s; the step-down from ``--high 1.6`` began at 1.52 mm/s.  Here every trial is a
closed-form verdict (creeping below ``EDGE``, smooth above it: the critical speed is 1.56 mm/s
at the 0.01-mm/s resolution), so the grid logic is tested exactly and without a simulation.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.analysis import critical, protocol
from feeddrive.analysis.critical import CreepTrial

MM = 1e-3
EDGE = 1.555 * MM  # [m/s] the fake drive creeps (oscillation) below it, is smooth above


def _kind(speed: float, edge: float) -> str:
    return "oscillation" if speed < edge else "smooth"


def _trial(speed: float, edge: float = EDGE) -> CreepTrial:
    return CreepTrial(speed=speed, kind=_kind(speed, edge), ripple_ratio=0.0,
                      stick_fraction=0.0, stick_slip_frequency=None, min_ratio=1.0,
                      duration=1.0)


@pytest.fixture
def fake_trials(monkeypatch: pytest.MonkeyPatch) -> list[float]:
    """Every trial from rest and every staircase closed-form; the speeds tried, in order."""
    tried: list[float] = []

    def run_trial(system: object, speed: float, nut_speed: float, rule: object,
                  options: object, embedded: bool) -> tuple[CreepTrial, np.ndarray, np.ndarray]:
        tried.append(speed)
        return _trial(speed), np.zeros(2), np.full(2, speed)

    def walk_down(system: object, speeds: Sequence[float], *, stop_after: int | None = None,
                  **kwargs: Any) -> tuple[list[CreepTrial], float]:
        trials: list[CreepTrial] = []
        for v in speeds:
            tried.append(float(v))
            trials.append(_trial(float(v)))
            if (stop_after is not None and len(trials) > stop_after + 1
                    and trials[-1].kind != trials[stop_after].kind):
                break
        return trials, 0.0

    monkeypatch.setattr(critical, "_run_trial", run_trial)
    monkeypatch.setattr(critical, "walk_down", walk_down)
    return tried


def _system() -> fd.DriveSystem:
    return fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)


@pytest.mark.parametrize("high", [1.61, 1.7, 1.6])
def test_from_rest_tests_the_top_of_a_range_of_no_whole_steps(fake_trials: list[float],
                                                              high: float) -> None:
    """1.61 − 0.02 mm/s is 7.95 scan steps: 1.61 mm/s is tested, so the answer is 1.56 mm/s,
    as with --high 1.7 (old: "above-range", the highest trial 1.42 mm/s)."""
    res = fd.critical_speed_from_rest(_system(), speed_range=(0.02 * MM, high * MM))
    speeds = [t.speed for t in res.trials]
    assert max(speeds) == pytest.approx(high * MM, abs=1e-12)
    assert min(speeds) == pytest.approx(0.02 * MM, abs=1e-12)
    assert res.speed_range == (min(speeds), max(speeds))
    assert (res.status, res.kind) == ("found", "oscillation")
    assert res.critical_speed == pytest.approx(1.56 * MM, abs=1e-12)


@pytest.mark.parametrize("high", [1.61, 1.6, 1.7])
def test_the_stepdown_starts_at_the_top_of_a_range_of_no_whole_steps(
        fake_trials: list[float], high: float) -> None:
    """The staircase from 1.6 mm/s began at 1.52 mm/s (old: "> 1.60 mm/s"); it now starts
    at --high and ends at the lowest speed, and finds 1.56 mm/s from every start."""
    res = fd.critical_speed_stepdown(_system(), start_speed=high * MM, lowest_speed=0.02 * MM)
    assert fake_trials[0] == pytest.approx(high * MM, abs=1e-12)
    speeds = [t.speed for t in res.trials]
    assert max(speeds) == pytest.approx(high * MM, abs=1e-12)
    assert min(speeds) == pytest.approx(0.02 * MM, abs=1e-12)
    assert res.speed_range == (min(speeds), max(speeds))
    assert res.status == "found"
    assert res.critical_speed == pytest.approx(1.56 * MM, abs=1e-12)


def test_creeping_at_the_top_is_above_the_range_tested(fake_trials: list[float],
                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    """"> 1.61 mm/s" is said only when 1.61 mm/s itself was tested and creeps."""
    def run_trial(system: object, speed: float, *args: object,
                  ) -> tuple[CreepTrial, np.ndarray, np.ndarray]:
        fake_trials.append(speed)
        return _trial(speed, edge=9.0 * MM), np.zeros(2), np.full(2, speed)

    monkeypatch.setattr(critical, "_run_trial", run_trial)
    res = fd.critical_speed_from_rest(_system(), speed_range=(0.02 * MM, 1.61 * MM))
    assert res.status == "above-range"
    assert max(fake_trials) == pytest.approx(1.61 * MM, abs=1e-12)
    assert res.display().startswith("> 1.61 mm/s (creeps at every tested speed")


def test_the_grid_is_the_whole_steps_and_the_top() -> None:
    """The coarse grid is the whole steps from the bottom, as before, and the top when that
    is not one of them: the protocol's own ranges (0.02–3.02 mm/s: 15 scan steps of 0.2 mm/s,
    30 staircase steps of 0.1 mm/s) give the speeds they gave, so ``reproduce`` does not
    change."""
    lo = protocol.SPEED_RANGE[0]
    cases = [(protocol.SPEED_RANGE[1], protocol.COARSE_STEP, 16, False),
             (protocol.SPEED_RANGE[1], protocol.STAIRCASE_COARSE_STEP, 31, False),
             (1.61 * MM, protocol.COARSE_STEP, 8, True),
             (1.6 * MM, protocol.STAIRCASE_COARSE_STEP, 16, True)]
    for hi, step, whole, top in cases:
        expected = np.round(lo + step * np.arange(whole), 12).tolist() + ([hi] if top else [])
        assert protocol.speed_grid(lo, hi, step).tolist() == pytest.approx(expected, abs=1e-15), hi


def test_the_command_line_states_the_range_it_tested(fake_trials: list[float]) -> None:
    """`creep --high 1.61`: both searches test 1.61 mm/s, answer 1.56 mm/s (old: "> 1.61",
    bands ending at 1.42), and the protocol lines state 0.02–1.61 mm/s."""
    from typer.testing import CliRunner

    from feeddrive.cli import app

    args = ["creep", "--high", "1.61", "--error-estimate", "none"]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 0, res.output
    lines = res.output.splitlines()
    answers = [ln for ln in lines if "critical creeping speed" in ln]
    assert len(answers) == 2, res.output
    for line in answers:
        assert "critical creeping speed 1.56 mm/s, oscillation below it" in line, line
        assert line.endswith("creeping bands [mm/s]: 0.02–1.55 oscillation"), line
    protocols = [ln for ln in lines if ln.startswith("  protocol ")]
    assert "scan 0.02–1.61 mm/s" in protocols[0], protocols
    assert "staircase from 1.61 mm/s" in protocols[1], protocols
    res = CliRunner().invoke(app, [*args, "--json"])
    assert res.exit_code == 0, res.output
    for search in json.loads(res.output)["searches"]:
        speeds = [t["speed"] for t in search["trials"]]
        assert search["speed_range_mm_s"] == [pytest.approx(min(speeds)),
                                              pytest.approx(max(speeds))]
        assert max(speeds) == pytest.approx(1.61)
        assert search["critical_speed_mm_s"] == pytest.approx(1.56)
