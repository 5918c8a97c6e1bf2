"""Creep (stick-slip) metrics of a table-speed trace, simulated or measured.  SI units.

Wang2021 Sect. 5.2 and Sect. 6 call a run *creeping* ("crawling") when the table speed does
not settle to the command but alternates between sticking and slipping; the critical creeping
speed is the lowest command speed at which the table still moves smoothly.  The paper judges
this by eye from speed plots (Figs. 6–8, 13).  This module turns that judgement into numbers
with explicit, user-changeable thresholds (:class:`CreepThresholds`):

* **ripple ratio** (max − min)/|v_cmd| of the speed in the steady window,
* **min ratio** min/|v_cmd| (≤ 0 means the table stopped or moved backwards),
* **stick fraction**: fraction of the window's *time* during which the speed, in the
  command's direction, is below ``stick_level``·|v_cmd|,
* **stick-slip frequency** [Hz]: the periodogram peak of the detrended speed,
* **verdict**: ``"unstable"`` if the loop diverges — the speed peaks above
  ``max_speed_ratio``·|v_cmd| (stick-slip peaks stay within a few times the command) or the
  table runs backwards on average faster than the command; else ``"creeping"`` if the stick
  fraction or the ripple ratio exceeds its limit; else ``"smooth"``.  The CLI exits with
  status 3 on ``"unstable"`` (README, "Exit status").

Negative command speeds are handled by working on the speed in the command's direction
(speed·sign(v_cmd)) and on |v_cmd|; the reported mean speed keeps its sign.

The metrics are computed on a *steady window* after the start transient; see
:func:`steady_window` for the rule, or pass ``window=(start, end)``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "CreepMetrics",
    "CreepThresholds",
    "MIN_SAMPLES",
    "creep_metrics",
    "resample_size",
    "travel_warning",
    "steady_window",
]

# numpy ≥ 2.0 calls it trapezoid; 1.26, the declared minimum, only has trapz
# (found by .ci/min-versions)
_trapezoid: Any = getattr(np, "trapezoid", None) or getattr(np, "trapz")  # noqa: B009

#: fewest samples accepted in a trace, and in its steady window
MIN_SAMPLES = 16
_MIN_WINDOW_SAMPLES = 8


@dataclass(frozen=True)
class CreepThresholds:
    """Limits that turn creep metrics into a verdict.  All ratios are relative to |v_cmd|.

    Attributes
    ----------
    stick_level:
        A sample *sticks* when its speed in the command's direction is below
        ``stick_level``·|v_cmd| (default 0.1: below 10 % of the command).
    max_stick_fraction:
        The run is creeping if the stick fraction exceeds this (default 0.02: the table
        sticks during more than 2 % of the window).
    max_ripple_ratio:
        The run is creeping if (max − min)/|v_cmd| exceeds this (default 0.5: a peak-to-peak
        speed ripple of more than half the command).
    min_ripple_for_frequency:
        No stick-slip frequency is reported when the ripple ratio is below this (default
        0.02): the ripple is negligible.
    min_peak_share:
        No stick-slip frequency is reported when the periodogram peak (its main lobe) holds
        less than this share of the ripple power (default 0.1): the ripple is not periodic
        (broadband noise spreads its power over all frequencies).
    max_speed_ratio:
        The run is unstable if max|v|/|v_cmd| exceeds this (default 20).  Stick-slip of the
        Wang2021 CDFS peaks at about 2.2× the command (0.5–1.5 mm/s, 12 s runs); a diverging
        loop (a 100-t table) reaches 10⁴×.
    """

    stick_level: float = 0.1
    max_stick_fraction: float = 0.02
    max_ripple_ratio: float = 0.5
    min_ripple_for_frequency: float = 0.02
    min_peak_share: float = 0.1
    max_speed_ratio: float = 20.0

    def __post_init__(self) -> None:
        for name in ("stick_level", "max_stick_fraction", "max_ripple_ratio",
                     "min_ripple_for_frequency", "min_peak_share", "max_speed_ratio"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float) \
                    or not math.isfinite(value) or value < 0:
                raise ValueError(f"thresholds.{name} = {value!r}: expected a finite number ≥ 0")
        if self.stick_level >= 1.0:
            raise ValueError(f"thresholds.stick_level = {self.stick_level!r}: expected < 1 "
                             "(a fraction of the command speed)")
        if self.max_stick_fraction >= 1.0 or self.min_peak_share > 1.0:
            raise ValueError("thresholds: max_stick_fraction must be < 1 and min_peak_share ≤ 1")


@dataclass(frozen=True)
class CreepMetrics:
    """Creep metrics of one trace over its steady window.

    Speeds in [m/s], times in [s], frequency in [Hz]; ratios are dimensionless, relative to
    |command_speed|.  ``stick_slip_frequency`` is None when the ripple is negligible or not
    periodic.
    """

    command_speed: float
    window_start: float
    window_end: float
    mean_speed: float
    ripple_ratio: float
    min_ratio: float
    stick_fraction: float
    stick_slip_frequency: float | None
    verdict: str
    thresholds: CreepThresholds
    max_ratio: float = float("nan")
    window_samples: int = 0

    @property
    def creeping(self) -> bool:
        """Not smooth: creeping, or worse (``"unstable"``)."""
        return self.verdict != "smooth"

    @property
    def unstable(self) -> bool:
        return self.verdict == "unstable"

    def to_dict(self, units: Literal["SI", "mm"] = "SI") -> dict[str, Any]:
        """Plain dict for JSON output; speeds in m/s (``"SI"``) or mm/s (``"mm"``)."""
        if units not in ("SI", "mm"):
            raise ValueError(f"units = {units!r}: expected 'SI' or 'mm'")
        k = 1.0 if units == "SI" else 1e3
        return {
            "units": {"speed": "m/s" if units == "SI" else "mm/s", "time": "s",
                      "frequency": "Hz"},
            "command_speed": self.command_speed * k,
            "window_start": self.window_start,
            "window_end": self.window_end,
            "window_samples": self.window_samples,
            "mean_speed": self.mean_speed * k,
            "ripple_ratio": self.ripple_ratio,
            "min_ratio": self.min_ratio,
            "max_ratio": self.max_ratio,
            "stick_fraction": self.stick_fraction,
            "stick_slip_frequency": self.stick_slip_frequency,
            "verdict": self.verdict,
            "thresholds": asdict(self.thresholds),
        }


# ---------------------------------------------------------------- input checks


def _as_trace(time: object, speed: object) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(time, dtype=float)
    v = np.asarray(speed, dtype=float)
    if t.ndim != 1:
        raise ValueError(f"time: expected a 1-D array, got shape {t.shape}")
    if v.ndim != 1:
        raise ValueError(f"speed: expected a 1-D array, got shape {v.shape}")
    if t.size != v.size:
        raise ValueError(f"speed: length {v.size} differs from time's length {t.size}")
    if t.size < MIN_SAMPLES:
        raise ValueError(f"time: {t.size} samples; need at least {MIN_SAMPLES}")
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise ValueError(f"time: not finite at index {bad[0]} ({t[bad[0]]!r})")
    bad = np.flatnonzero(~np.isfinite(v))
    if bad.size:
        raise ValueError(f"speed: not finite at index {bad[0]} ({v[bad[0]]!r})")
    step = np.diff(t)
    bad = np.flatnonzero(step <= 0.0)
    if bad.size:
        i = int(bad[0]) + 1
        raise ValueError(f"time: not strictly increasing at index {i} "
                         f"({t[i - 1]!r} then {t[i]!r})")
    return t, v


def _check_command(command_speed: object) -> float:
    if isinstance(command_speed, bool) or not isinstance(command_speed, int | float | np.floating):
        raise ValueError(f"command_speed = {command_speed!r}: expected a number [m/s]")
    vc = float(command_speed)
    if not math.isfinite(vc) or vc == 0.0:
        raise ValueError(f"command_speed = {command_speed!r}: expected a finite, non-zero speed "
                         "[m/s]")
    return vc


def _check_fraction(name: str, value: float) -> float:
    if not (0.0 <= value < 1.0):
        raise ValueError(f"{name} = {value!r}: expected a fraction in [0, 1)")
    return value


# ---------------------------------------------------------------- steady window


def steady_window(
    time: object,
    speed: object,
    command_speed: float,
    *,
    settle_fraction: float = 0.1,
    min_fraction: float = 0.2,
    max_fraction: float = 0.5,
    reach_level: float = 0.9,
    persistence: float = 0.8,
    min_window_fraction: float = 0.25,
) -> tuple[float, float]:
    """(start, end) [s] of the steady part of a speed trace, after the start transient.

    With t₀, t₁ the first and last sample time and D = t₁ − t₀ the record length:

    1. t_reach is the first time the speed in the command's direction reaches
       ``reach_level``·|v_cmd| (default 90 % of the command);
    2. start = t_reach + ``settle_fraction``·D (default 10 % of the record as a settling
       margin), but never earlier than t₀ + ``min_fraction``·D (default 20 %) and never
       later than t₀ + ``max_fraction``·D (default 50 %);
    3. if the speed never reaches the command (a table that stays stuck, or a record of the
       run-up only), start = t₀ + ``max_fraction``·D;
    4. end = t₁;
    5. a decaying start-up oscillation is skipped: while the ripple of the window's second
       half is below ``persistence`` (default 0.8) × the ripple of its first half (and the
       first half's ripple is above 2 % of the command, i.e. not noise), the window starts
       at its midpoint instead, as long as it stays at least ``min_window_fraction`` of the
       record (default 25 %).  Stick-slip keeps its amplitude, so its window is unchanged;
       a weakly damped servo transient is not mistaken for creep.

    So the window is always the last 50 %–80 % of the record: a stick-slip trace that never
    settles still gets the second half of the record, where the stick-slip cycle is
    established.  Records with a long start transient (Wang2021 Fig. 6b settles after ~7 s)
    should be long enough that the transient ends before ``max_fraction``·D, or be given
    an explicit window.
    """
    t, v = _as_trace(time, speed)
    vc = _check_command(command_speed)
    for name, value in (("settle_fraction", settle_fraction), ("min_fraction", min_fraction),
                        ("max_fraction", max_fraction)):
        _check_fraction(name, value)
    if min_fraction > max_fraction:
        raise ValueError(f"min_fraction = {min_fraction!r}: must not exceed max_fraction = "
                         f"{max_fraction!r}")
    if not (0.0 < reach_level <= 1.0):
        raise ValueError(f"reach_level = {reach_level!r}: expected a fraction in (0, 1]")
    t0, t1 = float(t[0]), float(t[-1])
    span = t1 - t0
    along = v * math.copysign(1.0, vc)
    reached = np.flatnonzero(along >= reach_level * abs(vc))
    earliest, latest = t0 + min_fraction * span, t0 + max_fraction * span
    if reached.size == 0:
        start = latest
    else:
        start = min(max(float(t[reached[0]]) + settle_fraction * span, earliest), latest)

    def ripple(a: float, b: float) -> float:
        sel = (t >= a) & (t <= b)
        if np.count_nonzero(sel) < 2:
            return 0.0
        return float(np.ptp(along[sel])) / abs(vc)

    while True:
        mid = 0.5 * (start + t1)
        if t1 - mid < min_window_fraction * span:
            break
        first, second = ripple(start, mid), ripple(mid, t1)
        if first > 0.02 and second < persistence * first:
            start = mid
        else:
            break
    return start, t1


# ---------------------------------------------------------------- metrics


def travel_warning(start_position: float, displacement: object,
                   screw_length: float) -> str | None:
    """A warning when the table leaves the screw's travel (0, ``screw_length``) [m], or None.

    ``start_position`` [m] is the table's start a on the screw; ``displacement`` [m] its
    motion from there (a simulated ``table_position``).  The model has no end stops, so such
    a run means the loop diverged or the duration is too long for the speed.
    """
    x = start_position + np.asarray(displacement, dtype=float)
    if x.size == 0:
        return None
    low, high = float(np.min(x)), float(np.max(x))
    if low > 0.0 and high < screw_length:
        return None
    return (f"the table leaves the screw's travel: it reaches {1e3 * low:.4g} … "
            f"{1e3 * high:.4g} mm on a {1e3 * screw_length:.4g}-mm screw (no end stops are "
            "modelled)")


def _time_below(t: np.ndarray, s: np.ndarray, level: float) -> float:
    """Time [s] during which the piecewise-linear interpolant of s is below ``level``."""
    a, b = s[:-1] - level, s[1:] - level
    dt = np.diff(t)
    both = (a < 0) & (b < 0)
    total = float(np.sum(dt[both]))
    cross = (a < 0) != (b < 0)
    if np.any(cross):
        a_c, b_c, dt_c = a[cross], b[cross], dt[cross]
        # fraction of the interval spent below the level, from the linear crossing point
        frac_below = np.where(a_c < 0, a_c / (a_c - b_c), b_c / (b_c - a_c))
        total += float(np.sum(frac_below * dt_c))
    return total


#: a uniform resampling grid holds at most this many times the samples it is made from
MAX_RESAMPLE_FACTOR = 4


def resample_size(t: np.ndarray, dt: float, *, lines: np.ndarray | None = None,
                  source: str | None = None) -> int:
    """Points of a uniform grid of step ``dt`` [s] over ``t``, refused with a message when
    it would exceed :data:`MAX_RESAMPLE_FACTOR` × the samples (a gap in the record: a
    31-row file whose last time is 10⁶ s would otherwise ask for 10⁹ points)."""
    n = int(math.floor((float(t[-1]) - float(t[0])) / dt + 1e-9)) + 1
    limit = MAX_RESAMPLE_FACTOR * int(t.size)
    if n > limit:
        steps = np.diff(t)
        k = int(np.argmax(steps))
        where = (f"line {int(lines[k + 1])}" if lines is not None and lines.size == t.size
                 else f"sample {k + 1}")
        prefix = f"{source}: " if source else ""
        raise ValueError(
            f"{prefix}time: a gap of {float(steps[k]):.6g} s before {where} (median step "
            f"{dt:.3g} s); a uniform grid would need {n} points, more than "
            f"{MAX_RESAMPLE_FACTOR}× the {t.size} samples; refused — split the record at the "
            "gap")
    return n


def _uniform(t: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, float]:
    """Samples of s on a uniform grid (resampled linearly when the sampling jitters > 1 %)."""
    steps = np.diff(t)
    dt = float(np.median(steps))
    if float(np.max(np.abs(steps - dt))) <= 0.01 * dt:
        return s, dt
    n = resample_size(t, dt)
    grid = t[0] + dt * np.arange(n)
    return np.interp(grid, t, s), dt


def _dominant_frequency(t: np.ndarray, s: np.ndarray, ripple_ratio: float,
                        thresholds: CreepThresholds) -> float | None:
    """Periodogram peak [Hz] of the linearly detrended speed, or None (see thresholds)."""
    if ripple_ratio < thresholds.min_ripple_for_frequency:
        return None
    x, dt = _uniform(t, s)
    n = x.size
    pad = 8
    nfft = 1 << int(math.ceil(math.log2(pad * n)))
    from scipy.signal import periodogram  # imported here: keeps `feeddrive --help` fast

    freq, power = periodogram(x, fs=1.0 / dt, window="hann", detrend="linear", nfft=nfft)
    span = n * dt
    usable = freq >= 2.0 / span  # a period must fit at least twice into the window
    total = float(np.sum(power[1:]))
    if not np.any(usable) or total <= 0.0:
        return None
    idx = np.flatnonzero(usable)
    k = int(idx[np.argmax(power[idx])])
    lobe = 2 * nfft // n + 1  # Hann main lobe: ±2 bins of the unpadded resolution
    share = float(np.sum(power[max(k - lobe, 1):k + lobe + 1])) / total
    if share < thresholds.min_peak_share:
        return None
    if 0 < k < freq.size - 1 and np.all(power[k - 1:k + 2] > 0):
        # parabolic interpolation of log power refines the peak between bins
        ym, y0, yp = np.log(power[k - 1:k + 2])
        denom = ym - 2.0 * y0 + yp
        shift = 0.5 * (ym - yp) / denom if denom < 0 else 0.0
        return float(freq[k] + shift * (freq[1] - freq[0]))
    return float(freq[k])


def creep_metrics(
    time: object,
    speed: object,
    command_speed: float,
    *,
    thresholds: CreepThresholds | None = None,
    window: tuple[float, float] | None = None,
) -> CreepMetrics:
    """Creep metrics of a table-speed trace.

    Parameters
    ----------
    time:
        Sample times [s], strictly increasing (need not be uniform).
    speed:
        Table speed [m/s] at those times.
    command_speed:
        Commanded table speed [m/s], non-zero; negative for motion in the − direction.
    thresholds:
        Verdict limits; :class:`CreepThresholds` defaults when None.
    window:
        (start, end) [s] of the part to assess; :func:`steady_window` when None.

    The speed is treated as piecewise linear between samples: the stick fraction is the
    exact fraction of window time during which that interpolant is below
    ``stick_level``·|v_cmd|, and the mean speed is its time average.
    """
    t, v = _as_trace(time, speed)
    vc = _check_command(command_speed)
    th = thresholds if thresholds is not None else CreepThresholds()
    if window is None:
        start, end = steady_window(t, v, vc)
    else:
        try:
            start, end = (float(window[0]), float(window[1]))
        except (TypeError, ValueError, IndexError):
            raise ValueError(f"window = {window!r}: expected (start, end) in seconds") from None
        if not (math.isfinite(start) and math.isfinite(end) and start < end):
            raise ValueError(f"window = {window!r}: expected finite start < end [s]")
        if end <= t[0] or start >= t[-1]:
            raise ValueError(f"window = {window!r}: outside the record "
                             f"[{t[0]:g}, {t[-1]:g}] s")
    sel = (t >= start) & (t <= end)
    if int(np.count_nonzero(sel)) < _MIN_WINDOW_SAMPLES:
        raise ValueError(f"window: only {int(np.count_nonzero(sel))} samples between "
                         f"{start:g} s and {end:g} s; need at least {_MIN_WINDOW_SAMPLES}")
    tw, vw = t[sel], v[sel]
    direction = math.copysign(1.0, vc)
    along = vw * direction
    ref = abs(vc)
    duration = float(tw[-1] - tw[0])
    mean_speed = float(_trapezoid(vw, tw) / duration)
    ripple = float((np.max(along) - np.min(along)) / ref)
    min_ratio = float(np.min(along) / ref)
    max_ratio = float(np.max(along) / ref)
    stick = _time_below(tw, along, th.stick_level * ref) / duration
    freq = _dominant_frequency(tw, along, ripple, th)
    creeping = stick > th.max_stick_fraction or ripple > th.max_ripple_ratio
    peak = float(np.max(np.abs(vw))) / ref
    unstable = peak > th.max_speed_ratio or mean_speed / vc < -1.0
    return CreepMetrics(
        command_speed=vc,
        window_start=float(tw[0]),
        window_end=float(tw[-1]),
        mean_speed=mean_speed,
        ripple_ratio=ripple,
        min_ratio=min_ratio,
        stick_fraction=float(stick),
        stick_slip_frequency=freq,
        verdict="unstable" if unstable else "creeping" if creeping else "smooth",
        thresholds=th,
        max_ratio=max_ratio,
        window_samples=int(tw.size),
    )


# ---------------------------------------------------------------- sine and position metrics


def reversal_overshoot(time: np.ndarray, speed: np.ndarray, reference: np.ndarray,
                       amplitude: float, frequency: float) -> float:
    """Largest |v − v_ref| / amplitude within ±10 % of a period around each reference zero
    crossing after the first period (Wang2021 Figs. 9–10: overshoot at speed reversal)."""
    return reversal_overshoot_at(time, speed, reference, amplitude, frequency)[0]


def reversal_overshoot_at(time: ArrayLike, speed: ArrayLike, reference: ArrayLike,
                          amplitude: float, frequency: float) -> tuple[float, float | None]:
    """:func:`reversal_overshoot` and the time [s] where it occurs (None: no reversal)."""
    t = np.asarray(time, dtype=float)
    v = np.asarray(speed, dtype=float)
    ref = np.asarray(reference, dtype=float)
    period = 1.0 / frequency
    crossings = np.arange(1, int(t[-1] * 2 * frequency) + 1) * period / 2.0
    crossings = crossings[(crossings >= period) & (crossings <= t[-1] - 0.1 * period)]
    worst, at = 0.0, None
    for tc in crossings:
        sel = np.flatnonzero(np.abs(t - tc) <= 0.1 * period)
        if sel.size:
            k = sel[int(np.argmax(np.abs(v[sel] - ref[sel])))]
            if at is None or abs(v[k] - ref[k]) > worst:
                worst, at = float(abs(v[k] - ref[k])), float(t[k])
    return worst / amplitude, at


@dataclass(frozen=True)
class SineMetrics:
    """How a table follows a sinusoidal speed command v_ref = A·sin(2πft).  SI units.

    Judged after the first period (the start transient).  ``tracking_error_*`` [m/s]: RMS
    and largest |v − v_ref|; ``reversal_overshoot``: :func:`reversal_overshoot` (a fraction
    of A); ``stick_time_at_reversals`` [s]: mean time around each reversal during which
    |v| < ``stick_level``·A, beside ``reference_dwell`` [s], the time the command itself
    spends there (so the excess is the table's sticking at reversal, Wang2021 Sect. 5.3).
    """

    amplitude: float
    frequency: float
    tracking_error_rms: float
    tracking_error_max: float
    reversal_overshoot: float
    stick_time_at_reversals: float
    reference_dwell: float
    reversals: int
    window_start: float
    window_end: float


def sine_metrics(time: np.ndarray, speed: np.ndarray, reference: np.ndarray, *,
                 frequency: float, stick_level: float = 0.1) -> SineMetrics:
    """:class:`SineMetrics` of a table-speed trace against its sinusoidal reference."""
    t, v = _as_trace(time, speed)
    ref = np.asarray(reference, dtype=float)
    if ref.shape != t.shape:
        raise ValueError("reference: expected one value per sample [m/s]")
    if not (math.isfinite(frequency) and frequency > 0.0):
        raise ValueError(f"frequency = {frequency!r}: expected > 0 [Hz]")
    stick_level = _check_fraction("stick_level", stick_level)
    period = 1.0 / frequency
    start = period if t[-1] - t[0] > 1.5 * period else t[0]
    sel = t >= start
    amplitude = float(np.max(np.abs(ref)))
    if amplitude <= 0.0:
        raise ValueError("reference: the sine amplitude is 0 [m/s]")
    err = v[sel] - ref[sel]
    level = stick_level * amplitude
    crossings = np.arange(1, int(t[-1] * 2 * frequency) + 1) * period / 2.0
    crossings = crossings[(crossings >= start) & (crossings <= t[-1] - 0.25 * period)]
    dwell = []
    for tc in crossings:
        near = np.abs(t - tc) <= 0.25 * period
        dwell.append(_time_below(t[near], np.abs(v[near]), level))
    return SineMetrics(
        amplitude=amplitude, frequency=frequency,
        tracking_error_rms=float(np.sqrt(np.mean(err**2))),
        tracking_error_max=float(np.max(np.abs(err))),
        reversal_overshoot=reversal_overshoot(t, v, ref, amplitude, frequency),
        stick_time_at_reversals=float(np.mean(dwell)) if dwell else 0.0,
        reference_dwell=2.0 * math.asin(stick_level) / (2.0 * math.pi * frequency),
        reversals=len(dwell), window_start=float(start), window_end=float(t[-1]))


def position_metrics(time: np.ndarray, following_error: np.ndarray,
                     window: tuple[float, float]) -> dict[str, float]:
    """Position-side figures a machine-tool engineer reads first, in µm, over ``window`` [s].

    ``following_error_max_um`` / ``_rms_um``: largest and RMS |x_ref − x| (commanded minus
    table position); ``position_deviation_um``: peak-to-peak variation of the following error
    (0 for motion at a constant lag; stick-slip shows as a sawtooth of this height).
    """
    t = np.asarray(time, dtype=float)
    e = np.asarray(following_error, dtype=float)
    sel = (t >= window[0]) & (t <= window[1])
    if not np.any(sel):
        raise ValueError(f"window = {window!r}: holds no sample [s]")
    e = e[sel]
    return {"following_error_max_um": 1e6 * float(np.max(np.abs(e))),
            "following_error_rms_um": 1e6 * float(np.sqrt(np.mean(e**2))),
            "position_deviation_um": 1e6 * float(np.ptp(e))}
