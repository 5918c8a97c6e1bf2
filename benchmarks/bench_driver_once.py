"""Benchmark (issue 42, the compile target): the engine's C drivers compiled once for every
model against once per model — compile cost of a cold ``feeddrive reproduce`` and run time of
the C build, two source trees measured in one run.

Run from the repository root, with a copy of the tree to compare against (for example
``git archive main | tar -x -C /tmp/before``)::

    python benchmarks/bench_driver_once.py --before /tmp/before [--after .] [--rounds 5]
        [--reproduce] [--out benchmarks/results/bench_driver_once.json]

Both trees run with this interpreter and its installed packages, each tree's ``src`` first on
``PYTHONPATH`` (so the ``feeddrive`` imported is that tree's), ``FEEDDRIVE_ENGINE=c``.

**Run time** (``--rounds`` rounds, the trees alternating, their order swapped every round;
each round a fresh process per tree, its C cache filled by a warm-up process first): for each
scenario of ``bench_engine_c.py`` and each method at its defaults, a warm-up run and then
``--repeat`` runs of 10 s (the fixed-step methods 1 s at 10 µs); per run the CPU time inside
the driver calls and of the whole ``simulate`` call.  Reported: per row the median over all
runs of each tree, the ratio after/before, the right-hand-side evaluations and whether the
two trees' signals are bit-identical (SHA-256 of every signal and of the solver statistics).

**Compile cost** (``--reproduce``): per tree, ``feeddrive reproduce --out DIR`` once with a
throw-away C cache (numba's cache and the package's other caches warm), then once more with an
empty ``FEEDDRIVE_C_CACHE``, under ``/usr/bin/time`` (user + system CPU of the whole process
tree) and with ``CC`` a wrapper that logs every compiler call's command and CPU seconds
(``/usr/bin/time -a``): their count (``--version`` calls apart) and CPU sum.  The load average
is recorded before and after each measurement.

Writes the JSON given by ``--out`` and the same name with ``.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = {
    "cdfs_2p0": ("wang2021", "cdfs", 2.0e-3, 0.0),
    "cdfs_1p2": ("wang2021", "cdfs", 1.2e-3, 0.0),
    "ddfs_0p5_vn16": ("wang2021", "ddfs", 0.5e-3, 16e-3),
    "cdfs_gms": ("examples/gms_guide.toml", "cdfs", 2.0e-3, 0.0),
}

# runs inside a child process with one tree's src on PYTHONPATH; prints one JSON line
_CHILD = r"""
import hashlib, json, sys, time
import numpy as np
import feeddrive as fd
from feeddrive.engine.options import METHODS
from feeddrive.model.reference import ConstantSpeed
from feeddrive.parameters.toml_io import load
from feeddrive.solvers import builds

root, scenarios, repeat = sys.argv[1], json.loads(sys.argv[2]), int(sys.argv[3])
inside = [0.0]
plain = builds.driver

def timed(model, use):
    fn = plain(model, use)
    def call(*args):
        t0 = time.process_time()
        try:
            return fn(*args)
        finally:
            inside[0] += time.process_time() - t0
    return call

builds.driver = timed
out = {"feeddrive": fd.__file__, "rows": {}}
for name, (source, drive, v_t, v_n) in scenarios.items():
    params = load(f"{root}/{source}") if source.endswith(".toml") else fd.preset(source)
    system = fd.DriveSystem(params, drive, 0.4)
    for method in METHODS:
        fixed = method.endswith("-fixed")
        options = fd.SolverOptions(method=method, **({"fixed_step": 1e-5} if fixed else {}))
        duration = 1.0 if fixed else 10.0
        runs = []
        for k in range(repeat + 1):
            inside[0] = 0.0
            t0 = time.process_time()
            r = fd.simulate(system, ConstantSpeed(v_t, v_n), duration, options=options)
            whole = time.process_time() - t0
            if k:
                runs.append((whole, inside[0]))
        assert r.solver_stats["engine"] == "c", r.solver_stats["engine"]
        digest = hashlib.sha256(np.ascontiguousarray(r.time).tobytes())
        for s in r.signal_names():
            digest.update(np.ascontiguousarray(np.asarray(r[s], dtype=float)).tobytes())
        stats = {k: v for k, v in r.solver_stats.items() if k not in ("wall_time_s",)}
        digest.update(json.dumps(stats, sort_keys=True, default=str).encode())
        out["rows"][f"{name}/{method}"] = {
            "whole": [w for w, _ in runs], "driver": [d for _, d in runs],
            "rhs": int(r.solver_stats["rhs_evaluations"]), "sha256": digest.hexdigest()}
print(json.dumps(out))
"""


def _env(tree: Path, cache: str, **more: str) -> dict[str, str]:
    env = dict(os.environ, FEEDDRIVE_ENGINE="c", FEEDDRIVE_C_CACHE=cache, **more)
    env["PYTHONPATH"] = str(tree / "src") + (os.pathsep + env["PYTHONPATH"]
                                             if env.get("PYTHONPATH") else "")
    return env


def run_time(trees: dict[str, Path], rounds: int, repeat: int, work: Path,
             scenarios: dict[str, Any]) -> dict[str, Any]:
    caches = {label: str(work / f"cache-{label}") for label in trees}
    for label, tree in trees.items():  # fill each tree's C cache
        subprocess.run([sys.executable, "-c", _CHILD, str(tree), json.dumps(
            {"cdfs_2p0": SCENARIOS["cdfs_2p0"]}), "0"], env=_env(tree, caches[label]),
            cwd=tree, check=True, capture_output=True, text=True)
    per: dict[str, dict[str, dict[str, Any]]] = {label: {} for label in trees}
    loads = []
    order = list(trees)
    for k in range(rounds):
        for label in (order if k % 2 == 0 else order[::-1]):
            before = os.getloadavg()
            done = subprocess.run([sys.executable, "-c", _CHILD, str(trees[label]),
                                   json.dumps(scenarios), str(repeat)],
                                  env=_env(trees[label], caches[label]), cwd=trees[label],
                                  check=True, capture_output=True, text=True)
            loads.append((label, k, before, os.getloadavg()))
            got = json.loads(done.stdout.strip().splitlines()[-1])
            assert got["feeddrive"].startswith(str(trees[label].resolve())), got["feeddrive"]
            for row, v in got["rows"].items():
                into = per[label].setdefault(row, {"whole": [], "driver": [], "rhs": set(),
                                                   "sha256": set()})
                into["whole"] += v["whole"]
                into["driver"] += v["driver"]
                into["rhs"].add(v["rhs"])
                into["sha256"].add(v["sha256"])
            print(f"round {k} {label}: load {before[0]:.2f} -> {os.getloadavg()[0]:.2f}",
                  flush=True)
    rows = []
    for row in per["before"]:
        b, a = per["before"][row], per["after"][row]
        med = {f"{label}_{what}": statistics.median(per[label][row][what])
               for label in trees for what in ("whole", "driver")}
        rows.append({"row": row, **med,
                     "after_over_before_driver": med["after_driver"] / med["before_driver"],
                     "after_over_before_whole": med["after_whole"] / med["before_whole"],
                     "rhs": sorted(b["rhs"] | a["rhs"]),
                     "bit_identical": len(b["sha256"] | a["sha256"]) == 1,
                     "runs": len(b["driver"])})
    return {"rows": rows, "loads": loads}


def _wrapper(folder: Path) -> Path:
    cc = shutil.which("gcc") or shutil.which("cc")
    assert cc is not None, "no gcc/cc on PATH"
    path = folder / "cc-logged"
    path.write_text("#!/bin/sh\nexec /usr/bin/time -a -o \"$FD_CC_LOG\" -f '%U %S %e %C' "
                    f"{cc} \"$@\"\n")
    path.chmod(0o755)
    return path


def reproduce(trees: dict[str, Path], work: Path) -> dict[str, Any]:
    cc = _wrapper(work)
    feeddrive = [sys.executable, "-m", "feeddrive", "reproduce"]
    out: dict[str, Any] = {}
    for label, tree in trees.items():
        warm_cache = work / f"repro-warm-{label}"
        subprocess.run(feeddrive + ["--out", str(work / f"out-warm-{label}")],
                       env=_env(tree, str(warm_cache)), cwd=tree, check=True,
                       capture_output=True, text=True)
        shutil.rmtree(warm_cache, ignore_errors=True)
        cold_cache = work / f"repro-cold-{label}"
        log, timing = work / f"cc-{label}.log", work / f"time-{label}.txt"
        before = os.getloadavg()
        t0 = time.time()
        subprocess.run(["/usr/bin/time", "-o", str(timing), "-f", "%U %S %e"] + feeddrive
                       + ["--out", str(work / f"out-cold-{label}")],
                       env=_env(tree, str(cold_cache), CC=str(cc), FD_CC_LOG=str(log)),
                       cwd=tree, check=True, capture_output=True, text=True)
        wall = time.time() - t0
        user, system, _ = (float(x) for x in timing.read_text().split()[-3:])
        calls = [line.split(maxsplit=3) for line in log.read_text().splitlines()
                 if line.strip() and "--version" not in line]
        compiles = [(float(u) + float(s), cmd) for u, s, _, cmd in calls]
        libraries = sorted(p.name for p in cold_cache.iterdir() if p.suffix in (".so", ".dll",
                                                                                  ".dylib"))
        out[label] = {"tree_user_s": user, "tree_sys_s": system, "tree_cpu_s": user + system,
                      "wall_s": wall, "compiler_calls": len(compiles),
                      "compiler_cpu_s": sum(c for c, _ in compiles),
                      "largest_compile_cpu_s": max((c for c, _ in compiles), default=0.0),
                      "libraries": len(libraries), "load_before": before,
                      "load_after": os.getloadavg()}
        print(label, out[label], flush=True)
    return out


def markdown(data: dict[str, Any]) -> str:
    lines = [f"# Engine drivers compiled once vs per model ({data['machine']}, {data['date']})",
             ""]
    if "reproduce" in data:
        lines += ["Cold `feeddrive reproduce` (empty C cache, numba's warm; CPU s of the "
                  "process tree by /usr/bin/time; compiler calls by a logging `CC`):", "",
                  "| tree | tree CPU (user + sys) | wall | compiler calls | compiler CPU | "
                  "largest call | libraries | load |", "|---|---|---|---|---|---|---|---|"]
        for label, v in data["reproduce"].items():
            lines.append(f"| {label} | {v['tree_cpu_s']:.1f} ({v['tree_user_s']:.1f} + "
                         f"{v['tree_sys_s']:.1f}) | {v['wall_s']:.1f} | {v['compiler_calls']} "
                         f"| {v['compiler_cpu_s']:.2f} | {v['largest_compile_cpu_s']:.2f} | "
                         f"{v['libraries']} | {v['load_before'][0]:.2f}→"
                         f"{v['load_after'][0]:.2f} |")
        lines.append("")
    if "run_time" in data:
        rt = data["run_time"]
        lines += [f"Run time, C build (medians over all runs of each tree: {data['rounds']} "
                  f"rounds × {data['repeat']} runs; CPU s):", "",
                  "| scenario/method | before driver | after driver | after/before driver | "
                  "before whole | after whole | after/before whole | RHS | bit-identical |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for r in rt["rows"]:
            lines.append(f"| {r['row']} | {r['before_driver']:.4f} | {r['after_driver']:.4f} "
                         f"| {r['after_over_before_driver']:.3f} | {r['before_whole']:.4f} | "
                         f"{r['after_whole']:.4f} | {r['after_over_before_whole']:.3f} | "
                         f"{'/'.join(map(str, r['rhs']))} | {r['bit_identical']} |")
        loads = [f"{label} r{k} {b[0]:.2f}→{a[0]:.2f}" for label, k, b, a in rt["loads"]]
        lines += ["", "Load average (1 min) per process: " + ", ".join(loads)]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, required=True)
    parser.add_argument("--after", type=Path, default=ROOT)
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--reproduce", action="store_true")
    parser.add_argument("--scenarios", default=",".join(SCENARIOS))
    parser.add_argument("--no-run-time", action="store_true")
    parser.add_argument("--out", type=Path,
                        default=ROOT / "benchmarks" / "results" / "bench_driver_once.json")
    args = parser.parse_args()
    trees = {"before": args.before.resolve(), "after": args.after.resolve()}
    data: dict[str, Any] = {"machine": f"{platform.machine()} {platform.system()}, "
                            f"{os.cpu_count()} cores",
                            "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
                            "trees": {k: str(v) for k, v in trees.items()},
                            "rounds": args.rounds, "repeat": args.repeat}
    with tempfile.TemporaryDirectory(prefix="bench-driver-once-") as tmp:
        work = Path(tmp)
        if args.reproduce:
            data["reproduce"] = reproduce(trees, work)
        if not args.no_run_time:
            data["run_time"] = run_time(trees, args.rounds, args.repeat, work,
                                        {k: SCENARIOS[k] for k in args.scenarios.split(",")})
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(data, indent=1, default=list) + "\n")
    args.out.with_suffix(".md").write_text(markdown(data))
    print(markdown(data))


if __name__ == "__main__":
    main()
