"""`feeddrive positioning`: the ISO 230-2 positioning test on a simulated axis.

The logic lives in feeddrive.analysis.positioning_run (cycle, reference, run, evaluation),
feeddrive.analysis.positioning (the quantities) and feeddrive.io.acceptance (the record).
"""

from __future__ import annotations

import math
from typing import Any

import typer

from ..io.outputs import PLOT_FORMATS
from ..parameters import ParameterError
from ..parameters.validation import MISSING
from ._common import (
    MM,
    MM_PER_S,
    PRESET_HELP,
    _stop_bar,
    app,
    console,
    err_console,
    interrupted,
    outputs,
    print_json,
    progress_bar,
    resolve_parameters,
    user_errors,
)
from ._solver import accuracy_options, max_steps_help
from .simulate_cmd import ALL_DRIVES

WARM_UP = 1  # the API's default, feeddrive.analysis.positioning_run.WARM_UP (tested)


def _say(text: str) -> None:
    console.print(text, markup=False, highlight=False, soft_wrap=True)


def parse_targets_mm(targets: str | None, count: int | None, span: str | None) -> list[float]:
    """``--targets`` (a list) or ``--count`` over ``--span FROM,TO`` [mm] → positions [m].

    Parameters
    ----------
    targets : str or None
        E.g. ``"100,150,200"`` [mm].
    count : int or None
        Number of targets, evenly spread over ``span`` (both ends included).
    span : str or None
        ``"FROM,TO"`` [mm].

    Returns
    -------
    list of float
        The targets [m].
    """
    if targets is not None and (count is not None or span is not None):
        raise ParameterError("--targets", targets, "give either --targets or --count with "
                             "--span, not both")
    if targets is not None:
        try:
            values = [float(v) for v in targets.split(",")]
        except ValueError:
            raise ParameterError("--targets", targets, "expected numbers [mm], e.g. "
                                 "100,150,200") from None
        if len(values) < 2 or not all(math.isfinite(v) for v in values):
            raise ParameterError("--targets", targets, "expected at least 2 positions [mm]")
        return [v * MM for v in values]
    if count is None or span is None:
        raise ParameterError("--targets", MISSING, "give --targets LIST [mm], or --count N with "
                             "--span FROM,TO [mm]")
    if count < 2:
        raise ParameterError("--count", count, "expected at least 2 targets")
    try:
        low, high = (float(v) for v in span.split(","))
    except ValueError:
        raise ParameterError("--span", span, "expected FROM,TO [mm], e.g. 100,500") from None
    if not (math.isfinite(low) and math.isfinite(high) and low < high):
        raise ParameterError("--span", span, "expected FROM < TO [mm]")
    return [(low + (high - low) * k / (count - 1)) * MM for k in range(count)]


@app.command("positioning")
@user_errors
@outputs(output=(".csv",), plot=PLOT_FORMATS)
@accuracy_options
def positioning_command(
    drive: str = typer.Option("cdfs", "--drive", metavar=ALL_DRIVES,
                              help="The axis: cdfs, ddfs, linear-motor or rack-pinion."),
    targets: str | None = typer.Option(None, "--targets", help="Target positions on the axis "
                                       "[mm], e.g. 100,150,200."),
    count: int | None = typer.Option(None, "--count", help="Number of targets spread evenly "
                                     "over --span [-]."),
    span: str | None = typer.Option(None, "--span", help="FROM,TO of the targets of --count "
                                    "[mm]."),
    cycles: int = typer.Option(5, "--cycles", help="Approaches per target and direction "
                               "[-] (ISO 230-2: at least 5)."),
    cycle: str = typer.Option("linear", "--cycle", help="Test cycle: linear (the standard "
                              "cycle) or pilgrim (pilgrim-step)."),
    feed: float = typer.Option(10.0, "--feed", help="Speed of the moves [mm/s]."),
    acceleration: float = typer.Option(500.0, "--acceleration", help="Acceleration of the "
                                       "moves [mm/s²]."),
    dwell: float = typer.Option(2.0, "--dwell", help="Rest at each stop [s]; the position is "
                                "read over its last quarter."),
    overshoot: float = typer.Option(2.0, "--overshoot", help="How far beyond a target the "
                                    "axis reverses [mm]."),
    warm_up: int = typer.Option(WARM_UP, "--warm-up", help="Linear passes over the targets "
                                "run first and not read, so that the first cycle comes as "
                                "the others do (0: start at rest, friction and loop integrals "
                                "unloaded) [-]."),
    preset_name: str | None = typer.Option(None, "--preset", help=PRESET_HELP),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
    max_steps: int | None = typer.Option(None, "--max-steps", help=max_steps_help()),
    output: str | None = typer.Option(None, "--output", help="Write the record of approaches "
                                      "to FILE.csv (analyze --positioning reads it)."),
    plot: str | None = typer.Option(None, "--plot", help="Write the ISO 230-2 chart."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
    force: bool = typer.Option(False, "--force", help="Replace existing --output/--plot files."),
    solver: Any = None,
) -> None:
    """ISO 230-2 positioning test of one axis: each target approached --cycles times in both
    directions, a dwell at each; accuracy A, repeatability R↑ R↓ R, reversal value B (per
    target and mean), systematic deviation E and mean deviation M [µm]."""
    from ..analysis.positioning import describe
    from ..analysis.positioning_run import run_positioning_test
    from ..engine.options import layered
    from ..engine.simulate import SimulationError, SimulationInterrupted
    from ..io.acceptance import write_positioning_record

    points = parse_targets_mm(targets, count, span)
    if cycles < 5:
        raise ParameterError("--cycles", cycles, "expected at least 5 approaches per target "
                             "and direction (ISO 230-2)")
    for option, value, unit in (("--feed", feed, "mm/s"), ("--acceleration", acceleration,
                                                           "mm/s²"),
                                ("--dwell", dwell, "s"), ("--overshoot", overshoot, "mm")):
        if not (math.isfinite(value) and value > 0):
            raise ParameterError(option, value, f"expected a value > 0 [{unit}]")
    if max_steps is not None and max_steps < 1:
        raise ParameterError("--max-steps", max_steps, "expected a whole number ≥ 1")
    options = layered([("command line", {"max_steps": (max_steps, "--max-steps")})],
                      base=solver)
    params = resolve_parameters(preset_name, params_file, drive)
    # progress of the runs (they sat silent for 5–8 s: an outside check, 2026-12-07)
    bar, advance = (None, None) if as_json else progress_bar(1.0)
    try:
        run = run_positioning_test(params, drive, points, cycles=cycles, kind=cycle,
                                   feed=feed * MM_PER_S, acceleration=acceleration * MM,
                                   dwell=dwell, overshoot=overshoot * MM, warm_up=warm_up,
                                   options=options, progress=advance)
    except ParameterError as err:  # the API names its arguments; the user typed options
        option = {"feed": "--feed", "targets": "--targets", "kind": "--cycle",
                  "cycles": "--cycles", "warm_up": "--warm-up",
                  "max_steps": "--max-steps"}.get(err.field, err.field)
        raise ParameterError(option, _in_mm(err.field, err.value),
                             _in_mm_units(err.field, err.message)) from None
    except SimulationError as err:
        err_console.print(f"error: {err}", markup=False, highlight=False, soft_wrap=True)
        raise typer.Exit(code=1) from None
    except SimulationInterrupted as stop:
        err_console.print(f"interrupted: {stop}", markup=False, highlight=False,
                          soft_wrap=True)
        raise interrupted() from None
    finally:
        _stop_bar(bar)
    test = run.test
    if output:
        write_positioning_record(output, test.targets, test.deviation_up, test.deviation_down,
                                 comment=f"feeddrive positioning --drive {drive} ({params.name})"
                                 f", {run.kind} cycle, feed {feed:g} mm/s, dwell {dwell:g} s"
                                 f", {_passes(warm_up)}")
    if plot:
        from ..plots.acceptance import positioning_figure, save

        save(positioning_figure(test), plot)
    if as_json:
        print_json({**test.to_dict(), "drive": drive, "parameters": params.name,
                    "cycle": run.kind, "feed_mm_s": feed, "acceleration_mm_s2": acceleration,
                    "dwell_s": dwell, "overshoot_mm": overshoot, "warm_up_passes": warm_up,
                    "reading_motion_um": 1e6 * run.reading_motion,
                    "duration_s": float(run.result.time[-1]), "output": output, "plot": plot})
        return
    _say(f"ISO 230-2 positioning test: {drive} ({params.name}), {len(points)} targets × "
         f"{cycles} approaches each way, {run.kind} cycle, feed {feed:g} mm/s, dwell "
         f"{dwell:g} s, overshoot {overshoot:g} mm, {_passes(warm_up)}; "
         f"{float(run.result.time[-1]):.4g} s simulated")
    for line in describe(test):
        _say(line)
    _say(f"largest motion within a reading window (the last quarter of a dwell): "
         f"{1e6 * run.reading_motion:.3g} µm — ISO 230-2 reads the axis at rest; a motion "
         "comparable to B means a longer --dwell")
    if output:
        _say(f"wrote record {output}")
    if plot:
        _say(f"wrote plot {plot}")


def _passes(warm_up: int) -> str:
    """The warm-up in words, beside the numbers it changes."""
    if warm_up == 0:
        return "no warm-up (started at rest, friction and loop integrals unloaded)"
    return f"after {warm_up} warm-up pass{'es' if warm_up > 1 else ''} (not read)"


def _in_mm_units(field: str, message: str) -> str:
    """The API's message on a value converted by :func:`_in_mm`, its unit the option's: the
    values were given in mm, the message said "[m]" (``--targets 100,100``: "expected at least
    2 increasing positions [m]"; a bad-input sweep, session 29)."""
    if field == "feed":
        return message.replace("[m/s]", "[mm/s]")
    if field == "targets":
        return message.replace("[m]", "[mm]")
    return message


def _in_mm(field: str, value: Any) -> Any:
    """An API value [m, m/s] as the option the user typed it [mm, mm/s]."""
    if field == "feed" and isinstance(value, float):
        return value / MM_PER_S
    if field == "targets" and isinstance(value, list):
        return ",".join(f"{v / MM:g}" for v in value)
    return value
