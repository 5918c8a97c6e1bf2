"""`feeddrive circular`: the ISO 230-4 circular test on a simulated machine.

The logic lives in feeddrive.analysis.circular_run (circle, runs, trace),
feeddrive.analysis.circular (the quantities) and feeddrive.io.acceptance (the record).
"""

from __future__ import annotations

import math
from typing import Any

import typer

from ..io.outputs import PLOT_FORMATS
from ..parameters import ParameterError
from ._common import (
    MM,
    _stop_bar,
    app,
    console,
    err_console,
    interrupted,
    outputs,
    print_json,
    progress_bar,
    refuse_unused,
    user_errors,
)
from ._solver import accuracy_options, max_steps_help

MM_PER_MIN = 1e-3 / 60.0  # [m/s] per mm/min


def _say(text: str) -> None:
    console.print(text, markup=False, highlight=False, soft_wrap=True)


def parse_axes(text: str | None) -> tuple[str, str] | None:
    """``--axes X,Y`` → the two axis names (None: the machine's first two).

    Parameters
    ----------
    text : str or None
        E.g. ``"x,y"``.

    Returns
    -------
    tuple of str or None
        The names.
    """
    if text is None:
        return None
    names = [n.strip() for n in text.split(",")]
    if len(names) != 2 or not all(names) or names[0] == names[1]:
        raise ParameterError("--axes", text, "expected two different axis names X,Y, e.g. x,y")
    return names[0], names[1]


@app.command("circular")
@user_errors
@outputs(output=(".csv",), plot=PLOT_FORMATS)
@accuracy_options
def circular_command(
    machine: str = typer.Option("xy-table", "--machine", help="A machine file (TOML, "
                                "docs/machine.md) or a built-in machine (xy-table); the "
                                "circle's centre is at its axes' table_position."),
    axes: str | None = typer.Option(None, "--axes", help="The two axes as X,Y, e.g. x,y "
                                    "(default the machine's first two)."),
    radius: float = typer.Option(50.0, "--radius", help="Circle radius R [mm]."),
    feed: float = typer.Option(1000.0, "--feed", help="Path feed F [mm/min]."),
    acceleration: float = typer.Option(1000.0, "--acceleration", help="Feed ramp of the "
                                       "lead-in and lead-out [mm/s²]."),
    lead_arc: float | None = typer.Option(None, "--lead-arc", help="Lead-in arc and "
                                          "lead-out arc of each run [°] (default: the "
                                          "settling rule's — the feed ramp, then until the "
                                          "slowest closed-loop mode has decayed to 0.1 %)."),
    nut_speed: float = typer.Option(0.0, "--nut-speed", help="Nut speed of the DDFS axes "
                                    "[mm/s]: spun up before the path starts, kept to the "
                                    "end."),
    pitch: float | None = typer.Option(None, "--pitch", help="Period of the cyclic error to "
                                       "fit, the screw's lead [mm]."),
    reversal_angle: float = typer.Option(1.0, "--reversal-angle", help="Smallest turn back "
                                         "of the path's angle about the centre that ends a "
                                         "run [°]; smaller ones, stick-slip at a low feed, "
                                         "stay in their run and are counted in a note."),
    magnification: float | None = typer.Option(None, "--magnification", help="--plot: "
                                               "deviation magnification [-] (default: "
                                               "automatic)."),
    max_steps: int | None = typer.Option(None, "--max-steps", help=max_steps_help()),
    output: str | None = typer.Option(None, "--output", help="Write the trace (time [s], "
                                      "x [mm], y [mm]) to FILE.csv (analyze --circular reads "
                                      "it)."),
    plot: str | None = typer.Option(None, "--plot", help="Write the polar plot, CW and CCW "
                                    "overlaid."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
    force: bool = typer.Option(False, "--force", help="Replace existing --output/--plot files."),
    solver: Any = None,
) -> None:
    """ISO 230-4 circular test of two axes of a machine: a CCW and a CW run with lead-in and
    lead-out arcs; circular deviations G(CCW), G(CW), G(b), mean radius deviation and radial
    deviation F [µm], and the ballbar diagnostics (squareness, scale and servo mismatch,
    backlash, lateral play, reversal spikes)."""
    from ..analysis.circular import describe
    from ..analysis.circular_run import UnevaluatedTrace, run_circular_test
    from ..engine.options import layered
    from ..engine.simulate import SimulationError, SimulationInterrupted
    from ..io.acceptance import write_xy_trace
    from ..machine import load_machine
    from ._units import contour_limit as limit
    from ._units import reversal_angle as reversal_of

    # the contour's limits in the options' units, a lead-in arc of at most a turn, a pitch
    # within the contour's radius range (an outside check, 2026-12-07: a lead arc of 1e300°
    # was refused as a "duration", an acceleration of 1e300 in m/s² under
    # contour.acceleration, a pitch of 1e300 mm taken)
    for option, value, unit, high in (
            ("--radius", radius, "mm", limit("radius")),
            ("--feed", feed, "mm/min", limit("feed")),
            ("--acceleration", acceleration, "mm/s²", limit("acceleration")),
            ("--lead-arc", 1.0 if lead_arc is None else lead_arc, "°", 360.0)):
        if not (math.isfinite(value) and 0 < value <= high):
            raise ParameterError(option, value, f"expected a value > 0, ≤ {high:g} [{unit}]")
    for option, given, high in (("--pitch", pitch, limit("radius")),
                                ("--magnification", magnification, 1e9)):
        if given is not None and not (math.isfinite(given) and 0 < given <= high):
            raise ParameterError(option, given, f"expected a value > 0, ≤ {high:g} ["
                                 + ("mm" if option == "--pitch" else "-") + "]")
    if plot is None:  # the plot's scale, without a plot to draw (it was dropped)
        refuse_unused((("--magnification", magnification, None),),
                      "applies to --plot, which this run does not write")
    if not (math.isfinite(nut_speed) and nut_speed >= 0):
        raise ParameterError("--nut-speed", nut_speed, "expected a speed ≥ 0 [mm/s]")
    if max_steps is not None and max_steps < 1:
        raise ParameterError("--max-steps", max_steps, "expected a whole number ≥ 1")
    reversal = reversal_of(reversal_angle)
    pair = parse_axes(axes)
    options = layered([("command line", {"max_steps": (max_steps, "--max-steps")})],
                      base=solver)
    built = load_machine(machine)
    # progress of the runs (they sat silent for 5–8 s: an outside check, 2026-12-07)
    # the two runs are equally long: the first half of the time is the CCW run's
    # (run_circular_test's progress covers both)
    bar, advance = (None, None) if as_json else progress_bar(
        1.0, label=lambda t, end: "CCW run" if t <= end / 2 else "CW run")
    try:
        run = run_circular_test(built, radius=radius * MM, feed=feed * MM_PER_MIN, axes=pair,
                                acceleration=acceleration * MM,
                                lead_arc=None if lead_arc is None else math.radians(lead_arc),
                                nut_speed=nut_speed * MM,
                                pitch=None if pitch is None else pitch * MM,
                                reversal=reversal, options=options, progress=advance)
    except ParameterError as err:  # the API names its arguments; the user typed options
        raise ParameterError(*_as_option(err.field, err.value), err.message) from None
    except SimulationError as err:
        err_console.print(f"error: {err}", markup=False, highlight=False, soft_wrap=True)
        raise typer.Exit(code=1) from None
    except UnevaluatedTrace as err:  # the runs are finished: their trace is kept
        _stop_bar(bar)
        err_console.print(f"error: {err}", markup=False, highlight=False, soft_wrap=True)
        if output:
            names = pair or (built.axes[0].name, built.axes[1].name)
            centre_mm = ",".join(repr(built.axis(n).table_position * 1e3) for n in names)
            write_xy_trace(output, err.time, err.x, err.y, comment=(
                f"feeddrive circular --machine {machine}, R {radius:g} mm, feed {feed:g} "
                "mm/min: not evaluated (no full revolution one way)\n"
                f"nominal circle: --radius {radius!r} --centre {centre_mm}"))
            err_console.print(f"wrote the trace all the same: {output}", markup=False,
                              highlight=False, soft_wrap=True)
        raise typer.Exit(code=1) from None
    except SimulationInterrupted as stop:
        err_console.print(f"interrupted: {stop}", markup=False, highlight=False,
                          soft_wrap=True)
        raise interrupted() from None
    finally:
        _stop_bar(bar)
    test = run.test
    lead = run.lead_in
    assert lead is not None
    centre_mm = f"{run.centre[0] * 1e3!r},{run.centre[1] * 1e3!r}"
    if output:
        write_xy_trace(output, run.time, run.x, run.y, comment=(
            f"feeddrive circular --machine {machine}, axes {run.axes[0]},{run.axes[1]}, "
            f"R {radius:g} mm, feed {feed:g} mm/min, {lead.describe()}\n"
            f"nominal circle: --radius {radius!r} --centre {centre_mm}"))
    if plot:
        from ..plots.acceptance import circular_figure, save

        save(circular_figure(test, magnification=magnification), plot)
    if as_json:
        print_json({**test.to_dict(), "machine": built.name, "axes": list(run.axes),
                    "acceleration_mm_s2": acceleration, "lead_in": lead.to_dict(),
                    "nut_speed_mm_s": nut_speed,
                    "duration_s": float(run.time[-1]), "output": output, "plot": plot})
        return
    _say(f"ISO 230-4 circular test: machine {built.name}, axes {run.axes[0]} (X) and "
         f"{run.axes[1]} (Y), R {radius:g} mm, feed {feed:g} mm/min"
         + (f", DDFS nut speed {nut_speed:g} mm/s" if nut_speed else "")
         + f"; {float(run.time[-1]):.4g} s simulated")
    _say(f"  {lead.describe()}")
    for note in lead.notes:
        _say(f"  lead-in rule: {note}")
    for note in test.notes:
        _say(f"  {note}")
    for line in describe(test):
        _say(line)
    if output:
        # the radius as given, every digit (rounded by :g it moved the numbers: an outside
        # check, 2026-12-07)
        _say(f"wrote trace {output} (feeddrive analyze --circular {output} --radius "
             f"{radius!r} --centre {centre_mm})")
    if plot:
        _say(f"wrote plot {plot}")


def _as_option(field: str, value: Any) -> tuple[str, Any]:
    """An API argument [m, m/s, rad] as the option the user typed [mm, mm/min, °]."""
    if (field in ("radius", "feed", "acceleration", "lead_arc", "nut_speed")
            and isinstance(value, float)):
        scale = {"radius": 1e3, "feed": 6e4, "acceleration": 1e3,
                 "lead_arc": 180.0 / math.pi, "nut_speed": 1e3}[field]
        return f"--{field.replace('_', '-')}", float(f"{value * scale:.12g}")
    return {"max_steps": "--max-steps", "axes": "--axes",
            "lead_arc": "--lead-arc"}.get(field, field), value
