"""How a table follows its command: sine tracking, following error, travel.  SI units.

The figures ``feeddrive simulate`` prints beside (or, for a sine, instead of) the creep
metrics: tracking error, reversal overshoot and stick time at the reversals of a sinusoidal
speed command (Wang2021 Sect. 5.3, Figs. 9–10), the following error and position deviation a
machine-tool engineer reads first, and whether the table left the screw's travel.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .trace_input import as_trace, check_fraction, time_below

__all__ = ["SineMetrics", "position_metrics", "reversal_overshoot", "reversal_overshoot_at",
           "sine_metrics", "travel_warning"]


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
    t, v = as_trace(time, speed)
    ref = np.asarray(reference, dtype=float)
    if ref.shape != t.shape:
        raise ValueError("reference: expected one value per sample [m/s]")
    if not (math.isfinite(frequency) and frequency > 0.0):
        raise ValueError(f"frequency = {frequency!r}: expected > 0 [Hz]")
    stick_level = check_fraction("stick_level", stick_level)
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
        dwell.append(time_below(t[near], np.abs(v[near]), level))
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
