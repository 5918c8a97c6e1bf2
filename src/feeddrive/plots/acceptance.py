"""Figures of the acceptance tests: the ISO 230-4 polar plot and the ISO 230-2 chart.

``matplotlib.figure.Figure`` objects only (no pyplot, the backend untouched); axes in µm and
mm.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.figure import Figure

if TYPE_CHECKING:
    from ..analysis.circular import CircularTest
    from ..analysis.positioning import PositioningTest

__all__ = ["circular_figure", "compensation_figure", "positioning_figure", "save"]

_COLOURS = {"CCW": "tab:blue", "CW": "tab:red"}


def _nice(value: float) -> float:
    """The 1-2-5 number at or above ``value``."""
    if value <= 0.0 or not math.isfinite(value):
        return 1.0
    exp = math.floor(math.log10(value))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * 10.0 ** exp >= value * (1 - 1e-12):
            return m * 10.0 ** exp
    return 10.0 ** (exp + 1)


def circular_figure(result: CircularTest, *, magnification: float | None = None) -> Figure:
    """Polar plot of a circular test: the radial deviation magnified, CW and CCW overlaid.

    Each point is drawn at its angle about the least-squares centre of the runs, at the radius
    R + k·δ in the plot's own scale: the nominal circle (δ = 0) at 60 % of the plot, one ring
    per division of deviation, k the magnification the title states.

    Parameters
    ----------
    result : CircularTest
        The analysis (:func:`feeddrive.analysis.circular.circular_test`).
    magnification : float, optional
        Deviation shown per unit of radius drawn [-]; by default the largest deviation fills
        the outer 40 % of the plot.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    from ..analysis.circular import fit_circle

    ax_all = np.concatenate([r.x for r in result.runs])
    ay_all = np.concatenate([r.y for r in result.runs])
    cx, cy, _ = fit_circle(ax_all, ay_all, start=result.centre)
    deviations = [np.hypot(r.x - cx, r.y - cy) - result.radius for r in result.runs]
    span = max(float(np.max(np.abs(np.concatenate(deviations)))), 1e-9)  # [m]
    division = _nice(span / 2.0)  # [m] per ring
    if magnification is None:
        # the nominal circle at 0.6, two divisions fit in the 0.4 beyond it
        magnification = 0.2 * result.radius / division
    if not (math.isfinite(magnification) and magnification > 0.0):
        raise ValueError(f"magnification = {magnification!r}: expected > 0 [-]")
    scale = 0.6 / result.radius  # plot radius per metre of nominal radius

    fig = Figure(figsize=(7.0, 7.6), layout="constrained")
    ax = fig.add_subplot(projection="polar")
    grid = np.linspace(0.0, 2 * math.pi, 721)
    ax.plot(grid, np.full_like(grid, 0.6), c="k", lw=0.8, label="nominal circle")
    rings = [0.6 + scale * magnification * division * k for k in (-2, -1, 1, 2)]
    for r in rings:
        ax.plot(grid, np.full_like(grid, r), c="0.8", lw=0.5)
    for run, dev in zip(result.runs, deviations, strict=True):
        angle = np.arctan2(run.y - cy, run.x - cx)
        ax.plot(angle, 0.6 + scale * magnification * dev, lw=0.9,
                c=_COLOURS.get(run.direction, "k"), label=run.direction)
    hidden = sum(1 for s in result.spikes if not s.stands_out)
    for s in result.spikes:
        # a "spike" that does not stand out of the path's deviation before its reversal is
        # an oscillation's peak (a low feed's stick-slip or hunting): not labelled as one
        if s.stands_out and abs(s.height) > 0.1 * span:
            a = math.radians(s.angle + (s.peak_angle if s.direction == "CCW"
                                        else -s.peak_angle))
            # CCW labels above-left of their peak, CW below-right: the two runs' spikes at one
            # reversal lie a few degrees apart
            ccw = s.direction == "CCW"
            ax.annotate(f"{s.height * 1e6:+.2f} µm", (a, 0.6 + scale * magnification * s.height),
                        xytext=(-6 if ccw else 6, 6 if ccw else -12),
                        textcoords="offset points", ha="right" if ccw else "left",
                        fontsize=7, color=_COLOURS.get(s.direction, "k"))
    ax.set_ylim(0.0, 1.05)  # the radial axis of a polar projection
    ax.set_yticks([])
    ax.legend(loc="lower right", fontsize=8)
    g_text = ", ".join(f"G({k}) {v * 1e6:.2f} µm" for k, v in result.circular_deviation.items())
    if result.bidirectional_circular_deviation is not None:
        g_text += f", G(b) {result.bidirectional_circular_deviation * 1e6:.2f} µm"
    ax.set_title(f"ISO 230-4 circular test, R = {result.radius * 1e3:.4g} mm, "
                 f"feed {result.feed * 6e4:.4g} mm/min\n{g_text}\n"
                 f"deviation magnified ×{magnification:.4g}; rings every "
                 f"{division * 1e6:.3g} µm"
                 + (f"; {hidden} reversal spikes not labelled (they do not stand out)"
                    if hidden else ""), fontsize=9)
    return fig


def positioning_figure(result: PositioningTest) -> Figure:
    """The ISO 230-2 chart: deviation per target, both approach directions, ±2s bands.

    Parameters
    ----------
    result : PositioningTest
        The analysis (:func:`feeddrive.analysis.positioning.positioning_test`).

    Returns
    -------
    matplotlib.figure.Figure
        The figure: the deviations of every approach (points), the mean unidirectional
        deviations x̄↑, x̄↓ (lines), their bands x̄ ± 2s (dashed) and the mean bidirectional
        deviation x̄ (black).
    """
    fig = Figure(figsize=(9.0, 5.5), layout="constrained")
    ax = fig.subplots()
    p = result.targets * 1e3
    um = 1e6
    for sign, name, colour, mean, s, dev in (
            ("↑", "up", "tab:blue", result.mean_up, result.s_up, result.deviation_up),
            ("↓", "down", "tab:red", result.mean_down, result.s_down, result.deviation_down)):
        for j in range(dev.shape[1]):
            ax.plot(p, dev[:, j] * um, ".", c=colour, ms=4,
                    label=f"x_ij{sign} ({name})" if j == 0 else None)
        ax.plot(p, mean * um, "-", c=colour, lw=1.2, label=f"x̄{sign}")
        ax.plot(p, (mean + 2 * s) * um, "--", c=colour, lw=0.8, label=f"x̄{sign} ± 2s{sign}")
        ax.plot(p, (mean - 2 * s) * um, "--", c=colour, lw=0.8)
    ax.plot(p, result.mean * um, "-", c="k", lw=1.0, label="x̄ (bidirectional)")
    ax.axhline(0.0, c="0.6", lw=0.6)
    ax.set_xlabel("target position P_i [mm]")
    ax.set_ylabel("positional deviation [µm]")
    ax.set_title(f"ISO 230-2: A = {result.accuracy * um:.3f} µm, R = "
                 f"{result.repeatability * um:.3f} µm, B = {result.reversal * um:.3f} µm, "
                 f"E = {result.systematic * um:.3f} µm, M = {result.mean_range * um:.3f} µm",
                 fontsize=9)
    ax.legend(fontsize=8, ncols=2)
    return fig


def save(fig: Figure, path: str | Path) -> Path:
    """Write a figure (PNG, PDF or SVG by suffix) atomically.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or Path
        The image file.

    Returns
    -------
    Path
        The file written.
    """
    from ..io.outputs import save_figure

    return save_figure(fig, path, dpi=120)


def compensation_figure(rows: list[dict[str, Any]]) -> Figure:
    """The friction-compensation comparison: one bar panel per quantity, one bar per scheme
    (issue 37 item 4; rows of
    ``feeddrive.analysis.compensation_compare.compare_compensations``).

    Parameters
    ----------
    rows : list of dict
        The comparison's rows.

    Returns
    -------
    matplotlib.figure.Figure
        The figure; a quantity a row lacks is left without its bar, and a critical speed given
        as a bound or a word (``< 0.20``, ``undecided``) is written where its bar would be.
    """
    from ..analysis.compensation_compare import COLUMNS

    fig = Figure(figsize=(10.0, 6.5), layout="constrained")
    names = [r["scheme"] for r in rows]
    for k, (key, heading) in enumerate(COLUMNS):
        ax = fig.add_subplot(2, 2, k + 1)
        values, words = [], []
        for r in rows:
            try:
                values.append(float(r.get(key, math.nan)))
                words.append("")
            except (TypeError, ValueError):  # "< 0.20", "undecided": written, not drawn
                values.append(math.nan)
                words.append(str(r[key]))
        ax.bar(range(len(rows)), values, color="tab:blue")
        for i, word in enumerate(words):
            if word:
                ax.annotate(word, (i, 0.0), ha="center", va="bottom", fontsize=8,
                            rotation=90, xytext=(0, 3), textcoords="offset points")
        ax.set_xticks(range(len(rows)), names, rotation=30, ha="right", fontsize=8)
        ax.set_ylabel(heading)
        ax.grid(True, axis="y", alpha=0.3)
    fig.suptitle("Friction compensation compared")
    return fig
