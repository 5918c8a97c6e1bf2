"""The report's linear-analysis section: loop poles and margins, and the linear stability band
of steady sliding beside the simulated critical speeds (issue 15)."""

from __future__ import annotations

from typing import Any

from ..analysis import protocol
from ..analysis.critical import format_critical_speed
from ..analysis.linear import loop_analysis, stability_band
from ..engine.simulate import DriveSystem
from ..parameters import DriveParameters
from .paper import PAPER

MID = 0.4  # [m] mid-screw, Wang2021 Table 3


def linear_rows(params: DriveParameters, results: dict[str, Any]) -> tuple[str, list[dict]]:
    """(section text, rows): the least-damped frictionless mode and loop margins of the CDFS,
    and for CDFS and DDFS the linearly unstable band next to the simulated critical speed."""
    crit = results.get("critical", {})
    rows: list[dict[str, str]] = []
    la = loop_analysis(DriveSystem(params, "cdfs", MID), 1.5e-3, frictionless=True)
    d = la.dominant()
    for lp in la.loops:
        rows.append({"item": f"CDFS {lp.name} (frictionless, 1.5 mm/s)",
                     "value": (f"crossover {lp.crossover_hz:.2f} Hz, phase margin "
                               f"{lp.phase_margin_deg:.1f}°" if lp.crossover_hz is not None
                               and lp.phase_margin_deg is not None else "no crossover"),
                     "compare": ""})
    cases = (("CDFS", "cdfs", 0.0, f"crit-cdfs-{MID}"),
             ("DDFS (v_n = 16 mm/s)", "ddfs", PAPER["ddfs_sim_nut_speed"], "crit-ddfs-fig8"))
    for label, drive, vn, key in cases:
        band = stability_band(DriveSystem(params, drive, MID), vn, points=30)
        lo, hi = (1e3 * v for v in protocol.LINEAR_SPEED_RANGE)
        shown = (f"stable at every speed {lo:g}–{hi:g} mm/s" if not band.intervals else "; ".join(
            f"{1e3 * lo:.3f}–{1e3 * hi:.3f} mm/s ({f:.2f} Hz)"
            for (lo, hi), f in zip(band.intervals, band.mode_frequency_hz, strict=True)))
        sim = format_critical_speed(crit[key]) if key in crit else "—"
        rows.append({"item": f"{label}: linearly unstable steady sliding", "value": shown,
                     "compare": f"simulated critical speed from rest {sim} mm/s"})
    text = (f"Closed loop linearised at steady sliding (`feeddrive loops`, `feeddrive "
            f"stability`).  The least-damped frictionless mode of the CDFS is "
            f"{d.frequency_hz:.2f} Hz with damping ratio ζ = {d.damping_ratio:.3f}: the "
            "Stribeck slope of the friction pushes this servo mode unstable, so the creep near "
            "the critical speed is a sustained oscillation of the loop.  Where the simulated "
            "critical speed lies above the top of the unstable band, limit cycles started from "
            "rest coexist with linearly stable sliding (a sub-critical range).")
    return text, rows
