"""`feeddrive simulate`."""

from __future__ import annotations

from typing import Any

import typer

from ..control import ConstantSpeed, SineSpeed
from ..io import check_format
from ..outputs import check_output_file
from ..parameters import ParameterError
from ..plotting import plot_result
from ..simulate import DriveSystem, SolverOptions, simulate
from ._common import (
    EXIT_UNSTABLE,
    MM,
    MM_PER_S,
    app,
    console,
    err_console,
    print_json,
    resolve_parameters,
    user_errors,
)


@app.command("simulate")
@user_errors
def simulate_command(
    drive: str = typer.Option("cdfs", "--drive", help="cdfs or ddfs"),
    table_speed: float = typer.Option(..., "--table-speed", help="Table speed [mm/s] "
                                      "(the amplitude for --profile sine)."),
    nut_speed: float = typer.Option(0.0, "--nut-speed", help="Nut (hollow-motor) speed [mm/s], "
                                    "DDFS only (the amplitude for --profile sine)."),
    position: float = typer.Option(400.0, "--position", help="Table position on the screw [mm]."),
    duration: float = typer.Option(10.0, "--duration", help="Simulated time [s]."),
    profile: str = typer.Option("constant", "--profile", help="constant or sine"),
    frequency: float = typer.Option(0.2, "--frequency", help="Sine frequency [Hz]."),
    preset_name: str | None = typer.Option(None, "--preset", help="Named parameter set "
                                           "(default wang2021)."),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
    output: str | None = typer.Option(None, "--output", help="Write signals to "
                                      "FILE.csv|.parquet|.nc|.mat"),
    plot: str | None = typer.Option(None, "--plot", help="Write a PNG of the run."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
    force: bool = typer.Option(False, "--force", help="Replace existing --output/--plot files."),
    max_steps: int = typer.Option(SolverOptions.max_steps, "--max-steps",
                                  help="Most solver steps; a run projected to need more is "
                                  "refused at once, naming the time constant that forces it."),
) -> None:
    """Simulate a drive and print a summary: mean and ripple of table speed after the
    transient, stick fraction, motor speeds."""
    if max_steps < 1:
        raise ParameterError("--max-steps", max_steps, "expected a positive number of steps")
    inputs = [params_file]
    if output:
        check_format(output)
        check_output_file(output, option="--output", inputs=inputs, force=force)
    if plot:
        check_output_file(plot, option="--plot", inputs=[*inputs, output], force=force)
    params = resolve_parameters(preset_name, params_file)
    system = DriveSystem(params, drive=drive, table_position=position * MM)
    if profile == "constant":
        prof: ConstantSpeed | SineSpeed = ConstantSpeed(table_speed * MM_PER_S,
                                                        nut_speed * MM_PER_S)
    elif profile == "sine":
        prof = SineSpeed(table_speed * MM_PER_S, nut_speed * MM_PER_S, frequency)
    else:
        raise ValueError(f"--profile = {profile!r}: expected constant or sine")
    result = simulate(system, prof, duration, options=SolverOptions(max_steps=max_steps))
    summary = result.summary()
    if output:
        summary["output"] = str(result.save(output))
    if plot:
        summary["plot"] = str(plot_result(result, plot))
    for text in summary["warnings"]:
        err_console.print(f"warning: {text}", markup=False, highlight=False, soft_wrap=True)
    if as_json:
        print_json(summary)
    else:
        _print_summary(summary, drive, table_speed, position, duration, params.name)
    if summary["verdict"] == "unstable":
        raise typer.Exit(code=EXIT_UNSTABLE)


def _print_summary(summary: dict[str, Any], drive: str, table_speed: float, position: float,
                   duration: float, name: str) -> None:
    console.print(f"[bold]{drive.upper()}[/] at {table_speed:g} mm/s, position {position:g} mm, "
                  f"{duration:g} s ({name})")
    for key in ("mean_table_speed_mm_s", "ripple_ratio", "min_ratio", "stick_fraction",
                "stick_slip_frequency_hz", "verdict", "mean_screw_speed_mm_s",
                "mean_nut_speed_mm_s", "window_s"):
        console.print(f"  {key:26s} {summary[key]}")
    s = summary["solver"]
    console.print(f"  solver: {s['method']}, {s['steps']} steps, {s['rejected_steps']} rejected, "
                  f"{1e3 * s['wall_time_s']:.1f} ms")
    for key in ("output", "plot"):
        if key in summary:
            console.print(f"  wrote {summary[key]}")
