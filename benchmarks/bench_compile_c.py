"""Benchmark (issue 42 item 6, compile cost): what a model costs to build in C with the system
compiler against numba's first compile of the same model, per registered topology, as ratios
taken in one run.

    python benchmarks/bench_compile_c.py [--rounds 1]

Each topology (every ``drive_names()``, with its ``example_preset``, the table at 0.4 m) runs
in a fresh process with empty caches (``NUMBA_CACHE_DIR`` and ``FEEDDRIVE_C_CACHE`` new empty
folders); after the imports and the model's assembly it measures, in this order:

* ``c_model_s``: the model's C with the solver blocks (``c_model_source`` +
  ``c_solver_source``) built into the compiled-object cache (``c_cache.cached_library``,
  ``-std=c99 -O2 -ffp-contract=off -fPIC -shared``) — CPU s (user + sys) of the compiler's
  whole process tree (``RUSAGE_CHILDREN``: cc1, as, collect2, ld); the compiler's
  ``--version`` asked before, its cost apart (``c_identity_s``);
* ``c_hit_s``: the same call again, from the cache, with the library loaded (this process's
  CPU s);
* ``c_fmu_s``: the FMU's whole translation unit (model, the DOPRI5 driver translated from
  ``solvers/driver.py``, the FMI 2 co-simulation wrapper) with the FMU's flags
  (``fmu.build.compile_library``), compiler tree CPU s;
* ``numba_model_s``: numba's first compile of the model's own functions — the generated
  module's ``rhs`` and ``sample_update`` with every kernel they call — by one call of each
  (this process's CPU s: numba compiles in-process);
* ``numba_first_run_s``: then a first 0.2-s ``simulate`` at 2 mm/s (the DDFS: 0.5 mm/s, nut
  16 mm/s) by the default method: numba's compile of the integrators (the shared drivers),
  with the run itself, this process's CPU s.

Ratios: ``numba_model_s / c_model_s`` (the model's functions, both builds) and
``(numba_model_s + numba_first_run_s) / c_fmu_s`` (model and integrator, both builds).  The
load average is recorded before and after each process.  Writes
``benchmarks/results/bench_compile_c.json``.
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
RESULTS = ROOT / "benchmarks" / "results" / "bench_compile_c.json"

WORKER = r'''
import json, resource, sys, tempfile, time
from pathlib import Path
import numpy as np
import feeddrive as fd
from feeddrive.backends import c_cache
from feeddrive.backends.c_backend import c_model_source, c_solver_source, load_cached
from feeddrive.fmu.build import compile_library, fmu_source
from feeddrive.fmu.description import variables
from feeddrive.fmu.model import build
from feeddrive.model.mechanisms import mechanism

def children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime

drive = sys.argv[1]
nut = 16e-3 if drive == "ddfs" else 0.0
table = 0.5e-3 if drive == "ddfs" else 2e-3
params = fd.preset(mechanism(drive).example_preset)
system = fd.DriveSystem(params, drive, 0.4)
model = system.model(fd.ConstantSpeed(table, nut))
fm = build(params, drive, 0.4)
text = c_model_source(model) + c_solver_source()
fmu = fmu_source(fm, variables(fm, "cs"), fmi=2, kind="cs",
                 token="{00000000-0000-0000-0000-000000000042}")
out = {"drive": drive, "preset": params.name, "states": len(model.states),
       "c_model_chars": len(text), "c_fmu_chars": len(fmu)}
c0 = children()
c_cache.compiler_identity(tuple(c_cache.find_compiler()))
c1 = children()
c_cache.cached_library(text)
c2 = children()
assert c_cache.STATS == {"compiles": 1, "hits": 0}, c_cache.STATS
p0 = time.process_time()
load_cached(text)
p1 = time.process_time()
assert c_cache.STATS["hits"] == 1
with tempfile.TemporaryDirectory() as tmp:
    compile_library(fmu, 2, Path(tmp), "bench")
c3 = children()
out.update(c_identity_s=c1 - c0, c_model_s=c2 - c1, c_hit_s=p1 - p0, c_fmu_s=c3 - c2)
n = len(model.states)
y, dy = np.zeros(n), np.empty(n)
held, aux = np.zeros(model.n_held), np.empty(len(model.aux))
p0 = time.process_time()
model.module.rhs(0.0, y, held, model.P, model.T, dy, aux)
model.module.sample_update(0.0, y, held, model.P, model.T, model.continuous_ticks())
p1 = time.process_time()
fd.simulate(system, fd.ConstantSpeed(table, nut), 0.2)
p2 = time.process_time()
out.update(numba_model_s=p1 - p0, numba_first_run_s=p2 - p1)
print(json.dumps(out))
'''


def run_drive(drive: str) -> dict:
    """One fresh process on empty caches: the measurements of one topology."""
    with tempfile.TemporaryDirectory() as numba_cache, tempfile.TemporaryDirectory() as c_dir:
        env = dict(os.environ, PYTHONPATH=str(ROOT / "src"), NUMBA_CACHE_DIR=numba_cache,
                   FEEDDRIVE_C_CACHE=c_dir)
        load = os.getloadavg()
        t0 = time.perf_counter()
        done = subprocess.run([sys.executable, "-c", WORKER, drive], env=env, check=True,
                              capture_output=True, text=True, cwd=tempfile.gettempdir())
        row = json.loads(done.stdout.strip().splitlines()[-1])
    row.update(wall_s=time.perf_counter() - t0, load_before=load, load_after=os.getloadavg())
    row["numba_model_over_c_model"] = row["numba_model_s"] / row["c_model_s"]
    row["numba_total_over_c_fmu"] = (row["numba_model_s"] + row["numba_first_run_s"]) / \
        row["c_fmu_s"]
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=1)
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT / "src"))
    from feeddrive.backends.c_cache import compiler_identity, find_compiler
    from feeddrive.model.mechanisms import drive_names

    rows = []
    for r in range(args.rounds):
        for drive in drive_names():
            row = dict(run_drive(drive), round=r + 1)
            rows.append(row)
            print(f"{drive:12s} C model+solver {row['c_model_s']:5.2f} s, FMU unit "
                  f"{row['c_fmu_s']:5.2f} s, hit {row['c_hit_s'] * 1e3:5.1f} ms | numba model "
                  f"{row['numba_model_s']:5.2f} s, first run {row['numba_first_run_s']:5.2f} s"
                  f" | ratios {row['numba_model_over_c_model']:5.1f}, "
                  f"{row['numba_total_over_c_fmu']:5.1f} | load {row['load_before'][0]:.1f}"
                  f"→{row['load_after'][0]:.1f}", flush=True)
    RESULTS.write_text(json.dumps({
        "benchmark": "python benchmarks/bench_compile_c.py", "rounds": args.rounds,
        "rows": rows, "compiler": compiler_identity(tuple(find_compiler())).splitlines()[:2],
        "machine": {"python": platform.python_version(), "cpus": os.cpu_count()},
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}, indent=1) + "\n")
    print(f"→ {RESULTS.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
