"""The report's linear-analysis section: loop poles and margins, and the linear stability band
of steady sliding beside the simulated critical speeds (issue 15)."""

from __future__ import annotations

from typing import Any, NamedTuple

from ..analysis import protocol
from ..analysis.critical import format_critical_speed
from ..analysis.linear import LoopAnalysis, StabilityBand, loop_analysis, stability_band
from ..engine.simulate import DriveSystem
from ..parameters import DriveParameters, ParameterError
from .paper import PAPER

MID = 0.4  # [m] mid-screw, Wang2021 Table 3


class CdfsLinear(NamedTuple):
    """The CDFS at mid-screw linearised (:func:`cdfs_linear`).

    Parameters
    ----------
    loops : LoopAnalysis or None
        Poles and margins without friction at 1.5 mm/s; None when no steady sliding state
        was found there (``note`` says why).
    band : StabilityBand
        The unstable band of steady sliding (nut held).
    note : str
        Why ``loops`` is None; empty otherwise.
    """

    loops: LoopAnalysis | None
    band: StabilityBand
    note: str = ""


def cdfs_linear(params: DriveParameters) -> CdfsLinear:
    """The CDFS at mid-screw linearised: its loops without friction at 1.5 mm/s (the
    least-damped mode) and the band of speeds at which steady sliding is linearly unstable.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.

    Returns
    -------
    CdfsLinear
        The loops (None, with the reason, when no steady sliding state exists at 1.5 mm/s:
        ``wang2021-literal``'s undamped table) and the band.
    """
    system = DriveSystem(params, "cdfs", MID)
    band = stability_band(system, 0.0, points=BAND_POINTS)
    try:
        return CdfsLinear(loop_analysis(system, 1.5e-3, frictionless=True), band)
    except ParameterError as err:
        return CdfsLinear(None, band, str(err))


#: the scan grid of the report's stability bands (the bisection to 10⁻³ mm/s is unchanged)
BAND_POINTS = 30


def linear_rows(params: DriveParameters, results: dict[str, Any], *,
                cdfs: CdfsLinear | None = None) -> tuple[str, list[dict]]:
    """(section text, rows): the least-damped frictionless mode and loop margins of the CDFS,
    and for CDFS and DDFS the linearly unstable band next to the simulated critical speed.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    results : dict
        Every study's stored results (for the simulated critical speeds).
    cdfs : CdfsLinear, optional
        :func:`cdfs_linear` of ``params``, when already computed.

    Returns
    -------
    text : str
        The section's Markdown text.
    rows : list of dict
        One row per drive and quantity: column heading → formatted cell (mm/s, Hz, dB, deg).
    """
    crit = results.get("critical", {})
    rows: list[dict[str, str]] = []
    la, cdfs_band, failed = cdfs if cdfs is not None else cdfs_linear(params)
    for lp in la.loops if la is not None else ():
        rows.append({"item": f"CDFS {lp.name} (frictionless, 1.5 mm/s)",
                     "value": (f"crossover {lp.crossover_hz:.2f} Hz, phase margin "
                               f"{lp.phase_margin_deg:.1f}°" if lp.crossover_hz is not None
                               and lp.phase_margin_deg is not None else "no crossover"),
                     "compare": ""})
    cases = (("CDFS", "cdfs", 0.0, f"crit-cdfs-{MID}"),
             ("DDFS (v_n = 16 mm/s)", "ddfs", PAPER["ddfs_sim_nut_speed"], "crit-ddfs-fig8"))
    for label, drive, vn, key in cases:
        band = cdfs_band if drive == "cdfs" else stability_band(
            DriveSystem(params, drive, MID), vn, points=BAND_POINTS)
        lo, hi = (1e3 * v for v in protocol.LINEAR_SPEED_RANGE)
        shown = (f"stable at every speed {lo:g}–{hi:g} mm/s" if not band.intervals else "; ".join(
            f"{lo}–{hi} mm/s ({f:.2f} Hz)"
            for (lo, hi), f in zip(band.edge_texts(), band.mode_frequency_hz, strict=True)))
        sim = format_critical_speed(crit[key]) if key in crit else "—"
        rows.append({"item": f"{label}: linearly unstable steady sliding", "value": shown,
                     "compare": f"simulated critical speed from rest {sim} mm/s"})
    if la is None:
        mode = (f"The CDFS's loops could not be linearised without friction at 1.5 mm/s "
                f"({failed}).")
    else:
        d = la.dominant()
        mode = (f"The least-damped frictionless mode of the CDFS is {d.frequency_hz:.2f} Hz "
                f"with damping ratio ζ = {d.damping_ratio:.3f}: the Stribeck slope of the "
                "friction pushes this servo mode unstable, so the creep near the critical speed "
                "is a sustained oscillation of the loop.")
    text = (f"Closed loop linearised at steady sliding (`feeddrive loops`, `feeddrive "
            f"stability`).  {mode}  Where the simulated "
            "critical speed lies above the top of the unstable band, limit cycles started from "
            "rest coexist with linearly stable sliding (a sub-critical range).")
    return text, rows
