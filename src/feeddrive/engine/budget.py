"""What a run will cost before it starts: solver steps and memory (issue 12 item 9, issue 13
item 4).

``simulate --duration 100000`` used to reach 12 GB and then stop with a solver error after
50 million steps; :func:`run_budget` lets the CLI refuse or warn before any work is done.

Two more failures surfaced only at the end of a long run: an output larger than the
machine's memory (``--duration 1e9``), and a parameter set so stiff for the explicit
Dormand–Prince integrator that it runs to ``max_steps`` after minutes (near-zero friction:
the LuGre bristle relaxes in F_c/(σ0·|v|) ≈ 30 ns; a current loop of microseconds).
:func:`feeddrive.simulate` itself refuses both before integrating:

* :func:`check_output_samples`: a run whose output interval leaves it no recorded sample
  after its start (the ``simulate`` command, which prints the run's summary, asks for the
  summary's :data:`SUMMARY_SAMPLES`);
* :func:`check_output_memory`: a run whose recorded samples would need more than half the
  available memory;
* :func:`step_rate_problem`: from a short probe integration (the first ~0.1 s), the steps
  of the whole run are projected; above ``max_steps`` the run is refused (a
  ``SimulationError`` raised by :func:`feeddrive.simulate` before integrating), naming the
  fastest time constant of the parameters (:func:`time_constants`), the one that forces
  small steps.  An explicit method is stable for steps up to about 3.3 × the fastest time
  constant (Hairer & Wanner, Solving ODEs II, Sect. IV.2, stability region of DOPRI5).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..parameters import DriveParameters, ParameterError

if TYPE_CHECKING:
    from .options import SolverOptions

# bytes per recorded sample: the solver's output arrays (time, 15 states, 15 auxiliaries of
# the ball-screw drives, float64: 12.2 GB measured at 5e7 samples, i.e. 244 B) and the
# Result's copies of them (about as much again)
BYTES_PER_SAMPLE = 2 * 8 * (1 + 15 + 15)
MEMORY_WARNING_BYTES = 2e9
#: fewest samples a run's summary takes (:meth:`feeddrive.Result.summary`): its trace analyses
#: (creep metrics, sine metrics) take a trace of at least
#: :data:`feeddrive.analysis.trace_input.MIN_SAMPLES` samples (a test checks the two agree).
#: A run records one sample at t = 0 and one every output interval, so its summary asks for
#: ``output_interval ≤ duration / (SUMMARY_SAMPLES − 1)``
SUMMARY_SAMPLES = 16


@dataclass(frozen=True)
class RunBudget:
    """Lower bound of a run's solver steps and estimate of its recorded output's memory.

    Parameters
    ----------
    duration : float
        Simulated time [s].
    min_steps : int
        Fewest steps the run can take: the step never exceeds the solver's ``max_step``.
    max_steps : int
        The solver's step limit.
    samples : int
        Number of recorded output samples.
    memory_bytes : float
        Estimated memory of the recorded output [bytes].
    """

    duration: float  # [s]
    min_steps: int  # the step never exceeds max_step [s]
    max_steps: int
    samples: int
    memory_bytes: float

    @property
    def steps_exceeded(self) -> bool:
        """Whether even the fewest possible steps exceed the step limit."""
        return self.min_steps > self.max_steps

    @property
    def longest_duration(self) -> float:
        """The longest duration [s] the step limit allows."""
        return self.duration * self.max_steps / max(self.min_steps, 1)


def run_budget(duration: float, *, max_step: float, output_interval: float,
               max_steps: int) -> RunBudget:
    """Budget a run before it starts: its fewest steps and its output's memory.

    Parameters
    ----------
    duration : float
        Simulated time [s].
    max_step : float
        The solver's largest step [s].
    output_interval : float
        Interval of the recorded output [s].
    max_steps : int
        The solver's step limit.

    Returns
    -------
    RunBudget
        The run's step bound and memory estimate.
    """
    samples = int(math.floor(duration / output_interval)) + 1
    return RunBudget(duration=duration, min_steps=int(math.ceil(duration / max_step)),
                     max_steps=max_steps, samples=samples,
                     memory_bytes=float(samples * BYTES_PER_SAMPLE))


#: simulated time [s] of the probe that measures the step rate
PROBE_TIME = 0.1
#: refuse when the projected steps exceed max_steps / this margin (the rate may still grow)
STEP_MARGIN = 1.5
#: a factor on BYTES_PER_SAMPLE for the copies made on writing a file
_COPY_FACTOR = 2.0


def available_memory() -> int:
    """Bytes of memory available to a new allocation.

    Linux ``MemAvailable`` from ``/proc/meminfo``, else ``sysconf``; 4 GiB when neither is known.

    Returns
    -------
    int
        Available memory [bytes].
    """
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return 4 << 30


def _source_kind(options: SolverOptions, name: str) -> str:
    """Who gave setting ``name`` of ``options``: ``"option"`` (a command-line option),
    ``"api"`` (given in Python), ``"default"``, or ``"file"`` (a file's ``[solver]`` table, or
    a command's settings carried by a parameter set)."""
    from .options import API_SOURCE, DEFAULT_SOURCE, RECORD_SOURCE

    base = options.source(name).rpartition(" ÷ ")[0] or options.source(name)
    if base.startswith("--"):
        return "option"
    if base in (API_SOURCE, RECORD_SOURCE):
        return "api"
    if base == DEFAULT_SOURCE:
        return "default"
    return "file"


def setting_field(options: SolverOptions, name: str) -> tuple[str, str]:
    """How a refusal names setting ``name`` of ``options``, as the user gave it: the field and
    a note on where it came from, as :func:`feeddrive.engine.options.layered` names a refused
    value (``solver.rtol = -1.0: … ([solver] in run.toml)``).

    Parameters
    ----------
    options : SolverOptions
        A run's options, each setting's source in ``origin``.
    name : str
        A field of :class:`~feeddrive.engine.options.SolverOptions`.

    Returns
    -------
    tuple of (str, str)
        ``("--max-steps", "")`` for a command-line option, ``("solver.max_steps",
        " ([solver] in run.toml)")`` for a file's table, ``("options.max_steps", "")`` for the
        API, ``(name, " (the default)")`` for a default.
    """
    kind = _source_kind(options, name)
    if kind == "option":
        return options.setting_place(name), ""
    if kind == "api":
        return f"options.{name}", ""
    if kind == "default":
        return name, " (the default)"
    return f"solver.{name}", f" ({options.source(name)})"


def setting_hint(options: SolverOptions, name: str, *, option: str | None = None) -> str:
    """Where to change setting ``name`` of a run's ``options``, as advice names it: where it
    came from (:meth:`feeddrive.SolverOptions.setting_place`: the command-line option, or
    the file's setting with the file), ``options.NAME`` when given in Python; a default,
    every place that sets it.

    Parameters
    ----------
    options : SolverOptions
        A run's options.
    name : str
        A field of :class:`~feeddrive.engine.options.SolverOptions`.
    option : str or None, default None
        The command-line option that sets it, where a command takes one (``--max-steps``),
        named for a default.

    Returns
    -------
    str
        E.g. ``"--max-steps"``, ``"solver.max_steps ([solver] in run.toml)"``,
        ``"options.max_steps"``, ``"max_steps (options.max_steps, a [solver] table's
        max_steps, or --max-steps where a command takes it)"``.
    """
    kind = _source_kind(options, name)
    if kind in ("option", "file"):
        return options.setting_place(name)
    if kind == "api":
        return f"options.{name}"
    where = f", or {option} where a command takes it" if option else ""
    return f"{name} (options.{name}, a [solver] table's {name}{where})"


def recorded_samples(duration: float, output_interval: float) -> int:
    """The samples a run of ``duration`` records: one at t = 0 and one every
    ``output_interval`` up to its end.

    Parameters
    ----------
    duration : float
        Simulated time [s].
    output_interval : float
        Interval of the recorded output [s].

    Returns
    -------
    int
        The number of samples.
    """
    return int(math.floor(duration / output_interval + 1e-9)) + 1


def check_output_samples(duration: float, options: SolverOptions, *, samples: int = 2,
                         purpose: str = "a run") -> None:
    """Refuse, before it starts, a run whose output interval leaves it fewer than ``samples``
    recorded samples.

    Every run needs 2 (one after its start: an output interval longer than the run left a
    Result without a sample, whose summary failed on an empty array); a run whose summary is
    printed needs :data:`SUMMARY_SAMPLES` (the ``simulate`` command asks for it), i.e.
    ``output_interval ≤ duration / (SUMMARY_SAMPLES − 1)``.

    Parameters
    ----------
    duration : float
        Simulated time [s].
    options : SolverOptions
        The run's options (its ``output_interval`` and where it came from).
    samples : int, default 2
        The fewest samples the run must record.
    purpose : str, default "a run"
        What needs them, in the message (``"the summary"``).

    Raises
    ------
    ParameterError
        Naming the output interval as the user gave it (``solver.output_interval`` with its
        file, ``options.output_interval``), its value and the largest interval allowed
        [s]; when the interval is the default, the duration and the shortest run allowed.
    """
    interval = options.output_interval
    got = recorded_samples(duration, interval)
    if got >= samples:
        return
    n = samples - 1
    default = _source_kind(options, "output_interval") == "default"
    if samples < SUMMARY_SAMPLES:
        m = SUMMARY_SAMPLES - 1
        summary = (f"a run of at least {m * interval:g} s" if default else
                   f"an interval ≤ duration/{m} = {duration / m:.3g} s")
        rule = (f"{purpose} records one sample at t = 0 and one per output interval and needs "
                f"{n} after its start ({duration:g} s at {interval:g} s gives {got - 1}); its "
                f"summary takes {SUMMARY_SAMPLES} samples, {summary}")
    else:
        rule = (f"{purpose} takes at least {samples} samples, one at t = 0 and one per output "
                f"interval ({duration:g} s at {interval:g} s gives {got})")
    if default:  # the user chose the duration, not the interval
        raise ParameterError("duration", duration,
                             f"expected ≥ {n * interval:g} [s], {n} output interval"
                             f"{'s' if n > 1 else ''} of {interval:g} s (the default "
                             f"output_interval): {rule}")
    field, origin = setting_field(options, "output_interval")
    limit = f"the run's duration, {duration:g}" if n == 1 else \
        f"duration/{n} = {duration / n:.3g}"
    raise ParameterError(field, interval, f"expected ≤ {limit} [s], or a run of at least "
                                          f"{n * interval:g} s: {rule}{origin}")


def check_step_budget(duration: float, options: SolverOptions) -> RunBudget:
    """Refuse, before it starts, a run whose duration needs more steps than its step limit
    allows at its largest step (:func:`run_budget`), naming the limit where it was set.

    Parameters
    ----------
    duration : float
        Simulated time [s].
    options : SolverOptions
        The run's options (its ``max_steps``, largest step and output interval, and where
        each came from).

    Returns
    -------
    RunBudget
        The run's budget (its samples and memory, for a warning).

    Raises
    ------
    ParameterError
        ``--duration = 1.0: needs at least 1e+03 solver steps (step ≤ 1 ms), more than
        solver.max_steps = 100 ([solver] in ms.toml); expected ≤ 0.1 [s], or raise it there or
        give --max-steps``.
    """
    max_step = options.largest_step
    budget = run_budget(duration, max_step=max_step, output_interval=options.output_interval,
                        max_steps=options.max_steps)
    if budget.steps_exceeded:
        field, origin = setting_field(options, "max_steps")
        way = "raise it there or give --max-steps" if field.startswith("solver.") \
            else "raise --max-steps"
        raise ParameterError(
            "--duration", duration,
            f"needs at least {budget.min_steps:.3g} solver steps (step ≤ {max_step * 1e3:g} "
            f"ms), more than {field} = {options.max_steps:.3g}{origin}; expected ≤ "
            f"{budget.longest_duration:g} [s], or {way}")
    return budget


def output_memory(duration: float, output_interval: float) -> tuple[int, float, float]:
    """What a run's recorded output needs, against what the host has.

    Parameters
    ----------
    duration : float
        Simulated time [s].
    output_interval : float
        Interval of the recorded output [s].

    Returns
    -------
    tuple of (int, float, float)
        The output samples, the bytes they need with their working copies, and the bytes
        available; :func:`check_output_memory` refuses a run needing more than half.
    """
    samples = recorded_samples(duration, output_interval)
    return samples, float(samples * BYTES_PER_SAMPLE * _COPY_FACTOR), float(available_memory())


def check_output_memory(duration: float, output_interval: float, *,
                        options: SolverOptions | None = None) -> None:
    """Refuse a run whose recorded output would not fit in memory.

    Parameters
    ----------
    duration : float
        Simulated time [s].
    output_interval : float
        Interval of the recorded output [s].
    options : SolverOptions or None, default None
        The run's options, whose ``output_interval`` the message names where it came from
        (:func:`setting_hint`: ``solver.output_interval ([solver] in run.toml)``); None: the
        options in force (:func:`feeddrive.engine.options.current`) when the interval is
        theirs.

    Raises
    ------
    ParameterError
        When the output (with its working copies) would need more than half the available
        memory; the message names the duration and the way out.
    """
    samples, need, free = output_memory(duration, output_interval)
    if need > 0.5 * free:
        if options is None:
            from .options import current

            options = current()
        hint = (setting_hint(options, "output_interval")
                if options.output_interval == output_interval else
                "the output interval (options.output_interval, a [solver] table's "
                "output_interval)")
        raise ParameterError(
            "duration", duration,
            f"{samples:.3g} output samples (one per {output_interval:g} s) would need about "
            f"{need / 2**30:.3g} GiB, more than half the {free / 2**30:.3g} GiB available; "
            f"shorten the duration [s] or raise {hint}")


def time_constants(params: DriveParameters, drive: str, speed: float) -> dict[str, float]:
    """The parameter set's fast time constants, by name, at a table speed.

    The bristle relaxation F_c/(σ0·|v|) of each LuGre site (Wang2021 Eqs. (9)–(11)) and each
    motor's current loop L/(R + K_ip): the candidates for what forces small solver steps.

    Parameters
    ----------
    params : DriveParameters
        The parameter set [SI].
    drive : str
        The drive name (which sites and motors take part).
    speed : float
        Table speed the relaxation is evaluated at [m/s]; at least 1 µm/s is used.

    Returns
    -------
    dict of str to float
        Description → time constant [s].

    References
    ----------
    .. [1] Wang2021 Eqs. (9)–(11).
    """
    v = max(abs(speed), 1e-6)
    out: dict[str, float] = {}
    sites = {"ddfs": ("screw", "nut", "guide"), "cdfs": ("screw", "guide")}.get(drive,
                                                                               ("guide",))
    for site in sites:
        lugre = getattr(params.friction, site)
        if not hasattr(lugre, "bristle_stiffness"):  # a law with parameters of its own
            continue
        fc = min(lugre.positive.coulomb_force, lugre.negative.coulomb_force)
        out[f"{site} bristle relaxation F_c/(σ0·|v|)"] = fc / (lugre.bristle_stiffness * v)
    c = params.controller
    motors: dict[str, Any] = {"cdfs": {"screw motor": params.screw_motor},
                              "ddfs": {"screw motor": params.screw_motor,
                                       "hollow motor": params.hollow_motor}}.get(drive, {})
    linear = getattr(params, "linear_motor", None)
    if not motors and linear is not None:
        motors = {"linear motor": linear}
    for name, motor in motors.items():
        out[f"{name} current loop L/(R + K_ip)"] = motor.inductance / (
            motor.resistance + c.current_gain)
    return out


def profile_speed(profile: Any) -> float:
    """The largest commanded table speed of a speed profile: its amplitude or its largest sample.

    Parameters
    ----------
    profile : Profile
        A reference profile (with ``table_speed`` or ``table_amplitude``).

    Returns
    -------
    float
        The speed [m/s]; 1 mm/s when the profile has none.
    """
    for name in ("table_speed", "table_amplitude"):
        value = getattr(profile, name, None)
        if value is not None:
            speed = float(np.max(np.abs(np.asarray(value, dtype=float)), initial=0.0))
            return speed or 1e-3
    return 1e-3


def step_rate_problem(*, steps: int, probe_time: float, duration: float, max_steps: int,
                      params: DriveParameters, drive: str, speed: float,
                      max_steps_hint: str = "max_steps") -> str | None:
    """Why a run cannot finish within its step limit, judged from a short probe, or None.

    The probe's step rate is projected over the duration; when it exceeds ``max_steps`` (with
    a margin) the message names the cause — the fastest time constant, or a chattering
    solution — and the remedies.

    Parameters
    ----------
    steps : int
        Steps the probe took.
    probe_time : float
        The probe's simulated time [s].
    duration : float
        The run's simulated time [s].
    max_steps : int
        The solver's step limit.
    params : DriveParameters
        The parameter set [SI].
    drive : str
        The drive name.
    speed : float
        The run's largest commanded table speed [m/s].
    max_steps_hint : str, default "max_steps"
        Where the step limit is raised, as the user gave it (:func:`setting_hint`:
        ``--max-steps``, ``solver.max_steps ([solver] in run.toml)``, …).

    Returns
    -------
    str or None
        A one-line refusal, or None when the run can finish.
    """
    rate = steps / probe_time
    projected = rate * duration
    if projected * STEP_MARGIN <= max_steps:
        return None
    h = probe_time / max(steps, 1)
    taus = time_constants(params, drive, speed)
    name, tau = min(taus.items(), key=lambda kv: kv[1])
    if tau < 10.0 * h:
        cause = (f"the fastest time constant, {name} = {tau:.3g} s, forces steps of "
                 f"{h:.3g} s")
    else:
        cause = (f"steps of {h:.3g} s, far below every parameter time constant (the fastest "
                 f"is {name} = {tau:.3g} s): the solution chatters")
    return (f"refused before integrating: the run would exceed the maximum number of steps, "
            f"max_steps = {max_steps}: the solver needs about {rate:.3g} steps per simulated "
            f"second here, {projected:.3g} for {duration:g} s (measured over the first "
            f"{probe_time:.3g} s); {cause}; change that parameter, shorten the duration [s], "
            f"raise {max_steps_hint}, or use the stiff solver (options.method = "
            "'auto': RODAS4 where the problem is stiff)")


def probe_time(duration: float, base: float) -> float:
    """The simulated time of the step-rate probe run before a long simulation.

    Parameters
    ----------
    duration : float
        The run's simulated time [s].
    base : float
        The sample period the probe is a multiple of [s].

    Returns
    -------
    float
        ``PROBE_TIME`` rounded to a multiple of ``base`` [s]; 0 (no probe) when the run is not
        much longer than the probe.
    """
    if duration <= 4.0 * PROBE_TIME:
        return 0.0
    return max(1, round(PROBE_TIME / base)) * base

