"""Benchmark: `feeddrive reproduce` wall time on an empty folder (issue 9 target ≤ 20 s on
2 cores; an earlier issue's ≤ 60 s) with the CPU time of each part, and a same-run
comparison with the plain scipy implementation.

Run from the repository root::

    python benchmarks/bench_reproduce.py

1. Runs ``feeddrive.reproduce.run`` on the ``wang2021`` preset into an empty folder (2
   workers, compiled code loaded from the numba cache after a warm-up call) and records the
   wall time, the CPU seconds of each part (summed over the workers' studies) and the number
   of trial simulations and simulated seconds it needed.
2. Times the same kind of trial with scipy ``solve_ivp(method="LSODA", rtol=1e-6)`` on the
   plain-Python model (``reference/scipy_model.py``): three representative 12-s trials of the
   study (CDFS creeping at 1.2 mm/s, CDFS smooth at 2.0 mm/s, DDFS at 1.0 mm/s with v_n =
   16 mm/s), and extrapolates to the study's simulated seconds, one process.
3. Prints and records the ratio (scipy estimate / feeddrive).

Writes ``benchmarks/results/bench_reproduce.json``.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.scipy_model import STATE_NAMES, ReferenceModel, tolerances  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.engine.simulate import DriveSystem, simulate  # noqa: E402
from feeddrive.model.reference import ConstantSpeed  # noqa: E402
from feeddrive.reproduce import run  # noqa: E402

PARTS = {"crit": "critical-speed searches (Table 3, Fig. 8, step-down)",
         "study": "model-reading study", "forced": "torque-ripple threshold searches",
         "compensation": "compensation study", "readingfig": "Figs. 7, 9-10 per reading",
         "fig6": "figure studies", "fig7": "figure studies", "figs9_10": "figure studies",
         "fig8_trace": "figure studies"}


def main() -> None:
    params = fd.preset("wang2021")
    simulate(DriveSystem(params, "ddfs", 0.4), ConstantSpeed(1e-3, 16e-3), 0.05)  # warm-up
    with tempfile.TemporaryDirectory() as tmp:
        started = time.perf_counter()
        results = run(params, Path(tmp), workers=2, study=True)
        wall = time.perf_counter() - started
    searches = list(results["critical"].values())
    sim_seconds = sum(s["simulated_time_s"] for s in searches)
    n_trials = sum(len(s["trials"]) for s in searches)
    # the study's searches are critical-speed searches of the same settings: use the mean
    # simulated time per search for them
    per_search = sim_seconds / len(searches)
    study_seconds = per_search * len(results["reading_study"])
    total_seconds = sim_seconds + study_seconds

    samples = [("cdfs", 1.2e-3, 0.0), ("cdfs", 2.0e-3, 0.0), ("ddfs", 1.0e-3, 16e-3)]
    rates = []
    for drive, v, vn in samples:
        model = ReferenceModel(params, drive, 0.4, ConstantSpeed(v, vn, 0.1))
        grid = np.arange(12001) * 1e-3
        t0 = time.perf_counter()
        sol = solve_ivp(model, (0.0, 12.0), np.zeros(len(STATE_NAMES)), method="LSODA",
                        rtol=1e-6, atol=tolerances(model.H), t_eval=grid)
        dt = time.perf_counter() - t0
        if sol.status != 0:
            raise RuntimeError(f"LSODA failed on {drive} {v}: {sol.message}")
        rates.append(dt / 12.0)
        print(f"scipy LSODA {drive} {v * 1e3:.1f} mm/s (v_n {vn * 1e3:g}): {dt:.2f} s per 12 s",
              flush=True)
    scipy_estimate = float(np.mean(rates)) * total_seconds
    parts: dict[str, float] = {}
    for name, seconds in results["cpu_seconds"].items():
        part = PARTS.get(name.split("-")[0], name)
        parts[part] = parts.get(part, 0.0) + seconds
    print("CPU seconds by part: " + ", ".join(f"{k} {v:.1f}" for k, v in parts.items()))
    out = {
        "machine": {"nproc": os.cpu_count(), "python": sys.version.split()[0]},
        "reproduce_wall_s": wall,
        "target_s": 20.0,
        "cpu_seconds_by_part": parts,
        "cpu_seconds_workers": sum(parts.values()),
        "searches": len(searches) + len(results["reading_study"]),
        "trials_in_paper_searches": n_trials,
        "simulated_seconds_estimate": total_seconds,
        "scipy_seconds_per_simulated_second": rates,
        "scipy_estimate_s_one_process": scipy_estimate,
        "ratio_scipy_over_feeddrive": scipy_estimate / wall,
    }
    print(json.dumps(out, indent=2))
    path = ROOT / "benchmarks" / "results" / "bench_reproduce.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
