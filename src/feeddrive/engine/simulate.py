"""One entry point: ``simulate(system, profile, duration, *, options) -> Result``."""

from __future__ import annotations

import math
import os
import threading
import time as _time
import weakref
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from numbers import Real
from pathlib import Path
from typing import Any

import numpy as np

from .._kept import Kept
from ..model.assemble import Model, assemble
from ..model.disturbances import LoadProfile
from ..model.mechanisms import Mechanism, drive_names, mechanism
from ..model.mechanisms.base import DEFAULT_TABLE_POSITION, check_nut_hold, check_table_position
from ..model.reference import (
    PROFILE_PARAMS,
    TABLE_COLUMNS,
    TABLE_OFFSET,
    ConstantSpeed,
    Profile,
    SampledSpeed,
    SineSpeed,
)
from ..model.replay import Replay
from ..parameters import DriveParameters, ParameterError
from ..parameters.validation import check_callback, check_flag, is_real
from ..solvers import builds, dopri5, switching
from . import budget
from .error_estimate import (
    SHADOW_FACTOR,
    embedded_entry,
    estimate_kind,
    signal_errors,
    summary_entry,
    tightened,
)
from .options import DENSE_MODES as _DENSE_MODES
from .options import METHODS as METHODS  # re-exported: the engine's public names
from .options import REVERSAL_METHODS as _REVERSAL_METHODS
from .options import RunScales, check_given
from .options import SolverOptions as SolverOptions
from .options import current as current_options
from .result import Result, Run

DRIVES = drive_names()


@dataclass(frozen=True)
class DriveSystem:
    """A drive to simulate: parameters, topology, where the table starts, and how.

    Parameters
    ----------
    parameters : DriveParameters
        The parameter set (SI).
    drive : str, default "ddfs"
        A registered topology — ``"cdfs"``, ``"ddfs"`` (Wang2021's ball-screw drives) or
        ``"linear-motor"`` (a direct-drive table; needs ``parameters.linear_motor``).
    table_position : float, default 0.4
        Distance a of the nut from the motor-side screw support [m] (Wang2021 Table 3:
        0.2 … 0.6 m; mid-screw 0.4 m).  Only a ball screw's model depends on it: another
        value is refused for a drive whose model does not (``Mechanism.uses_table_position``;
        the linear motor, the rack and pinion).
    nut_hold : {"locked", "servo"}, default "locked"
        For the CDFS the hollow motor is held: ``"locked"`` freezes the nut's states,
        ``"servo"`` keeps the hollow motor's loop at zero command.  A drive that holds no nut
        (``Mechanism.held_part``: the DDFS drives its own, the linear motor has none) refuses
        ``"servo"``.
    initial_state : mapping of str to float, default {}
        States set by name, in each state's SI unit [unit of the state] (e.g.
        ``{"table_speed": 5e-3}``); all others start at 0.
    load : LoadProfile or None, default None
        A load-force record on the table.
    """

    parameters: DriveParameters
    drive: str = "ddfs"
    table_position: float = DEFAULT_TABLE_POSITION
    nut_hold: str = "locked"
    initial_state: Mapping[str, float] = field(default_factory=dict)
    load: LoadProfile | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.parameters, DriveParameters):
            raise ParameterError("parameters", self.parameters, "expected a DriveParameters "
                                 "(feeddrive.preset(name) or feeddrive.load(path))")
        if isinstance(self.table_position, bool) or not isinstance(self.table_position, Real):
            raise ParameterError("table_position", self.table_position, "expected a number "
                                 "of metres between the screw's supports")
        if not isinstance(self.initial_state, Mapping):
            raise ParameterError("initial_state", self.initial_state, "expected a mapping of "
                                 "state names to numbers in each state's SI unit ({} for none)")
        if self.nut_hold not in ("locked", "servo"):
            raise ParameterError("nut_hold", self.nut_hold, "expected locked or servo")
        # a dict or a number failed at simulate with "'dict' object has no attribute
        # 'encode'" (an outside check, 2026-12-07)
        if self.load is not None and not isinstance(self.load, LoadProfile):
            raise ParameterError("load", type(self.load).__name__, "expected a LoadProfile, "
                                 "e.g. LoadProfile(time=…, force=…) [s, N] (a constant load "
                                 "is the parameter disturbances.load_force [N])")
        mechanism(self.drive).check(self.parameters, self.drive, self.table_position)
        # a start position on a drive whose model does not read it (the linear motor, the rack
        # and pinion) was dropped without a word (an earlier sweep, session 30); the default
        # cannot be told from none given and is taken on every drive
        check_table_position(self.drive, self.table_position)
        # "servo" on a drive that holds no nut (the DDFS drives its own, the linear motor
        # has none) was dropped without a word
        check_nut_hold(self.drive, self.nut_hold)
        for name, value in self.initial_state.items():
            if not (is_real(value) and math.isfinite(value)):
                raise ParameterError(f"initial_state.{name}", value, "expected a finite number "
                                     "in the state's SI unit")

    def __repr__(self) -> str:
        more = "".join(f", {k}={v!r}" for k, v in (("initial_state", dict(self.initial_state)),
                                                   ("load", self.load)) if v)
        return (f"DriveSystem(parameters=<DriveParameters {self.parameters.name!r}>, "
                f"drive={self.drive!r}, "
                f"table_position={self.table_position!r}, nut_hold={self.nut_hold!r}{more})")

    def topology(self) -> Mechanism:
        """The drive's topology, which declares its structure (axes, sites, what it holds).

        Returns
        -------
        Mechanism
            The registered mechanism of :attr:`drive`, built for this system.
        """
        return mechanism(self.drive)(self.parameters, self.drive, self.table_position,
                                     self.nut_hold)

    def model(self, profile: Profile) -> Model:
        """The assembled model of this drive following ``profile``.

        Parameters
        ----------
        profile : ConstantSpeed, SineSpeed or SampledSpeed
            The reference the loops follow.

        Returns
        -------
        Model
            Names, units, packed parameters and the compiled module (cached per structure).
        """
        return assemble(self.parameters, self.drive, self.table_position, self.nut_hold,
                        profile, self.load)

    def initial_vector(self, model: Model) -> np.ndarray:
        """The initial state vector of ``model``: zeros except the states named in
        ``initial_state``.

        Parameters
        ----------
        model : Model
            The assembled model (its state order).

        Returns
        -------
        numpy.ndarray
            One value per state, each in that state's SI unit [unit of the state].
        """
        y0 = np.zeros(len(model.state_names))
        for name, value in self.initial_state.items():
            y0[model.index(name)] = float(value)
        return y0


class SimulationError(RuntimeError):
    """The integrator could not finish; the message says why and where."""


@dataclass(frozen=True)
class Sampling:
    """The breakpoint grid of a run and its sample schedule: breakpoint unit ``base`` [s] (the
    fastest sample period), per clock of the model (:attr:`Model.clocks
    <feeddrive.model.assemble.Model.clocks>`: the loops and every sampled part) its period in
    breakpoints (0 = continuous), and the output stride in breakpoints.

    Parameters
    ----------
    base : float
        The breakpoint unit, the fastest sample period [s].
    clocks : tuple of str
        The model's clocks, by their period's parameter path.
    steps : tuple of int
        Each clock's period in breakpoints; 0 = continuous.
    out_every : int
        The output stride in breakpoints.
    """

    base: float
    clocks: tuple[str, ...]
    steps: tuple[int, ...]
    out_every: int

    @property
    def schedule(self) -> np.ndarray:
        """``steps`` as the solvers take it (int64; one entry at least)."""
        return np.array(self.steps or (0,), dtype=np.int64)

    @property
    def sampled(self) -> bool:
        """Whether any part is sampled (the run has instants where outputs jump)."""
        return any(n > 0 for n in self.steps)

    def step(self, clock: str) -> int:
        """The period of ``clock`` (e.g. ``"controller.velocity_period"``) in breakpoints.

        Parameters
        ----------
        clock : str
            The clock's period path.

        Returns
        -------
        int
            Breakpoints per period; 0 = continuous.
        """
        return self.steps[self.clocks.index(clock)]

    def parameters(self, model: Model, P: np.ndarray | None = None) -> np.ndarray:
        """``P`` (default: the model's) with each sampled clock's period slot set to the
        spacing of its instants on the grid, steps·base [s]: what a sampled part integrates
        over is the time between its instants (equal to the declared period within the
        1e-9 the grid allows).

        Parameters
        ----------
        model : Model
            The assembled model (its clocks' period slots).
        P : numpy.ndarray, optional
            The parameter vector to start from; the model's by default [SI, per slot].

        Returns
        -------
        numpy.ndarray
            A copy with the sampled periods on the grid [SI, per slot].
        """
        out = (model.P if P is None else P).copy()
        for (_, slot), n in zip(model.clocks, self.steps, strict=True):
            if n > 0:
                out[slot] = n * self.base
        return out


def sampling(params: DriveParameters, output_interval: float,
             model: Model | None = None, *, P: np.ndarray | None = None) -> Sampling:
    """The breakpoint grid and sample schedule of a run of ``params`` (``model``: its assembled
    model, whose declared clocks are the schedule; None: the three loops' and the sections'
    own schedules read from ``params``; ``P``: the parameter vector the periods are read from,
    default the model's).

    Every period must be a multiple of the fastest one (each instant is an exact breakpoint
    count); the output interval a multiple of the fastest period.  A sampled part may run
    beside continuous loops: the solvers stop at its instants only (its clock is the
    schedule), re-evaluating the derivative there.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    output_interval : float
        Interval of the recorded output [s].
    model : Model, optional
        The assembled model, whose clocks are the schedule.
    P : numpy.ndarray, optional
        The parameter vector the periods are read from [SI, per slot].

    Returns
    -------
    Sampling
        The grid and schedule.

    Raises
    ------
    ParameterError
        For a period that is not a multiple of the fastest, an output interval that is not,
        or quantised feedback with continuous position or velocity loops.
    """
    c = params.controller
    loops = [(f"controller.{k}", float(getattr(c, k))) for k in (
        "position_period", "velocity_period", "current_period")]
    # sampled parts (model/parts/) with schedules of their own: (field, period [s]) pairs
    parts = [(f"{name}.{field}", float(period)) for name, section in params.sections
             for field, period in getattr(section, "schedule", lambda: ())()]
    clocks = list(model.periods(P).items()) if model is not None else loops + parts
    if (c.encoder_counts > 0 or c.grating_resolution > 0) and not (
            c.position_period > 0 and c.velocity_period > 0):
        raise ParameterError("controller.encoder_counts", c.encoder_counts,
                             "quantisation needs sampled position and velocity loops "
                             "(set controller.position_period and velocity_period > 0 [s])")
    nonzero = [p for _, p in clocks if p > 0]
    base = min(nonzero) if nonzero else output_interval
    for slot, period in clocks:  # every schedule lands on the breakpoint grid
        if period > 0 and abs(period / base - round(period / base)) > 1e-9 * period / base:
            raise ParameterError(slot, period, f"expected a multiple of the fastest sample "
                                 f"period {base:g} [s] (each schedule is an exact event "
                                 "time on one breakpoint grid)")
    steps = tuple(int(round(p / base)) if p > 0 else 0 for _, p in clocks)
    out_every = max(1, int(round(output_interval / base)))
    if abs(out_every * base - output_interval) > 1e-9 * output_interval:
        raise ParameterError("options.output_interval", output_interval,
                             f"must be a multiple of the fastest controller period {base:g} [s]")
    return Sampling(base, tuple(name for name, _ in clocks), steps, out_every)


def _check_step_rate(system: DriveSystem, profile: Profile, model: Model, grid: Sampling,
                     options: SolverOptions, y0: np.ndarray, t_end: float,
                     adaptive: int, rtol: float, atol: np.ndarray, rel: np.ndarray,
                     h_init: float, h_max: float, bound: np.ndarray,
                     switch_rows: np.ndarray | None) -> None:
    """Refuse, before integrating with ``dopri5``, a run whose steps (projected from a short
    probe) exceed ``max_steps`` (feeddrive.engine.budget)."""
    t_probe = budget.probe_time(t_end, grid.base) if adaptive else 0.0
    if not t_probe:
        return
    allowed = int(options.max_steps * t_probe / t_end) + 1000
    _, _, _, stats, _ = dopri5.integrate(
        model, y0.copy(), t_probe, grid.out_every, grid.base, grid.schedule, rtol,
        atol, rel, h_init, h_max, adaptive, allowed, stability_share=options.stability_share,
        bound=bound, P=grid.parameters(model), switch_rows=switch_rows)
    if int(stats[0]) in (dopri5.STATUS_OK, dopri5.STATUS_MAX_STEPS) and stats[4] > 0:
        problem = budget.step_rate_problem(
            steps=int(stats[1]), probe_time=float(stats[4]), duration=t_end,
            max_steps=options.max_steps, params=system.parameters, drive=system.drive,
            speed=budget.profile_speed(profile),
            max_steps_hint=budget.setting_hint(options, "max_steps", option=MAX_STEPS_OPTION))
        if problem:
            raise SimulationError(problem)


# A run stops early as diverged when a speed state exceeds this multiple of the reference
# speed: the largest commanded table plus nut speed, the largest initial speed or 1 mm/s,
# whichever is largest.  5× the "unstable" verdict's 20× (feeddrive.analysis.creep_window
# CreepThresholds.max_speed_ratio): a run stopped here is "unstable" by that verdict too.
DIVERGENCE_SPEED_RATIO = 100.0
DIVERGENCE_SPEED_FLOOR = 1e-3  # [m/s]


def _peak(value: Any) -> float:
    if value is None:
        return 0.0
    return float(np.max(np.abs(np.asarray(value, dtype=float)), initial=0.0))


def command_speed(system: DriveSystem, profile: Profile, *, table: bool = False) -> float:
    """The largest speed the run is commanded to or starts with: the table's, nut's and sine
    amplitudes' peaks summed (a DDFS's screw runs at table plus nut speed), or the largest
    initial speed state, whichever is larger.

    Parameters
    ----------
    system : DriveSystem
        The drive (its initial state).
    profile : Profile
        The reference profile (its speeds).
    table : bool, default False
        The table's own: its command's and amplitude's peaks and its initial speed.

    Returns
    -------
    float
        The speed [m/s]; 0 for a run at rest.
    """
    names = ("table_speed", "table_amplitude") if table else (
        "table_speed", "nut_speed", "table_amplitude", "nut_amplitude")
    command = sum(_peak(getattr(profile, name, None)) for name in names)
    initial = max((abs(float(v)) for k, v in system.initial_state.items()
                   if ("table_speed" in k if table else "speed" in k)), default=0.0)
    return max(command, initial)


def run_scales(system: DriveSystem, profile: Profile, model: Model) -> RunScales:
    """The speed and current scales the run's default tolerances follow
    (:mod:`feeddrive.engine.options`).

    Parameters
    ----------
    system : DriveSystem
        The drive (its initial state and controller's current limit).
    profile : Profile
        The reference profile (its speeds).
    model : Model
        The assembled model (unused now; the scales of a machine's axes will read it).

    Returns
    -------
    RunScales
        Speed scales V (motors) and V_t (table) from :func:`command_speed`, each at least
        ``SPEED_SCALE_FLOOR`` [m/s]; current scale: the current limit when below
        ``NO_CURRENT_LIMIT``, else 1 A [A].
    """
    from . import options as opt

    limit = float(system.parameters.controller.current_limit)
    current = limit if 0.0 < limit < opt.NO_CURRENT_LIMIT else 1.0
    return RunScales(
        speed=max(command_speed(system, profile), opt.SPEED_SCALE_FLOOR),
        table_speed=max(command_speed(system, profile, table=True), opt.SPEED_SCALE_FLOOR),
        current=current)


def divergence_speed(system: DriveSystem, profile: Profile) -> float:
    """The linear speed beyond which a run stops as diverged: :data:`DIVERGENCE_SPEED_RATIO`
    × the reference speed (:func:`command_speed`, at least :data:`DIVERGENCE_SPEED_FLOOR`).

    Parameters
    ----------
    system : DriveSystem
        The drive (its initial state).
    profile : Profile
        The reference profile (its speeds; a replay's ``speed_scale``).

    Returns
    -------
    float
        The bound [m/s].
    """
    return DIVERGENCE_SPEED_RATIO * max(command_speed(system, profile), DIVERGENCE_SPEED_FLOOR)


def replay_bound_problem(profile: Profile, at: float, bound: float) -> str:
    """Why a replay's run that reached its divergence bound is an error, not a verdict: a
    replay without ``speed_scale`` commands no speed, so its bound is the floor's
    (:data:`DIVERGENCE_SPEED_FLOOR`), not a speed the run was judged against.  "" for any
    other run (a loop that ran 100× beyond its command diverged: the verdict "unstable").

    Parameters
    ----------
    profile : Profile
        The run's profile.
    at : float
        When a speed left the bound [s].
    bound : float
        The bound [m/s].

    Returns
    -------
    str
        The message, or "".
    """
    if not isinstance(profile, Replay) or profile.speed_scale > 0.0:
        return ""
    name = type(profile).__name__
    return (f"a speed reached {bound:g} m/s at t = {at:.6g} s, the bound of a replay without "
            f"speed_scale ({DIVERGENCE_SPEED_RATIO:g} × the {1e3 * DIVERGENCE_SPEED_FLOOR:g}-mm/s "
            f"floor): a replay commands no speed, so give {name}(..., speed_scale=...) the "
            "largest table speed the run is expected to reach [m/s] (it also scales the "
            "default tolerances)")


def divergence_bounds(system: DriveSystem, profile: Profile, model: Model) -> np.ndarray:
    """The largest |state| per state before a run stops as diverged.

    Speed states (linear and, through the lead, rotary) are bounded at
    :data:`DIVERGENCE_SPEED_RATIO` × the reference speed (or the initial speed, at least
    :data:`DIVERGENCE_SPEED_FLOOR`); the other states are unbounded, since a diverging loop shows
    in its speeds first.

    Parameters
    ----------
    system : DriveSystem
        The drive (its initial state).
    profile : Profile
        The reference profile (its speeds).
    model : Model
        The assembled model (the states' tolerance kinds and scales).

    Returns
    -------
    numpy.ndarray
        Bound per state [SI, per state]; ``inf`` where unbounded.
    """
    limit = divergence_speed(system, profile)
    bound = np.full(len(model.states), np.inf)
    for i, (kind, scale) in enumerate(zip(model.tolerance_kinds, model.tolerance_scales,
                                          strict=True)):
        if kind == "speed":
            bound[i] = limit
        elif kind == "rotary_speed":
            bound[i] = limit / scale
    return bound


def switching_rows(model: Model, P: np.ndarray) -> np.ndarray:
    """The friction sites' sliding speeds as switching surfaces W·y of the dense-output
    integrator: their zero crossings, where a law with a direction branch has a kink, become
    step ends (:mod:`feeddrive.solvers.events`).

    A site whose law declares ``kink_at_zero_speed`` (LuGre, Dahl: ż = v − σ0·|v|·z/…; GMS:
    a sticking element's dδ/dt = v) gives
    one row: the rate of its first state with every state zero but one is the sliding speed
    that one state makes, so n + 1 evaluations of the right-hand side read off the
    coefficients.  A row is kept only if the speed is linear in the state (checked at a
    second, mixed state to 1e-9) and not zero (a site that does not act, such as the held nut
    of a CDFS).

    Parameters
    ----------
    model : Model
        The assembled model.
    P : numpy.ndarray
        Its parameter vector [SI, per slot].

    Returns
    -------
    numpy.ndarray
        (m, n) rows, one per switching site [state units → m/s]; (0, n) when none.
    """
    from ..model.friction import friction_law

    n = len(model.states)
    firsts = []
    for site, law_name in model.sites:
        law = friction_law(law_name)
        if law.kink_at_zero_speed and law.first_state:
            firsts.append(model.index(f"{site}_{law.first_state}"))
    if not firsts:
        return np.zeros((0, n))
    rates = builds.compiled(model, "_ev_rates")
    held, dy, aux = np.zeros(model.n_held), np.empty(n), np.empty(len(model.aux))
    P = np.ascontiguousarray(P, dtype=float)
    T = np.ascontiguousarray(model.T, dtype=float)

    def speeds(y: np.ndarray) -> np.ndarray:
        rates(0.0, np.ascontiguousarray(y, dtype=float), held, P, T, dy, aux)
        return dy[firsts].copy()

    scale = np.array(model.tolerance_scales, dtype=float)
    scale = np.where(np.isfinite(scale) & (scale > 0.0), scale, 1.0)
    mixed = np.zeros(n)
    mixed[:] = scale * np.linspace(0.3, 1.7, n)
    mixed[firsts] = 0.0
    base = speeds(np.zeros(n))
    probe = speeds(mixed) - base
    # the rows of this structure and these numbers but the profile's (a search's trials): the
    # sliding speeds are those of the states, so the rows are the same; taken again when
    # the two evaluations that check them (at rest and at the mixed state) say the same
    key = _rows_key(model, P, T)
    kept = _SWITCH_ROWS.get(key)  # under its lock: the explorer's jobs run in threads
    if kept is not None and np.array_equal(kept[1], base) and np.array_equal(kept[2], probe):
        return kept[0].copy()
    W = np.zeros((len(firsts), n))
    for j in range(n):
        y = np.zeros(n)
        y[j] = scale[j]
        W[:, j] = (speeds(y) - base) / scale[j]
    for k in firsts:  # a friction state is not a speed
        W[:, k] = 0.0
    keep = (np.abs(W).max(axis=1) > 0.0) & (np.abs(base) == 0.0) & (
        np.abs(probe - W @ mixed) <= 1e-9 * np.maximum(np.abs(W) @ np.abs(mixed), 1e-300))
    rows = np.ascontiguousarray(W[keep])
    _SWITCH_ROWS.put(key, (rows.copy(), base, probe))
    return rows


#: switching rows already found (:func:`switching_rows`), by :func:`_rows_key`: 64 at most
_SWITCH_ROWS = Kept(64)


def _rows_key(model: Model, P: np.ndarray, T: np.ndarray) -> tuple[Any, ...]:
    """The generated module (the structure), and a digest of ``P`` without the profile's
    block and of ``T`` without the profile's table — a digest, not their bytes: ``T`` holds a
    record's samples (an 8-kHz, 100-s record: 26 MB), and 64 keys of a fit's parameter points
    held 64 copies of it.  The profile's numbers and table are left out alike: the sliding
    speeds are the states', so a fit's records at one parameter point share their rows (each
    taken again where the two evaluations that check them differ)."""
    import hashlib

    T = np.ascontiguousarray(T)
    try:
        o = model.parameter_names.index("profile[0]")
    except ValueError:
        o, to, end = P.size, T.size, T.size
    else:
        to = int(P[o + TABLE_OFFSET])
        end = to + 4 * int(P[o + TABLE_COLUMNS])
    masked = P.copy()
    masked[o:o + len(PROFILE_PARAMS)] = 0.0
    digest = hashlib.blake2b(masked.tobytes(), digest_size=32)
    digest.update(T[:to].tobytes())
    digest.update(T[end:].tobytes())
    return (model.module.__name__, P.size, T.size, digest.digest())


def profile_breakpoints(profile: Profile, t_end: float, base: float, *,
                        every_sample: bool = False) -> np.ndarray:
    """Instants where the command has a kink, declared to the dense-output integrator as step
    ends.

    The end of a constant-speed start ramp; the samples of a sampled profile where its speed
    has a kink (interpolated: the slope on the two sides of the sample differs; held: the
    value changes) or where its table ends, when its grid is no finer than ``base`` — a finer
    grid is left to the error control, as the fixed-breakpoint integrator does.  A sample
    inside a stretch of one speed or one slope (a staircase's dwell, a ramp whose differences
    are equal) is no kink: the command is smooth there, and a step may pass it.

    Parameters
    ----------
    profile : Profile
        The reference profile.
    t_end : float
        End of the run [s].
    base : float
        The breakpoint unit (:class:`Sampling`) [s].
    every_sample : bool, default False
        Every sample of a sampled profile, kink or not (``SolverOptions.sample_steps``).

    Returns
    -------
    numpy.ndarray
        The instants in (0, t_end) [s]; empty when there are none.
    """
    if isinstance(profile, Replay):  # an open-loop replay: its sample instants
        return profile.breakpoints(t_end)
    if isinstance(profile, ConstantSpeed):
        stops = [profile.ramp_time] if 0.0 < profile.ramp_time < t_end else []
        return np.array(stops, dtype=float)
    if isinstance(profile, SampledSpeed):
        times = np.asarray(profile.time, dtype=float)
        if times.size > 1 and float(np.mean(np.diff(times))) >= base * (1 - 1e-9):
            inside = (times > 0.0) & (times < t_end)
            return times[inside if every_sample else inside & _sample_kinks(profile)]
    return np.zeros(0)


def check_profile_span(profile: Profile, duration: float, output_interval: float) -> None:
    """Refuse a run that goes on past the end of a tabulated profile still commanding a speed.

    Past its last sample the reference (:func:`feeddrive.model.reference.reference_kernel`)
    holds the speed it ends with but not the position: a profile that ends at rest holds the
    table there (a machine run given a longer duration settles), one that ends moving commands
    a speed and a standing position at once, the position loop pulling the table back (a
    0.01-s table of 1 mm/s run for 1 s was judged "creeping" without a word: an outside
    check, 2026-12-07).  A run may pass the last sample by one sample interval of the profile
    or one output interval, whichever is longer: the output instant after its end (a fit
    simulates its record to the sample after the last).

    Parameters
    ----------
    profile : Profile
        The reference profile; only a :class:`SampledSpeed` (and a machine's axes) is checked.
    duration : float
        The run's end, a finite number > 0 (:meth:`Simulation.run` checks it first) [s].
    output_interval : float
        The run's output interval [s].

    Raises
    ------
    ParameterError
        Naming ``duration``, the profile's end and the speed it ends with.
    """
    if not isinstance(profile, SampledSpeed):
        return
    t = np.asarray(profile.time, dtype=float)
    end = float(t[-1])
    step = (end - float(t[0])) / (t.size - 1)
    limit = end + max(step, float(output_interval))
    if duration <= limit * (1.0 + 1e-9):
        return
    parts = [("", profile), *((f"axis {name}'s ", p) for name, p in getattr(profile, "axes", ())
                              if isinstance(p, SampledSpeed))]
    for where, part in parts:
        for which, speeds in (("table", np.asarray(part.table_speed, dtype=float)),
                              ("nut", np.asarray(_nut(part), dtype=float))):
            held = float(speeds[-2] if part.hold else speeds[-1])  # what the kernel holds
            if held != 0.0:
                raise ParameterError(
                    "duration", duration,
                    f"expected ≤ {limit:.6g} [s]: the profile ends at {end:.6g} s still "
                    f"commanding {where}{which} speed {1e3 * held:.6g} mm/s, and past its "
                    "last sample the reference holds that speed but not the position (the "
                    "position loop pulls the table back); lengthen the profile, end it at "
                    "rest, or shorten the run")


def _sample_kinks(profile: SampledSpeed) -> np.ndarray:
    """Per sample of ``profile``, whether the command is not smooth there: a change of the
    slope (interpolated) or of the value (held) of the table or nut speed, compared exactly
    (a rounding difference only adds a step end), and the table's last sample."""
    kink = np.zeros(len(profile.time), dtype=bool)
    kink[-1] = True
    for speed in (profile.table_speed, _nut(profile)):
        step = np.diff(np.asarray(speed, dtype=float))
        if profile.hold:
            kink[1:] |= step != 0.0
        else:
            kink[1:-1] |= step[1:] != step[:-1]
    return kink


class SimulationInterrupted(KeyboardInterrupt):
    """Ctrl-C during a long run: the integration stopped between two chunks.

    What was computed up to ``t_reached`` is in ``result`` (and written to ``output``).

    Parameters
    ----------
    t_reached : float
        Simulated time reached [s].
    result : Result or None
        The run up to there; None when nothing was recorded yet.
    output : str or None
        The file the samples so far were written to, if any.
    """

    def __init__(self, t_reached: float, result: Result | None, output: str | None) -> None:
        self.t_reached = t_reached
        self.result = result
        self.output = output
        where = f"; {output} holds 0 … {t_reached:g} s" if output else ""
        super().__init__(f"simulation interrupted at t = {t_reached:g} s{where}")


# A run is integrated in chunks of about this much wall time [s] once it is longer than the
# first chunk: a stop request acts between chunks (Ctrl-C within a step where _advance waits
# in a helper thread), progress is reported after each, and with an
# output file each chunk is written and dropped (memory does not grow with the duration).
CHUNK_WALL_TIME = 0.25
FIRST_CHUNK = 2.0  # [s] simulated
MAX_CHUNK_SAMPLES = 20_000
KEEP_STREAMED = 60.0  # [s] of a streamed run kept in memory (its end) for the summary


def run_options(system: DriveSystem | DriveParameters,
                options: SolverOptions | None = None) -> SolverOptions:
    """The options a run of ``system`` takes: ``options`` (None: those in force,
    :func:`feeddrive.engine.options.current`) over the integrator settings its parameter set
    carries (:attr:`feeddrive.DriveParameters.solver`, the ``[solver]`` table of
    the file it was loaded from), over the defaults.  Every run takes its options here
    (:class:`Simulation`), so a creep search, a fit, a prediction, a sensitivity study or a
    sweep of a set honours its table as :func:`simulate` does.

    Precedence, per setting: the command line, the API, the set's table, the default.  A
    setting counts as given by ``options`` when its source is not the default
    (:meth:`feeddrive.SolverOptions.source`: a command-line option, a file, or a value other
    than the default); one left at its default value is the table's to set (to hold a
    default against a table, give its source: ``SolverOptions(accuracy=1.0,
    origin=(("accuracy", "API"),))``).  An ``accuracy`` given by ``options`` replaces the
    table's explicit tolerances, as a higher setting's does in
    :func:`feeddrive.engine.options.layered`; ``options`` made N times tighter than the
    defaults (an error estimate's shadow run, source ``"default ÷ N"``) make the table's
    tolerances and accuracy N times tighter.

    Parameters
    ----------
    system : DriveSystem or DriveParameters
        The drive (or its parameter set).
    options : SolverOptions or None, default None
        The options given (None: those in force).

    Returns
    -------
    SolverOptions
        The options of the run; :meth:`~feeddrive.SolverOptions.describe` names each
        setting's source (``"accuracy 0.01 (from [solver] in run.toml)"``).

    Raises
    ------
    ParameterError
        For a value of the table that the options refuse, naming the setting and the file.

    Examples
    --------
    >>> import feeddrive as fd
    >>> params = fd.parameters.loads('extends = "wang2021"\\n[solver]\\naccuracy = 0.01\\n')
    >>> system = fd.DriveSystem(params, drive="cdfs", table_position=0.4)
    >>> run_options(system).accuracy
    0.01
    >>> run_options(system, fd.SolverOptions(accuracy=0.5)).accuracy
    0.5
    """
    from . import options as opt

    chosen = options if options is not None else current_options()
    params = system if isinstance(system, DriveParameters) else system.parameters
    table = getattr(params, "solver", ())
    if not table:
        return chosen
    tolerances = tuple(name for name, _, _ in opt.TOLERANCES)
    tighter = {name: _tightened_default(chosen, name) for name in opt.SETTINGS}
    accuracy_given = tighter["accuracy"] is None
    factor = tighter["accuracy"] or 1.0  # how much tighter than the defaults they were made
    values: dict[str, Any] = {}
    origin = dict(chosen.origin)
    for name, value, source in table:
        if tighter.get(name) is None or (accuracy_given and name in tolerances):
            continue  # given by the options (an accuracy of theirs replaces the tolerances)
        if factor != 1.0 and (name in tolerances or name == "accuracy"):
            value, source = value / factor, f"{source}{_DIVIDED}{factor:g}"
        values[name] = value
        origin[name] = source
    if not values:
        return chosen
    try:
        return replace(chosen, **values, origin=tuple(sorted(origin.items())))
    except ParameterError as err:  # name the setting and the file it came from
        name = err.field.removeprefix("options.")
        if name in values:
            raise ParameterError(f"solver.{name}", err.value,
                                 f"{err.message} ({origin[name]})") from None
        raise


def named_sources(options: SolverOptions,
                  system: DriveSystem | DriveParameters) -> SolverOptions:
    """``options`` with each setting the set's ``[solver]`` table gives, at the same value,
    that ``options`` name as given in Python, named by that table's source instead: the
    options of a sweep's or a fit's worker are read back from their record without sources
    (:meth:`feeddrive.SolverOptions.from_record`), and a refusal or advice there named
    ``options.max_steps`` for a limit set in the parameter file.  For messages only: the
    settings are unchanged (the options compare equal).

    Parameters
    ----------
    options : SolverOptions
        A run's options (:func:`~feeddrive.engine.simulate.run_options`).
    system : DriveSystem or DriveParameters
        The drive (or its parameter set), whose set carries the table.

    Returns
    -------
    SolverOptions
        The options, their ``origin`` completed.
    """
    from .options import API_SOURCE

    params = system if isinstance(system, DriveParameters) else system.parameters
    origin = dict(options.origin)
    for name, value, source in getattr(params, "solver", ()):
        if options.source(name) == API_SOURCE and getattr(options, name, None) == value:
            origin[name] = source
    if origin == dict(options.origin):
        return options
    return replace(options, origin=tuple(sorted(origin.items())))


#: how a derived setting's source names its divisor (``"default ÷ 10"``:
#: :meth:`feeddrive.SolverOptions.tightened_source`)
_DIVIDED = " ÷ "


def _tightened_default(options: SolverOptions, name: str) -> float | None:
    """1 when setting ``name`` of ``options`` is left at its default, N when it is the default
    made N times tighter (source ``"default ÷ N"``: a shadow run's), None when it is given."""
    from .options import DEFAULT_SOURCE

    source = options.source(name)
    if source == DEFAULT_SOURCE:
        return 1.0
    base, sep, divisor = source.rpartition(_DIVIDED)
    if sep and base == DEFAULT_SOURCE:
        try:
            return float(divisor)
        except ValueError:
            return None
    return None


def simulate(system: DriveSystem, profile: Profile, duration: float, *,
             options: SolverOptions | None = None, output: str | Path | None = None,
             progress: Callable[[float, float], None] | None = None,
             error_estimate: bool | str = False) -> Result:
    """Simulate ``system`` following ``profile`` for ``duration`` from rest.

    ``output`` (``.parquet`` or ``.csv``): every sample is written to that file as it is
    computed, in chunks, and the Result keeps only the last minute of the run, so memory does
    not grow with the duration.  ``progress(t, t_end)`` is called after each chunk of a long
    run (a fraction of a second of work, or ten simulated seconds) and, on the main thread,
    with the solver's live time when no chunk has ended for 0.2 s; there a run given
    ``progress`` (and every run of the command line, :func:`feeddrive._sigint.stop_within_a_step`)
    is waited on in a helper thread, so that Ctrl-C stops the compiled solver after the step
    it is in.

    Parameters
    ----------
    system : DriveSystem
        The drive.
    profile : ConstantSpeed, SineSpeed or SampledSpeed
        The reference the loops follow: a constant speed, a sine, or a tabulated profile such
        as :func:`feeddrive.trapezoid` (ramp, hold, stop) and :func:`feeddrive.stepdown` (the
        paper's staircase, Wang2021 Sect. 6).
    duration : float
        Simulated time [s].
    options : SolverOptions or None, default None
        Integrator settings (None: those in force, :func:`feeddrive.engine.options.current`,
        by default the defaults), over the ``[solver]`` table the parameter set carries,
        setting by setting (:func:`~feeddrive.engine.simulate.run_options`).
    output : str, pathlib.Path or None, default None
        Stream every sample to this ``.parquet`` or ``.csv`` file.
    progress : callable or None, default None
        Called as ``progress(t, t_end)`` [s] after each chunk (and, on the main thread,
        with the live time when no chunk has ended for 0.2 s); an exception it raises stops
        the run.  With ``error_estimate`` True the second run reports too, its t from 0
        again.
    error_estimate : bool or str, default False
        Also estimate the run's global integration error per signal (largest absolute and
        relative to the signal's range): True or ``"shadow"`` from a second run with every
        tolerance ten times tighter (:mod:`feeddrive.engine.error_estimate`; it costs that
        run; within a factor 3 of the true error on the validation cases); ``"embedded"``
        carried along the run itself (:mod:`feeddrive.solvers.global_error`; dense-output
        methods, the states only, a few per cent more CPU, but not even an order-of-magnitude
        statement: 0.15–200 000 × the true error where measured,
        :data:`~feeddrive.solvers.global_error.MEASURED_RATIO`).  In
        ``solver_stats["error_estimate"]``, the summary, the JSON and each signal's
        attributes.

    Returns
    -------
    Result
        Named signals, SI units; the xarray Dataset is built when read.

    Raises
    ------
    ParameterError
        For a ``duration`` past the end of a tabulated profile that still commands a speed
        there (``check_profile_span``), refused before the integration.
    SimulationError
        If the integrator fails (a result is never NaN silently).
    SimulationInterrupted
        On Ctrl-C, holding the part of the run that was finished.

    See Also
    --------
    Result.summary, Result.plot, Result.to_pandas, Result.save

    Examples
    --------
    The CDFS at mid-screw commanded at 2 mm/s, above its critical speed (1.56 mm/s), runs
    smoothly after its start-up transient:

    >>> import feeddrive as fd
    >>> system = fd.DriveSystem(fd.preset("wang2021"), drive="cdfs", table_position=0.4)
    >>> result = fd.simulate(system, fd.ConstantSpeed(table_speed=2e-3), duration=3.0)
    >>> s = result.summary()
    >>> print(f"{s['mean_table_speed_mm_s']:.2f} mm/s, {s['verdict']}")
    2.00 mm/s, smooth

    A move that ramps up, holds 2 mm/s and stops:

    >>> move = fd.trapezoid(2e-3, duration=2.0, ramp_time=0.5)
    >>> result = fd.simulate(system, move, duration=2.0)
    >>> print(f"{1e3 * result['table_position'][-1]:.2f} mm travelled")
    3.00 mm travelled
    """
    kind = estimate_kind(error_estimate)
    embedded = kind == "embedded"
    sim = Simulation(system, profile, options, embedded_estimate=embedded)
    if embedded and not sim.embedded_estimate:
        raise ParameterError("error_estimate", error_estimate,
                             f"the embedded estimate needs a dense-output method, not "
                             f"{sim.options.method!r} (or use error_estimate='shadow')")
    shadow_options = (tightened(sim.options) if kind == "shadow"
                      else None)  # refused before work
    result = sim.run(duration, output=output, progress=progress)
    if embedded:
        carried = result.solver_stats["embedded_error_estimate"]["signals"]
        states = [st.name for st in sim.model.states]
        result.add_error_estimate(embedded_entry(
            states, np.array([carried[name]["absolute"] for name in states]),
            np.column_stack([np.asarray(result[name], dtype=float) for name in states])))
    if shadow_options is not None:
        try:
            shadow = Simulation(system, profile, shadow_options).run(duration,
                                                                     progress=progress)
        except SimulationError as err:  # the run itself is done: say which run failed, keep it
            where = f" ({output} holds it)" if output is not None else ""
            failed = SimulationError(
                f"error estimate: the second run, every tolerance {SHADOW_FACTOR:g}× tighter, "
                f"failed — {err}; the run itself finished{where}: ask for no estimate, or "
                f"allow the second run what it needs")
            failed.result = result  # type: ignore[attr-defined]
            raise failed from None
        if shadow.time.size != result.time.size:  # a streamed run keeps its last part only
            shadow = _tail(shadow, result.time)
        errors = signal_errors(result, shadow)
        result.add_error_estimate(summary_entry(errors, sim.options, shadow_options,
                                                shadow.solver_stats))
    return result


def _streamed_note(output: str | Path | None, kept_until: float) -> str:
    """What a failed run left in its output file: nothing (an empty file it made is removed,
    so that a retry is not refused as "exists"), or the samples up to ``kept_until`` [s]."""
    if output is None:
        return ""
    path = Path(output)
    if path.is_file() and path.stat().st_size == 0:
        path.unlink()
        return f"; {output} not written"
    return f"; {output} holds 0 … {kept_until:g} s" if path.is_file() else ""


def _tail(shadow: Result, times: np.ndarray) -> Result:
    """``shadow``'s samples at ``times`` (a streamed run's kept part: the same output grid)."""
    idx = np.searchsorted(shadow.time, times)
    if idx.size == 0 or idx[-1] >= shadow.time.size \
            or not np.array_equal(shadow.time[idx], times):
        raise ValueError("the shadow run's output instants differ from the run's")
    return Result(shadow.dataset.isel(time=idx))


class Simulation:
    """A run from rest that can be continued.

    ``run(duration)`` returns the Result over [0, ``duration``]; a later call with a longer
    duration integrates on from where the previous one stopped, the integrator's state carried
    over, so the Result is bit-identical to ``simulate(system, profile, duration)`` (the
    dense-output methods continue from the last multiple of :data:`DENSE_CHUNK`).
    The creep verdict uses it to lengthen an undecided trial without repeating it
    (:func:`feeddrive.analysis.critical.decide`).

    Parameters
    ----------
    system : DriveSystem
        The drive.
    profile : ConstantSpeed, SineSpeed or SampledSpeed
        The reference the loops follow.
    options : SolverOptions or None, default None
        Integrator settings (None: those in force), over the ``[solver]`` table the parameter
        set carries (:func:`~feeddrive.engine.simulate.run_options`).
    embedded_estimate : bool, default False
        Carry the embedded global-error estimate along the integration
        (:mod:`feeddrive.solvers.global_error`; dense-output methods): each Result's
        ``solver_stats["embedded_error_estimate"]`` (:func:`~.error_estimate.embedded_entry`).
        The run itself is bit-identical with or without it.
    """

    def __init__(self, system: DriveSystem, profile: Profile,
                 options: SolverOptions | None = None, *,
                 embedded_estimate: bool = False) -> None:
        if isinstance(system, DriveParameters) or not callable(getattr(system, "model", None)):
            raise ParameterError("system", type(system).__name__, "expected a DriveSystem, "
                                 "e.g. DriveSystem(params, drive='cdfs', table_position=0.4)")
        if not isinstance(profile, ConstantSpeed | SineSpeed | SampledSpeed | Replay):
            raise ParameterError("profile", type(profile).__name__,
                                 "expected ConstantSpeed, SineSpeed, SampledSpeed or a Replay")
        check_given(options)
        self.system, self.profile = system, profile
        # those given, else those in force, over the set's [solver] table (run_options)
        self.options = options = run_options(system, options)
        # the same, each setting named where the user gave it, for refusals and advice
        self.named = named_sources(options, system)
        self.embedded_estimate = (check_flag("embedded_estimate", embedded_estimate)
                                  and options.method in _DENSE_MODES)
        self.model = system.model(profile)
        self.grid = sampling(system.parameters, options.output_interval, self.model)
        self.P = self.grid.parameters(self.model)  # the sample periods on the grid
        self.scales = run_scales(system, profile, self.model)
        self.tolerances = tol = options.resolve(self.scales)
        self.atol, self.rel = self.model.tolerances(
            tol.position, tol.speed, tol.current, tol.deflection,
            motor_position=tol.motor_position, motor_speed=tol.motor_speed)
        self.y0 = system.initial_vector(self.model)
        self.bound = divergence_bounds(system, profile, self.model)
        # the friction reversals every adaptive method locates (not the fixed-step order
        # checks; not with locate_reversals=False, the v1 engine's dopri5)
        self.switch_rows = (switching_rows(self.model, self.P)
                            if options.locate_reversals and options.method in _REVERSAL_METHODS
                            else None)
        self._chunks: _Chunks | None = None
        self._running: _Chunks | None = None
        self._reached: float | None = None  # the last Result's end [s] (repr)

    def __repr__(self) -> str:
        # what a notebook shows: the drive, the profile, the method and how far it has run
        reached = self._reached
        return (f"<feeddrive.Simulation {self.system.drive} of "
                f"{self.system.parameters.name!r} at {self.system.table_position!r} m, "
                f"{self.profile!r}, method {self.options.method!r}; "
                + ("not run yet>" if reached is None else f"run to {reached:g} s>"))

    def keep_checkpoints(self) -> None:
        """Keep the carried state at every committed chunk end of the coming runs, so that a
        later :class:`Simulation` of a profile with the same beginning can start there
        (:meth:`resume`) instead of from rest."""
        if self._chunks is None:
            self._chunks = _Chunks(self, want_aux=False)
        if self._chunks.checkpoints is None:
            self._chunks.checkpoints = [] if self._chunks.start == 0 else None

    def resume(self, previous: Simulation) -> float:
        """Start this run where ``previous`` (run with :meth:`keep_checkpoints`) committed its
        last chunk before the two profiles part: the result is bit-identical to a run from
        rest, since the state carried at a chunk end (states, held controller values, the
        integrator's memory, counters) is what the run from rest has there.

        Only tabulated profiles (:class:`~feeddrive.model.reference.SampledSpeed`, e.g. the
        step-down staircase) of the same system, options and grid are resumed; the profiles
        agree up to the last sample both have equal (two samples are kept in hand: the
        reference interpolates between neighbours).

        Parameters
        ----------
        previous : Simulation
            An earlier run of the same system with another profile.

        Returns
        -------
        float
            The time the run resumes from [s]; 0 when nothing is shared (a run from rest).
        """
        kept = self._shared(previous)
        if not kept:
            return 0.0
        start, y, held, memory, totals, n_parts = kept[-1]
        chunks = _Chunks(self, want_aux=False)
        chunks.checkpoints = kept
        chunks.start, chunks.y, chunks.held = start, y.copy(), held.copy()
        chunks.memory = chunks.live = memory.copy()
        chunks.totals = totals.copy()
        chunks.parts = previous._chunks.parts[:n_parts] if previous._chunks else []
        self._chunks = chunks
        return start * self.grid.base

    def resumable_from(self, previous: Simulation) -> float:
        """The time [s] :meth:`resume` would start this run from (0: from rest), without
        resuming.

        Parameters
        ----------
        previous : Simulation
            An earlier run of the same system with another profile.

        Returns
        -------
        float
            The time [s].
        """
        kept = self._shared(previous)
        return kept[-1][0] * self.grid.base if kept else 0.0

    def _shared(self, previous: Simulation) -> list[tuple[int, np.ndarray, np.ndarray,
                                                          np.ndarray, np.ndarray, int]]:
        """The checkpoints of ``previous`` this run's profile shares (empty: none)."""
        prev = previous._chunks
        if prev is None or not prev.checkpoints or not self._same_but_profile(previous):
            return []
        a, b = self.profile, previous.profile
        assert isinstance(a, SampledSpeed) and isinstance(b, SampledSpeed)
        n = min(len(a.time), len(b.time))
        differ = np.flatnonzero(
            (np.asarray(a.time[:n]) != np.asarray(b.time[:n]))
            | (np.asarray(a.table_speed[:n]) != np.asarray(b.table_speed[:n]))
            | (_nut(a)[:n] != _nut(b)[:n]))
        same = int(differ[0]) if differ.size else n  # samples 0 … same − 1 agree
        if same < 2:
            return []
        until = float(a.time[same - 2]) + 1e-12  # the run reads up to the next sample
        return [c for c in prev.checkpoints if c[0] * self.grid.base <= until]

    def _same_but_profile(self, other: Simulation) -> bool:
        """Whether ``other`` integrates the same model, options and grid, and both profiles are
        tables that are the model's only table (so they differ only in the profile's
        numbers and its length slot)."""
        a, b = self.profile, other.profile
        if not (isinstance(a, SampledSpeed) and isinstance(b, SampledSpeed)
                and a.hold == b.hold and self.system is other.system
                and self.options == other.options
                and self.embedded_estimate == other.embedded_estimate and self.grid == other.grid
                and self.model.source == other.model.source
                and self.model.parameter_names == other.model.parameter_names):
            return False
        names = self.model.parameter_names
        if "profile[6]" not in names:
            return False
        length = names.index("profile[6]")
        if self.model.T.size != 4 * int(self.P[length]) \
                or other.model.T.size != 4 * int(other.P[length]):
            return False  # another table (a load record) shares T
        mask = np.arange(self.P.size) != length
        return bool(np.array_equal(self.P[mask], other.P[mask])
                    and np.array_equal(self.atol, other.atol)
                    and np.array_equal(self.rel, other.rel)
                    and np.array_equal(self.y0, other.y0)
                    and np.array_equal(self.bound, other.bound))

    def live_time(self) -> float:
        """The simulated time the solver has reached in the run going on now.

        Read while :meth:`run` computes (from another thread: the compiled solver releases the
        GIL and writes the time of each accepted step into its memory's last slot).

        Returns
        -------
        float
            The time reached [s]; 0 before the first step.
        """
        chunks = self._running
        return 0.0 if chunks is None else float(chunks.live[-1])

    def request_stop(self) -> None:
        """Ask the run going on (in another thread) to stop: the compiled solver ends after
        the step it is in, and :meth:`run` raises :class:`SimulationInterrupted` with what
        was finished, as on Ctrl-C.  The explorer's Cancel uses it."""
        chunks = self._running
        if chunks is not None:
            chunks.stop_requested = True
            chunks.live[-2] = 1.0

    def run(self, duration: float, *, output: str | Path | None = None,
            progress: Callable[[float, float], None] | None = None) -> Result:
        """The Result over [0, ``duration``], continuing the previous call where possible.

        Parameters
        ----------
        duration : float
            End of the run [s].
        output : str, pathlib.Path or None, default None
            Stream every sample to this ``.parquet`` or ``.csv`` file (the run then starts anew).
        progress : callable or None, default None
            Called as ``progress(t, t_end)`` [s] after each chunk.

        Returns
        -------
        Result
            Bit-identical to ``simulate(system, profile, duration)``.
        """
        # True ran for 1 s and np.float32(0.05) was refused as "expected a finite time"
        # (an API sweep of session 29)
        if not (is_real(duration) and math.isfinite(duration) and duration > 0):
            raise ParameterError("duration", duration, "expected a finite time > 0 [s]")
        duration = float(duration)
        # a number as output was os.fspath's TypeError, a number as progress "'int' object
        # is not callable" after the first chunk had run (session 29)
        if output is not None and not isinstance(output, str | os.PathLike):
            raise ParameterError("output", output, "expected None or a file name (str or "
                                 "pathlib.Path) ending in .parquet or .csv")
        check_callback("progress", progress, "progress(t, t_end) [s]")
        check_profile_span(self.profile, duration, self.options.output_interval)
        options, grid, model = self.options, self.grid, self.model
        # an output interval longer than the run left a Result without a sample (its summary
        # failed after the run on an empty array): refused before any work, naming the setting
        budget.check_output_samples(float(duration), self.named)
        n_break = int(round(duration / grid.base))
        t_end = n_break * grid.base
        if output is None:  # a streamed run keeps only its last KEEP_STREAMED seconds
            budget.check_output_memory(t_end, options.output_interval, options=self.named)
        started = _time.perf_counter()
        chunks = self._chunks
        if chunks is None or output is not None or n_break < chunks.start:
            chunks = _Chunks(self, want_aux=output is not None)
        self._chunks = None if output is not None else chunks
        self._running = chunks
        if not chunks.dense:
            _check_step_rate(self.system, self.profile, model, grid, self.named, self.y0, t_end,
                             chunks.adaptive, self.tolerances.rtol, self.atol, self.rel,
                             chunks.h_init, chunks.h_max,
                             self.bound, self.switch_rows)
        try:
            t, y_parts, aux_parts, stats = _advance(self, chunks, n_break, output, progress)
        except _Stopped as stop:
            if chunks.stop_requested:  # request_stop: not continued from
                self._chunks = None
            partial = self._result(*stop.joined, {"method": options.method, "interrupted": True,
                                                  "t_reached_s": stop.t_reached})
            raise SimulationInterrupted(stop.t_reached, partial,
                                        None if output is None else str(output)) from None
        wall = _time.perf_counter() - started
        status = int(stats[0])
        diverged = status == dopri5.STATUS_DIVERGED
        limit = divergence_speed(self.system, self.profile)
        problem = replay_bound_problem(self.profile, float(stats[4]), limit) if diverged else ""
        if problem:
            self._chunks = None
            raise SimulationError(problem)
        if status != dopri5.STATUS_OK and not diverged:
            self._chunks = None
            raise SimulationError(
                f"integration stopped at t = {stats[4]:.6g} s of {t_end:g} s: "
                f"{dopri5.STATUS_MESSAGES[status]} (steps {int(stats[1])}, rejected "
                f"{int(stats[2])}); {failure_advice(status, self.named)}"
                f"{_streamed_note(output, chunks.start * grid.base)}")
        solver_stats: dict[str, Any] = {
            "method": options.method, **self.tolerances.as_dict(),
            "accuracy": options.accuracy, "speed_scale": self.scales.speed,
            "table_speed_scale": self.scales.table_speed,
            "current_scale": self.scales.current,
            "steps": int(stats[1]), "rejected_steps": int(stats[2]),
            "rhs_evaluations": int(stats[3]), "wall_time_s": wall,
            "breakpoint_interval_s": grid.base, "engine": builds.engine_of(model),
        }
        if options.method in ("modal", "auto"):
            solver_stats["rosenbrock"] = options.rosenbrock
        if diverged:  # stopped early: the Result ends where a speed left its bound
            solver_stats.update({"diverged": True, "diverged_at_s": float(stats[4]),
                                 "divergence_speed_ratio": DIVERGENCE_SPEED_RATIO,
                                 "divergence_speed_m_s": limit})
        if chunks.dense:
            solver_stats.update({
                "jacobians": int(stats[5]), "rosenbrock_steps": int(stats[6]),
                "method_switches": int(stats[7]), "output_rhs_evaluations": int(stats[8]),
                "eigen_analyses": int(stats[9]), "switch_crossings": int(stats[10]),
                "spectral_radii": int(stats[11])})
            carried = switching.error_estimate(chunks.live, len(model.states))
            if carried is not None:  # the memory of the call that ended the run
                solver_stats["embedded_error_estimate"] = embedded_entry(
                    [s.name for s in model.states], carried[1])
        self._reached = float(t[-1]) if t.size else 0.0
        return self._result(t, y_parts, aux_parts, solver_stats)

    def _result(self, t: np.ndarray, y_parts: list[np.ndarray], aux_parts: list[np.ndarray],
                solver_stats: dict[str, Any]) -> Result:
        model = self.model
        n = len(model.states)
        y = y_parts[0] if len(y_parts) == 1 else np.zeros((0, n))
        run = Run(t, y, np.zeros((0, len(model.aux))), model, self.system, self.profile,
                  solver_stats, options=self.named)
        if len(y_parts) > 1:  # a state's parts are joined when it is read
            run.defer_states(y_parts)
        if sum(a.shape[0] for a in aux_parts) == t.shape[0]:  # recorded: joined when read
            run.defer_aux(lambda _: _join(aux_parts, len(model.aux)))
        else:  # not recorded (continuous loops, dense output): evaluated when read
            run.defer_aux(lambda r: builds.compiled(r.model, "auxiliary")(
                r.t, r.states(), r.model.P, r.model.T))
        return Result.from_run(run)


# A dense-output run is integrated in calls that end at the multiples of this [s] (simulated),
# whatever its duration: the steps there are the same in every run, so a run continued to a
# longer duration is bit-identical to one from rest, and Ctrl-C and progress act between calls.
DENSE_CHUNK = 10.0


class _Chunks:
    """A run integrated in chunks and continued by each :meth:`advance`; the result is
    bit-identical to one call over the whole span.

    ``dopri5`` (every breakpoint a step end): a chunk may end at any breakpoint; its size
    follows :data:`CHUNK_WALL_TIME`.  Dense output (:mod:`feeddrive.solvers.switching`): the
    chunks end at the multiples of :data:`DENSE_CHUNK`; the part after the last multiple is
    integrated from a copy of the carried state and integrated again when the run is continued.
    """

    @property
    def sim(self) -> Simulation:
        """The simulation these chunks belong to (alive while they are used)."""
        sim = self._sim()
        assert sim is not None, "a run's chunks outlived their Simulation"
        return sim

    def __init__(self, sim: Simulation, *, want_aux: bool) -> None:
        options, grid, model = sim.options, sim.grid, sim.model
        # weakly: the simulation holds its chunks (``_chunks``, ``_running``), and a cycle
        # would keep a finished run's output parts until Python's next cyclic collection
        # (a step-down search's 16 staircase runs: ≈ 600 MB at its peak)
        self._sim = weakref.ref(sim)
        self.dense = options.method in _DENSE_MODES
        every = grid.out_every
        n = len(model.states)
        self.held = np.zeros(model.n_held)
        if self.dense:
            self.mode, self.adaptive = options.driver_mode
            cap, first = options.largest_step, DENSE_CHUNK
            self.want_aux = want_aux or grid.sampled
        else:  # every breakpoint a step end
            self.adaptive = 1 if options.method == "dopri5" else 0
            cap, first = min(options.largest_step, grid.base), FIRST_CHUNK
        self.h_init = 1e-6 if self.adaptive else options.fixed_step
        self.h_max = cap if self.adaptive else options.fixed_step
        self.memory = (switching.new_memory(n, sim.embedded_estimate) if self.dense
                       else dopri5.new_memory(n, self.h_init))
        self.live = self.memory  # the memory of the solver call going on (live_time)
        self.stop_requested = False  # Simulation.request_stop
        self.size = max(every, int(round(first / grid.base)) // every * every)
        self.parts: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        self.totals = np.zeros(len(switching.STAT_NAMES) if self.dense else 5)
        self.start = 0
        self.diverged = False
        self.y = sim.y0
        # the profile's kinks over the whole time axis, once (each chunk takes those before
        # its end: a long staircase profile's ≈ 1 ms a chunk)
        self.kinks = profile_breakpoints(sim.profile, math.inf, grid.base,
                                         every_sample=options.sample_steps) if self.dense \
            else np.zeros(0)
        # (breakpoint, y, held, memory, totals, parts so far) at each committed chunk end,
        # kept for Simulation.resume when Simulation.keep_checkpoints asked for them
        self.checkpoints: list[tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                     int]] | None = None

    def _call(self, y: np.ndarray, start: int, stop: int, held: np.ndarray,
              memory: np.ndarray, max_steps: int,
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        grid = self.sim.grid
        t, yy, aa, stats = self._integrate(y, start, stop, held, memory, max_steps)
        if start > 0 and t.size and t[0] <= start * grid.base:
            t, yy, aa = t[1:], yy[1:], aa[1:]  # the shared breakpoint, already kept
        return t, yy, aa, stats

    def _integrate(self, y: np.ndarray, start: int, stop: int, held: np.ndarray,
                   memory: np.ndarray, max_steps: int,
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        sim, grid = self.sim, self.sim.grid
        t_stop = stop * grid.base
        if self.dense:
            t, yy, aa, stats, _ = switching.integrate(
                sim.model, y, t_stop, grid.out_every, grid.base, grid.schedule,
                sim.tolerances.rtol, sim.atol, sim.rel, self.h_init, self.h_max, self.adaptive,
                max_steps, self.mode,
                self.kinks[self.kinks < t_stop], self.want_aux,
                start=start, held=held, memory=memory, bound=sim.bound, P=sim.P,
                switch_rows=sim.switch_rows)
        else:
            t, yy, aa, stats, _ = dopri5.integrate(
                sim.model, y, t_stop, grid.out_every, grid.base, grid.schedule,
                sim.tolerances.rtol, sim.atol, sim.rel, self.h_init, self.h_max, self.adaptive,
                max_steps, stability_share=sim.options.stability_share, start=start,
                held=held, memory=memory, bound=sim.bound, P=sim.P,
                switch_rows=sim.switch_rows)
        return t, yy, aa, stats

    def _add(self, stats: np.ndarray) -> np.ndarray:
        """Totals so far with ``stats`` added (status and time reached from ``stats``)."""
        out = self.totals + stats
        out[0], out[4] = stats[0], stats[4]
        return out

    def advance(self, n_break: int, output: str | Path | None,
                progress: Callable[[float, float], None] | None,
                ) -> tuple[np.ndarray, list[np.ndarray], list[np.ndarray], np.ndarray]:
        """Integrate on to breakpoint ``n_break``; (t, the states' parts, the auxiliary
        signals' parts, stats) from t = 0 (the parts are joined only where a signal among them
        is read)."""
        from ..io.results import ChunkWriter

        sim, grid = self.sim, self.sim.grid
        every = grid.out_every
        t_end = n_break * grid.base
        writer = (ChunkWriter(output, sim.model, sim.system, Run, sim.profile,
                              method=sim.options.method) if output is not None else None)
        kept = sum(p[0].size for p in self.parts)
        keep = int(KEEP_STREAMED / (every * grid.base)) + 1
        tail: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        stats = self.totals
        try:
            while self.start < n_break and not self.diverged:
                if self.dense:
                    stop = (self.start // self.size + 1) * self.size
                else:
                    stop = min(n_break, self.start + self.size)
                # a dense run's part after its last multiple of DENSE_CHUNK: integrated from a
                # copy of the carried state and not kept for a continuation
                commit = stop <= n_break
                stop = min(stop, n_break)
                held, memory = (self.held, self.memory) if commit else (
                    self.held.copy(), self.memory.copy())
                self.live = memory  # its last slot: the solver's live time (live_time)
                if self.stop_requested:
                    raise KeyboardInterrupt  # a stop asked for between two calls
                began = _time.perf_counter()
                t, yy, aa, last = self._call(self.y, self.start, stop, held, memory,
                                             self.sim.options.max_steps - int(self.totals[1]))
                wall = _time.perf_counter() - began
                stats = self._add(last)
                if int(last[0]) == dopri5.STATUS_DIVERGED:
                    # kept up to the divergence and final: a continuation returns it again
                    self.totals = stats
                    self.parts.append((t, yy, aa))
                    if writer is not None:
                        writer.write(t, yy, aa)
                    self.start = max(self.start, int(math.ceil(last[4] / grid.base - 1e-9)))
                    self.diverged = True
                    break
                if int(last[0]) == dopri5.STATUS_STOPPED:
                    # stopped inside the call (request_stop): its part is dropped and the
                    # carried state it changed is not continued from
                    self.sim._chunks = None
                    raise KeyboardInterrupt
                if int(last[0]) != dopri5.STATUS_OK:
                    break
                if writer is not None:
                    writer.write(t, yy, aa)
                if commit:
                    self.totals = stats
                    self.parts.append((t, yy, aa))
                    kept += t.size
                    while writer is not None and len(self.parts) > 1 \
                            and kept - self.parts[0][0].size >= keep:
                        kept -= self.parts.pop(0)[0].size
                    self.y = yy[-1].copy() if yy.shape[0] else self.y
                    self.start = stop
                    if self.checkpoints is not None and writer is None:
                        self.checkpoints.append((stop, self.y.copy(), self.held.copy(),
                                                 self.memory.copy(), self.totals.copy(),
                                                 len(self.parts)))
                else:
                    tail.append((t, yy, aa))
                if progress is not None:
                    progress(stop * grid.base, t_end)
                if not commit:
                    break
                if not self.dense:
                    scale = CHUNK_WALL_TIME / max(wall, 1e-4)
                    self.size = max(every, min(int(self.size * min(scale, 4.0)) // every
                                               * every, MAX_CHUNK_SAMPLES * every))
        except KeyboardInterrupt:
            if writer is not None:
                writer.close()  # the samples so far, complete rows
            raise _Stopped(self.start * grid.base, self._joined(self.parts)) from None
        except BaseException as err:
            if writer is not None:
                writer.abort(err)  # e.g. a full disk: nothing partial under the output name
            raise
        if writer is not None:
            writer.close()
        return (*self._joined([*self.parts, *tail]), stats)

    def _joined(self, parts: list[tuple[np.ndarray, np.ndarray, np.ndarray]],
                ) -> tuple[np.ndarray, list[np.ndarray], list[np.ndarray]]:
        """t of ``parts`` end to end, their states' and auxiliary arrays as lists (joined
        when read: :meth:`~feeddrive.engine.result.Run.defer_states`)."""
        return (_join([p[0] for p in parts], None), [p[1] for p in parts],
                [p[2] for p in parts])


#: the command-line option of ``max_steps``, where a command takes one (``simulate``,
#: ``circular``, ``positioning``)
MAX_STEPS_OPTION = "--max-steps"
#: the advice on a run out of steps, ``{}`` where to raise the limit
#: (:func:`feeddrive.engine.budget.setting_hint`)
_MAX_STEPS_ADVICE = "raise {}, shorten the run, or loosen the tolerances (--accuracy)"
#: what a user can do about a failed integration, by the driver's status (an outside check,
#: 2026-12-06: a step-size underflow from a 5e-324-A tolerance advised raising --max-steps),
#: for a step limit left at its default or given in Python; a limit given on the command
#: line or in a file's ``[solver]`` table is named as given (:func:`failure_advice`)
FAILURE_ADVICE = {
    dopri5.STATUS_MAX_STEPS: _MAX_STEPS_ADVICE.format(
        f"max_steps (options.max_steps, a [solver] table's max_steps, or {MAX_STEPS_OPTION} "
        "where a command takes it)"),
    dopri5.STATUS_STEP_UNDERFLOW: "the tolerances ask for more than the steps can resolve in "
                                  "double precision (loosen them: --accuracy), or the "
                                  "parameters make the model too stiff (check them)",
    dopri5.STATUS_NON_FINITE: "check the parameters (a state became NaN or infinite)",
}


def failure_advice(status: int, options: SolverOptions) -> str:
    """What a user can do about a run that failed with the driver's ``status``: the advice
    of :data:`FAILURE_ADVICE`, a step limit named where it came from (``raise solver.max_steps
    ([solver] in run.toml)``, ``raise --max-steps``: an outside check, 2026-12-06, found
    ``creep`` and ``sweep`` advising a ``--max-steps`` they do not have for a limit set in a
    parameter file).

    Parameters
    ----------
    status : int
        The driver's status (:data:`feeddrive.solvers.dopri5.STATUS_MAX_STEPS`, …).
    options : SolverOptions
        The run's options, each setting's source in ``origin``.

    Returns
    -------
    str
        The advice.
    """
    if status == dopri5.STATUS_MAX_STEPS:
        field, _ = budget.setting_field(options, "max_steps")
        if field.startswith(("--", "solver.")):  # a command-line option, a file's table
            return _MAX_STEPS_ADVICE.format(budget.setting_hint(options, "max_steps"))
    return FAILURE_ADVICE.get(status, "check the parameters")


#: a run waited on by the main thread reports the solver's live time when no chunk has ended
#: for this long [s of wall time]
LIVE_PROGRESS_EVERY = 0.2


def _interruptible(progress: Callable[[float, float], None] | None = None) -> bool:
    """Whether to wait for the run in a helper thread: asked for (``progress`` given, or
    :func:`feeddrive._sigint.stop_within_a_step`, as the command line does), and Ctrl-C can
    reach this thread as KeyboardInterrupt — the main thread, SIGINT not ignored (a pool worker
    of ``reproduce`` or a sweep ignores it), not a dry run of
    :func:`feeddrive.solvers.shared.prepared_models` (its flag is this thread's)."""
    import signal

    from .. import _sigint
    from ..solvers import shared

    return ((progress is not None or _sigint.asked())
            and threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGINT) not in (signal.SIG_IGN, None)
            and not shared.preparing())


def _advance(sim: Simulation, chunks: _Chunks, n_break: int, output: str | Path | None,
             progress: Callable[[float, float], None] | None,
             ) -> tuple[np.ndarray, list[np.ndarray], list[np.ndarray], np.ndarray]:
    """``chunks.advance`` so that Ctrl-C stops the run within a solver step.

    A compiled solver call holds the main thread until it returns, and Python acts on Ctrl-C
    only between such calls: a chunk of the run (up to :data:`DENSE_CHUNK` simulated
    seconds) at tight tolerances can take many seconds.  Where asked for (:func:`_interruptible`:
    the command line, or a run given ``progress``) the chunks therefore run in a helper thread
    (the compiled solver releases the GIL) while the main thread waits; Ctrl-C there asks the
    solver to stop after its current step (:meth:`Simulation.request_stop`), and the run ends
    as on a Ctrl-C between chunks (:class:`SimulationInterrupted` with what was finished).
    ``progress`` is called on the main thread, after each chunk in step with the worker (which
    waits for it, so that an error it raises stops the run where that chunk ended) and, when
    no chunk has ended for :data:`LIVE_PROGRESS_EVERY` seconds, with the solver's live time.
    The steps are the same either way: the helper thread runs the same calls.
    """
    if not _interruptible(progress):
        return chunks.advance(n_break, output, progress)
    import contextvars
    import queue

    t_end = n_break * sim.grid.base
    done: dict[str, Any] = {}
    # each chunk end the worker reached, with where to hand back what progress raised: the
    # worker waits for it, so progress is called in step with the chunks, as without a thread
    ends: queue.Queue[tuple[float, queue.Queue[BaseException | None]] | None] = queue.Queue()
    shown = [0.0]  # the last time given to progress
    # the worker's end, seen even where Ctrl-C cut in after its wake-up (None) was taken; not
    # Thread.join: a join interrupted by Ctrl-C can mark the running thread as ended (CPython
    # 3.11's threading._wait_for_tstate_lock)
    finished = threading.Event()

    def chunk_end(t: float, _: float) -> None:  # on the worker
        reply: queue.Queue[BaseException | None] = queue.Queue(maxsize=1)
        ends.put((t, reply))
        while True:
            try:
                err = reply.get(timeout=0.1)
                break
            except queue.Empty:
                if chunks.stop_requested:  # Ctrl-C before the main thread replied
                    raise KeyboardInterrupt from None
        if err is not None:
            raise err

    def work() -> None:
        try:
            done["value"] = chunks.advance(n_break, output,
                                           None if progress is None else chunk_end)
        except BaseException as err:  # handed to the main thread
            done["error"] = err
        finally:
            finished.set()
            ends.put(None)  # wakes the main thread at once

    def show(t: float) -> None:
        if progress is not None and t > shown[0]:
            shown[0] = t
            progress(t, t_end)

    # the worker sees this thread's context (the solver settings in force, options.using)
    worker = threading.Thread(target=contextvars.copy_context().run, args=(work,),
                              name="feeddrive-run", daemon=True)
    worker.start()
    stop: BaseException | None = None  # Ctrl-C on this thread
    quiet_until = _time.monotonic() + LIVE_PROGRESS_EVERY
    while not finished.is_set():
        try:
            try:
                item = ends.get(timeout=0.05)
                if item is None:  # the worker has ended
                    break
                t, reply = item
            except queue.Empty:
                if stop is None and _time.monotonic() >= quiet_until:  # a long chunk
                    quiet_until += LIVE_PROGRESS_EVERY
                    show(float(chunks.live[-1]))
                continue
            raised: BaseException | None = None
            if stop is None:
                try:
                    show(t)
                except BaseException as err:  # the worker raises it where the chunk ended
                    raised = err
            reply.put(raised)
            quiet_until = _time.monotonic() + LIVE_PROGRESS_EVERY
        except BaseException as err:  # Ctrl-C (or a live report raised): stop after this step
            stop = stop or err
            sim.request_stop()
    if stop is not None and not isinstance(stop, KeyboardInterrupt):
        raise stop  # a live report's own error: the run was stopped for it
    if "error" in done:
        raise done["error"]
    if stop is not None:
        raise stop  # Ctrl-C as the run ended: it is still obeyed
    return done["value"]


class _Stopped(Exception):
    def __init__(self, t_reached: float,
                 joined: tuple[np.ndarray, list[np.ndarray], list[np.ndarray]]) -> None:
        super().__init__(t_reached)
        self.t_reached, self.joined = t_reached, joined


def _nut(profile: SampledSpeed) -> np.ndarray:
    """A tabulated profile's nut speeds (zeros when it has none) [m/s]."""
    t = np.asarray(profile.time)
    return np.zeros(t.shape) if profile.nut_speed is None else np.asarray(profile.nut_speed)


def _join(arrays: list[np.ndarray], columns: int | None) -> np.ndarray:
    """The chunks' arrays end to end (a single one as it is: no copy)."""
    if len(arrays) == 1:
        return arrays[0]
    if not arrays:
        return np.zeros(0) if columns is None else np.zeros((0, columns))
    return np.concatenate(arrays)
