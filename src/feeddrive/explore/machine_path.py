"""A machine's XY path on the explorer page (issue 40): a machine file — a built-in name
(:data:`feeddrive.machine.MACHINES`) or the text of a TOML machine file with its coupling
parts — follows a circle on its first two axes; the page draws the actual path over the
commanded one and the contour error over time.

:func:`check_request` turns the page's request into a machine and a contour (one-line
``ParameterError`` naming the field, before any work); :func:`run_machine_path` simulates it
with :func:`feeddrive.machine.simulate_machine` and returns JSON-ready values in the page's
units (mm, µm, s).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..machine import (
    MACHINES,
    Machine,
    machine_from_dict,
    machine_summary,
    make_contour,
    simulate_machine,
)
from ..machine.contour import Contour
from ..parameters import ParameterError
from .compute import Report, _f, _list, decimate
from .settings import MAX_DURATION

#: the page's defaults: R = 50 mm, F = 5000 mm/min (issue 40's XY circle), a = 1000 mm/s²
DEFAULTS = {"machine": "xy-table", "radius": 50.0, "feed": 5000.0, "acceleration": 1000.0}
#: the longest machine file text the page may send [characters]
MAX_TEXT = 100_000
_MM_PER_MIN = 1e-3 / 60.0  # [m/s] per mm/min
#: the ranges the page takes, in its units: a ballbar's radii (ISO 230-4 names 50–600 mm),
#: feeds up to 1 m/s and accelerations up to 100 m/s²; outside them the machine's checks
#: answered in SI under another field, and 1e300 overflowed into a 500 (an outside check,
#: 2026-12-07)
RANGES = {"radius": (0.1, 1000.0, "mm"), "feed": (1.0, 60_000.0, "mm/min"),
          "acceleration": (1.0, 100_000.0, "mm/s^2")}
#: the most axes a machine on the page may have: the path uses two, and each axis adds its
#: whole drive to every step (a 40-axis file took 13 s for one circle)
MAX_AXES = 8


def check_request(body: dict[str, Any]) -> tuple[Machine, Contour]:
    """The machine and the circle of a page's request, refused before any work.

    Parameters
    ----------
    body : dict
        ``machine`` (a built-in machine's name or a machine file's TOML text), ``radius``
        [mm], ``feed`` [mm/min], ``acceleration`` [mm/s^2]; missing keys take
        :data:`DEFAULTS`.

    Returns
    -------
    machine : Machine
        The machine.
    contour : Contour
        The circle on its first two axes.

    Raises
    ------
    ParameterError
        One line naming the field (``machine``, ``radius`` …, or the machine file's own
        key, ``axes.y.table.mass``), the value and what was expected.
    """
    from ..parameters.toml_io import parse_toml

    given = {**DEFAULTS, **{k: body[k] for k in DEFAULTS if body.get(k) is not None}}
    numbers: dict[str, float] = {}
    for name, (low, high, unit) in RANGES.items():
        raw = given[name]
        try:
            if isinstance(raw, bool):  # JSON true is no number of mm
                raise TypeError
            value = float(raw)
        except (TypeError, ValueError, OverflowError):
            raise ParameterError(name, str(raw)[:40], f"expected a number {low:g} … {high:g} "
                                 f"[{unit}]") from None
        if not (math.isfinite(value) and low <= value <= high):
            raise ParameterError(name, value, f"expected {low:g} … {high:g} [{unit}]")
        numbers[name] = value
    text = given["machine"]
    if not isinstance(text, str) or not text.strip() or len(text) > MAX_TEXT:
        raise ParameterError("machine", str(text)[:40], "expected a built-in machine "
                             f"({', '.join(MACHINES)}) or a machine file's TOML text "
                             f"(≤ {MAX_TEXT} characters)")
    data = (MACHINES[text.strip()] if text.strip() in MACHINES
            else parse_toml(text, field="machine", source="the machine file"))
    _no_files(data)
    machine = machine_from_dict(data)
    if not 2 <= len(machine.axes) <= MAX_AXES:
        raise ParameterError("machine", machine.name, f"has {len(machine.axes)} axes; expected "
                             f"2 … {MAX_AXES} for an XY path (the circle runs on the first "
                             "two; `feeddrive simulate --machine` takes more)")
    axes = (machine.axes[0].name, machine.axes[1].name)
    contour = make_contour("circle", feed=numbers["feed"] * _MM_PER_MIN,
                           acceleration=numbers["acceleration"] * 1e-3,
                           radius=numbers["radius"] * 1e-3, axes=axes)
    if contour.duration > MAX_DURATION:
        raise ParameterError("feed", numbers["feed"], f"the circle takes "
                             f"{contour.duration:.3g} s; expected ≤ {MAX_DURATION:g} s "
                             "(a larger feed or a smaller radius)")
    return machine, contour


def _no_files(data: dict[str, Any]) -> None:
    """Refuse an axis that extends a file: the page sends text, and the server reads no file
    a page names (the CLI reads them, relative to the machine file)."""
    from ..parameters import PRESETS

    axes = data.get("axes")
    for name, table in (axes.items() if isinstance(axes, dict) else ()):
        parent = table.get("extends") if isinstance(table, dict) else None
        if parent is not None and parent not in PRESETS:
            raise ParameterError(f"axes.{name}.extends", parent,
                                 f"expected a built-in set ({', '.join(PRESETS)}); the "
                                 "explorer reads no other file (use feeddrive simulate "
                                 "--machine FILE)")


def run_machine_path(machine: Machine, contour: Contour, report: Report) -> dict[str, Any]:
    """Simulate ``machine`` on ``contour``: the path, the command and the contour error.

    Parameters
    ----------
    machine : Machine
        The machine.
    contour : Contour
        The circle (:func:`check_request`).
    report : callable
        ``report(done, total, text)``: the job's progress (raises ``Cancelled`` once the page
        cancelled; the run stops between chunks).

    Returns
    -------
    dict
        ``machine``, ``axes`` (the two axes' names), ``couplings`` (part names),
        ``duration_s``; ``path``: ``time_s``, ``x_mm``, ``y_mm`` (the actual positions of the
        two axes), ``x_reference_mm``, ``y_reference_mm``, ``contour_error_um`` (signed normal
        distance to the path, positive outside), decimated to at most
        :data:`~feeddrive.explore.compute.MAX_POINTS` samples keeping the contour error's
        extremes; ``summary``: ``contour_error_max_um``, ``contour_error_min_um``,
        ``radius_reduction_um``, ``roundness_um`` and each axis' largest following error
        [µm].
    """
    what = f"{machine.name}: circle"
    report(0.0, contour.duration, what)

    def progress(t: float, t_end: float) -> None:
        report(t, t_end, f"{what}: {t:.3g} s done")

    result = simulate_machine(machine, contour, progress=progress)
    a, b = contour.axes
    err = np.asarray(result["contour_error"])
    keep = decimate(len(err), err)
    mm, um = 1e3, 1e6
    summary = machine_summary(result, machine, contour)
    return {
        "machine": machine.name, "axes": [a, b],
        "couplings": [f"{c.name} ({c.part})" for c in machine.couplings],
        "duration_s": float(result.time[-1]),
        "path": {
            "time_s": _list(result.time[keep]),
            "x_mm": _list(np.asarray(result[f"{a}.table_position"])[keep], mm),
            "y_mm": _list(np.asarray(result[f"{b}.table_position"])[keep], mm),
            "x_reference_mm": _list(
                np.asarray(result[f"{a}.table_position_reference"])[keep], mm),
            "y_reference_mm": _list(
                np.asarray(result[f"{b}.table_position_reference"])[keep], mm),
            "contour_error_um": _list(err[keep], um),
        },
        "summary": {
            "contour_error_max_um": _f(summary["contour_error_max"] * um),
            "contour_error_min_um": _f(summary["contour_error_min"] * um),
            "radius_reduction_um": _f(summary.get("radius_reduction", math.nan) * um),
            "roundness_um": _f(summary.get("roundness", math.nan) * um),
            "following_error_max_um": {name: _f(ax["following_error_max"] * um)
                                       for name, ax in summary["axes"].items()},
        },
    }
