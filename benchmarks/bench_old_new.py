"""Benchmark (issue 19, "speed does not regress"): the engine of this tree against the engine of
a baseline tree, the scenarios of ``bench_engine.py``, in the same run.

Run from the repository root, with the baseline's source extracted beside (nothing is
installed; each tree is imported from its own ``src``)::

    git archive ec220f9 | tar -x -C /tmp/feeddrive-baseline
    nice -n 10 python benchmarks/bench_old_new.py --old /tmp/feeddrive-baseline [--rounds 5]

Two worker processes, one per tree (``PYTHONPATH=<tree>/src``), each import their tree's own
``benchmarks/bench_engine.py`` and time, in CPU seconds (``time.process_time`` inside the
worker), what the user runs:

* ``dopri5`` (the default method: the breakpoint driver): ``simulate()`` of the three base
  scenarios, 10 s (the σ0 stress variants take ~10⁷ right-hand sides with it);
* ``modal`` (the dense-output DOPRI5 ⇄ RODAS4 driver): ``bench_engine.engine_states`` (no
  auxiliary signals, as the baselines of bench_engine) of all six scenarios, 10 s, and of the
  three base scenarios, 100 s.

Rounds are interleaved — old, new, then new, old, … — so a load from other jobs on the machine
falls on both alike; each figure is the median over ``--rounds`` after one warm-up (numba
compile or cache load).  The ratio new/old of the medians is the result (≤ 1.10 is "no
regression").  Each worker also reports its table-position trajectory: the largest difference
between the trees is recorded beside the times (0 when the new tree is bit-identical).

Writes ``benchmarks/results/bench_old_new.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "bench_old_new.json"
BASE = ("cdfs_2p0", "cdfs_1p2", "ddfs_0p5_vn16")
STRESS = ("ddfs_0p5_vn16_s0x10", "ddfs_0p5_vn16_s0x100", "cdfs_2p0_s0x100")
CASES = ([("dopri5", name, 10.0) for name in BASE]
         + [("modal", name, 10.0) for name in BASE + STRESS]
         + [("modal", name, 100.0) for name in BASE])

WORKER = r'''
import importlib.util, json, sys, time
import numpy as np
root = sys.argv[1]
spec = importlib.util.spec_from_file_location("bench_engine", root + "/benchmarks/bench_engine.py")
be = importlib.util.module_from_spec(spec)
spec.loader.exec_module(be)
import feeddrive as fd
from feeddrive import ConstantSpeed, DriveSystem, SolverOptions, simulate  # both trees' API
assert fd.__file__.startswith(root), (fd.__file__, root)
built = {}
def case(name):
    if name not in built:
        drive, v_t, v_n, kind, sigma0 = be.SCENARIOS[name]
        p = fd.preset("wang2021")
        if sigma0 != 1.0:
            p = p.replace_path("friction.screw.bristle_stiffness",
                               sigma0 * p.friction.screw.bristle_stiffness)
        system = DriveSystem(p, drive, 0.4)
        profile = ConstantSpeed(v_t, v_n)
        built[name] = (system, profile, system.model(profile))
    return built[name]
for line in sys.stdin:
    method, name, duration = line.split()
    system, profile, model = case(name)
    options = SolverOptions(method=method)
    t0 = time.process_time()
    if method == "dopri5":
        r = simulate(system, profile, float(duration), options=options)
        x = np.asarray(r["table_position"])
    else:
        _, y, _ = be.engine_states(system, model, profile, float(duration), options)
        x = y[:, model.index("table_position")]
    cpu = time.process_time() - t0
    np.save(sys.argv[2] + f"/{method}_{name}_{duration}.npy", x)
    print(json.dumps({"cpu_s": cpu}), flush=True)
'''


class Worker:
    """One tree's worker process (its ``src`` first on the path)."""

    def __init__(self, tree: Path, out: Path) -> None:
        out.mkdir(parents=True, exist_ok=True)
        env = dict(os.environ, PYTHONPATH=str(tree / "src"))
        self.proc = subprocess.Popen([sys.executable, "-c", WORKER, str(tree), str(out)],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, env=env,
                                     text=True, cwd=str(tree))
        self.out = out

    def run(self, method: str, name: str, duration: float) -> float:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(f"{method} {name} {duration}\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError(f"worker of {self.out} died")
        return float(json.loads(line)["cpu_s"])

    def close(self) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        self.proc.wait()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--old", type=Path, required=True, help="baseline source tree")
    parser.add_argument("--rounds", type=int, default=5, help="interleaved rounds (median)")
    parser.add_argument("--work", type=Path, default=Path("/tmp/feeddrive-bench-old-new"))
    parser.add_argument("--only", default="", help="comma-separated methods (e.g. dopri5)")
    args = parser.parse_args()
    cases = [c for c in CASES if not args.only or c[0] in args.only.split(",")]
    workers = {"old": Worker(args.old.resolve(), args.work / "old"),
               "new": Worker(ROOT, args.work / "new")}
    times: dict[str, dict[str, list[float]]] = {"old": {}, "new": {}}
    started = time.time()
    for method, name, duration in cases:  # warm-up: compile or load numba's cache
        for w in workers.values():
            w.run(method, name, duration)
    for r in range(args.rounds):
        order = ("old", "new") if r % 2 == 0 else ("new", "old")
        for method, name, duration in cases:
            key = f"{method} {name} {duration:g}s"
            for tree in order:
                times[tree].setdefault(key, []).append(workers[tree].run(method, name,
                                                                         duration))
        print(f"round {r + 1}/{args.rounds} done ({time.time() - started:.0f} s)", flush=True)
    for w in workers.values():
        w.close()
    rows = []
    for method, name, duration in cases:
        key = f"{method} {name} {duration:g}s"
        old = float(np.median(times["old"][key]))
        new = float(np.median(times["new"][key]))
        stem = f"{method}_{name}_{duration}.npy"
        x_old, x_new = np.load(args.work / "old" / stem), np.load(args.work / "new" / stem)
        diff = (float(np.max(np.abs(x_old - x_new))) if x_old.shape == x_new.shape
                else float("nan"))
        rows.append({"case": key, "old_cpu_ms": 1e3 * old, "new_cpu_ms": 1e3 * new,
                     "ratio_new_over_old": new / old,
                     "ratio_of_minima": min(times["new"][key]) / min(times["old"][key]),
                     "old_cpu_ms_all": [1e3 * v for v in times["old"][key]],
                     "new_cpu_ms_all": [1e3 * v for v in times["new"][key]],
                     "max_table_position_difference_m": diff})
        print(f"{key:34s} old {1e3 * old:9.1f} ms  new {1e3 * new:9.1f} ms  "
              f"new/old {new / old:5.3f} (minima {rows[-1]['ratio_of_minima']:5.3f})  "
              f"|Δx| {diff:.1e} m")
    ratios = [row["ratio_new_over_old"] for row in rows]
    summary = {"median_ratio": float(np.median(ratios)), "worst_ratio": float(max(ratios)),
               "within_10_percent": bool(max(ratios) <= 1.10)}
    print(json.dumps(summary))
    if args.only:  # a partial run is not the recorded result
        return
    RESULTS.write_text(json.dumps({
        "baseline": str(args.old), "rounds": args.rounds, "cases": rows, "summary": summary,
        "machine": {"nproc": os.cpu_count(), "python": platform.python_version(),
                    "load_average": os.getloadavg()},
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
    }, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
