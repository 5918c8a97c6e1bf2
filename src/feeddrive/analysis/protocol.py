"""The critical-speed protocol `feeddrive creep` and `feeddrive reproduce` share.  SI units.

Both used to search different speed grids (0.05–3.0 mm/s in 0.1-mm/s steps against
0.02–3.02 mm/s in 0.2-mm/s steps), and a step-down search remembers the steps it came down,
so the CLI and the report gave the CDFS 1.35 and 1.32 mm/s by "the same" protocol (issue 12
item 18).  One set of numbers now serves both; the report and the CLI print it.
"""

from __future__ import annotations

import math

import numpy as np

SPEED_RANGE = (0.02e-3, 3.02e-3)  # [m/s] lowest and highest speed tested
COARSE_STEP = 0.2e-3  # [m/s] scan step from rest, before the bisection
STAIRCASE_COARSE_STEP = 0.1e-3  # [m/s] first staircase of the step-down search
RESOLUTION = 0.01e-3  # [m/s] Wang2021 Sect. 6: the speed was stepped down by 0.01 mm/s
TRIAL_DURATION = 12.0  # [s] first trial length (doubled until the verdict is decided)
TRIAL_MAX_DURATION = 240.0  # [s] longest trial; still undecided then: 'undecided'
# the linear stability scan of steady sliding (`feeddrive stability`, the sweep's
# `linear-band` quantity, the explorer, linear.stability_band): one default range (issue 24
# item 8: the command scanned 0.01–5 mm/s and the sweep 0.02–3.02 mm/s)
LINEAR_SPEED_RANGE = (0.01e-3, 5e-3)  # [m/s] log-spaced scan, edges bisected
LINEAR_POINTS = 40  # [-] scan points
# [-] the most scan points a band takes: one linearisation each (10^8 ran for hours before
# any check: an outside check, 2026-12-07)
MAX_LINEAR_POINTS = 10_000
# a search's work is bounded before it starts (issue 39 item 4): `predict --resolution
# 1e-300` bisected forever (its speeds are rounded to 1e-12 m/s, so the bisection stalled)
SMALLEST_RESOLUTION = RESOLUTION / 100  # [m/s] a hundredth of the paper's step
MAX_SEARCH_STEPS = 2000  # [-] speeds on a coarse scan; fine steps per coarse step


def check_search(*, low: float, high: float, coarse_step: float, resolution: float,
                 names: dict[str, str] | None = None, unit: str = "mm/s") -> None:
    """Refuse a critical-speed search whose work is not bounded, before it starts.

    At most ``MAX_SEARCH_STEPS`` speeds on the coarse scan of [low, high] and fine steps
    per coarse step (a step-down staircase runs every one), and a resolution of at least
    ``SMALLEST_RESOLUTION``.

    Parameters
    ----------
    low, high : float
        The speeds searched [m/s].
    coarse_step : float
        Step of the coarse scan [m/s].
    resolution : float
        Resolution of the bisection or fine staircase [m/s].
    names : dict of str to str, optional
        The name each of ``low``, ``high``, ``coarse_step``, ``resolution`` has in messages
        (``--resolution``, ``quantity.resolution``); the keyword by default.
    unit : str, default "mm/s"
        The unit the settings were given in, and messages show them in: ``"mm/s"`` (the CLI,
        a sweep's ``[quantity]``) or ``"m/s"`` (the API's own arguments).

    Raises
    ------
    ParameterError
        Naming the setting, its value and the bound [``unit``].
    """
    from ..parameters import ParameterError

    name = {k: k for k in ("low", "high", "coarse_step", "resolution")} | (names or {})
    factor = 1e3 if unit == "mm/s" else 1.0

    def refuse(key: str, value: float, expected: str) -> ParameterError:
        return ParameterError(name[key], value * factor, f"{expected} [{unit}]")

    if not resolution >= SMALLEST_RESOLUTION:
        raise refuse("resolution", resolution,
                     f"expected ≥ {SMALLEST_RESOLUTION * factor:g}")
    if (high - low) / coarse_step > MAX_SEARCH_STEPS:
        raise refuse("coarse_step", coarse_step, f"expected ≥ {(high - low) * factor:g} / "
                                                 f"{MAX_SEARCH_STEPS} (speeds on the scan)")
    if coarse_step / resolution > MAX_SEARCH_STEPS:
        raise refuse("resolution", resolution, f"expected ≥ the coarse step "
                                               f"{coarse_step * factor:g} / {MAX_SEARCH_STEPS}")


def speed_grid(low: float, high: float, step: float) -> np.ndarray:
    """The coarse speeds of a search on [low, high] [m/s], rising: ``low``, ``low + step``, …
    and ``high`` itself, the last step shorter when the range is not a whole number of steps
    (the grid stopped at the last whole step: ``creep --high 1.61`` tested nothing above
    1.42 mm/s and answered "> 1.61 mm/s (creeps at every tested speed)"; an outside check,
    2026-12-07).  A range of whole steps (the protocol's 0.02–3.02 mm/s) gives the same speeds
    as before.  The search from rest scans it rising, the step-down's first staircase falling.

    Parameters
    ----------
    low, high : float
        The speeds searched [m/s].
    step : float
        The coarse step [m/s].

    Returns
    -------
    numpy.ndarray
        The speeds [m/s], rounded to 1e-12 m/s.
    """
    n = int(math.floor((high - low) / step + 1e-9))
    grid = np.round(low + step * np.arange(n + 1), 12)
    top = round(high, 12)
    if top > grid[-1] + 1e-9 * step:
        grid = np.append(grid, top)
    return grid


def grid_steps(low: float, high: float, step: float) -> tuple[int, float | None]:
    """The steps of :func:`speed_grid`: how many are whole, and the shorter one at its top
    when the range is not a whole number of steps.

    Parameters
    ----------
    low, high : float
        The speeds searched [m/s].
    step : float
        The coarse step [m/s].

    Returns
    -------
    tuple of (int, float or None)
        The whole steps, and the shorter step [m/s] (None when every step is whole).
    """
    gaps = np.diff(speed_grid(low, high, step))
    if gaps.size and gaps[-1] < step * (1.0 - 1e-6):
        return gaps.size - 1, float(gaps[-1])
    return int(gaps.size), None


def fine_staircase(upper: float, lower: float, step: float) -> np.ndarray:
    """The speeds of a step-down's fine staircase between two coarse speeds [m/s], falling:
    ``upper − step``, ``upper − 2·step``, … and ``lower`` itself, the last step shorter when
    the gap is not a whole number of steps (Wang2021 Sect. 6 lowers the speed 0.01 mm/s at a
    time).  The staircase stopped at the last whole step above ``lower`` or, half a step or
    more short, took one whole step past it, below the gap it refines (``creep --high
    1.537``: 1.527, then 1.517 mm/s under the coarse 1.52).  A gap of whole steps (every gap of
    the protocol's 0.02–3.02 mm/s staircase) gives the same speeds as before.

    Parameters
    ----------
    upper, lower : float
        The coarse speeds the staircase runs between, ``upper > lower`` [m/s].
    step : float
        The fine step [m/s].

    Returns
    -------
    numpy.ndarray
        The speeds below ``upper`` down to ``lower`` [m/s], rounded to 1e-12 m/s.

    References
    ----------
    Wang2021 Sect. 6: the step-down lowers the speed by 0.01 mm/s.
    """
    whole = np.round(np.arange(upper - step, lower - step / 2, -step), 12)
    return np.append(whole[whole > lower + 1e-9 * step], round(lower, 12))


def _last_fine(upper: float, lower: float, step: float) -> float | None:
    """The shorter last step [m/s] of :func:`fine_staircase` between two coarse speeds, or
    None when its steps are whole (or it is one step, the coarse one)."""
    fine = fine_staircase(upper, lower, step)
    if fine.size < 2:
        return None
    last = float(fine[-2] - fine[-1])
    return last if last < step * (1.0 - 1e-6) else None


def _fine_text(low: float, high: float, coarse_step: float, step: float) -> str:
    """Where the fine staircases (:func:`fine_staircase`) end on a shorter step [m/s in,
    mm/s out]: ``, the last 0.005 mm/s within the first`` for the first coarse step (from
    ``high`` down, shorter when the range is not whole coarse steps), ``, the last 0.01 mm/s
    within each coarse step`` when ``step`` does not divide ``coarse_step``, both when they
    differ; ``""`` when every staircase is whole steps."""
    grid = speed_grid(low, high, coarse_step)
    first = _last_fine(float(grid[-1]), float(grid[-2]), step)
    top_short = grid_steps(low, high, coarse_step)[1] is not None
    if not top_short:
        whole = first
    elif grid.size > 2:
        whole = _last_fine(float(grid[-2]), float(grid[-3]), step)
    else:  # one coarse step, the shorter one
        whole = None
    if whole is None:
        return "" if first is None else \
            f", the last {1e3 * first:g} mm/s within {'it' if grid.size == 2 else 'the first'}"
    if grid.size == 2:
        return f", the last {1e3 * whole:g} mm/s within it"
    if first is not None and math.isclose(first, whole, rel_tol=1e-6):
        return f", the last {1e3 * whole:g} mm/s within each coarse step"
    return (f", the last {1e3 * whole:g} mm/s within each coarse step but the first"
            + ("" if first is None else f", {1e3 * first:g} mm/s within that one"))


def _steps_text(low: float, high: float, step: float, odd: str) -> str:
    """``in 0.2-mm/s steps``, with ``, the last 0.08 mm/s`` (``odd`` naming which one)
    where :func:`speed_grid` ends on a shorter step [m/s in, mm/s out]."""
    whole, short = grid_steps(low, high, step)
    if short is None:
        return f"in {1e3 * step:g}-mm/s steps"
    if whole == 0:
        return f"in one {1e3 * short:g}-mm/s step"
    return f"in {1e3 * step:g}-mm/s steps, the {odd} {1e3 * short:g} mm/s"


def describe(start: str, *, speed_range: tuple[float, float] = SPEED_RANGE,
             coarse_step: float | None = None, resolution: float = RESOLUTION,
             durations: tuple[float, float] = (TRIAL_DURATION, TRIAL_MAX_DURATION),
             holds: bool = False) -> str:
    """The critical-speed search protocol in words, in mm/s, for the CLI and the report: by
    default the protocol's own settings, else those a search ran with.

    Parameters
    ----------
    start : str
        ``"rest"`` (trials from rest, scan then bisection) or ``"stepdown"`` (a staircase on a
        running table; any other word than ``"rest"`` is the step-down, ``"running"`` too).
    speed_range : tuple of float, optional
        Lowest and highest speed tested [m/s].
    coarse_step : float or None, default None
        The scan step from rest, or the step-down's first (coarse) staircase step [m/s], as
        ``critical_speed_from_rest(coarse_step=…)`` and ``critical_speed_stepdown(
        coarse_step=…)`` take it; None: the protocol's for that start (``COARSE_STEP``,
        ``STAIRCASE_COARSE_STEP``).
    resolution : float, default RESOLUTION
        The bisection's resolution from rest, or the step-down's fine step [m/s]
        (``critical_speed_stepdown(step=…)``, a sweep's ``quantity.resolution``).
    durations : tuple of float, optional
        A trial's first and longest length [s] (a step-down step's hold).
    holds : bool, default False
        Whether the step-down's sentence says how long each step is held.

    Returns
    -------
    str
        One sentence with the durations [s], the speed range and the steps [mm/s], as the
        search's grids (:func:`speed_grid`, :func:`fine_staircase`) run them.
    """
    lo, hi = (1e3 * v for v in speed_range)
    held = f"{durations[0]:g} s doubled up to {durations[1]:g} s until decided"
    if start == "rest":  # the scan rises: its last step is the shorter one
        steps = _steps_text(*speed_range, COARSE_STEP if coarse_step is None else coarse_step,
                            "last")
        return (f"from rest: trials of {held}, scan {lo:g}–{hi:g} mm/s {steps}, then "
                f"bisection to {1e3 * resolution:g} mm/s")
    coarse = STAIRCASE_COARSE_STEP if coarse_step is None else coarse_step
    steps = _steps_text(*speed_range, coarse, "first")  # it falls
    fine = _fine_text(*speed_range, coarse, resolution)
    return (f"step-down on a running table: staircase from {hi:g} mm/s {steps}, then "
            f"{1e3 * resolution:g}-mm/s steps from the last smooth one{fine} (down to "
            f"{lo:g} mm/s)" + (f", each step held {held}" if holds else ""))
