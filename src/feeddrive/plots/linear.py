"""Plots of the linearised loops — Bode (crossover and margins marked), Nyquist, closed-loop
step responses — and of the stability-band scan (engineering units)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure

from ..io.outputs import atomic_path

if TYPE_CHECKING:
    from ..analysis.linear import LoopAnalysis, LoopResult, StabilityBand

#: the kinds of `feeddrive loops --plot-kind`
PLOT_KINDS = ("bode", "nyquist", "step")


def _title(analysis: LoopAnalysis, what: str) -> str:
    d = analysis.dominant()
    lin = analysis.linear
    return (f"{what}\nat {1e3 * lin.table_speed:g} mm/s, {analysis.friction}: "
            f"least-damped mode {d.frequency_hz:.2f} Hz, ζ = {d.damping_ratio:.3f}")


def plot_loops(analysis: LoopAnalysis, path: str | Path, kind: str = "bode") -> Path:
    """Write a plot of the loops' open-loop transfers.

    Parameters
    ----------
    analysis : LoopAnalysis
        The analysis from :func:`feeddrive.analysis.linear.loop_analysis`.
    path : str or Path
        The image file; written atomically.
    kind : str, default "bode"
        One of :data:`PLOT_KINDS`: ``"bode"``, ``"nyquist"`` or ``"step"``.

    Returns
    -------
    Path
        The file written.
    """
    draw = {"bode": _bode, "nyquist": _nyquist, "step": _step}[kind]
    fig = draw(analysis)
    p = Path(path)
    with atomic_path(p) as tmp:
        fig.savefig(tmp, dpi=110)
    return p


def _margins_label(lp: LoopResult) -> str:
    """A loop's legend entry in the Bode and the Nyquist plot: its name, phase margin at the
    gain crossover and gain margin, ``"screw position loop, PM 89.7° at 1.36 Hz, GM 2.6 dB"``;
    "GM ∞ dB" for a loop whose phase never crosses −180°
    (:func:`~feeddrive.analysis.linear.margin_text`), no PM for a loop without gain
    crossover."""
    from ..analysis.linear import margin_text

    pm = f", PM {lp.phase_margin_deg:.1f}°" if lp.phase_margin_deg is not None else ""
    fc = f" at {lp.crossover_hz:.2f} Hz" if lp.crossover_hz is not None else ""
    gm = f", GM {margin_text('gain_margin_db', lp.gain_margin_db, '.1f', 'dB')}"
    return f"{lp.name}{pm}{fc}{gm}"


def _bode(analysis: LoopAnalysis) -> Figure:
    """Open-loop magnitude and phase of every loop; at each gain crossover a dot on 0 dB and
    the phase margin drawn as a bar up from −180°, at the phase crossover the gain margin as a
    bar down to 0 dB; the legend gives "GM ∞ dB" for a loop without phase crossover
    (:func:`~feeddrive.analysis.linear.margin_text`)."""
    fig = Figure(figsize=(8.5, 7), layout="constrained")
    ax_m, ax_p = fig.subplots(2, 1, sharex=True)
    for lp in analysis.loops:
        (line,) = ax_m.semilogx(lp.frequency_hz, lp.magnitude_db, lw=1.0,
                                label=_margins_label(lp))
        colour = line.get_color()
        ax_p.semilogx(lp.frequency_hz, lp.phase_deg, lw=1.0, color=colour, label=lp.name)
        # phases are unwrapped: draw the margin against the −180° line nearest the curve
        if lp.crossover_hz is not None and lp.phase_margin_deg is not None:
            fc_ = lp.crossover_hz
            ph = float(np.interp(fc_, lp.frequency_hz, lp.phase_deg))
            base = ph - lp.phase_margin_deg
            ax_m.plot([fc_], [0.0], "o", color=colour, ms=5)
            ax_m.axvline(fc_, color=colour, lw=0.6, ls=":")
            ax_p.axvline(fc_, color=colour, lw=0.6, ls=":")
            ax_p.annotate("", xy=(fc_, ph), xytext=(fc_, base),
                          arrowprops={"arrowstyle": "<->", "color": colour, "lw": 1.2})
            ax_p.text(fc_ * 1.08, 0.5 * (ph + base), f"PM {lp.phase_margin_deg:.1f}°",
                      color=colour, fontsize=8, va="center")
            ax_p.axhline(base, color="k", lw=0.6)
        if lp.gain_margin_db is not None:
            wrapped = (lp.phase_deg + 360.0) % 360.0 - 180.0
            above = lp.frequency_hz > (lp.crossover_hz or 0.0)
            ks = np.where(above[:-1] & (np.abs(np.diff(np.sign(wrapped))) > 0)
                          & (np.abs(np.diff(wrapped)) < 180.0))[0]
            if ks.size:
                k = int(ks[0])
                fg = float(np.interp(0.0, [wrapped[k], wrapped[k + 1]],
                                     [lp.frequency_hz[k], lp.frequency_hz[k + 1]]))
                ax_m.annotate("", xy=(fg, 0.0), xytext=(fg, -lp.gain_margin_db),
                              arrowprops={"arrowstyle": "<->", "color": colour, "lw": 1.2})
                ax_m.text(fg * 1.08, -0.5 * lp.gain_margin_db, f"GM {lp.gain_margin_db:.1f} dB",
                          color=colour, fontsize=8, va="center")
    ax_m.axhline(0.0, color="k", lw=0.6)
    ax_m.set_ylabel("|L(jω)| [dB]")
    ax_p.set_ylabel("∠L(jω) [deg]")
    ax_p.set_xlabel("frequency [Hz]")
    ax_m.legend(loc="best", fontsize=8)
    ax_m.grid(True, which="both", lw=0.3)
    ax_p.grid(True, which="both", lw=0.3)
    fig.suptitle(_title(analysis, "Open loops L(jω) (loop broken at its command)"))
    return fig


def _nyquist(analysis: LoopAnalysis) -> Figure:
    """L(jω) of every loop in the complex plane (positive frequencies, solid; their mirror,
    dashed), the critical point −1 and the unit circle; zoomed on the region around −1, where
    the margins are read; the legend gives each loop's phase and gain margins as the Bode
    plot's does (:func:`_margins_label`)."""
    fig = Figure(figsize=(7.5, 7), layout="constrained")
    ax = fig.subplots()
    for lp in analysis.loops:
        L = 10 ** (lp.magnitude_db / 20) * np.exp(1j * np.radians(lp.phase_deg))
        (line,) = ax.plot(L.real, L.imag, lw=1.1, label=_margins_label(lp))
        ax.plot(L.real, -L.imag, lw=0.7, ls="--", color=line.get_color())
    t = np.linspace(0, 2 * np.pi, 361)
    ax.plot(np.cos(t), np.sin(t), color="0.6", lw=0.6, label="|L| = 1")
    ax.plot([-1], [0], "r+", ms=12, mew=2, label="critical point −1")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.axvline(0.0, color="k", lw=0.5)
    ax.set_xlim(-3.0, 1.5)
    ax.set_ylim(-2.5, 2.5)
    ax.set_aspect("equal")
    ax.set_xlabel("Re L(jω)")
    ax.set_ylabel("Im L(jω)")
    ax.legend(loc="lower right", fontsize=8)
    lp0 = analysis.loops[0] if analysis.loops else None
    span = (f"{lp0.frequency_hz[0]:g}–{lp0.frequency_hz[-1]:g} Hz" if lp0 is not None else "")
    fig.suptitle(_title(analysis, f"Nyquist, {span}"))
    return fig


def _step(analysis: LoopAnalysis) -> Figure:
    """Closed-loop step responses of the linear model: the table position after a 1 µm step of
    the commanded table position (no speed feed-forward: a step has none), and after a 1 N
    step of the load force on the table."""
    import control

    lin = analysis.linear
    sys = lin.to_control()
    poles = [p for p in analysis.poles if not p.rigid_body and p.real < 0]
    slowest = min((abs(p.real) for p in poles), default=1.0)
    t_end = min(max(5.0 / slowest, 0.05), 5.0)  # five time constants of the slowest mode
    t = np.linspace(0.0, t_end, 2000)
    fig = Figure(figsize=(8.5, 6.5), layout="constrained")
    ax_r, ax_l = fig.subplots(2, 1, sharex=True)
    for ax, inp, scale, label in ((ax_r, "table_position_reference", 1e-6,
                                   "1 µm step of the commanded table position"),
                                  (ax_l, "load_force", 1.0, "1 N step of the load force")):
        i = lin.inputs.index(inp)
        for out, colour in (("table_position", "tab:blue"), ("following_error", "tab:red")):
            o = lin.outputs.index(out)
            resp = control.step_response(sys[o, i], T=t)
            ax.plot(resp.time, 1e6 * scale * np.asarray(resp.outputs).ravel(), color=colour,
                    lw=1.1, label=out.replace("_", " "))
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_ylabel("[µm]")
        ax.set_title(label, fontsize=10)
        ax.legend(loc="best", fontsize=8)
        ax.grid(True, lw=0.3)
    ax_l.set_xlabel("time after the step [s]")
    fig.suptitle(_title(analysis, "Closed-loop steps"))
    return fig


def plot_band(band: StabilityBand, path: str | Path) -> Path:
    """Plot the rightmost pole's real part against table speed, the unstable bands shaded
    (:func:`band_figure`).

    Parameters
    ----------
    band : StabilityBand
        The scan from :func:`feeddrive.analysis.linear.stability_band`.
    path : str or Path
        The image file; written atomically.

    Returns
    -------
    Path
        The file written.
    """
    fig = band_figure(band)
    p = Path(path)
    with atomic_path(p) as tmp:
        fig.savefig(tmp, dpi=110)
    return p


#: the legend entry of a band edge that is the scan's end
BEYOND_SCAN = "band continues beyond the scan (edge = scan's end)"


def band_figure(band: StabilityBand) -> Figure:
    """The figure of :func:`plot_band`: the rightmost pole's real part against table speed,
    the unstable bands shaded; an edge that is only the scan's end
    (:attr:`~feeddrive.analysis.linear.StabilityBand.edges_at_scan_ends`) dashed, with an
    arrow pointing on out of the scan and the legend entry :data:`BEYOND_SCAN` — the band
    goes on there, while a solid edge is one found.

    Parameters
    ----------
    band : StabilityBand
        The scan from :func:`feeddrive.analysis.linear.stability_band`.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    fig = Figure(figsize=(8, 4.5), layout="constrained")
    ax = fig.subplots()
    ax.semilogx(1e3 * band.speeds, band.max_real_part, "o-", ms=3, lw=1.0)
    ax.axhline(0.0, color="k", lw=0.6)
    label = BEYOND_SCAN
    for (lo, hi), cuts in zip(band.intervals, band.edges_at_scan_ends, strict=True):
        ax.axvspan(1e3 * lo, 1e3 * hi, color="tab:red", alpha=0.15)
        for edge, cut, outward in ((lo, cuts[0], -1), (hi, cuts[1], 1)):
            if not cut:
                continue
            ax.axvline(1e3 * edge, color="tab:red", ls="--", lw=1.2, label=label)
            label = "_nolegend_"  # one legend entry for all the cut edges
            ax.annotate("", xy=(1e3 * edge, 0.5), xycoords=("data", "axes fraction"),
                        xytext=(outward * 18, 0), textcoords="offset points",
                        arrowprops={"arrowstyle": "<-", "color": "tab:red", "lw": 1.2})
    if label != BEYOND_SCAN:
        fig.legend(loc="outside lower center", frameon=False, fontsize=8)
    ax.set_xlabel("table speed [mm/s]")
    ax.set_ylabel("largest real part of the poles [1/s]")
    ax.set_title("Linear stability of steady sliding (shaded: unstable)")
    return fig
