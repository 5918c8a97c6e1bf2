"""`feeddrive loops` and `feeddrive stability`: the linearised closed loop."""

from __future__ import annotations

import typer

from ..analysis import protocol
from ..io.outputs import PLOT_FORMATS
from . import _units
from ._common import (
    app,
    console,
    outputs,
    print_json,
    refuse_beside_machine,
    refuse_unused,
    resolve_parameters,
    user_errors,
)
from ._loops_text import print_loops
from .simulate_cmd import ALL_DRIVES, ALL_DRIVES_TEXT


@app.command("loops")
@user_errors
@outputs(plot=PLOT_FORMATS)
def loops_command(
    drive: str = typer.Option("cdfs", "--drive", metavar=ALL_DRIVES,
                              help=ALL_DRIVES_TEXT),
    table_speed: float = typer.Option(1.5, "--table-speed", help="Operating point: steady "
                                      "table speed [mm/s]."),
    nut_speed: float = typer.Option(0.0, "--nut-speed", help="Nut speed [mm/s], DDFS."),
    position: float = typer.Option(400.0, "--position", help="Table position [mm]."),
    with_friction: bool = typer.Option(False, "--with-friction", help="Linearise with the "
                                       "friction laws at steady sliding (default: "
                                       "frictionless loops)."),
    preset_name: str | None = typer.Option(None, "--preset", help="Named parameter set."),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
    plot: str | None = typer.Option(None, "--plot", help="Write a plot of the loops "
                                    "(PNG, PDF or SVG; its kind: --plot-kind)."),
    plot_kind: str = typer.Option("bode", "--plot-kind", help="bode (open-loop magnitude and "
                                  "phase, crossover and margins marked), nyquist, or step "
                                  "(closed-loop responses to a reference and a load step)."),
    force: bool = typer.Option(False, "--force", help="Replace an existing plot file."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
    machine: str | None = typer.Option(
        None, "--machine", help="A machine file or built-in machine (docs/machine.md): "
        "each axis' loops, and the MIMO closed loop of the whole machine (every axis at "
        "--table-speed; a drive's options and --plot are refused beside it)."),
) -> None:
    """Poles (frequency, damping ratio; rigid-body poles listed as such) and the velocity-
    and position-loop margins and bandwidths of every motor axis, from the closed loop
    linearised at steady sliding."""
    if machine is not None:
        from .machine_run import run_machine_loops

        # dropped without a word: `loops --machine M --plot p.png` exited 0 and wrote no plot
        # (a bad-input sweep, session 29)
        refuse_beside_machine((
            ("--drive", drive, "cdfs"), ("--nut-speed", nut_speed, 0.0),
            ("--position", position, 400.0), ("--preset", preset_name, None),
            ("--params", params_file, None)))
        refuse_beside_machine((("--plot", plot, None), ("--plot-kind", plot_kind, "bode")),
                              "a machine's loops are printed, not plotted")
        run_machine_loops(machine, table_speed=table_speed, with_friction=with_friction,
                          as_json=as_json)
        return
    from ..analysis.linear import loop_analysis
    from ..engine.simulate import DriveSystem
    from ..parameters import ParameterError
    from ..plots.linear import PLOT_KINDS

    if plot_kind not in PLOT_KINDS:
        raise ParameterError("--plot-kind", plot_kind, f"expected {', '.join(PLOT_KINDS)}")
    if plot is None:  # the plot's kind, without a plot to draw (it was dropped)
        refuse_unused((("--plot-kind", plot_kind, "bode"),),
                      "applies to --plot, which this run does not write")
    params = resolve_parameters(preset_name, params_file, drive)
    system = DriveSystem(params, drive, _units.position("--position", position, params, drive))
    # with friction steady sliding needs a speed: refused here in mm/s (the API said
    # "table_speed = 0.0 … [m/s]": an outside check, 2026-12-07)
    result = loop_analysis(system, _units.speed("--table-speed", table_speed,
                                                nonzero=with_friction),
                           _units.speed("--nut-speed", nut_speed),
                           frictionless=not with_friction)
    data = result.as_dict()
    if plot:
        from ..plots.linear import plot_loops

        data["plot"] = str(plot_loops(result, plot, plot_kind))
        data["plot_kind"] = plot_kind
    if as_json:
        print_json(data)
        return
    print_loops(f"{drive.upper()}", params.name, table_speed, with_friction, data)
    if plot:
        console.print(f"  wrote {data['plot']}")


@app.command("stability")
@user_errors
@outputs(plot=PLOT_FORMATS)
def stability_command(
    drive: str = typer.Option("cdfs", "--drive", metavar=ALL_DRIVES,
                              help=ALL_DRIVES_TEXT),
    nut_speed: float = typer.Option(0.0, "--nut-speed", help="Nut speed [mm/s], DDFS."),
    position: float = typer.Option(400.0, "--position", help="Table position [mm]."),
    low: float = typer.Option(1e3 * protocol.LINEAR_SPEED_RANGE[0], "--low",
                              help="Lowest table speed scanned [mm/s] (the default range is "
                              "the sweep's linear-band default too)."),
    high: float = typer.Option(1e3 * protocol.LINEAR_SPEED_RANGE[1], "--high",
                               help="Highest table speed scanned [mm/s]."),
    points: int = typer.Option(protocol.LINEAR_POINTS, "--points",
                               help="Log-spaced scan points, at least 2 (edges are then "
                               "bisected to 0.001 mm/s)."),
    preset_name: str | None = typer.Option(None, "--preset", help="Named parameter set."),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
    plot: str | None = typer.Option(None, "--plot", help="Write the scan [.png, .pdf, .svg]."),
    force: bool = typer.Option(False, "--force", help="Replace an existing --plot file."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """Table speeds at which steady sliding is linearly unstable (full model, every friction
    site and bristle state), with the unstable mode's frequency."""
    from ..analysis.linear import stability_band
    from ..engine.simulate import DriveSystem
    from ..parameters import ParameterError

    params = resolve_parameters(preset_name, params_file, drive)
    system = DriveSystem(params, drive, _units.position("--position", position, params, drive))
    lo, hi = _units.speed_range("--low", low, "--high", high)
    try:  # the scan's own check, before any linearisation, named as the option
        band = stability_band(system, _units.speed("--nut-speed", nut_speed), low=lo, high=hi,
                              points=points)
    except ParameterError as err:
        if err.field != "points":
            raise
        raise ParameterError("--points", err.value, err.message) from None
    data = band.as_dict()
    if plot:
        from ..plots.linear import plot_band

        data["plot"] = str(plot_band(band, plot))
    if as_json:
        print_json(data)
        return
    console.print(f"[bold]{drive.upper()}[/] ({params.name}), v_n = {nut_speed:g} mm/s, "
                  f"scan {low:g}–{high:g} mm/s:")
    for note in data["notes"]:
        console.print(f"  {note}", markup=False)
    if not band.intervals:
        console.print("  steady sliding is linearly stable at every speed scanned")
    # an edge at the scan's end is that end (≤ / ≥), not an edge found (a note says so); the
    # mode's frequency with the speed it is taken at and its range over the band
    for (lo_text, hi_text), (cut_lo, cut_hi), f, v, (f_lo, f_hi) in zip(
            band.edge_texts(), band.edges_at_scan_ends, band.mode_frequency_hz,
            data["unstable_mode_speed_mm_s"], band.mode_frequency_range_hz, strict=True):
        part = "its scanned part" if cut_lo or cut_hi else "the band"
        console.print(f"  unstable from {lo_text} to {hi_text} mm/s (mode {f:.2f} Hz at "
                      f"{v:.2f} mm/s, the geometric middle of {part}; "
                      f"{f_lo:.2f}–{f_hi:.2f} Hz at the speeds evaluated in it)")
    console.print(f"  rule: {data['rule']}", markup=False)
    if plot:
        console.print(f"  wrote {data['plot']}")
