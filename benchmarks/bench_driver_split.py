"""Benchmark (issue 42 item 3): the driver split into its pieces against the driver before the
split, per build and method, in one session.

Run from the repository root::

    python benchmarks/bench_driver_split.py BEFORE_SRC [--rounds 3] [--repeat 5] [--after SRC]
        [--out NAME.json]

``BEFORE_SRC`` is the ``src`` folder of a tree at the commit before the split (e.g. ``git
archive b27e7de src | tar -x -C /tmp/before``). Each round runs, in fresh processes alternating
between the two trees, the bench_engine scenarios ``cdfs_2p0``, ``cdfs_1p2`` and
``ddfs_0p5_vn16`` (wang2021, mid-screw, 10 s) with ``modal`` (the default) and ``dopri5`` in the
C and the numba build (the trees' order alternating from round to round): each process warms up
(compile or cache load) and then times one ``simulate`` per case ``--repeat`` times (5; CPU
s, ``time.process_time``, their median and least). Ratios after/before of the median over
rounds, and of the least time of all rounds (the code's own speed: the host's other load only
adds to a run's time, so the least is the steadier figure on a loaded host); the load average
before and after is recorded. Writes ``benchmarks/results/bench_driver_split.json``
(``--out``: another name there; the second round of the split, the drivers' own lines, is
``bench_driver_split2.json``; the third, ``bench_driver_split3*.json``). """

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CASES = (("cdfs_2p0", "cdfs", 2.0, 0.0), ("cdfs_1p2", "cdfs", 1.2, 0.0),
         ("ddfs_0p5_vn16", "ddfs", 0.5, 16.0))
METHODS = ("modal", "dopri5")
ENGINES = ("c", "numba")

CHILD = r"""
import json, sys, time
import feeddrive as fd
from feeddrive.engine.simulate import DriveSystem, SolverOptions, simulate
from feeddrive.model.reference import ConstantSpeed
cases = json.loads(sys.argv[1])
p = fd.preset("wang2021")
out = {}
for name, drive, vt, vn in cases:
    for method in METHODS_HERE:
        system = DriveSystem(p, drive, 0.4)
        profile = ConstantSpeed(vt * 1e-3, vn * 1e-3)
        options = SolverOptions(method=method)
        simulate(system, profile, 0.2, options=options)  # warm-up: compile or load
        cpu = []
        for _ in range(REPEAT_HERE):
            c0 = time.process_time()
            r = simulate(system, profile, 10.0, options=options)
            cpu.append(time.process_time() - c0)
        out[f"{name}|{method}"] = [sorted(cpu)[len(cpu) // 2], int(r.solver_stats["steps"]),
                                   r.solver_stats.get("engine", "?"), min(cpu)]
print(json.dumps(out))
""".replace("METHODS_HERE", repr(METHODS))


def run(src: str, engine: str, repeat: int = 5) -> dict[str, list]:
    env = dict(os.environ, PYTHONPATH=src, FEEDDRIVE_ENGINE=engine)
    child = CHILD.replace("REPEAT_HERE", str(repeat))
    done = subprocess.run([sys.executable, "-c", child, json.dumps(CASES)], env=env,
                          capture_output=True, text=True, check=True, cwd=ROOT)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("before", help="the src folder of the tree before the split")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--repeat", type=int, default=5,
                        help="timed runs per case in each process")
    parser.add_argument("--after", default=str(ROOT / "src"),
                        help="the src folder of the tree after (default: this tree's)")
    parser.add_argument("--out", default="bench_driver_split.json",
                        help="the results file's name in benchmarks/results/")
    args = parser.parse_args()
    trees = {"before": str(Path(args.before).resolve()), "after": str(Path(args.after).resolve())}
    load0 = os.getloadavg()
    t0 = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    times: dict[str, dict[str, list[float]]] = {}
    least: dict[str, dict[str, float]] = {}
    steps: dict[str, dict[str, int]] = {}
    for k in range(args.rounds):
        for engine in ENGINES:  # the trees' order alternates from round to round
            for tree, src in (list(trees.items()) if k % 2 == 0 else
                              list(trees.items())[::-1]):
                for case, (cpu, n, ran, low) in run(src, engine, args.repeat).items():
                    key = f"{case}|{engine}"
                    times.setdefault(key, {}).setdefault(tree, []).append(cpu)
                    by = least.setdefault(key, {})
                    by[tree] = min(by.get(tree, low), low)
                    steps.setdefault(key, {})[tree] = n
                    assert ran == engine, (key, ran)
    load1 = os.getloadavg()
    rows = []
    for key, by in times.items():
        b, a = statistics.median(by["before"]), statistics.median(by["after"])
        lb, la = least[key]["before"], least[key]["after"]
        rows.append({"case": key, "before_s": b, "after_s": a, "ratio": a / b,
                     "least_before_s": lb, "least_after_s": la, "least_ratio": la / lb,
                     "steps_equal": steps[key]["before"] == steps[key]["after"]})
        print(f"{key:32s} before {b * 1e3:8.1f} ms  after {a * 1e3:8.1f} ms  "
              f"ratio {a / b:5.3f}  least {lb * 1e3:6.2f} → {la * 1e3:6.2f} ms  "
              f"ratio {la / lb:5.3f}  steps equal {rows[-1]['steps_equal']}")
    record = {"recorded": t0, "load_before": load0, "load_after": load1,
              "rounds": args.rounds, "repeat": args.repeat, "rows": rows}
    out = ROOT / "benchmarks" / "results" / args.out
    out.write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")
    print("load average", load0, "→", load1)


if __name__ == "__main__":
    main()
