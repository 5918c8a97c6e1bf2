"""`feeddrive calibrate`: fit a named unknown parameter to a target critical speed."""

from __future__ import annotations

import math
from typing import Any

import typer

from ..analysis import protocol
from ..parameters import ParameterError
from . import _units
from ._common import (
    app,
    console,
    err_console,
    outputs,
    print_json,
    resolve_parameters,
    user_errors,
)
from ._solver import accuracy_options, file_table
from .simulate_cmd import ALL_DRIVES, ALL_DRIVES_TEXT

#: ``--out``'s help: what the written file's ``[solver]`` table is (:func:`fitted_set`)
OUT_HELP = ("Write the fitted set to FILE.toml, with the --params file's own [solver] table "
            "as read (none from a preset); the command line's integrator settings "
            "(--accuracy, --rtol, …) are this run's, not saved.")


@app.command("calibrate")
@user_errors
@outputs(out=(".toml",))
@accuracy_options
def calibrate_command(
    unknown: str = typer.Option("controller.velocity_integral_gain", "--unknown",
                                help="Dotted parameter path to fit."),
    low: float = typer.Option(500.0, "--low", help="Lower end of the search bracket "
                              "[SI unit of --unknown]."),
    high: float = typer.Option(20000.0, "--high", help="Upper end of the search bracket "
                               "[SI unit of --unknown]."),
    tolerance: float = typer.Option(0.02, "--tolerance",
                                    help="Relative width of the final bracket of the fit "
                                    "[fraction]."),
    max_duration: float = typer.Option(protocol.TRIAL_MAX_DURATION, "--max-duration",
                                       help="Longest creep trial [s], at least the "
                                       f"first trial's {protocol.TRIAL_DURATION:g} s; the "
                                       "default is the protocol of `feeddrive creep` and "
                                       "`reproduce`."),
    drive: str = typer.Option("cdfs", "--drive", metavar=ALL_DRIVES, help=ALL_DRIVES_TEXT),
    target: float = typer.Option(1.56, "--target", help="Target critical speed [mm/s] "
                                 "(default: Wang2021 Sect. 5.2, CDFS simulated)."),
    position: float = typer.Option(400.0, "--position", help="Table position [mm]."),
    nut_speed: float = typer.Option(0.0, "--nut-speed", help="Hollow-motor speed [mm/s]."),
    preset_name: str | None = typer.Option(None, "--preset", help="Starting parameter set."),
    params_file: str | None = typer.Option(None, "--params", help="Starting parameters (TOML)."),
    out: str | None = typer.Option(None, "--out", help=OUT_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
    force: bool = typer.Option(False, "--force", help="Replace an existing --out file."),
    solver: Any = None,
) -> None:
    """Fit one unknown so the drive's critical creeping speed matches a target: the drive
    creeps (stick-slip or sustained oscillation) 0.01 mm/s below the target and not at it.
    The fit is the geometric mean of the two values where those verdicts switch."""
    from ..analysis.calibrate import Target, Unknown, calibrate
    from ..parameters import save

    if not (0 < tolerance < 1):
        raise ParameterError("--tolerance", tolerance, "expected a fraction in (0, 1)")
    if not (math.isfinite(low) and low > 0):
        raise ParameterError("--low", low, f"expected 0 < --low < --high [SI unit of {unknown}]")
    if not (math.isfinite(high) and high > low):
        raise ParameterError("--high", high, f"expected > --low = {low:g} [SI unit of "
                                             f"{unknown}]")
    params = resolve_parameters(preset_name, params_file, drive)
    from ..analysis.fit import FitError, _field_meta

    try:  # a number (`--unknown name` said "name = 500.0: expected text", `table` "expected
        # Table": an outside check, 2026-12-07)
        _field_meta(params, unknown, "--unknown")
    except FitError as err:
        said = str(err).split(": ", 1)[1]
        if "params show" not in said:
            said += "; `feeddrive params show` prints the set's fields"
        raise ParameterError("--unknown", unknown, said) from None
    for value in (low, high):  # the bracket's ends, checked as fields before any trial
        try:
            params.replace_path(unknown, value)
        except ParameterError as err:
            if err.field == unknown and err.message.startswith("unknown field"):
                raise ParameterError("--unknown", unknown, f"{err.message}; `feeddrive params "
                                     "show` prints the set's fields") from None
            raise
    rule = _units.trial_rule(max_duration)
    result = calibrate(
        params, Target(drive=drive, critical_speed=_units.speed("--target", target, positive=True),
                       table_position=_units.position("--position", position, params, drive),
                       nut_speed=_units.speed("--nut-speed", nut_speed)),
        Unknown(path=unknown, low=low, high=high), relative_tolerance=tolerance, rule=rule,
        progress=None if as_json else (lambda msg: console.print(f"  {msg}")))
    written = out if out and result.reached else None
    if written:
        save(fitted_set(result.parameters, unknown, result.value, drive, target, position,
                        nut_speed, table=file_table(params_file)), written)
    achieved = result.achieved.to_dict()
    data = {"unknown": unknown, "value": result.value, "target_mm_s": target,
            "achieved_mm_s": achieved["critical_speed_mm_s"], "achieved": achieved["display"],
            "achieved_kind": achieved["kind"], "bands": achieved["bands"],
            "tolerance": tolerance, "interval": list(result.interval),
            "reached": result.reached, "reason": result.reason() or None,
            "evaluations": result.evaluations, "verdict_rule": rule.to_dict(),
            "integrator": solver.describe(), "written": written}
    if as_json:
        print_json(data)
    else:
        console.print(f"{unknown} = {result.value:.6g} → {drive.upper()} critical speed "
                      f"{achieved['display']} (target {target:g} mm/s), {result.evaluations} "
                      "evaluations", markup=False, highlight=False)
        console.print(f"Integrator: {solver.describe()}", markup=False, highlight=False)
        if written:
            console.print(f"wrote {written}", markup=False, highlight=False)
    if not result.reached:
        err_console.print(f"error: target {target:g} mm/s not reached: {result.reason()}"
                          + (f"; {out} not written" if out else ""),
                          markup=False, highlight=False, soft_wrap=True)
        raise typer.Exit(code=1)


def fitted_set(params: Any, unknown: str, value: float, drive: str, target: float,
               position: float, nut_speed: float, *, table: Any = ()) -> Any:
    """The fitted parameter set as ``calibrate --out`` writes it: named and described as fitted.

    So that a file written from ``wang2021`` is not taken for the preset (issue 24 item 10):
    the name gets ``-fitted``, the description says what was fitted to which target, when, by
    which version, and from which set.  Its ``[solver]`` table is ``table``, the starting
    file's own (:func:`feeddrive.cli._solver.file_table`), not the one the set loaded under
    the command carries, which holds the command line's values for the file's settings
    (``--accuracy 0.5`` over a file's ``accuracy = 0.1`` was saved as 0.5, ``--rtol 1e-8``
    was not: a one-off setting became the file's, or not, by which key the file had).

    Parameters
    ----------
    params : DriveParameters
        The set with the fitted value in place.
    unknown : str
        The fitted parameter's path.
    value : float
        Its fitted value [SI unit of the parameter].
    drive : str
        The drive the target belongs to.
    target : float
        The critical speed fitted to [mm/s].
    position : float
        The table position of the target [mm].
    nut_speed : float
        The nut speed of the target (DDFS) [mm/s].
    table : tuple of (str, object, str), default ()
        The ``[solver]`` table the set carries (:attr:`DriveParameters.solver`).

    Returns
    -------
    DriveParameters
        ``params`` renamed and re-described, carrying ``table``.
    """
    import datetime as dt
    from dataclasses import replace

    from .. import __version__

    when = dt.datetime.now(dt.UTC).strftime("%Y-%m-%d")
    vn = f", v_n = {nut_speed:g} mm/s" if nut_speed else ""
    note = (f"Fitted by feeddrive calibrate {__version__} on {when}: {unknown} = {value:.6g} "
            f"gives the {drive.upper()} critical speed {target:g} mm/s at {position:g} mm{vn}. "
            f"Started from {params.name!r}: {params.description}")
    return replace(params, name=f"{params.name}-fitted", description=note, solver=table)
