"""One entry point: ``simulate(system, profile, duration, *, options) -> Result``."""

from __future__ import annotations

import math
import time as _time
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from . import budget
from .control import ConstantSpeed, Profile, SampledSpeed, SineSpeed
from .model.assemble import Model, assemble
from .model.disturbances import LoadProfile
from .model.mechanisms import drive_names, mechanism
from .parameters import DriveParameters, ParameterError
from .result import Result, build_dataset
from .solvers import dopri5

DRIVES = drive_names()


@dataclass(frozen=True)
class DriveSystem:
    """A drive to simulate: parameters, topology, where the table starts, and how.

    ``drive``: a registered topology — ``"cdfs"``, ``"ddfs"`` (Wang2021's ball-screw drives)
    or ``"linear-motor"`` (a direct-drive table; needs ``parameters.linear_motor``).
    ``table_position`` [m] is the
    distance a of the nut from the motor-side screw support (Wang2021 Table 3: 0.2 … 0.6 m;
    mid-screw 0.4 m).  For the CDFS the hollow motor is held: ``nut_hold = "locked"`` freezes
    the nut's states (the default), ``"servo"`` keeps the hollow motor's loop at zero command.
    ``initial_state`` sets states by name (SI; e.g. ``{"table_speed": 5e-3}``), all others
    start at 0; ``load`` adds a load-force record on the table (:class:`LoadProfile`).
    """

    parameters: DriveParameters
    drive: str = "ddfs"
    table_position: float = 0.4
    nut_hold: str = "locked"
    initial_state: Mapping[str, float] = field(default_factory=dict)
    load: LoadProfile | None = None

    def __post_init__(self) -> None:
        if self.nut_hold not in ("locked", "servo"):
            raise ParameterError("nut_hold", self.nut_hold, "expected locked or servo")
        mechanism(self.drive).check(self.parameters, self.drive, self.table_position)
        for name, value in self.initial_state.items():
            if not (isinstance(value, int | float) and math.isfinite(value)):
                raise ParameterError(f"initial_state.{name}", value, "expected a finite number "
                                     "in the state's SI unit")

    def model(self, profile: Profile) -> Model:
        """The assembled model of this drive following ``profile``."""
        return assemble(self.parameters, self.drive, self.table_position, self.nut_hold,
                        profile, self.load)

    def initial_vector(self, model: Model) -> np.ndarray:
        y0 = np.zeros(len(model.state_names))
        for name, value in self.initial_state.items():
            y0[model.index(name)] = float(value)
        return y0


@dataclass(frozen=True)
class SolverOptions:
    """Integrator settings, echoed in the result.

    ``method``: ``"dopri5"`` (adaptive) or ``"dopri5-fixed"`` (fixed step ``fixed_step``).
    ``output_interval`` [s] is the spacing of the recorded samples; it is also the breakpoint
    spacing for continuous control.  ``position_tolerance`` [m] and ``speed_tolerance`` [m/s]
    are absolute error targets (angles scaled by H), combined with ``rtol`` on speeds.
    """

    method: str = "dopri5"
    rtol: float = 1e-6
    position_tolerance: float = 1e-10
    speed_tolerance: float = 1e-8
    current_tolerance: float = 1e-6
    output_interval: float = 1e-3
    max_step: float = 1e-3
    fixed_step: float = 1e-5
    max_steps: int = 50_000_000

    def __post_init__(self) -> None:
        if self.method not in ("dopri5", "dopri5-fixed"):
            raise ParameterError("options.method", self.method, "expected dopri5 or dopri5-fixed")
        for name in ("rtol", "position_tolerance", "speed_tolerance", "current_tolerance",
                     "output_interval", "max_step", "fixed_step"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ParameterError(f"options.{name}", v, "expected a finite value > 0")


class SimulationError(RuntimeError):
    """The integrator could not finish; the message says why and where."""


@dataclass(frozen=True)
class Sampling:
    """The breakpoint grid: fastest controller period ``base`` [s], loop periods in units of
    it (0 = continuous), and the output stride."""

    base: float
    n_pos: int
    n_vel: int
    n_cur: int
    out_every: int


def sampling(params: DriveParameters, output_interval: float) -> Sampling:
    c = params.controller
    periods = [c.position_period, c.velocity_period, c.current_period]
    nonzero = [p for p in periods if p > 0]
    if (c.encoder_counts > 0 or c.grating_resolution > 0) and not (
            c.position_period > 0 and c.velocity_period > 0):
        raise ParameterError("controller.encoder_counts", c.encoder_counts,
                             "quantisation needs sampled position and velocity loops "
                             "(set controller.position_period and velocity_period > 0 [s])")
    base = min(nonzero) if nonzero else output_interval
    n = [int(round(p / base)) if p > 0 else 0 for p in periods]
    out_every = max(1, int(round(output_interval / base)))
    if abs(out_every * base - output_interval) > 1e-9 * output_interval:
        raise ParameterError("options.output_interval", output_interval,
                             f"must be a multiple of the fastest controller period {base:g} [s]")
    return Sampling(base, n[0], n[1], n[2], out_every)


def _check_budget(system: DriveSystem, profile: Profile, model: Model, grid: Sampling,
                  options: SolverOptions, y0: np.ndarray, t_end: float,
                  adaptive: int, atol: np.ndarray, rel: np.ndarray, h_init: float,
                  h_max: float) -> None:
    """Refuse, before integrating, a run whose output would not fit in memory or whose
    steps (projected from a short probe) exceed ``max_steps`` (feeddrive.budget)."""
    budget.check_output_memory(t_end, options.output_interval)
    t_probe = budget.probe_time(t_end, grid.base) if adaptive else 0.0
    if not t_probe:
        return
    allowed = int(options.max_steps * t_probe / t_end) + 1000
    _, _, _, stats, _ = dopri5.integrate(
        model, y0.copy(), t_probe, grid.out_every, grid.base, grid.n_pos, grid.n_vel,
        grid.n_cur, options.rtol, atol, rel, h_init, h_max, adaptive, allowed)
    if int(stats[0]) in (dopri5.STATUS_OK, dopri5.STATUS_MAX_STEPS) and stats[4] > 0:
        problem = budget.step_rate_problem(
            steps=int(stats[1]), probe_time=float(stats[4]), duration=t_end,
            max_steps=options.max_steps, params=system.parameters, drive=system.drive,
            speed=budget.profile_speed(profile))
        if problem:
            raise SimulationError(problem)


def simulate(system: DriveSystem, profile: Profile, duration: float, *,
             options: SolverOptions | None = None) -> Result:
    """Simulate ``system`` following ``profile`` for ``duration`` [s] from rest.

    Returns a :class:`Result` (xarray Dataset with named signals and units).  Raises
    :class:`SimulationError` if the integrator fails (never returns NaN silently).
    """
    options = options or SolverOptions()
    if not (isinstance(duration, int | float) and math.isfinite(duration) and duration > 0):
        raise ParameterError("duration", duration, "expected a finite time > 0 [s]")
    if not isinstance(profile, ConstantSpeed | SineSpeed | SampledSpeed):
        raise ParameterError("profile", type(profile).__name__,
                             "expected ConstantSpeed, SineSpeed or SampledSpeed")
    model = system.model(profile)
    grid = sampling(system.parameters, options.output_interval)
    n_break = int(round(duration / grid.base))
    t_end = n_break * grid.base
    atol, rel = model.tolerances(options.position_tolerance, options.speed_tolerance,
                                 options.current_tolerance)
    adaptive = 1 if options.method == "dopri5" else 0
    h_init = 1e-6 if adaptive else options.fixed_step
    h_max = min(options.max_step, grid.base) if adaptive else options.fixed_step
    y0 = system.initial_vector(model)
    _check_budget(system, profile, model, grid, options, y0, t_end, adaptive, atol,
                  rel, h_init, h_max)
    started = _time.perf_counter()
    t, y, aux, stats, _ = dopri5.integrate(
        model, y0, t_end, grid.out_every, grid.base, grid.n_pos, grid.n_vel, grid.n_cur,
        options.rtol, atol, rel, h_init, h_max, adaptive, options.max_steps)
    wall = _time.perf_counter() - started
    status = int(stats[0])
    if status != dopri5.STATUS_OK:
        raise SimulationError(
            f"integration stopped at t = {stats[4]:.6g} s of {t_end:g} s: "
            f"{dopri5.STATUS_MESSAGES[status]} (steps {int(stats[1])}, rejected "
            f"{int(stats[2])}); raise max_steps (--max-steps) or check the parameters")
    solver_stats = {
        "method": options.method, "rtol": options.rtol,
        "position_tolerance": options.position_tolerance,
        "speed_tolerance": options.speed_tolerance,
        "steps": int(stats[1]), "rejected_steps": int(stats[2]),
        "rhs_evaluations": int(stats[3]), "wall_time_s": wall,
        "breakpoint_interval_s": grid.base,
    }
    dataset = build_dataset(t, y, aux, model, system, profile, solver_stats)
    return Result(dataset)
