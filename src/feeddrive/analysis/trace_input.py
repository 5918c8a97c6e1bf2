"""A speed trace as the creep and tracking metrics take it.  SI units.

The checks every metric runs on its input (one-line errors naming the field), the uniform
resampling they may need (bounded by the data's size: issue 13 item 1), and the exact time a
piecewise-linear signal spends below a level (the stick time of the window rule, the
limit-cycle rule and the sine metrics).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..parameters.validation import check_speed, real_array

__all__ = ["MAX_RESAMPLE_FACTOR", "MIN_SAMPLES", "MIN_WINDOW_SAMPLES", "as_trace",
           "check_command", "check_fraction", "resample_size", "time_below", "uniform_samples"]

# numpy ≥ 2.0 calls it trapezoid; 1.26, the declared minimum, only has trapz
# (found by .ci/min-versions)
trapezoid: Any = getattr(np, "trapezoid", None) or getattr(np, "trapz")  # noqa: B009

#: fewest samples accepted in a trace, and in its steady window
MIN_SAMPLES = 16
#: fewest samples accepted in a window of a trace
MIN_WINDOW_SAMPLES = 8


def as_trace(time: object, speed: object) -> tuple[np.ndarray, np.ndarray]:
    """The trace as float arrays, or a one-line error naming what is wrong with it.

    Parameters
    ----------
    time : array_like
        Sample times [s]: 1-D, finite, strictly increasing, at least :data:`MIN_SAMPLES`.
    speed : array_like
        Table speed at those times [m/s]: finite, one per time.

    Returns
    -------
    tuple of numpy.ndarray
        (time [s], speed [m/s]).
    """
    # text, complex numbers and booleans refused naming the value (complex ones were cast to
    # their real part with a warning, booleans to 0 and 1 m/s: session 29)
    t = real_array("time", time, "s")
    v = real_array("speed", speed, "m/s")
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
                         f"({float(t[i - 1])!r} then {float(t[i])!r})")
    return t, v


def check_command(command_speed: object) -> float:
    """The command speed as a float, or a one-line refusal naming ``command_speed``: the
    shared :func:`~feeddrive.parameters.validation.check_speed` (any sign, not zero, at most
    ``LARGEST_SPEED``).

    Parameters
    ----------
    command_speed : float
        Commanded table speed [m/s]: finite and non-zero.

    Returns
    -------
    float
        The command speed [m/s].

    Raises
    ------
    ParameterError
        For a non-number, a non-finite or zero speed, or one above the limit (a ValueError:
        ``except ValueError`` still catches it).
    """
    # its own wording, a bare ValueError and no upper bound (1e9 m/s was taken) until the
    # shared check (session 27)
    return check_speed("command_speed", command_speed, sign="nonzero")


def check_fraction(name: str, value: float) -> float:
    """``value`` if it is a fraction in [0, 1), else a one-line error naming ``name``.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : float
        The fraction [-].

    Returns
    -------
    float
        ``value`` [-].
    """
    if not (0.0 <= value < 1.0):
        raise ValueError(f"{name} = {value!r}: expected a fraction in [0, 1)")
    return value


def time_below(t: np.ndarray, s: np.ndarray, level: float) -> float:
    """Time [s] during which the piecewise-linear interpolant of s is below ``level``.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times [s].
    s : numpy.ndarray
        The signal [its unit].
    level : float
        The level [unit of ``s``].

    Returns
    -------
    float
        The time [s].
    """
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
    31-row file whose last time is 10⁶ s would otherwise ask for 10⁹ points).

    Parameters
    ----------
    t : numpy.ndarray
        Sample times [s].
    dt : float
        Grid step [s].
    lines : numpy.ndarray of int, optional
        The file line of each sample, for the message.
    source : str, optional
        The file, for the message.

    Returns
    -------
    int
        Number of grid points.

    Raises
    ------
    ValueError
        When the grid would be too large, naming the gap.
    """
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


def uniform_samples(t: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, float]:
    """Samples of s on a uniform grid (resampled linearly when the sampling jitters > 1 %).

    Parameters
    ----------
    t : numpy.ndarray
        Sample times [s].
    s : numpy.ndarray
        The signal [its unit].

    Returns
    -------
    samples : numpy.ndarray
        The signal on the uniform grid [unit of ``s``].
    dt : float
        The grid step [s].
    """
    steps = np.diff(t)
    dt = float(np.median(steps))
    if float(np.max(np.abs(steps - dt))) <= 0.01 * dt:
        return s, dt
    n = resample_size(t, dt)
    grid = t[0] + dt * np.arange(n)
    return np.interp(grid, t, s), dt

