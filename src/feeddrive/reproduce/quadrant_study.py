"""Beyond the paper (issue 37 item 5): does the DDFS remove the quadrant glitch?

In a CDFS every friction site slides at a speed proportional to the table's, so each reverses
when an axis of a circular test reverses, and the reversal leaves the ISO 230-4 reversal
spike.  In a DDFS whose nut runs faster than the table, the screw and the nut turn one way
throughout (the table moves at their difference): their bearings' friction never crosses zero;
only the guide (at the table's speed) and the ball–nut share of the screw friction (at the
relative screw–nut speed, ``friction.ball_nut_share``) reverse with the table.  This study runs
the ISO 230-4 circular test (:func:`~feeddrive.analysis.circular_run.run_circular_test`) on an
XY pair of the studied set's axes — CDFS, CDFS with static friction feed-forward, DDFS at
three nut speeds, and the DDFS with the guide's friction halved and doubled and with half the
screw friction at the ball–nut — and records the reversal spikes, G(b) and which friction sites
reverse.  A small circle at a low feed keeps it cheap (eight cases, two runs each).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from ..analysis.circular_run import SETTLE_FRACTION
from ..parameters import DriveParameters

__all__ = ["CASES", "FEED", "RADIUS", "run"]

#: the circle: R [m] and feed F [m/s] (1000 mm/min; below the DDFS nut speeds but the second)
RADIUS = 0.01
#: the feed F [m/s] (1000 mm/min)
FEED = 1000.0 / 6e4
ACCELERATION = 1.0  # [m/s^2]

#: (label, drive, nut speed [m/s], changes as (dotted path, value or "×k" of the set's))
CASES: tuple[tuple[str, str, float, tuple[tuple[str, Any], ...]], ...] = (
    ("CDFS", "cdfs", 0.0, ()),
    ("CDFS, static friction feed-forward", "cdfs", 0.0,
     (("controller.compensation.mode", "feedforward"),)),
    ("DDFS, v_n = 10 mm/s", "ddfs", 0.01, ()),
    ("DDFS, v_n = 20 mm/s", "ddfs", 0.02, ()),
    ("DDFS, v_n = 100 mm/s", "ddfs", 0.1, ()),
    ("DDFS, v_n = 20 mm/s, guide friction ×0.5", "ddfs", 0.02, (("guide", 0.5),)),
    ("DDFS, v_n = 20 mm/s, guide friction ×2", "ddfs", 0.02, (("guide", 2.0),)),
    ("DDFS, v_n = 20 mm/s, ball–nut share 0.5", "ddfs", 0.02,
     (("friction.ball_nut_share", 0.5),)),
)


def _scaled_guide(params: DriveParameters, factor: float) -> DriveParameters:
    """The set with the guide's Coulomb, static and viscous friction times ``factor``."""
    guide = params.friction.guide
    sides = {side: dataclasses.replace(
        getattr(guide, side), coulomb_force=getattr(guide, side).coulomb_force * factor,
        static_force=getattr(guide, side).static_force * factor,
        viscous_coefficient=getattr(guide, side).viscous_coefficient * factor)
        for side in ("positive", "negative")}
    return params.replace_path("friction.guide", dataclasses.replace(guide, **sides))


def _case_parameters(params: DriveParameters, changes: tuple[tuple[str, Any], ...]
                     ) -> DriveParameters:
    for path, value in changes:
        params = (_scaled_guide(params, value) if path == "guide"
                  else params.replace_path(path, value))
    return params


def run(params: DriveParameters) -> dict[str, Any]:
    """Every case's circular test.

    Parameters
    ----------
    params : DriveParameters
        The studied set (both axes).

    Returns
    -------
    dict
        ``radius_mm``, ``feed_mm_min`` and ``rows``: per case its label, drive, nut speed
        [mm/s], the largest and the mean reversal spike [µm] over the eight reversals, how
        many of them stand out of the path's deviation before their reversal, G(b)
        [µm], the friction sites of the X axis whose force changes sign in the measured
        revolutions and the lead arc of its runs [°] (the settling rule's,
        :func:`~feeddrive.analysis.circular_run.settling_lead`).

    References
    ----------
    .. [1] Wang2021 Sect. 2 (the DDFS: table speed = screw speed − nut speed), Sect. 6
       (v_n = 20 mm/s in the experiment).
    .. [2] ISO 230-4:2005 (the circular test).
    """
    from ..analysis.circular_run import run_circular_test
    from ..machine import Machine, MachineAxis

    rows = []
    for label, drive, nut_speed, changes in CASES:
        p = _case_parameters(params, changes)
        machine = Machine(name="xy", axes=(MachineAxis("x", p, drive),
                                           MachineAxis("y", p, drive)))
        test = run_circular_test(machine, radius=RADIUS, feed=FEED, acceleration=ACCELERATION,
                                 nut_speed=nut_speed)
        heights = np.abs([s.height for s in test.test.spikes])
        sites = test.reversing_sites()["x"]
        rows.append({"case": label, "drive": drive, "nut_speed_mm_s": nut_speed * 1e3,
                     "variant": bool(changes),
                     "spike_max_um": float(np.max(heights)) * 1e6,
                     "spike_mean_um": float(np.mean(heights)) * 1e6,
                     "bidirectional_circular_deviation_um": float(
                         test.test.bidirectional_circular_deviation or math.nan) * 1e6,
                     # spikes standing out of the residual before their reversal: where
                     # fewer than eight do, the path oscillates between the reversals and a
                     # "spike" is that oscillation's peak (analysis.circular.ReversalSpike)
                     "spikes_standing_out": sum(s.stands_out for s in test.test.spikes),
                     "reversing_sites": [s for s, n in sites.items() if n > 0],
                     "lead_arc_deg": math.degrees(test.lead_arc)})
    return {"radius_mm": RADIUS * 1e3, "feed_mm_min": FEED * 6e4, "rows": rows}


def section(study: dict[str, Any] | None) -> tuple[str, list[dict[str, str]]]:
    """The report's section: its text, with the answer read from the rows, and its table.

    Parameters
    ----------
    study : dict or None
        What :func:`run` returned (None: the study was not run).

    Returns
    -------
    text : str
        Markdown.
    rows : list of dict of str to str
        The table.
    """
    if not study:
        return "Not run (`reproduce --no-study`).", []
    rows = study["rows"]
    by = {r["case"]: r for r in rows}
    cdfs = by["CDFS"]["spike_max_um"]
    ddfs = {r["nut_speed_mm_s"]: r["spike_max_um"] for r in rows
            if r["drive"] == "ddfs" and not r["variant"]}
    fastest = max(ddfs)
    variants = [r for r in rows if r["variant"] and r["drive"] == "ddfs"]
    base = next((r for r in rows if variants and r["drive"] == "ddfs" and not r["variant"]
                 and r["nut_speed_mm_s"] == variants[0]["nut_speed_mm_s"]), None)
    text = (f"The ISO 230-4 circular test (R = {study['radius_mm']:g} mm, F = "
            f"{study['feed_mm_min']:g} mm/min, CCW and CW, `feeddrive circular`) on two "
            "axes of this set; 'reverse' lists the X axis' friction sites whose force changes "
            "sign in the measured revolutions, the spikes are the magnitudes of the eight "
            "reversal spikes.  Each case's lead-in and lead-out arcs are the settling "
            "rule's (the feed ramp, then until the slowest closed-loop mode of the axes at "
            f"the feed has decayed to {SETTLE_FRACTION:.1%}; column 'lead arc'), so that the "
            "start-up transient is no part of the numbers.  "
            f"Largest spike: CDFS {cdfs:.3g} µm; DDFS "
            + ", ".join(f"{ddfs[v]:.3g} µm at v_n = {v:g} mm/s" for v in sorted(ddfs))
            + f": at {fastest:g} mm/s the DDFS leaves {ddfs[fastest] / cdfs:.0%} of the "
            "CDFS's largest spike.  Only the sites that slide with the table still reverse "
            "there; the DDFS takes the screw's and the nut's bearing friction out of the "
            "reversal, not the guide's nor a ball–nut share.")
    hidden = [r["case"] for r in rows if r.get("spikes_standing_out", 8) < 8]
    if hidden:
        text += (f"  In {len(hidden)} of the {len(rows)} cases ({', '.join(hidden)}) fewer "
                 "than the eight spikes stand out of the path's deviation in the 45° before "
                 "their reversal (column 'stand out'): there the path oscillates between the "
                 "reversals as much as after them, and such a spike is that oscillation's "
                 "largest excursion after the reversal, not a reversal transient "
                 "(docs/acceptance-tests.md).")
    if base is not None:
        text += (f"  Mean spike at v_n = {base['nut_speed_mm_s']:g} mm/s: "
                 f"{base['spike_mean_um']:.3g} µm; "
                 + "; ".join(f"{r['case'].split(', ', 2)[-1]}: {r['spike_mean_um']:.3g} µm"
                             for r in variants) + ".")
    table = [{"case": r["case"], "largest spike [µm]": f"{r['spike_max_um']:.3g}",
              "mean spike [µm]": f"{r['spike_mean_um']:.3g}",
              "stand out": (f"{r['spikes_standing_out']} of 8" if "spikes_standing_out" in r
                            else "—"),
              "G(b) [µm]": f"{r['bidirectional_circular_deviation_um']:.4g}",
              "reverse": ", ".join(r["reversing_sites"]) or "—",
              "lead arc [°]": (f"{r['lead_arc_deg']:.4g}" if "lead_arc_deg" in r else "—")}
             for r in rows]
    return text, table
