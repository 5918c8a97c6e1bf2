"""Figures of the identification fits and the trace analysis (PNG, SVG, PDF by suffix).

Built on ``matplotlib.figure.Figure`` directly (no pyplot, no GUI backend).  Axes speak the
units of the paper and the CLI: mm, mm/s, µm, N.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..analysis.presliding import DynamicFit
from ..analysis.static_fit import StaticFit, stribeck_curve
from ..analysis.trace import TraceAnalysis

__all__ = ["plot_dynamic_fit", "plot_static_fit", "plot_trace"]


def _save(fig: Figure, path: str | Path) -> None:
    from ..io.outputs import save_figure

    save_figure(fig, path, dpi=120)


def plot_static_fit(fit: StaticFit, path: str | Path) -> None:
    """Measured and fitted steady friction per direction, and the residuals."""
    fig = Figure(figsize=(10, 6.5), layout="constrained")
    axes = fig.subplots(2, len(fit.branches()), sharex="col", height_ratios=[2, 1],
                        squeeze=False)
    for col, (name, b) in enumerate(fit.branches().items()):
        v_mm = b.speed * 1e3
        grid = np.geomspace(float(np.min(b.speed)), float(np.max(b.speed)), 300)
        theta = np.array([b.branch.coulomb_force,
                          b.branch.static_force - b.branch.coulomb_force,
                          b.branch.stribeck_velocity, b.branch.viscous_coefficient])
        top, bottom = axes[0, col], axes[1, col]
        top.plot(v_mm, b.force, "o", ms=3, label="measured")
        top.plot(grid * 1e3, stribeck_curve(theta, grid), "-", label="fit")
        top.axvline(b.branch.stribeck_velocity * 1e3, ls=":", c="grey", label="v_s")
        top.set_xscale("log")
        top.set_ylabel("|friction force| [N]")
        top.set_title(f"{name} direction: F_c = {b.branch.coulomb_force:.4g} N, "
                      f"F_s = {b.branch.static_force:.4g} N,\n"
                      f"v_s = {b.branch.stribeck_velocity * 1e3:.4g} mm/s, "
                      f"σ2 = {b.branch.viscous_coefficient:.4g} N s/m", fontsize=9)
        top.legend(fontsize=8)
        bottom.plot(v_mm, b.residual, "o", ms=3)
        bottom.axhline(0.0, c="k", lw=0.8)
        bottom.set_xscale("log")
        bottom.set_xlabel("|speed| [mm/s]")
        bottom.set_ylabel("residual [N]")
    if fit.source:
        fig.suptitle(f"static friction fit: {fit.source}", fontsize=10)
    _save(fig, path)


def plot_dynamic_fit(fit: DynamicFit, path: str | Path) -> None:
    """Measured and simulated pre-sliding displacement, residual, and the σ1 profile."""
    fig = Figure(figsize=(10, 7.5), layout="constrained")
    ax = fig.subplots(3, 1, height_ratios=[2, 1, 1.4])
    ax[0].plot(fit.time, fit.position * 1e6, ".", ms=2, label="measured")
    ax[0].plot(fit.time, fit.fitted * 1e6, "-", lw=1, label=f"model ({fit.model})")
    ax[0].set_ylabel("displacement [µm]")
    ax[0].legend(fontsize=8)
    twin = ax[0].twinx()
    twin.plot(fit.time, fit.force, c="grey", lw=0.7, alpha=0.6)
    twin.set_ylabel("force [N]", color="grey")
    ax[1].plot(fit.time, fit.residual * 1e9, ".", ms=2)
    ax[1].axhline(0.0, c="k", lw=0.8)
    ax[1].set_xlabel("time [s]")
    ax[1].set_ylabel("residual [nm]")
    s1 = fit.profile_sigma1
    ok = s1 > 0
    ax[2].plot(s1[ok], fit.profile_ssr[ok], "o-", ms=3)
    ax[2].axhline(fit.ssr_threshold, ls="--", c="r",
                  label=f"{100 * fit.bristle_damping.confidence:.0f} % bound")
    ax[2].set_xscale("log")
    ax[2].set_yscale("log")
    ax[2].set_xlabel("σ1 [N s/m] (σ0 refitted at each)")
    ax[2].set_ylabel("residual sum of squares [m²]")
    ax[2].legend(fontsize=8)
    s0 = fit.bristle_stiffness
    verdict = "determined" if fit.sigma1_determined else "POORLY DETERMINED"
    fig.suptitle(f"pre-sliding fit{': ' + fit.source if fit.source else ''}\n"
                 f"σ0 = {s0.value / 1e6:.4g} ± {s0.stderr / 1e6:.2g} N/µm, σ1 {verdict}",
                 fontsize=10)
    _save(fig, path)


def plot_trace(analysis: TraceAnalysis, path: str | Path) -> None:
    """Position and speed of a trace, segments shaded, command speeds and windows marked."""
    fig = Figure(figsize=(11, 6.5), layout="constrained")
    ax = fig.subplots(2, 1, sharex=True)
    ax[0].plot(analysis.time, analysis.position * 1e3, lw=0.8)
    ax[0].set_ylabel("position [mm]")
    ax[1].plot(analysis.time, analysis.speed * 1e3, lw=0.6, label="speed")
    for seg in analysis.segments:
        m = seg.metrics
        color = "tab:red" if m.creeping else "tab:green"
        for a in ax:
            a.axvspan(m.window_start, m.window_end, color=color, alpha=0.12, lw=0)
        ax[1].hlines(seg.command_speed * 1e3, seg.start, seg.end, colors="k", lw=1.0,
                     linestyles="--")
        ax[1].annotate(f"{seg.command_speed * 1e3:.4g} mm/s\n{m.verdict}",
                       (0.5 * (seg.start + seg.end), seg.command_speed * 1e3),
                       textcoords="offset points", xytext=(0, 8), ha="center", fontsize=7)
    ax[1].set_xlabel("time [s]")
    ax[1].set_ylabel("speed [mm/s]")
    title = analysis.source or "trace"
    crit = [c for c in analysis.critical if c.lowest_smooth is not None]
    if crit:
        title += "   critical speed " + ", ".join(
            f"{c.direction}: {c.lowest_smooth * 1e3:.4g} mm/s" for c in crit
            if c.lowest_smooth is not None)
    fig.suptitle(title + "   (green: smooth, red: creeping windows)", fontsize=10)
    _save(fig, path)
