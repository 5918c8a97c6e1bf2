"""Critical creeping speed and creeping bands.  SI units.

Every trial is judged by :func:`feeddrive.analysis.cycle_verdict.trace_verdict` and runs until
its outcome is decided (:class:`~feeddrive.analysis.cycle_verdict.VerdictRule`): the speed settles
within a band around the command (``smooth``), or the oscillation repeats as a limit cycle
(``stick-slip`` when the table stops, ``oscillation`` when it never does).  A trial still
undecided at the rule's maximum duration answers ``undecided``; it is never guessed.

Two protocols, because the answer can depend on how the table got to its speed (a friction
limit cycle can persist above the speed where steady sliding turns stable):

* **from rest** (``start="rest"``): every trial starts the table from rest with a short ramp.
  A coarse scan classifies a grid of speeds from the range's bottom to its top, both tested
  (the last step shorter when the range is not a whole number of coarse steps); wherever
  neighbouring speeds differ in kind (smooth, stick-slip, oscillation) the boundary is
  bisected to ``resolution`` (0.01 mm/s by default).  Every creeping interval found is
  reported as a band.
* **step-down from a running table** (``start="running"``), the paper's experimental protocol
  (Wang2021 Sect. 6): one continuous run that starts at the top speed and steps the command
  down, dwelling at each speed until the step is decided.  A coarse staircase walks the whole
  range, its top and bottom both held (the step next to the top shorter when the range is
  not a whole number of coarse steps); at each change of kind a fine staircase repeats the
  same history down to the coarse step above it and then walks down 0.01 mm/s at a time to
  the coarse speed below (its last step shorter when the gap is not a whole number of fine
  steps: ``protocol.fine_staircase``).

The critical speed reported is the upper edge of the highest creeping band: the lowest tested
speed above it, which is smooth (status ``found``).  If a trial above that band is undecided,
so is the critical speed (status ``undecided``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from .. import units
from ..engine.budget import setting_field
from ..engine.error_estimate import estimate_kind
from ..engine.options import check_given
from ..engine.simulate import DriveSystem, Simulation, SolverOptions, run_options
from ..model.reference import ConstantSpeed, _staircase
from ..parameters import ParameterError
from ..parameters.validation import check_callback, check_speed, mm_s_hint
from . import protocol
from .cycle_verdict import TraceVerdict, VerdictRule, trace_verdict
from .verdict_words import CREEPING_KINDS, NON_SMOOTH, SMOOTH, STICK_SLIP, UNDECIDED, UNSTABLE

MM_S = units.MM_PER_S

# a trial whose run diverged (stopped early, feeddrive.engine.simulate.DIVERGENCE_SPEED_RATIO)
# has the kind UNSTABLE: not smooth, not a limit cycle either

#: a trace runner for :func:`decide`: duration [s] → (time [s], speed [m/s])
Runner = Callable[[float], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class CreepTrial:
    """One tested speed [m/s] and its verdict (:class:`~.metrics.TraceVerdict`).

    ``duration`` [s]: the simulated length that decided it (the maximum when undecided);
    ``decided_at`` [s]: when, within it, the outcome was first decided.

    Parameters
    ----------
    speed : float
        Commanded table speed [m/s].
    kind : str
        One of ``KINDS``: ``"stick-slip"``, ``"oscillation"``, ``"smooth"``, ``"undecided"``.
    ripple_ratio : float
        Peak-to-peak speed ripple over the command [-].
    stick_fraction : float
        Fraction of the judged stretch the table is stuck (below the stick level) [-].
    stick_slip_frequency : float or None
        Frequency of the limit cycle [Hz].
    min_ratio : float, default nan
        Smallest speed along the motion over the command [-].
    duration : float, default 0.0
        Simulated length that decided it [s].
    decided_at : float, optional
        When the outcome was first decided [s].
    speed_error : float, optional
        The run's largest table-speed integration error when it was estimated [m/s]: the
        shadow estimate (the difference to the same trial run with every tolerance
        ``SHADOW_FACTOR`` times tighter, :mod:`feeddrive.engine.error_estimate`; a search
        makes it for the trials that decide its critical speed) or the embedded one
        (:mod:`feeddrive.solvers.global_error`, carried along the trial).
    """

    speed: float
    kind: str
    ripple_ratio: float
    stick_fraction: float
    stick_slip_frequency: float | None
    min_ratio: float = math.nan
    duration: float = 0.0
    decided_at: float | None = None
    speed_error: float | None = None

    @property
    def creeping(self) -> bool:
        """Whether the kind is a creeping one (stick-slip or oscillation)."""
        return self.kind in CREEPING_KINDS

    @classmethod
    def from_verdict(cls, speed: float, v: TraceVerdict, duration: float) -> CreepTrial:
        """A trial from a trace verdict.

        Parameters
        ----------
        speed : float
            Commanded table speed [m/s].
        v : TraceVerdict
            The verdict (:func:`~feeddrive.analysis.metrics.trace_verdict`).
        duration : float
            Simulated length that decided it [s].

        Returns
        -------
        CreepTrial
            The trial.
        """
        return cls(speed=speed, kind=v.kind, ripple_ratio=v.ripple_ratio,
                   stick_fraction=v.stick_fraction, stick_slip_frequency=v.frequency,
                   min_ratio=v.min_ratio, duration=duration, decided_at=v.decided_at)

    def to_dict(self) -> dict[str, Any]:
        """Speed in mm/s, the rest as stored.

        Returns
        -------
        dict
            The fields, ``speed`` in mm/s, ``speed_error`` as ``speed_error_mm_s`` (only when
            estimated), and ``creeping``.
        """
        out = {**asdict(self), "speed": self.speed / MM_S, "creeping": self.creeping}
        error = out.pop("speed_error")
        if error is not None:
            out["speed_error_mm_s"] = error / MM_S
        return out


@dataclass(frozen=True)
class CreepBand:
    """A run of tested speeds [m/s] with one kind: ``lower``…``upper`` are its lowest and
    highest tested speeds; ``below``/``above`` the nearest tested speeds outside it (None at
    the end of the range) and their kinds.

    Parameters
    ----------
    kind : str
        The band's kind (``"stick-slip"``, ``"oscillation"``, ``"smooth"``).
    lower : float
        Its lowest tested speed [m/s].
    upper : float
        Its highest tested speed [m/s].
    below : float or None
        The nearest tested speed below it [m/s].
    below_kind : str or None
        That speed's kind.
    above : float or None
        The nearest tested speed above it [m/s].
    above_kind : str or None
        That speed's kind.
    """

    kind: str
    lower: float
    upper: float
    below: float | None
    below_kind: str | None
    above: float | None
    above_kind: str | None

    def to_dict(self) -> dict[str, Any]:
        """The band for JSON, speeds in mm/s.

        Returns
        -------
        dict
            ``kind``, ``lower_mm_s``, ``upper_mm_s``, ``below_mm_s``, ``below_kind``,
            ``above_mm_s``, ``above_kind``.
        """
        def mm(v: float | None) -> float | None:
            return None if v is None else round(v / MM_S, 6)
        return {"kind": self.kind, "lower_mm_s": mm(self.lower), "upper_mm_s": mm(self.upper),
                "below_mm_s": mm(self.below), "below_kind": self.below_kind,
                "above_mm_s": mm(self.above), "above_kind": self.above_kind}


def bands_of(trials: Sequence[CreepTrial], *, smooth_too: bool = False) -> tuple[CreepBand, ...]:
    """Maximal runs of one kind among ``trials`` sorted by speed (smooth runs only if
    ``smooth_too``).

    Parameters
    ----------
    trials : sequence of CreepTrial
        The tested speeds.
    smooth_too : bool, default False
        Also return the smooth runs.

    Returns
    -------
    tuple of CreepBand
        The bands, by increasing speed.
    """
    ordered = sorted(trials, key=lambda tr: tr.speed)
    runs: list[list[CreepTrial]] = []
    for tr in ordered:
        if runs and runs[-1][-1].kind == tr.kind:
            runs[-1].append(tr)
        else:
            runs.append([tr])
    out = []
    for i, run in enumerate(runs):
        if run[0].kind == SMOOTH and not smooth_too:
            continue
        below = runs[i - 1][-1] if i > 0 else None
        above = runs[i + 1][0] if i + 1 < len(runs) else None
        out.append(CreepBand(kind=run[0].kind, lower=run[0].speed, upper=run[-1].speed,
                             below=None if below is None else below.speed,
                             below_kind=None if below is None else below.kind,
                             above=None if above is None else above.speed,
                             above_kind=None if above is None else above.kind))
    return tuple(out)


def critical_of(trials: Sequence[CreepTrial]) -> tuple[str, float | None, str | None]:
    """(status, critical speed [m/s], kind of the highest creeping band) of a set of trials.

    Parameters
    ----------
    trials : sequence of CreepTrial
        The tested speeds.

    Returns
    -------
    status : str
        ``"found"``, ``"below-range"`` (smooth everywhere), ``"above-range"`` (creeps
        everywhere) or ``"undecided"``.
    critical_speed : float or None
        The smooth end of the highest creeping band [m/s].
    kind : str or None
        That band's kind.
    """
    ordered = sorted(trials, key=lambda tr: tr.speed)
    creeping = [tr for tr in ordered if tr.kind in NON_SMOOTH]
    top = creeping[-1] if creeping else None
    above = [tr for tr in ordered if top is None or tr.speed > top.speed]
    if any(tr.kind == UNDECIDED for tr in above):
        return UNDECIDED, None, None if top is None else top.kind
    if top is None:
        return "below-range", None, None
    if not above:
        return "above-range", None, top.kind
    return "found", above[0].speed, top.kind


@dataclass(frozen=True)
class CriticalSpeed:
    """Result of a critical-speed search.

    Parameters
    ----------
    drive : str
        The topology searched.
    table_position : float
        Table position a of the trials [m].
    nut_speed : float
        Hollow-motor (nut) speed of the trials [m/s].
    start : str
        ``"rest"`` (every trial from rest) or ``"stepdown"`` (the paper's protocol).
    critical_speed : float or None
        The lowest smooth speed above the highest creeping band [m/s]; None when out of range.
    status : str
        ``"found"``; ``"below-range"`` (smooth at every tested speed: the critical speed is
        below ``speed_range[0]``); ``"above-range"`` (creeps at the top tested speed);
        ``"undecided"`` (a trial above the highest creeping band stayed undecided).
    resolution : float
        Speed resolution of the search [m/s].
    speed_range : tuple of float
        Lowest and highest tested speed [m/s].
    trials : tuple of CreepTrial, default ()
        Every trial with its verdict.
    simulated_time : float, default 0
        Simulated time of all trials [s].
    kind : str or None, default None
        Kind of the highest creeping band (``"stick-slip"`` or ``"oscillation"``).
    bands : tuple of CreepBand, default ()
        Every non-smooth run of tested speeds, with its kind.
    rule : VerdictRule, default VerdictRule()
        The rule that judged the trials.
    error_estimate : str or None, default None
        How the trials' ``speed_error`` was estimated: ``"shadow"`` (the deciding trials run
        again, every tolerance ``SHADOW_FACTOR`` times tighter), ``"embedded"`` (carried along
        every trial) or None (not estimated).
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
    kind: str | None = None
    bands: tuple[CreepBand, ...] = field(default_factory=tuple)
    rule: VerdictRule = field(default_factory=VerdictRule)
    error_estimate: str | None = None

    @property
    def speed_error(self) -> float | None:
        """The integration error the critical speed's runs carried: the larger estimate of the
        table speed's error (``error_estimate``: the shadow or the embedded one; an estimate,
        not a bound) of the trials that decide it
        (:func:`~feeddrive.analysis.critical.deciding_trials`); None when the search made no
        estimate [m/s]."""
        errors = [t.speed_error for t in deciding_trials(self.trials)]
        if not errors or any(e is None for e in errors):
            return None
        return max(e for e in errors if e is not None)

    def __repr__(self) -> str:
        return (f"<feeddrive CriticalSpeed {self.drive} at {1e3 * self.table_position:g} mm, "
                f"v_n {1e3 * self.nut_speed:g} mm/s, from {self.start}: {self.display()}; "
                f"{len(self.trials)} trials, {len(self.bands)} bands; .trials .bands, "
                ".to_dict()>")

    def display(self) -> str:
        """The result in mm/s as a user reads it, with the bound when out of range.

        Returns
        -------
        str
            E.g. ``"1.56 mm/s, oscillation below it"``.
        """
        text = format_critical_speed({
            "critical_speed_mm_s": None if self.critical_speed is None
            else self.critical_speed / MM_S,
            "speed_range_mm_s": [v / MM_S for v in self.speed_range],
            "status": self.status})
        kind = f", {self.kind} below it" if self.kind else ""
        if self.status == "below-range":
            return f"{text} mm/s (smooth at every tested speed)"
        if self.status == "above-range":
            return f"{text} mm/s (creeps at every tested speed{kind})"
        if self.status == UNDECIDED:
            return f"{text} (a trial above the highest creeping band is undecided)"
        return f"{text} mm/s{kind}"

    def to_dict(self) -> dict[str, Any]:
        """The result in engineering units (mm, mm/s) for printing and JSON.

        Returns
        -------
        dict
            Plain values; speeds in mm/s, positions in mm, times in s.
        """
        return {
            "drive": self.drive,
            "table_position_mm": self.table_position * 1e3,
            "nut_speed_mm_s": self.nut_speed / MM_S,
            "start": self.start,
            "critical_speed_mm_s": (None if self.critical_speed is None
                                    else round(self.critical_speed / MM_S, 6)),
            "status": self.status,
            "kind": self.kind,
            "display": self.display(),
            "bands": [b.to_dict() for b in self.bands],
            "resolution_mm_s": self.resolution / MM_S,
            "speed_range_mm_s": [s / MM_S for s in self.speed_range],
            "verdict_rule": self.rule.to_dict(),
            "trials": [t.to_dict() for t in self.trials],
            "simulated_time_s": self.simulated_time,
            **({} if self.speed_error is None
               else {"speed_error_mm_s": self.speed_error / MM_S,
                     "speed_error_method": self.error_estimate}),
        }


def deciding_trials(trials: Sequence[CreepTrial]) -> list[CreepTrial]:
    """The trials (in speed order) that decide a search's critical speed: the top of the
    highest creeping band and the lowest trial above it — or, with no creeping trial, the
    lowest one (the search is below its range); either may be missing at the range's ends.

    Parameters
    ----------
    trials : sequence of CreepTrial
        A search's trials, by rising speed.

    Returns
    -------
    list of CreepTrial
        One or two trials.
    """
    creeping = [t for t in trials if t.kind in NON_SMOOTH]
    top = creeping[-1] if creeping else None
    above = [t for t in trials if top is None or t.speed > top.speed]
    return [t for t in (top, above[0] if above else None) if t is not None]


def format_critical_speed(search: dict[str, Any]) -> str:
    """Critical speed [mm/s] of a search (as :meth:`CriticalSpeed.to_dict` gives it), or the
    bound an out-of-range search gives: "< low" (smooth everywhere), "> high" (creeps
    everywhere), "undecided".

    Parameters
    ----------
    search : dict
        A search's result (:meth:`CriticalSpeed.to_dict`).

    Returns
    -------
    str
        The speed or bound, in mm/s without the unit.
    """
    value = search["critical_speed_mm_s"]
    low, high = search["speed_range_mm_s"]
    if value is not None:
        return f"{value:.2f}"
    if search["status"] == UNDECIDED:
        return UNDECIDED
    return f"< {low:.2f}" if search["status"] == "below-range" else f"> {high:.2f}"


def format_integration_error(search: dict[str, Any]) -> str:
    """What a search's deciding runs carried as integration error (as
    :meth:`CriticalSpeed.to_dict` stores it), written after the speed by the report and
    ``feeddrive creep``: the estimate of their table-speed error (``speed_error_mm_s``,
    :attr:`CriticalSpeed.speed_error`) with how it was made and what it is worth — an
    estimate, not a bound: the measured range of its ratio to the true error (the shadow's
    :data:`feeddrive.engine.error_estimate.SHADOW_RATIO`, the embedded one's
    :data:`feeddrive.solvers.global_error.MEASURED_RATIO`; an entry stored without
    ``speed_error_method`` is an embedded one) — or nothing for a search without it.

    Parameters
    ----------
    search : dict
        A search as ``CriticalSpeed.to_dict`` gives it.

    Returns
    -------
    str
        E.g. ``" [integration error estimated 4.4e-05 mm/s (difference to the deciding
        trials run 10× tighter: 0.8–1.2× the true error)]"``; empty without an estimate.

    Examples
    --------
    >>> shadow = format_integration_error({"speed_error_mm_s": 4.4e-5,
    ...                                    "speed_error_method": "shadow"})
    >>> shadow.startswith(" [integration error estimated 4.4e-05 mm/s (difference")
    True
    >>> shadow.endswith("10× tighter: 0.8–1.2× the true error)]")
    True
    >>> format_integration_error({"speed_error_mm_s": 2.4e-2}).split(" (")[1]
    'embedded estimate: 0.15–200 000× the true error)]'
    >>> format_integration_error({"critical_speed_mm_s": 1.56})
    ''
    """
    from ..engine.error_estimate import RATIOS, SHADOW_FACTOR, ratio_text

    error = search.get("speed_error_mm_s")
    if error is None:
        return ""
    shadow = search.get("speed_error_method") == "shadow"
    worth = ratio_text(RATIOS["shadow" if shadow else "embedded"])
    how = (f"difference to the deciding trials run {SHADOW_FACTOR:g}× tighter" if shadow
           else "embedded estimate")
    return f" [integration error estimated {error:.1e} mm/s ({how}: {worth}× the true error)]"


def format_bands(search: dict[str, Any]) -> str:
    """The creeping bands of a search in mm/s, e.g. "0.25–1.24 stick-slip; 1.25–1.55
    oscillation" ("none" when there is none).

    Parameters
    ----------
    search : dict
        A search's result (:meth:`CriticalSpeed.to_dict`).

    Returns
    -------
    str
        The bands.
    """
    parts = [f"{b['lower_mm_s']:.2f}–{b['upper_mm_s']:.2f} {b['kind']}"
             for b in search.get("bands", [])]
    return "; ".join(parts) if parts else "none"


def check_kinds(system: object, *, rule: object = None, options: object = None,
                progress: object = None) -> None:
    """Refuse, before any trial, a system, rule, options or progress of the wrong kind (they
    failed at the first trial, as an AttributeError from inside: ``options={}`` said
    ``'dict' object has no attribute 'output_interval'``; an outside check, 2026-12-07).  The
    wording is :class:`~feeddrive.engine.simulate.Simulation`'s.

    Parameters
    ----------
    system : DriveSystem
        The drive.
    rule, options, progress : object, optional
        A VerdictRule, SolverOptions and callable, or None.

    Raises
    ------
    ParameterError
        Naming the argument and the kind expected.
    """
    from ..parameters import DriveParameters

    if isinstance(system, DriveParameters) or not callable(getattr(system, "model", None)):
        raise ParameterError("system", type(system).__name__, "expected a DriveSystem, "
                             "e.g. DriveSystem(params, drive='cdfs', table_position=0.4)")
    check_given(options)
    if rule is not None and not isinstance(rule, VerdictRule):
        raise ParameterError("rule", type(rule).__name__, "expected a VerdictRule or None, "
                             "e.g. VerdictRule(max_duration=60.0)")
    check_callback("progress", progress, "progress(done, total)")


def table_speed_limit(system: DriveSystem) -> tuple[float, str]:
    """The largest table speed of ``system``'s axis and what sets it
    (:func:`~feeddrive.analysis.positioning_run.axis_speed_limit`).

    Parameters
    ----------
    system : DriveSystem
        The drive.

    Returns
    -------
    tuple of (float, str)
        The limit [m/s] and what sets it.
    """
    from .positioning_run import axis_speed_limit

    return axis_speed_limit(system.parameters, system.drive)


def speed_pair(name: str, value: object) -> tuple[float, float]:
    """``value`` as (low, high) [m/s]: a pair of finite speeds, 0 < low < high, or a refusal
    naming ``name`` (a scalar said "'float' object is not subscriptable", three speeds were
    taken as two: an outside check, 2026-12-07).

    Parameters
    ----------
    name : str
        The argument (``speed_range``).
    value : object
        What was given [m/s].

    Returns
    -------
    tuple of float
        (low, high) [m/s].
    """
    if isinstance(value, str | bytes) or not isinstance(value, Sequence | np.ndarray) \
            or len(value) != 2:
        raise ParameterError(name, value, "expected a pair (low, high) of speeds [m/s]")
    lo = check_speed(f"{name}[0]", value[0])
    hi = check_speed(f"{name}[1]", value[1])
    if not lo < hi:
        raise ParameterError(name, tuple(value), "expected low < high [m/s]")
    return lo, hi


def check_scan(system: DriveSystem, name: str, shown: object, lo: float, hi: float,
               coarse_step: float, protocol_step: float, span: str = "high − low") -> None:
    """Refuse a search range above the axis's speed limit, or wider than
    ``protocol.MAX_SEARCH_STEPS`` coarse steps — at the step given, or at the protocol's own
    (``protocol_step``) when that is larger: then it is the range that is too wide, not the
    step too fine (``speed_range=(0.02, 3.0)``, in mm/s, blamed ``coarse_step = 0.2 [mm/s]``,
    a setting not given: an outside check, 2026-12-07).  A range that would pass in mm/s says
    the API takes m/s.

    Parameters
    ----------
    system : DriveSystem
        The drive searched.
    name : str
        The range's argument (``speed_range``; ``start_speed`` for a step-down).
    shown : object
        Its value as given, for the message.
    lo, hi : float
        The range [m/s].
    coarse_step : float
        The scan's coarse step given [m/s].
    protocol_step : float
        The protocol's coarse step for this search [m/s].
    span : str, default "high − low"
        The range's width in words, for the message.
    """
    from ..units import MM_PER_S

    bound, why = table_speed_limit(system)
    if hi > bound:
        raise ParameterError(name, shown, f"expected speeds ≤ {bound:.6g} [m/s] ({why})"
                             + mm_s_hint(hi, hi * MM_PER_S <= bound))
    step = max(coarse_step, protocol_step)
    widest = protocol.MAX_SEARCH_STEPS * step
    if hi - lo > widest:
        raise ParameterError(name, shown, f"expected {span} ≤ {widest:.6g} [m/s] (at most "
                             f"{protocol.MAX_SEARCH_STEPS} coarse steps of {step:g} m/s on the "
                             "scan)" + mm_s_hint(hi, (hi - lo) * MM_PER_S <= widest))


def decide(run: Runner, command_speed: float, rule: VerdictRule | None = None,
           *, start: float | None = None) -> tuple[TraceVerdict, float]:
    """Run a trial until decided: ``run(duration)`` for each of ``rule.durations()`` in turn,
    judged by :func:`trace_verdict`.  Returns the verdict and the duration [s] that decided it
    (the maximum when still undecided).

    Parameters
    ----------
    run : callable
        ``run(duration)`` → (time [s], table speed [m/s]) of the trial up to ``duration``.
    command_speed : float
        Commanded table speed [m/s].
    rule : VerdictRule, optional
        The creep-verdict rule (trial durations); the protocol's default when omitted.
    start : float, optional
        Judge the trace from this time on [s].

    Returns
    -------
    verdict : TraceVerdict
        The verdict.
    duration : float
        The duration that decided it [s].
    """
    rule = rule or VerdictRule()
    verdict: TraceVerdict | None = None
    duration = rule.initial_duration
    for duration in rule.durations():
        time, speed = run(duration)
        verdict = trace_verdict(time, speed, command_speed, rule, start=start)
        if verdict.decided:
            break
    assert verdict is not None
    return verdict, duration


def judge_trial(time: np.ndarray, speed: np.ndarray, command_speed: float,
                rule: VerdictRule | None = None) -> CreepTrial:
    """Verdict on a finished trace (no extension: "undecided" if it is too short to tell).

    Parameters
    ----------
    time : numpy.ndarray
        Sample times [s].
    speed : numpy.ndarray
        Table speed [m/s].
    command_speed : float
        Commanded table speed [m/s].
    rule : VerdictRule, optional
        The creep-verdict rule (trial durations); the protocol's default when omitted.

    Returns
    -------
    CreepTrial
        The verdict.
    """
    v = trace_verdict(time, speed, command_speed, rule)
    return CreepTrial.from_verdict(command_speed, v, float(time[-1] - time[0]))


def _shadow_options(options: SolverOptions | None,
                    system: DriveSystem | None = None) -> SolverOptions:
    """The shadow runs' options: the trials' (``options`` over the set's ``[solver]`` table,
    :func:`feeddrive.engine.simulate.run_options`, as a trial takes them) with every tolerance
    ``SHADOW_FACTOR`` times tighter, refused with one line before any trial runs when the
    trials' own are at double precision's reach."""
    from ..engine.error_estimate import tightened
    from ..engine.options import current
    from ..engine.simulate import run_options

    given = options if options is not None else current()
    return tightened(run_options(system, given) if system is not None else given)


def shadow_possible(options: SolverOptions | None = None,
                    system: DriveSystem | None = None) -> bool:
    """Whether a trial's shadow (every tolerance ``SHADOW_FACTOR`` times tighter) can be run at
    ``options`` (the current ones by default; over ``system``'s ``[solver]`` table when it is
    given): False where they are at double precision's reach — ``feeddrive creep`` and
    ``reproduce`` then search without an estimate and say so.

    Parameters
    ----------
    options : SolverOptions or None, default None
        The trials' options.
    system : DriveSystem or None, default None
        The drive whose set's table the trials take.

    Returns
    -------
    bool
        Whether ``error_estimate=True`` is possible.
    """
    try:
        _shadow_options(options, system)
    except ParameterError:
        return False
    return True


#: The coarsest output interval a creep verdict is judged on [s]: the default's (1 ms), at
#: which the verdict corpus was built; the critical speeds do not move between 0.25 ms and
#: 1 ms (tests/validation/test_verdict_interval.py).  A search's trials sample the table speed
#: at the run's output interval, and one sampled coarser than the drive's oscillation cannot
#: see it (at 0.5 s a CDFS step-down search found 1.39 mm/s and two undecided bands where the
#: default finds 1.40 mm/s and none); so a coarser interval is refused before the first trial.
VERDICT_INTERVAL = 1e-3


def check_verdict_interval(system: DriveSystem, options: SolverOptions | None) -> None:
    """Refuse, before a trial runs, an output interval coarser than :data:`VERDICT_INTERVAL`
    in the options a run of ``system`` takes (:func:`~feeddrive.engine.simulate.run_options`:
    ``options`` over the parameter file's ``[solver]`` table).

    Parameters
    ----------
    system : DriveSystem
        The drive (its parameter set may carry a ``[solver]`` table).
    options : SolverOptions or None
        The options given (None: those in force).

    Raises
    ------
    ParameterError
        Naming the interval where it was set (``solver.output_interval ([solver] in
        run.toml)``, ``options.output_interval``), its value [s] and the largest allowed.
    """
    merged = run_options(system, options)
    interval = merged.output_interval
    if interval <= VERDICT_INTERVAL * (1.0 + 1e-9):
        return
    field, origin = setting_field(merged, "output_interval")
    raise ParameterError(field, interval,
                         f"expected ≤ {VERDICT_INTERVAL:g} [s] for a creep verdict: its trials "
                         f"judge the table speed sampled at the output interval, checked at "
                         f"≤ {VERDICT_INTERVAL:g} s{origin}")


def _trial_profile(speed: float, nut_speed: float) -> ConstantSpeed:
    """A trial's reference: the table (and nut) from rest to their speeds [m/s] in 0.1 s."""
    return ConstantSpeed(speed, nut_speed, ramp_time=0.1)


def _run_trial(system: DriveSystem, speed: float, nut_speed: float,
               rule: VerdictRule | None, options: SolverOptions | None,
               embedded: bool) -> tuple[CreepTrial, np.ndarray, np.ndarray]:
    """A trial (:func:`creep_trial`) and the table-speed trace it was judged on [s; m/s]."""
    check_verdict_interval(system, options)
    sim = Simulation(system, _trial_profile(speed, nut_speed), options,
                     embedded_estimate=embedded)
    error: list[float | None] = [None]
    trace: list[np.ndarray] = [np.zeros(0), np.zeros(0)]

    def run(duration: float) -> tuple[np.ndarray, np.ndarray]:
        result = sim.run(duration)
        error[0] = speed_error(result.solver_stats)
        trace[:] = [result.time, result["table_speed"]]
        if result.solver_stats.get("diverged"):
            raise _Diverged(result.time, result["table_speed"])
        return result.time, result["table_speed"]

    try:
        verdict, duration = decide(run, speed, rule)
    except _Diverged as stop:
        return replace(stop.trial(speed), speed_error=error[0]), trace[0], trace[1]
    trial = replace(CreepTrial.from_verdict(speed, verdict, duration), speed_error=error[0])
    return trial, trace[0], trace[1]


def _shadow_error(system: DriveSystem, trial: CreepTrial, nut_speed: float,
                  shadow: SolverOptions, time: np.ndarray, speed: np.ndarray) -> float | None:
    """The trial's table-speed error estimated by its shadow: the largest difference on the
    output grid to the same trial run with ``shadow``'s tighter tolerances over the same
    simulated length [m/s]; None for a trial whose run diverged (nothing to compare to)."""
    if trial.kind == UNSTABLE:
        return None
    run = Simulation(system, _trial_profile(trial.speed, nut_speed), shadow).run(trial.duration)
    if run.solver_stats.get("diverged") or run.time.shape != time.shape:
        return None
    return float(np.max(np.abs(np.asarray(run["table_speed"]) - speed)))


def creep_trial(system: DriveSystem, speed: float, *, nut_speed: float = 0.0,
                rule: VerdictRule | None = None,
                options: SolverOptions | None = None,
                error_estimate: bool | str = False) -> CreepTrial:
    """Start the table from rest at ``speed`` [m/s] (nut at ``nut_speed``) and run until the
    verdict is decided (:func:`decide`); a longer trial continues the shorter one
    (:class:`~feeddrive.engine.simulate.Simulation`), so an undecided trial is not repeated.

    Parameters
    ----------
    system : DriveSystem
        The drive.
    speed : float
        Commanded table speed [m/s].
    nut_speed : float, default 0.0
        Nut speed [m/s].
    rule : VerdictRule, optional
        The creep-verdict rule (trial durations); the protocol's default when omitted.
    options : SolverOptions, optional
        The solver options.
    error_estimate : bool or str, default False
        Estimate the trial's table-speed integration error, its ``speed_error``: ``"shadow"``
        (or True) runs the trial again with every tolerance ``SHADOW_FACTOR`` times tighter
        and takes the largest difference (:mod:`feeddrive.engine.error_estimate`; 1.6–2.5×
        the trial's CPU once more), ``"embedded"`` carries the embedded global-error estimate
        along the one run (:mod:`feeddrive.solvers.global_error`; 1–10 % more CPU, but 0.15–
        200 000× the true error where measured).

    Returns
    -------
    CreepTrial
        The verdict.
    """
    check_kinds(system, rule=rule, options=options)
    speed = check_speed("speed", speed, sign="nonzero", limit=table_speed_limit(system))
    check_speed("nut_speed", nut_speed, sign="any")
    kind = estimate_kind(error_estimate)
    shadow = _shadow_options(options, system) if kind == "shadow" else None
    trial, time, trace = _run_trial(system, speed, nut_speed, rule, options,
                                    kind == "embedded")
    if shadow is not None:
        trial = replace(trial, speed_error=_shadow_error(system, trial, nut_speed, shadow,
                                                         time, trace))
    return trial


def speed_error(solver_stats: dict[str, Any]) -> float | None:
    """The table-speed entry of a run's embedded error estimate (None without one) [m/s].

    Parameters
    ----------
    solver_stats : dict
        A Result's solver statistics.

    Returns
    -------
    float or None
        The largest estimated table-speed error of the run [m/s].
    """
    entry = solver_stats.get("embedded_error_estimate")
    if entry is None or "table_speed" not in entry["signals"]:
        return None
    return float(entry["signals"]["table_speed"]["absolute"])


class _Diverged(Exception):
    """A trial's run stopped early as diverged (``divergence_bounds``)."""

    def __init__(self, time: np.ndarray, speed: np.ndarray) -> None:
        super().__init__(float(time[-1]))
        self.time, self.speed = time, speed

    def trial(self, command: float) -> CreepTrial:
        along = self.speed * math.copysign(1.0, command) / abs(command)
        end = float(self.time[-1])
        return CreepTrial(speed=command, kind=UNSTABLE,
                          ripple_ratio=float(np.max(along) - np.min(along)),
                          stick_fraction=math.nan, stick_slip_frequency=None,
                          min_ratio=float(np.min(along)), duration=end, decided_at=end)


def critical_speed_from_rest(
    system: DriveSystem, *, nut_speed: float = 0.0,
    speed_range: tuple[float, float] = protocol.SPEED_RANGE,
    coarse_step: float = protocol.COARSE_STEP, resolution: float = protocol.RESOLUTION,
    rule: VerdictRule | None = None, options: SolverOptions | None = None,
    progress: Callable[[int, int], None] | None = None, error_estimate: bool | str = False,
) -> CriticalSpeed:
    """Critical creeping speed by a coarse scan plus bisection, every trial from rest.

    Every change of verdict kind found by the coarse scan is bisected to ``resolution`` (see
    the module docstring).  The defaults are the protocol of ``feeddrive creep`` and
    ``reproduce`` (``feeddrive.analysis.protocol``).

    Parameters
    ----------
    system : DriveSystem
        The drive to search.
    nut_speed : float, default 0
        Hollow-motor (nut) speed of every trial [m/s] (DDFS).
    speed_range : tuple of float, default (2e-5, 3.02e-3)
        Lowest and highest table speed tested [m/s].
    coarse_step : float, default 2e-4
        Spacing of the coarse scan [m/s].
    resolution : float, default 1e-5
        Resolution of the bisections [m/s].
    rule : VerdictRule or None, default None
        How a trial is judged (None: the protocol's rule).
    options : SolverOptions or None, default None
        Integrator settings of the trials.
    progress : callable or None, default None
        Called as ``progress(done, total)`` after each trial.
    error_estimate : bool or str, default False
        Estimate the integration error of the trials that decide the critical speed
        (:func:`~feeddrive.analysis.critical.deciding_trials`), the result's
        :attr:`CriticalSpeed.speed_error`:
        ``"shadow"`` (or True) runs those one or two trials again with every tolerance
        ``SHADOW_FACTOR`` times tighter once the search is done (the table-speed traces of
        the trials that may still decide are kept until then; 7–9 % of a search's CPU,
        0.8–1.2× the true error where measured,
        :data:`~feeddrive.engine.error_estimate.SHADOW_RATIO`); ``"embedded"`` carries the
        embedded estimate along every trial
        (:mod:`feeddrive.solvers.global_error`; 4–10 %, 0.15–200 000×).

    Returns
    -------
    CriticalSpeed
        The critical speed, its status, the creeping bands and every trial.

    References
    ----------
    Wang2021 Sect. 5.2 (Figs. 6-8) defines the critical creeping speed studied here.
    """
    lo, hi = check_search_settings(system, speed_range=speed_range, coarse_step=coarse_step,
                                   resolution=resolution, rule=rule, options=options,
                                   progress=progress)
    check_speed("nut_speed", nut_speed, sign="any")
    rule = rule or VerdictRule()
    estimate = estimate_kind(error_estimate)
    shadow = _shadow_options(options, system) if estimate == "shadow" else None  # up front
    simulated = 0.0
    # the table-speed traces of the trials that may still decide (the shadow's): the top
    # creeping trial's and every one above it (a trial below the top creeping one never will)
    traces: dict[float, tuple[np.ndarray, np.ndarray]] = {}

    def judge(v: float) -> str:
        nonlocal simulated
        trial, time, trace = _run_trial(system, v, nut_speed, rule, options,
                                        estimate == "embedded")
        simulated += trial.duration  # the trial is continued, not repeated
        trials[v] = trial
        if shadow is not None:
            traces[v] = (time, trace)
            top = max((u for u, t in trials.items() if t.kind in NON_SMOOTH), default=None)
            for u in [u for u in traces if top is not None and u < top]:
                del traces[u]
        if progress:
            progress(len(trials), 0)
        return trial.kind

    trials: dict[float, CreepTrial] = {}
    search_kinds(judge, lo, hi, coarse_step, resolution)
    ordered = tuple(trials[k] for k in sorted(trials))
    if shadow is not None:
        decided = {id(t): _shadow_error(system, t, nut_speed, shadow, *traces[t.speed])
                   for t in deciding_trials(ordered)}
        ordered = tuple(replace(t, speed_error=decided[id(t)]) if id(t) in decided else t
                        for t in ordered)
    status, crit, kind = critical_of(ordered)
    return CriticalSpeed(drive=system.drive, table_position=system.table_position,
                         nut_speed=nut_speed, start="rest", critical_speed=crit, status=status,
                         resolution=resolution, speed_range=(lo, hi), trials=ordered,
                         simulated_time=simulated, kind=kind, bands=bands_of(ordered),
                         rule=rule, error_estimate=estimate)


def check_search_settings(system: DriveSystem, *, speed_range: object,
                          coarse_step: object = protocol.COARSE_STEP,
                          resolution: object = protocol.RESOLUTION, rule: object = None,
                          options: object = None, progress: object = None
                          ) -> tuple[float, float]:
    """The checks :func:`critical_speed_from_rest` makes before its first trial (and
    :func:`~feeddrive.analysis.calibrate.calibrate` before its first, for the search it ends
    with): the kinds of its arguments, ``speed_range`` a pair 0 < low < high within the axis's
    speed limit and within ``MAX_SEARCH_STEPS`` coarse steps, the steps finite speeds > 0 and
    the search bounded (:func:`~feeddrive.analysis.protocol.check_search`), every message in
    m/s, the unit the arguments are given in.

    Parameters
    ----------
    system : DriveSystem
        The drive to search.
    speed_range, coarse_step, resolution : object
        As :func:`critical_speed_from_rest` takes them [m/s].
    rule, options, progress : object, optional
        As :func:`critical_speed_from_rest` takes them.

    Returns
    -------
    tuple of float
        (low, high) [m/s].

    Raises
    ------
    ParameterError
        Naming the argument, its value as given and what was expected [m/s].
    """
    check_kinds(system, rule=rule, options=options, progress=progress)
    lo, hi = speed_pair("speed_range", speed_range)
    step = check_speed("coarse_step", coarse_step)
    res = check_speed("resolution", resolution)
    check_scan(system, "speed_range", tuple(speed_range), lo, hi,  # type: ignore[arg-type]
               step, protocol.COARSE_STEP)
    protocol.check_search(low=lo, high=hi, coarse_step=step, resolution=res,
                          names={"low": "speed_range[0]", "high": "speed_range[1]"},
                          unit="m/s")
    return lo, hi


def search_kinds(kind_at: Callable[[float], str], low: float, high: float, coarse_step: float,
                 resolution: float, max_trials: int = 400) -> dict[float, str]:
    """Kinds at a coarse grid on [low, high] [m/s] (both ends on it, the last step shorter
    when the range is not a whole number of steps), every boundary between two decided,
    different kinds (at least one creeping) bisected to ``resolution``.  Each speed is
    evaluated at most once; returns {speed: kind}.

    Parameters
    ----------
    kind_at : callable
        ``kind_at(speed)`` → the kind at ``speed`` [m/s].
    low : float
        Lowest speed [m/s].
    high : float
        Highest speed [m/s].
    coarse_step : float
        Step of the coarse grid [m/s].
    resolution : float
        Bisection resolution [m/s].
    max_trials : int, default 400
        Most speeds evaluated.

    Returns
    -------
    dict of float to str
        Speed [m/s] → kind.
    """
    kinds: dict[float, str] = {}

    def judge(v: float) -> str:
        v = round(v, 12)
        if v not in kinds:
            kinds[v] = kind_at(v)
        return kinds[v]

    for v in protocol.speed_grid(low, high, coarse_step):
        judge(float(v))
    while len(kinds) < max_trials:
        speeds = sorted(kinds)
        todo = None
        for a, b in zip(speeds[:-1], speeds[1:], strict=True):
            ka, kb = kinds[a], kinds[b]
            if ka == kb or UNDECIDED in (ka, kb) or not ({ka, kb} & set(NON_SMOOTH)):
                continue
            if b - a > resolution * (1 + 1e-9):
                todo = (a, b)
                break
        if todo is None:
            break
        a, b = todo
        mid = round((a + b) / 2.0 / resolution) * resolution
        if mid <= a + 1e-15 or mid >= b - 1e-15:
            mid = (a + b) / 2.0
        judge(mid)
    return kinds


def search_boundary(creeps: Callable[[float], bool], low: float, high: float,
                    coarse_step: float, resolution: float) -> tuple[str, float | None]:
    """Smooth end of the highest creep boundary in [low, high] [m/s] for a yes/no judge
    (:func:`search_kinds` with two kinds).  Returns (status, critical speed).

    Parameters
    ----------
    creeps : callable
        ``creeps(speed)`` → whether the table creeps at ``speed`` [m/s].
    low : float
        Lowest speed [m/s].
    high : float
        Highest speed [m/s].
    coarse_step : float
        Step of the coarse grid [m/s].
    resolution : float
        Bisection resolution [m/s].

    Returns
    -------
    status : str
        As :func:`critical_of`: ``"found"``, ``"below-range"``, ``"above-range"``, ``"undecided"``.
    critical_speed : float or None
        The smooth end of the highest boundary [m/s].
    """
    kinds = search_kinds(lambda v: STICK_SLIP if creeps(v) else SMOOTH, low, high,
                         coarse_step, resolution)
    trials = [CreepTrial(speed=v, kind=k, ripple_ratio=0.0, stick_fraction=0.0,
                         stick_slip_frequency=None) for v, k in kinds.items()]
    status, crit, _ = critical_of(trials)
    return status, crit


def judge_staircase(time: np.ndarray, speed: np.ndarray, speeds: np.ndarray,
                    starts: np.ndarray, dwell: float | Sequence[float],
                    rule: VerdictRule | None = None) -> list[CreepTrial]:
    """Judge each step of a step-down trace with :func:`trace_verdict` on the step alone
    (from its start to just before the next step).

    Parameters
    ----------
    time : numpy.ndarray
        Sample times [s].
    speed : numpy.ndarray
        Table speed [m/s].
    speeds : numpy.ndarray
        Commanded speed of each step [m/s].
    starts : numpy.ndarray
        Start time of each step [s].
    dwell : float or sequence of float
        Length of each step [s].
    rule : VerdictRule, optional
        The creep-verdict rule (trial durations); the protocol's default when omitted.

    Returns
    -------
    list of CreepTrial
        One per step.
    """
    dwells = np.broadcast_to(np.asarray(dwell, dtype=float), (len(speeds),))
    return [_judge_step(time, speed, float(v), float(t0), float(d), rule)
            for v, t0, d in zip(speeds, starts, dwells, strict=True)]


def _judge_step(time: np.ndarray, speed: np.ndarray, command: float, start: float,
                dwell: float, rule: VerdictRule | None) -> CreepTrial:
    """One step of a staircase judged on its samples alone, start ≤ t < start + dwell·(1 −
    1e-6) (found by bisection of the sorted times: the same samples as the comparison)."""
    a, b = np.searchsorted(time, [start, start + dwell * (1.0 - 1e-6)], side="left")
    verdict = trace_verdict(time[a:b], speed[a:b], command, rule)
    return CreepTrial.from_verdict(command, verdict, dwell)


def walk_down(system: DriveSystem, speeds: Sequence[float] | np.ndarray, *, nut_speed: float = 0.0,
              rule: VerdictRule | None = None, options: SolverOptions | None = None,
              stop_after: int | None = None, runs: list[Simulation] | None = None,
              ) -> tuple[list[CreepTrial], float]:
    """One continuous run from rest at ``speeds[0]`` stepping down through ``speeds`` [m/s],
    each step held until decided: its dwell doubles from ``rule.initial_duration`` up to
    ``rule.max_duration``, and the run is simulated again with the longer dwell — not from the
    start: the history before the step is unchanged, so the run continues from the state the
    previous run had at its last chunk end before the profiles part
    (:meth:`~feeddrive.engine.simulate.Simulation.resume`; bit-identical to a run from rest).
    ``stop_after``: stop at the first step after that index whose kind differs from that
    step's.  Returns (trials, simulated time [s]: the seconds integrated, the shared
    beginnings counted once).

    Parameters
    ----------
    system : DriveSystem
        The drive.
    speeds : sequence of float
        The step speeds, decreasing [m/s].
    nut_speed : float, default 0.0
        Nut speed [m/s].
    rule : VerdictRule, optional
        The creep-verdict rule (trial durations); the protocol's default when omitted.
    options : SolverOptions, optional
        The solver options.
    stop_after : int, optional
        Stop at the first step after this index whose kind differs from its own.
    runs : list of Simulation, optional
        Earlier staircase runs of this system to continue from where a profile begins as
        theirs (the search's coarse walk for its fine walks); the walk's last run is added.

    Returns
    -------
    trials : list of CreepTrial
        One per step walked.
    duration : float
        Simulated time [s].
    """
    check_verdict_interval(system, options)
    rule = rule or VerdictRule()
    levels = rule.durations()
    sp = np.asarray(speeds, dtype=float)
    level = [0] * len(sp)
    trials: list[CreepTrial] = []
    simulated = 0.0

    def done() -> bool:
        if len(trials) == len(sp):
            return True
        return (stop_after is not None and len(trials) > stop_after + 1
                and trials[-1].kind != trials[stop_after].kind)

    earlier = list(runs or [])
    last: Simulation | None = None
    while not done():
        dwell = [levels[i] for i in level]
        profile, starts = _staircase(sp, dwell, 0.0, nut_speed)
        duration = float(profile.time[-1])
        sim = Simulation(system, profile, options)
        sim.keep_checkpoints()
        resumed = _resume(sim, [*earlier, *([last] if last is not None else [])])
        result = sim.run(duration)
        last = sim
        simulated += duration - resumed
        if result.solver_stats.get("diverged"):  # every step from the divergence on
            reached = float(result.time[-1])
            for k in range(len(trials), len(sp)):
                if starts[k] + dwell[k] > reached:
                    trials.extend(_Diverged(result.time, result["table_speed"]).trial(float(v))
                                  for v in sp[k:])
                    break
                trials.append(_judge_step(result.time, result["table_speed"], float(sp[k]),
                                          float(starts[k]), float(dwell[k]), rule))
            break
        for k in range(len(trials), len(sp)):  # each step judged when it is reached
            step = _judge_step(result.time, result["table_speed"], float(sp[k]),
                               float(starts[k]), float(dwell[k]), rule)
            if step.kind == UNDECIDED and level[k] + 1 < len(levels):
                level[k] += 1
                break
            trials.append(step)
            if done():
                break
    if runs is not None and last is not None:
        runs.append(last)
    return trials, simulated


def check_stepdown(system: DriveSystem, *, nut_speed: float, start_speed: float,
                   lowest_speed: float, step: float, coarse_step: float,
                   rule: VerdictRule | None, options: SolverOptions | None,
                   ) -> tuple[float, float, np.ndarray]:
    """Every refusal of :func:`critical_speed_stepdown`'s arguments, before any work (the
    command line makes them before its search from rest, so that ``creep --method both``
    does not run that search to refuse the step-down after it).

    Parameters
    ----------
    system : DriveSystem
        The drive to search.
    nut_speed, start_speed, lowest_speed, step, coarse_step : float
        As :func:`critical_speed_stepdown`'s [m/s].
    rule : VerdictRule or None
        How each step is judged (None: the protocol's rule).
    options : SolverOptions or None
        Integrator settings.

    Returns
    -------
    tuple of (float, float, ndarray)
        The lowest and the start speed [m/s] and the coarse staircase's speeds, highest first.

    Raises
    ------
    ParameterError
        Naming the argument refused.
    """
    check_kinds(system, rule=rule, options=options)
    hi = check_speed("start_speed", start_speed)
    lo = check_speed("lowest_speed", lowest_speed)
    step = check_speed("step", step)
    if hi <= lo:
        raise ParameterError("start_speed", start_speed,
                             f"expected > lowest_speed = {lo:g} [m/s]")
    coarse_step = check_speed("coarse_step", coarse_step)
    # a nut speed the drive does not follow (the CDFS holds its nut) was refused only by the
    # first trial, showing the staircase's ramped first sample (1e-3 shown as 1e-05: an API
    # sweep of session 29); refused here with the speed given
    system.topology().check_profile(
        {"nut": (check_speed("nut_speed", nut_speed, sign="any"), np.zeros(1))})
    check_scan(system, "start_speed", start_speed, lo, hi, coarse_step,
               protocol.STAIRCASE_COARSE_STEP, "start_speed − lowest_speed")
    protocol.check_search(low=lo, high=hi, coarse_step=coarse_step, resolution=step,
                          names={"low": "lowest_speed", "high": "start_speed",
                                 "resolution": "step"}, unit="m/s")
    coarse = protocol.speed_grid(lo, hi, coarse_step)[::-1]
    check_staircase(coarse, rule or VerdictRule(), options, nut_speed=nut_speed,
                    shown=start_speed)
    return lo, hi, coarse


def check_staircase(speeds: Sequence[float] | np.ndarray, rule: VerdictRule,
                    options: SolverOptions | None, *, nut_speed: float = 0.0,
                    shown: object = None) -> None:
    """Refuse, before any work, a step-down whose first staircase (every coarse step held
    ``rule.initial_duration``) would record more output than memory holds: the refusal named
    ``duration`` and ``options.output_interval`` (settings the step-down's user never gave)
    and, under ``creep --method both``, came only after the search from rest had run (an
    outside check, 2026-12-07: ``creep --high 200 --method stepdown``, 2 000 steps, 24 000 s).

    Parameters
    ----------
    speeds : sequence of float
        The coarse staircase's speeds [m/s], highest first.
    rule : VerdictRule
        The verdict rule (each step's first dwell).
    options : SolverOptions or None
        The trials' settings (None: the settings in force).
    nut_speed : float, default 0
        Hollow-motor (nut) speed [m/s].
    shown : object, default None
        ``start_speed`` as given, for the message.

    Raises
    ------
    ParameterError
        On ``start_speed``, with the staircase's length and what it would need.
    """
    from ..engine.budget import output_memory
    from ..engine.options import current

    sp = np.asarray(speeds, dtype=float)
    dwell = rule.durations()[0]
    profile, _ = _staircase(sp, [dwell] * len(sp), 0.0, nut_speed)
    duration = float(profile.time[-1])
    interval = (options or current()).output_interval
    samples, need, free = output_memory(duration, interval)
    if need > 0.5 * free:
        fit = int(len(sp) * 0.5 * free / need)
        raise ParameterError(
            "start_speed", sp[0] if shown is None else shown,
            f"its staircase down to {sp[-1] / units.MM_PER_S:g} mm/s ({len(sp)} steps held "
            f"{dwell:g} s each, {duration:g} s, {samples:.3g} output samples at "
            f"{interval:g} s) would need about {need / 2**30:.3g} GiB, more than half the "
            f"{free / 2**30:.3g} GiB available; expected a lower start (about {fit} steps "
            "fit), or a longer output interval")


def _resume(sim: Simulation, candidates: list[Simulation]) -> float:
    """Resume ``sim`` from the candidate whose committed history it shares longest; the
    time it resumes from [s] (0: from rest)."""
    best, at = None, 0.0
    for other in candidates:
        t = sim.resumable_from(other)
        if t > at:
            best, at = other, t
    return sim.resume(best) if best is not None else 0.0


def critical_speed_stepdown(
    system: DriveSystem, *, nut_speed: float = 0.0, start_speed: float = 3.0 * MM_S,
    lowest_speed: float = 0.05 * MM_S, step: float = 0.01 * MM_S,
    coarse_step: float = 0.1 * MM_S, rule: VerdictRule | None = None,
    options: SolverOptions | None = None,
) -> CriticalSpeed:
    """Critical creeping speed by the paper's protocol on a running table.

    The command steps down, each step held until decided; a fine staircase (``step``) is run
    at each change of kind.

    Parameters
    ----------
    system : DriveSystem
        The drive to search.
    nut_speed : float, default 0
        Hollow-motor (nut) speed [m/s] (DDFS).
    start_speed : float, default 3e-3
        First commanded table speed [m/s].
    lowest_speed : float, default 5e-5
        Speed at which the staircase stops [m/s].
    step : float, default 1e-5
        Fine step of the staircase [m/s] (Wang2021 Sect. 6: 0.01 mm/s).
    coarse_step : float, default 1e-4
        Coarse step until the first change of kind [m/s].
    rule : VerdictRule or None, default None
        How each step is judged (None: the protocol's rule).
    options : SolverOptions or None, default None
        Integrator settings.

    Returns
    -------
    CriticalSpeed
        The critical speed (``start = "stepdown"``), its status and the steps as trials.

    References
    ----------
    Wang2021 Sect. 6 (Fig. 13): the experiment's step-down protocol.
    """
    lo, hi, coarse = check_stepdown(system, nut_speed=nut_speed, start_speed=start_speed,
                                    lowest_speed=lowest_speed, step=step,
                                    coarse_step=coarse_step, rule=rule, options=options)
    rule, step = rule or VerdictRule(), float(step)
    runs: list[Simulation] = []  # the coarse walk's last run: the fine walks start from it
    coarse_trials, simulated = walk_down(system, coarse, nut_speed=nut_speed, rule=rule,
                                         options=options, runs=runs)
    found: dict[float, CreepTrial] = {round(t.speed, 12): t for t in coarse_trials}
    for i in range(len(coarse_trials) - 1):
        upper, lower = coarse_trials[i], coarse_trials[i + 1]
        if upper.kind == lower.kind or UNDECIDED in (upper.kind, lower.kind):
            continue
        fine = protocol.fine_staircase(upper.speed, lower.speed, step)
        fine_trials, t_fine = walk_down(system, [*coarse[:i + 1], *fine], nut_speed=nut_speed,
                                        rule=rule, options=options, stop_after=i,
                                        runs=runs[:1])
        simulated += t_fine
        # the fine walk's own steps, down to its first change of kind
        for tr in fine_trials[i + 1:]:
            found[round(tr.speed, 12)] = tr
            if tr.kind != upper.kind:
                break
    ordered = tuple(found[k] for k in sorted(found))
    status, crit, kind = critical_of(ordered)
    return CriticalSpeed(drive=system.drive, table_position=system.table_position,
                         nut_speed=nut_speed, start="running", critical_speed=crit,
                         status=status, resolution=step, speed_range=(lo, hi), trials=ordered,
                         simulated_time=simulated, kind=kind, bands=bands_of(ordered),
                         rule=rule)


def __getattr__(name: str) -> Any:
    """Names that moved from here before 0.2.0: importable until 0.3.0, with a
    DeprecationWarning naming their new place (:mod:`feeddrive._compat`)."""
    from .. import _compat

    return _compat.moved(__name__, name)
