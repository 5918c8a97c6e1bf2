"""Benchmark: the start-up of a short ``feeddrive simulate`` in a fresh process (issue 21 item 4).

Run from the repository root::

    python benchmarks/bench_startup.py [--runs 11] [--label after]

Target: a 1-s ``feeddrive simulate --drive cdfs --table-speed 2 --duration 1 --json`` in a
fresh process takes ≤ 1.0 s wall with the compile cache warm.  One warm-up run fills the cache
(and is not counted); then ``--runs`` fresh processes are started one after another and each is
timed: **wall** (from the start of the process to its exit) and **CPU** (user + system time
of the child, from ``getrusage(RUSAGE_CHILDREN)``).  Medians are reported, beside the
machine's load average before and after (the machine is shared: wall time grows with the
load, CPU time much less).

Python's bytecode cache is used as on a user's machine: ``PYTHONDONTWRITEBYTECODE`` is removed
from the children's environment (pip compiles an installed package's modules; an editable
install writes them at its first import), so the warm-up run writes what is missing; with
``--no-bytecode`` the variable is kept and every module of the package (and the generated
model module) is compiled from its source in every run, as in a session that sets it.

For scale, the same is measured for the floor every Python command pays: ``python -c pass``
and ``python -c "import numpy"`` (interleaved with the simulate runs, same load).

The command's JSON output must be the same in every run, byte for byte, except the solver's
own ``wall_time_s`` (a clock reading): checked here, and its digest recorded, so that a
change of start-up code that changed a result would show.

``--variant before=/path/to/old/src`` times another state of the package beside the installed
one (on ``PYTHONPATH``, so it needs no install of its own), interleaved run by run: a fair
before/after on a shared machine, whose load moves within minutes.

Writes ``benchmarks/results/bench_startup.json`` (one entry per ``--label``; earlier labels
are kept, so "before" and "after" sit side by side).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import platform
import re
import resource
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "bench_startup.json"

SIMULATE_ARGS = ["simulate", "--drive", "cdfs", "--table-speed", "2", "--duration", "1",
                 "--json"]


def _feeddrive_command() -> list[str]:
    """The installed ``feeddrive`` script beside this interpreter (what a user runs), else
    ``python -m feeddrive``."""
    script = Path(sys.executable).with_name("feeddrive")
    if script.exists():
        return [str(script)]
    found = shutil.which("feeddrive")
    return [found] if found else [sys.executable, "-m", "feeddrive"]


def fresh_process(cmd: list[str], env: dict[str, str] | None = None
                  ) -> tuple[float, float, subprocess.CompletedProcess[bytes]]:
    """Wall [s], CPU (user + system of the child) [s] and the finished process (its output
    captured) of one fresh process run from the repository root; a failure ends the
    benchmark with the end of its standard error (bench_nonumba.py uses it too)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, cwd=ROOT, check=False, env=env)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}): "
                         f"{proc.stderr.decode()[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, proc


def _normalised(out: bytes) -> bytes:
    """The JSON output without the solver's clock reading."""
    return re.sub(rb'"wall_time_s": [0-9.e+-]+', b'"wall_time_s": 0', out)


#: what the start-up work costs, piece by piece: CPU of a fresh process doing ``code`` minus
#: one doing ``base`` (the pieces overlap: scipy.signal imports scipy.stats, for one)
COMPONENTS: dict[str, tuple[str, str]] = {
    "numpy": ("pass", "import numpy"),
    "numba (import)": ("import numpy", "import numba"),
    "numba refresh (what a cache load did before it was skipped)": (
        "import numba", "import numba; from numba.core.registry import cpu_target; "
        "cpu_target.target_context.refresh()"),
    "typer": ("pass", "import typer"),
    "typer's pydantic adapters (parsing any option)": ("import typer",
                                                        "import typer, typer._adapters"),
    "rich.console": ("import typer", "import typer, rich.console"),
    "rich.progress": ("import typer, rich.console",
                      "import typer, rich.console, rich.progress"),
    "xarray + pandas": ("import numpy", "import numpy, xarray"),
    "scipy.signal": ("import numpy", "import numpy, scipy.signal"),
    "scipy.optimize": ("import numpy", "import numpy, scipy.optimize"),
    "scipy.linalg": ("import numpy", "import numpy, scipy.linalg"),
    "every command module (feeddrive.cli before)": (
        "import feeddrive.cli, feeddrive.cli.simulate_cmd",
        "import feeddrive.cli; feeddrive.cli.load_commands()"),
    "solver template sources, built (now read from the cache folder)": (
        "import numba, feeddrive.solvers.switching, feeddrive.solvers.dopri5, "
        "feeddrive.solvers.rodas4",
        "import numba, feeddrive.solvers.switching, feeddrive.solvers.dopri5, "
        "feeddrive.solvers.rodas4, feeddrive.solvers.steps; "
        "[m.template_sources() for m in (feeddrive.solvers.steps, feeddrive.solvers.rodas4, "
        "feeddrive.solvers.dopri5, feeddrive.solvers.switching)]"),
    "the simulate path's feeddrive modules (engine, model, solvers, analyses)": (
        "import numba, feeddrive.cli, feeddrive.cli.simulate_cmd",
        "import numba, feeddrive.cli, feeddrive.cli.simulate_cmd, feeddrive.engine.simulate, "
        "feeddrive.analysis.compensation, feeddrive.analysis.creep_window, "
        "feeddrive.analysis.tracking"),
}


def components(runs: int, env: dict[str, str]) -> dict[str, float]:
    """Median CPU [s] of each piece of :data:`COMPONENTS`, base and code interleaved."""
    out = {}
    for name, (base, code) in COMPONENTS.items():
        diffs = []
        for _ in range(runs):
            diffs.append(fresh_process([sys.executable, "-c", code], env)[1]
                         - fresh_process([sys.executable, "-c", base], env)[1])
        out[name] = round(statistics.median(diffs), 4)
        print(f"  {name:70s} {out[name]:.3f} s CPU")
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=11, help="fresh processes per command")
    parser.add_argument("--label", default="current", help="name of this measurement")
    parser.add_argument("--note", default="", help="what was measured (the code's state)")
    parser.add_argument("--no-bytecode", action="store_true",
                        help="keep PYTHONDONTWRITEBYTECODE (modules compiled in every run)")
    parser.add_argument("--components", action="store_true",
                        help="also time each piece of the start-up work (COMPONENTS)")
    parser.add_argument("--variant", action="append", default=[], metavar="NAME=SRC",
                        help="also time the package in folder SRC (e.g. an older commit's "
                        "src/, on PYTHONPATH), interleaved with the installed one; repeatable")
    args = parser.parse_args()
    env = dict(os.environ)
    if not args.no_bytecode:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
    bytecode = "PYTHONDONTWRITEBYTECODE" not in env
    variants: dict[str, dict[str, str]] = {}
    for spec in args.variant:
        name, _, src = spec.partition("=")
        variants[name] = dict(env, PYTHONPATH=str(Path(src).resolve()))
    variants["installed"] = env

    simulate = [*_feeddrive_command(), *SIMULATE_ARGS]
    floor = {"python -c pass": [sys.executable, "-c", "pass"],
             "python -c 'import numpy'": [sys.executable, "-c", "import numpy"]}
    for venv in variants.values():
        fresh_process(simulate, venv)  # warm-up: the compile caches filled, files in the page cache
    load_before = os.getloadavg()
    names = [f"simulate [{v}]" for v in variants] + list(floor)
    samples: dict[str, dict[str, list[float]]] = {
        name: {"wall_s": [], "cpu_s": []} for name in names}
    outputs: dict[str, set[bytes]] = {v: set() for v in variants}
    for _ in range(args.runs):  # interleaved: every command sees the same load
        for variant, venv in variants.items():
            wall, cpu, proc = fresh_process(simulate, venv)
            samples[f"simulate [{variant}]"]["wall_s"].append(wall)
            samples[f"simulate [{variant}]"]["cpu_s"].append(cpu)
            outputs[variant].add(_normalised(proc.stdout))
        for name, cmd in floor.items():
            wall, cpu, _ = fresh_process(cmd, env)
            samples[name]["wall_s"].append(wall)
            samples[name]["cpu_s"].append(cpu)
    parts = components(args.runs, env) if args.components else None
    load_after = os.getloadavg()
    if any(len(o) != 1 for o in outputs.values()):
        raise SystemExit("the JSON output differs between runs (beyond wall_time_s)")
    digests = {v: hashlib.sha256(next(iter(o))).hexdigest() for v, o in outputs.items()}
    entry = {
        "note": args.note,
        "recorded_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
        "machine": {"python": platform.python_version(), "cpus": os.cpu_count(),
                    "load_average_1min_before": round(load_before[0], 2),
                    "load_average_1min_after": round(load_after[0], 2)},
        "command": " ".join(["feeddrive", *SIMULATE_ARGS]),
        "runs": args.runs,
        "bytecode_cache": bytecode,
        "variants": {v: venv.get("PYTHONPATH", "(installed package)")
                     for v, venv in variants.items()},
        "output_sha256": digests,
        "same_output": len(set(digests.values())) == 1,
        "median": {name: {key: round(statistics.median(v), 4) for key, v in s.items()}
                   for name, s in samples.items()},
        "samples": {name: {key: [round(x, 4) for x in v] for key, v in s.items()}
                    for name, s in samples.items()},
    }
    if parts is not None:
        entry["component_cpu_s"] = parts
    results = json.loads(RESULTS.read_text()) if RESULTS.exists() else {}
    results[args.label] = entry
    RESULTS.write_text(json.dumps(results, indent=2) + "\n")
    print(f"{args.label}: load {load_before[0]:.2f} → {load_after[0]:.2f}, {args.runs} runs, "
          f"bytecode cache {'used' if bytecode else 'off'}")
    for name, med in entry["median"].items():
        print(f"  {name:28s} wall {med['wall_s']:.3f} s   CPU {med['cpu_s']:.3f} s")
    print(f"  output sha256 {', '.join(f'{v} {d[:16]}' for v, d in digests.items())} "
          f"(wall_time_s blanked): {'the same' if entry['same_output'] else 'DIFFERENT'}")


if __name__ == "__main__":
    main()
