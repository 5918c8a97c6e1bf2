"""`feeddrive analyze`: creep analysis of a measured (or exported) position trace; with
``--circular`` the ISO 230-4 circular test of an XY trace, with ``--positioning`` the ISO 230-2
evaluation of a positioning record.

File formats: docs/measured-data.md, docs/acceptance-tests.md.  The logic lives in
feeddrive.analysis.trace, feeddrive.analysis.circular, feeddrive.analysis.positioning and
feeddrive.io.
"""

from __future__ import annotations

import math

import typer

from ..analysis.creep_window import CreepThresholds
from ..analysis.trace import (
    DEFAULT_MIN_SEGMENT_TIME,
    DEFAULT_MIN_STEP,
    MIN_STEP_APPLIES,
    describe_critical,
)
from ..io.outputs import PLOT_FORMATS
from ..parameters import ParameterError
from . import _units
from ._common import (
    MM,
    MM_PER_S,
    DecimalOption,
    SepOption,
    TimeUnitOption,
    app,
    console,
    outputs,
    print_json,
    refuse_unused,
    user_errors,
)


def _say(text: str) -> None:
    console.print(text, highlight=False, markup=False, soft_wrap=True)


_DEFAULTS = CreepThresholds()
#: --min-step's default [mm/s]: the API's (0.005 mm/s)
_MIN_STEP_MM_S = DEFAULT_MIN_STEP / MM_PER_S


@app.command("analyze")
@user_errors
@outputs(plot=PLOT_FORMATS)
def analyze_command(
    file: str = typer.Argument(..., help="CSV with time and table position; with --circular "
                               "time, x and y; with --positioning an ISO 230-2 record."),
    circular: bool = typer.Option(False, "--circular", help="ISO 230-4 circular test of an XY "
                                  "trace (columns time, x, y; docs/acceptance-tests.md)."),
    positioning: bool = typer.Option(False, "--positioning", help="ISO 230-2 evaluation of a "
                                     "record of approaches (columns target, direction, "
                                     "position or deviation)."),
    radius: float | None = typer.Option(None, "--radius", help="--circular: nominal radius "
                                        "[mm] (default: the least-squares radius, stated)."),
    centre: str | None = typer.Option(None, "--centre", help="--circular: nominal centre X,Y "
                                      "[mm] (default: the least-squares centre, stated)."),
    pitch: float | None = typer.Option(None, "--pitch", help="--circular: period of the cyclic "
                                       "error looked for, the screw's lead [mm]."),
    magnification: float | None = typer.Option(
        None, "--magnification", help="--circular --plot: deviation magnification [-] "
        "(default: the largest deviation fills the outer 40 % of the plot)."),
    reversal_angle: float | None = typer.Option(
        None, "--reversal-angle", help="--circular: smallest turn back of the path's angle "
        "about the centre that ends a run [°] (default 1°); smaller ones, stick-slip at a "
        "low feed, stay in their run and are counted in a note."),
    x_column: str | None = typer.Option(None, "--x-column", help="--circular: default x, "
                                        "x_position or x.table_position."),
    y_column: str | None = typer.Option(None, "--y-column", help="--circular: default y, "
                                        "y_position or y.table_position."),
    command_speed: float | None = typer.Option(
        None, "--command-speed", help="Commanded speed [mm/s] of the whole trace (else from a "
        "command column, else estimated per segment)."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
    plot: str | None = typer.Option(None, "--plot", help="Write the trace plot here."),
    time_column: str = typer.Option("time", "--time-column"),
    position_column: str | None = typer.Option(
        None, "--position-column", help="Default: position, else table_position."),
    command_column: str | None = typer.Option(
        None, "--command-column", help="Default: command_speed or table_speed_reference, if "
        "present."),
    speed_column: str | None = typer.Option(
        None, "--speed-column", help="Use this speed column [mm/s] instead of "
        "differentiating the position."),
    time_unit: TimeUnitOption = None,
    position_unit: str | None = typer.Option(None, "--position-unit",
                                             help="mm (default), um, nm, m."),
    sep: SepOption = None,
    decimal: DecimalOption = ".",
    smoothing: float | None = typer.Option(
        None, "--smoothing", help="Savitzky–Golay window [ms] (default 20 ms)."),
    segments: bool = typer.Option(True, "--segments/--no-segments",
                                  help="Detect step-down segments (without --command-speed "
                                  "or a command column; --no-segments: the whole trace as "
                                  "one, refused beside a command)."),
    min_step: float = typer.Option(_MIN_STEP_MM_S, "--min-step",
                                   help="Smallest speed step between segments detected "
                                   "[mm/s] (without --command-speed, a command column or "
                                   "--no-segments)."),
    min_segment: float = typer.Option(DEFAULT_MIN_SEGMENT_TIME, "--min-segment",
                                      help="Shortest segment [s]."),
    stick_level: float = typer.Option(_DEFAULTS.stick_level, "--stick-level",
                                      help="Sticking below this fraction of the command [-]."),
    max_stick_fraction: float = typer.Option(_DEFAULTS.max_stick_fraction,
                                             "--max-stick-fraction",
                                             help="Creeping above this stick fraction [-]."),
    max_ripple_ratio: float = typer.Option(_DEFAULTS.max_ripple_ratio, "--max-ripple-ratio",
                                           help="Creeping above this peak-to-peak ripple / "
                                           "command [-]."),
    force: bool = typer.Option(False, "--force", help="Replace an existing --plot file."),
) -> None:
    """Creep metrics of a position trace (per segment of a step-down run) and the critical
    creeping speed; or an ISO 230-4 circular test (--circular) or an ISO 230-2 positioning
    test (--positioning)."""
    if circular and positioning:
        raise ParameterError("--circular", True, "expected one of --circular, --positioning")
    mode = "--circular" if circular else "--positioning" if positioning else "creep"
    # an option of another analysis would be ignored: refused, naming the analyses it serves
    creep, both = ("creep",), ("creep", "--circular")
    # option: (its value, whether it was given, the analyses it serves)
    given: dict[str, tuple[object, bool, tuple[str, ...]]] = {
        "--radius": (radius, radius is not None, ("--circular",)),
        "--centre": (centre, centre is not None, ("--circular",)),
        "--pitch": (pitch, pitch is not None, ("--circular",)),
        "--magnification": (magnification, magnification is not None, ("--circular",)),
        "--reversal-angle": (reversal_angle, reversal_angle is not None, ("--circular",)),
        "--x-column": (x_column, x_column is not None, ("--circular",)),
        "--y-column": (y_column, y_column is not None, ("--circular",)),
        "--time-column": (time_column, time_column != "time", both),
        "--time-unit": (time_unit, time_unit is not None, both),
        "--position-unit": (position_unit, position_unit is not None, both),
        "--command-speed": (command_speed, command_speed is not None, creep),
        "--position-column": (position_column, position_column is not None, creep),
        "--command-column": (command_column, command_column is not None, creep),
        "--speed-column": (speed_column, speed_column is not None, creep),
        "--smoothing": (smoothing, smoothing is not None, creep),
        "--no-segments": (True, not segments, creep),
        "--min-step": (min_step, min_step != _MIN_STEP_MM_S, creep),
        "--min-segment": (min_segment, min_segment != DEFAULT_MIN_SEGMENT_TIME, creep),
        "--stick-level": (stick_level, stick_level != _DEFAULTS.stick_level, creep),
        "--max-stick-fraction": (max_stick_fraction,
                                 max_stick_fraction != _DEFAULTS.max_stick_fraction, creep),
        "--max-ripple-ratio": (max_ripple_ratio,
                               max_ripple_ratio != _DEFAULTS.max_ripple_ratio, creep),
    }
    for option, (value, is_given, modes) in given.items():
        if is_given and mode not in modes:
            served = " or ".join("the creep analysis" if m == "creep" else m for m in modes)
            raise ParameterError(option, value, f"applies to {served}, not to "
                                 f"{'the creep analysis' if mode == 'creep' else mode}")
    if plot is None:  # the plot's scale, without a plot to draw (it was dropped)
        refuse_unused((("--magnification", magnification, None),),
                      "applies to --plot, which this run does not write")
    if circular:
        _circular(file, radius=radius, centre=centre, pitch=pitch, magnification=magnification,
                  reversal_angle=reversal_angle, time_column=time_column, x_column=x_column,
                  y_column=y_column,
                  time_unit=time_unit, position_unit=position_unit, sep=sep, decimal=decimal,
                  as_json=as_json, plot=plot)
        return
    if positioning:
        _positioning(file, sep=sep, decimal=decimal, as_json=as_json, plot=plot)
        return
    from ..analysis.trace import analyze_trace
    from ..io.measured import read_position_trace

    if smoothing is not None and not (math.isfinite(smoothing) and smoothing > 0):
        raise ParameterError("--smoothing", smoothing, "expected a window > 0 [ms]")
    for option, value, unit in (("--min-step", min_step, "mm/s"),
                                ("--min-segment", min_segment, "s")):
        if not (math.isfinite(value) and value > 0):
            raise ParameterError(option, value, f"expected a value > 0 [{unit}]")
    try:
        thresholds = CreepThresholds(stick_level=stick_level,
                                     max_stick_fraction=max_stick_fraction,
                                     max_ripple_ratio=max_ripple_ratio)
    except ParameterError as err:  # the rule's field, named as the option that set it
        option = "--" + err.field.removeprefix("thresholds.").replace("_", "-")
        raise ParameterError(option, err.value, err.message) from None
    v_cmd = (None if command_speed is None
             else _units.speed("--command-speed", command_speed, nonzero=True))
    trace = read_position_trace(file, time_column=time_column, position_column=position_column,
                                command_column=command_column, speed_column=speed_column,
                                time_unit=time_unit, position_unit=position_unit, sep=sep,
                                decimal=decimal)
    beside = ("--command-speed, which makes the whole trace one segment" if v_cmd is not None
              else f"the command column {trace.command_column!r} of {trace.source}, whose "
              "steps set the segments" if trace.command_speed is not None else None)
    if not segments and beside is not None:
        # the API refuses it as segment = False; named here as the option (session 30)
        raise ParameterError("--no-segments", True, f"not with {beside} (segments are detected "
                             "only without a command); expected --segments")
    if beside is not None or not segments:
        # read nowhere then: the API refuses it as min_step (an earlier sweep, session 30)
        refuse_unused((("--min-step", min_step, _MIN_STEP_MM_S),),
                      f"not with {beside or '--no-segments'} ({MIN_STEP_APPLIES}); omit it")
    result = analyze_trace(
        trace.time, trace.position,
        command_speed=v_cmd,
        command=trace.command_speed, speed=trace.speed, thresholds=thresholds,
        smoothing_time=None if smoothing is None else smoothing * 1e-3,
        segment=segments, min_segment_time=min_segment,
        min_step=None if min_step == _MIN_STEP_MM_S else min_step * MM_PER_S,
        source=trace.source, lines=trace.lines)
    if plot:
        from ..plots.analysis import plot_trace

        plot_trace(result, plot)
    if as_json:
        print_json({**result.to_dict("mm"), "position_column": trace.position_column,
                    "plot": plot})
        return
    _say(f"{trace.source}: {result.time.size} samples, "
                  f"{result.time[-1] - result.time[0]:.4g} s, position from "
                  f"{trace.position_column!r}")
    for note in result.notes:
        _say(f"  {note}")
    from ..analysis.creep_window import frequency_label

    for i, seg in enumerate(result.segments, start=1):
        m = seg.metrics
        freq = (f"{m.stick_slip_frequency:.3g} Hz" if m.stick_slip_frequency is not None
                else "none")
        # "stick-slip" only when the table sticks (issue 24 item 5)
        freq_word = frequency_label(m.stick_fraction).removesuffix(" frequency")
        _say(
            f"  segment {i}: {seg.start:.2f}–{seg.end:.2f} s (window from "
            f"{m.window_start:.2f} s), command {seg.command_speed / MM_PER_S:.4g} mm/s "
            f"({seg.command_from}): {m.verdict.upper()}"
            f"{'' if seg.settled else ' (not settled)'}  ripple {m.ripple_ratio:.3g}, "
            f"min {m.min_ratio:.3g}, stick {m.stick_fraction:.3g}, {freq_word} {freq}")
    _say(f"  verdicts by the {thresholds.describe()}")
    for c in result.critical:
        _say(f"  critical speed ({c.direction}): "
             f"{describe_critical(c.lowest_smooth, c.first_creeping, unsettled=c.unsettled)}")
    if plot:
        _say(f"wrote plot {plot}")


def parse_point_mm(option: str, text: str) -> tuple[float, float]:
    """``"X,Y"`` [mm] → (x, y) [m], naming the option when it is not two numbers.

    Parameters
    ----------
    option : str
        The option, for messages.
    text : str
        E.g. ``"200,150"`` [mm].

    Returns
    -------
    tuple of float
        The point [m].
    """
    parts = text.split(",")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != 2 or not all(math.isfinite(v) for v in values):
        raise ParameterError(option, text, "expected two numbers X,Y [mm], e.g. 200,150")
    return values[0] * MM, values[1] * MM


def _circular(file: str, *, radius: float | None, centre: str | None, pitch: float | None,
              magnification: float | None, reversal_angle: float | None, time_column: str,
              x_column: str | None,
              y_column: str | None, time_unit: str | None, position_unit: str | None,
              sep: str | None, decimal: str, as_json: bool, plot: str | None) -> None:
    from ..analysis.circular import REVERSAL, circular_test, describe
    from ..io.acceptance import read_xy_trace
    from ._units import reversal_angle as reversal_of

    # the radius and the cyclic error's pitch within a contour's radius range (a pitch of
    # 1e300 mm was taken and moved the other diagnostics: an outside check, 2026-12-07)
    for option, value, high in (("--radius", radius, _units.contour_limit("radius")),
                                ("--pitch", pitch, _units.contour_limit("radius")),
                                ("--magnification", magnification, 1e9)):
        if value is not None and not (math.isfinite(value) and 0 < value <= high):
            unit = "-" if option == "--magnification" else "mm"
            raise ParameterError(option, value, f"expected a value > 0, ≤ {high:g} [{unit}]")
    reversal = REVERSAL if reversal_angle is None else reversal_of(reversal_angle)
    point = None if centre is None else parse_point_mm("--centre", centre)
    trace = read_xy_trace(file, time_column=time_column, x_column=x_column, y_column=y_column,
                          time_unit=time_unit, position_unit=position_unit, sep=sep,
                          decimal=decimal)
    result = circular_test(trace.time, trace.x, trace.y,
                           radius=None if radius is None else radius * MM, centre=point,
                           pitch=None if pitch is None else pitch * MM, reversal=reversal)
    if plot:
        from ..plots.acceptance import circular_figure, save

        save(circular_figure(result, magnification=magnification), plot)
    if as_json:
        print_json({**result.to_dict(), "source": trace.source,
                    "columns": list(trace.columns), "plot": plot})
        return
    _say(f"{trace.source}: {trace.time.size} samples, x from {trace.columns[0]!r}, y from "
         f"{trace.columns[1]!r}")
    for note in result.notes:
        _say(f"  {note}")
    for line in describe(result):
        _say(line)
    if plot:
        _say(f"wrote plot {plot}")


def _positioning(file: str, *, sep: str | None, decimal: str, as_json: bool,
                 plot: str | None) -> None:
    from ..analysis.positioning import describe, positioning_test
    from ..io.acceptance import read_positioning_record

    record = read_positioning_record(file, sep=sep, decimal=decimal)
    result = positioning_test(record.targets, record.deviation_up, record.deviation_down)
    if plot:
        from ..plots.acceptance import positioning_figure, save

        save(positioning_figure(result), plot)
    if as_json:
        print_json({**result.to_dict(), "source": record.source, "plot": plot})
        return
    _say(f"{record.source}: {record.targets.size} targets × {record.deviation_up.shape[1]} "
         "approaches each way")
    for line in describe(result):
        _say(line)
    if plot:
        _say(f"wrote plot {plot}")
