"""`feeddrive calibrate`: fit a named unknown parameter to a target critical speed."""

from __future__ import annotations

import typer

from ..analysis.calibrate import Target, Unknown, calibrate
from ..outputs import check_output_file
from ..parameters import save
from ._common import MM, MM_PER_S, app, console, print_json, resolve_parameters, user_errors


@app.command("calibrate")
@user_errors
def calibrate_command(
    unknown: str = typer.Option("controller.velocity_integral_gain", "--unknown",
                                help="Dotted parameter path to fit."),
    low: float = typer.Option(500.0, "--low", help="Lower end of the search bracket (SI)."),
    high: float = typer.Option(20000.0, "--high", help="Upper end of the search bracket (SI)."),
    drive: str = typer.Option("cdfs", "--drive", help="cdfs or ddfs"),
    target: float = typer.Option(1.56, "--target", help="Target critical speed [mm/s] "
                                 "(default: Wang2021 Sect. 5.2, CDFS simulated)."),
    position: float = typer.Option(400.0, "--position", help="Table position [mm]."),
    nut_speed: float = typer.Option(0.0, "--nut-speed", help="Hollow-motor speed [mm/s]."),
    preset_name: str | None = typer.Option(None, "--preset", help="Starting parameter set."),
    params_file: str | None = typer.Option(None, "--params", help="Starting parameters (TOML)."),
    out: str | None = typer.Option(None, "--out", help="Write the fitted set to FILE.toml."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
    force: bool = typer.Option(False, "--force", help="Replace an existing --out file."),
) -> None:
    """Fit one unknown so the drive's critical creeping speed matches a target."""
    if out:
        check_output_file(out, option="--out", inputs=[params_file], force=force)
    params = resolve_parameters(preset_name, params_file)
    result = calibrate(
        params, Target(drive=drive, critical_speed=target * MM_PER_S,
                       table_position=position * MM, nut_speed=nut_speed * MM_PER_S),
        Unknown(path=unknown, low=low, high=high),
        progress=None if as_json else (lambda msg: console.print(f"  {msg}")))
    if out:
        save(result.parameters, out)
    achieved = result.achieved.to_dict()["critical_speed_mm_s"]
    data = {"unknown": unknown, "value": result.value, "target_mm_s": target,
            "achieved_mm_s": achieved, "evaluations": result.evaluations, "written": out}
    if as_json:
        print_json(data)
        return
    console.print(f"{unknown} = {result.value:.6g} → {drive.upper()} critical speed "
                  f"{achieved} mm/s (target {target} mm/s), {result.evaluations} evaluations")
