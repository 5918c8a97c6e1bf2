"""Figures of the reproduction, one PNG per paper figure (engineering units).

``build_*`` return the matplotlib Figure (tested); the ``fig*`` functions save it.  CAPTIONS
says, per file, which report section shows it, what it shows and what the paper shows.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib
from matplotlib.figure import Figure

from ..analysis.tracking import reversal_overshoot_at

# file → (report section, caption: what it shows; what the paper shows)
CAPTIONS: dict[str, tuple[str, str]] = {
    "fig6_cdfs_1p55_1p56.png": (
        "fig6", "Table speed of the CDFS at mid-screw commanded at 1.55 and 1.56 mm/s "
        "(dashed: command). Wang2021 Fig. 6: the table crawls at 1.55 mm/s and runs stably "
        "at 1.56 mm/s after about 7 s."),
    "fig7_ddfs_nut_speed.png": (
        "fig7", "DDFS at 1.55 mm/s for hollow-motor speeds v_n in multiples of the CDFS "
        "critical speed (left) and the overshoot and settling time against v_n (right). "
        "Wang2021 Fig. 7: overshoot and settling shrink as v_n grows, with no further gain "
        "beyond about 10× the CDFS critical speed."),
    "fig8_ddfs_critical.png": (
        "fig8", "DDFS (v_n = 16 mm/s) at feeddrive's critical speed when its search finds "
        "one in range, else at the paper's 0.5 mm/s; the title says which (dashed: "
        "command). Wang2021 Fig. 8: smooth motion at 0.5 mm/s (v_s = 16.5 mm/s)."),
    "fig9_sine_1p56.png": (
        "sine", "Sinusoidal table speed of amplitude 1.56 mm/s, one panel per hollow-motor "
        "amplitude v_np; the largest reversal overshoot (the largest gap between table and "
        "command near a reversal) is drawn as a red bar. Wang2021 Fig. 9: the "
        "overshoot at speed reversal falls as v_np grows."),
    "fig10_sine_2.png": (
        "sine", "As Fig. 9 at 2 mm/s amplitude. Wang2021 Fig. 10: the same trend at 2 mm/s."),
    "fig14_position.png": (
        "table3", "Critical creeping speed against table position, feeddrive (solid) and "
        "Table 3's measurements (dashed), with k_sa (dotted, right axis). Wang2021 Fig. 14 "
        "and Table 3: the critical speed is highest at mid-screw, where k_sa is lowest."),
    "sensitivity_linear_band.png": (
        "sensitivity", "Tornado chart: change of the CDFS linear band's upper edge [%] at −step "
        "(blue) and +step (red) of each parameter, ranked by elasticity (feeddrive "
        "sensitivity --quantity linear-band; * the halving check failed). No counterpart in "
        "the paper."),
}


def _save(fig: Any, path: Path) -> Path:
    from ..io.outputs import atomic_path

    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    return path


def _mm_s(values: list[float]) -> list[float]:
    return [1e3 * v for v in values]


def _speed_axes(ax: Any, trace: dict[str, list[float]], label: str, **style: Any) -> None:
    ax.plot(trace["time"], _mm_s(trace["table_speed"]), lw=0.8, label=label, **style)


def _command(ax: Any, trace: dict[str, list[float]]) -> None:
    ax.plot(trace["time"], _mm_s(trace["table_speed_reference"]), "k--", lw=0.8,
            label="command")


def _legend_outside(fig: Any, ax: Any, where: str = "upper") -> None:
    """One legend for the figure, above or below the panels: on a trace that fills its axes
    an inner legend always covers data (issue 24 item 2).  Below when the figure has a
    suptitle (constrained layout puts an upper legend over it)."""
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc=f"outside {where} center", ncol=len(handles),
               fontsize=8, frameon=False)


def build_fig6(data: dict[str, Any]) -> Any:
    """The two CDFS runs of Wang2021 Fig. 6 side by side: table speed and its command.

    Parameters
    ----------
    data : dict
        Per commanded speed (``"1.55"``, ``"1.56"`` mm/s): its ``trace`` and ``verdict``.

    Returns
    -------
    matplotlib.figure.Figure
        Table speed [mm/s] against time [s].

    References
    ----------
    .. [1] Wang2021 Fig. 6.
    """
    fig = Figure(figsize=(10, 3.9), layout="constrained")
    axes = fig.subplots(1, 2, sharey=True)
    for ax, (key, d) in zip(axes, data.items(), strict=True):
        _speed_axes(ax, d["trace"], "table")
        _command(ax, d["trace"])
        ax.set_title(f"CDFS, v = {key} mm/s: {d['verdict']}")
        ax.set_xlabel("time [s]")
    axes[0].set_ylabel("table speed [mm/s]")
    _legend_outside(fig, axes[0])
    return fig


def fig6(data: dict[str, Any], out: Path) -> Path:
    """Draw :func:`build_fig6` and save it as ``out/fig6_cdfs_1p55_1p56.png``.

    Parameters
    ----------
    data : dict
        The stored study (as :func:`build_fig6` takes it).
    out : Path
        The report folder.

    Returns
    -------
    Path
        The file written.

    References
    ----------
    .. [1] Wang2021 Fig. 6.
    """
    return _save(build_fig6(data), out / "fig6_cdfs_1p55_1p56.png")


#: the colours of overlaid traces, in order: matplotlib's qualitative "tab10" without its grey
#: (the held nut's trace is grey) — neighbours of a sequential map (viridis) could not be told
#: apart in Fig. 7's legend (issue 41 item 5), and its yellow end was invisible (issue 24)
TRACE_COLORS = tuple(matplotlib.colormaps["tab10"](k) for k in range(10) if k != 7)


def trace_color(i: int, n: int) -> Any:
    """Colour of trace ``i`` of ``n`` overlaid traces: a distinct hue each (:data:`TRACE_COLORS`;
    more traces than hues repeat them).

    Parameters
    ----------
    i : int
        The trace's position.
    n : int
        Number of traces.

    Returns
    -------
    tuple of float
        RGB colour.
    """
    return TRACE_COLORS[i % len(TRACE_COLORS)]


def build_fig7(data: dict[str, Any]) -> Any:
    """The DDFS at 1.55 mm/s for each hollow-motor speed v_n = k × the CDFS critical speed, as in
    Wang2021 Fig. 7: the traces (v_n = 0 in grey beneath) and the overshoot and settling time
    against k.

    Parameters
    ----------
    data : dict
        The stored Fig. 7 study: ``traces`` by multiple k and the metric ``rows``.

    Returns
    -------
    matplotlib.figure.Figure
        Two panels, speeds in mm/s.

    References
    ----------
    .. [1] Wang2021 Fig. 7.
    """
    fig = Figure(figsize=(11, 4.4), layout="constrained")
    axes = fig.subplots(1, 2)
    traces = list(data["traces"].items())
    # v_n = 0 (the hollow motor held: the CDFS's behaviour) in grey beneath the others, the
    # DDFS's traces a distinct hue each (TRACE_COLORS)
    ddfs = [(k, t) for k, t in traces if float(k) > 0]
    for key, trace in traces:
        if float(key) <= 0:
            _speed_axes(axes[0], trace, f"{key}× (nut held)", color="0.6")
    for i, (key, trace) in enumerate(ddfs):
        _speed_axes(axes[0], trace, f"{key}×", color=trace_color(i, len(ddfs)))
    axes[0].set_xlabel("time [s]")
    axes[0].set_ylabel("table speed [mm/s]")
    axes[0].set_title("DDFS at 1.55 mm/s")
    # below the axes, in rows: seven traces and their legend used to cover the data, and a
    # legend beside the axes took 40 % of the width (issue 24 item 2)
    axes[0].legend(title="v_n / v_crit,CDFS", fontsize=7, title_fontsize=7,
                   loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=4)
    # v_n = 0 (the nut held) too: the right panel started at 1× (issue 41 item 5)
    rows = list(data["rows"])
    vn = [1e3 * r["nut_speed"] for r in rows]
    left = axes[1].plot(vn, [100 * r["overshoot"] for r in rows], "o-", color="C0",
                        label="overshoot [%] (left axis)")
    st = [r["settling_time"] if r["settling_time"] is not None else float("nan") for r in rows]
    ax2 = axes[1].twinx()
    right = ax2.plot(vn, st, "s--", color="C1", label="settling time [s] (right axis)")
    axes[1].set_xlabel("hollow-motor speed v_n [mm/s]")
    axes[1].set_ylabel("overshoot [%]  (circles)", color="C0")
    axes[1].tick_params(axis="y", colors="C0")
    ax2.set_ylabel("settling time (±5 %) [s]  (squares)", color="C1")
    ax2.tick_params(axis="y", colors="C1")
    axes[1].legend(handles=[*left, *right], fontsize=7, loc="upper center", ncol=2,
                   bbox_to_anchor=(0.5, -0.16))
    axes[1].set_title("overshoot and settling against v_n")
    return fig


def fig7(data: dict[str, Any], out: Path) -> Path:
    """Draw :func:`build_fig7` and save it as ``out/fig7_ddfs_nut_speed.png``.

    Parameters
    ----------
    data : dict
        The stored study (as :func:`build_fig7` takes it).
    out : Path
        The report folder.

    Returns
    -------
    Path
        The file written.

    References
    ----------
    .. [1] Wang2021 Fig. 7.
    """
    return _save(build_fig7(data), out / "fig7_ddfs_nut_speed.png")


def fig8_title(critical: dict[str, Any]) -> str:
    """Title of Fig. 8; an out-of-range search says its bound, never "None" (issue 12 item 17).

    Parameters
    ----------
    critical : dict
        The DDFS critical-speed search's result.

    Returns
    -------
    str
        The title, with the critical speed or the search's bound [mm/s].

    References
    ----------
    .. [1] Wang2021 Fig. 8.
    """
    from ..analysis.critical import format_critical_speed

    c = critical["critical_speed_mm_s"]
    head = f"DDFS, v_n = {critical['nut_speed_mm_s']:g} mm/s"
    if c is not None:
        return f"{head}, at its critical speed {c:.2f} mm/s\n(Wang2021 Fig. 8: 0.5 mm/s)"
    # the status in words, not the search's internal word "below-range" (issue 41 item 5)
    found = {"below-range": "smooth at every speed searched",
             "above-range": "creeps at every speed searched"}.get(critical["status"],
                                                                   str(critical["status"]))
    return (f"{head}: critical speed {format_critical_speed(critical)} mm/s ({found})\n"
            "shown at the paper's 0.5 mm/s (Wang2021 Fig. 8)")


def build_fig8(trace: dict[str, Any], critical: dict[str, Any]) -> Any:
    """The DDFS run at its critical speed (Wang2021 Fig. 8): table speed and command.

    Parameters
    ----------
    trace : dict
        The run's decimated ``time`` [s], ``table_speed`` and ``table_speed_reference`` [m/s].
    critical : dict
        The critical-speed search's result (for the title, :func:`fig8_title`).

    Returns
    -------
    matplotlib.figure.Figure
        Table speed [mm/s] against time [s].

    References
    ----------
    .. [1] Wang2021 Fig. 8.
    """
    fig = Figure(figsize=(7, 3.6), layout="constrained")
    ax = fig.subplots()
    _speed_axes(ax, trace, "table")
    _command(ax, trace)
    ax.set_title(fig8_title(critical))
    ax.set_xlabel("time [s]")
    ax.set_ylabel("table speed [mm/s]")
    _legend_outside(fig, ax)
    return fig


def fig8(trace: dict[str, Any], critical: dict[str, Any], out: Path) -> Path:
    """Draw :func:`build_fig8` and save it as ``out/fig8_ddfs_critical.png``.

    Parameters
    ----------
    trace : dict
        The run's decimated trace.
    critical : dict
        The critical-speed search's result.
    out : Path
        The report folder.

    Returns
    -------
    Path
        The file written.

    References
    ----------
    .. [1] Wang2021 Fig. 8.
    """
    return _save(build_fig8(trace, critical), out / "fig8_ddfs_critical.png")


def build_sine(data: dict[str, Any], amplitude_mm_s: float, figure: str) -> Any:
    """Small multiples: one panel per hollow-motor amplitude (overlaid, the 10 mm/s trace was
    hidden), the largest reversal overshoot marked and written in each panel.

    Parameters
    ----------
    data : dict
        The stored Figs. 9–10 study.
    amplitude_mm_s : float
        The table-speed amplitude shown [mm/s].
    figure : str
        Which paper figure it reproduces, for the title (``"Fig. 9"``).

    Returns
    -------
    matplotlib.figure.Figure
        One panel per hollow-motor amplitude, speeds in mm/s.

    References
    ----------
    .. [1] Wang2021 Figs. 9–10.
    """
    traces = [(k, t) for k, t in data["traces"].items()
              if abs(float(k.split("/")[0]) - amplitude_mm_s) < 1e-9]
    fig = Figure(figsize=(8, 1.9 * len(traces) + 1.0), layout="constrained")
    axes = fig.subplots(len(traces), 1, sharex=True, sharey=True, squeeze=False)
    for ax, (key, trace) in zip(axes[:, 0], traces, strict=True):
        vn = key.split("/")[1]
        _speed_axes(ax, trace, "table")
        _command(ax, trace)
        # the number is the study's (full-resolution run); the stored trace only places it
        _, at = reversal_overshoot_at(trace["time"], _mm_s(trace["table_speed"]),
                                      _mm_s(trace["table_speed_reference"]),
                                      amplitude_mm_s, data["frequency"])
        value = next(r["reversal_overshoot"] for r in data["rows"]
                     if abs(1e3 * r["table_amplitude"] - amplitude_mm_s) < 1e-9
                     and abs(1e3 * r["nut_amplitude"] - float(vn)) < 1e-9)
        if at is not None:
            # the overshoot is the largest gap between table and command near a reversal
            # (not a peak of the trace): drawn as that gap, a bar from command to table
            k = min(range(len(trace["time"])), key=lambda i: abs(trace["time"][i] - at))
            ref_k = 1e3 * trace["table_speed_reference"][k]
            ax.plot([at, at], [ref_k, 1e3 * trace["table_speed"][k]], "-", color="C3", lw=2.2,
                    solid_capstyle="butt",
                    label="largest gap to the command near a reversal (reversal overshoot)")
        # the panel's label as its title: a box in the axes blanked the trace's peak
        ax.set_title(f"v_np = {vn} mm/s: reversal overshoot {100 * value:.0f} %",
                     loc="left", fontsize=8, pad=3)
        ax.set_ylabel("table speed\n[mm/s]", fontsize=8)
    _legend_outside(fig, axes[0, 0], "lower")
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(f"{figure}: sinusoidal table speed, amplitude {amplitude_mm_s:g} mm/s, "
                 f"{data['frequency']:g} Hz")
    return fig


def figs9_10(data: dict[str, Any], out: Path) -> list[Path]:
    """Draw :func:`build_sine` for the 1.56 and 2 mm/s amplitudes and save them as
    ``out/fig9_sine_1p56.png`` and ``out/fig10_sine_2.png``.

    Parameters
    ----------
    data : dict
        The stored Figs. 9–10 study.
    out : Path
        The report folder.

    Returns
    -------
    list of Path
        The two files written.

    References
    ----------
    .. [1] Wang2021 Figs. 9–10.
    """
    return [_save(build_sine(data, amp, figure), out / name)
            for amp, figure, name in ((1.56, "Fig. 9", "fig9_sine_1p56.png"),
                                      (2.0, "Fig. 10", "fig10_sine_2.png"))]


def build_fig14(rows: list[dict[str, Any]]) -> Any:
    """Critical speed against table position, feeddrive's beside Wang2021 Table 3's measured
    values, for CDFS and DDFS.

    Parameters
    ----------
    rows : list of dict
        Per position: ``position`` [m], ``cdfs``/``ddfs`` critical speeds [m/s] (None when not
        found) and the paper's ``cdfs_paper``/``ddfs_paper`` [m/s].

    Returns
    -------
    matplotlib.figure.Figure
        Speeds in mm/s against position in mm.

    References
    ----------
    .. [1] Wang2021 Table 3, Fig. 14.
    """
    fig = Figure(figsize=(7.5, 4.2), layout="constrained")
    ax = fig.subplots()
    pos = [1e3 * r["position"] for r in rows]

    def mm(v: float | None) -> float:
        return float("nan") if v is None else 1e3 * v

    for drive, marker, color in (("cdfs", "o", "C0"), ("ddfs", "s", "C2")):
        name = drive.upper()
        ours = [mm(r[drive]) for r in rows]
        if any(v == v for v in ours):  # a legend entry only for a line with data
            ax.plot(pos, ours, marker + "-", color=color, label=f"{name} (feeddrive)")
        ax.plot(pos, [mm(r[f"{drive}_paper"]) for r in rows], marker + "--", color=color,
                alpha=0.6, label=f"{name} (Table 3, measured)")
        # out-of-range searches: a triangle at the bound they give
        below = [(p, mm(r["speed_range"][0])) for p, r in zip(pos, rows, strict=True)
                 if r[drive] is None and r[f"{drive}_status"] == "below-range"]
        if below:
            ax.plot(*zip(*below, strict=True), "v", color=color, ms=9,
                    label=f"{name} (feeddrive): smooth down to {below[0][1]:.2f} mm/s")
    ax.set_xlabel("table position x_t [mm]")
    ax.set_ylabel("critical creeping speed [mm/s]")
    ax2 = ax.twinx()
    ax2.plot(pos, [1e-6 * r["k_sa"] for r in rows], "k:", label="k_sa (right axis)")
    ax2.set_ylabel("k_sa [N/µm]")
    handles = ax.get_legend_handles_labels()[0] + ax2.get_legend_handles_labels()[0]
    # below the plot, in two columns: beside it, the legend took 40 % of the width
    fig.legend(handles=handles, fontsize=7, loc="outside lower center", ncol=2,
               frameon=False)
    ax.set_title("critical speed against table position (Table 3, Fig. 14)")
    return fig


def fig14(rows: list[dict[str, Any]], out: Path) -> Path:
    """Draw :func:`build_fig14` and save it as ``out/fig14_position.png``.

    Parameters
    ----------
    rows : list of dict
        Per position, as :func:`build_fig14` takes them.
    out : Path
        The report folder.

    Returns
    -------
    Path
        The file written.

    References
    ----------
    .. [1] Wang2021 Fig. 14.
    """
    return _save(build_fig14(rows), out / "fig14_position.png")
