"""Critical speed of a drive whose speed ripple is *forced* (motor torque ripple, cogging).

A periodic disturbance on a fast shaft (the DDFS's motors turn at ~16 mm/s of nut motion)
makes the table speed ripple at the disturbance's frequency at every speed; the ripple's size
falls roughly as 1/v_n and does not depend on the command.  Such a drive never "creeps" in
the sense of :class:`~feeddrive.analysis.cycle_verdict.VerdictRule` (stick-slip or a self-sustained
oscillation): it oscillates everywhere, and its critical speed is *defined by a threshold* —
the lowest command at which the steady peak-to-peak table-speed ripple stays below ``threshold``
× the command.  With 1.0 the speed just touches zero (a visible staircase in a position
trace); Wang2021's plots and the v1 engine's creep verdict correspond to 0.5.  The number is
reported with its threshold and its sensitivity to it (issue 14).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from ..engine.simulate import DriveSystem, SolverOptions, simulate
from ..model.reference import ConstantSpeed
from .creep_window import creep_metrics
from .critical import check_verdict_interval

THRESHOLDS = (0.3, 0.5, 1.0)
TRIAL = 12.0  # [s] the forced ripple is steady after the start (checked against 24 s)


@dataclass(frozen=True)
class ForcedRipplePoint:
    """The steady table-speed ripple at one commanded speed (the forced-ripple criterion).

    Parameters
    ----------
    speed : float
        Commanded table speed [m/s].
    ripple_ratio : float
        Steady peak-to-peak speed over the command [-].
    min_ratio : float
        Lowest speed over the command [-].
    mean_ratio : float
        Mean speed over the command [-].
    stuck : bool
        The table stopped or reversed (stick-slip rather than forced ripple).
    """
    speed: float  # [m/s]
    ripple_ratio: float  # steady peak-to-peak / command
    min_ratio: float  # lowest speed / command
    mean_ratio: float  # mean speed / command
    stuck: bool  # the table stopped or reversed (stick-slip rather than forced ripple)

    def exceeds(self, threshold: float) -> bool:
        """Ripple above ``threshold`` × command, or a mean off the command by more than half
        of it (a table that has not broken away has no ripple, and no speed either).

        Parameters
        ----------
        threshold : float
            The ripple threshold, relative to the command [-].

        Returns
        -------
        bool
            Whether the point fails the criterion.
        """
        return (self.ripple_ratio > threshold
                or abs(self.mean_ratio - 1.0) > 0.5 * threshold)


def ripple_point(system: DriveSystem, speed: float, nut_speed: float = 0.0, *,
                 duration: float = TRIAL, options: SolverOptions | None = None
                 ) -> ForcedRipplePoint:
    """Steady table-speed ripple at ``speed`` [m/s] over the last half of a ``duration`` run.

    Parameters
    ----------
    system : DriveSystem
        The drive.
    speed : float
        Commanded table speed [m/s].
    nut_speed : float, default 0.0
        Nut speed [m/s].
    duration : float, default 12.0
        Length of the run [s].
    options : SolverOptions, optional
        The solver options.

    Returns
    -------
    ForcedRipplePoint
        The ripple.
    """
    r = simulate(system, ConstantSpeed(speed, nut_speed), duration, options=options)
    m = creep_metrics(r.time, r["table_speed"], speed, window=(duration / 2.0, duration),
                      frequency=False)  # the frequency is not part of the point
    return ForcedRipplePoint(speed, m.ripple_ratio, m.min_ratio, m.mean_speed / speed,
                             m.min_ratio <= 0.0)


def threshold_critical_speed(system: DriveSystem, nut_speed: float = 0.0, *,
                             threshold: float = 0.5,
                             speed_range: tuple[float, float] = (0.05e-3, 3.0e-3),
                             coarse_step: float = 0.2e-3, resolution: float = 0.01e-3,
                             options: SolverOptions | None = None,
                             known: dict[float, ForcedRipplePoint] | None = None,
                             ) -> dict[str, Any]:
    """The lowest speed [m/s] in ``speed_range`` above which the steady ripple stays below
    ``threshold`` × the command: scan down in ``coarse_step``, bisect to ``resolution``.

    ``known``: ripple points of this system and nut speed already simulated (filled in as the
    search goes), so that searches at several thresholds share their runs
    (:func:`threshold_critical_speeds`); the result lists the points this search used.

    Parameters
    ----------
    system : DriveSystem
        The drive.
    nut_speed : float, default 0.0
        Nut speed [m/s].
    threshold : float, default 0.5
        Ripple threshold, relative to the command [-].
    speed_range : tuple of (float, float)
        Speeds searched [m/s].
    coarse_step : float, default 2e-4
        Step of the scan [m/s].
    resolution : float, default 1e-5
        Bisection resolution [m/s].
    options : SolverOptions, optional
        The solver options.
    known : dict of float to ForcedRipplePoint, optional
        Points already simulated, by speed [m/s]; filled in as the search goes.

    Returns
    -------
    dict
        Drive, nut speed [mm/s], threshold, critical speed [mm/s] (None when out of range),
        status, kind, the speed range [mm/s] and the points used.

    Raises
    ------
    ValueError
        For a threshold ≤ 0.
    ParameterError
        For an output interval coarser than a verdict's
        (:func:`~feeddrive.analysis.critical.check_verdict_interval`).
    """
    if not (0.0 < threshold and math.isfinite(threshold)):
        raise ValueError(f"threshold = {threshold!r}: expected > 0 (a ripple/command ratio)")
    check_verdict_interval(system, options)  # the ripple is read off the samples
    lo, hi = speed_range
    cache: dict[float, ForcedRipplePoint] = {} if known is None else known
    points: dict[float, ForcedRipplePoint] = {}

    def above(v: float) -> bool:
        if v not in cache:
            cache[v] = ripple_point(system, v, nut_speed, options=options)
        points[v] = cache[v]
        return points[v].exceeds(threshold)

    # coarse scan from the top (the ripple need not be monotonic: the CDFS is smooth again
    # below its creep band), then bisection between the highest exceeding speed and the
    # tested speed above it
    n = max(2, int(math.ceil((hi - lo) / coarse_step)) + 1)
    grid = [hi - k * (hi - lo) / (n - 1) for k in range(n)]
    crit: float | None = None
    status = "below-range"
    if above(grid[0]):
        status = "above-range"
    else:
        for upper, lower in zip(grid[:-1], grid[1:], strict=True):
            if above(lower):
                a, b = lower, upper
                while b - a > resolution:
                    mid = 0.5 * (a + b)
                    if above(mid):
                        a = mid
                    else:
                        b = mid
                # the answer on the grid of multiples of the resolution, whatever the scan:
                # the lowest multiple that does not exceed, with the one below it exceeding
                k = math.floor(a / resolution + 1e-9) + 1
                while above(k * resolution):
                    k += 1
                while k - 1 > 0 and (k - 1) * resolution > lo and not above(
                        (k - 1) * resolution):
                    k -= 1
                crit = round(k * resolution, 12)
                status = "found"
                break
    # the kind just below the critical speed: the highest tested speed under it
    below = [p for v, p in sorted(points.items()) if crit is not None and v < crit]
    kind = None if not below else ("stick-slip" if below[-1].stuck else "oscillation")
    return {
        "drive": system.drive, "nut_speed_mm_s": 1e3 * nut_speed, "threshold": threshold,
        "critical_speed_mm_s": None if crit is None else round(1e3 * crit, 6),
        "status": status, "kind": kind,
        "speed_range_mm_s": [1e3 * speed_range[0], 1e3 * speed_range[1]],
        "rule": (f"lowest command above which the steady peak-to-peak table-speed ripple "
                 f"(last half of a {TRIAL:g}-s run) stays below {threshold:g} × the "
                 "command"),
        "points": [{"speed_mm_s": 1e3 * p.speed, "ripple_ratio": p.ripple_ratio,
                    "min_ratio": p.min_ratio, "mean_ratio": p.mean_ratio}
                   for p in sorted(points.values(), key=lambda p: p.speed)],
    }


def threshold_critical_speeds(system: DriveSystem, nut_speed: float = 0.0, *,
                              thresholds: tuple[float, ...] = THRESHOLDS,
                              **search: Any) -> list[dict[str, Any]]:
    """:func:`threshold_critical_speed` at each of ``thresholds``, the ripple runs shared
    (the scan grid is the same for every threshold).

    Parameters
    ----------
    system : DriveSystem
        The drive.
    nut_speed : float, default 0.0
        Nut speed [m/s].
    thresholds : tuple of float, default (0.3, 0.5, 1.0)
        Ripple thresholds, relative to the command [-].
    **search
        Passed to :func:`threshold_critical_speed`.

    Returns
    -------
    list of dict
        One search result per threshold.
    """
    known: dict[float, ForcedRipplePoint] = {}
    return [threshold_critical_speed(system, nut_speed, threshold=th, known=known, **search)
            for th in thresholds]
