"""`feeddrive friction`: Table 1 parameters of one site and the analytic friction indicators."""

from __future__ import annotations

import math
from typing import Any

import typer
from rich.markup import escape
from rich.table import Table

from .. import units
from ..io.outputs import PLOT_FORMATS
from ..parameters import DriveParameters, ParameterError
from . import _units
from ._common import (
    MM_PER_S,
    N_PER_UM,
    app,
    console,
    outputs,
    print_json,
    resolve_parameters,
    user_errors,
)

SITES = units.SITES
BRANCHES = ("positive", "negative")
#: the most speeds a scan takes (the whole command at 1e5: ≈ 7 CPU s, 2026-12-06)
MAX_POINTS = 100_000

SCAN_LIMITATION = (
    "The scan linearises one mass pulled at constant speed through a spring and a damper "
    "while sliding on this site alone (Åström & Canudas de Wit, IEEE CSM 2008). It leaves out "
    "the servo loops, the motor and screw inertias and the other friction sites, so its "
    "unstable band shows where stick-slip can start in that oscillator; it is not the drive's "
    "critical creeping speed (simulate the drive for that)."
)


#: the scan oscillator's largest values, those of the parameter-file fields they stand for
#: (Table.mass, stiffness.equivalent_stiffness in N/µm, stiffness.axial_damping): 1e300 N/µm
#: ended in scipy's "Array must not contain infs or NaNs", 1e300 kg was taken (an outside check,
#: 2026-12-07)
LARGEST = {"--mass": 1e5, "--stiffness": 1e5, "--damping": 1e8}


def _positive(option: str, value: float, unit: str, allow_zero: bool = False) -> float:
    high = LARGEST.get(option, math.inf)
    ok = math.isfinite(value) and (value >= 0.0 if allow_zero else value > 0.0) \
        and value <= high
    if not ok:
        op = "≥" if allow_zero else ">"
        raise ParameterError(option, value, f"expected a finite value {op} 0, ≤ {high:g} "
                                            f"[{unit}]")
    return value


def _scan_setup(params: DriveParameters, mass: float | None, stiffness_n_per_um: float | None,
                damping: float | None) -> tuple[float, float, float]:
    """(m [kg], k [N/m], c [N s/m]) of the scan; defaults come from the parameter set."""
    from ..model.mechanisms import ball_screw_stiffness as stiffness

    m = params.table.mass if mass is None else _positive("--mass", mass, "kg")
    if stiffness_n_per_um is None:
        k = stiffness.equivalent_stiffness(params, stiffness.mid_screw_position(params.screw))
    else:
        k = _positive("--stiffness", stiffness_n_per_um, "N/µm") * N_PER_UM
    c = (params.stiffness.axial_damping if damping is None
         else _positive("--damping", damping, "N s/m", allow_zero=True))
    return m, k, c


def _mm_s(speed: float) -> float:
    return speed / MM_PER_S


@app.command("friction")
@user_errors
@outputs(plot=PLOT_FORMATS)
def friction_command(
    site: str = typer.Option("screw", "--site", help="Friction site: screw, nut or guide."),
    plot: str | None = typer.Option(
        None, "--plot", help="Write the Stribeck curves of both branches to this PNG file."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of tables."),
    preset_name: str | None = typer.Option(None, "--preset", help="Named parameter set."),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
    mass: float | None = typer.Option(
        None, "--mass", metavar="KG",
        help="Scan: sliding mass [kg]. Default: the table mass (20 kg for wang2021)."),
    stiffness_n_per_um: float | None = typer.Option(
        None, "--stiffness", metavar="N_PER_UM",
        help="Scan: spring stiffness [N/µm]. Default: K_eq at mid-screw of the parameter set "
             "(the Eqs. 2–5 chain, 32.3 N/µm for wang2021, or stiffness.equivalent_stiffness "
             "if set)."),
    damping: float | None = typer.Option(
        None, "--damping", metavar="N_S_PER_M",
        help="Scan: damper parallel to the spring [N s/m]. Default: stiffness.axial_damping "
             "of the parameter set (2541 N s/m for wang2021, an assumed 5 % damping ratio; "
             "0 for wang2021-literal: the paper gives no structural damping)."),
    speed_min: float = typer.Option(0.05, "--speed-min", help="Scan: lowest speed [mm/s]."),
    speed_max: float = typer.Option(5.0, "--speed-max", help="Scan: highest speed [mm/s]."),
    points: int = typer.Option(400, "--points", help="Scan: number of speeds, log-spaced, "
                               "2 … 100000 [-]."),
    force: bool = typer.Option(False, "--force", help="Replace an existing --plot file."),
) -> None:
    """Friction parameters of one site (Wang2021 Table 1) and analytic indicators of its law.

    Per branch, under the site's law (LuGre, Dahl, static Stribeck, none): the negative-slope
    band of the steady friction curve and its zero-slope speed (below it friction has
    negative damping), the LuGre passivity margin σ2 − σ1(F_s − F_c)/F_c (LuGre only),
    and a linear-stability scan of steady sliding of a mass–spring–damper on this site.
    The scan is an indicator for a generic oscillator, not the drive: it leaves out the servo
    loops, the drive inertias and the other sites.
    """
    import numpy as np

    from ..model.friction import stribeck as friction
    from ..reproduce.paper import CDFS_CRITICAL_SPEED

    if site not in SITES:
        raise ParameterError("--site", site, f"expected one of {', '.join(SITES)}")
    from ..model.friction.lugre_parameters import LuGreParameters  # numba: at use only

    params = resolve_parameters(preset_name, params_file)
    lugre: LuGreParameters = getattr(params.friction, site).require(
        LuGreParameters, f"friction.{site}", "feeddrive friction")
    m, k, c = _scan_setup(params, mass, stiffness_n_per_um, damping)
    lo, hi = _units.speed_range("--speed-min", speed_min, "--speed-max", speed_max)
    if not 2 <= points <= MAX_POINTS:
        raise ParameterError("--points", points, f"expected 2 … {MAX_POINTS} scan speeds")
    speeds = np.geomspace(lo, hi, points)

    from ..model.friction import indicators as site_indicators

    law = lugre.law  # every indicator follows the site's own law (issue 24 item 7)
    passivity = site_indicators.has_passivity_criterion(lugre)
    branches: dict[str, dict[str, Any]] = {}
    for name in BRANCHES:
        b = lugre.branch(name)
        slope = site_indicators.steady_slope(lugre, name)
        band = slope.band
        margin = friction.passivity_margin(b, lugre) if passivity else None
        sign = 1.0 if name == "positive" else -1.0
        scan = site_indicators.site_sliding_stability(sign * speeds, lugre, m, k, c)
        unstable = friction.unstable_speed_band(scan)
        branches[name] = {
            "coulomb_force_N": b.coulomb_force,
            "static_force_N": b.static_force,
            "stribeck_velocity_mm_s": _mm_s(b.stribeck_velocity),
            "viscous_coefficient_N_s_per_m": b.viscous_coefficient,
            # an unbounded band (σ2 = 0) ends in null: no zero-slope speed
            "negative_slope_band_mm_s": (None if band is None else [
                _mm_s(band.lower), _mm_s(band.upper) if band.bounded else None]),
            "zero_slope_speed_mm_s": (None if band is None or not band.bounded
                                      else _mm_s(band.zero_slope_speed)),
            "min_steady_slope_N_s_per_m": slope.min_slope,
            "passivity_margin_N_s_per_m": margin,
            "passive": None if margin is None else margin > 0.0,
            "unstable_band_mm_s": (None if unstable is None
                                   else [_mm_s(unstable[0]), _mm_s(unstable[1])]),
            "unstable_points": int(np.count_nonzero(~scan.stable)),
        }

    paper_speed = CDFS_CRITICAL_SPEED  # Wang2021 Sect. 5.2, Fig. 6
    zero_pos = branches["positive"]["zero_slope_speed_mm_s"]
    result: dict[str, Any] = {
        "site": site,
        "law": law,
        "parameters": params.name,
        "source": "Wang2021 Table 1 (rotary sites as forces: torque / H)",
        "bristle_stiffness_N_per_m": lugre.bristle_stiffness,
        "bristle_damping_N_s_per_m": lugre.bristle_damping,
        "branches": branches,
        "paper_cdfs_critical_speed_mm_s": _mm_s(paper_speed),
        "paper_cdfs_critical_speed_source": "Wang2021 Sect. 5.2, Fig. 6",
        "stability_scan": {
            "mass_kg": m,
            "stiffness_N_per_um": k / N_PER_UM,
            "damping_N_s_per_m": c,
            "speed_min_mm_s": speed_min,
            "speed_max_mm_s": speed_max,
            "points": points,
            "limitation": SCAN_LIMITATION,
        },
    }
    if plot:
        from ..plots.stribeck import save_figure, stribeck_figure

        fig = stribeck_figure(lugre, title=f"Steady friction, {site} ({params.name}), "
                                           "Wang2021 Table 1")
        save_figure(fig, plot)
        result["plot"] = plot

    if as_json:
        print_json(result)
        return

    def fmt_band(band: list[float | None] | None) -> str:
        if band is None:
            return "none"
        lower, upper = band
        assert lower is not None  # a band always has its lower edge (0 without σ2)
        return units.slope_band_text(lower, upper)

    law_title = {"lugre": "LuGre", "dahl": "Dahl", "stribeck": "static Stribeck",
                 "none": "no"}.get(law, law)
    table = Table(title=f"{law_title} friction, {site} — {params.name} (parameters: "
                        "Wang2021 Table 1)")
    table.add_column("quantity")
    for name in BRANCHES:
        table.add_column(name, justify="right")
    rows: list[tuple[str, str]] = [
        ("F_c [N]", "{coulomb_force_N:.4g}"),
        ("F_s [N]", "{static_force_N:.4g}"),
        ("v_s [mm/s]", "{stribeck_velocity_mm_s:.4g}"),
        ("σ2 [N s/m]", "{viscous_coefficient_N_s_per_m:.4g}"),
    ]
    for label, pattern in rows:
        table.add_row(escape(label), *(pattern.format(**branches[n]) for n in BRANCHES))
    table.add_row(escape("σ0 [N/m]"), *([f"{lugre.bristle_stiffness:.4g}"] * 2))
    table.add_row(escape("σ1 [N s/m]"), *([f"{lugre.bristle_damping:.4g}"] * 2))
    table.add_row(escape("negative-slope band [mm/s]"),
                  *(fmt_band(branches[n]["negative_slope_band_mm_s"]) for n in BRANCHES))
    table.add_row(escape("zero-slope speed [mm/s]"),
                  *("none" if branches[n]["zero_slope_speed_mm_s"] is None
                    else f"{branches[n]['zero_slope_speed_mm_s']:.3f}" for n in BRANCHES))
    if law not in site_indicators.STRIBECK_CURVE_LAWS:
        table.add_row(escape("smallest steady slope [N s/m]"),
                      *(f"{branches[n]['min_steady_slope_N_s_per_m']:.4g}" for n in BRANCHES))
    table.add_row(escape("σ2 − σ1(F_s−F_c)/F_c [N s/m]"),
                  *((f"{branches[n]['passivity_margin_N_s_per_m']:.4g} "
                     f"{'pass' if branches[n]['passive'] else 'FAIL'}") if passivity
                    else "— (a LuGre criterion)" for n in BRANCHES))
    table.add_row(escape("unstable sliding [mm/s]"),
                  *(fmt_band(branches[n]["unstable_band_mm_s"]) for n in BRANCHES))
    console.print(table)
    if site == "screw" and zero_pos is not None:
        console.print(
            f"Zero-slope speed, + branch: {zero_pos:.3f} mm/s; Wang2021 Sect. 5.2 simulated "
            f"CDFS critical creeping speed: {_mm_s(paper_speed):.2f} mm/s "
            f"({zero_pos / _mm_s(paper_speed) - 1.0:+.1%})."
        )
    if passivity:
        console.print(
            "Passivity margin > 0 is a sufficient condition for the LuGre map to be "
            "dissipative (Barabanov & Ortega 2000); a FAIL does not by itself mean "
            "instability.", markup=False, highlight=False,
        )
    else:
        unused = site_indicators.UNUSED_PARAMETERS.get(law)
        console.print(
            f"The {site} site uses the {law!r} law: slopes and the scan come from that law's "
            "steady curve and linearisation; the LuGre passivity margin does not apply."
            + (f" Parameters above that this law does not use: {unused}." if unused else ""),
            markup=False, highlight=False,
        )
    console.print(
        f"Stability scan: m = {m:g} kg, k = {k / N_PER_UM:.4g} N/µm, c = {c:g} N s/m, "
        f"{points} speeds {speed_min:g} … {speed_max:g} mm/s (log-spaced). "
        + SCAN_LIMITATION,
        markup=False, highlight=False,
    )
    if plot:
        console.print(f"wrote {plot}", markup=False, highlight=False)
