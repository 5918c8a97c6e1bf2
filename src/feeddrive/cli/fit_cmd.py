"""`feeddrive fit` and `feeddrive predict`: a whole drive fitted to measured traces, and the
critical speed carried through the fit's uncertainty (docs/fitting.md)."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import typer

from ..io.outputs import PLOT_FORMATS, atomic_path, shown
from ..parameters import DriveParameters, ParameterError
from . import _units
from ._common import (
    STORE,
    DecimalOption,
    SepOption,
    app,
    console,
    err_console,
    outputs,
    print_json,
    resolve_parameters,
    user_errors,
)
from ._solver import accuracy_options
from .simulate_cmd import ALL_DRIVES, ALL_DRIVES_TEXT


def _say(text: str) -> None:
    console.print(text, markup=False, highlight=False, soft_wrap=True)


def _weights(items: list[str] | None) -> dict[str, float]:
    """``SIGNAL=W`` parsed (fit_drive checks the signal and the weight's range)."""
    out: dict[str, float] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        try:
            w = float(value)
        except ValueError:
            sep = ""
        if not sep or not name.strip():
            raise ValueError(f"--weight {item!r}: expected SIGNAL=W with a number W "
                             "(e.g. table_position=2)")
        out[name.strip()] = w
    return out


def _table_motor_constant(params: DriveParameters, drive: str, table_position: float) -> float:
    """The torque (or force) constant of the motor that drives the table, from the slot the
    topology names for it (``Mechanism.motor_output`` of its ``table_axis``) [N m/A or N/A]."""
    from ..engine.simulate import DriveSystem
    from ..model.reference import ConstantSpeed

    system = DriveSystem(params, drive, table_position)
    topology = system.topology()
    slot, _ = topology.motor_output(topology.table_axis)
    return system.model(ConstantSpeed(0.0)).parameter(slot)


#: ``fit``'s and ``validate``'s time unit: a CSV's, or with --map the variable's own
#: (their --sep and --decimal are every reader's, :data:`._common.SepOption`)
FitTimeUnitOption = Annotated[str | None, typer.Option(
    "--time-unit", help="Unit of the CSV traces' time column: s (default) or ms (with --map: "
    "time=VARIABLE[ms]).")]


@dataclass(frozen=True)
class CsvReading:
    """How the CSV traces are read (``--sep``, ``--decimal``, ``--time-unit``).

    Parameters
    ----------
    sep : str or None, default None
        Column separator; None: detected from the header.
    decimal : str, default "."
        Decimal mark.
    time_unit : str or None, default None
        Unit of the time column; None: the header's, else s.
    """

    sep: str | None = None
    decimal: str = "."
    time_unit: str | None = None

    def given(self) -> list[str]:
        """The options given.

        Returns
        -------
        list of str
            Their names as typed (``--sep``, ``--decimal``, ``--time-unit``).
        """
        return [o for o, on in (("--sep", self.sep is not None),
                                ("--decimal", self.decimal != "."),
                                ("--time-unit", self.time_unit is not None)) if on]


def _read_traces(traces: list[str], params: DriveParameters, drive: str, table_position: float,
                 signal: list[str] | None, command_speed: float | None,
                 profile_file: str | None, record_map: list[str] | None,
                 as_json: bool, replay: str | None = None,
                 reading: CsvReading | None = None) -> tuple[list[Any], list[str]]:
    """The records of ``fit`` and ``validate``: CSV traces (``read_experiment``, read as
    ``reading`` says) or, with ``--map``, MATLAB records (``read_rig_record``, ``replay``:
    its ``--input``); and the cleaning notes (printed unless JSON)."""
    from ..analysis.fit import read_experiment

    reading = reading or CsvReading()
    if profile_file and command_speed is not None:
        raise ValueError("--profile: give either --profile or --command-speed, not both")
    speed = None if command_speed is None else _units.speed("--command-speed", command_speed)
    if record_map:
        from ..analysis.rig_record import parse_map, read_rig_record

        if signal or speed is not None or profile_file:
            raise ValueError("--map: the roles choose the signals and the reference; not with "
                             "--signal, --command-speed or --profile")
        if reading.given():  # a .mat record has no text to read so
            option = reading.given()[0]
            raise ParameterError(option, getattr(reading, option[2:].replace("-", "_")),
                                 "applies to CSV traces, not to --map (.mat) records; give a "
                                 "variable's unit in the map instead, e.g. time=t_ms[ms]")
        roles = parse_map(record_map, replay)
        records = [read_rig_record(t, roles, params, drive=drive,
                                   table_position=table_position, input=replay)
                   for t in traces]
        notes = [n for r in records for n in r.notes]
        for note in notes if not as_json else []:
            _say(f"  {note}")
        return [r.experiment for r in records], notes
    reference = None
    if profile_file:
        from ..model.reference import from_csv

        prof = from_csv(profile_file)
        reference = (prof.time, prof.table_speed)
    torque_constant = _table_motor_constant(params, drive, table_position)
    ratio = 1.0
    if replay == "speed":
        from ..analysis.rig_record import _axis_ratio
        from ..engine.simulate import DriveSystem

        axis = DriveSystem(params, drive, table_position).topology().table_axis
        ratio = _axis_ratio(params, drive, table_position, axis)
    return [read_experiment(t, signals=signal, command_speed=speed, profile=reference,
                            torque_constant=torque_constant, input=replay, speed_ratio=ratio,
                            sep=reading.sep, decimal=reading.decimal,
                            time_unit=reading.time_unit)
            for t in traces], []


#: the --map option of fit and validate
_MAP_HELP = ("MATLAB .mat records (v5; v7.3 through h5py): ROLE=VARIABLE, repeat or quote "
             "several, e.g. --map 'time=t position=qm reference=qg force=vir'; a struct's "
             "field by its dotted path, e.g. time=rec.t position=rec.pos[mm], or a "
             "feeddrive .mat run's time=feeddrive.time position=feeddrive.table_position. "
             "Roles: time "
             "[s], reference (position reference [m]) or speed_reference [m/s], and the fitted "
             "position [m], speed [m/s], current [A], force [N] (motor force at the table), "
             "drive_force [N] (force on the table from the drive); with --input also torque "
             "[N m] or motor_speed [rad/s] (SI, or the unit in brackets after the variable, "
             "e.g. time=t_ms[ms] position=qm[mm]; docs/fitting.md).")
#: the --input option of fit and validate
_INPUT_HELP = ("Open-loop replay: the record's motor current [A], torque [N m], force [N] (the "
               "motor's force at the table) or motor speed [rad/s] (a CSV column "
               "motor_current, motor_torque, motor_force or motor_speed; with --map the roles "
               "current, torque, force, motor_speed) drives the model, interpolated linearly "
               "between the record's samples, the loops bypassed (no reference); one of "
               "current, torque, force, speed.")


@app.command("fit")
@user_errors
@outputs(out=(".toml",), plot=PLOT_FORMATS)
@accuracy_options
def fit_command(
    traces: Annotated[list[str], typer.Argument(
        help="Trace CSV files (simulate --output files, or measured: docs/measured-data.md), "
        "or MATLAB .mat records with --map; one experiment each, fitted together.")],
    free: Annotated[list[str] | None, typer.Option(
        "--free", help="Dotted parameter path to fit (repeat for several), e.g. "
        "controller.velocity_integral_gain; bounds: the parameter's plausible range.")] = None,
    drive: str = typer.Option("cdfs", "--drive", metavar=ALL_DRIVES,
                              help=ALL_DRIVES_TEXT),
    preset_name: str | None = typer.Option(None, "--preset", help="Starting parameter set "
                                           "(default wang2021)."),
    params_file: str | None = typer.Option(None, "--params", help="Starting parameters (TOML)."),
    weight: Annotated[list[str] | None, typer.Option(
        "--weight", help="SIGNAL=W: multiply that signal's residuals (already divided by "
        "the data's own noise level) by W, e.g. screw_current=0.5.")] = None,
    signal: Annotated[list[str] | None, typer.Option(
        "--signal", help="Measured signal to fit (repeat): table_position, table_speed, "
        "screw_current, nut_current, screw_torque, motor_current (default: table position "
        "and motor current or torque, those present).")] = None,
    command_speed: float | None = typer.Option(
        None, "--command-speed", help="Reference of traces without a command column: "
        "constant table speed [mm/s] after a 0.1-s ramp."),
    profile_file: str | None = typer.Option(
        None, "--profile", help="Reference of every trace from a CSV (time [s], table_speed "
        "[mm/s], as simulate --profile-file), on the traces' clock; it must cover them."),
    record_map: Annotated[list[str] | None, typer.Option("--map", help=_MAP_HELP)] = None,
    replay: str | None = typer.Option(None, "--input", metavar="current|torque|force|speed",
                                      help=_INPUT_HELP),
    sep: SepOption = None,
    decimal: DecimalOption = ".",
    time_unit: FitTimeUnitOption = None,
    position: float = typer.Option(400.0, "--position", help="Table position [mm]."),
    confidence: float = typer.Option(0.95, "--confidence", help="Interval level [fraction]."),
    max_evaluations: int = typer.Option(200, "--max-evaluations",
                                        help="Residual evaluations per stage [-]."),
    no_profile: bool = typer.Option(False, "--no-profile", help="Linear intervals only "
                                    "(no profile likelihood)."),
    workers: int | None = typer.Option(None, "--workers", help="Local processes for the "
                                       "Jacobian columns (default: none, in this process)."),
    dask_workers: int | None = typer.Option(None, "--dask-workers",
                                            help="A Dask LocalCluster of N workers."),
    scheduler: str | None = typer.Option(None, "--scheduler",
                                         help="Address of a running Dask scheduler."),
    out: str | None = typer.Option(None, "--out", help="Write the fitted set (extends the "
                                   "base set, with a [fit] record) to FILE.toml."),
    plot: str | None = typer.Option(None, "--plot", help="Write residual plots to FILE.png."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
    force: bool = typer.Option(False, "--force", help="Replace existing --out/--plot files."),
    solver: Any = None,
) -> None:
    """Fit parameters of a whole drive to measured time traces by least squares (several
    experiments at once), with standard errors, correlations, identifiability (condition
    number, poorly determined combinations), profile-likelihood intervals where the linear
    one is not credible, and a residual check. Values are in the parameter file's SI units."""
    from ..analysis.fit import fit_drive, plot_residuals

    if not free:
        raise ValueError("--free: give at least one parameter path to fit")
    if not (0 < confidence < 1):
        raise ValueError(f"--confidence {confidence!r}: expected a fraction in (0, 1)")
    params = resolve_parameters(preset_name, params_file, drive)
    table_position = _units.position("--position", position, params, drive)
    experiments, notes = _read_traces(traces, params, drive, table_position, signal,
                                      command_speed, profile_file, record_map, as_json, replay,
                                      CsvReading(sep, decimal, time_unit))
    progress = None if as_json else (lambda msg: console.print(f"  {msg}", markup=False,
                                                               highlight=False))
    result = fit_drive(params, experiments, free, drive=drive, table_position=table_position,
                       weights=_weights(weight), confidence=confidence,
                       max_evaluations=max_evaluations, profile=not no_profile,
                       workers=workers, dask_workers=dask_workers, scheduler=scheduler,
                       progress=progress)
    written = None
    if out:
        if params_file:
            extends = os.path.relpath(Path(params_file).resolve(), Path(out).resolve().parent)
        else:
            extends = preset_name or "wang2021"
        data_names = [os.path.relpath(Path(t).resolve(), Path(out).resolve().parent)
                      for t in traces]
        with atomic_path(out) as tmp:  # nothing partial under the name (a full disk)
            tmp.write_text(result.fitted_toml(extends, data_names), encoding="utf-8")
        written = out
    skipped = plot if plot and result.interrupted else None
    if skipped:  # its residuals are simulated again: not after Ctrl-C (it took 2.4–3.8 s to
        # stop: an outside check, 2026-12-07)
        plot = None
    if plot:
        plot_residuals(result, plot)
    data = result.to_dict()
    data["written"] = written
    data["plot"] = plot
    # the settings the fit started with; those it ended with: integration_check
    data["integrator"] = solver.describe()
    data["record_notes"] = notes
    if as_json:
        print_json(data)
        return
    level = f"{100 * confidence:.0f} %"
    _say(f"fit of {len(free)} parameter(s) to {len(traces)} trace(s), {drive.upper()}: "
         f"{result.evaluations} evaluations; {result.message}")
    _say(f"  integrator as started (the accuracy check below may tighten it): "
         f"{solver.describe()}")
    for e in result.estimates:
        if math.isfinite(e.low) and math.isfinite(e.high):
            ci = (f"{level} CI {e.low:.6g} … {e.high:.6g} (±{100 * e.relative_half_width:.2g} "
                  f"%, {e.interval})")
        else:
            ci = f"{level} interval not determined"
        state = "determined" if e.determined else f"POORLY DETERMINED: {e.issue}"
        _say(f"  {e.path} = {e.value:.6g} [{e.unit}] (start {e.start:.6g}), {ci}; {state}")
    cond = result.condition_number
    _say(f"  condition number (relative parameters) {cond:.3g}" if math.isfinite(cond)
         else "  condition number: not available")
    for c in result.poorly_determined:
        combo = " ".join(f"{v:+.2f}·{k}" for k, v in c["combination"].items())
        _say(f"  poorly determined combination (singular value {c['singular_value_ratio']:.2g}"
             f" of the largest): {combo}")
    for r in result.residuals:
        error = (f"; integration error {r.integration_error:.3g} "
                 f"({r.integration_error / r.noise:.2g}× the noise)"
                 if math.isfinite(r.integration_error) else "")
        structure = f"; {r.diagnostics.describe()}" if r.diagnostics is not None else ""
        _say(f"  residual {shown(Path(r.source).name)} {r.signal}: rms {r.rms:.4g}, "
             f"{r.ratio:.2f}× the data's noise {r.noise:.3g} [SI]{error}{structure}")
    check = result.integration
    if check is not None:
        last = check.history[-1] if check.history else {}
        shift, spread = last.get("estimate_shift_stderr"), last.get("stderr_shift")
        step = last.get("gauss_newton_step_stderr")
        step_text = ("" if step is None else
                     f"; the Gauss–Newton step at the optimum {step:.2g} standard errors"
                     + (" (the model's own roughness: it did not shrink with the integrator)"
                        if last.get("roughness") else ""))
        spread_text = (f"the standard errors by {100 * spread:.2g} %"
                       if spread is not None and last.get("stderr_shift_at")
                       else "no credible linear interval's standard error to compare")
        _say(f"  integrator {check.label} ({check.steps} tightening(s)): "
             + ("estimated integration error ≤ "
                f"{data['integration_check']['limit_fraction_of_noise']:g}× every signal's "
                f"noise; the estimates move by {shift:.2g} standard errors and "
                f"{spread_text} with it ten times tighter{step_text}"
                if check.met and shift is not None and spread is not None
                else f"intervals withheld: {check.reason}"))
    if result.hac is not None:
        bands = ", ".join(f"{b:.3g}" for b in result.hac.bandwidths)
        _say(f"  covariance: HAC sandwich (Newey–West, Bartlett kernel), bandwidth per "
             f"record {bands} samples (Andrews 1991); "
             + ("stable at half and double the bandwidth" if result.hac.stable else
                "NOT stable at half and double the bandwidth: the widest used"))
    if result.inadequate:
        err_console.print(f"warning: {result.inadequate}; intervals withheld", markup=False,
                          highlight=False, soft_wrap=True)
    if written:
        _say(f"wrote {shown(written)}")
    if plot:
        _say(f"wrote {shown(plot)}")
    if skipped:
        _say(f"  {shown(skipped)} not written: the fit was interrupted (its residuals would be "
             "simulated again)")
    if result.interrupted:
        raise typer.Exit(code=130)


@app.command("predict")
@user_errors
@outputs(store=STORE, plot=PLOT_FORMATS)
@accuracy_options
def predict_command(
    fit_file: str = typer.Argument(..., help="A fitted file (feeddrive fit --out)."),
    samples: int = typer.Option(100, "--samples", help="Monte Carlo samples [-]."),
    seed: int = typer.Option(0, "--seed", help="Seed of the draws [-]."),
    store: str | None = typer.Option(None, "--store", help="Results store (SQLite; default "
                                     "FIT.predict.sqlite); a rerun resumes from it."),
    workers: int | None = typer.Option(None, "--workers", help="Local processes "
                                       "(default: every core)."),
    dask_workers: int | None = typer.Option(None, "--dask-workers",
                                            help="A Dask LocalCluster of N workers."),
    scheduler: str | None = typer.Option(None, "--scheduler",
                                         help="Address of a running Dask scheduler."),
    resolution: float | None = typer.Option(None, "--resolution", help="Critical-speed "
                                            "search resolution [mm/s] (default 0.01)."),
    low: float | None = typer.Option(None, "--low", help="Lowest speed searched [mm/s]."),
    high: float | None = typer.Option(None, "--high", help="Highest speed searched [mm/s]."),
    plot: str | None = typer.Option(None, "--plot", help="Histogram and convergence plot "
                                    "FILE.png."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
    force: bool = typer.Option(False, "--force", help="Replace an existing --plot file."),
    solver: Any = None,
) -> None:
    """The critical creeping speed as a distribution: Monte Carlo over the fit's covariance
    (multivariate normal), each sample a critical-speed search from rest on the shared
    protocol, run through the sweep machinery (local pool or Dask; resumable store).
    Prints the 5/50/95 % points with their Monte Carlo 95 % intervals."""
    from ..analysis.predict import plot_prediction, predict
    from ..analysis.protocol import SPEED_RANGE

    rng = None
    if low is not None or high is not None:
        lo = _units.speed("--low", low, positive=True) if low is not None else SPEED_RANGE[0]
        hi = _units.speed("--high", high, positive=True) if high is not None else SPEED_RANGE[1]
        if not hi > lo:
            raise ValueError(f"--high {hi * 1e3:g}: expected > --low {lo * 1e3:g} [mm/s]")
        rng = (lo, hi)
    res = None if resolution is None else _units.speed("--resolution", resolution,
                                                        positive=True, warn_small=False)

    def started(todo: int, where: str) -> None:
        if not as_json:
            _say(f"  {todo} samples to compute on {where}")

    def progress(done: int, todo: int) -> None:
        if not as_json and (done == todo or done % max(1, todo // 10) == 0):
            _say(f"  {done}/{todo} samples")

    from ..sweep.executors import SweepAborted

    try:
        pred = predict(fit_file, samples=samples, seed=seed, store=store, workers=workers,
                       dask_workers=dask_workers, scheduler=scheduler, resolution=res,
                       speed_range=rng, progress=progress, started=started)
    except SweepAborted as err:
        err_console.print(f"error: {err}", markup=False, highlight=False, soft_wrap=True)
        raise typer.Exit(code=1) from None
    except KeyboardInterrupt:
        where = store or str(Path(fit_file).with_suffix(".predict.sqlite"))
        err_console.print(f"interrupted: every finished sample is in {shown(where)}; rerun "
                          "the same command to resume", markup=False, highlight=False,
                          soft_wrap=True)
        raise typer.Exit(code=130) from None
    if plot:
        plot_prediction(pred, plot)
    data = pred.to_dict()
    data["plot"] = plot
    data["integrator"] = solver.describe()
    if as_json:
        print_json(data)
        return
    _say(f"integrator: {solver.describe()}")
    _say(f"{pred.record.drive.upper()} critical speed from rest over {', '.join(pred.record.free)}"
         f": {samples} samples (seed {seed}), {pred.computed} computed now, store "
         f"{shown(pred.store)}")
    for p in data["percentiles"]:
        v, (a, b) = p["critical_speed_mm_s"], p["mc_interval_mm_s"]

        def fmt(x: float | str) -> str:
            return f"{x:.3f}" if isinstance(x, float) else x

        _say(f"  {p['percentile']:g} %: {fmt(v)} mm/s (Monte Carlo 95 % interval {fmt(a)} … "
             f"{fmt(b)})")
    _say(f"  search resolution {data['resolution_mm_s']:g} mm/s over "
         f"{data['speed_range_mm_s'][0]:g}–{data['speed_range_mm_s'][1]:g} mm/s; "
         f"{data['below_range']} below, {data['above_range']} above the range, "
         f"{data['failed']} failed; {data['refused_draws']} draws refused (invalid sets)")
    if plot:
        _say(f"wrote {shown(plot)}")


@app.command("validate")
@user_errors
@outputs(plot=PLOT_FORMATS)
@accuracy_options
def validate_command(
    fit_file: str = typer.Argument(..., help="A fitted file (feeddrive fit --out)."),
    traces: Annotated[list[str], typer.Argument(
        help="Held-out records (not used in the fit): trace CSV files, or MATLAB .mat "
        "records with --map.")] = ...,  # type: ignore[assignment]
    drive: str | None = typer.Option(None, "--drive", metavar=ALL_DRIVES,
                                     help="The records' drive (default: the fit's); a fit "
                                     "made for another drive is refused."),
    signal: Annotated[list[str] | None, typer.Option(
        "--signal", help="Measured signal to compare (repeat), as fit --signal.")] = None,
    command_speed: float | None = typer.Option(
        None, "--command-speed", help="Reference of records without a command column: "
        "constant table speed [mm/s] after a 0.1-s ramp."),
    profile_file: str | None = typer.Option(
        None, "--profile", help="Reference of every record from a CSV (time [s], "
        "table_speed [mm/s]), as fit --profile."),
    record_map: Annotated[list[str] | None, typer.Option("--map", help=_MAP_HELP)] = None,
    replay: str | None = typer.Option(None, "--input", metavar="current|torque|force|speed",
                                      help=_INPUT_HELP),
    sep: SepOption = None,
    decimal: DecimalOption = ".",
    time_unit: FitTimeUnitOption = None,
    level: float = typer.Option(0.95, "--level", help="Level of the prediction band "
                                "[fraction]."),
    plot: str | None = typer.Option(None, "--plot", help="Write measured, predicted and "
                                    "band per signal to FILE.png."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
    force: bool = typer.Option(False, "--force", help="Replace an existing --plot file."),
    solver: Any = None,
) -> None:
    """Simulate held-out records with a fitted set: per signal the fit % of the
    system-identification benchmarks (100·(1 − ‖y − ŷ‖/‖y − ȳ‖)), the NRMSE (rms error over
    the signal's range) and the fraction of the measured samples inside the prediction band
    the fit's covariance and the record's noise give (docs/fitting.md)."""
    from ..analysis.predict import read_fit_record
    from ..analysis.validate import plot_validation, validate

    record = read_fit_record(fit_file)
    experiments, notes = _read_traces(traces, record.parameters, record.drive,
                                      record.table_position, signal, command_speed,
                                      profile_file, record_map, as_json, replay,
                                      CsvReading(sep, decimal, time_unit))
    # its steps said as fit says its own (validate sat silent for 4–12 s: an outside check,
    # 2026-12-07)
    result = validate(fit_file, experiments, drive=drive, level=level,
                      progress=None if as_json else (lambda msg: console.print(
                          f"  {msg}", markup=False, highlight=False)))
    if plot:
        plot_validation(result, plot)
    data = result.to_dict()
    data["record_notes"] = notes
    data["plot"] = plot
    if as_json:
        print_json(data)
        return
    _say(f"{Path(fit_file).name} ({record.drive.upper()}, free: {', '.join(record.free)}) on "
         f"{len(experiments)} held-out record(s):")
    for s in result.signals:
        _say(f"  {shown(Path(s.source).name)} {s.signal}: fit {s.fit_percent:.2f} %, NRMSE "
             f"{s.nrmse:.3g}, {100 * s.inside_band:.1f} % inside the {100 * level:.0f} % "
             "prediction band")
    if plot:
        _say(f"wrote {shown(plot)}")
