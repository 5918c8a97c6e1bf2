"""`feeddrive creep`: critical creeping speed and creeping bands."""

from __future__ import annotations

from typing import Any

import typer

from ..analysis import protocol
from . import _units
from ._common import MM_PER_S, app, console, print_json, resolve_parameters, user_errors
from ._solver import accuracy_options
from .simulate_cmd import ALL_DRIVES, ALL_DRIVES_TEXT

_LOW, _HIGH = (round(v / MM_PER_S, 9) for v in protocol.SPEED_RANGE)


def not_estimated() -> str:
    """What ``creep`` says when the search from rest can make no integration-error estimate
    (``feeddrive.analysis.critical.shadow_possible``).

    Returns
    -------
    str
        The line.
    """
    from ..engine.error_estimate import SHADOW_FACTOR
    from ..engine.options import MIN_RELATIVE

    return (f"Integration error: not estimated — a run {SHADOW_FACTOR:g}× tighter than these "
            f"settings would ask for less than {MIN_RELATIVE:g} relative (double precision's "
            "reach)")


@app.command("creep")
@user_errors
@accuracy_options
def creep_command(
    drive: str = typer.Option("cdfs", "--drive", metavar=ALL_DRIVES, help=ALL_DRIVES_TEXT),
    position: float = typer.Option(400.0, "--position", help="Table position [mm]."),
    nut_speed: float = typer.Option(0.0, "--nut-speed", help="Hollow-motor speed [mm/s] (DDFS)."),
    method: str = typer.Option("both", "--method", help="bisect (from rest), stepdown (the "
                               "paper's protocol on a running table) or both"),
    low: float = typer.Option(_LOW, "--low", help="Lowest speed tested [mm/s] (as "
                              "`reproduce`)."),
    high: float = typer.Option(_HIGH, "--high", help="Highest speed tested, where the "
                               "step-down starts [mm/s] (as `reproduce`)."),
    initial_duration: float = typer.Option(protocol.TRIAL_DURATION, "--initial-duration",
                                           help="First trial length [s], at least 2 (the "
                                           "rule's settle time); doubled until the verdict "
                                           "is decided."),
    max_duration: float = typer.Option(protocol.TRIAL_MAX_DURATION, "--max-duration",
                                       help="Longest trial [s], at least the first "
                                       "(--initial-duration); still undecided then: "
                                       "'undecided'."),
    ripple_threshold: float | None = typer.Option(
        None, "--ripple-threshold", help="Define the critical speed by a ripple threshold "
        "instead, for a forced oscillation (motor torque ripple, e.g. --preset "
        "wang2021-ripple): the lowest command above which the steady peak-to-peak table-speed "
        "ripple stays below this fraction of the command [fraction]."),
    preset_name: str | None = typer.Option(None, "--preset", help="Named parameter set."),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
    solver: Any = None,
) -> None:
    """Critical creeping speed [mm/s]: the upper edge of the highest creeping band (the lowest
    tested speed above every stick-slip or sustained oscillation), resolution 0.01 mm/s, with
    every creeping band found and its kind.  Each trial runs until decided (smooth, stick-slip,
    oscillation) or answers 'undecided'.  With --method both, the answers from rest and from a
    running table are shown.  The protocol (speed grid, steps) is the one `reproduce` uses,
    so both give one number.  The search from rest states the table-speed integration error
    of the trials that decide it: their difference to the same trials run with every
    tolerance 10× tighter (7–9 % more CPU), an estimate, not a bound, written with the
    measured range of its ratio to the true error (docs/model.md)."""
    from ..analysis.critical import (
        critical_speed_from_rest,
        critical_speed_stepdown,
        format_bands,
        format_integration_error,
        shadow_possible,
    )
    from ..engine.simulate import DriveSystem

    if method not in ("bisect", "stepdown", "both"):
        raise ValueError(f"--method = {method!r}: expected bisect, stepdown or both")
    rule = _units.trial_rule(max_duration, initial_duration)
    params = resolve_parameters(preset_name, params_file, drive)
    system = DriveSystem(params, drive=drive,
                         table_position=_units.position("--position", position, params, drive))
    v_n = _units.speed("--nut-speed", nut_speed)
    lo, hi = _units.speed_range("--low", low, "--high", high)
    # the drive, and where its table is when that matters (not for a linear motor)
    where = drive.upper() + (f" at {position:g} mm" if system.topology().uses_table_position
                             else "")
    if ripple_threshold is not None:
        from ..analysis.forced import threshold_critical_speed
        from ..parameters import ParameterError

        if not 0 < ripple_threshold <= 10:
            raise ParameterError("--ripple-threshold", ripple_threshold,
                                 "expected a fraction of the command in (0, 10]")
        res = threshold_critical_speed(system, v_n, threshold=ripple_threshold,
                                       speed_range=(lo, hi),
                                       coarse_step=min(protocol.COARSE_STEP, (hi - lo) / 2),
                                       resolution=protocol.RESOLUTION)
        res.update(parameter_set=params.name, table_position_mm=position,
                   integrator=solver.describe())
        if as_json:
            print_json(res)
            return
        shown = (f"{res['critical_speed_mm_s']:.2f} mm/s ({res['kind']} below it)"
                 if res["critical_speed_mm_s"] is not None else res["status"])
        console.print(f"{where}, v_n = {nut_speed:g} mm/s: critical speed {shown}",
                      markup=False, highlight=False)
        console.print(f"Rule: {res['rule']}", markup=False, highlight=False)
        console.print(f"Integrator: {solver.describe()}", markup=False, highlight=False)
        return
    results = []
    estimate = shadow_possible()  # not where the settings leave no tighter run
    if method in ("bisect", "both"):
        results.append(critical_speed_from_rest(
            system, nut_speed=v_n, speed_range=(lo, hi),
            coarse_step=min(protocol.COARSE_STEP, (hi - lo) / 2),
            resolution=protocol.RESOLUTION, rule=rule, error_estimate=estimate))
    if method in ("stepdown", "both"):
        results.append(critical_speed_stepdown(
            system, nut_speed=v_n, start_speed=hi, lowest_speed=lo, step=protocol.RESOLUTION,
            coarse_step=protocol.STAIRCASE_COARSE_STEP, rule=rule))
    searches = [r.to_dict() for r in results]
    out = {"drive": drive, "table_position_mm": position, "nut_speed_mm_s": nut_speed,
           **({} if estimate or method == "stepdown"
              else {"integration_error": not_estimated()}),
           "parameter_set": params.name,
           "critical_speed_mm_s": searches[0]["critical_speed_mm_s"],
           "status": searches[0]["status"], "kind": searches[0]["kind"],
           "bands": searches[0]["bands"], "verdict_rule": rule.to_dict(),
           "integrator": solver.describe(), "searches": searches}
    if len(results) == 2:
        a, b = (r.critical_speed for r in results)
        out["start_condition_matters"] = a != b
    if as_json:
        print_json(out)
        return
    default_grid = (low, high) == (_LOW, _HIGH)
    for r, d in zip(results, searches, strict=True):
        console.print(f"{where}, start from {r.start}: critical "
                      f"creeping speed {r.display()}{format_integration_error(d)} "
                      f"({len(r.trials)} trials); creeping bands [mm/s]: {format_bands(d)}",
                      markup=False, highlight=False)
        if default_grid:
            console.print(f"  protocol {protocol.describe(r.start)}", markup=False,
                          highlight=False)
    console.print(f"Verdict rule: {rule.describe()}", markup=False, highlight=False)
    console.print(f"Integrator: {solver.describe()}", markup=False, highlight=False)
    if method != "stepdown" and not estimate:
        console.print(not_estimated(), markup=False, highlight=False)
