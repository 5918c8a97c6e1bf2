"""Creep analysis of position traces (feeddrive.analysis.trace) on synthetic step-down runs.

The step-down protocol is Wang2021 Sect. 6: the commanded speed is lowered in 0.01 mm/s
steps until the table crawls.  Smooth segments settle exponentially (τ = 0.2 s) to their
command; creeping segments are a 2 Hz stick-slip sawtooth whose mean equals the command.
Positions are rounded to 1 nm (interferometer resolution).
"""

from __future__ import annotations

import numpy as np
import pytest

from feeddrive.analysis.trace import analyze_trace, estimate_speed, find_segments, savgol_window

FS = 1000.0
SEGMENT = 10.0


def speed_profile(commands: list[float], creeping: list[bool]) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(0.0, SEGMENT * len(commands), 1.0 / FS)
    v = np.zeros_like(t)
    previous = 0.0
    for i, (c, creeps) in enumerate(zip(commands, creeping, strict=True)):
        sel = (t >= i * SEGMENT) & (t < (i + 1) * SEGMENT)
        local = t[sel] - i * SEGMENT
        if creeps:
            period, stick = 0.5, 0.2
            peak = 2.0 * c * period / (period - stick)
            phase = np.mod(local, period)
            v[sel] = np.where(phase < stick, 0.0, peak * (1 - (phase - stick) / (period - stick)))
        else:
            v[sel] = c + (previous - c) * np.exp(-local / 0.2)
        previous = c
    return t, v


def position_of(t: np.ndarray, v: np.ndarray) -> np.ndarray:
    x = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) / FS)])
    return np.round(x / 1e-9) * 1e-9


STEPS = [1.70e-3, 1.69e-3, 1.68e-3, 1.67e-3, 1.66e-3]
CREEPS = [False, False, False, True, True]


@pytest.fixture(scope="module")
def step_down() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t, v = speed_profile(STEPS, CREEPS)
    return t, position_of(t, v), np.repeat(STEPS, int(SEGMENT * FS))


def test_savgol_window_from_sample_rate() -> None:
    assert savgol_window(1e-3) == 21  # 20 ms at 1 kHz
    assert savgol_window(1e-4) == 201
    assert savgol_window(0.1) == 5  # never fewer than polyorder + 3
    assert savgol_window(1e-3, smoothing_time=0.05) == 51


def test_savgol_speed_of_a_ramp_and_a_sine() -> None:
    t = np.arange(0.0, 2.0, 1e-3)
    est = estimate_speed(t, 1.5e-3 * t + 2e-6 * np.sin(2 * np.pi * 2.0 * t))
    ripple = 2e-6 * 2 * np.pi * 2.0
    exact = 1.5e-3 + ripple * np.cos(2 * np.pi * 2.0 * t)
    # a 2 Hz stick-slip ripple passes the 20 ms window with less than 1 % loss
    assert np.max(np.abs(est.speed - exact)) < 0.01 * ripple
    assert est.window == 21 and not est.resampled


def test_uneven_sampling_is_resampled() -> None:
    rng = np.random.default_rng(0)
    t = np.cumsum(1e-3 * (1 + 0.2 * rng.random(2000)))
    est = estimate_speed(t, 1e-3 * t)
    assert est.resampled
    assert np.allclose(est.speed, 1e-3, rtol=1e-6)


def test_step_down_with_command_column(step_down: tuple) -> None:
    t, x, cmd = step_down
    a = analyze_trace(t, x, command=cmd)
    assert [s.command_speed for s in a.segments] == pytest.approx(STEPS)
    assert [s.metrics.creeping for s in a.segments] == CREEPS
    (crit,) = a.critical
    assert crit.lowest_smooth == pytest.approx(1.68e-3)
    assert crit.first_creeping == pytest.approx(1.67e-3)
    assert crit.monotonic
    assert a.segments[3].metrics.stick_slip_frequency == pytest.approx(2.0, rel=0.02)


def test_step_down_segments_detected_without_command(step_down: tuple) -> None:
    t, x, _ = step_down
    a = analyze_trace(t, x)
    smooth = [s for s in a.segments if not s.metrics.creeping]
    # the three smooth levels are resolved, each estimated to 0.1 µm/s
    assert [s.command_speed for s in smooth] == pytest.approx(STEPS[:3], abs=1e-7)
    assert all(s.command_from == "estimated" for s in a.segments)
    # the creeping levels differ by less than their ripple allows: reported as one
    creeping = [s for s in a.segments if s.metrics.creeping]
    assert len(creeping) == 1
    assert creeping[0].start == pytest.approx(30.0, abs=0.1)
    (crit,) = a.critical
    assert crit.lowest_smooth == pytest.approx(1.68e-3, abs=1e-7)
    assert crit.first_creeping == pytest.approx(1.665e-3, abs=1e-5)
    assert any("estimated" in n for n in a.notes)


def test_single_creeping_run_from_rest() -> None:
    t, v = speed_profile([1.55e-3], [True])
    a = analyze_trace(t, position_of(t, v))
    (seg,) = a.segments
    assert seg.metrics.verdict == "creeping"
    assert seg.command_speed == pytest.approx(1.55e-3, rel=0.01)
    assert a.critical == ()  # one segment: no step-down


def test_given_command_speed_is_one_segment(step_down: tuple) -> None:
    t, x, _ = step_down
    a = analyze_trace(t, x, command_speed=1.7e-3)
    (seg,) = a.segments
    assert seg.command_from == "given"
    assert seg.metrics.creeping  # the window (second half) creeps


def test_negative_direction_trace() -> None:
    t, v = speed_profile(STEPS, CREEPS)
    a = analyze_trace(t, position_of(t, -v))
    crit = {c.direction: c for c in a.critical}
    assert crit["negative"].lowest_smooth == pytest.approx(1.68e-3, abs=1e-7)


def test_rest_between_runs_is_skipped() -> None:
    t, v = speed_profile([1.7e-3, 0.0, 1.6e-3], [False, False, False])
    a = analyze_trace(t, position_of(t, v))
    assert [s.command_speed for s in a.segments] == pytest.approx([1.7e-3, 1.6e-3], abs=1e-6)


def test_find_segments_does_not_split_stick_slip() -> None:
    t, v = speed_profile([1.6e-3] * 3, [True] * 3)
    x = position_of(t, v)
    spans = find_segments(t, x, np.gradient(x, t))
    assert len(spans) == 1


def test_static_table_is_refused() -> None:
    t = np.arange(0.0, 5.0, 1e-3)
    with pytest.raises(ValueError, match="does not move"):
        analyze_trace(t, np.zeros_like(t))
