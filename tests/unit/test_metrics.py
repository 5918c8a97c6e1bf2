"""Creep metrics on synthetic traces with known answers (feeddrive.analysis.creep_window)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from feeddrive.analysis.creep_window import CreepThresholds, creep_metrics, steady_window

V_CMD = 1.55e-3  # m/s, the CDFS creeping speed of Wang2021 Sect. 5.2


def sawtooth_stick_slip(period: float, stick: float, peak: float, t_end: float,
                        fs: float = 2000.0) -> tuple[np.ndarray, np.ndarray]:
    """Speed 0 for ``stick`` s, then a jump to ``peak`` falling linearly to 0, period ``period``.

    The mean speed is peak·(period − stick)/(2·period).
    """
    t = np.arange(0.0, t_end, 1.0 / fs)
    phase = np.mod(t, period)
    slip = period - stick
    v = np.where(phase < stick, 0.0, peak * (1.0 - (phase - stick) / slip))
    return t, v


def test_constant_trace_is_smooth_with_zero_ripple() -> None:
    t = np.linspace(0.0, 5.0, 2001)
    v = np.full_like(t, V_CMD)
    m = creep_metrics(t, v, V_CMD)
    assert m.verdict == "smooth"
    assert m.ripple_ratio == pytest.approx(0.0, abs=1e-12)
    assert m.min_ratio == pytest.approx(1.0)
    assert m.stick_fraction == 0.0
    assert m.stick_slip_frequency is None
    assert m.mean_speed == pytest.approx(V_CMD)


def test_sawtooth_stick_slip_frequency_and_stick_fraction() -> None:
    period, stick = 0.5, 0.2  # 2 Hz, sticking 40 % of each cycle
    slip = period - stick
    peak = 2.0 * V_CMD * period / slip  # mean speed equals the command
    t, v = sawtooth_stick_slip(period, stick, peak, t_end=10.0)
    m = creep_metrics(t, v, V_CMD)
    assert m.verdict == "creeping"
    assert m.stick_slip_frequency == pytest.approx(2.0, rel=0.02)
    level = 0.1 * V_CMD
    expected_stick = (stick + slip * level / peak) / period  # plateau + the ramp's last part
    assert m.stick_fraction == pytest.approx(expected_stick, abs=0.003)
    assert m.ripple_ratio == pytest.approx(peak / V_CMD, rel=1e-3)
    assert m.min_ratio == 0.0
    assert m.mean_speed == pytest.approx(V_CMD, rel=0.03)


def test_sinusoidal_ripple_ratio_and_frequency() -> None:
    amplitude = 0.1 * V_CMD  # ripple ratio 2·0.1 = 0.2: below the 0.5 limit, no sticking
    t = np.arange(0.0, 8.0, 1e-3)
    v = V_CMD + amplitude * np.sin(2 * math.pi * 3.3 * t)
    m = creep_metrics(t, v, V_CMD)
    assert m.ripple_ratio == pytest.approx(0.2, rel=1e-3)
    assert m.min_ratio == pytest.approx(0.9, rel=1e-3)
    assert m.stick_fraction == 0.0
    assert m.verdict == "smooth"
    assert m.stick_slip_frequency == pytest.approx(3.3, rel=0.01)


def test_large_sinusoidal_ripple_is_creeping_by_ripple_limit() -> None:
    t = np.arange(0.0, 8.0, 1e-3)
    v = V_CMD * (1.0 + 0.3 * np.sin(2 * math.pi * 2.0 * t))
    m = creep_metrics(t, v, V_CMD)
    assert m.stick_fraction == 0.0
    assert m.ripple_ratio == pytest.approx(0.6, rel=1e-3)
    assert m.verdict == "creeping"


def test_negative_command_uses_magnitudes() -> None:
    period, stick = 0.25, 0.1
    peak = 2.0 * V_CMD * period / (period - stick)
    t, v = sawtooth_stick_slip(period, stick, peak, t_end=6.0)
    pos = creep_metrics(t, v, V_CMD)
    neg = creep_metrics(t, -v, -V_CMD)
    assert neg.verdict == pos.verdict == "creeping"
    assert neg.stick_fraction == pytest.approx(pos.stick_fraction)
    assert neg.ripple_ratio == pytest.approx(pos.ripple_ratio)
    assert neg.stick_slip_frequency == pytest.approx(4.0, rel=0.02)
    assert neg.mean_speed == pytest.approx(-pos.mean_speed)


def test_white_noise_ripple_has_no_frequency() -> None:
    rng = np.random.default_rng(1)
    t = np.arange(0.0, 5.0, 1e-3)
    v = V_CMD * (1.0 + 0.02 * rng.standard_normal(t.size))
    m = creep_metrics(t, v, V_CMD)
    assert m.ripple_ratio > 0.02  # the noise is not negligible ...
    assert m.stick_slip_frequency is None  # ... but not periodic either
    assert m.verdict == "smooth"


def test_stick_fraction_is_time_weighted_on_uneven_sampling() -> None:
    # dense samples while sticking must not inflate the stick fraction
    t_stick = np.linspace(0.0, 1.0, 1000, endpoint=False)
    t_move = np.linspace(1.0, 4.0, 30)
    t = np.concatenate([t_stick, t_move])
    v = np.where(t < 1.0, 0.0, V_CMD)
    v[t_stick.size] = 0.0  # leave the stop at exactly t = 1 s
    m = creep_metrics(t, v, V_CMD, window=(0.0, 4.0))
    ramp = (t_move[1] - t_move[0]) * 0.1  # the 0 → v_cmd ramp spends 10 % of a step below
    assert m.stick_fraction == pytest.approx((1.0 + ramp) / 4.0, rel=1e-9)


def test_steady_window_rule() -> None:
    t = np.linspace(0.0, 10.0, 1001)
    v = V_CMD * np.clip(t / 2.5, 0.0, 1.0)  # reaches 90 % at 2.25 s
    start, end = steady_window(t, v, V_CMD)
    assert start == pytest.approx(2.25 + 1.0, abs=0.011)  # + 10 % settling margin
    assert end == 10.0
    # reaching the command early cannot start the window before 20 % of the record
    assert steady_window(t, np.full_like(t, V_CMD), V_CMD)[0] == pytest.approx(2.0)
    # a table that never reaches the command gets the second half
    assert steady_window(t, np.zeros_like(t), V_CMD)[0] == pytest.approx(5.0)
    # a late arrival is capped at 50 %
    late = V_CMD * (t > 8.0)
    assert steady_window(t, late, V_CMD)[0] == pytest.approx(5.0)


def test_steady_window_skips_start_transient() -> None:
    t = np.arange(0.0, 10.0, 1e-3)
    v = V_CMD * (1.0 - np.exp(-t / 0.2)) * (1.0 + 0.8 * np.exp(-t / 0.3) * np.sin(20 * t))
    m = creep_metrics(t, v, V_CMD)
    assert m.window_start >= 2.0
    assert m.verdict == "smooth"
    assert m.ripple_ratio < 0.01


def test_stuck_table_is_creeping() -> None:
    t = np.linspace(0.0, 2.0, 200)
    m = creep_metrics(t, np.zeros_like(t), V_CMD)
    assert m.stick_fraction == pytest.approx(1.0)
    assert m.verdict == "creeping"


def test_thresholds_change_the_verdict() -> None:
    t = np.arange(0.0, 8.0, 1e-3)
    v = V_CMD * (1.0 + 0.3 * np.sin(2 * math.pi * 2.0 * t))
    lenient = CreepThresholds(max_ripple_ratio=0.7)
    assert creep_metrics(t, v, V_CMD, thresholds=lenient).verdict == "smooth"


def test_to_dict_units() -> None:
    t = np.linspace(0.0, 5.0, 501)
    m = creep_metrics(t, np.full_like(t, V_CMD), V_CMD)
    si, mm = m.to_dict(), m.to_dict("mm")
    assert si["command_speed"] == pytest.approx(V_CMD)
    assert mm["command_speed"] == pytest.approx(1.55)
    assert mm["units"]["speed"] == "mm/s"
    assert si["thresholds"]["stick_level"] == 0.1
    with pytest.raises(ValueError, match="units"):
        m.to_dict("inch")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("time", "speed", "command", "match"),
    [
        (np.arange(20.0), np.ones(19), 1.0, "speed: length 19"),
        (np.r_[np.arange(10.0), np.arange(10.0)], np.ones(20), 1.0, "time: not strictly"),
        (np.arange(20.0), np.r_[np.ones(19), np.nan], 1.0, "speed: not finite at index 19"),
        (np.r_[np.inf, np.arange(19.0)], np.ones(20), 1.0, "time: not finite"),
        (np.arange(20.0), np.ones(20), 0.0, "command_speed"),
        (np.arange(20.0), np.ones(20), float("nan"), "command_speed"),
        (np.arange(5.0), np.ones(5), 1.0, "time: 5 samples"),
    ],
)
def test_bad_input_names_the_argument(time: np.ndarray, speed: np.ndarray, command: float,
                                      match: str) -> None:
    with pytest.raises(ValueError, match=match):
        creep_metrics(time, speed, command)


def test_bad_window_and_thresholds() -> None:
    t = np.linspace(0.0, 1.0, 100)
    v = np.ones_like(t)
    with pytest.raises(ValueError, match="window"):
        creep_metrics(t, v, 1.0, window=(0.5, 0.2))
    with pytest.raises(ValueError, match="window: only"):
        creep_metrics(t, v, 1.0, window=(0.5, 0.52))
    with pytest.raises(ValueError, match="stick_level"):
        CreepThresholds(stick_level=1.5)


def test_steady_window_skips_a_decaying_start_up_oscillation() -> None:
    # a weakly damped servo transient (5 Hz, time constant 0.6 s) is not creep: the window
    # moves past it and the verdict is smooth; constant-amplitude stick-slip keeps the
    # window of the base rule and stays creeping
    from feeddrive.analysis.creep_window import creep_metrics, steady_window
    t = np.arange(0.0, 5.0, 1e-3)
    v0 = 0.5e-3
    decaying = v0 * (1 + 2.0 * np.exp(-t / 0.6) * np.sin(2 * np.pi * 5 * t))
    start, end = steady_window(t, decaying, v0)
    assert start >= 2.5 and end == pytest.approx(t[-1])
    assert creep_metrics(t, decaying, v0).verdict == "smooth"
    stick_slip = np.where((t % 0.5) < 0.25, 0.0, 2 * v0)
    assert steady_window(t, stick_slip, v0) == steady_window(t, stick_slip, v0, persistence=0.0)
    assert creep_metrics(t, stick_slip, v0).verdict == "creeping"


def _traces() -> list[tuple[np.ndarray, float]]:
    """Traces of the kinds the creep window sees: noise, a ripple on a ramp, a random walk,
    stick-slip with jitter; odd and even lengths, the engine's 1-ms grid and others."""
    rng = np.random.default_rng(20261202)
    out = []
    for trial in range(120):
        n = int(rng.integers(10, 6000))
        dt = (1e-3, 2e-3, 5e-4, float(rng.uniform(1e-4, 1e-2)))[trial % 4]
        t = np.arange(n) * dt
        kind = trial % 4
        if kind == 0:
            x = rng.normal(size=n)
        elif kind == 1:
            x = (2e-3 + 1e-3 * np.sin(2 * np.pi * rng.uniform(0.5, 50) * t)
                 + 1e-7 * rng.normal(size=n) + 1e-4 * t)
        elif kind == 2:
            x = np.cumsum(rng.normal(size=n)) * 1e-5
        else:
            x = (np.where(np.sin(2 * np.pi * rng.uniform(1, 20) * t) > 0.3, 0.0, 4e-3)
                 + 1e-9 * rng.normal(size=n))
        out.append((x, dt))
    return out


def test_hann_periodogram_is_scipys_bit_for_bit() -> None:
    """The creep window's periodogram is computed with numpy so that a short `simulate` does not
    import scipy.signal (issue 21 item 4); every reported stick-slip frequency must stay the
    same to the last bit: scipy.signal.periodogram (window "hann", detrend "linear", the
    padded FFT length the metrics use) is the reference."""
    import scipy
    from scipy.signal import periodogram

    from feeddrive.analysis.creep_window import hann_periodogram

    # bit for bit against the scipy the function mirrors (its docstring: scipy 1.17's
    # ShortTimeFFT-based periodogram); the minimum-versions job's scipy 1.11 sums in another
    # order (measured: powers within 5.5e-15 of the peak, frequencies and peak bin equal), so
    # there the same frequencies, the same peak bin and the powers to 1e-13 of the peak
    exact = tuple(int(v) for v in scipy.__version__.split(".")[:2]) >= (1, 17)
    for x, dt in _traces():
        nfft = 1 << math.ceil(math.log2(8 * x.size))
        for size in (nfft, nfft + 1):  # the metrics' power of two, and an odd length
            f_ref, p_ref = periodogram(x, fs=1.0 / dt, window="hann", detrend="linear",
                                       nfft=size)
            f, p = hann_periodogram(x, 1.0 / dt, size)
            assert np.array_equal(f, f_ref)
            if exact:
                assert np.array_equal(p, p_ref)
            else:
                assert int(np.argmax(p)) == int(np.argmax(p_ref))
                assert np.max(np.abs(p - p_ref)) <= 1e-13 * np.max(p_ref)
