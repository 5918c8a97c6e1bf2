"""`feeddrive sensitivity`: which parameter matters for the critical speed."""

from __future__ import annotations

import math
from typing import Annotated, Any

import typer

from ..io.outputs import PLOT_FORMATS, shown
from . import _units
from ._common import STORE, app, console, err_console, outputs, print_json, user_errors
from ._solver import accuracy_options
from .simulate_cmd import ALL_DRIVES, ALL_DRIVES_TEXT


def _fit_table(path: str) -> dict:
    """The ``[fit]`` table of a fitted file (its drive and table position [m]), or {}."""
    from ..parameters.toml_io import read_toml_file

    rec = read_toml_file(path, field="FIT.toml").get("fit")
    return rec if isinstance(rec, dict) else {}


def _say(text: str) -> None:
    console.print(text, markup=False, highlight=False, soft_wrap=True)


@app.command("sensitivity")
@user_errors
@outputs(store=STORE, plot=PLOT_FORMATS)
@accuracy_options
def sensitivity_command(
    fit_file: str | None = typer.Argument(
        None, metavar="FIT.toml", help="A parameter file, e.g. a fitted file (feeddrive fit "
        "--out), as `predict FIT.toml` takes it: the same as --params; a fitted file's drive "
        "and table position are the defaults."),
    drive: str | None = typer.Option(None, "--drive", metavar=ALL_DRIVES,
                                     help=ALL_DRIVES_TEXT + " [default: a fitted file's "
                                     "drive, else cdfs]"),
    preset_name: str | None = typer.Option(None, "--preset", help="Parameter set (default "
                                           "wang2021)."),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
    quantity: str = typer.Option("critical-speed", "--quantity", help="critical-speed (the "
                                 "simulated critical speed from rest) or linear-band (the "
                                 "linear band's upper edge: cheap)."),
    parameters: Annotated[list[str] | None, typer.Option(
        "--parameters", help="Only these dotted paths; * matches (repeat), e.g. "
        "'friction.screw.*'.")] = None,
    position: float | None = typer.Option(None, "--position", help="Table position [mm] "
                                          "[default: a fitted file's, else 400]."),
    store: str | None = typer.Option(None, "--store", help="Results store (SQLite); a "
                                     "rerun resumes from it (default: "
                                     "sensitivity-SET-DRIVE-QUANTITY.sqlite in the working "
                                     "folder)."),
    workers: int | None = typer.Option(None, "--workers", help="Local processes "
                                       "(default: every core)."),
    dask_workers: int | None = typer.Option(None, "--dask-workers",
                                            help="A Dask LocalCluster of N workers."),
    scheduler: str | None = typer.Option(None, "--scheduler",
                                         help="Address of a running Dask scheduler."),
    plot: str | None = typer.Option(None, "--plot", help="Tornado chart FILE.png."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
    force: bool = typer.Option(False, "--force", help="Replace an existing --plot file."),
    solver: Any = None,
) -> None:
    """Elasticity of the critical speed (or of the linear band's upper edge) to every nonzero
    numeric parameter (zero-valued ones with a stated scale: their derivative), by central
    differences through the sweep machinery. Each step is doubled from ±10 % until its
    effect is at least 10× the quantity's resolution, and checked by halving."""
    from ..analysis.sensitivity import STEPS, default_store, plot_tornado, sensitivity
    from ..parameters import load, preset

    if fit_file is not None:
        if params_file is not None:
            raise ValueError(f"{fit_file}: give the parameter file once, as FIT.toml or "
                             "--params, not both")
        params_file = fit_file
    if preset_name and params_file:
        raise ValueError("--params: give either --preset or --params, not both")
    source = params_file or preset_name or "wang2021"
    params = load(source) if params_file else preset(source)
    fitted = _fit_table(params_file) if params_file else {}
    drive = drive or str(fitted.get("drive", "cdfs"))
    table_position = (_units.position("--position", position, params, drive)
                      if position is not None else
                      float(fitted.get("table_position",
                                       _units.position("--position", 400.0, params, drive))))
    from ..sweep.executors import SweepAborted

    try:
        result = sensitivity(source, drive=drive, table_position=table_position,
                             quantity=quantity, patterns=parameters, store=store,
                             workers=workers, dask_workers=dask_workers, scheduler=scheduler,
                             progress=None if as_json else (lambda m: _say(f"  {m}")))
    except SweepAborted as err:
        err_console.print(f"error: {err}", markup=False, highlight=False, soft_wrap=True)
        raise typer.Exit(code=1) from None
    except KeyboardInterrupt:  # the store named (it was "the store": an outside check,
        # 2026-12-07)
        where = store or default_store(source, drive, quantity)
        err_console.print(f"interrupted: every finished point is in {where}; rerun the "
                          "same command to resume", markup=False, highlight=False,
                          soft_wrap=True)
        raise typer.Exit(code=130) from None
    if plot:
        plot_tornado(result, plot)
    data = result.to_dict()
    data["plot"] = plot
    data["integrator"] = solver.describe()
    if as_json:
        print_json(data)
        return
    _say(f"integrator: {solver.describe()}")
    what = "critical speed" if result.quantity == "critical_speed" else \
        "linear band's upper edge"
    steps = ", ±".join(f"{h:g}" for h in STEPS)
    _say(f"{result.parameter_set}, {drive.upper()}: {what} {result.base * 1e3:.4g} mm/s "
         f"(resolution {result.resolution * 1e3:g} mm/s); steps ±{steps} "
         f"until the effect is ≥ 10× the resolution; {result.evaluations} points on "
         f"{result.executor}")
    for e in result.entries:
        kind = "dQ/dp" if e.absolute else "E"
        if e.resolved:
            check = "halving agrees" if e.consistent else f"NONLINEAR ({e.note})"
            _say(f"  {e.path}: {kind} = {e.elasticity:+.3g} (step ±{100 * e.step:g} %, half "
                 f"step {e.halved:+.3g}: {check})")
        else:
            bound = f"|{kind}| < {e.bound:.2g}" if math.isfinite(e.bound) else "not resolved"
            _say(f"  {e.path}: {bound} ({e.note})")
    if result.skipped:
        _say(f"  left out ({len(result.skipped)}): " + "; ".join(
            f"{k} ({v})" for k, v in result.skipped.items()))
    if plot:
        _say(f"wrote {shown(plot)}")
