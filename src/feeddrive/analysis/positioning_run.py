"""The ISO 230-2 positioning test run on a simulated axis: cycle → reference → simulate →
approaches → quantities.  SI.

:func:`run_positioning_test` lays out the cycle
(:func:`~feeddrive.analysis.positioning.positioning_cycle`), turns its stops into a
reference that rests at each
(:func:`~feeddrive.model.positioning_profile.stops_profile`), simulates the drive from rest at
the first stop, reads the actual position at the end of each dwell and evaluates the
approaches (:func:`~feeddrive.analysis.positioning.positioning_test`).  A request the axis
cannot make (fewer than 5 cycles, a stop outside the travel, a feed beyond the axis's speed)
is refused before the run.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import units
from ..parameters import DriveParameters, ParameterError
from ..parameters.validation import check_callback, is_real
from .positioning import (
    MIN_CYCLES,
    PositioningTest,
    Stop,
    positioning_cycle,
    positioning_test,
    read_approaches,
    reading_motion,
)

#: linear passes run before a simulated positioning test, not read (:func:`warm_up_stops`)
WARM_UP = 1
#: the most warm-up passes taken
MAX_WARM_UP = 100

if TYPE_CHECKING:
    from ..engine.options import SolverOptions
    from ..engine.result import Result

__all__ = ["MAX_WARM_UP", "PositioningRun", "WARM_UP", "axis_speed_limit", "axis_travel",
           "run_positioning_test", "warm_up_stops"]


def axis_travel(params: DriveParameters, drive: str) -> tuple[float, str] | None:
    """The table's travel (0, L) as the drive's mechanism declares it (``travel_length``).

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    drive : str
        The drive.

    Returns
    -------
    tuple of (float, str) or None
        L [m] and the parameter it comes from; None when the mechanism declares none.
    """
    from ..model.mechanisms import mechanism

    path = mechanism(drive).travel_length
    if not path:
        return None
    where: Any = params
    for key in path.split("."):
        where = getattr(where, key)
    return float(where), path


def axis_speed_limit(params: DriveParameters, drive: str) -> tuple[float, str]:
    """The largest table speed the axis can reach, and why.

    For a lead-screw drive, the screw motor's no-load speed at the controller's voltage
    limit, U_max/K_e (back EMF equal to the supply), times the lead/2π; never above the
    largest speed any feed drive has (``units.LARGEST_SPEED``).

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    drive : str
        The drive.

    Returns
    -------
    tuple of (float, str)
        The limit [m/s] and what sets it.
    """
    from ..model.mechanisms import mechanism

    limit, why = units.LARGEST_SPEED, "no feed drive is faster"
    if mechanism(drive).has_lead_screw:
        u_max = params.controller.voltage_limit
        k_e = params.screw_motor.back_emf_constant
        v = u_max / k_e * params.screw.lead / (2.0 * math.pi)
        if v < limit:
            limit = v
            why = (f"the screw motor's no-load speed at the voltage limit: "
                   f"controller.voltage_limit / screw_motor.back_emf_constant × lead/2π = "
                   f"{u_max:g} V / {k_e:g} V s/rad × {params.screw.lead * 1e3:g} mm/2π")
    return limit, why


@dataclass(frozen=True)
class PositioningRun:
    """A simulated positioning test.

    Parameters
    ----------
    test : PositioningTest
        The ISO 230-2 quantities.
    stops : tuple of Stop
        The cycle's stops, positions on the axis [m].
    dwell_ends : numpy.ndarray
        When each stop's dwell ends [s].
    start : float
        Where the table starts, at rest (the first stop) [m].
    result : Result
        The simulation (``table_position`` is the motion from ``start``).
    kind : str
        ``"linear"`` or ``"pilgrim"``.
    feed, acceleration, dwell, overshoot : float
        The test's settings [m/s, m/s², s, m].
    warm_up : int, default 1
        Linear passes run before the test, not read (:func:`run_positioning_test`).
    """

    test: PositioningTest
    stops: tuple[Stop, ...]
    dwell_ends: np.ndarray
    start: float
    result: Result
    kind: str
    feed: float
    acceleration: float
    dwell: float
    overshoot: float
    warm_up: int = 1

    @property
    def reading_motion(self) -> float:
        """The largest peak-to-peak motion within a reading window [m]
        (:func:`~feeddrive.analysis.positioning.reading_motion`): 0 when every reading is
        taken at rest."""
        return reading_motion(self.result.time, np.asarray(self.result["table_position"]),
                              self.stops[1:], self.dwell_ends, self.dwell)

    def __repr__(self) -> str:
        """One line in the CLI's units (the dataclass printed every array, 3351 characters:
        an outside check, 2026-12-07)."""
        t = self.test
        targets = np.asarray(t.targets)
        return (f"<feeddrive PositioningRun {self.result.attrs.get('drive', '?')}, "
                f"{targets.size} targets {targets[0] * 1e3:g}…{targets[-1] * 1e3:g} mm, "
                f"{np.shape(t.deviation_up)[-1]} cycles {self.kind}, feed "
                f"{self.feed * 1e3:g} mm/s, dwell {self.dwell:g} s: A {t.accuracy * 1e6:.3g} "
                f"µm, R {t.repeatability * 1e6:.3g} µm, B {t.reversal * 1e6:.3g} µm; .test "
                ".result, .test.to_dict()>")


def warm_up_stops(targets: Sequence[float], passes: int, overshoot: float) -> list[Stop]:
    """The stops of the warm-up that precedes a simulated test, none of them read: ``passes``
    times the linear cycle's pass (from P_1 − overshoot up through every target to
    P_m + overshoot and back down to P_1 − overshoot), ending where the test starts.

    A real axis comes to the test's first stop by a move, its friction and loop integrals
    loaded; a simulation starts at rest with them unloaded, and on ``wang2021``'s CDFS that
    start alone moved the first approach of P_1 by 0.14 µm against 0.024 µm for the four
    others at a 2-s dwell (R 0.26 µm, 0.033 µm without it: an outside check, 2026-12-07).
    One pass leaves every approach of the linear cycle the same to 1e-4 µm there
    (tests/unit/test_positioning_warm_up.py).

    Parameters
    ----------
    targets : sequence of float
        The target positions, increasing [m].
    passes : int
        How many passes (0: none).
    overshoot : float
        How far beyond a target the axis reverses [m].

    Returns
    -------
    list of Stop
        The warm-up's stops, starting at P_1 − overshoot, without the last one (the test's
        first stop).
    """
    one = positioning_cycle(targets, MIN_CYCLES, kind="linear", overshoot=overshoot)
    m = len(targets)
    lap = [Stop(s.position, -1, 0, 0) for s in one[:2 * m + 2]]
    return lap * int(passes)


def _number(name: str, value: object, unit: str) -> float:
    """A finite number > 0 [``unit``], or a refusal naming ``name`` (``feed="0.01"`` raised a
    TypeError from inside: an outside check, 2026-12-07)."""
    if not is_real(value):
        raise ParameterError(name, value, f"expected a number > 0 [{unit}]")
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise ParameterError(name, value, f"expected a finite value > 0 [{unit}]")
    return v


def _check_request(params: object, drive: object, targets: object, cycles: object,
                   feed: object, acceleration: object, dwell: object, overshoot: object,
                   options: object, progress: object, warm_up: object = 0) -> SolverOptions:
    """Refuse, before the cycle or the profile is made, arguments of the wrong kind and a test
    that cannot fit the run: ``cycles=10**5`` built its profile for minutes before the
    ``max_steps`` refusal, ``cycles=1e300`` never returned, ``nan`` and ``5.5`` were refused
    for the wrong reason (an outside check, 2026-12-07).  Returns the solver options the
    budget is checked against.

    The test's length is bounded below without building anything: each of the
    2 × targets × cycles approaches dwells ``dwell`` and is reached by a move of at least
    δ = min(overshoot, the closest targets' gap), which takes at least
    max(δ/feed, 2√(δ/acceleration)).  A length above what the reference holds
    (``MAX_PROFILE_SAMPLES`` at the profile's 1-ms grid) or what ``max_steps`` allows at the
    largest step is refused, naming ``cycles`` (or, at the fewest cycles ISO 230-2 allows, the
    dwell or the feed that makes it so long).
    """
    from ..engine.options import SolverOptions, check_given
    from ..engine.options import current as current_options
    from ..model.reference import MAX_PROFILE_SAMPLES

    if not isinstance(params, DriveParameters):
        raise ParameterError("params", params, "expected a DriveParameters "
                             "(feeddrive.preset(name) or feeddrive.load(path))")
    if not isinstance(drive, str):
        raise ParameterError("drive", drive, "expected the name of a drive, e.g. 'cdfs'")
    check_given(options)
    check_callback("progress", progress, "progress(t, t_end)")
    whole = (f"expected a whole number ≥ {MIN_CYCLES} of approaches per target and "
             "direction [-]")
    if isinstance(cycles, bool) or not isinstance(cycles, int | float | np.integer
                                                  | np.floating):
        raise ParameterError("cycles", cycles, whole)
    try:
        n_cycles = float(cycles)
    except OverflowError:  # an int beyond any float: too long a test, below
        n_cycles = math.inf if cycles > 0 else -math.inf
    if n_cycles != math.inf and not (math.isfinite(n_cycles) and n_cycles.is_integer()):
        raise ParameterError("cycles", cycles, whole)
    if (isinstance(warm_up, bool) or not isinstance(warm_up, int | np.integer)
            or not 0 <= warm_up <= MAX_WARM_UP):
        raise ParameterError("warm_up", warm_up, f"expected a whole number 0 … {MAX_WARM_UP} "
                             "of passes [-]")
    feed_ = _number("feed", feed, "m/s")
    acc = _number("acceleration", acceleration, "m/s²")
    dwell_ = _number("dwell", dwell, "s")
    over = _number("overshoot", overshoot, "m")
    try:
        p = np.asarray(targets, dtype=float)
    except (TypeError, ValueError, OverflowError):
        p = np.full(1, np.nan)
    if p.ndim != 1 or p.size < 2 or not np.all(np.isfinite(p)) or np.any(np.diff(p) <= 0):
        raise ParameterError("targets", targets, "expected at least 2 increasing positions [m]")
    solver = options if options is not None else current_options()
    assert isinstance(solver, SolverOptions)
    if n_cycles < MIN_CYCLES:
        return solver  # refused by positioning_cycle, with the standard's reason
    # the shortest the test can last [s]
    gap = min(over, float(np.min(np.diff(p))))
    move = max(gap / feed_, 2.0 * math.sqrt(gap / acc))
    approaches = 2 * p.size
    interval = 1e-3  # [s] stops_profile's grid
    holds = MAX_PROFILE_SAMPLES * interval
    allows = solver.max_steps * solver.largest_step
    longest = min(holds, allows)
    per_cycle = approaches * (dwell_ + move)
    shortest = (n_cycles + int(warm_up)) * per_cycle
    if shortest <= longest:
        return solver
    why = (f"longer than the {holds:g} s its reference holds ({MAX_PROFILE_SAMPLES} samples "
           f"of {interval * 1e3:g} ms)" if holds <= allows else
           f"longer than max_steps = {solver.max_steps:.3g} solver steps allow at the largest "
           f"step {solver.largest_step:g} s ({allows:.4g} s)")
    passes = (f" and {int(warm_up)} warm-up pass{'es' if warm_up != 1 else ''}"
              if warm_up else "")
    said = (f"{p.size} targets × {n_cycles:g} cycles × 2 directions{passes} last at least "
            f"{shortest:.4g} s (each approach a dwell of {dwell_:g} s and a move of at least "
            f"{move:.3g} s), {why}")
    most = math.floor(longest / per_cycle) - int(warm_up)
    if most >= MIN_CYCLES:
        raise ParameterError("cycles", cycles, f"expected ≤ {most} [-]: {said}")
    if dwell_ >= move:
        raise ParameterError("dwell", dwell, f"expected a shorter dwell [s], or fewer targets: "
                             f"{said}")
    raise ParameterError("feed", feed, f"expected a higher feed [m/s], or fewer targets: {said}")


def run_positioning_test(params: DriveParameters, drive: str, targets: Sequence[float], *,
                         cycles: int = 5, kind: str = "linear", feed: float = 0.01,
                         acceleration: float = 0.5, dwell: float = 1.0,
                         overshoot: float = 2e-3, warm_up: int = WARM_UP,
                         options: SolverOptions | None = None,
                         progress: Callable[[float, float], None] | None = None
                         ) -> PositioningRun:
    """Simulate an ISO 230-2 test of one axis and evaluate it.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    drive : str
        Any registered drive.
    targets : sequence of float
        Target positions on the axis, increasing [m].
    cycles : int, default 5
        Approaches per target and direction (at least 5).
    kind : str, default "linear"
        The test cycle, ``"linear"`` or ``"pilgrim"``.
    feed : float, default 0.01
        Speed of the moves [m/s].
    acceleration : float, default 0.5
        Acceleration of the moves [m/s²].
    dwell : float, default 1.0
        Rest at each stop; the position is read over its last quarter [s].
    overshoot : float, default 2e-3
        How far beyond a target the axis reverses [m].
    warm_up : int, default 1 (:data:`WARM_UP`)
        Linear passes over the targets run before the test and not read
        (:func:`warm_up_stops`), so that the first cycle's approaches come with the same
        history as the later ones; 0 starts the test at rest with friction and loop integrals
        unloaded, which alone moves the first approach of P_1 (by 0.14 µm of the 0.26-µm
        repeatability on ``wang2021``'s CDFS at a 2-s dwell).
    options : SolverOptions, optional
        Integrator settings.
    progress : callable, optional
        ``progress(t, t_end)`` during the run.

    Returns
    -------
    PositioningRun
        The quantities, the cycle and the simulation.

    Raises
    ------
    ParameterError
        Before the run: fewer than 5 cycles or not a whole number of them, a stop outside the
        travel, a feed beyond :func:`axis_speed_limit`, a test longer than the solver's step
        limit allows or its reference holds (refused before the cycle is laid out), or bad
        settings.
    """
    from ..engine.budget import run_budget
    from ..engine.simulate import DriveSystem, simulate
    from ..model.mechanisms.base import start_position
    from ..model.positioning_profile import stops_profile

    solver = _check_request(params, drive, targets, cycles, feed, acceleration, dwell,
                            overshoot, options, progress, warm_up)
    stops = positioning_cycle(targets, cycles, kind=kind, overshoot=overshoot)
    stops = [*warm_up_stops(targets, warm_up, overshoot), *stops]
    limit, why = axis_speed_limit(params, drive)
    if feed > limit:
        raise ParameterError("feed", feed, f"expected ≤ {limit * 1e3:.6g} mm/s, the axis's "
                             f"speed limit ({why})")
    travel = axis_travel(params, drive)
    if travel is not None:
        length, path = travel
        low = min(s.position for s in stops)
        high = max(s.position for s in stops)
        if not (low > 0.0 and high < length):
            raise ParameterError("targets", [float(p) for p in targets],
                                 f"the test reaches {low * 1e3:.6g} … {high * 1e3:.6g} mm "
                                 "(targets ∓ the overshoot); expected within the travel 0 … "
                                 f"{length * 1e3:.6g} mm ({path})")
    start = stops[0].position
    profile, ends = stops_profile([s.position - start for s in stops[1:]], feed=feed,
                                  acceleration=acceleration, dwell=dwell)
    duration = float(profile.time[-1])
    budget = run_budget(duration, max_step=solver.largest_step,
                        output_interval=solver.output_interval, max_steps=solver.max_steps)
    if budget.steps_exceeded:
        raise ParameterError("max_steps", solver.max_steps,
                             f"the test lasts {duration:.6g} s and needs at least "
                             f"{budget.min_steps:.3g} solver steps; fewer targets or cycles, a "
                             "shorter dwell or a higher feed, or raise --max-steps")
    # the first stop is where a ball screw's nut starts; another drive's model does not read
    # it (and refuses a value other than its default)
    system = DriveSystem(params, drive=drive, table_position=start_position(drive, start))
    result = simulate(system, profile, duration, options=options, progress=progress)
    measured = list(stops[1:])
    up, down = read_approaches(result.time, start + np.asarray(result["table_position"]),
                               measured, ends, dwell, targets)
    test = positioning_test(targets, up, down)
    return PositioningRun(test=test, stops=tuple(stops), dwell_ends=ends, start=start,
                          result=result, kind=kind, feed=float(feed),
                          acceleration=float(acceleration), dwell=float(dwell),
                          overshoot=float(overshoot), warm_up=int(warm_up))
