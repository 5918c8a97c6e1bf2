"""Critical-speed search logic on synthetic judges and traces with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from feeddrive.analysis.critical import _staircase, judge_staircase, search_boundary

MM = 1e-3


def test_boundary_found_to_resolution() -> None:
    # a drive that creeps below 1.234 mm/s: the smooth end of the boundary is 1.24 mm/s
    calls: list[float] = []

    def creeps(v: float) -> bool:
        calls.append(v)
        return v < 1.234 * MM

    status, crit = search_boundary(creeps, 0.1 * MM, 3.0 * MM, 0.2 * MM, 0.01 * MM)
    assert status == "found"
    assert crit == pytest.approx(1.24 * MM, abs=1e-9)
    assert len(calls) == len(set(calls)) <= 15 + 6


def test_highest_boundary_of_a_creeping_band() -> None:
    # creeping only between 0.5 and 1.0 mm/s (a band, as a weak loop gives the DDFS)
    status, crit = search_boundary(lambda v: 0.5 * MM <= v < 1.0 * MM, 0.1 * MM, 3.0 * MM,
                                   0.1 * MM, 0.01 * MM)
    assert status == "found"
    assert crit == pytest.approx(1.0 * MM, abs=1e-9)


@pytest.mark.parametrize(("flag", "status"), [(True, "above-range"), (False, "below-range")])
def test_out_of_range(flag: bool, status: str) -> None:
    assert search_boundary(lambda v: flag, 0.1 * MM, 3.0 * MM, 0.2 * MM, 0.01 * MM) == (status,
                                                                                         None)


def test_staircase_profile_steps_down() -> None:
    speeds = np.array([2.0, 1.9, 1.8]) * MM
    profile, starts = _staircase(speeds, dwell=2.0, lead_in=3.0, nut_speed=0.0)
    t, v = profile.time, profile.table_speed
    assert starts.tolist() == [3.0, 5.0, 7.0]
    for s, t0 in zip(speeds, starts, strict=True):
        sel = (t > t0 + 0.01) & (t < t0 + 1.99)
        assert np.allclose(v[sel], s)
    assert t[-1] == pytest.approx(9.0)


def test_stepdown_judged_on_a_synthetic_trace() -> None:
    # smooth at 2.0 and 1.9 mm/s, stick-slip (1 Hz sawtooth with sticking) at 1.8 mm/s
    speeds = np.array([2.0, 1.9, 1.8, 1.7]) * MM
    starts = np.array([0.0, 4.0, 8.0, 12.0])
    t = np.arange(0, 16.0, 1e-3)
    v = np.interp(t, starts, speeds, left=speeds[0], right=speeds[-1])
    v = speeds[np.clip(np.searchsorted(starts, t, side="right") - 1, 0, 3)].copy()
    seg = (t >= 8.0) & (t < 12.0)
    phase = (t[seg] - 8.0) % 1.0
    v[seg] = np.where(phase < 0.5, 0.0, 3.6 * MM)  # mean 1.8, half the time stuck
    trials = judge_staircase(t, v, speeds, starts, dwell=4.0)
    assert [tr.creeping for tr in trials] == [False, False, True]
    assert trials[-1].stick_fraction == pytest.approx(0.5, abs=0.01)


def _trace(kind: str) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(0, 12.0, 1e-3)
    v0 = 1.5 * MM
    if kind == "decaying":  # weakly damped start-up oscillation, still large at the end
        return t, v0 * (1 + 2.0 * np.exp(-t / 6.0) * np.sin(2 * np.pi * 5 * t))
    if kind == "stick-slip":  # persistent 2-Hz stick-slip: stuck half the time
        return t, np.where((t % 0.5) < 0.25, 0.0, 2 * v0)
    return t, np.zeros_like(t)  # never breaks away


@pytest.mark.parametrize(("kind", "creeping"), [("decaying", False), ("stick-slip", True),
                                                ("stuck", True)])
def test_judge_trial_separates_transients_from_limit_cycles(kind: str, creeping: bool) -> None:
    from feeddrive.analysis.critical import judge_trial
    t, v = _trace(kind)
    trial = judge_trial(t, v, 1.5 * MM)
    assert trial.creeping is creeping
    if kind == "decaying":
        # the metrics alone call the last quarter creeping (ripple ≈ 0.9 > 0.5) ...
        assert trial.ripple_ratio > 0.5
        # ... but it decays: exp(-3/6) of the quarter before
        assert trial.decay_ratio == pytest.approx(np.exp(-0.5), rel=0.05)
