"""The ISO 230-4 circular test run on a simulated machine: circle → two runs → trace →
quantities.  SI.

:func:`run_circular_test` drives two axes of a machine (:mod:`feeddrive.machine`) round a
circle about the axes' start positions, once counter-clockwise and once clockwise, each run
with a lead-in and a lead-out arc (ISO 230-4:2005 test procedure: the data taken over 360°
between arcs that let the feed settle), joins the two runs into one trace (time, x, y) and
evaluates it with :func:`~feeddrive.analysis.circular.circular_test`.  The CCW run starts at
45° − the lead arc and ends where the CW run starts, 45° + the lead arc, so that both runs'
measured revolutions start and end at 45°, halfway between axis reversals, and the trace is
one continuous path.  A request the machine cannot make (a circle beyond an axis' travel, a
feed beyond an axis' speed limit) is refused before any run.

The lead arc is chosen by a stated rule (:func:`settling_lead`) unless it is given: the
lead-in holds the feed ramp and then lasts until the slowest closed-loop mode of the test's
axes, linearised at the circle's feed, has decayed to ``SETTLE_FRACTION`` (0.1 %) of its
start — the start-up transient is then no part of the measured revolution (issue 37: at a
fixed 90° lead the xy-table's G(b) at R = 50 mm, F = 5000 mm/min was mostly the transient's).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..parameters import ParameterError
from ..parameters.validation import MISSING
from .circular import REVERSAL, CircularTest, circular_test, deviations
from .positioning_run import axis_speed_limit, axis_travel

if TYPE_CHECKING:
    from ..engine.options import SolverOptions
    from ..machine import Machine

__all__ = ["SETTLE_FRACTION", "CircularRunTrace", "LeadIn", "UnevaluatedTrace",
           "circular_start_angles", "run_circular_test", "settling_lead"]

#: where each run's measured revolution starts and ends, halfway between reversals [rad]
MEASURE_START = math.radians(45.0)
#: rest after a DDFS nut has reached its speed, before the path starts [s]
NUT_SETTLE = 0.5
#: what is left of the slowest closed-loop mode's start-up transient when the measured
#: revolution starts, by the lead-in rule (:func:`settling_lead`) [-]
SETTLE_FRACTION = 1e-3


@dataclass(frozen=True)
class LeadIn:
    """The lead arc of a circular test and why.

    Parameters
    ----------
    arc : float
        The lead-in arc, equal to the lead-out arc [rad].
    rule_arc : float
        The arc the settling rule gives [rad] (``nan`` when it could not be computed).
    given : bool
        Whether ``arc`` was given (an override) rather than the rule's.
    axis : str
        The axis whose mode is the slowest ("" when not computed).
    decay_rate : float
        That mode's decay rate −Re(s) [1/s].
    frequency : float
        That mode's frequency |Im(s)|/2π [Hz].
    fraction : float
        ``SETTLE_FRACTION`` [-].
    notes : tuple of str
        What the linearisation left out.
    """

    arc: float
    rule_arc: float
    given: bool
    axis: str = ""
    decay_rate: float = math.nan
    frequency: float = math.nan
    fraction: float = SETTLE_FRACTION
    notes: tuple[str, ...] = ()

    def describe(self) -> str:
        """One line stating the lead arc and the rule's choice (summary, record, report).

        Returns
        -------
        str
            The line.
        """
        how = (f"the feed ramp, then the slowest closed-loop mode (axis {self.axis}, "
               f"{self.frequency:.3g} Hz, decaying at {self.decay_rate:.3g} 1/s) down to "
               f"{self.fraction:.1%}")
        arc = f"lead arcs {math.degrees(self.arc):.4g}°"
        if not self.given:
            return f"{arc} by the settling rule: {how}"
        if not math.isfinite(self.rule_arc):
            return f"{arc} as given (the settling rule not computed)"
        return f"{arc} as given (the settling rule's {math.degrees(self.rule_arc):.4g}°: {how})"

    def to_dict(self) -> dict[str, Any]:
        """The JSON form [°, 1/s, Hz]; what the rule could not compute is null.

        Returns
        -------
        dict
            The lead in, JSON-ready.
        """
        def known(x: float) -> float | None:
            return x if math.isfinite(x) else None

        return {"lead_arc_deg": math.degrees(self.arc), "given": self.given,
                "rule_lead_arc_deg": known(math.degrees(self.rule_arc)),
                "slowest_mode_axis": self.axis or None,
                "slowest_mode_decay_1_s": known(self.decay_rate),
                "slowest_mode_frequency_hz": known(self.frequency),
                "settle_fraction": self.fraction, "notes": list(self.notes)}


def circular_start_angles(lead_arc: float) -> dict[str, float]:
    """The start angle of each run about the centre for a lead arc.

    Parameters
    ----------
    lead_arc : float
        The lead-in arc, equal to the lead-out arc [rad].

    Returns
    -------
    dict
        ``"CCW"`` and ``"CW"`` → start angle [rad]; the CCW run ends where the CW run starts.
    """
    return {"CCW": MEASURE_START - lead_arc, "CW": MEASURE_START + lead_arc}


class UnevaluatedTrace(ValueError):
    """The runs were simulated but their trace has no full revolution to evaluate: the
    message says why; ``time``, ``x``, ``y`` [s, m] hold the trace (``--output`` writes it
    all the same).

    Parameters
    ----------
    message : str
        Why the trace was not evaluated.
    time : numpy.ndarray
        The joined trace's times [s].
    x, y : numpy.ndarray
        The two axes' positions [m].
    """

    def __init__(self, message: str, time: np.ndarray, x: np.ndarray, y: np.ndarray) -> None:
        super().__init__(message)
        self.time, self.x, self.y = time, x, y


@dataclass(frozen=True, repr=False)
class CircularRunTrace:
    """A simulated circular test.

    Parameters
    ----------
    test : CircularTest
        The ISO 230-4 quantities and the diagnostics.
    time : numpy.ndarray
        The joined trace's times, CCW run then CW run [s].
    x, y : numpy.ndarray
        The two axes' positions on the machine (the axes' ``table_position`` frame) [m].
    axes : tuple of str
        The machine axes used as X and Y.
    centre : tuple of float
        The circle's centre [m].
    radius, feed, acceleration, lead_arc : float
        The test's settings [m, m/s, m/s², rad].
    nut_speed : float
        The DDFS axes' nut speed [m/s] (0: none).
    start_time : float
        When the path starts in each run (after the nuts' spin-up) [s].
    results : dict
        ``"CCW"`` and ``"CW"`` → the machine's simulation of that run.
    offsets : dict
        ``"CCW"`` and ``"CW"`` → where that run's time 0 lies in the joined trace [s].
    lead_in : LeadIn, optional
        The lead arc, whether given, and the settling rule's choice beside it.
    """

    test: CircularTest
    time: np.ndarray
    x: np.ndarray
    y: np.ndarray
    axes: tuple[str, str]
    centre: tuple[float, float]
    radius: float
    feed: float
    acceleration: float
    lead_arc: float
    nut_speed: float
    start_time: float
    results: dict[str, Any]
    offsets: dict[str, float] = dataclasses.field(default_factory=dict)
    lead_in: LeadIn | None = None

    def __repr__(self) -> str:
        # one line: the dataclass' repr printed the trace's arrays and each run's Result, and
        # raised on those (an outside check, 2026-12-07)
        machine = next((str(r.attrs.get("machine", r.attrs.get("drive", "")))
                        for r in self.results.values() if hasattr(r, "attrs")), "")
        return (f"<feeddrive CircularRunTrace {machine + ' ' if machine else ''}"
                f"{','.join(self.axes)} R {self.radius * 1e3:.6g} mm, feed "
                f"{self.feed * 6e4:.6g} mm/min: {deviations(self.test)}>")

    def reversing_sites(self) -> dict[str, dict[str, int]]:
        """How often each friction site's force changes sign within the measured revolutions.

        A friction force changes sign when its site's sliding speed reverses: in a CDFS every
        site reverses with the table, in a DDFS whose nut runs faster than the table only the
        sites sliding at the table's speed (the guide, and the ball–nut share at the relative
        screw–nut speed) do.

        Returns
        -------
        dict
            Axis → site (``screw``, ``nut``, ``guide`` …) → sign changes over both runs'
            measured revolutions [-].
        """
        out: dict[str, dict[str, int]] = {}
        for run in self.test.runs:
            result = self.results[run.direction]
            t = np.asarray(result.time, dtype=float) + self.offsets[run.direction]
            inside = (t >= run.time[0]) & (t <= run.time[-1])
            for name in self.axes:
                prefix = f"{name}."
                for var in result.signal_names():  # no Dataset built to read names
                    if not (var.startswith(prefix) and var.endswith("_friction")):
                        continue
                    force = np.asarray(result[var], dtype=float)[inside]
                    sign = np.sign(force[force != 0.0])
                    site = var[len(prefix):-len("_friction")]
                    changes = int(np.count_nonzero(np.diff(sign)))
                    out.setdefault(name, {})[site] = out.get(name, {}).get(site, 0) + changes
        return out


def _continuous_loops(params: Any) -> tuple[Any, tuple[str, ...]]:
    """The set with continuous loops and exact feedback, for the linearisation; a note when
    its loops were sampled (their 2–8 kHz periods move a few-Hz mode by little)."""
    c = params.controller
    periods = (c.current_period, c.velocity_period, c.position_period)
    if not any(periods):
        return params, ()
    flat = params.replace_path("controller", c.with_values(
        current_period=0.0, velocity_period=0.0, position_period=0.0, encoder_counts=0.0,
        grating_resolution=0.0))
    return flat, ("sampled loops linearised as continuous loops with exact feedback",)


def _slowest_mode(axis: Any, speed: float, nut_speed: float
                  ) -> tuple[float, float, tuple[str, ...]]:
    """The axis' rightmost closed-loop pole at steady sliding at ``speed``: (decay rate
    [1/s], frequency [Hz], notes).  Parts that act at sampled instants only (a disturbance
    observer, a reset integrator) refuse continuous loops: the loops are linearised without
    the parts beyond the mechanism kind's own, and a note names them."""
    from ..engine.simulate import DriveSystem
    from ..parameters import composition
    from .linear import rightmost_pole

    params, notes = _continuous_loops(axis.parameters)

    def pole(p: Any) -> tuple[float, float]:
        return rightmost_pole(DriveSystem(p, axis.drive, axis.table_position, axis.nut_hold),
                              speed, nut_speed)

    try:
        real, frequency = pole(params)
    except ParameterError:
        own = set(composition(params.mechanism).order())
        extra = tuple(name for name, _ in params.sections if name not in own)
        if not extra:
            raise
        kept = tuple((k, v) for k, v in params.sections if k in own)
        real, frequency = pole(dataclasses.replace(params, sections=kept))
        notes += (f"axis {axis.name} linearised without {', '.join(extra)} (sampled "
                  "instants only)",)
    return -real, frequency, notes


def settling_lead(machine: Machine, axes: tuple[str, str], *, radius: float, feed: float,
                  acceleration: float, nut_speed: float = 0.0,
                  fraction: float = SETTLE_FRACTION) -> LeadIn:
    """The lead arc by the settling rule: the feed ramp, then the time in which the slowest
    closed-loop mode of the two axes decays to ``fraction`` of its start.

    ``arc = (F²/2a + F·ln(1/fraction)/σ) / R``, with σ the smallest decay rate −Re(s) of the
    rightmost pole of either axis' closed loop linearised at steady sliding at the feed F
    (:func:`~feeddrive.analysis.linear.rightmost_pole`, friction included; a DDFS axis at its
    nut speed).  Its coupling parts are left out; sampled loops are linearised as continuous.
    ISO 230-4:2005 asks that the data be taken over 360° between arcs that let the feed
    settle and names no length; this makes "settle" a stated quantity.

    Parameters
    ----------
    machine : Machine
        The machine.
    axes : tuple of str
        The test's X and Y axes.
    radius, feed, acceleration : float
        R [m], F [m/s], the ramp's a [m/s²].
    nut_speed : float, default 0.0
        The DDFS axes' nut speed [m/s].
    fraction : float, default SETTLE_FRACTION
        What is left of the mode's start when the measured revolution starts [-].

    Returns
    -------
    LeadIn
        The rule's arc, the mode it rests on, the notes.

    Raises
    ------
    ParameterError
        When the slowest mode does not decay (an axis unstable at the feed): no lead-in lets
        it settle; give the lead arc.
    """
    nut_driven = _nut_driven(machine, axes, nut_speed)
    slowest: tuple[float, float, str] | None = None
    notes: tuple[str, ...] = ()
    for name in axes:
        ax = machine.axis(name)
        rate, frequency, said = _slowest_mode(ax, feed, nut_speed if name in nut_driven
                                              else 0.0)
        notes += tuple(n for n in said if n not in notes)
        if slowest is None or rate < slowest[0]:
            slowest = (rate, frequency, name)
    assert slowest is not None
    rate, frequency, name = slowest
    if not rate > 0.0:
        raise ParameterError("lead_arc", MISSING, f"axis {name}'s closed loop at the feed "
                             f"{feed * 6e4:.6g} mm/min has a pole at {-rate:.3g} 1/s "
                             f"({frequency:.3g} Hz) that does not decay; no lead-in lets it "
                             "settle; expected the lead arc given")
    settle = feed * math.log(1.0 / fraction) / rate
    arc = (feed ** 2 / (2.0 * acceleration) + settle) / radius
    return LeadIn(arc=arc, rule_arc=arc, given=False, axis=name, decay_rate=rate,
                  frequency=frequency, fraction=fraction, notes=notes)


def _check_request(machine: Machine, axes: tuple[str, str], centre: tuple[float, float],
                   radius: float, feed: float) -> None:
    for name, c in zip(axes, centre, strict=True):
        ax = machine.axis(name)
        limit, why = axis_speed_limit(ax.parameters, ax.drive)
        if feed > limit:
            raise ParameterError("feed", feed, f"expected ≤ {limit * 6e4:.6g} mm/min, axis "
                                 f"{name}'s speed limit ({why})")
        travel = axis_travel(ax.parameters, ax.drive)
        if travel is None:
            continue
        length, path = travel
        if not (c - radius > 0.0 and c + radius < length):
            raise ParameterError("radius", radius, f"axis {name} would run {(c - radius) * 1e3:.6g}"
                                 f" … {(c + radius) * 1e3:.6g} mm about its centre "
                                 f"{c * 1e3:.6g} mm; expected within its travel 0 … "
                                 f"{length * 1e3:.6g} mm ({name}.{path})")


def _nut_driven(machine: Machine, axes: tuple[str, str], nut_speed: float) -> tuple[str, ...]:
    """The axes whose nut follows ``nut_speed`` (a DDFS); refused when there is none."""
    from ..model.mechanisms import mechanism

    if not (isinstance(nut_speed, int | float) and math.isfinite(nut_speed) and nut_speed >= 0):
        raise ParameterError("nut_speed", nut_speed, "expected a speed ≥ 0 [m/s]")
    if nut_speed == 0.0:
        return ()
    driven = tuple(name for name in axes
                   if "nut" in mechanism(machine.axis(name).drive)
                   .followed_references(machine.axis(name).drive))
    if not driven:
        raise ParameterError("nut_speed", nut_speed, "no axis of the test drives its nut (a "
                             "DDFS); expected 0")
    return driven


def _profile(machine: Machine, contour: Any, nut_driven: tuple[str, ...], nut_speed: float,
             acceleration: float, start_time: float) -> Any:
    """The contour's references, after a rest of ``start_time`` in which the nuts spin up."""
    from ..machine import MachineProfile
    from ..model.reference import SampledSpeed

    profile = MachineProfile.from_contour(contour, machine)
    if not nut_driven:
        return profile
    step = float(profile.time[1] - profile.time[0])
    before = int(round(start_time / step))
    t = np.arange(before + profile.time.size) * step
    rest = np.zeros(before)
    vn = np.minimum(acceleration * t, nut_speed)
    axes = tuple((name, SampledSpeed(time=t, table_speed=np.concatenate([rest, r.table_speed]),
                                     nut_speed=vn if name in nut_driven else None))
                 for name, r in profile.axes)
    return MachineProfile(time=t, table_speed=np.concatenate([rest, profile.table_speed]),
                          axes=axes, contour=contour)


def _check_length(duration: float, arc: float, feed: float, start_time: float) -> None:
    """Refuse, naming the feed in both units, a run longer than a machine run's references
    hold (:data:`feeddrive.machine.contour.MAX_REFERENCE_SAMPLES` at its grid); ``arc`` is
    the path's turns × R [m].  It was refused as ``contour.duration``, an option ``circular``
    does not have (an outside check, 2026-12-07)."""
    from ..machine.contour import INTERVAL, MAX_REFERENCE_SAMPLES

    longest = MAX_REFERENCE_SAMPLES * INTERVAL
    if duration <= longest:
        return
    lowest = 2.0 * math.pi * arc / max(longest - start_time, 1e-9)
    raise ParameterError("feed", feed, f"each run would last {duration:.4g} s, longer than "
                         f"the {longest:g} s a machine run's references hold (a "
                         f"{INTERVAL * 1e3:g}-ms grid); expected a feed of at least about "
                         f"{lowest * 6e4:.4g} mm/min ({lowest:.3g} m/s) at this radius, or a "
                         "smaller radius")


def _check_budget(duration: float, options: SolverOptions | None) -> None:
    from ..engine.budget import check_output_memory, run_budget
    from ..engine.options import current

    solver = options if options is not None else current()
    budget = run_budget(duration, max_step=solver.largest_step,
                        output_interval=solver.output_interval, max_steps=solver.max_steps)
    if budget.steps_exceeded:
        raise ParameterError("max_steps", solver.max_steps,
                             f"each run lasts {duration:.6g} s and needs at least "
                             f"{budget.min_steps:.3g} solver steps; a smaller radius or a "
                             "higher feed, or raise --max-steps")
    check_output_memory(2.0 * duration, solver.output_interval, options=solver)


def _lead_in(machine: Machine, axes: tuple[str, str], radius: float, feed: float,
             acceleration: float, nut_speed: float, given: float | None) -> LeadIn:
    """The rule's lead arc, or the one given with the rule's stated beside it."""
    try:
        rule = settling_lead(machine, axes, radius=radius, feed=feed,
                             acceleration=acceleration, nut_speed=nut_speed)
    except (ParameterError, ValueError) as err:  # a given arc does not need the rule
        if given is None:
            raise
        said = err.message if isinstance(err, ParameterError) else str(err)
        # the arc was given: the refusal's advice to give one is not repeated to the user who
        # did (an outside check, 2026-12-07)
        said = said.removesuffix("; expected the lead arc given")
        return LeadIn(arc=float(given), rule_arc=math.nan, given=True,
                      notes=(f"the settling rule gives no arc: {said}",))
    if given is None:
        return rule
    return dataclasses.replace(rule, arc=float(given), given=True)


def _progress_of_runs(progress: Callable[[float, float], None] | None, before: float,
                      left: int) -> Callable[[float, float], None] | None:
    """A run's ``progress(t, t_end)`` as a share of the test's equally long runs: ``t``
    after the runs ``before`` it [s], out of ``before`` and the ``left`` runs, this one
    included, each as long as it (the bar went to each run's end and started again: an
    outside check, 2026-12-07)."""
    if progress is None:
        return None

    def advance(t: float, t_end: float) -> None:
        progress(before + t, before + left * t_end)

    return advance


def run_circular_test(machine: Machine, *, radius: float, feed: float,
                      axes: tuple[str, str] | None = None, acceleration: float = 1.0,
                      lead_arc: float | None = None, nut_speed: float = 0.0,
                      pitch: float | None = None, reversal: float = REVERSAL,
                      options: SolverOptions | None = None,
                      progress: Callable[[float, float], None] | None = None
                      ) -> CircularRunTrace:
    """Simulate an ISO 230-4 circular test (CCW then CW) on two axes of a machine.

    Parameters
    ----------
    machine : Machine
        The machine; the circle's centre is at its two axes' ``table_position``.
    radius : float
        R [m].
    feed : float
        Path feed F [m/s].
    axes : tuple of str, optional
        The machine axes used as X and Y; default its first two.
    acceleration : float, default 1.0
        Tangential acceleration of the lead-in and lead-out ramps [m/s²].
    lead_arc : float, optional
        The lead-in arc and the lead-out arc of each run [rad], an override of the settling
        rule's (:func:`settling_lead`, the default); the feed ramp must end within it.
    nut_speed : float, default 0.0
        Speed of the nut of every axis that drives its nut (the DDFS) [m/s]: it rises at
        ``acceleration`` from rest and runs ``NUT_SETTLE`` (0.5) s at speed before the path
        starts, and keeps its speed to the end (the table moves at the screw's speed minus the
        nut's, Wang2021 Sect. 2).
    pitch : float, optional
        Period of the cyclic error looked for [m].
    reversal : float, default ``feeddrive.analysis.circular.REVERSAL`` (1°)
        Smallest turn back of the path's angle that ends a run [rad]; smaller ones
        (stick-slip at a low feed) stay in their run
        (:func:`~feeddrive.analysis.circular.split_runs`).
    options : SolverOptions, optional
        Integrator settings.
    progress : callable, optional
        ``progress(t, t_end)`` during the runs: ``t`` over both, the CW run's after the CCW
        run's, ``t_end`` the two runs' total [s] (they are equally long).

    Returns
    -------
    CircularRunTrace
        The quantities, the joined trace and both runs' simulations.

    Raises
    ------
    ParameterError
        Before any run: a machine with fewer than two axes or an unknown axis, a circle beyond
        an axis' travel, a feed beyond an axis' speed limit
        (:func:`~feeddrive.analysis.positioning_run.axis_speed_limit`), a lead arc given
        shorter than the feed ramp, a nut speed with no axis that drives its nut,
        runs needing more solver steps than the
        options allow.
    UnevaluatedTrace
        After the runs, when their trace turned less than 360° one way (it carries the
        trace).
    """
    from ..machine import Circle, simulate_machine
    from ..model.mechanisms.base import start_position

    if axes is None:
        if len(machine.axes) < 2:
            raise ParameterError("axes", [a.name for a in machine.axes],
                                 "a circular test needs two axes")
        axes = (machine.axes[0].name, machine.axes[1].name)
    if len(axes) != 2 or axes[0] == axes[1]:
        raise ParameterError("axes", list(axes), "expected two different axes, e.g. x,y")
    for value, name, unit in ((radius, "radius", "m"), (feed, "feed", "m/s"),
                              (acceleration, "acceleration", "m/s²"),
                              (1.0 if lead_arc is None else lead_arc, "lead_arc", "rad")):
        if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
            raise ParameterError(name, value, f"expected a value > 0 [{unit}]")
    centre = (machine.axis(axes[0]).table_position, machine.axis(axes[1]).table_position)
    _check_request(machine, axes, centre, radius, feed)
    nut_driven = _nut_driven(machine, axes, nut_speed)
    start_time = nut_speed / acceleration + NUT_SETTLE if nut_driven else 0.0
    lead = _lead_in(machine, (axes[0], axes[1]), radius, feed, acceleration, nut_speed,
                    lead_arc)
    lead_arc = lead.arc
    ramp = feed ** 2 / (2.0 * acceleration)
    if ramp >= radius * lead_arc:
        raise ParameterError("lead_arc", lead_arc, f"the feed ramp F²/2a = {ramp * 1e3:.6g} mm"
                             f" does not end within the lead arc R·{math.degrees(lead_arc):g}° ="
                             f" {radius * lead_arc * 1e3:.6g} mm; expected a longer lead arc or "
                             "a higher acceleration")
    turns = 1.0 + lead_arc / math.pi
    duration = start_time + 2.0 * math.pi * radius * turns / feed + feed / acceleration
    _check_length(duration, radius * turns, feed, start_time)
    _check_budget(duration, options)
    runs = []
    for direction, start in circular_start_angles(lead_arc).items():
        # each run's axes start at rest on the circle at its start angle
        start_xy = (centre[0] + radius * math.cos(start), centre[1] + radius * math.sin(start))
        # (a ball screw's nut starts there; another drive's model does not read its start,
        # and its axis refuses one other than the default)
        placed = dataclasses.replace(machine, axes=tuple(
            dataclasses.replace(ax, table_position=start_position(
                ax.drive, start_xy[axes.index(ax.name)])) if ax.name in axes else ax
            for ax in machine.axes))
        contour = Circle(feed=feed, acceleration=acceleration, axes=axes, radius=radius,
                         clockwise=direction == "CW", start_angle=start, turns=turns)
        runs.append((direction, start_xy, placed, _profile(placed, contour, nut_driven,
                                                           nut_speed, acceleration,
                                                           start_time)))
    times, xs, ys, results, offsets = [], [], [], {}, {}
    offset = 0.0
    done = 0.0  # the runs' simulated time so far, for the progress [s]
    for k, (direction, start_xy, placed, profile) in enumerate(runs):
        # (progress was taken and never passed on: an outside check, 2026-12-07)
        result = simulate_machine(placed, profile, options=options,
                                  progress=_progress_of_runs(progress, done, len(runs) - k))
        results[direction] = result
        offsets[direction] = offset
        t = np.asarray(result.time, dtype=float)
        done += float(t[-1])
        times.append(t + offset)
        xs.append(start_xy[0] + np.asarray(result[f"{axes[0]}.table_position"], dtype=float))
        ys.append(start_xy[1] + np.asarray(result[f"{axes[1]}.table_position"], dtype=float))
        # the CW run follows the CCW run one output interval after its end
        offset += float(t[-1]) + float(t[1] - t[0])
    # the trace as a record holds it (mm, 17 digits: read back exactly, io.acceptance)
    time = np.concatenate(times)
    x = np.concatenate(xs) * 1e3 * 1e-3
    y = np.concatenate(ys) * 1e3 * 1e-3
    try:
        test = circular_test(time, x, y, radius=radius, centre=centre, pitch=pitch,
                             reversal=reversal)
    except ParameterError:
        raise
    except ValueError as err:  # said of the simulated runs, not of a record's columns (it
        # told a `circular` user to "check --centre and the x, y columns": an outside check,
        # 2026-12-07)
        if "no full revolution" not in str(err):
            raise
        # the runs are kept: the error carries their trace (--output writes it)
        why = (str(err).partition(": ")[2] if "reversal angle" in str(err) else
               "a run ends where the path's angle about the centre turns back by more than "
               f"{math.degrees(reversal):.3g}°, the reversal angle")
        raise UnevaluatedTrace(
            "the simulated path did not turn 360° one way about the centre, which the "
            f"ISO 230-4 evaluation needs ({why})", time, x, y) from None
    return CircularRunTrace(test=test, time=time, x=x, y=y, axes=(axes[0], axes[1]),
                            centre=centre, radius=float(radius), feed=float(feed),
                            acceleration=float(acceleration), lead_arc=float(lead_arc),
                            nut_speed=float(nut_speed), start_time=float(start_time),
                            results=results, offsets=offsets, lead_in=lead)
