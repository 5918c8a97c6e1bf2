"""Bode plots of the loop transfers and the stability-band scan (engineering units)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from matplotlib.figure import Figure

from .outputs import atomic_path

if TYPE_CHECKING:
    from .linear import LoopAnalysis, StabilityBand


def plot_loops(analysis: LoopAnalysis, path: str | Path) -> Path:
    """Open-loop magnitude and phase of every loop, margins in the legend."""
    fig = Figure(figsize=(8.5, 7), layout="constrained")
    ax_m, ax_p = fig.subplots(2, 1, sharex=True)
    for lp in analysis.loops:
        pm = f", PM {lp.phase_margin_deg:.1f}°" if lp.phase_margin_deg is not None else ""
        fc = f" at {lp.crossover_hz:.2f} Hz" if lp.crossover_hz is not None else ""
        ax_m.semilogx(lp.frequency_hz, lp.magnitude_db, lw=1.0, label=f"{lp.name}{pm}{fc}")
        ax_p.semilogx(lp.frequency_hz, lp.phase_deg, lw=1.0, label=lp.name)
    ax_m.axhline(0.0, color="k", lw=0.6)
    ax_p.axhline(-180.0, color="k", lw=0.6)
    ax_m.set_ylabel("|L(jω)| [dB]")
    ax_p.set_ylabel("∠L(jω) [deg]")
    ax_p.set_xlabel("frequency [Hz]")
    ax_m.legend(loc="best", fontsize=8)
    d = analysis.dominant()
    lin = analysis.linear
    fig.suptitle(f"Open loops at {1e3 * lin.table_speed:g} mm/s"
                 f"{' (frictionless)' if lin.frictionless else ''}: least-damped mode "
                 f"{d.frequency_hz:.2f} Hz, ζ = {d.damping_ratio:.3f}")
    p = Path(path)
    with atomic_path(p) as tmp:
        fig.savefig(tmp, dpi=110)
    return p


def plot_band(band: StabilityBand, path: str | Path) -> Path:
    """Rightmost pole's real part against table speed, unstable bands shaded."""
    fig = Figure(figsize=(8, 4.5), layout="constrained")
    ax = fig.subplots()
    ax.semilogx(1e3 * band.speeds, band.max_real_part, "o-", ms=3, lw=1.0)
    ax.axhline(0.0, color="k", lw=0.6)
    for lo, hi in band.intervals:
        ax.axvspan(1e3 * lo, 1e3 * hi, color="tab:red", alpha=0.15)
    ax.set_xlabel("table speed [mm/s]")
    ax.set_ylabel("largest real part of the poles [1/s]")
    ax.set_title("Linear stability of steady sliding (shaded: unstable)")
    p = Path(path)
    with atomic_path(p) as tmp:
        fig.savefig(tmp, dpi=110)
    return p
