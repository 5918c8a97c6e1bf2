"""A run's solver record as the commands state it: the integrator settings in one line (the
tolerances in mm and mm/s, each marked scaled or as given), the solver's counts, and the record
in ``--json`` in the command line's units (``simulate``, ``simulate --machine``)."""

from __future__ import annotations

import math
from typing import Any

from ..engine import options as _opt
from . import _units
from ._common import MM, MM_PER_S


def solver_counts(stats: dict[str, Any]) -> str:
    """The run's method, steps, rejected steps and wall time, as the summary's ``solver:``
    line gives them.

    Parameters
    ----------
    stats : dict
        A run's ``solver_stats``.

    Returns
    -------
    str
        E.g. ``"modal, 710 steps, 39 rejected, 4.9 ms"``.
    """
    return (f"{stats['method']}, {stats['steps']} steps, {stats['rejected_steps']} rejected, "
            f"{1e3 * stats['wall_time_s']:.1f} ms")


def machine_solver_report(stats: dict[str, Any], options: Any
                          ) -> tuple[list[str], dict[str, Any]]:
    """What ``simulate --machine`` states of its integrator, as a single drive's summary: the
    settings line (:func:`integrator_line`, the axes' tolerances in table units) and the
    counts (:func:`solver_counts`) for the text, :func:`solver_json` for ``--json``.

    Parameters
    ----------
    stats : dict
        The machine run's ``solver_stats``.
    options : SolverOptions
        The run's options.

    Returns
    -------
    tuple of (list of str, dict)
        The text lines and the JSON's ``solver`` record.
    """
    return ([f"integrator: {integrator_line(stats, options, 'axes')}",
             f"solver: {solver_counts(stats)}"], solver_json(stats))


def integrator_line(stats: dict[str, Any], options: Any = None, part: str = "table") -> str:
    """The run's integrator settings in one line, in the CLI's units: the table's absolute
    tolerances and, where they differ (a DDFS's motors run at the table speed plus the nut's),
    the motors', each default one with the speed scale it was scaled to, an explicit one
    marked as given (it is not scaled).

    Parameters
    ----------
    stats : dict
        A run's ``solver_stats``.
    options : SolverOptions, optional
        The options the command passed: a tolerance they give explicitly is marked as given.
        Otherwise the run's record says it (``stats`` holds what the run took, a parameter
        set's own ``[solver]`` table included): an explicit position tolerance leaves
        ``deflection_fraction`` None; a speed tolerance other than the scaled default
        (``SPEED_FRACTION`` × the table's speed scale × accuracy) was given.
    part : str, default "table"
        What the first tolerances are of (a machine's: ``"axes"``, in table units).

    Returns
    -------
    str
        The method, rtol, the tolerances [mm, mm/s, A] and the speed scales [mm/s], and the
        accuracy factor.
    """
    n = _units.number
    scaled = _opt.SPEED_FRACTION * stats.get("table_speed_scale", stats["speed_scale"]) \
        * stats["accuracy"]
    given_position = stats.get("deflection_fraction", 0.0) is None or (
        options is not None and options.position_tolerance is not None)
    given_speed = not math.isclose(stats["speed_tolerance"], scaled, rel_tol=1e-9) or (
        options is not None and options.speed_tolerance is not None)

    def tolerances(position: float, speed: float, scale: float) -> str:
        where = f"scaled to {n(scale / MM_PER_S, 3)} mm/s"
        positions = f"positions {n(position / MM, 3)} mm"
        speeds = f"speeds {n(speed / MM_PER_S, 3)} mm/s"
        if given_position and given_speed:
            return f"{positions}, {speeds} (as given, not scaled)"
        if given_position:
            return f"{positions} (as given), {speeds} ({where})"
        if given_speed:
            return f"{positions} ({where}), {speeds} (as given)"
        return f"{positions}, {speeds} ({where})"

    table = tolerances(stats["position_tolerance"], stats["speed_tolerance"],
                       stats.get("table_speed_scale", stats["speed_scale"]))
    motors = ""
    if (stats.get("motor_position_tolerance", stats["position_tolerance"]),
            stats.get("motor_speed_tolerance", stats["speed_tolerance"])) \
            != (stats["position_tolerance"], stats["speed_tolerance"]):
        motors = "; motors " + tolerances(stats["motor_position_tolerance"],
                                          stats["motor_speed_tolerance"], stats["speed_scale"])
    return (f"{stats['method']}, rtol {n(stats['rtol'], 3)}, {part} {table}{motors}, currents "
            f"{n(stats['current_tolerance'], 3)} A; accuracy {n(stats['accuracy'], 3)}")


#: the solver record's lengths and speeds [SI] as ``--json`` gives them: in the command
#: line's units (its --position-tolerance takes mm, --speed-tolerance mm/s), the unit in the
#: key as every other key of the JSON (``command_speed_mm_s``); currents [A] named so too
SOLVER_JSON_UNITS = {
    "position_tolerance": ("position_tolerance_mm", MM),
    "speed_tolerance": ("speed_tolerance_mm_s", MM_PER_S),
    "motor_position_tolerance": ("motor_position_tolerance_mm", MM),
    "motor_speed_tolerance": ("motor_speed_tolerance_mm_s", MM_PER_S),
    "speed_scale": ("speed_scale_mm_s", MM_PER_S),
    "table_speed_scale": ("table_speed_scale_mm_s", MM_PER_S),
    "current_tolerance": ("current_tolerance_a", 1.0),
    "current_scale": ("current_scale_a", 1.0),
}


def solver_json(stats: dict[str, Any]) -> dict[str, Any]:
    """A run's solver record as the command's ``--json`` gives it: the keys of
    :data:`SOLVER_JSON_UNITS` renamed with their unit and converted (mm, mm/s, A), the error
    estimate's absolute errors in the tabular exports' units (mm, mm/s, N/µm; each entry's
    ``unit`` says which), everything else as ``Result.solver_stats`` has it (SI, which the
    API keeps).

    Parameters
    ----------
    stats : dict
        A run's ``solver_stats`` [SI].

    Returns
    -------
    dict
        The record in the command line's units.
    """
    from ..units import ENGINEERING

    out: dict[str, Any] = {}
    for key, value in stats.items():
        if key in SOLVER_JSON_UNITS and isinstance(value, int | float):
            name, per = SOLVER_JSON_UNITS[key]
            out[name] = value / per
        else:
            out[key] = value
    estimate = stats.get("error_estimate")
    if isinstance(estimate, dict) and isinstance(estimate.get("signals"), dict):
        signals = {}
        for name, entry in estimate["signals"].items():
            unit = entry.get("unit")
            if unit in ENGINEERING:
                shown_unit, factor = ENGINEERING[unit]
                entry = {**entry, "absolute": entry["absolute"] * factor, "unit": shown_unit}
            signals[name] = entry
        out["error_estimate"] = {**estimate, "signals": signals}
    return out
