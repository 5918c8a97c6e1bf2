"""Benchmark: `feeddrive reproduce` as a user runs it, for one or more source trees, the trees
alternated round by round; CPU seconds of the whole process tree (user + system of the
command and its workers) and wall seconds.

Run from the repository root::

    python benchmarks/bench_reproduce_trees.py TREE [TREE ...] [--rounds 3] [--cold]
        [--keep DIR] [--out FILE.json]

Each TREE is a checkout whose ``src`` is put first on ``PYTHONPATH`` (this venv's
dependencies serve every tree).  A warm run uses the user's compiled-object cache as it is
(run each tree once before: the first run of a new tree is a cold one); ``--cold`` gives
every run an empty ``FEEDDRIVE_C_CACHE`` of its own, so it compiles and translates what it
needs.  ``--keep DIR`` copies each tree's first output folder to ``DIR/<tree name>`` (for
``benchmarks/diff_reproduce.py``).  Prints one line per run and each tree's median; with
``--out`` writes them as JSON with the load average beside each run.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def one_run(tree: Path, cold: bool) -> dict[str, float]:
    """One ``python -m feeddrive reproduce`` of ``tree`` into a fresh folder."""
    out = Path(tempfile.mkdtemp(prefix="bench-reproduce-"))
    env = dict(os.environ, PYTHONPATH=str(tree / "src"))
    cache = None
    if cold:
        cache = tempfile.mkdtemp(prefix="bench-reproduce-cache-")
        env["FEEDDRIVE_C_CACHE"] = cache
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "feeddrive", "reproduce", "--out",
                           str(out / "out")], env=env, stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE, text=True, check=False)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{tree}: reproduce failed (status {done.returncode}):\n"
                         f"{done.stderr[-2000:]}")
    if cache is not None:
        shutil.rmtree(cache, ignore_errors=True)
    return {"cpu_s": (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime),
            "wall_s": wall, "load_average": os.getloadavg()[0], "folder": str(out / "out")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("trees", nargs="+", type=Path)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--cold", action="store_true")
    parser.add_argument("--keep", type=Path)
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    trees = [t.resolve() for t in args.trees]
    runs: dict[str, list[dict[str, float]]] = {str(t): [] for t in trees}
    for r in range(args.rounds):
        for tree in trees if r % 2 == 0 else trees[::-1]:
            got = one_run(tree, args.cold)
            folder = Path(str(got.pop("folder")))
            if args.keep is not None and r == 0:
                shutil.copytree(folder, args.keep / tree.name, dirs_exist_ok=True)
            shutil.rmtree(folder.parent, ignore_errors=True)
            runs[str(tree)].append(got)
            print(f"round {r} {tree}: {got['cpu_s']:.1f} CPU s, {got['wall_s']:.1f} s wall, "
                  f"load {got['load_average']:.2f}", flush=True)
    summary = {}
    for tree, got in runs.items():
        cpu = sorted(g["cpu_s"] for g in got)
        summary[tree] = {"median_cpu_s": cpu[len(cpu) // 2], "runs": got}
        print(f"{tree}: median {cpu[len(cpu) // 2]:.1f} CPU s of {[round(c, 1) for c in cpu]}")
    if args.out is not None:
        args.out.write_text(json.dumps({"cold": args.cold, "trees": summary}, indent=1) + "\n",
                            encoding="utf-8")


if __name__ == "__main__":
    main()
