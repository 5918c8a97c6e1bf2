"""Creep analysis of a measured (or exported) table position trace.  SI units.

Pipeline: position [m] → speed by a Savitzky–Golay differentiator → segments (one per
commanded speed) → :func:`feeddrive.analysis.creep_window.creep_metrics` per segment → critical
speed of a step-down run (Wang2021 Sect. 6: the speed is lowered in 0.01 mm/s steps until
the table crawls).

Speed estimate
    ``scipy.signal.savgol_filter(position, window, polyorder=2, deriv=1)``.  The default
    window spans ``smoothing_time`` = 20 ms (at least 5 samples, odd): about a −3 dB cut-off
    of 1/(3.2·window) ≈ 15 Hz, which keeps stick-slip cycles (periods of 0.1 s and more at
    the speeds of Wang2021) and suppresses interferometer quantisation noise.  Override with
    ``smoothing_time`` or ``window``.  Unevenly sampled traces (jitter > 1 % of the median
    step) are first interpolated onto a uniform grid.

Segments
    From a command-speed column when the file has one (runs of equal command), else
    detected in two stages, starting ``min_segment_time`` after the table has first reached
    90 % of its overall mean speed (the run-up and its settling are not a segment):

    1. *regimes*: each sample is labelled rest (local mean speed below 1 % of the fastest),
       creeping (over a sliding window of ``min_segment_time`` the stick fraction or the
       ripple ratio exceeds its :class:`CreepThresholds` limit, against the local mean
       speed) or smooth; runs shorter than ``min_segment_time`` join a neighbour, and moving
       runs shorter than twice that next to a rest are taken as its stop or start;
    2. *speed steps* within each smooth or creeping run: binary segmentation of the position
       into straight lines (constant mean speed).  A split is kept when the two sides' mean
       speeds differ by more than ``min_step`` *and* by more than their worst-case error
       3·d/L per side (d the largest deviation of the position from that side's line, L its
       duration: the least-squares slope through data within ±d of a line is off by at most
       3d/L).  So stick-slip ripple never splits a segment, and neighbouring creeping
       segments whose speeds differ by less than their ripple allows are reported as one.

    Rests are skipped; no segment is shorter than ``min_segment_time``.  A detected segment
    ends one smoothing window plus 5 % of ``min_segment_time`` before the detected edge.

Command speed
    A segment's command speed is the given one, the file's column, or, when neither exists,
    *estimated* as the mean speed (least-squares slope of the position) over the segment's
    steady window.  The mean and not the median: a position-controlled axis that creeps
    still advances at the commanded mean speed, whereas the median of a stick-slip speed is
    near zero.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from ..parameters import ParameterError
from ..parameters.validation import MISSING, check_flag, check_speed, is_real
from ..units import LARGEST_SPEED
from .creep_window import CreepMetrics, CreepThresholds, creep_metrics, steady_window
from .cycle_verdict import VerdictRule, trace_verdict
from .trace_input import resample_size
from .verdict_words import SMOOTH, UNDECIDED

__all__ = [
    "CriticalSpeed",
    "SpeedEstimate",
    "TraceAnalysis",
    "TraceSegment",
    "analyze_trace",
    "estimate_speed",
    "find_segments",
    "hold_settled",
    "savgol_window",
]

DEFAULT_SMOOTHING_TIME = 0.02  # [s]
#: a given command speed this many times the trace's own mean speed is mm/s given where the
#: API takes m/s (1 m/s given for a 1-mm/s trace: every sample "sticks" below 10 % of the
#: command, and the verdict is creeping) …
UNIT_SLIP_FACTOR = 1000.0
#: … within this factor either way (half a decade: a drive that follows its command, even
#: by stick-slip, averages its command speed, a ratio near 1; one at rest has no mean speed)
UNIT_SLIP_TOLERANCE = math.sqrt(10.0)
DEFAULT_MIN_STEP = 5e-6  # [m/s], half the 0.01 mm/s step of Wang2021 Sect. 6
#: where the smallest speed step between segments applies, said when it is given elsewhere
MIN_STEP_APPLIES = "it splits the segments detected from the position, without a command"
DEFAULT_MIN_SEGMENT_TIME = 1.0  # [s]
_REST_FRACTION = 0.01
_MAX_SEGMENTATION_POINTS = 20000


def savgol_window(sample_time: float, *, smoothing_time: float = DEFAULT_SMOOTHING_TIME,
                  polyorder: int = 2) -> int:
    """Odd Savitzky–Golay window [samples] spanning ``smoothing_time`` [s], at least
    ``polyorder`` + 3 samples.

    Parameters
    ----------
    sample_time : float
        Sample interval [s].
    smoothing_time : float, default 0.02
        Window length [s].
    polyorder : int, default 2
        Polynomial order.

    Returns
    -------
    int
        The window [samples].
    """
    if not (is_real(sample_time) and sample_time > 0 and math.isfinite(sample_time)):
        raise ParameterError("sample_time", sample_time, "expected a finite step > 0 [s]")
    if not (is_real(smoothing_time) and smoothing_time > 0 and math.isfinite(smoothing_time)):
        raise ParameterError("smoothing_time", smoothing_time, "expected a finite time > 0 [s]")
    _check_polyorder(polyorder)
    n = int(round(smoothing_time / sample_time))
    n = max(n, polyorder + 3)
    return n if n % 2 else n + 1


def _whole(value: object) -> bool:
    """Whether ``value`` is a whole number (an int, not a bool)."""
    return not isinstance(value, bool) and isinstance(value, int | np.integer)


def _check_polyorder(polyorder: object) -> None:
    """Refuse a Savitzky–Golay order the speed (a first derivative) cannot come from: -1 was
    scipy's "expected deg >= 0", 0 a speed of zero everywhere."""
    if not _whole(polyorder) or int(polyorder) < 1:  # type: ignore[call-overload]
        raise ParameterError("polyorder", polyorder, "expected a whole number ≥ 1 (the "
                             "speed is the fitted polynomial's derivative) [-]")


@dataclass(frozen=True)
class SpeedEstimate:
    """Table speed from a position record by a Savitzky–Golay differentiator.

    Parameters
    ----------
    time : numpy.ndarray
        Uniform sample times [s].
    position : numpy.ndarray
        Position on that grid [m].
    speed : numpy.ndarray
        The estimated speed [m/s].
    window : int
        Filter window [samples].
    window_time : float
        Filter window [s].
    resampled : bool
        Whether the record was resampled onto a uniform grid.
    """
    time: np.ndarray  # [s], uniform
    position: np.ndarray  # [m] on that grid
    speed: np.ndarray  # [m/s]
    window: int  # samples
    window_time: float  # [s]
    resampled: bool


def estimate_speed(time: object, position: object, *, smoothing_time: float | None = None,
                   window: int | None = None, polyorder: int = 2,
                   lines: np.ndarray | None = None, source: str | None = None
                   ) -> SpeedEstimate:
    """Table speed [m/s] from position [m] by a Savitzky–Golay differentiator (see module).

    An uneven record is resampled onto a uniform grid of its median step, at most
    :data:`~feeddrive.analysis.trace_input.MAX_RESAMPLE_FACTOR` × its samples: a record with a
    gap is refused, naming the gap (``lines``: file line of each sample; ``source``: file).

    Parameters
    ----------
    time : array_like
        Sample times, increasing [s].
    position : array_like
        Table position [m].
    smoothing_time : float, optional
        Window as a time [s]; 20 ms by default.
    window : int, optional
        Window in samples instead (odd, > ``polyorder``).
    polyorder : int, default 2
        Polynomial order.
    lines : numpy.ndarray of int, optional
        The file line of each sample.
    source : str, optional
        The file.

    Returns
    -------
    SpeedEstimate
        The speed on a uniform grid.

    Raises
    ------
    ValueError
        For fewer than 16 samples, non-finite or non-increasing times, a gap or a bad window.

    References
    ----------
    .. [1] A. Savitzky, M. J. E. Golay, "Smoothing and differentiation of data by simplified
       least squares procedures", Anal. Chem. 36 (1964) 1627–1639.
    """
    # the window's settings first, before any work: 0 s was taken as the default (its `or`),
    # 2.5 samples and polyorder -1 were scipy's TypeError and "expected deg >= 0"
    if smoothing_time is not None and not (is_real(smoothing_time) and smoothing_time > 0 and
                                           math.isfinite(smoothing_time)):
        raise ParameterError("smoothing_time", smoothing_time, "expected a finite time > 0 [s]")
    if window is not None and not _whole(window):
        raise ParameterError("window", window, "expected an odd whole number of samples > "
                             "polyorder [samples]")
    _check_polyorder(polyorder)
    t = np.asarray(time, dtype=float)
    x = np.asarray(position, dtype=float)
    if t.ndim != 1 or x.shape != t.shape:
        raise ValueError(f"position: expected one value per time sample ({x.shape} vs "
                         f"{t.shape})")
    if t.size < 16:
        raise ValueError(f"time: {t.size} samples; need at least 16")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x))):
        raise ValueError("time, position: must be finite")
    steps = np.diff(t)
    if np.any(steps <= 0):
        i = int(np.flatnonzero(steps <= 0)[0]) + 1
        raise ValueError(f"time: not strictly increasing at index {i}")
    dt = float(np.median(steps))
    resampled = bool(np.max(np.abs(steps - dt)) > 0.01 * dt)
    if resampled:
        n = resample_size(t, dt, lines=lines, source=source)
        grid = t[0] + dt * np.arange(n)
        x = np.interp(grid, t, x)
        t = grid
    # the longest odd window the trace holds [samples]
    most = t.size - (1 - t.size % 2)
    trace = (f"({t.size} samples at its {dt * 1e3:.4g}-ms step); give a shorter --smoothing "
             f"(at most {most * dt * 1e3:.6g} ms) or a longer record")
    wanted = None
    if window is None:
        wanted = DEFAULT_SMOOTHING_TIME if smoothing_time is None else smoothing_time
        if wanted / dt > most + 1:  # before the count: 1e300 s printed a 300-digit integer
            raise ParameterError("smoothing_time", wanted, "expected a window not longer than "
                                 f"the trace, at most {most * dt:.6g} s [s] {trace}",
                                 source=source)
        window = savgol_window(dt, smoothing_time=wanted, polyorder=polyorder)
    if window % 2 == 0 or window <= polyorder:
        raise ParameterError("window", window, "expected an odd number of samples > "
                             f"polyorder = {polyorder} [samples]")
    if window > t.size:
        field, value, most_text = (("window", window, f"{most} samples [samples]")
                                   if wanted is None else
                                   ("smoothing_time", wanted, f"{most * dt:.6g} s [s]"))
        raise ParameterError(field, value, "expected a window not longer than the trace, at "
                             f"most {most_text} {trace}; it spans {window} samples "
                             f"({window * dt * 1e3:.4g} ms)", source=source)
    from scipy.signal import savgol_filter  # here: keeps `feeddrive --help` fast

    speed = savgol_filter(x, window, polyorder, deriv=1, delta=dt, mode="interp")
    return SpeedEstimate(time=t, position=x, speed=np.asarray(speed), window=window,
                         window_time=window * dt, resampled=resampled)


def savgol_gain(window: int, sample_time: float, frequency: float, polyorder: int = 2) -> float:
    """Amplitude the Savitzky–Golay differentiator passes of a sinusoidal speed at
    ``frequency`` [Hz], a fraction of it [-] (1 passes it whole): |H(f)| / (2πf) of its
    coefficients, exact for a sinusoid.

    Parameters
    ----------
    window : int
        Filter window [samples].
    sample_time : float
        Sample interval [s].
    frequency : float
        The ripple's frequency [Hz].
    polyorder : int, default 2
        Polynomial order.

    Returns
    -------
    float
        The gain [-].
    """
    from scipy.signal import savgol_coeffs

    coeffs = savgol_coeffs(window, polyorder, deriv=1, delta=sample_time, use="dot")
    k = np.arange(window) - window // 2
    w = 2.0 * math.pi * frequency
    return float(abs(np.sum(coeffs * np.exp(1j * w * k * sample_time))) / w)


def smoothing_note(metrics: CreepMetrics, window: int, sample_time: float) -> str | None:
    """What the speed filter takes off a segment's ripple at its detected frequency, when it
    moves the printed ripple (more than half a unit of its third significant digit), else
    None.  The docs' 20-ms window was justified by a 2-Hz ripple (< 1 % loss); the CDFS of
    Wang2021 sticks and slips at 5.47 Hz, where it takes 1.3 % of the fundamental and more
    of the harmonics that make the stick phase (an outside check, 2026-12-07: min ratio
    −0.0294 from the 21-ms window, −0.0569 from the exact speed; stick 0.117 vs 0.125).

    Parameters
    ----------
    metrics : CreepMetrics
        The segment's metrics from the filtered speed.
    window : int
        Filter window [samples].
    sample_time : float
        Sample interval [s].

    Returns
    -------
    str or None
        The note: the gain at the fundamental and its 2nd and 3rd harmonics.

    References
    ----------
    Savitzky, A., Golay, M. J. E. (1964). Smoothing and differentiation of data by simplified
    least squares procedures. Analytical Chemistry 36(8), 1627–1639.
    Wang2021 Sect. 5: the CDFS's low-speed stick-slip.
    """
    f = metrics.stick_slip_frequency
    if f is None or window < 3:
        return None
    gains = [savgol_gain(window, sample_time, n * f) for n in (1, 2, 3)]
    ripple = metrics.ripple_ratio
    digit = 0.5 * 10.0 ** (math.floor(math.log10(float(f"{ripple:.3g}"))) - 2)
    if (1.0 - gains[0]) * ripple <= digit:
        return None
    return (f"the {1e3 * window * sample_time:.3g}-ms speed filter passes "
            f"{100 * gains[0]:.3g} % of the {f:.3g}-Hz ripple ({100 * gains[1]:.3g} and "
            f"{100 * gains[2]:.3g} % of its 2nd and 3rd harmonics): ripple, min ratio and "
            "stick fraction are of the filtered speed (a stick-slip's minimum less deep, its "
            "stick shorter); a shorter --smoothing, or the speed column, loses less")


# ---------------------------------------------------------------- segmentation


class _LineCost:
    """O(1) least-squares line fits of x(t) over index ranges, from cumulative sums."""

    def __init__(self, t: np.ndarray, x: np.ndarray) -> None:
        self.t, self.x = t, x
        zero = np.zeros(1)
        self.c1 = np.arange(t.size + 1, dtype=float)
        self.ct = np.concatenate([zero, np.cumsum(t)])
        self.ctt = np.concatenate([zero, np.cumsum(t * t)])
        self.cx = np.concatenate([zero, np.cumsum(x)])
        self.ctx = np.concatenate([zero, np.cumsum(t * x)])
        self.cxx = np.concatenate([zero, np.cumsum(x * x)])

    def sse(self, a: np.ndarray | int, b: np.ndarray | int) -> np.ndarray:
        n = self.c1[b] - self.c1[a]
        st = self.ct[b] - self.ct[a]
        stt = self.ctt[b] - self.ctt[a]
        sx = self.cx[b] - self.cx[a]
        stx = self.ctx[b] - self.ctx[a]
        sxx = self.cxx[b] - self.cxx[a]
        vt = stt - st * st / n
        cov = stx - st * sx / n
        vx = sxx - sx * sx / n
        return np.asarray(np.maximum(vx - cov * cov / np.where(vt > 0, vt, np.inf), 0.0))

    def line(self, a: int, b: int) -> tuple[float, float]:
        """(slope, worst-case slope error 3·max|deviation|/duration) over [a, b)."""
        tt, xx = self.t[a:b], self.x[a:b]
        slope, icpt = np.polyfit(tt, xx, 1)
        dev = float(np.max(np.abs(xx - (slope * tt + icpt))))
        return float(slope), 3.0 * dev / float(tt[-1] - tt[0])


def _split_ok(cost: _LineCost, a: int, k: int, b: int, min_step: float) -> bool:
    s1, e1 = cost.line(a, k)
    s2, e2 = cost.line(k, b)
    return abs(s1 - s2) > max(min_step, e1 + e2)


def _regimes(t: np.ndarray, x: np.ndarray, v: np.ndarray, width: int,
             th: CreepThresholds) -> np.ndarray:
    """Per-sample regime: 0 rest, 1 smooth, 2 creeping, judged over a sliding window."""
    half = 0.5 * (t[min(width, t.size - 1)] - t[0])
    lo = np.interp(t - half, t, x)
    hi = np.interp(t + half, t, x)
    span = np.minimum(t + half, t[-1]) - np.maximum(t - half, t[0])
    local = (hi - lo) / span  # mean speed over the window around each sample
    ref = np.abs(local)
    along = v * np.sign(local)
    from scipy.ndimage import maximum_filter1d, minimum_filter1d, uniform_filter1d

    stick = uniform_filter1d((along < th.stick_level * ref).astype(float), width,
                             mode="nearest")
    ripple = (maximum_filter1d(along, width, mode="nearest")
              - minimum_filter1d(along, width, mode="nearest")) / np.maximum(ref, 1e-300)
    label = np.where((stick > th.max_stick_fraction) | (ripple > th.max_ripple_ratio), 2, 1)
    return np.where(ref < _REST_FRACTION * float(np.max(ref)), 0, label)


def _runs(label: np.ndarray, min_n: int) -> list[list[int]]:
    """[start, end, label] runs, runs shorter than ``min_n`` merged into a neighbour."""
    change = np.flatnonzero(np.diff(label)) + 1
    starts = np.r_[0, change]
    ends = np.r_[change, label.size]
    runs = [[int(a), int(b), int(label[a])] for a, b in zip(starts, ends, strict=True)]
    while len(runs) > 1:
        lengths = [r[1] - r[0] for r in runs]
        i = int(np.argmin(lengths))
        if lengths[i] >= min_n:
            break
        # absorb into the longer neighbour
        j = i - 1 if i == len(runs) - 1 or (i > 0 and lengths[i - 1] >= lengths[i + 1]) else i + 1
        lo, hi = min(i, j), max(i, j)
        keep = runs[j][2]
        runs[lo:hi + 1] = [[runs[lo][0], runs[hi][1], keep]]
        _join(runs)
    # a short moving run beside a rest is the stop or the start, not a segment
    changed = True
    while changed:
        changed = False
        for i, r in enumerate(runs):
            beside_rest = ((i > 0 and runs[i - 1][2] == 0)
                           or (i < len(runs) - 1 and runs[i + 1][2] == 0))
            if r[2] != 0 and beside_rest and r[1] - r[0] < 2 * min_n:
                r[2] = 0
                changed = True
        _join(runs)
    # the sliding window sees a rest half a window late and early: move the edges
    half = min_n // 2
    for left, right in zip(runs[:-1], runs[1:], strict=True):
        if left[2] == 0 and right[2] != 0:
            edge = min(right[0] + half, right[1] - 1)
        elif right[2] == 0 and left[2] != 0:
            edge = max(left[1] - half, left[0] + 1)
        else:
            continue
        left[1] = right[0] = edge
    return runs


def _join(runs: list[list[int]]) -> None:
    """Join neighbouring runs with the same label, in place."""
    k = 0
    while k < len(runs) - 1:
        if runs[k][2] == runs[k + 1][2]:
            runs[k:k + 2] = [[runs[k][0], runs[k + 1][1], runs[k][2]]]
        else:
            k += 1


def _line_segments(cost: _LineCost, a0: int, b0: int, min_n: int,
                   min_step: float) -> list[int]:
    """Interior split indices of [a0, b0) by binary segmentation into straight lines."""
    bounds = [a0, b0]
    queue = [(a0, b0)]
    while queue and len(bounds) < 400:
        a, b = queue.pop()
        if b - a < 2 * min_n:
            continue
        ks = np.arange(a + min_n, b - min_n + 1)
        total = cost.sse(np.full(ks.size, a), ks) + cost.sse(ks, np.full(ks.size, b))
        k = int(ks[int(np.argmin(total))])
        if _split_ok(cost, a, k, b, min_step):
            bounds.append(k)
            queue.extend([(a, k), (k, b)])
    bounds.sort()
    merged = True
    while merged and len(bounds) > 2:
        merged = False
        for i in range(1, len(bounds) - 1):
            if not _split_ok(cost, bounds[i - 1], bounds[i], bounds[i + 1], min_step):
                del bounds[i]
                merged = True
                break
    return bounds[1:-1]


def find_segments(time: object, position: object, speed: object, *,
                  thresholds: CreepThresholds | None = None,
                  min_step: float = DEFAULT_MIN_STEP,
                  min_segment_time: float = DEFAULT_MIN_SEGMENT_TIME,
                  start: float | None = None) -> list[tuple[float, float]]:
    """(start, end) [s] of the moving, constant-command segments of a trace (see module).

    ``time`` [s], ``position`` [m], ``speed`` [m/s] on a common grid; ``start`` [s] is where
    segmentation begins (default: ``min_segment_time`` after the speed first reaches 90 % of
    the overall mean speed).  Rests are left out.

    Parameters
    ----------
    time : array_like
        Sample times [s].
    position : array_like
        Table position [m].
    speed : array_like
        Table speed [m/s].
    thresholds : CreepThresholds, optional
        Verdict limits.
    min_step : float, default 5e-6
        Smallest command change that starts a segment [m/s].
    min_segment_time : float, default 1.0
        Shortest segment [s].
    start : float, optional
        Where segmentation begins [s].

    Returns
    -------
    list of (float, float)
        (start, end) of each segment [s].

    Raises
    ------
    ValueError
        For a non-positive ``min_step`` or ``min_segment_time``.
    """
    _check_settings(thresholds, min_step, min_segment_time)
    t = np.asarray(time, dtype=float)
    x = np.asarray(position, dtype=float)
    v = np.asarray(speed, dtype=float)
    th = thresholds or CreepThresholds()
    if start is None:
        start = segmentation_start(t, x, v, min_segment_time)
    sel = t >= start
    t, x, v = t[sel], x[sel], v[sel]
    if t.size < 16:
        return []
    # decimate long records by block means (segmentation needs no more resolution)
    block = max(1, t.size // _MAX_SEGMENTATION_POINTS)
    if block > 1:
        m = (t.size // block) * block
        t, x, v = (arr[:m].reshape(-1, block).mean(axis=1) for arr in (t, x, v))
    dt = float(np.median(np.diff(t)))
    min_n = max(4, int(math.ceil(min_segment_time / dt)))
    if t.size < 2 * min_n:
        return [(float(t[0]), float(t[-1]))]
    regimes = _runs(_regimes(t, x, v, min_n, th), min_n)
    # the sliding window flags creeping half a window early: move those edges back
    for left, right in zip(regimes[:-1], regimes[1:], strict=True):
        if {left[2], right[2]} == {1, 2}:
            shift = min_n // 2 if left[2] == 1 else -(min_n // 2)
            edge = int(np.clip(left[1] + shift, left[0] + 1, right[1] - 1))
            left[1] = right[0] = edge
    # remove the overall line so the cumulative sums hold small numbers
    tc = t - t[0]
    slope, icpt = np.polyfit(tc, x, 1)
    cost = _LineCost(tc, x - (slope * tc + icpt))
    pieces: list[list[int]] = []  # [first index, end index, regime]
    for a, b, label in regimes:
        if label == 0:
            continue
        cuts = [a, *_line_segments(cost, a, b, min_n, min_step), b]
        pieces += [[i, j, label] for i, j in zip(cuts[:-1], cuts[1:], strict=True)]
    _merge_holds(cost, pieces, min_step)
    spans = []
    for i, j, _ in pieces:
        lo = float(t[i]) if i == 0 else float(0.5 * (t[i - 1] + t[i]))
        hi = float(t[j - 1]) if j == t.size else float(0.5 * (t[j - 1] + t[j]))
        spans.append((lo, hi))
    return spans


def segmentation_start(time: np.ndarray, position: np.ndarray, speed: np.ndarray,
                       min_segment_time: float) -> float:
    """Where :func:`find_segments` begins by default: ``min_segment_time`` after the speed
    first reaches 90 % of the overall mean speed (the run-up and its settling are no segment),
    but at least ``2·min_segment_time`` before the end.

    Parameters
    ----------
    time : numpy.ndarray
        Sample times [s].
    position : numpy.ndarray
        Table position [m].
    speed : numpy.ndarray
        Table speed [m/s].
    min_segment_time : float
        Shortest segment [s].

    Returns
    -------
    float
        The start [s].
    """
    t = time
    mean_speed = (position[-1] - position[0]) / (t[-1] - t[0])
    moved = np.abs(speed) >= 0.9 * abs(mean_speed)
    start = float(t[np.flatnonzero(moved)[0]]) if np.any(moved) else float(t[0])
    return min(start + min_segment_time, float(t[-1] - 2.0 * min_segment_time))


def _merge_holds(cost: _LineCost, pieces: list[list[int]], min_step: float) -> None:
    """Join neighbouring pieces (no rest between) whose mean speeds differ by at most
    ``min_step``, in place: one hold whose oscillation grows (smooth, then creeping) or
    decays mid-record was two segments at one command (an outside check, 2026-12-07: a
    1.36-mm/s hold decimated 5× became segments at 1.359993 and 1.359927 mm/s, the first
    "smooth" by 0.499 against the 0.5 ripple limit, and the critical speed moved from 1.4 to
    1.36 mm/s).  A first piece that creeps before a smooth one at the same speed is left
    alone: :func:`analyze_trace` excludes it as the start-up transient."""
    k = 0
    while k < len(pieces) - 1:
        left, right = pieces[k], pieces[k + 1]
        startup = k == 0 and left[2] == 2 and right[2] == 1
        if (left[1] == right[0] and not startup and
                abs(cost.line(left[0], left[1])[0] - cost.line(right[0], right[1])[0])
                <= min_step):
            pieces[k:k + 2] = [[left[0], right[1], right[2]]]
        else:
            k += 1


def _check_settings(thresholds: object, min_step: object, min_segment_time: object) -> None:
    """Refuse thresholds that are not :class:`CreepThresholds` (a dict was "'dict' object has
    no attribute 'stick_level'") and a segmentation step or length that is not a finite
    positive number."""
    if thresholds is not None and not isinstance(thresholds, CreepThresholds):
        raise ParameterError("thresholds", thresholds, "expected a CreepThresholds, e.g. "
                             "feeddrive.CreepThresholds(stick_level=0.1, max_stick_fraction="
                             "0.02, max_ripple_ratio=0.5) [-]")
    for name, value, unit in (("min_step", min_step, "m/s"),
                              ("min_segment_time", min_segment_time, "s")):
        if not (0 < (float(value) if is_real(value) else math.nan) < math.inf):
            raise ParameterError(name, value, f"expected a finite value > 0 [{unit}]")


def _check_command_speed(command_speed: object) -> float:
    """The given command speed [m/s], refused (naming ``command_speed``) when not a finite,
    non-zero speed of at most :data:`~feeddrive.units.LARGEST_SPEED`: the shared
    :func:`~feeddrive.parameters.validation.check_speed`."""
    return check_speed("command_speed", command_speed, sign="nonzero")


def _derived_command(command: float, origin: str, where: str) -> float:
    """A command speed [m/s] taken from the record (``origin`` "estimated": its position's
    slope; "column": its command column), refused naming what it came from when it is beyond
    :data:`~feeddrive.units.LARGEST_SPEED`: the metrics' own check named ``command_speed``,
    an argument not given (a position in µm given as m; session 27)."""
    if abs(command) <= LARGEST_SPEED:
        return command
    field, expected = (("position", "expected a position in m [m]") if origin == "estimated"
                       else ("command", "expected a command speed in m/s [m/s]"))
    raise ParameterError(field, MISSING, f"{where} moves at {command:.6g} m/s, faster than "
                         f"any feed drive (|speed| ≤ {LARGEST_SPEED:g} m/s): {expected}")


def unit_slip_note(command_speed: float, mean_speed: float) -> str | None:
    """A note when a given command speed is about :data:`UNIT_SLIP_FACTOR` times the trace's
    own mean speed (within :data:`UNIT_SLIP_TOLERANCE`): a speed in mm/s given where the API
    takes m/s.

    Parameters
    ----------
    command_speed : float
        The given command speed [m/s].
    mean_speed : float
        The trace's mean speed over the judged window [m/s].

    Returns
    -------
    str or None
        The note, or None when the two are not that far apart.
    """
    if mean_speed == 0.0 or not math.isfinite(mean_speed):
        return None
    ratio = abs(command_speed / mean_speed)
    if not (UNIT_SLIP_FACTOR / UNIT_SLIP_TOLERANCE <= ratio
            <= UNIT_SLIP_FACTOR * UNIT_SLIP_TOLERANCE):
        return None
    return (f"command speed {command_speed:g} m/s is {ratio:.4g}× the trace's mean speed "
            f"{1e3 * mean_speed:.4g} mm/s: the API takes m/s — was {command_speed:g} mm/s "
            f"meant (command_speed={command_speed * 1e-3:g})? The verdict is against the "
            "speed given")


def _detected_notes(tt: np.ndarray, xx: np.ndarray, vv: np.ndarray,
                    spans: list[tuple[float, float]], min_step: float,
                    min_segment_time: float) -> list[str]:
    """The notes on segments detected from the position: how many, with the options that set
    them, and the run-up left out before the first (a constant-speed record's one segment
    began 1 s into it, unexplained)."""
    how = (f"binary segmentation of the position, --min-step {1e3 * min_step:.3g} mm/s, "
           f"--min-segment {min_segment_time:g} s")
    out = [f"segments: one, with no speed step ({how})" if len(spans) == 1
           else f"segments: {len(spans)} detected ({how})"]
    start = segmentation_start(tt, xx, vv, min_segment_time)
    if not spans or start <= tt[0]:
        return out
    why = (f"{2 * min_segment_time:g} s (2 × --min-segment) before the end of a short record"
           if start == float(tt[-1] - 2.0 * min_segment_time) else
           f"--min-segment {min_segment_time:g} s after the speed first reaches 90 % of its "
           "mean")
    return [*out, f"{tt[0]:.2f}–{start:.2f} s left out as the run-up: segmentation starts {why}"]


def _column_runs(tt: np.ndarray, command: np.ndarray, min_segment_time: float,
                 notes: list[str]) -> tuple[list[tuple[float, float, float, str]], str | None]:
    """The segments of a command column (``command_runs.column_segments``), what they leave
    out added to ``notes``; and, when the column holds no command long enough, why there is no
    segment (it was "the table does not move")."""
    from .command_runs import column_segments

    found = column_segments(tt, command, min_segment_time)
    notes.append(found.head())
    left_out = found.left_out()
    if left_out:
        notes.append(left_out)
    why = None
    if not found.kept and left_out:
        why = (f"no run of constant command speed in the command column lasts --min-segment "
               f"{min_segment_time:g} s: {'; '.join(found.left_out_parts())}; give a shorter "
               "--min-segment, or --command-speed for one command over the whole record")
    return [(r.start, r.end, r.command, "column") for r in found.kept], why


# ---------------------------------------------------------------- analysis


@dataclass(frozen=True)
class TraceSegment:
    """One constant-command segment of a trace and its creep metrics.

    Parameters
    ----------
    start : float
        Start [s].
    end : float
        End [s].
    command_speed : float
        Commanded speed [m/s].
    command_from : str
        ``"given"``, ``"column"`` or ``"estimated"``.
    metrics : CreepMetrics
        The segment's creep metrics.
    settled : bool, default True
        False when its verdict is smooth but its oscillation has not settled within it
        (:func:`hold_settled`): the verdict is not firm.
    """
    start: float  # [s]
    end: float  # [s]
    command_speed: float  # [m/s]
    command_from: str  # "given", "column" or "estimated"
    metrics: CreepMetrics
    #: False when the window rule calls it smooth but it has not settled (:func:`hold_settled`)
    settled: bool = True

    def to_dict(self, units: Literal["SI", "mm"] = "mm") -> dict[str, Any]:
        """The segment for the JSON report.

        Parameters
        ----------
        units : {"SI", "mm"}, default "mm"
            Units of the metrics.

        Returns
        -------
        dict
            Start and end [s], where the command came from, and the metrics.
        """
        return {"start": self.start, "end": self.end, "command_from": self.command_from,
                "settled": self.settled, "metrics": self.metrics.to_dict(units)}


@dataclass(frozen=True)
class CriticalSpeed:
    """Critical creeping speed of a step-down run, one direction (speeds as magnitudes).

    ``lowest_smooth``: the lowest command speed at and above which every segment is smooth
    (the paper's critical creeping speed, Wang2021 Sect. 5.2: creeps at 1.55, stable at
    1.56 mm/s → 1.56 mm/s).  ``first_creeping``: the highest creeping command speed.
    ``monotonic`` is False when a smooth segment lies below a creeping one.

    Parameters
    ----------
    direction : str
        ``"positive"`` or ``"negative"``.
    lowest_smooth : float or None
        The critical creeping speed [m/s].
    first_creeping : float or None
        The highest creeping command speed [m/s].
    monotonic : bool
        False when a smooth segment lies below a creeping one.
    unsettled : tuple of float, default ()
        Command speeds [m/s] (magnitudes) of the holds called smooth that have not settled
        (:func:`hold_settled`); when any, the critical speed is not firm.

    References
    ----------
    .. [1] Wang2021 Sect. 5.2, Sect. 6.
    """

    direction: str
    lowest_smooth: float | None
    first_creeping: float | None
    monotonic: bool
    unsettled: tuple[float, ...] = ()


@dataclass(frozen=True)
class TraceAnalysis:
    """Creep metrics of a position trace, per commanded-speed segment (:func:`analyze_trace`).

    Parameters
    ----------
    source : str or None
        The file.
    time : numpy.ndarray
        Sample times [s].
    position : numpy.ndarray
        Table position [m].
    speed : numpy.ndarray
        Table speed [m/s].
    window : int
        Savitzky–Golay window [samples].
    window_time : float
        Savitzky–Golay window [s].
    segments : tuple of TraceSegment
        The judged segments.
    critical : tuple of CriticalSpeed
        The critical speed per direction (step-down records).
    notes : tuple of str, default ()
        Warnings.
    record : str, default "constant-speed"
        ``"constant-speed"`` (segments judged) or ``"non-constant-speed"`` (a move or a
        ramp: nothing to judge).
    """
    source: str | None
    time: np.ndarray
    position: np.ndarray
    speed: np.ndarray
    window: int
    window_time: float
    segments: tuple[TraceSegment, ...]
    critical: tuple[CriticalSpeed, ...]
    notes: tuple[str, ...] = field(default=())
    #: "constant-speed" (segments of constant command, judged), or "non-constant-speed"
    #: (a move or a ramp: nothing to judge for creep)
    record: str = "constant-speed"

    def __repr__(self) -> str:
        # what a notebook prints: the record and its verdicts, never the arrays
        t = self.time
        span = f"{t.size} samples, {float(t[-1] - t[0]):.4g} s" if t.size else "no samples"
        if self.record != "constant-speed":
            judged = f"{self.record}: no verdict"
        else:
            shown = [f"{1e3 * s.command_speed:.4g} mm/s {s.metrics.verdict}"
                     for s in self.segments[:3]]
            more = f", … {len(self.segments) - 3} more" if len(self.segments) > 3 else ""
            judged = (f"{len(self.segments)} segment{'s' if len(self.segments) != 1 else ''}: "
                      f"{', '.join(shown)}{more}")
        name = self.source or ""
        src = f" {name if len(name) <= 60 else '…' + name[-59:]!r}" if name else ""
        return (f"<feeddrive.TraceAnalysis{src}: {span}; {judged}; {len(self.notes)} notes; "
                ".segments .critical .notes, .to_dict()>")

    def to_dict(self, units: Literal["SI", "mm"] = "mm") -> dict[str, Any]:
        """The analysis for the JSON report (``feeddrive analyze --json``).

        Parameters
        ----------
        units : {"SI", "mm"}, default "mm"
            Units of speeds and positions.

        Returns
        -------
        dict
            Source, sample count, duration [s], the filter window, the segments, the critical
            speeds and the notes.
        """
        k = 1.0 if units == "SI" else 1e3
        return {
            "source": self.source,
            "samples": int(self.time.size),
            "duration": float(self.time[-1] - self.time[0]),
            "savgol_window_samples": self.window,
            "savgol_window_time": self.window_time,
            "segments": [s.to_dict(units) for s in self.segments],
            "critical_speed": [
                {"direction": c.direction,
                 "lowest_smooth": None if c.lowest_smooth is None else c.lowest_smooth * k,
                 "first_creeping": None if c.first_creeping is None else c.first_creeping * k,
                 "monotonic": c.monotonic,
                 "unsettled": [v * k for v in c.unsettled]}
                for c in self.critical
            ],
            "speed_unit": "m/s" if units == "SI" else "mm/s",
            "record": self.record,
            "notes": list(self.notes),
        }


#: a span whose speed trend (the range of a quadratic fit of the speed over it) exceeds this
#: fraction of its mean speed is not at constant speed: a move or a ramp.  Stick-slip at a
#: constant command is periodic about its mean, so its quadratic trend is small (measured:
#: below 0.1 over a 1-s span at 1 mm/s); a 0 → 644 → 0 mm/s move gives about 1.5.
MAX_SPEED_TREND = 0.5


def speed_trend(t: np.ndarray, v: np.ndarray) -> float:
    """Range of the least-squares quadratic in time through the speed ``v`` over ``t``,
    relative to the mean |speed| (see :data:`MAX_SPEED_TREND`); inf at rest.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times [s].
    v : numpy.ndarray
        Speed [m/s].

    Returns
    -------
    float
        The relative range [-].
    """
    if t.size < 8:
        return 0.0
    mean = abs(float(np.mean(v)))
    if mean == 0.0:
        return math.inf
    tc = (t - t[0]) / max(float(t[-1] - t[0]), 1e-300)
    fit = np.polyval(np.polyfit(tc, v, 2), tc)
    return float(np.ptp(fit)) / mean


def _moving_part(t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Samples from the first to the last with |v| above 2 % of its peak."""
    peak = float(np.max(np.abs(v))) if v.size else 0.0
    moving = np.flatnonzero(np.abs(v) > 0.02 * peak) if peak > 0 else np.zeros(0, int)
    sel = np.zeros(t.size, dtype=bool)
    if moving.size:
        sel[moving[0]:moving[-1] + 1] = True
    return sel


def _slope(t: np.ndarray, x: np.ndarray) -> float:
    return float(np.polyfit(t - t[0], x, 1)[0])


#: the travel a fitted slope implies over its span, in units in the last place of the
#: positions, up to which the table is at rest: a constant position's least-squares slope is
#: the rounding of its sums (a table held at 5 mm gave -7.7e-16 mm/s, then "UNSTABLE, ripple
#: 1.24e+04" against that command, exit 0; a bad-input sweep, session 29); 1000 ulps of a
#: 1-m position are 0.2 pm, far below any measured motion
REST_ULPS = 1000.0


def _at_rest(t: np.ndarray, x: np.ndarray, slope: float) -> bool:
    """Whether ``slope`` [m/s], fitted to positions ``x`` [m] at times ``t`` [s], is zero to
    the positions' rounding: its travel over the span within :data:`REST_ULPS` units in the
    last place of the largest position."""
    travel = abs(slope) * float(t[-1] - t[0])
    return travel <= REST_ULPS * float(np.spacing(np.max(np.abs(x))))


def _critical(segments: list[TraceSegment]) -> list[CriticalSpeed]:
    return critical_of_holds([(s.command_speed, s.metrics.creeping, s.settled)
                              for s in segments])


def hold_settled(time: np.ndarray, speed: np.ndarray, command_speed: float,
                 verdict: str) -> str | None:
    """Why a hold the window rule calls smooth has not settled, or None when it has (or its
    verdict is not smooth: creeping stands).

    Settled is the limit-cycle rule's (:func:`~feeddrive.analysis.cycle_verdict.trace_verdict`,
    :class:`~feeddrive.analysis.cycle_verdict.VerdictRule` defaults) decision within the
    hold: decayed (within ±2 % of the command for max(2 s, 2 periods) and not growing) or a
    repeating cycle.  A hold it leaves undecided — an oscillation growing hold to hold, a
    hold shorter than its settling time — is smooth by the window rule only for now (an
    outside check, 2026-12-07: 4-s holds at 1.44 … 1.36 mm/s, ripple 0.04 → 0.13 at
    5.45 Hz, were "smooth" and the staircase's critical speed 1.36 mm/s, against 1.4 mm/s
    from 30-s holds).

    Parameters
    ----------
    time : numpy.ndarray
        The hold's sample times [s].
    speed : numpy.ndarray
        Table speed [m/s].
    command_speed : float
        The hold's command speed [m/s].
    verdict : str
        The window rule's verdict of the hold.

    Returns
    -------
    str or None
        The limit-cycle rule's reason when the hold has not settled, else None.
    """
    if verdict != SMOOTH:
        return None
    decision = trace_verdict(time, speed, command_speed)
    return decision.reason if decision.kind == UNDECIDED else None


def describe_critical(lowest_smooth: float | None, first_creeping: float | None,
                      what: str = "segment", unsettled: Sequence[float] = ()) -> str:
    """The critical speed in words, as ``analyze`` and ``simulate --profile stepdown`` print it.

    Parameters
    ----------
    lowest_smooth : float or None
        The lowest smooth command speed [m/s] (:class:`CriticalSpeed`).
    first_creeping : float or None
        The highest creeping command speed [m/s].
    what : str, default "segment"
        What a hold is called (``"segment"`` of a record, ``"hold"`` of a profile).
    unsettled : sequence of float, default ()
        Command speeds [m/s] of smooth holds that have not settled
        (:attr:`CriticalSpeed.unsettled`): said after the two numbers, which are then not
        firm.

    Returns
    -------
    str
        E.g. ``"lowest smooth 1.42 mm/s; first creeping 1.4 mm/s"`` [mm/s].
    """
    smooth = (f"{1e3 * lowest_smooth:.4g} mm/s" if lowest_smooth is not None
              else f"none (every {what} creeps)")
    creep = (f"{1e3 * first_creeping:.4g} mm/s" if first_creeping is not None
             else f"none (no {what} creeps)")
    text = f"lowest smooth {smooth}; first creeping {creep}"
    if unsettled:
        speeds = ", ".join(f"{1e3 * abs(v):.4g}" for v in unsettled)
        text += (f" — not firm: the {what}{'s' if len(unsettled) > 1 else ''} at {speeds} "
                 f"mm/s {'are' if len(unsettled) > 1 else 'is'} smooth by the window rule but "
                 f"not settled (the limit-cycle rule: neither within ±"
                 f"{100 * VerdictRule().smooth_band:g} % for its settling time nor a repeating "
                 f"cycle within the {what}); longer {what}s decide")
    return text


def critical_of_holds(holds: Sequence[tuple[float, bool] | tuple[float, bool, bool]]
                      ) -> list[CriticalSpeed]:
    """The critical speed per direction of a run of holds at constant command speeds (a
    step-down record's segments, a staircase's steps): ``feeddrive analyze`` and ``simulate
    --profile stepdown`` headline the same two numbers.

    Parameters
    ----------
    holds : sequence of (float, bool) or (float, bool, bool)
        Per hold: its command speed [m/s] (signed), whether it creeps (not smooth) and,
        optionally, whether it has settled (:func:`hold_settled`; True when not given).

    Returns
    -------
    list of CriticalSpeed
        One per direction with at least two holds.
    """
    out = []
    for direction, sign in (("positive", 1.0), ("negative", -1.0)):
        mine = [h for h in holds if h[0] * sign > 0]
        segs = sorted(((abs(h[0]), h[1]) for h in mine), reverse=True)
        if len(segs) < 2:
            continue
        unsettled = tuple(sorted((abs(h[0]) for h in mine
                                  if len(h) > 2 and not h[1] and not h[2]), reverse=True))
        lowest_smooth = None
        for speed, creeps in segs:
            if creeps:
                break
            lowest_smooth = speed
        creeping = [speed for speed, creeps in segs if creeps]
        first_creeping = max(creeping) if creeping else None
        smooth_below = any(not creeps and first_creeping is not None and speed < first_creeping
                           for speed, creeps in segs)
        out.append(CriticalSpeed(direction=direction, lowest_smooth=lowest_smooth,
                                 first_creeping=first_creeping, monotonic=not smooth_below,
                                 unsettled=unsettled))
    return out


def analyze_trace(
    time: object,
    position: object,
    *,
    command_speed: float | None = None,
    command: object | None = None,
    speed: object | None = None,
    thresholds: CreepThresholds | None = None,
    smoothing_time: float | None = None,
    window: int | None = None,
    segment: bool = True,
    min_step: float | None = None,
    min_segment_time: float = DEFAULT_MIN_SEGMENT_TIME,
    source: str | None = None,
    lines: np.ndarray | None = None,
) -> TraceAnalysis:
    """Creep metrics of a position trace, per commanded-speed segment.

    Parameters
    ----------
    time : array_like
        Sample times [s].
    position : array_like
        Table position [m].
    command_speed : float, optional
        The commanded speed of the whole trace (one segment) [m/s].  Else ``command`` defines
        the segments; else they are detected (``segment=True``) and each command speed is
        estimated.
    command : array_like, optional
        A per-sample command speed, e.g. a file column [m/s].
    speed : array_like, optional
        Table speed per sample, to use instead of differentiating the position [m/s].
    thresholds : CreepThresholds, optional
        Verdict limits.
    smoothing_time : float, optional
        Savitzky–Golay window as a time [s] (see :func:`estimate_speed`).
    window : int, optional
        The window in samples instead.
    segment : bool, default True
        Detect segments when no command is given; False (one segment over the whole trace,
        its command estimated) is refused with ``command_speed`` or ``command``, which set
        the segments.
    min_step : float, optional
        Smallest command change that starts a segment [m/s], default 5e-6
        (``DEFAULT_MIN_STEP``).  It sets the segments detected from the position only:
        refused with ``command_speed``, ``command`` or ``segment=False``.
    min_segment_time : float, default 1.0
        Shortest segment [s].
    source : str, optional
        File name, for error messages.
    lines : numpy.ndarray of int, optional
        The file line of every sample, for error messages.

    Returns
    -------
    TraceAnalysis
        The segments, their metrics and the critical speeds.

    Raises
    ------
    ValueError
        For arrays of unequal length, a zero or non-finite command speed, a trace that
        :func:`estimate_speed` refuses, or no moving segment to analyse; ``segment=False``
        or ``min_step`` beside a command (``ParameterError``).

    Examples
    --------
    A position record whose speed oscillates ±80 % about 1 mm/s:

    >>> import numpy as np
    >>> from feeddrive.analysis.trace import analyze_trace
    >>> t = np.linspace(0.0, 20.0, 20001)
    >>> position = 1e-3 * t - 0.8e-3 / (2 * np.pi * 2.0) * np.cos(2 * np.pi * 2.0 * t)
    >>> segment = analyze_trace(t, position, command_speed=1e-3).segments[0]
    >>> m = segment.metrics
    >>> print(f"{1e3 * m.mean_speed:.2f} mm/s, ripple {m.ripple_ratio:.2f}, {m.verdict}")
    1.00 mm/s, ripple 1.60, creeping
    """
    notes: list[str] = []
    # the settings first, before any work
    _check_settings(thresholds, DEFAULT_MIN_STEP if min_step is None else min_step,
                    min_segment_time)
    segment = check_flag("segment", segment)  # "no" was taken as True (session 29)
    beside = ("command_speed, which makes the whole trace one segment"
              if command_speed is not None else "command, whose steps set the segments"
              if command is not None else None)
    if not segment and beside is not None:
        # dropped without a word: a command sets the segments, detection runs without one
        # (an earlier sweep, session 30)
        raise ParameterError("segment", False, f"not with {beside} (segments are detected "
                             "only without a command); expected True or no command")
    if min_step is not None and (beside is not None or not segment):
        # it splits detected segments only: beside a command or segment=False it was read
        # nowhere (an earlier sweep, session 30)
        raise ParameterError("min_step", min_step, f"not with {beside or 'segment=False'} "
                             f"({MIN_STEP_APPLIES}); expected None")
    min_step = DEFAULT_MIN_STEP if min_step is None else float(min_step)
    if command_speed is not None:
        command_speed = _check_command_speed(command_speed)
    t = np.asarray(time, dtype=float)
    x = np.asarray(position, dtype=float)
    if speed is None:
        est = estimate_speed(t, x, smoothing_time=smoothing_time, window=window,
                             lines=lines, source=source)
        tt, xx, vv = est.time, est.position, est.speed
        win, win_t = est.window, est.window_time
        notes.append(f"speed: Savitzky–Golay derivative, window {win} samples "
                     f"({1e3 * win_t:.3g} ms), polyorder 2")
        if est.resampled:
            notes.append("uneven sampling: the trace was interpolated onto a uniform grid")
    else:
        tt, xx, vv = t, x, np.asarray(speed, dtype=float)
        if vv.shape != tt.shape:
            raise ValueError("speed: expected one value per time sample")
        if tt.size > 1:  # the metrics resample uneven records: refuse a gap here, by line
            resample_size(tt, float(np.median(np.diff(tt))), lines=lines, source=source)
        win, win_t = 1, 0.0
        notes.append("speed: taken from the file's speed column")

    runs: list[tuple[float, float, float | None, str]] = []
    no_segment = None  # why a command column gives no segment
    if command_speed is not None:
        runs.append((float(tt[0]), float(tt[-1]), float(command_speed), "given"))
    elif command is not None:
        cmd = np.asarray(command, dtype=float)
        if cmd.shape != t.shape:
            raise ValueError("command: expected one value per time sample")
        cmd_on_grid = np.interp(tt, t, cmd) if cmd.shape != tt.shape else cmd
        column, no_segment = _column_runs(tt, cmd_on_grid, min_segment_time, notes)
        runs += column
    else:
        spans = (find_segments(tt, xx, vv, thresholds=thresholds, min_step=min_step,
                               min_segment_time=min_segment_time)
                 if segment else [(float(tt[0]), float(tt[-1]))])
        # a detected edge is uncertain by a few samples of smoothing: keep clear of it
        guard = win_t + 0.05 * min_segment_time
        for a, b in spans:
            runs.append((a, b - guard if b < tt[-1] - win_t else b, None, "estimated"))
        if segment:
            notes += _detected_notes(tt, xx, vv, spans, min_step, min_segment_time)
        notes.append("command speed not given: estimated as the mean speed (slope of the "
                     "position) over each segment's steady window")

    if command_speed is None:
        # a move or a ramp has no constant-speed span to judge (issue 22: a 0 → 644 → 0 mm/s
        # move in 0.54 s was called creeping with a "3.9 Hz stick-slip")
        whole = _moving_part(tt, vv)
        trend = speed_trend(tt[whole], vv[whole]) if np.count_nonzero(whole) >= 8 else 0.0
        steady = [r for r in runs if speed_trend(
            tt[(tt >= r[0]) & (tt <= r[1])], vv[(tt >= r[0]) & (tt <= r[1])]) <=
            MAX_SPEED_TREND] if runs else []
        if trend > MAX_SPEED_TREND and not steady:
            sel = whole
            lo_v, hi_v = float(np.min(vv[sel])), float(np.max(vv[sel]))
            notes.append(
                f"non-constant-speed record (a move or a ramp): the speed goes from "
                f"{1e3 * lo_v:.4g} to {1e3 * hi_v:.4g} mm/s over {tt[sel][0]:.3f}–"
                f"{tt[sel][-1]:.3f} s with no constant-speed span of {min_segment_time:g} s; "
                "creep is judged on constant-speed records only, so no verdict is given")
            return TraceAnalysis(source=source, time=tt, position=xx, speed=vv, window=win,
                                 window_time=win_t, segments=(), critical=(),
                                 notes=tuple(notes), record="non-constant-speed")
        if len(steady) < len(runs):
            for r in runs:
                if r not in steady:
                    notes.append(f"span {r[0]:.2f}–{r[1]:.2f} s skipped: not at constant "
                                 "speed (a ramp or a move)")
            runs = steady

    segments: list[TraceSegment] = []
    for a, b, given, origin in runs:
        sel = (tt >= a) & (tt <= b)
        if np.count_nonzero(sel) < 16:
            notes.append(f"segment {a:.3f}–{b:.3f} s skipped: fewer than 16 samples")
            continue
        ts, xs, vs = tt[sel], xx[sel], vv[sel]
        where = f"{source + ': ' if source else ''}segment {ts[0]:.3f}–{ts[-1]:.3f} s"
        if given is None:
            half = ts >= ts[0] + 0.5 * (ts[-1] - ts[0])
            guess = _slope(ts[half], xs[half])
            if _at_rest(ts[half], xs[half], guess):
                notes.append(f"segment {a:.3f}–{b:.3f} s skipped: the table is at rest")
                continue
            start, _ = steady_window(ts, vs, _derived_command(guess, origin, where))
            c = _derived_command(_slope(ts[ts >= start], xs[ts >= start]), origin, where)
        else:
            c = given if origin == "given" else _derived_command(given, origin, where)
        try:
            m = creep_metrics(ts, vs, c, thresholds=thresholds)
        except ValueError as err:  # a steady window too short to judge: name the file
            raise ValueError(f"{where}: {err}") from None
        span = float(ts[-1] - ts[0])
        if span < min_segment_time:  # only a given command judges a run this short
            notes.append(
                f"segment {ts[0]:.3f}–{ts[-1]:.3f} s: {ts.size} samples ({span:.3g} s), "
                f"shorter than --min-segment {min_segment_time:g} s: its verdict rests on a "
                f"steady window of {m.window_samples} samples "
                f"({m.window_end - m.window_start:.3g} s) and misses any slower stick-slip "
                "cycle; record longer for a reliable verdict")
        slip = unit_slip_note(c, m.mean_speed) if origin == "given" else None
        if slip:
            notes.append(slip)
        # the settling is judged clear of the filter's reach into the neighbouring holds
        inner = (ts >= ts[0] + win_t) & (ts <= ts[-1] - win_t)
        if m.sampling_note:
            notes.append(f"segment {ts[0]:.2f}–{ts[-1]:.2f} s: {m.sampling_note}")
        smoothed = smoothing_note(m, win, float(tt[1] - tt[0])) if speed is None else None
        if smoothed:
            notes.append(f"segment {ts[0]:.2f}–{ts[-1]:.2f} s: {smoothed}")
        why = (hold_settled(ts[inner], vs[inner], c, m.verdict)
               if np.count_nonzero(inner) >= 16 else None)
        if why:
            notes.append(f"segment {ts[0]:.2f}–{ts[-1]:.2f} s ({1e3 * c:.4g} mm/s): smooth by "
                         f"the window rule but not settled ({why}, by the limit-cycle rule "
                         "over the segment): its verdict is not firm; a longer hold decides")
        segments.append(TraceSegment(start=float(ts[0]), end=float(ts[-1]), command_speed=c,
                                     command_from=origin, metrics=m, settled=why is None))
    if (len(segments) >= 2 and segments[0].command_from == "estimated"
            and segments[0].metrics.creeping and not segments[1].metrics.creeping
            and abs(segments[0].command_speed - segments[1].command_speed) <= min_step):
        # the drive cannot creep and then run smoothly at one command: the first span is
        # the start-up transient decaying (issue 22: it made its own "creeping" segment at
        # 1.599 mm/s beside the smooth 1.6 mm/s one, and a wrong critical speed)
        first = segments.pop(0)
        notes.append(f"start-up transient {first.start:.2f}–{first.end:.2f} s excluded: it "
                     f"oscillates and then settles at the same speed "
                     f"({1e3 * segments[0].command_speed:.4g} mm/s)")
    if not segments:
        why = no_segment or "no moving segment to analyse (the table does not move)"
        raise ValueError(f"{source + ': ' if source else ''}{why}")
    critical = _critical(segments)
    for c_ in critical:
        if not c_.monotonic:
            notes.append(f"{c_.direction} direction: a smooth segment lies below a creeping "
                         "one; the critical speed is not sharp")
    return TraceAnalysis(source=source, time=tt, position=xx, speed=vv, window=win,
                         window_time=win_t, segments=tuple(segments),
                         critical=tuple(critical), notes=tuple(notes))
