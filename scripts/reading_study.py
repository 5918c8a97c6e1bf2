"""Model-reading study: how each unstated choice moves the CDFS and DDFS critical speeds.

Runs a critical-speed search from rest (scan 0.1–3.1 mm/s in 0.2 mm/s steps, bisection to
0.01 mm/s, 12-s trials judged on their second half) at mid-screw for the CDFS and for the
DDFS with v_n = 16 mm/s (Wang2021 Fig. 8), for each variant below.  Writes
src/feeddrive/reproduce/data/reading_study.csv, which the report and
docs/model-reading.md quote.

    python scripts/reading_study.py            # ~3–5 min on 2 cores
"""

from __future__ import annotations

import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pandas as pd

import feeddrive as fd
from feeddrive.reproduce.studies import StudySettings, critical_speed
from feeddrive.simulate import SimulationError

LIT = "wang2021-literal"
SHIP = "wang2021"


def variants() -> list[tuple[str, str, dict[str, object]]]:
    damp = fd.preset(SHIP).stiffness.axial_damping
    kvi = fd.preset(SHIP).controller.velocity_integral_gain
    kii = fd.preset(SHIP).controller.current_integral_gain
    return [
        ("literal (Table 2 in SI, no damping)", LIT, {}),
        ("literal + 5 % table-mode damping", LIT, {"stiffness.axial_damping": damp}),
        ("+ K_vp on table speed (A per m/s)", LIT, {"stiffness.axial_damping": damp,
                                                    "controller.velocity_gain_basis": "table"}),
        ("+ PI current loop (K_ii = K_ip R/L)", LIT, {
            "stiffness.axial_damping": damp, "controller.velocity_gain_basis": "table",
            "controller.current_integral_gain": kii}),
        ("wang2021 (+ fitted velocity integral)", SHIP, {}),
        ("wang2021, velocity integral × 0.5", SHIP,
         {"controller.velocity_integral_gain": 0.5 * kvi}),
        *[(f"wang2021, velocity integral × {f:g}", SHIP,
            {"controller.velocity_integral_gain": f * kvi}) for f in (0.6, 0.7, 0.8, 0.9)],
        ("wang2021, velocity integral × 1.5", SHIP,
         {"controller.velocity_integral_gain": 1.5 * kvi}),
        ("wang2021, P current loop", SHIP, {"controller.current_integral_gain": 0.0}),
        ("wang2021, K_eq = 2.16e7 N/m (paper)", SHIP, {"stiffness.equivalent_stiffness": 2.16e7}),
        ("wang2021, axial damping × 4", SHIP, {"stiffness.axial_damping": 4 * damp}),
        ("wang2021, velocity feedback from the table", SHIP,
         {"controller.velocity_feedback": "table"}),
        ("wang2021, sampled 1 kHz pos/vel loops, 10000 counts/rev, 0.1 µm grating", SHIP, {
            "controller.position_period": 1e-3, "controller.velocity_period": 1e-3,
            "controller.encoder_counts": 10000.0, "controller.grating_resolution": 1e-7}),
    ]


def job(args: tuple[str, str, dict[str, object], str, float]) -> dict[str, object]:
    name, preset, changes, drive, nut = args
    p = fd.preset(preset)
    for path, value in changes.items():
        p = p.replace_path(path, value)
    t0 = time.perf_counter()
    row: dict[str, object] = {"variant": name, "drive": drive, "nut_speed_mm_s": nut * 1e3}
    try:
        res = critical_speed(p, drive, 0.4, nut, StudySettings())
        row.update(critical_speed_mm_s=res["critical_speed_mm_s"], status=res["status"])
    except SimulationError as err:
        # a variant the solver cannot finish is a finding, not a reason to lose the others
        row.update(critical_speed_mm_s=None, status=f"solver failed: {err}")
    row["wall_s"] = round(time.perf_counter() - t0, 1)
    return row


def main(out: Path) -> None:
    jobs = [(n, pr, ch, d, nut) for n, pr, ch in variants()
            for d, nut in (("cdfs", 0.0), ("ddfs", 16e-3))]
    rows = []
    with ProcessPoolExecutor(max_workers=2) as pool:
        for row in pool.map(job, jobs):
            rows.append(row)
            pd.DataFrame(rows).to_csv(out, index=False)  # finished rows are never lost
            print(row, flush=True)


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("src/feeddrive/reproduce/data/reading_study.csv"))
