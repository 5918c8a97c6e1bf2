"""Benchmark: `feeddrive reproduce` wall time on an empty folder (issue 9 target ≤ 20 s on
2 cores; an earlier issue's ≤ 60 s) with the CPU time of each part, and a same-run
comparison with the plain scipy implementation.

Run from the repository root::

    python benchmarks/bench_reproduce.py

1. Runs ``feeddrive.reproduce.run`` on the ``wang2021`` preset into an empty folder (2
   workers, compiled code loaded from the numba cache after a warm-up call) and records the
   wall time, the CPU seconds of each part (summed over the workers' studies) and the number
   of trial simulations and simulated seconds it needed.
2. Times the same kind of trial with scipy ``solve_ivp(method="LSODA", rtol=1e-6)`` on the
   plain-Python model (``reference/scipy_model.py``): three representative 12-s trials of the
   study (CDFS creeping at 1.2 mm/s, CDFS smooth at 2.0 mm/s, DDFS at 1.0 mm/s with v_n =
   16 mm/s), and extrapolates to the study's simulated seconds, one process.
3. Prints and records the ratio (scipy estimate / feeddrive).

Writes ``benchmarks/results/bench_reproduce.json``.

``--profile DIR``: instead, run the whole study once into an empty folder with every task
of the pool profiled (cProfile per task, ``DIR/<n>.prof``) and counted: CPU and wall
seconds, simulated seconds and calls of the compiled integrators per task, written to
``DIR/tasks.json`` with a summary by part and the merged cProfile's top functions
(``DIR/top.txt``).  ``--out FOLDER`` keeps the reproduce output there (for
``benchmarks/diff_reproduce.py``).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.scipy_model import STATE_NAMES, ReferenceModel, tolerances  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.engine.simulate import DriveSystem, simulate  # noqa: E402
from feeddrive.model.reference import ConstantSpeed  # noqa: E402
from feeddrive.reproduce import run  # noqa: E402

PARTS = {"crit": "critical-speed searches (Table 3, Fig. 8, step-down)",
         "study": "model-reading study", "forced": "torque-ripple threshold searches",
         "compensation": "compensation study", "readingfig": "Figs. 7, 9-10 per reading",
         "fig6": "figure studies", "fig7": "figure studies", "figs9_10": "figure studies",
         "fig8_trace": "figure studies"}


def _label(fn: object, args: tuple) -> str:
    name = getattr(fn, "__name__", str(fn))
    if name == "_critical_job":
        _, drive, position, nut, _, start = args[0]
        return f"crit {drive} a={position:g} vn={1e3 * nut:g} {start}"
    if name == "run_variant":
        return f"study {args[0][0]} / {args[0][3]}"
    if name == "run" and isinstance(args[0], tuple):
        drive, vn, a, th = args[0]
        return f"forced {drive} vn={1e3 * vn:g} a={a:g} thresholds={len(th)}"
    if name == "reading_figures":
        return f"readingfig {args[0]}"
    return name


_PROFILE_DIR = "FEEDDRIVE_BENCH_PROFILE_DIR"
_PROFILE_CPROFILE = "FEEDDRIVE_BENCH_PROFILE_CPROFILE"
_COUNTERS: dict[str, float] = {}


def _count_integrations() -> None:
    """Wrap this process's integrators so that each task's simulated seconds, calls and
    CPU seconds inside them are counted (once per worker)."""
    from feeddrive.solvers import dopri5, switching

    if _COUNTERS:
        return
    _COUNTERS.update({"sim_s": 0.0, "calls": 0, "integrate_cpu": 0.0})

    def counted(original):  # type: ignore[no-untyped-def]
        def integrate(model, y0, t_end, out_every, base, *args, **kw):  # type: ignore
            began = time.process_time()
            try:
                return original(model, y0, t_end, out_every, base, *args, **kw)
            finally:
                _COUNTERS["integrate_cpu"] += time.process_time() - began
                _COUNTERS["sim_s"] += t_end - kw.get("start", 0) * base
                _COUNTERS["calls"] += 1
        return integrate

    switching.integrate = counted(switching.integrate)
    dopri5.integrate = counted(dopri5.integrate)


def _profiled_timed(fn, *args):  # type: ignore[no-untyped-def]
    """The pool's task wrapper in ``--profile`` (reproduce's ``runner._timed``): the task's
    CPU and wall seconds, its integrators' counts and (optionally) its cProfile, appended
    to ``tasks.jsonl`` of the folder named in the environment."""
    import cProfile

    _count_integrations()
    folder = Path(os.environ[_PROFILE_DIR])
    for k in _COUNTERS:
        _COUNTERS[k] = 0 if k == "calls" else 0.0
    prof = cProfile.Profile() if os.environ.get(_PROFILE_CPROFILE) == "1" else None
    began, wall = time.process_time(), time.perf_counter()
    if prof is not None:
        prof.enable()
    value = fn(*args)
    if prof is not None:
        prof.disable()
    cpu, wall = time.process_time() - began, time.perf_counter() - wall
    n = f"{os.getpid()}-{time.monotonic_ns()}"
    if prof is not None:
        prof.dump_stats(str(folder / f"{n}.prof"))
    with open(folder / "tasks.jsonl", "a") as fh:
        fh.write(json.dumps({"task": _label(fn, args), "cpu_s": cpu, "wall_s": wall,
                             "prof": f"{n}.prof", **_COUNTERS}) + "\n")
    return value, cpu


def profile(folder: Path, out: Path | None, use_cprofile: bool = True) -> None:
    """Run the study with every pool task profiled (see the module docstring).

    Parameters
    ----------
    folder : Path
        Where the per-task profiles and ``tasks.json`` go.
    out : Path or None
        The reproduce output folder (a temporary one when None).
    use_cprofile : bool, default True
        Profile each task with cProfile (its overhead inflates Python-heavy tasks several
        times: the CPU seconds of ``--no-cprofile`` are the ones to quote).
    """
    import pstats

    from feeddrive.reproduce import runner

    folder.mkdir(parents=True, exist_ok=True)
    # the pool's workers are spawned: they read the settings from the environment and count
    # in their own process (_profiled_timed, importable from this module as __mp_main__)
    os.environ[_PROFILE_DIR] = str(folder)
    os.environ[_PROFILE_CPROFILE] = "1" if use_cprofile else "0"
    runner._timed = _profiled_timed
    (folder / "tasks.jsonl").unlink(missing_ok=True)
    params = fd.preset("wang2021")
    simulate(DriveSystem(params, "ddfs", 0.4), ConstantSpeed(1e-3, 16e-3), 0.05)  # warm-up
    cpu0 = os.times()
    with tempfile.TemporaryDirectory() as tmp:
        target = out if out is not None else Path(tmp)
        started = time.perf_counter()
        run(params, target, workers=2, study=True)
        wall = time.perf_counter() - started
    cpu1 = os.times()
    tasks = [json.loads(line) for line in (folder / "tasks.jsonl").read_text().splitlines()]
    parts: dict[str, dict[str, float]] = {}
    for t in tasks:
        part = t["task"].split(" ")[0]
        agg = parts.setdefault(part, {"cpu_s": 0.0, "sim_s": 0.0, "integrate_cpu": 0.0,
                                      "tasks": 0})
        for k in ("cpu_s", "sim_s", "integrate_cpu"):
            agg[k] += t[k]
        agg["tasks"] += 1
    summary = {"wall_s": wall,
               "cpu_s_children": (cpu1.children_user + cpu1.children_system)
               - (cpu0.children_user + cpu0.children_system),
               "cpu_s_parent": (cpu1.user + cpu1.system) - (cpu0.user + cpu0.system),
               "cpu_s_tasks": sum(t["cpu_s"] for t in tasks),
               "sim_s_tasks": sum(t["sim_s"] for t in tasks),
               "load_average": os.getloadavg(), "parts": parts,
               "tasks": sorted(tasks, key=lambda t: -t["cpu_s"])}
    (folder / "tasks.json").write_text(json.dumps(summary, indent=1) + "\n")
    if use_cprofile:
        stats = pstats.Stats(*[str(folder / t["prof"]) for t in tasks])
        with open(folder / "top.txt", "w") as fh:
            stats.stream = fh  # type: ignore[attr-defined]
            stats.sort_stats("tottime").print_stats(40)
            stats.sort_stats("cumulative").print_stats(60)
    print(json.dumps({k: v for k, v in summary.items() if k != "tasks"}, indent=1))
    for t in summary["tasks"][:25]:
        print(f"{t['cpu_s']:7.2f} s CPU {t['wall_s']:7.2f} s wall {t['sim_s']:8.0f} sim-s "
              f"{t['integrate_cpu']:7.2f} s integrating  {t['task']}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", type=Path, metavar="DIR",
                        help="profile every task of the pool into DIR instead (see the module)")
    parser.add_argument("--no-cprofile", action="store_true",
                        help="with --profile: count CPU and calls only, no cProfile")
    parser.add_argument("--out", type=Path, metavar="FOLDER",
                        help="with --profile: keep the reproduce output in FOLDER")
    args = parser.parse_args()
    if args.out is not None and args.profile is None:
        parser.error("--out goes with --profile")
    if args.profile is not None:
        profile(args.profile, args.out, use_cprofile=not args.no_cprofile)
        return
    params = fd.preset("wang2021")
    simulate(DriveSystem(params, "ddfs", 0.4), ConstantSpeed(1e-3, 16e-3), 0.05)  # warm-up
    with tempfile.TemporaryDirectory() as tmp:
        started = time.perf_counter()
        results = run(params, Path(tmp), workers=2, study=True)
        wall = time.perf_counter() - started
    searches = list(results["critical"].values())
    sim_seconds = sum(s["simulated_time_s"] for s in searches)
    n_trials = sum(len(s["trials"]) for s in searches)
    # the study's searches are critical-speed searches of the same settings: use the mean
    # simulated time per search for them
    per_search = sim_seconds / len(searches)
    study_seconds = per_search * len(results["reading_study"])
    total_seconds = sim_seconds + study_seconds

    samples = [("cdfs", 1.2e-3, 0.0), ("cdfs", 2.0e-3, 0.0), ("ddfs", 1.0e-3, 16e-3)]
    rates = []
    for drive, v, vn in samples:
        model = ReferenceModel(params, drive, 0.4, ConstantSpeed(v, vn, 0.1))
        grid = np.arange(12001) * 1e-3
        t0 = time.perf_counter()
        sol = solve_ivp(model, (0.0, 12.0), np.zeros(len(STATE_NAMES)), method="LSODA",
                        rtol=1e-6, atol=tolerances(model.H), t_eval=grid)
        dt = time.perf_counter() - t0
        if sol.status != 0:
            raise RuntimeError(f"LSODA failed on {drive} {v}: {sol.message}")
        rates.append(dt / 12.0)
        print(f"scipy LSODA {drive} {v * 1e3:.1f} mm/s (v_n {vn * 1e3:g}): {dt:.2f} s per 12 s",
              flush=True)
    scipy_estimate = float(np.mean(rates)) * total_seconds
    parts: dict[str, float] = {}
    for name, seconds in results["cpu_seconds"].items():
        part = PARTS.get(name.split("-")[0], name)
        parts[part] = parts.get(part, 0.0) + seconds
    print("CPU seconds by part: " + ", ".join(f"{k} {v:.1f}" for k, v in parts.items()))
    out = {
        "machine": {"nproc": os.cpu_count(), "python": sys.version.split()[0]},
        "reproduce_wall_s": wall,
        "target_s": 20.0,
        "cpu_seconds_by_part": parts,
        "cpu_seconds_workers": sum(parts.values()),
        "searches": len(searches) + len(results["reading_study"]),
        "trials_in_paper_searches": n_trials,
        "simulated_seconds_estimate": total_seconds,
        "scipy_seconds_per_simulated_second": rates,
        "scipy_estimate_s_one_process": scipy_estimate,
        "ratio_scipy_over_feeddrive": scipy_estimate / wall,
    }
    print(json.dumps(out, indent=2))
    path = ROOT / "benchmarks" / "results" / "bench_reproduce.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
