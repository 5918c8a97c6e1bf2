"""Benchmark: sweep throughput on the local process pool (1 and 2 workers) and a Dask
LocalCluster (2 workers); overhead per point (issue 10).

Run from the repository root::

    python benchmarks/bench_sweep.py [--points 24]

One sweep of ``--points`` CDFS critical-speed searches from rest (the shipped protocol of
``feeddrive creep``: 0.02–3.02 mm/s, 0.01-mm/s resolution, trials until decided; no linear
band), table
positions spread over 200–600 mm × three velocity-integral gains, each run into a fresh store
(nothing found stored).  Kernels are compiled once beforehand (numba's disk cache), as
``run_sweep`` itself warms them in the parent.

* **points/s**: computed points / wall time of ``run_sweep`` (pool start, warm-up, every
  point, every store commit);
* **efficiency** at N workers: rate(N) / (N · rate(1));
* **machine parallelism** (the 2 cores are shared with other jobs): right before each
  multi-worker run, the same pure-Python loop is timed in 1 process and in N processes at
  once; ``available = N · t(1) / t(N)`` is how many cores this job actually got, and
  ``efficiency_of_available`` = rate(N) / (available · rate(1)) separates the sweep's own
  losses from the machine's load;
* **overhead per point**: (wall · workers − Σ per-point compute time) / points — what the
  executor, pickling, the store and the pool's start-up add, spread over the points; the
  per-point compute time is measured inside the worker (``seconds`` of each result).

Writes ``benchmarks/results/bench_sweep.json``.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from feeddrive.sweep import SweepStore, parse_config, run_sweep
from feeddrive.sweep.quantities import warm

ROOT = Path(__file__).resolve().parents[1]


def config(points: int) -> object:
    positions = [float(p) for p in np.linspace(200, 600, max(points // 3, 1))]
    return parse_config({
        "name": "bench", "drive": "cdfs",
        "quantity": {"kind": "critical-speed", "linear": False},
        "axes": {"table_position": positions,
                 "controller.velocity_integral_gain": [3600.0, 3925.28, 4200.0]},
    }, str(ROOT / "benchmarks" / "bench.toml"))


def one(cfg: object, **executor: object) -> dict[str, float]:
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        store = SweepStore(Path(tmp) / "bench.sqlite")
        t0 = time.perf_counter()
        summary = run_sweep(cfg, store, **executor)  # type: ignore[arg-type]
        wall = time.perf_counter() - t0
        compute = sum(r[3]["seconds"] for r in store.rows("bench") if r[3] is not None) \
            if summary.distinct == summary.points else float("nan")
        store.close()
    workers = summary.workers
    return {"points": summary.computed, "workers": workers, "wall_s": wall,
            "points_per_s": summary.computed / wall, "compute_s": compute,
            "mean_point_s": compute / summary.computed,
            "overhead_per_point_s": (wall * workers - compute) / summary.computed,
            "load_average_1min_before": load}


def _burn(n: int) -> float:
    t = time.perf_counter()
    s = 0
    for i in range(n):
        s += i * i
    return time.perf_counter() - t


def available_cores(workers: int, n: int = 15_000_000) -> float:
    """Cores this job gets now: N · t(1 process) / t(N processes at once)."""
    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(workers) as pool:
        one = min(pool.map(_burn, [n]) for _ in range(2))[0]
        many = max(pool.map(_burn, [n] * workers))
    return workers * one / many


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, default=30)
    args = ap.parse_args()
    cfg = config(args.points)
    points = cfg.points()  # type: ignore[attr-defined]
    warm(points[0].task)
    results = {"local_1": one(cfg, workers=1)}
    cores = {"local_1": 1.0}
    cores["local_2"] = available_cores(2)
    results["local_2"] = one(cfg, workers=2)
    cores["dask_local_cluster_2"] = available_cores(2)
    results["dask_local_cluster_2"] = one(cfg, dask_workers=2)
    r1 = results["local_1"]["points_per_s"]
    for name, r in results.items():
        r["efficiency"] = r["points_per_s"] / (r["workers"] * r1)
        r["available_cores"] = cores[name]
        r["efficiency_of_available"] = r["points_per_s"] / (cores[name] * r1)
        print(f"{name:22s} {r['points']:3d} points  {r['wall_s']:6.1f} s  "
              f"{r['points_per_s']:.3f} points/s  efficiency {100 * r['efficiency']:5.1f} %  "
              f"(cores available {r['available_cores']:.2f}: "
              f"{100 * r['efficiency_of_available']:5.1f} %)  "
              f"mean point {r['mean_point_s']:.2f} s  overhead {r['overhead_per_point_s']:.3f} "
              "s/point")
    out = {"machine": {"cpus": os.cpu_count(), "processor": platform.processor(),
                       "python": platform.python_version()},
           "sweep": {"points": len(points), "quantity": "critical-speed from rest, CDFS, "
                     "0.02–3.02 mm/s, 0.01 mm/s resolution"},
           "load_average_before": os.getloadavg(),
           "results": results}
    dest = ROOT / "benchmarks" / "results" / "bench_sweep.json"
    dest.write_text(json.dumps(out, indent=2) + "\n")
    print(f"written {dest}")


if __name__ == "__main__":
    main()
