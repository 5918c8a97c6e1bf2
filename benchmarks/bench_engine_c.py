"""Benchmark (issue 42 items 1, 2, 6): the C build of the engine against the numba build, per
method and scenario, in one run; the compile cost of each; the machine's load with every row.

Run from the repository root (about 5 minutes on 2 cores)::

    python benchmarks/bench_engine_c.py [--runs 3] [--duration 10]

Scenarios (the ``wang2021`` preset, table at mid-screw, from rest; those of
``bench_engine.py``): ``cdfs_2p0`` (smooth), ``cdfs_1p2`` (creeping, stick-slip throughout),
``ddfs_0p5_vn16`` (smooth, stiff screw bristle), and ``cdfs_gms`` (the CDFS with the GMS guide
of ``examples/gms_guide.toml``).  Methods: every one of ``SolverOptions`` at its defaults; the
fixed-step ones at a 10-µs step over a tenth of the duration.

Per row and build, medians of ``--runs`` rounds (the builds interleaved, each after a warm-up
that compiles or loads it): the CPU time of the whole ``simulate`` call, the CPU time inside the
driver calls, the right-hand-side evaluations and evaluations per CPU second of the driver; the
ratio numba/C of both times; and the largest difference of any signal between the builds,
relative to that signal's largest magnitude (0: bit-identical), with the solver statistics
compared.

Compile cost: fresh processes with empty caches (``FEEDDRIVE_C_CACHE``, ``NUMBA_CACHE_DIR`` in
a temporary folder), each importing feeddrive and running 10 ms of the CDFS with the default
method under one build, then the same again with the caches filled; CPU seconds of the
process and its children (the C compiler).

Writes ``benchmarks/results/bench_engine_c.json`` and ``bench_engine_c.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

import feeddrive as fd  # noqa: E402

# the processor's model name beside the ratios: they differ by CPU (2026-12-07: 1.1–1.7× on
# "AMD EPYC" where 1.7–3.3× had been measured on "Intel Xeon"; benchmarks/README.md)
from bench_engine import machine  # noqa: E402
from feeddrive.engine.options import METHODS  # noqa: E402
from feeddrive.model.reference import ConstantSpeed  # noqa: E402
from feeddrive.parameters.toml_io import load  # noqa: E402
from feeddrive.solvers import builds  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
# name -> (parameters, drive, table speed, nut speed)
SCENARIOS = {
    "cdfs_2p0": ("wang2021", "cdfs", 2.0e-3, 0.0),
    "cdfs_1p2": ("wang2021", "cdfs", 1.2e-3, 0.0),
    "ddfs_0p5_vn16": ("wang2021", "ddfs", 0.5e-3, 16e-3),
    "cdfs_gms": ("examples/gms_guide.toml", "cdfs", 2.0e-3, 0.0),
}
FIXED_STEP = 1e-5  # [s]

_DRIVER_CPU = [0.0]
_plain_driver = builds.driver


def _timed_driver(model: Any, use: str) -> Any:
    fn = _plain_driver(model, use)

    def call(*args: Any) -> Any:
        started = time.process_time()
        try:
            return fn(*args)
        finally:
            _DRIVER_CPU[0] += time.process_time() - started

    return call


builds.driver = _timed_driver  # the CPU time inside the drivers (both builds)


def parameters(source: str) -> Any:
    return load(ROOT / source) if source.endswith(".toml") else fd.preset(source)


def one_run(name: str, method: str, duration: float, engine: str) -> tuple[float, float, Any]:
    source, drive, v_t, v_n = SCENARIOS[name]
    os.environ["FEEDDRIVE_ENGINE"] = engine
    system = fd.DriveSystem(parameters(source), drive, 0.4)
    fixed = method.endswith("-fixed")
    options = fd.SolverOptions(method=method, **({"fixed_step": FIXED_STEP} if fixed else {}))
    _DRIVER_CPU[0] = 0.0
    started = time.process_time()
    result = fd.simulate(system, ConstantSpeed(v_t, v_n), duration / 10 if fixed else duration,
                         options=options)
    whole = time.process_time() - started
    assert result.solver_stats["engine"] == engine
    return whole, _DRIVER_CPU[0], result


def difference(a: Any, b: Any) -> float:
    if a.time.shape != b.time.shape or np.any(a.time != b.time):
        return float("inf")
    worst = 0.0
    for name in a.signal_names():
        x, y = np.asarray(a[name], dtype=float), np.asarray(b[name], dtype=float)
        scale = float(np.max(np.abs(x))) if x.size else 0.0
        d = float(np.max(np.abs(x - y))) if x.size else 0.0
        worst = max(worst, d / scale if scale > 0 else d)
    return worst


def row(name: str, method: str, duration: float, runs: int) -> dict[str, Any]:
    load_before = os.getloadavg()
    out: dict[str, Any] = {"scenario": name, "method": method}
    last: dict[str, Any] = {}
    times: dict[str, list[tuple[float, float]]] = {"numba": [], "c": []}
    for engine in times:  # warm-up: compile or load
        one_run(name, method, duration, engine)
    for _ in range(runs):
        for engine in times:
            whole, inside, result = one_run(name, method, duration, engine)
            times[engine].append((whole, inside))
            last[engine] = result
    for engine, pairs in times.items():
        whole = statistics.median(p[0] for p in pairs)
        inside = statistics.median(p[1] for p in pairs)
        evals = int(last[engine].solver_stats["rhs_evaluations"])
        out[engine] = {"whole_cpu_s": whole, "driver_cpu_s": inside, "rhs_evaluations": evals,
                       "evaluations_per_cpu_s": evals / inside if inside > 0 else None}
    out["numba_over_c_whole"] = out["numba"]["whole_cpu_s"] / out["c"]["whole_cpu_s"]
    out["numba_over_c_driver"] = out["numba"]["driver_cpu_s"] / out["c"]["driver_cpu_s"]
    out["largest_relative_difference"] = difference(last["numba"], last["c"])
    untimed = [{k: v for k, v in last[e].solver_stats.items() if k not in ("wall_time_s", "engine")}
               for e in ("numba", "c")]
    out["solver_stats_equal"] = untimed[0] == untimed[1]
    out["verdict_equal"] = last["numba"].summary().get("verdict") == \
        last["c"].summary().get("verdict")
    out["load_before"], out["load_after"] = load_before, os.getloadavg()
    return out


_COLD = """
import resource, time, os
t0 = time.process_time()
import feeddrive as fd
from feeddrive.model.reference import ConstantSpeed
r = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4), ConstantSpeed(2e-3), 0.01)
assert r.solver_stats["engine"] == os.environ["FEEDDRIVE_ENGINE"]
ch = resource.getrusage(resource.RUSAGE_CHILDREN)
print(time.process_time() - t0, ch.ru_utime + ch.ru_stime)
"""


def compile_cost() -> dict[str, Any]:
    out: dict[str, Any] = {}
    for engine in ("c", "numba"):
        with tempfile.TemporaryDirectory() as tmp:
            env = dict(os.environ, FEEDDRIVE_ENGINE=engine, FEEDDRIVE_C_CACHE=f"{tmp}/c",
                       NUMBA_CACHE_DIR=f"{tmp}/numba")
            for state in ("cold", "warm"):
                load = os.getloadavg()
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                done = subprocess.run([sys.executable, "-c", _COLD], env=env, cwd=ROOT,
                                      capture_output=True, text=True, check=True)
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
                own, children = (float(v) for v in done.stdout.split())
                tree = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
                out[f"{engine}_{state}"] = {"process_cpu_s": own, "compiler_cpu_s": children,
                                            "tree_cpu_s": tree, "load_before": load,
                                            "load_after": os.getloadavg()}
                print(engine, state, out[f"{engine}_{state}"], flush=True)
    return out


def markdown(data: dict[str, Any]) -> str:
    lines = [f"# C build vs numba build ({data['machine']}, {data['date']})", "",
             f"Duration {data['duration_s']} s (fixed-step methods a tenth, step "
             f"{FIXED_STEP:g} s); medians of {data['runs']} rounds; CPU seconds.", "",
             "| scenario | method | numba whole | C whole | ×whole | numba driver | C driver | "
             "×driver | C evals/s | largest diff | stats equal | load |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in data["rows"]:
        eps = r["c"]["evaluations_per_cpu_s"]
        lines.append(
            f"| {r['scenario']} | {r['method']} | {r['numba']['whole_cpu_s']:.4f} | "
            f"{r['c']['whole_cpu_s']:.4f} | {r['numba_over_c_whole']:.2f} | "
            f"{r['numba']['driver_cpu_s']:.4f} | {r['c']['driver_cpu_s']:.4f} | "
            f"{r['numba_over_c_driver']:.2f} | {eps:.3g} | "
            f"{r['largest_relative_difference']:.3g} | {r['solver_stats_equal']} | "
            f"{r['load_before'][0]:.1f}→{r['load_after'][0]:.1f} |")
    lines += ["", "Compile cost (fresh process, empty caches, then filled; CPU s):", "",
              "| build | cache | process | compiler (children) | load |", "|---|---|---|---|---|"]
    for key, v in data["compile"].items():
        engine, state = key.split("_")
        lines.append(f"| {engine} | {state} | {v['process_cpu_s']:.2f} | "
                     f"{v['compiler_cpu_s']:.2f} | {v['load_before'][0]:.1f}→"
                     f"{v['load_after'][0]:.1f} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--duration", type=float, default=10.0)
    parser.add_argument("--scenarios", default=",".join(SCENARIOS))
    parser.add_argument("--methods", default=",".join(METHODS))
    args = parser.parse_args()
    data: dict[str, Any] = {
        "machine": f"{platform.machine()} {platform.system()}, {machine()['cpu']}, "
                   f"{os.cpu_count()} cores, Python {platform.python_version()}",
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "duration_s": args.duration, "runs": args.runs, "rows": []}
    data["compile"] = compile_cost()
    for name in args.scenarios.split(","):
        for method in args.methods.split(","):
            r = row(name, method, args.duration, args.runs)
            data["rows"].append(r)
            print(f"{name:14s} {method:13s} whole ×{r['numba_over_c_whole']:.2f} driver "
                  f"×{r['numba_over_c_driver']:.2f} diff {r['largest_relative_difference']:.3g}"
                  f" stats {r['solver_stats_equal']} load {r['load_before'][0]:.1f}", flush=True)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "bench_engine_c.json").write_text(json.dumps(data, indent=1) + "\n")
    (RESULTS / "bench_engine_c.md").write_text(markdown(data))


if __name__ == "__main__":
    main()
