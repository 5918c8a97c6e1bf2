"""The DDFS question (issue 14): the torque-ripple reading ``wang2021-ripple``, whose creep
is a forced oscillation and whose critical speed is defined by a ripple threshold
(:mod:`feeddrive.analysis.forced`): CDFS and DDFS at every threshold, the DDFS against the
hollow-motor speed, and the DDFS at the five table positions."""

from __future__ import annotations

from typing import Any

from .. import parameters
from ..analysis.forced import THRESHOLDS, threshold_critical_speeds
from ..engine.simulate import DriveSystem
from .studies import MID, PAPER

PRESET = "wang2021-ripple"
NUT_SPEEDS = (2e-3, 5e-3, 10e-3, 16e-3, 20e-3, 30e-3)  # [m/s] issue 14


def jobs() -> list[tuple[str, float, float, tuple[float, ...]]]:
    """(drive, nut speed [m/s], position [m], thresholds); the thresholds of one job share
    their ripple runs."""
    out: list[tuple[str, float, float, tuple[float, ...]]] = [("cdfs", 0.0, MID, THRESHOLDS)]
    out += [("ddfs", vn, MID, THRESHOLDS) for vn in NUT_SPEEDS]
    out += [("ddfs", PAPER["experiment_nut_speed"], a, (0.5,)) for a in PAPER["positions"]
            if a != MID]
    return out


def run(job: tuple[str, float, float, tuple[float, ...]]) -> dict[str, Any]:
    """{"rows": one threshold search per threshold of the job}."""
    drive, vn, position, thresholds = job
    system = DriveSystem(parameters.preset(PRESET), drive, position)
    rows = threshold_critical_speeds(system, vn, thresholds=thresholds)
    for res in rows:
        res["position_mm"] = 1e3 * position
    return {"rows": rows}


# ---- Figs. 7, 9–10 metrics per reading (issue 14 item 3)

FIGURE_READINGS: tuple[tuple[str, str, dict[str, Any]], ...] = (
    ("wang2021 (shipped)", "wang2021", {}),
    ("wang2021-ripple (torque ripple)", "wang2021-ripple", {}),
    ("wang2021-drive (real drive)", "wang2021-drive", {}),
    ("wang2021, ball–nut share 0.5", "wang2021", {"friction.ball_nut_share": 0.5}),
)


def reading_figures(index: int, settings: Any) -> dict[str, Any]:
    """Fig. 7 (DDFS at 1.55 mm/s against v_n) and Figs. 9–10 (sine reversal overshoot) metrics
    of one reading, without traces."""
    from .studies import fig7, figs9_10

    label, preset, changes = FIGURE_READINGS[index]
    p = parameters.preset(preset)
    for path, value in changes.items():
        p = p.replace_path(path, value)
    f7 = fig7(p, PAPER["cdfs_critical_sim"], settings)
    sine = figs9_10(p, settings)
    return {"reading": label,
            "fig7": [{k: r[k] for k in ("multiple", "overshoot", "settling_time", "kind")}
                     for r in f7["rows"]],
            "sine": sine["rows"]}
