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
from .positioning import (
    PositioningTest,
    Stop,
    positioning_cycle,
    positioning_test,
    read_approaches,
    reading_motion,
)

if TYPE_CHECKING:
    from ..engine.options import SolverOptions
    from ..engine.result import Result

__all__ = ["PositioningRun", "axis_speed_limit", "axis_travel", "run_positioning_test"]


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

    @property
    def reading_motion(self) -> float:
        """The largest peak-to-peak motion within a reading window [m]
        (:func:`~feeddrive.analysis.positioning.reading_motion`): 0 when every reading is
        taken at rest."""
        return reading_motion(self.result.time, np.asarray(self.result["table_position"]),
                              self.stops[1:], self.dwell_ends, self.dwell)


def run_positioning_test(params: DriveParameters, drive: str, targets: Sequence[float], *,
                         cycles: int = 5, kind: str = "linear", feed: float = 0.01,
                         acceleration: float = 0.5, dwell: float = 1.0,
                         overshoot: float = 2e-3, options: SolverOptions | None = None,
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
        Before the run: fewer than 5 cycles, a stop outside the travel, a feed beyond
        :func:`axis_speed_limit`, a test longer than the solver's step limit allows, or bad
        settings.
    """
    from ..engine.budget import run_budget
    from ..engine.options import current as current_options
    from ..engine.simulate import DriveSystem, simulate
    from ..model.positioning_profile import stops_profile

    stops = positioning_cycle(targets, cycles, kind=kind, overshoot=overshoot)
    if not (math.isfinite(feed) and feed > 0.0):
        raise ParameterError("feed", feed, "expected a speed > 0 [m/s]")
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
    solver = options if options is not None else current_options()
    budget = run_budget(duration, max_step=solver.largest_step,
                        output_interval=solver.output_interval, max_steps=solver.max_steps)
    if budget.steps_exceeded:
        raise ParameterError("max_steps", solver.max_steps,
                             f"the test lasts {duration:.6g} s and needs at least "
                             f"{budget.min_steps:.3g} solver steps; fewer targets or cycles, a "
                             "shorter dwell or a higher feed, or raise --max-steps")
    system = DriveSystem(params, drive=drive, table_position=start)
    result = simulate(system, profile, duration, options=options, progress=progress)
    measured = list(stops[1:])
    up, down = read_approaches(result.time, start + np.asarray(result["table_position"]),
                               measured, ends, dwell, targets)
    test = positioning_test(targets, up, down)
    return PositioningRun(test=test, stops=tuple(stops), dwell_ends=ends, start=start,
                          result=result, kind=kind, feed=float(feed),
                          acceleration=float(acceleration), dwell=float(dwell),
                          overshoot=float(overshoot))
