"""The figure of a machine run: the XY path (commanded and actual, the contour error
magnified) and the contour error over time, in mm and µm."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.figure import Figure

if TYPE_CHECKING:
    from ..engine.result import Result
    from ..machine.contour import Contour


def machine_figure(result: Result, contour: Contour, title: str | None = None,
                   magnify: float | None = None) -> Any:
    """Path and contour error of a machine run.

    Parameters
    ----------
    result : Result
        A run of :func:`feeddrive.machine.simulate_machine`.
    contour : Contour
        The path it followed.
    title : str, optional
        The figure's title.
    magnify : float, optional
        Factor the contour error is drawn magnified by on the path (default: the largest
        error shown as 5 % of the path's extent) [-].

    Returns
    -------
    matplotlib.figure.Figure
        Two panels: the path [mm] and the contour error [µm] over time [s].
    """
    a, b = contour.axes
    x, y = np.asarray(result[f"{a}.table_position"]), np.asarray(result[f"{b}.table_position"])
    err = np.asarray(result["contour_error"])
    s = np.linspace(0.0, contour.length, 2000)
    path = contour.point(s)
    extent = float(max(np.ptp(path[0]), np.ptp(path[1]), 1e-9))
    peak = float(np.max(np.abs(err))) or 1.0
    k = magnify if magnify is not None else 0.05 * extent / peak
    # the actual point moved along the error direction, magnified k times
    ex, ey = np.gradient(x), np.gradient(y)
    norm = np.hypot(ex, ey)
    norm[norm == 0] = 1.0
    nx, ny = ey / norm, -ex / norm  # the right normal of the motion
    fig = Figure(figsize=(10, 4.5))
    ax1, ax2 = fig.subplots(1, 2)
    ax1.plot(path[0] * 1e3, path[1] * 1e3, color="0.6", lw=1, label="path")
    ax1.plot((x - (k - 1) * err * nx) * 1e3, (y - (k - 1) * err * ny) * 1e3, lw=1,
             label=f"actual, error ×{k:.3g}")
    ax1.set_aspect("equal", adjustable="datalim")
    ax1.set_xlabel(f"{a} [mm]")
    ax1.set_ylabel(f"{b} [mm]")
    ax1.legend(fontsize=8, frameon=False)
    ax2.plot(result.time, err * 1e6, lw=1)
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("contour error [µm]")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def plot_machine(result: Result, contour: Contour, path: str | Path,
                 title: str | None = None) -> Path:
    """Write :func:`machine_figure` to an image file, atomically.

    Parameters
    ----------
    result : Result
        The run.
    contour : Contour
        Its path.
    path : str or Path
        The image file (.png, .pdf, .svg).
    title : str, optional
        The title.

    Returns
    -------
    Path
        The file written.
    """
    from ..io.outputs import atomic_path

    fig = machine_figure(result, contour, title)
    p = Path(path)
    with atomic_path(p) as tmp:  # its folder must exist (docs/outputs.md)
        fig.savefig(tmp, dpi=110)
    return p
