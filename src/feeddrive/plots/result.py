"""Figures (matplotlib ``Figure`` objects, no pyplot: the user's backend is never touched):
engineering units on the axes."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.figure import Figure

from ..engine.machine_axes import machine_axes

if TYPE_CHECKING:
    from ..engine.result import Result


def run_title(result: Result) -> str:
    """What was run, for a figure title: drive, profile, speed, position, duration, parameter set.

    Parameters
    ----------
    result : Result
        The run.

    Returns
    -------
    str
        E.g. ``"DDFS, constant 1.55 mm/s, position 400 mm, 10 s — wang2021"`` (engineering
        units).
    """
    # its attributes as the run holds them: a repr built the whole Dataset for them
    attrs = result.attrs
    axes = machine_axes(result)
    if axes:  # a machine's run: its axes' signals are "<axis>.<name>"
        machine = attrs.get("machine", attrs.get("drive", ""))
        return (f"machine {machine}: {attrs.get('profile', '')}, axes "
                f"{', '.join(axes)}, {float(result.time[-1]):.4g} s — "
                f"{attrs.get('parameter_set', '')}")
    kind = str(attrs.get("profile", "")).split("(")[0] or "profile"
    what = {"ConstantSpeed": "constant", "SineSpeed": "sine amplitude",
            "SampledSpeed": "sampled profile, top speed"}.get(kind, kind)
    drive = str(attrs["drive"])
    where = (f", position {1e3 * float(attrs.get('table_start_position_m', 0.0)):g} mm"
             if _uses_table_position(drive) else "")
    # a sine's stated amplitude (a run shorter than a quarter period never reaches it)
    from ..model.reference import sine_field

    amplitude = sine_field(str(attrs.get("profile", "")), "table_amplitude")
    # signed: a run at −2 mm/s said "constant 2 mm/s" (an outside check, 2026-12-07)
    speed = result.command_speed if amplitude is None else abs(amplitude)
    return (f"{drive.upper()}, {what} {1e3 * speed:.4g} mm/s{where}, "
            f"{float(result.time[-1]):.4g} s — {attrs['parameter_set']}")


def machine_figure(result: Result, title: str | None = None) -> Any:
    """The figure of a machine's run: each axis' table speed against its command, and the
    contour error where the run followed a path.

    Parameters
    ----------
    result : Result
        A machine's run.
    title : str, optional
        The title; :func:`run_title` by default.

    Returns
    -------
    matplotlib.figure.Figure
        One axes per machine axis (mm/s), and the contour error [µm] below.
    """
    t = result.time
    names = machine_axes(result)
    error = "contour_error" in result
    fig = Figure(figsize=(8, 2.4 * (len(names) + error) + 1.2), layout="constrained")
    panels = np.atleast_1d(fig.subplots(len(names) + error, 1, sharex=True))
    for ax, name in zip(panels, names, strict=False):
        ax.plot(t, 1e3 * result[f"{name}.table_speed"], lw=0.8, label=f"{name} table")
        ax.plot(t, 1e3 * result[f"{name}.table_speed_reference"], "k--", lw=0.8,
                label="command")
        ax.set_ylabel(f"{name} speed [mm/s]")
        _legend_above(ax)
    if error:
        ax = panels[-1]
        ax.plot(t, 1e6 * result["contour_error"], lw=0.8, label="contour error")
        ax.set_ylabel("contour error [µm]")
        _legend_above(ax)
    panels[-1].set_xlabel("time [s]")
    fig.suptitle(title or run_title(result), fontsize=10)
    return fig


def _uses_table_position(drive: str) -> bool:
    """Whether the drive's topology depends on the table position (the header names it then);
    a drive no longer registered (a record of a plug-in's run) is named with its position."""
    from ..model.mechanisms import drive_names, mechanism

    return mechanism(drive).uses_table_position if drive in drive_names() else True


def _legend_above(ax: Any) -> None:
    """The legend in a row above its panel: inside, it covered the trace (issue 24 item 2)."""
    n = len(ax.get_legend_handles_labels()[0])
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.0), ncol=max(n, 1), fontsize=8,
              frameon=False, borderaxespad=0.2)


def plot_result(result: Result, path: str | Path, title: str | None = None) -> Path:
    """Write :func:`result_figure` of one run to a PNG file, atomically.

    Parameters
    ----------
    result : Result
        The run.
    path : str or Path
        The image file; its folder is created.
    title : str, optional
        The title; :func:`run_title` by default.

    Returns
    -------
    Path
        The file written.
    """
    fig = result_figure(result, title)
    p = Path(path)
    from ..io.outputs import atomic_path

    with atomic_path(p) as tmp:
        fig.savefig(tmp, dpi=110)
    return p


def result_figure(result: Result, title: str | None = None) -> Any:
    """The figure of one run: table speed against its command, motor speeds, friction forces.

    Parameters
    ----------
    result : Result
        The run.
    title : str, optional
        The title; :func:`run_title` by default.

    Returns
    -------
    matplotlib.figure.Figure
        Three stacked axes sharing time [s], speeds in mm/s, forces in N.
    """
    if machine_axes(result):
        return machine_figure(result, title)
    t = result.time
    fig = Figure(figsize=(8, 8.6), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    ax = axes[0]
    ax.plot(t, 1e3 * result["table_speed"], lw=0.8, label="table")
    ax.plot(t, 1e3 * result["table_speed_reference"], "k--", lw=0.8, label="command")
    ax.set_ylabel("table speed [mm/s]")
    _legend_above(ax)
    ax = axes[1]
    if "screw_linear_speed" in result.dataset:
        ax.plot(t, 1e3 * result["screw_linear_speed"], lw=0.8, label="screw × H")
        ax.plot(t, 1e3 * result["nut_linear_speed"], lw=0.8, label="nut × H")
        ax.set_ylabel("motor speed [mm/s]")
    else:
        ax.plot(t, result["motor_current"], lw=0.8, label="motor current")
        ax.set_ylabel("current [A]")
    _legend_above(ax)
    ax = axes[2]
    for name in [n for n in result.dataset.data_vars if str(n).endswith("_friction")]:
        ax.plot(t, result[str(name)], lw=0.8, label=str(name).replace("_", " "))
    ax.set_ylabel("friction [N]")
    ax.set_xlabel("time [s]")
    _legend_above(ax)
    fig.suptitle(title or run_title(result), fontsize=10)
    return fig
