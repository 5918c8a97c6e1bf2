"""`feeddrive simulate --machine FILE`: a machine of axes following a contour."""

from __future__ import annotations

import math
from typing import Any

from ._common import EXIT_FAILED, _fail, console, print_json, progress_bar, run_outcome
from ._solver_report import machine_solver_report

#: the contour kinds (feeddrive.machine.CONTOURS; the machine package loads numba)
CONTOURS = ("circle", "line", "corner", "csv", "together")
MM_PER_MIN = 1e-3 / 60.0  # [m/s] per mm/min


def run_machine(machine_file: str, *, contour: str, radius: float, feed: float,
                acceleration: float, clockwise: bool, start_angle: float, turns: float,
                length: float, angle: float, contour_file: str | None,
                duration: float | None, options: Any, output: str | None,
                plot: str | None, as_json: bool) -> None:
    """Parse the contour options (mm, mm/min, mm/s², degrees), run, save and print: per axis
    the largest following error, the contour error, the integrator settings and the solver's
    counts (text and ``--json``, as a single drive's summary).

    Parameters
    ----------
    machine_file : str
        A machine file or built-in machine name.
    contour : str
        circle, line, corner or csv.
    radius : float
        Circle (corner blend) radius [mm].
    feed : float
        Path feed [mm/min].
    acceleration : float
        Lead-in and lead-out acceleration [mm/s^2].
    clockwise : bool
        Circle sense.
    start_angle : float
        Circle start angle [deg].
    turns : float
        Circle revolutions [-].
    length : float
        Line (corner leg) length [mm].
    angle : float
        Line direction, corner turn [deg].
    contour_file : str or None
        CSV path file.
    duration : float or None
        Simulated time [s]; None: the contour's.
    options : SolverOptions
        Integrator settings.
    output : str or None
        Result file.
    plot : str or None
        Figure file.
    as_json : bool
        Print the summary as JSON.
    """
    from ..machine import load_machine, machine_summary, make_contour, simulate_machine
    from ..parameters import ParameterError
    from ._units import contour_limit as limit

    # the contour's limits in the command line's units
    for option, value, unit, high in (
            ("--radius", radius, "mm", limit("radius")),
            ("--feed", feed, "mm/min", limit("feed")),
            ("--acceleration", acceleration, "mm/s^2", limit("acceleration")),
            ("--turns", turns, "-", limit("turns")),
            ("--length", length, "mm", limit("distance"))):
        if not (math.isfinite(value) and 0 < value <= high):
            raise ParameterError(option, value, f"expected > 0, ≤ {high:g} [{unit}]")
    for option, value in (("--start-angle", start_angle), ("--angle", angle)):
        if not math.isfinite(value):
            raise ParameterError(option, value, "expected a finite angle [°]")
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise ParameterError("--duration", duration, "expected a finite time > 0 [s]")
    ramp = (feed * MM_PER_MIN) ** 2 / (acceleration * 1e-3) * 1e3  # lead-in and -out [mm]
    path_mm = {"circle": 2 * math.pi * radius * turns, "line": length,
               "together": length}.get(contour)
    if path_mm is not None and ramp > path_mm:  # said in the options' units, before the API
        raise ParameterError("--acceleration", acceleration, f"the lead-in and lead-out at "
                             f"{feed:g} mm/min need {ramp:.4g} mm, the path is {path_mm:.4g} "
                             f"mm long; expected ≥ {acceleration * ramp / path_mm:.4g} [mm/s^2]")
    if contour not in CONTOURS:
        raise ParameterError("--contour", contour, f"expected one of {', '.join(CONTOURS)}")
    machine = load_machine(machine_file)
    path = make_contour(contour, feed=feed * MM_PER_MIN, acceleration=acceleration * 1e-3,
                        radius=radius * 1e-3, clockwise=clockwise,
                        start_angle=math.radians(start_angle), turns=turns,
                        length=length * 1e-3, angle=math.radians(angle),
                        path_file=contour_file)
    from ..engine.budget import check_output_memory, check_step_budget

    # bounded work, as for one drive: refused before any step when the steps cannot fit
    t_end = path.duration if duration is None else duration
    check_step_budget(t_end, options)
    if output is not None and output.lower().endswith(".mat"):
        # the MATLAB 5 format holds the run's struct below 4 GiB: refused before the run
        # (scipy's MatWriteError came after it, as a traceback: an outside check, 2026-12-07)
        from ..io.results import check_mat_output

        check_mat_output(output, duration=t_end, output_interval=options.output_interval,
                         signals=len(recorded_machine_signals(machine, path)))
    check_output_memory(t_end, options.output_interval, options=options)
    bar, advance = (None, None) if as_json else progress_bar(t_end)
    with run_outcome(bar):
        result = simulate_machine(machine, path, duration, options=options, progress=advance)
    summary = machine_summary(result, machine, path)
    unwritten = None
    if output:
        from ._common import save_output

        written, unwritten = save_output(result, output)
        if written is not None:
            summary["output"] = written
    if plot and contour == "together":
        raise ParameterError("--plot", plot, "no XY path to draw for --contour together "
                             "(write --output and plot its signals)")
    if plot:
        from ..plots.machine import plot_machine

        summary["plot"] = str(plot_machine(result, path, plot, title=(
            f"{machine.name}: {contour}, F = {feed:g} mm/min")))
    summary = in_micrometres(summary)
    # the integrator settings the run took and its counts, as a single drive's summary states
    solver_lines, summary["solver"] = machine_solver_report(result.solver_stats, options)
    if as_json:
        print_json(summary)
    else:
        _print_machine(summary, machine.name, contour, feed, result, solver_lines)
    if unwritten is not None:  # after the summary it kept
        raise _fail(unwritten, EXIT_FAILED)


def recorded_machine_signals(machine: Any, path: Any) -> list[str]:
    """The signals a machine's run following ``path`` records (its Dataset's variables besides
    ``time``), known before the run from its model: each axis' signals, ``contour_error`` for
    a path in a plane.

    Parameters
    ----------
    machine : Machine
        The machine.
    path : Contour
        What it follows.

    Returns
    -------
    list of str
        The names.
    """
    import numpy as np

    from ..engine.result import recorded_signals
    from ..machine import MachineProfile, MachineSystem, Together
    from ..model.reference import SampledSpeed

    # the model's signals do not depend on the references' samples: two stand in for them
    still = SampledSpeed(time=np.array([0.0, 1.0]), table_speed=np.zeros(2))
    profile = MachineProfile.common(machine, still)
    system = MachineSystem(machine)
    names = recorded_signals(system.model(profile), system, profile)
    return names if isinstance(path, Together) else [*names, "contour_error"]


def _print_machine(summary: dict[str, Any], name: str, contour: str, feed: float,
                   result: Any, solver_lines: list[str]) -> None:
    lines = [f"machine {name}: {contour} at {feed:g} mm/min, "
             f"{result.time[-1]:g} s simulated"]
    for axis, ax in summary["axes"].items():
        lines.append(f"  axis {axis} ({ax['drive']}, {ax['parameter_set']}): largest "
                     f"following error {ax['following_error_max_um']:.4g} µm")
    if contour != "together":
        lines.append(f"  contour error {summary['contour_error_min_um']:.4g} … "
                     f"{summary['contour_error_max_um']:.4g} µm")
    if "roundness_um" in summary:
        lines.append(f"  mean radius reduction {summary['radius_reduction_um']:.4g} µm, "
                     f"roundness {summary['roundness_um']:.4g} µm (after the lead-in)")
    lines += [f"  {text}" for text in solver_lines]
    for key in ("output", "plot"):
        if key in summary:
            lines.append(f"  {key}: {summary[key]}")
    for ln in lines:
        console.print(ln, markup=False, highlight=False, soft_wrap=True)


#: the lengths of :func:`feeddrive.machine.machine_summary` [m], shown in µm at the edge
_LENGTHS = ("following_error_max", "contour_error_max", "contour_error_min", "mean_radius",
            "radius_reduction", "roundness")


def in_micrometres(summary: dict[str, Any]) -> dict[str, Any]:
    """``summary`` with its lengths [m] as ``<name>_um`` [µm], as the explorer and a drive's
    summary give errors (``simulate --machine --json`` gave them in m with no unit).

    Parameters
    ----------
    summary : dict
        :func:`feeddrive.machine.machine_summary` [SI].

    Returns
    -------
    dict
        The same with every length of :data:`_LENGTHS` renamed and in µm, at every level.
    """

    def convert(d: dict[str, Any]) -> dict[str, Any]:
        return {(f"{k}_um" if k in _LENGTHS else k):
                (1e6 * v if k in _LENGTHS else convert(v) if isinstance(v, dict) else v)
                for k, v in d.items()}

    return convert(summary)


def run_machine_loops(machine_file: str, *, table_speed: float, with_friction: bool,
                      as_json: bool) -> None:
    """`loops --machine`: each axis' loops, then the MIMO loop's size, poles and coupling.

    Parameters
    ----------
    machine_file : str
        A machine file or built-in machine name.
    table_speed : float
        Operating point of every axis [mm/s].
    with_friction : bool
        Linearise with the friction laws at steady sliding.
    as_json : bool
        Print JSON.
    """
    from ..analysis.linear import classify_poles
    from ..machine import load_machine
    from ..machine.linear import axis_loops, cross_coupling, linearize_machine
    from ._loops_text import print_loops

    machine = load_machine(machine_file)
    v = table_speed * 1e-3
    per_axis = {name: r.as_dict() for name, r in
                axis_loops(machine, v, frictionless=not with_friction).items()}
    lin = linearize_machine(machine, {ax.name: v for ax in machine.axes},
                            frictionless=not with_friction)
    mimo_poles = [p.as_dict() for p in classify_poles(lin.poles())]
    coupling = cross_coupling(lin)
    mimo = {"inputs": list(lin.inputs), "outputs": list(lin.outputs),
            "states": len(lin.states), "notes": list(lin.notes), "poles": mimo_poles,
            "cross_coupling_peak": coupling}
    if as_json:
        print_json({"machine": machine.name, "axes": per_axis, "mimo": mimo})
        return
    for ax in machine.axes:
        print_loops(f"axis {ax.name} ({ax.drive})", ax.parameters.name, table_speed,
                    with_friction, per_axis[ax.name])
    say = lambda text: console.print(text, markup=False, highlight=False,  # noqa: E731
                                     soft_wrap=True)
    say(f"MIMO loop of {machine.name}: {len(lin.states)} states, inputs "
        f"{', '.join(lin.inputs)}; outputs {', '.join(lin.outputs)}")
    for note in lin.notes:
        say(f"  {note}")
    damped = sorted((p for p in mimo_poles  # each complex pair once
                     if p["kind"] != "rigid-body" and p["imag_rad_per_s"] >= 0.0),
                    key=lambda p: p["damping_ratio"])[:3]
    for p in damped:
        say(f"  {p['kind']:12s} {p['frequency_hz']:10.4g} Hz  ζ = {p['damping_ratio']:.4g}")
    for pair, gain in coupling.items():
        say(f"  cross-coupling {pair}: peak |position/reference| {gain:.3g}")
