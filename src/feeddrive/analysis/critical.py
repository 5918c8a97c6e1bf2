"""Critical creeping velocity: the lowest table speed without stick-slip.  SI units.

Two protocols, because the answer can depend on how the table got to its speed (a friction
limit cycle can persist above the speed where steady sliding turns stable):

* **from rest** (``start="rest"``): every trial starts the table from rest with a short ramp;
  a coarse scan finds the highest creeping speed on a grid, then bisection refines the
  boundary to ``resolution`` (0.01 mm/s by default).  The scan guards against non-monotone
  behaviour (a creeping *band*), which plain bisection would miss.
* **step-down from a running table** (``start="running"``), the paper's experimental protocol
  (Wang2021 Sect. 6): one continuous run that starts higher and steps the command down by
  0.01 mm/s, dwelling at each speed, until the table crawls.  A coarse staircase first
  locates the region, a fine one then walks down 0.01 mm/s at a time.

The critical speed reported is the lowest tested speed that was smooth with every creeping
speed below it, i.e. the smooth end of the boundary.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from .. import units
from ..control import ConstantSpeed, SampledSpeed
from ..simulate import DriveSystem, SolverOptions, simulate
from .metrics import CreepMetrics, CreepThresholds, creep_metrics

MM_S = units.MM_PER_S


@dataclass(frozen=True)
class CreepTrial:
    """One tested speed [m/s] and what the metrics said."""

    speed: float
    creeping: bool
    ripple_ratio: float
    stick_fraction: float
    stick_slip_frequency: float | None
    decay_ratio: float | None = None  # late/early ripple of a trial from rest (judge_trial)

    @classmethod
    def from_metrics(cls, speed: float, m: CreepMetrics) -> CreepTrial:
        return cls(speed=speed, creeping=m.creeping, ripple_ratio=m.ripple_ratio,
                   stick_fraction=m.stick_fraction, stick_slip_frequency=m.stick_slip_frequency)


@dataclass(frozen=True)
class CriticalSpeed:
    """Result of a critical-speed search.

    ``status``: ``"found"``; ``"below-range"`` (smooth at every tested speed: the critical
    speed is below ``speed_range[0]``); ``"above-range"`` (creeps at every tested speed).
    """

    drive: str
    table_position: float
    nut_speed: float
    start: str
    critical_speed: float | None
    status: str
    resolution: float
    speed_range: tuple[float, float]
    trials: tuple[CreepTrial, ...] = field(default_factory=tuple)
    simulated_time: float = 0.0

    def display(self) -> str:
        """The result in mm/s as a user reads it, with the bound when out of range."""
        text = format_critical_speed({
            "critical_speed_mm_s": None if self.critical_speed is None
            else self.critical_speed / MM_S,
            "speed_range_mm_s": [v / MM_S for v in self.speed_range],
            "status": self.status})
        if self.status == "below-range":
            return f"{text} mm/s (smooth at every tested speed)"
        if self.status == "above-range":
            return f"{text} mm/s (creeps at every tested speed)"
        return f"{text} mm/s"

    def to_dict(self) -> dict[str, Any]:
        """Engineering units (mm, mm/s) for printing and JSON."""
        return {
            "drive": self.drive,
            "table_position_mm": self.table_position * 1e3,
            "nut_speed_mm_s": self.nut_speed / MM_S,
            "start": self.start,
            "critical_speed_mm_s": (None if self.critical_speed is None
                                    else round(self.critical_speed / MM_S, 6)),
            "status": self.status,
            "display": self.display(),
            "resolution_mm_s": self.resolution / MM_S,
            "speed_range_mm_s": [s / MM_S for s in self.speed_range],
            "trials": [{**asdict(t), "speed": t.speed / MM_S} for t in self.trials],
            "simulated_time_s": self.simulated_time,
        }


def format_critical_speed(search: dict[str, Any]) -> str:
    """Critical speed [mm/s] of a search (as :meth:`CriticalSpeed.to_dict` gives it), or the
    bound an out-of-range search gives: "< low" (smooth everywhere), "> high" (creeps
    everywhere)."""
    value = search["critical_speed_mm_s"]
    low, high = search["speed_range_mm_s"]
    if value is not None:
        return f"{value:.2f}"
    return f"< {low:.2f}" if search["status"] == "below-range" else f"> {high:.2f}"


def _check_speed(name: str, value: float) -> float:
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} = {value!r}: expected a finite speed > 0 [m/s]")
    return float(value)


#: an oscillation whose ripple in the last quarter of a trial is below this fraction of the
#: ripple in the quarter before is a decaying transient, not creep
PERSISTENCE = 0.8


def judge_trial(time: np.ndarray, speed: np.ndarray, command_speed: float,
                thresholds: CreepThresholds | None = None) -> CreepTrial:
    """Verdict on a trial started from rest, judged on its last quarter.

    Creeping means the metrics say so in the last quarter *and* the ripple there is at least
    ``PERSISTENCE`` × the ripple of the quarter before: stick-slip is a limit cycle of
    constant amplitude, while a weakly damped start-up oscillation decays (it may still be
    large after a few seconds; the paper's Fig. 6b "stabilised after 7 s" is of that kind).
    """
    t_end = float(time[-1])
    late = creep_metrics(time, speed, command_speed, thresholds=thresholds,
                         window=(0.75 * t_end, t_end))
    early = creep_metrics(time, speed, command_speed, thresholds=thresholds,
                          window=(0.5 * t_end, 0.75 * t_end))
    decay = late.ripple_ratio / early.ripple_ratio if early.ripple_ratio > 0 else 1.0
    trial = CreepTrial.from_metrics(command_speed, late)
    creeping = trial.creeping and decay >= PERSISTENCE
    return CreepTrial(speed=command_speed, creeping=creeping, ripple_ratio=trial.ripple_ratio,
                      stick_fraction=trial.stick_fraction,
                      stick_slip_frequency=trial.stick_slip_frequency, decay_ratio=decay)


def creep_trial(system: DriveSystem, speed: float, *, nut_speed: float = 0.0,
                duration: float = 12.0, thresholds: CreepThresholds | None = None,
                options: SolverOptions | None = None) -> CreepTrial:
    """Start the table from rest at ``speed`` [m/s] (nut at ``nut_speed``) and judge creep
    with :func:`judge_trial`."""
    result = simulate(system, ConstantSpeed(speed, nut_speed, ramp_time=0.1), duration,
                      options=options)
    return judge_trial(result.time, result["table_speed"], speed, thresholds)


def _grid(lo: float, hi: float, step: float) -> np.ndarray:
    n = int(math.floor((hi - lo) / step + 1e-9))
    return np.round(lo + step * np.arange(n + 1), 12)


def critical_speed_from_rest(
    system: DriveSystem, *, nut_speed: float = 0.0,
    speed_range: tuple[float, float] = (0.05 * MM_S, 3.0 * MM_S),
    coarse_step: float = 0.1 * MM_S, resolution: float = 0.01 * MM_S, duration: float = 12.0,
    thresholds: CreepThresholds | None = None, options: SolverOptions | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> CriticalSpeed:
    """Coarse scan plus bisection, every trial from rest (see module docstring)."""
    lo, hi = (_check_speed("speed_range[0]", speed_range[0]),
              _check_speed("speed_range[1]", speed_range[1]))
    if hi <= lo:
        raise ValueError(f"speed_range = {speed_range!r}: expected low < high [m/s]")
    _check_speed("resolution", resolution)
    _check_speed("coarse_step", coarse_step)
    trials: dict[float, CreepTrial] = {}

    def judge(v: float) -> bool:
        trials[v] = creep_trial(system, v, nut_speed=nut_speed, duration=duration,
                                thresholds=thresholds, options=options)
        if progress:
            progress(len(trials), 0)
        return trials[v].creeping

    status, crit = search_boundary(judge, lo, hi, coarse_step, resolution)
    ordered = tuple(trials[k] for k in sorted(trials))
    return CriticalSpeed(drive=system.drive, table_position=system.table_position,
                         nut_speed=nut_speed, start="rest", critical_speed=crit, status=status,
                         resolution=resolution, speed_range=(lo, hi), trials=ordered,
                         simulated_time=duration * len(trials))


def search_boundary(creeps: Callable[[float], bool], low: float, high: float,
                    coarse_step: float, resolution: float) -> tuple[str, float | None]:
    """Smooth end of the highest creep boundary in [low, high] [m/s].

    ``creeps(v)`` is evaluated on a coarse grid from ``low`` (so a creeping *band* is not
    missed), then bisection between the highest creeping grid speed and its smooth neighbour
    narrows the boundary to ``resolution``.  Each speed is evaluated at most once.
    Returns (status, critical speed) with status found / below-range / above-range.
    """
    cache: dict[float, bool] = {}

    def judge(v: float) -> bool:
        v = round(v, 12)
        if v not in cache:
            cache[v] = creeps(v)
        return cache[v]

    grid = _grid(low, high, coarse_step)
    flags = [judge(float(v)) for v in grid]
    creeping = [float(v) for v, f in zip(grid, flags, strict=True) if f]
    if not creeping:
        return "below-range", None
    if flags[-1]:
        return "above-range", None
    a = max(creeping)
    b = float(grid[int(np.searchsorted(grid, a)) + 1])
    while b - a > resolution * (1 + 1e-9):
        mid = round((a + b) / 2.0 / resolution) * resolution
        if mid <= a or mid >= b:
            mid = (a + b) / 2.0
        if judge(mid):
            a = mid
        else:
            b = mid
    return "found", b


def _staircase(speeds: np.ndarray, dwell: float, lead_in: float, nut_speed: float,
               interval: float = 1e-3) -> tuple[SampledSpeed, np.ndarray]:
    """Speed staircase: a ramp to speeds[0] over ``lead_in`` [s] … then ``dwell`` per step."""
    starts = lead_in + dwell * np.arange(len(speeds))
    t_end = starts[-1] + dwell
    t = np.arange(int(round(t_end / interval)) + 1) * interval
    idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(speeds) - 1)
    vt = speeds[idx].astype(float)
    ramp = min(0.1, lead_in)
    vt = np.where(t < ramp, speeds[0] * t / ramp, vt)
    vn = np.where(t < ramp, nut_speed * t / ramp, nut_speed)
    return SampledSpeed(time=t, table_speed=vt, nut_speed=vn), starts


def _run_staircase(system: DriveSystem, speeds: np.ndarray, dwell: float, lead_in: float,
                   nut_speed: float, thresholds: CreepThresholds | None,
                   options: SolverOptions | None) -> tuple[list[CreepTrial], float]:
    profile, starts = _staircase(speeds, dwell, lead_in, nut_speed)
    duration = float(profile.time[-1])
    result = simulate(system, profile, duration, options=options)
    return judge_staircase(result.time, result["table_speed"], speeds, starts, dwell,
                           thresholds), duration


def judge_staircase(time: np.ndarray, speed: np.ndarray, speeds: np.ndarray,
                    starts: np.ndarray, dwell: float,
                    thresholds: CreepThresholds | None = None) -> list[CreepTrial]:
    """Judge each step of a step-down trace on its second half (the step's own transient is
    over by then), stopping at the first creeping step."""
    out = []
    for v, t0 in zip(speeds, starts, strict=True):
        # end just before the next step starts (its first sample belongs to the next step)
        window = (t0 + 0.5 * dwell, t0 + dwell * (1.0 - 1e-6))
        m = creep_metrics(time, speed, float(v), thresholds=thresholds, window=window)
        out.append(CreepTrial.from_metrics(float(v), m))
        if out[-1].creeping:
            break
    return out


def critical_speed_stepdown(
    system: DriveSystem, *, nut_speed: float = 0.0, start_speed: float = 3.0 * MM_S,
    lowest_speed: float = 0.05 * MM_S, step: float = 0.01 * MM_S,
    coarse_step: float = 0.1 * MM_S, dwell: float = 4.0, lead_in: float = 6.0,
    thresholds: CreepThresholds | None = None, options: SolverOptions | None = None,
) -> CriticalSpeed:
    """The paper's protocol (Sect. 6) on a running table: step the command down until it crawls."""
    hi = _check_speed("start_speed", start_speed)
    lo = _check_speed("lowest_speed", lowest_speed)
    _check_speed("step", step)
    if hi <= lo:
        raise ValueError(f"start_speed = {hi!r}: expected above lowest_speed = {lo!r} [m/s]")
    coarse = _grid(lo, hi, coarse_step)[::-1]
    coarse_trials, t1 = _run_staircase(system, coarse, dwell, lead_in, nut_speed, thresholds,
                                       options)
    trials = list(coarse_trials)
    simulated = t1
    if not coarse_trials[-1].creeping:
        status, crit = "below-range", None
    elif len(coarse_trials) == 1:
        status, crit = "above-range", None
    else:
        last_smooth = coarse_trials[-2].speed
        fine = np.round(np.arange(last_smooth, coarse_trials[-1].speed - step / 2, -step), 12)
        approach = np.array([t.speed for t in coarse_trials[:-2]] + list(fine))
        fine_trials, t2 = _run_staircase(system, approach, dwell, lead_in, nut_speed,
                                         thresholds, options)
        simulated += t2
        trials += fine_trials
        if not fine_trials[-1].creeping:
            # the fine staircase stayed smooth down to the coarse creeping speed
            status, crit = "found", float(fine_trials[-1].speed)
        elif len(fine_trials) >= 2:
            status, crit = "found", float(fine_trials[-2].speed)
        else:
            status, crit = "above-range", None
    unique = {round(t.speed, 12): t for t in trials}
    ordered = tuple(unique[k] for k in sorted(unique))
    return CriticalSpeed(drive=system.drive, table_position=system.table_position,
                         nut_speed=nut_speed, start="running", critical_speed=crit,
                         status=status, resolution=step, speed_range=(lo, hi), trials=ordered,
                         simulated_time=simulated)
