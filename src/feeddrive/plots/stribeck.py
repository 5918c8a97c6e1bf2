"""Stribeck-curve figure for `feeddrive friction --plot`.  matplotlib object API on the Agg
canvas: no pyplot, no global backend switch."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from .. import units
from ..model.friction import friction_law
from ..model.friction.lugre_parameters import LuGreParameters
from ..model.friction.stribeck import negative_slope_band, steady_friction

_MM_PER_S = units.MM_PER_S


def stribeck_figure(params: LuGreParameters, title: str = "",
                    speed_max: float | None = None) -> Figure:
    """Steady friction force against sliding speed for both branches of a site.

    The curve is Wang2021 Eq. (11) at steady state (Stribeck + Coulomb + viscous, Table 1) for
    LuGre and static sites, the law's own steady curve otherwise; the negative branch is drawn
    as magnitudes so the two can be compared.  Each branch's negative-slope band is shaded and
    its zero-slope speed marked.

    Parameters
    ----------
    params : LuGreParameters
        The friction site.
    title : str, default ""
        The figure title.
    speed_max : float, optional
        Largest speed drawn [m/s]; three times the larger zero-slope speed (or 5 v_s without
        a band) by default.

    Returns
    -------
    matplotlib.figure.Figure
        Force [N] against speed [mm/s].

    References
    ----------
    .. [1] Wang2021 Eq. (11), Table 1.
    """
    from ..model.friction.indicators import STRIBECK_CURVE_LAWS, steady_slope

    # the site's own law: a Dahl or frictionless site has no Stribeck curve (issue 24 item 7)
    stribeck = params.law in STRIBECK_CURVE_LAWS
    bands = {name: (negative_slope_band(params.branch(name)) if stribeck
                    else steady_slope(params, name).band) for name in ("positive", "negative")}
    if speed_max is None:
        edges = [b.upper for b in bands.values() if b is not None and b.bounded]
        vs = max(params.positive.stribeck_velocity, params.negative.stribeck_velocity)
        speed_max = 3.0 * max(edges) if edges else 5.0 * vs
    speed = np.linspace(0.0, speed_max, 801)[1:]

    fig = Figure(figsize=(7.0, 4.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    styles = {"positive": ("C0", 1.0), "negative": ("C3", -1.0)}
    for name, (colour, sign) in styles.items():
        force = np.abs(steady_friction(sign * speed, params) if stribeck
                       else friction_law(params.law).steady_force(sign * speed, params))
        ax.plot(speed / _MM_PER_S, force, color=colour, label=f"{name} branch")
        band = bands[name]
        if band is not None:
            ax.axvspan(band.lower / _MM_PER_S, min(band.upper, speed_max) / _MM_PER_S,
                       color=colour, alpha=0.08)
            if not band.bounded:  # σ2 = 0: the curve falls at every speed
                continue
            v0 = band.zero_slope_speed
            f0 = float(np.interp(v0, speed, force))
            ax.axvline(v0 / _MM_PER_S, color=colour, linestyle="--", linewidth=0.8)
            ax.plot([v0 / _MM_PER_S], [f0], "o", color=colour,
                    label=f"zero slope, {name}: {v0 / _MM_PER_S:.2f} mm/s")
    ax.set_xlabel("sliding speed [mm/s]")
    ax.set_ylabel("steady friction force [N]")
    ax.set_xlim(0.0, speed_max / _MM_PER_S)
    ax.set_title(title or "Steady LuGre friction (Wang2021 Eq. 11, Table 1)")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize="small")
    return fig


def save_figure(fig: Figure, path: str | Path, dpi: int = 120) -> None:
    """Write a figure atomically, the format following the file extension (e.g. ``.png``).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or Path
        The image file.
    dpi : int, default 120
        Resolution [dots per inch].
    """
    from ..io.outputs import save_figure as save

    save(fig, path, dpi=dpi)
