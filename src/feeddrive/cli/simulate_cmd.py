"""`feeddrive simulate`."""

from __future__ import annotations

import math
from typing import Any

import typer

from ..engine import options as _opt
from ..engine.options import layered
from ..io.outputs import PLOT_FORMATS, RESULT_FORMATS
from . import _units
from ._common import (
    EXIT_FAILED,
    EXIT_UNSTABLE,
    MM_PER_S,
    PRESET_HELP,
    _fail,
    app,
    console,
    err_console,
    outputs,
    print_json,
    progress_bar,
    refuse_beside_machine,
    refuse_unused,
    resolve_parameters,
    run_outcome,
    save_output,
    user_errors,
)
from ._solver import accuracy_options, max_steps_help
from ._solver_report import integrator_line, solver_counts, solver_json

#: every drive topology, for --help (the registry is not imported at start-up: it loads numba;
#: tests/integration/test_cli_new_user3.py checks this against feeddrive.registry)
ALL_DRIVES = "cdfs|ddfs|linear-motor|rack-pinion"
#: the same list as words, for help texts ("cdfs, ddfs, linear-motor or rack-pinion")
ALL_DRIVES_TEXT = " or ".join(ALL_DRIVES.replace("|", ", ").rsplit(", ", 1))
PROFILES = ("constant", "sine", "trapezoid", "stepdown", "csv")
DEFAULT_METHOD = "modal"  # as feeddrive.engine.simulate.SolverOptions.method (a test checks it)
#: the integrators offered (feeddrive.engine.simulate.METHODS without the fixed-step order checks)
CLI_METHODS = ("modal", "dopri5", "auto", "rodas4", "dopri5-dense")


def method_help() -> str:
    """``--method``'s help, the default method and the Rosenbrock method of ``modal`` and
    ``auto`` read from the engine's constants (:data:`feeddrive.engine.options.DEFAULT_METHOD`,
    :data:`~feeddrive.engine.options.DEFAULT_ROSENBROCK` and its label; the help had said
    RODAS4 after the default became RODAS5P).

    Returns
    -------
    str
        The help text.
    """
    rosenbrock = _opt.DEFAULT_ROSENBROCK
    label = _opt.ROSENBROCKS[rosenbrock].label
    default = _opt.DEFAULT_METHOD
    return (f"Integrator: modal (DOPRI5 and the Rosenbrock method of --rosenbrock, {label} "
            "by default, switched on stiffness and cost, steps capped on lightly damped "
            "modes), dopri5 (every output instant a step end, as the v1 engine; friction "
            "reversals located), auto (DOPRI5 and the Rosenbrock method switched on stiffness "
            "and cost, no cap), rodas4 (RODAS4 throughout) or dopri5-dense; default: the "
            f"parameter file's [solver] method, else {default}.")


#: what --max-steps does: before the start, the fewest steps the largest step allows
#: (feeddrive.engine.budget.run_budget, checked below; no bound for the dense-output methods,
#: whose steps are not capped) and dopri5's probe (engine.simulate._check_step_rate); then the
#: solver stops at the limit (tests/integration/test_cli_simulate_s18.py checks each)
MAX_STEPS_HELP = max_steps_help(probe=True)


def _say(text: str) -> None:
    console.print(text, markup=False, highlight=False, soft_wrap=True)


@app.command("simulate")
@user_errors
@outputs(output=RESULT_FORMATS, plot=PLOT_FORMATS)
@accuracy_options
def simulate_command(
    drive: str = typer.Option("cdfs", "--drive", metavar=ALL_DRIVES,
                              help="cdfs, ddfs, linear-motor (a "
                              "direct-drive table; default preset linear-motor-example) or "
                              "rack-pinion"),
    table_speed: float | None = typer.Option(
        None, "--table-speed", help="Table speed [mm/s]: the command (constant), the "
        "amplitude (sine), the top speed (trapezoid), the first step (stepdown). Required "
        "except for --profile csv."),
    nut_speed: float = typer.Option(0.0, "--nut-speed", help="Nut (hollow-motor) speed "
                                    "[mm/s], DDFS only (the amplitude for --profile sine)."),
    position: float = typer.Option(400.0, "--position", help="Table position on the screw "
                                   "[mm]."),
    duration: float | None = typer.Option(
        None, "--duration", help="Simulated time [s] (default 10 s; stepdown: as long as "
        "the staircase; csv: as long as the file)."),
    profile: str = typer.Option("constant", "--profile",
                                help="constant, sine, trapezoid, stepdown or csv"),
    frequency: float = typer.Option(0.2, "--frequency", help="Sine frequency [Hz]."),
    ramp_time: float = typer.Option(0.5, "--ramp-time", help="Trapezoid: ramp up and ramp "
                                    "down time [s]."),
    lowest_speed: float = typer.Option(0.05, "--lowest-speed", help="Stepdown: last step "
                                       "[mm/s]."),
    step: float = typer.Option(0.01, "--step", help="Stepdown: speed step [mm/s] "
                               "(Wang2021 Sect. 6: 0.01 mm/s)."),
    dwell: float = typer.Option(4.0, "--dwell", help="Stepdown: time per step [s]."),
    profile_file: str | None = typer.Option(
        None, "--profile-file", help="csv: a CSV with columns time [s] and table_speed "
        "[mm/s] (optionally nut_speed [mm/s]); units in the header are honoured."),
    method: str | None = typer.Option(None, "--method", help=method_help()),
    max_steps: int | None = typer.Option(None, "--max-steps", help=MAX_STEPS_HELP),
    preset_name: str | None = typer.Option(None, "--preset", help=PRESET_HELP),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
    output: str | None = typer.Option(None, "--output", help="Write signals to "
                                      "FILE.csv|.parquet|.nc|.mat"),
    plot: str | None = typer.Option(None, "--plot", help="Write a PNG of the run."),
    error_estimate: bool = typer.Option(
        False, "--error-estimate", help="Also estimate the run's global integration error per "
        "signal, from a second run with every tolerance 10× tighter (it costs that run); "
        "not available with --machine."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
    force: bool = typer.Option(False, "--force", help="Replace existing --output/--plot files."),
    machine: str | None = typer.Option(
        None, "--machine", help="A machine file (TOML, docs/machine.md) or a built-in machine "
        "(xy-table, gantry): simulate its axes following --contour; a drive's options (--drive, "
        "--table-speed, --profile, …) are refused beside it, --params sets its integrator."),
    contour: str = typer.Option("circle", "--contour",
                                metavar="circle|line|corner|csv|together",
                                help="--machine: the path (default circle); together: every "
                                "axis moves --length at once (a gantry)."),
    radius: float = typer.Option(50.0, "--radius", help="--machine: circle radius, corner "
                                 "blend radius [mm]."),
    feed: float = typer.Option(1000.0, "--feed", help="--machine: path feed F [mm/min]."),
    acceleration: float = typer.Option(1000.0, "--acceleration", help="--machine: lead-in "
                                       "and lead-out acceleration [mm/s^2]."),
    clockwise: bool = typer.Option(False, "--clockwise", help="--machine: run the circle "
                                   "clockwise (G02)."),
    start_angle: float = typer.Option(0.0, "--start-angle", help="--machine: circle start "
                                      "angle [deg]."),
    turns: float = typer.Option(1.0, "--turns", help="--machine: circle revolutions [rev]."),
    length: float = typer.Option(100.0, "--length", help="--machine: line length, corner "
                                 "leg length, travel of --contour together [mm]."),
    angle: float = typer.Option(0.0, "--angle", help="--machine: line direction, corner "
                                "turn (0: 90) [deg]."),
    contour_file: str | None = typer.Option(None, "--contour-file", help="--machine: a CSV "
                                            "path, columns x and y [mm]."),
    solver: Any = None,
) -> None:
    """Simulate a drive and print a summary: for constant, trapezoid and step-down commands
    the mean and ripple of table speed after the transient, stick fraction and verdict; for a
    sine the tracking error, reversal overshoot and stick time at reversals; always the
    following error and position deviation [µm]."""
    from ..engine.budget import (
        MEMORY_WARNING_BYTES,
        SUMMARY_SAMPLES,
        check_output_memory,
        check_output_samples,
        check_step_budget,
    )
    from ..engine.error_estimate import SHADOW_FACTOR
    from ..engine.simulate import (
        DriveSystem,
        SimulationInterrupted,
        run_options,
        simulate,
    )
    from ..model import reference
    from ..model.reference import ConstantSpeed, SampledSpeed, SineSpeed
    from ..parameters import ParameterError
    from ..parameters.validation import MISSING

    # each profile's own options (name, value, default): refused beside --machine and under
    # another profile
    profile_options = {
        "sine": (("--frequency", frequency, 0.2),),
        "trapezoid": (("--ramp-time", ramp_time, 0.5),),
        "stepdown": (("--lowest-speed", lowest_speed, 0.05), ("--step", step, 0.01),
                     ("--dwell", dwell, 4.0)),
        "csv": (("--profile-file", profile_file, None),)}
    if machine is not None:
        from .machine_run import run_machine

        if error_estimate:  # refused as `export fmu --machine` refuses a drive's options
            raise ParameterError("--error-estimate", MISSING, "not available with --machine "
                                 "(the estimate is of one drive's run; --accuracy 0.1 runs "
                                 "the machine ten times tighter to compare)")
        # a drive's command: the machine's axes follow --contour (they were dropped without
        # a word; --params stays: its [solver] table sets the machine's integrator)
        refuse_beside_machine((
            ("--drive", drive, "cdfs"), ("--table-speed", table_speed, None),
            ("--nut-speed", nut_speed, 0.0), ("--position", position, 400.0),
            ("--preset", preset_name, None), ("--profile", profile, "constant"),
            *(given for options_of in profile_options.values() for given in options_of)),
            "its axes are set in the machine file and follow --contour")
        run_machine(machine, contour=contour, radius=radius, feed=feed,
                    acceleration=acceleration, clockwise=clockwise, start_angle=start_angle,
                    turns=turns, length=length, angle=angle, contour_file=contour_file,
                    duration=duration, options=layered(
                        [("command line", {"method": (method, "--method"),
                                           "max_steps": (max_steps, "--max-steps")})],
                        base=solver), output=output, plot=plot, as_json=as_json)
        return
    # the warnings printed from here on, for --json
    with _units.recorded_warnings() as printed:
        if profile not in PROFILES:
            raise ParameterError("--profile", profile, f"expected one of {', '.join(PROFILES)}")
        # options this run does not use, refused rather than dropped without a word (a
        # --frequency without --profile sine ran a constant speed; bad-input sweep, session 29)
        refuse_unused((
            ("--contour", contour, "circle"), ("--radius", radius, 50.0),
            ("--feed", feed, 1000.0), ("--acceleration", acceleration, 1000.0),
            ("--clockwise", clockwise, False), ("--start-angle", start_angle, 0.0),
            ("--turns", turns, 1.0), ("--length", length, 100.0), ("--angle", angle, 0.0),
            ("--contour-file", contour_file, None)),
            "an option of --machine, which a drive's run does not use")
        for used_by, options_of in profile_options.items():
            if used_by != profile:
                refuse_unused(options_of, f"applies to --profile {used_by}, not to --profile "
                              f"{profile}")
        if profile == "csv":
            refuse_unused((("--table-speed", table_speed, None), ("--nut-speed", nut_speed, 0.0)),
                          "not with --profile csv (the --profile-file's columns are the "
                          "command)")
        if profile != "csv" and table_speed is None:
            raise ParameterError("--table-speed", MISSING,
                                 f"required for --profile {profile} [mm/s]")
        if profile == "csv" and profile_file is None:
            raise ParameterError("--profile-file", MISSING, "required for --profile csv")
        if max_steps is not None and max_steps < 1:
            raise ParameterError("--max-steps", max_steps, "expected a whole number ≥ 1")
        if method is not None and method not in CLI_METHODS:
            raise ParameterError("--method", method, f"expected one of {', '.join(CLI_METHODS)}")
        options = layered([("command line", {"method": (method, "--method"),
                                             "max_steps": (max_steps, "--max-steps")})],
                          base=solver)
        params = resolve_parameters(preset_name, params_file, drive)
        system = DriveSystem(params, drive=drive,
                             table_position=_units.position("--position", position, params, drive))
        v_n = _units.speed("--nut-speed", nut_speed)
        # a command of 0 is refused before the run, not by its summary after it
        v_t = 0.0 if table_speed is None else _units.speed("--table-speed", table_speed,
                                                           nonzero=True)
        prof: ConstantSpeed | SineSpeed | SampledSpeed
        if profile == "constant":
            prof = ConstantSpeed(v_t, v_n)
        elif profile == "sine":
            if not (math.isfinite(frequency) and 0 < frequency <= reference.MAX_FREQUENCY):
                raise ParameterError("--frequency", frequency, f"expected a frequency > 0, ≤ "
                                     f"{reference.MAX_FREQUENCY:g} [Hz]")
            prof = SineSpeed(v_t, v_n, frequency)
        elif profile == "trapezoid":
            prof = reference.trapezoid(v_t, duration or 10.0, ramp_time=ramp_time, nut_speed=v_n)
        elif profile == "stepdown":
            low = _units.speed("--lowest-speed", lowest_speed, positive=True)
            if not lowest_speed < table_speed:  # type: ignore[operator]
                raise ParameterError("--lowest-speed", lowest_speed,
                                     f"expected < --table-speed = {table_speed:g} [mm/s]")
            try:
                prof, _ = reference.stepdown(v_t, low,
                                             step=_units.speed("--step", step, positive=True),
                                             dwell=dwell, nut_speed=v_n)
            except ParameterError as err:  # the API's names and SI: the options' and mm/s
                if err.field not in ("step", "dwell"):
                    raise
                given = step if err.field == "step" else dwell
                raise ParameterError(f"--{err.field}", given, err.message.replace(
                    "[m/s]", "[mm/s]")) from None
        else:
            prof = reference.from_csv(str(profile_file))
        if isinstance(prof, SampledSpeed) and duration is None:
            duration = float(prof.time[-1])
        duration = 10.0 if duration is None else duration
        if not (math.isfinite(duration) and duration > 0):
            raise ParameterError("--duration", duration, "expected a finite time > 0 [s]")
        # the options the run takes: the command line's over the set's [solver] table
        # (run_options), each setting's source kept for the refusals below
        taken = run_options(system, options)
        # the summary printed after the run needs its samples: refused before the run
        check_output_samples(duration, taken, samples=SUMMARY_SAMPLES, purpose="the summary")
        budget = check_step_budget(duration, taken)
        # .parquet/.csv outputs are written while the run goes (memory bounded); .nc/.mat at the end
        streamed = output is not None and output.lower().endswith((".parquet", ".csv"))
        if output is not None and output.lower().endswith(".mat"):
            # the MATLAB 5 format holds the run's struct below 4 GiB: refused before the run
            # (scipy's MatWriteError ended the run with a traceback: an outside check,
            # 2026-12-07); the model (≈ 30 ms, cached for the run) says what it records
            from ..engine.result import recorded_signals
            from ..io.results import check_mat_output

            check_mat_output(output, duration=duration, output_interval=taken.output_interval,
                             signals=len(recorded_signals(system.model(prof), system, prof)))
        if not streamed:  # a record that cannot fit is refused before any warning about it
            check_output_memory(duration, taken.output_interval, options=taken)
        if budget.memory_bytes > MEMORY_WARNING_BYTES and not streamed:
            _units.warn(f"--duration {duration:g} s keeps {budget.samples:.3g} samples: about "
                        f"{budget.memory_bytes / 1e9:.1f} GB of memory (a .parquet or .csv "
                        "--output is written as the run goes and keeps memory small)")
        if profile != "sine":  # a steady command: the observer's gain k checked there
            from ..analysis.compensation import observer_gain_warning

            # the lowest steady speed of the run: the observer's k destabilises slow sliding
            # (--lowest-speed as converted above: its warning printed once)
            steady = 0.0 if profile == "csv" else low if profile == "stepdown" else v_t
            k_warning = observer_gain_warning(system, steady, v_n)
            if k_warning:
                _units.warn(k_warning)
        bar, advance = (None, None) if as_json else progress_bar(
            duration, again=f"error estimate: the run {SHADOW_FACTOR:g}× tighter"
            if error_estimate else None)
        with run_outcome(bar):
            try:
                result = simulate(system, prof, duration, options=options,
                                  output=output if streamed else None, progress=advance,
                                  error_estimate=error_estimate)
            except SimulationInterrupted as stop:
                raise _kept(stop, output, streamed, bar) from None
        summary = result.summary()
        summary["profile"] = profile
        unwritten = None
        if output and streamed:
            # written while the run went, before its statistics and estimate existed
            from ..io.results import add_solver_record

            add_solver_record(output, result.solver_stats)
            summary["output"] = output
            summary["streamed"] = True
            if float(result.time[0]) > 0:  # the summary judged the kept tail, not the run:
                # said beside its numbers (they differed from the same run's without an
                # --output, silently: an outside check, 2026-12-07)
                from ..engine.simulate import KEEP_STREAMED

                a, b = summary["window_s"]
                summary.setdefault("warnings", []).append(
                    f"the summary is over {a:g}–{b:g} s, within the last {KEEP_STREAMED:g} s "
                    f"a streamed --output keeps in memory (without --output, or with .mat or "
                    f".nc, the whole run is judged); the whole run is in {output}: feeddrive "
                    f"analyze {output}")
        elif output:
            written, unwritten = save_output(result, output)
            if written is not None:
                summary["output"] = written
        if plot:
            from ..plots.result import plot_result

            summary["plot"] = str(plot_result(result, plot, title=run_header(
                drive, profile, profile_file, table_speed, frequency, position, duration,
                params.name)))
        for text in summary.get("warnings", []):  # the run's own, after those of its options
            _units.warn(text)
        summary["warnings"] = list(printed)  # the --json carries every warning printed
        if as_json:
            print_json({**summary, "solver": solver_json(summary["solver"])})
        else:
            _print_summary(summary, drive, profile, profile_file, table_speed, frequency,
                           position, duration, params.name, output, options)
        if output and not streamed and unwritten is not None:  # after the summary it kept
            raise _fail(unwritten, EXIT_FAILED)
        if summary.get("verdict") == "unstable":
            raise typer.Exit(code=EXIT_UNSTABLE)


def _kept(stop: Any, output: str | None, streamed: bool, bar: Any) -> Any:
    """An interrupted run's samples so far written to an ``--output`` that is not written as
    the run goes (``.mat``, ``.nc``), as ``.csv`` and ``.parquet`` keep theirs: it was lost
    (an outside check, 2026-12-07).  Ctrl-C again while it is written drops it (the file is
    written to a temporary name first).  The interruption to raise, naming the file."""
    from ..engine.simulate import SimulationInterrupted

    if not output or streamed or stop.result is None:
        return stop
    if bar is not None and bar.live.is_started:
        bar.stop()
    err_console.print(f"interrupted at t = {stop.t_reached:g} s: writing the run so far to "
                      f"{output} (Ctrl-C again drops it)", markup=False, highlight=False,
                      soft_wrap=True)
    try:
        written, unwritten = save_output(stop.result, output, what="the run so far")
    except KeyboardInterrupt:
        return stop
    if written is None:
        err_console.print(f"error: {unwritten}", markup=False, highlight=False,
                          soft_wrap=True)
        return stop
    return SimulationInterrupted(stop.t_reached, stop.result, written)


def run_header(drive: str, profile: str, profile_file: str | None, table_speed: float | None,
               frequency: float, position: float, duration: float, name: str) -> str:
    """What was run, in the user's words: the summary's first line and the ``--plot`` title.

    Parameters
    ----------
    drive : str
        The drive name.
    profile : str
        One of ``PROFILES``: ``"constant"``, ``"sine"``, ``"trapezoid"``, ``"stepdown"``,
        ``"csv"``.
    profile_file : str or None
        The profile's CSV file, for ``csv``.
    table_speed : float or None
        Commanded table speed or amplitude [mm/s].
    frequency : float
        Sine frequency [Hz].
    position : float
        Table start position [mm] (not shown for a linear motor, whose position moves no part
        of the model).
    duration : float
        Simulated time [s].
    name : str
        The parameter set's name.

    Returns
    -------
    str
        E.g. ``"DDFS, constant 1.55 mm/s, position 400 mm, 10 s (wang2021)"``.
    """
    what = (f"{profile_file}" if profile == "csv" else
            f"{profile} {table_speed:g} mm/s" + (f" at {frequency:g} Hz" if profile == "sine"
                                                 else ""))
    # a position only where the drive's model depends on it (the ball screw's K_eq(a))
    from ..model.mechanisms import mechanism

    where = f", position {position:g} mm" if mechanism(drive).uses_table_position else ""
    return f"{drive.upper()}, {what}{where}, {duration:g} s ({name})"


def _print_summary(summary: dict[str, Any], drive: str, profile: str,
                   profile_file: str | None, table_speed: float | None, frequency: float,
                   position: float, duration: float, name: str, output: str | None,
                   options: Any) -> None:
    _say(run_header(drive, profile, profile_file, table_speed, frequency, position, duration,
                    name))
    for label, text in _lines(summary, options):
        _say(f"  {label:24s} {text}")
    _say(f"  solver: {solver_counts(summary['solver'])}")
    for key in ("output", "plot"):
        if key in summary:
            _say(f"  wrote {summary[key]}")
    if profile == "stepdown" and output:
        _say(f"  analyse the steps with: feeddrive analyze {summary['output']}")


#: the verdict row's words for a constant-speed run the limit-cycle rule leaves undecided
UNSETTLED = ("; not settled, so not firm: the limit-cycle rule (below) has not decided; a "
             "longer --duration decides")


def _lines(s: dict[str, Any], options: Any = None) -> list[tuple[str, str]]:
    from ..analysis.creep_window import CreepThresholds, frequency_label

    n = _units.number
    rows: list[tuple[str, str]] = []
    if s.get("too_short"):  # diverged before the metrics' samples (Result.summary)
        return [("verdict", f"{s['verdict']}: the loop diverged at {n(s['diverged_at_s'], 3)} s, "
                            f"before the samples a summary needs; no creep or tracking "
                            "metrics"),
                ("integrator", integrator_line(s["solver"], options))]
    if s["profile"] == "sine":
        rows += [
            ("amplitude", f"{n(s['amplitude_mm_s'])} mm/s at {n(s['frequency_hz'])} Hz"),
            ("tracking error", f"rms {n(s['tracking_error_rms_mm_s'])} mm/s, max "
                               f"{n(s['tracking_error_max_mm_s'])} mm/s"),
        ]
        if not s["reversals"]:  # a run too short to reach a reversal in its window
            rows.append(("reversals", "none in the measured window: no overshoot or stick "
                                      "time to give (run longer)"))
        else:
            rows += [
                ("reversal overshoot", f"{n(100 * s['reversal_overshoot'], 3)} % of the "
                                       "amplitude"),
                ("stick time at reversal", f"{n(s['stick_time_at_reversals_s'], 3)} s below "
                                           f"10 % of the amplitude (the command: "
                                           f"{n(s['reference_dwell_at_reversals_s'], 3)} s), "
                                           f"mean of {s['reversals']} reversals"),
            ]
    else:
        freq = s["oscillation_frequency_hz"]
        segments = s.get("segments") or []
        if len(segments) > 1:
            # a staircase: its headline is what the holds come to, as `analyze` prints it
            # (the first hold's verdict read as the run's, issue 41 item 2)
            from ..analysis.trace import describe_critical

            for c in s["critical"]:
                sign = "" if c["direction"] == "positive" else " (negative)"
                rows.append((f"critical speed{sign}", describe_critical(
                    _si(c["lowest_smooth_mm_s"]), _si(c["first_creeping_mm_s"]), "hold",
                    unsettled=[v * MM_PER_S for v in c["unsettled_mm_s"]])))
            rows.append(("segments", f"{len(segments)} holds of one command speed, each judged "
                                  "over its own steady window:"))
            for i, g in enumerate(segments, start=1):
                f = g["oscillation_frequency_hz"]
                at = "" if f is None else (f", {frequency_label(g['stick_fraction'])} "
                                           f"{n(f, 3)} Hz")
                rows.append((f"  {i}: {n(g['command_speed_mm_s'])} mm/s",
                             f"{g['verdict']}{'' if g['settled'] else ' (not settled)'}, "
                             f"mean {n(g['mean_table_speed_mm_s'])} mm/s, "
                             f"ripple {n(g['ripple_ratio'], 3)}, stick "
                             f"{n(g['stick_fraction'], 3)}{at}; window "
                             f"{n(g['window_s'][0])}–{n(g['window_s'][1])} s"))
        else:
            rows += [
                ("command speed", f"{n(s['command_speed_mm_s'])} mm/s"),
                ("mean table speed", f"{n(s['mean_table_speed_mm_s'])} mm/s"),
                ("ripple ratio", n(s["ripple_ratio"], 3)),
                ("min ratio", n(s["min_ratio"], 3)),
                ("stick fraction", n(s["stick_fraction"], 3)),
                (frequency_label(s["stick_fraction"]),
                 "none" if freq is None else f"{n(freq, 3)} Hz"),
                ("verdict", f"{s['verdict']} (by the window rule, below)"
                            f"{'' if s.get('settled', True) else UNSETTLED}"),
            ]
            if "limit_cycle_verdict" in s:  # a constant speed: as `creep` judges a trial
                rows.append(("limit-cycle rule", f"{s['limit_cycle_verdict']}: "
                                                 f"{s['limit_cycle_reason']}"))
        rows.append(("verdict rule", s.get("verdict_rule") or CreepThresholds().describe()))
    a, b = s["window_s"]
    e = s.get("run") or s  # a staircase: over the whole run, not its first hold's window
    over = f", over the whole run ({n(e['window_s'][0])}–{n(e['window_s'][1])} s)" \
        if "run" in s else ""
    rows += [
        ("following error", f"max {n(e['following_error_max_um'], 3)} µm, rms "
                            f"{n(e['following_error_rms_um'], 3)} µm{over}"),
        ("position deviation", f"{n(e['position_deviation_um'], 3)} µm (peak-to-peak of the "
                               f"following error){over}"),
    ]
    if s["mean_screw_speed_mm_s"] is not None:  # a linear motor has no screw and no nut
        rows.append(("mean motor speeds", f"screw {n(s['mean_screw_speed_mm_s'])} mm/s, nut "
                                          f"{n(s['mean_nut_speed_mm_s'])} mm/s (× H)"))
    if "run" not in s:
        rows.append(("window", f"{n(a)}–{n(b)} s"))
    rows.append(("integrator", integrator_line(s["solver"], options)))
    estimate = s["solver"].get("error_estimate")
    if estimate is not None:
        sig = estimate["signals"]
        rows.append(("integration error", "estimated: table position "
                     f"{n(1e6 * sig['table_position']['absolute'], 3)} µm "
                     f"({n(sig['table_position']['relative'], 3)} of its range), table speed "
                     f"{n(1e3 * sig['table_speed']['absolute'], 3)} mm/s "
                     f"({n(sig['table_speed']['relative'], 3)}); largest "
                     f"{n(estimate['largest_relative']['relative'], 3)} of the range "
                     f"({estimate['largest_relative']['signal']}); by the "
                     f"{estimate['method']}"))
    return rows


def _si(mm_s: float | None) -> float | None:
    return None if mm_s is None else mm_s * MM_PER_S


