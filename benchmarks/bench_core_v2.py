"""The composable core (v2) against the hard-wired v1 engine it replaced, same machine, same run.

Issue "Engine core v2" asks that the benchmark's three scenarios (``reference.cases.BENCH_CASES``,
10 s each) are no slower than before by more than 10 %.  This script times ``simulate()`` of
both engines in separate worker processes, interleaved (v1, v2, v1, v2, …), each after a
warm-up run (compile or disk-cache load), and reports medians of CPU time and the ratio.

The v1 engine is the package at commit 1f1fc75, checked out with
``git worktree add /tmp/v1tree 1f1fc75`` (pass another folder with ``--v1``).

    python benchmarks/bench_core_v2.py [--v1 /tmp/v1tree] [--rounds 7]

Results: ``benchmarks/results/bench_core_v2.json`` and benchmarks/README.md.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "bench_core_v2.json"

WORKER = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
from reference.cases import BENCH_CASES
import feeddrive as fd
cases = {c.name: c for c in BENCH_CASES}
out = {}
for name, case in cases.items():
    system = fd.DriveSystem(case.parameters(), case.drive, 0.4)
    fd.simulate(system, case.profile(), case.duration)  # warm-up
    cpu = []
    for _ in range(int(sys.argv[2])):
        t0 = time.process_time()
        r = fd.simulate(system, case.profile(), case.duration)
        cpu.append(time.process_time() - t0)
    out[name] = {"cpu_s": cpu, "rhs_evaluations": r.solver_stats["rhs_evaluations"],
                 "final_speed": float(r["table_speed"][-1])}
print(json.dumps(out))
"""


def run(src: Path, repeats: int) -> dict[str, dict[str, object]]:
    env = dict(os.environ, PYTHONPATH=str(src))
    done = subprocess.run([sys.executable, "-c", WORKER, str(ROOT), str(repeats)], env=env,
                          capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--v1", default="/tmp/v1tree")
    ap.add_argument("--rounds", type=int, default=7)
    args = ap.parse_args()
    v1_src, v2_src = Path(args.v1) / "src", ROOT / "src"
    samples: dict[str, dict[str, list[float]]] = {}
    info: dict[str, dict[str, object]] = {}
    for _ in range(args.rounds):
        for label, src in (("v1", v1_src), ("v2", v2_src)):
            for name, rec in run(src, 3).items():
                samples.setdefault(name, {}).setdefault(label, []).extend(rec["cpu_s"])
                info.setdefault(name, {})[label] = {"rhs_evaluations": rec["rhs_evaluations"],
                                                    "final_speed": rec["final_speed"]}
    table = {}
    for name, s in samples.items():
        v1, v2 = float(np.median(s["v1"])), float(np.median(s["v2"]))
        table[name] = {"v1_ms": 1e3 * v1, "v2_ms": 1e3 * v2, "v2_over_v1": v2 / v1,
                       "samples_each": len(s["v1"]), **info[name]}
        print(f"{name:16s} v1 {1e3 * v1:7.2f} ms   v2 {1e3 * v2:7.2f} ms   "
              f"v2/v1 {v2 / v1:5.3f}   same final speed: "
              f"{info[name]['v1']['final_speed'] == info[name]['v2']['final_speed']}")
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps({"rounds": args.rounds, "metric": "median CPU time of "
                                   "simulate(), 10-s runs", "cases": table}, indent=2) + "\n")


if __name__ == "__main__":
    main()
