"""Benchmark (issue 21 item 3, cold start): what a new model structure costs to compile, this
tree against a baseline tree, each in fresh processes on an empty compile cache.

Run from the repository root, with the baseline's source extracted beside::

    git archive 0474c48 | tar -x -C /tmp/feeddrive-baseline
    python benchmarks/bench_compile.py --old /tmp/feeddrive-baseline [--rounds 2]

For each tree, a fresh process (``PYTHONPATH=<tree>/src``, ``NUMBA_CACHE_DIR`` an empty
folder) runs a 0.2-s ``simulate`` of the default method on each of five model *structures*
in turn (each a generated module of its own): the ``wang2021`` CDFS, the same with motor
torque ripple (``wang2021-ripple``), with a Stribeck (static) guide law, the
``linear-motor-example`` and the ``rack-pinion-example``.  The CPU seconds of each first run
(``time.process_time``: compilation, or loading, and the run) are recorded, and the
trajectory's digest, which must be the same in both trees.  Rounds alternate the trees.

Before the shared drivers (``feeddrive.solvers.shared``) every structure compiled its own
copy of the integrators; now the first pays for the drivers and each further one compiles
only its ``rhs`` and ``sample_update``.

Writes ``benchmarks/results/bench_compile.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "bench_compile.json"

WORKER = r'''
import hashlib, json, sys, time
import numpy as np
import feeddrive as fd
from feeddrive.model.reference import ConstantSpeed
assert fd.__file__.startswith(sys.argv[1]), fd.__file__
cases = [("wang2021", "cdfs", None), ("wang2021-ripple", "cdfs", None),
         ("wang2021", "cdfs", ("friction.guide.law", "stribeck")),
         ("linear-motor-example", "linear-motor", None),
         ("rack-pinion-example", "rack-pinion", None)]
out = []
for preset, drive, change in cases:
    params = fd.preset(preset)
    if change is not None:
        params = params.replace_path(*change)
    system = fd.DriveSystem(params, drive) if drive in ("linear-motor", "rack-pinion") \
        else fd.DriveSystem(params, drive, 0.4)
    t0 = time.process_time()
    result = fd.simulate(system, ConstantSpeed(2e-3), 0.2)
    cpu = time.process_time() - t0
    x = np.ascontiguousarray(result.dataset["table_position"].values)
    out.append({"case": f"{preset}/{drive}" + (f" {change[0]}={change[1]}" if change else ""),
                "cpu_s": cpu, "digest": hashlib.sha256(x.tobytes()).hexdigest()[:16]})
print(json.dumps(out))
'''


def run_tree(src: str) -> list[dict]:
    """One fresh process of a tree on an empty compile cache: its five first runs."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, PYTHONPATH=src, NUMBA_CACHE_DIR=cache)
        done = subprocess.run([sys.executable, "-c", WORKER, src], env=env, check=True,
                              capture_output=True, text=True, cwd=tempfile.gettempdir())
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--old", required=True, help="the baseline tree (its src/ is used)")
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args()
    trees = {"old": str(Path(args.old).resolve() / "src"), "new": str(ROOT / "src")}
    runs: dict[str, list[list[dict]]] = {"old": [], "new": []}
    for r in range(args.rounds):
        for name in (("old", "new") if r % 2 == 0 else ("new", "old")):
            t0 = time.perf_counter()
            runs[name].append(run_tree(trees[name]))
            print(f"round {r + 1}: {name} {time.perf_counter() - t0:.0f} s wall", flush=True)
    summary = []
    for i, case in enumerate(runs["new"][0]):
        old = sorted(run[i]["cpu_s"] for run in runs["old"])
        new = sorted(run[i]["cpu_s"] for run in runs["new"])
        same = {run[i]["digest"] for run in runs["old"] + runs["new"]}
        row = {"case": case["case"], "old_cpu_s": old, "new_cpu_s": new,
               "same_trajectory": len(same) == 1}
        summary.append(row)
        print(f"{case['case']:50s} old {min(old):6.2f} s  new {min(new):6.2f} s  "
              f"{'same trajectory' if row['same_trajectory'] else 'TRAJECTORIES DIFFER'}")
    totals = {k: min(sum(c["cpu_s"] for c in run) for run in v) for k, v in runs.items()}
    print(f"all five: old {totals['old']:.1f} s, new {totals['new']:.1f} s CPU")
    RESULTS.write_text(json.dumps({
        "benchmark": "python benchmarks/bench_compile.py --old TREE", "baseline": args.old,
        "rounds": args.rounds, "cases": summary, "total_cpu_s_min": totals,
        "machine": {"python": platform.python_version(), "cpus": os.cpu_count(),
                    "load_average": os.getloadavg()},
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}, indent=1) + "\n")
    print(f"→ {RESULTS.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
