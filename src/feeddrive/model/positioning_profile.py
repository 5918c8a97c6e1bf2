"""A reference that visits a list of positions, stopping at each: the positioning test's moves.

Built on :class:`~feeddrive.model.reference.SampledSpeed` (so the compiled reference kernel
needs nothing new): each move is a trapezoidal speed profile on the sample grid — linear ramps
at the given acceleration, a hold at (at most) the feed — followed by a dwell at rest.  The
ramps and the hold are whole numbers of samples and the hold speed is scaled so that the
exact integral of the linearly interpolated speed (what the kernel integrates) is the move's
length: the commanded position stands exactly on each stop during its dwell.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..parameters import ParameterError
from .reference import SampledSpeed

__all__ = ["stops_profile"]


def _positive(name: str, value: float, unit: str) -> float:
    if not (math.isfinite(value) and value > 0.0):
        raise ParameterError(name, value, f"expected a value > 0 [{unit}]")
    return float(value)


def stops_profile(positions: Sequence[float], *, feed: float, acceleration: float,
                  dwell: float, interval: float = 1e-3
                  ) -> tuple[SampledSpeed, np.ndarray]:
    """Move from 0 to each of ``positions`` in turn, resting ``dwell`` at each.

    Parameters
    ----------
    positions : sequence of float
        The stops, relative to the start (the table at rest at 0) [m].
    feed : float
        Largest speed of a move [m/s].
    acceleration : float
        Acceleration of the ramps [m/s²].
    dwell : float
        Rest at each stop [s].
    interval : float, default 1e-3
        Sample interval of the tabulated speed [s].

    Returns
    -------
    profile : SampledSpeed
        The tabulated speed (positions its exact integral).
    dwell_ends : numpy.ndarray
        When each stop's dwell ends [s].

    Raises
    ------
    ParameterError
        For a feed, acceleration, dwell or interval ≤ 0, or a dwell shorter than 2 samples.

    Examples
    --------
    >>> from feeddrive.model.positioning_profile import stops_profile
    >>> prof, ends = stops_profile([0.01, 0.0], feed=0.02, acceleration=0.2, dwell=0.5)
    >>> enc = prof.encode()[1]  # rows: table position, table speed, …
    >>> print(f"{enc[0][int(round(ends[0] / 1e-3))] * 1e3:.12f} mm, {ends[-1]:.3f} s")
    10.000000000000 mm, 2.200 s
    """
    feed = _positive("feed", feed, "m/s")
    acceleration = _positive("acceleration", acceleration, "m/s²")
    dwell = _positive("dwell", dwell, "s")
    interval = _positive("interval", interval, "s")
    n_dwell = int(round(dwell / interval))
    if n_dwell < 2:
        raise ParameterError("dwell", dwell, f"expected at least 2 samples of {interval:g} s")
    speeds: list[np.ndarray] = [np.zeros(1)]
    ends: list[float] = []
    here = 0.0
    count = 1  # samples so far; the last one is at rest
    for target in positions:
        distance = float(target) - here
        if distance != 0.0:
            # ramp time to the feed, then the hold that covers the distance at the feed
            n_ramp = max(1, int(math.ceil(feed / acceleration / interval - 1e-9)))
            n_hold = max(0, int(math.ceil((abs(distance) / feed - n_ramp * interval)
                                          / interval - 1e-9)))
            # area of the unit trapezoid on the grid: (ramp + hold) samples × interval
            peak = distance / ((n_ramp + n_hold) * interval)
            if n_hold == 0:
                # too short to reach the feed: the triangle at the acceleration, when it is
                # shorter and stays within the feed (the ramps were stretched to the feed's
                # length, so a higher feed made a short move slower: an outside check,
                # 2026-12-07)
                n_tri = max(1, int(math.ceil(math.sqrt(abs(distance) / acceleration)
                                             / interval - 1e-9)))
                if n_tri < n_ramp and abs(distance) / (n_tri * interval) <= feed:
                    n_ramp = n_tri
                    peak = distance / (n_ramp * interval)
            if abs(peak) / (n_ramp * interval) > acceleration * (1 + 1e-9):
                # a short move: a triangle at the acceleration, its peak below the feed
                n_ramp = max(1, int(math.ceil(math.sqrt(abs(distance) / acceleration)
                                              / interval - 1e-9)))
                n_hold = 0
                peak = distance / (n_ramp * interval)
            up = peak * np.arange(1, n_ramp + 1) / n_ramp
            move = np.concatenate([up, np.full(n_hold, peak), up[::-1][1:], [0.0]])
            speeds.append(move)
            count += move.size
        speeds.append(np.zeros(n_dwell))
        count += n_dwell
        ends.append((count - 1) * interval)
        here = float(target)
    v = np.concatenate(speeds)
    t = np.arange(v.size) * interval
    return SampledSpeed(time=t, table_speed=v), np.asarray(ends)
