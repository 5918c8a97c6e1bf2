"""Benchmark (issues 35 item 4, 42): what a RODAS4 and a RODAS5P step cost against a DOPRI5
step, and what the cost-aware switch back to DOPRI5 (``feeddrive.solvers.driver.RODAS4_COST``,
``RODAS5P_COST``) saves.

Run from the repository root::

    python benchmarks/bench_switch_cost.py [--runs 3]

1. Per scenario and build (C, and numba when it is installed): CPU seconds per attempted step
   (accepted + rejected) of ``rodas4``, of RODAS5P throughout (the driver's mode
   ``MODE_RODAS4 + ROSENBROCK_5``, no method name of its own) and of ``dopri5-dense`` run alone
   at the defaults, and their ratios — the numbers ``RODAS4_COST`` and ``RODAS5P_COST`` stand
   for.
2. ``modal`` with RODAS4 steps and ``RODAS4_COST`` = 1 (the switch back only where DOPRI5 is
   stable at RODAS4's step: the rule before 2026-12-05), 2, 3, 4 and the shipped value, and
   with RODAS5P steps and ``RODAS5P_COST`` = 3, 5, 8, 10 and the shipped value (how much the
   choice matters): CPU per run, steps, Rosenbrock steps, right-hand-side calls; C build.
   Each setting runs in a fresh process (the C text carries the constant's value, so each has
   its own compiled library).

Scenarios: the ``bench_engine`` ones (``wang2021`` CDFS 2.0 mm/s; DDFS 0.5 mm/s with the hollow
motor at 16 mm/s), the torque-ripple DDFS of ``reproduce``'s forced study (``wang2021-ripple``,
1 mm/s, hollow motor 30 mm/s: its steps are held by the ripple, not by stiffness) and the GMS
guide (``examples/gms_guide.toml``, CDFS 2 mm/s).  Medians of ``--runs`` rounds after a warm-up
call; the load average is recorded beside the figures.  Writes
``benchmarks/results/bench_switch_cost.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# name -> (parameter set, drive, table speed [m/s], nut speed [m/s], simulated time [s])
SCENARIOS = {
    "cdfs_2p0": ("wang2021", "cdfs", 2.0e-3, 0.0, 10.0),
    "cdfs_2p0_100s": ("wang2021", "cdfs", 2.0e-3, 0.0, 100.0),
    "ddfs_0p5_vn16": ("wang2021", "ddfs", 0.5e-3, 16e-3, 10.0),
    "ddfs_0p5_vn16_100s": ("wang2021", "ddfs", 0.5e-3, 16e-3, 100.0),
    "ripple_ddfs_1p0_vn30": ("wang2021-ripple", "ddfs", 1.0e-3, 30e-3, 10.0),
    "gms_cdfs_2p0": ("examples/gms_guide.toml", "cdfs", 2.0e-3, 0.0, 10.0),
}

CHILD = r"""
import json, statistics, sys, time
import feeddrive as fd
from feeddrive.solvers import driver, switching
constants, runs, spec = json.loads(sys.argv[1]), int(sys.argv[2]), json.loads(sys.argv[3])
for name, value in constants.items():  # before the first build: the driver reads switching's
    setattr(driver, name, value)
    setattr(switching, name, value)
from feeddrive.engine import options as opts
from feeddrive.engine.simulate import DriveSystem, simulate
from feeddrive.model.reference import ConstantSpeed
# "rodas5p": RODAS5P throughout, run as the method rodas4 with the driver's mode moved
opts.DENSE_MODES["rodas5p"] = (switching.MODE_RODAS4 + switching.ROSENBROCK_5, 1)
opts.METHODS = (*opts.METHODS, "rodas5p")
out = {}
for name, (source, drive, vt, vn, duration) in spec["scenarios"].items():
    params = fd.load(source) if source.endswith(".toml") else fd.preset(source)
    system = DriveSystem(params, drive, 0.4)
    profile = ConstantSpeed(vt, vn)
    for method in spec["methods"]:
        options = fd.SolverOptions(method=method, rosenbrock=spec["rosenbrock"])
        r = simulate(system, profile, duration, options=options)
        cpu = []
        for _ in range(runs):
            t0 = time.process_time()
            r = simulate(system, profile, duration, options=options)
            cpu.append(time.process_time() - t0)
        s = r.solver_stats
        out[f"{name}/{method}"] = {
            "cpu_s": statistics.median(cpu), "steps": s["steps"],
            "rejected": s["rejected_steps"], "rhs": s["rhs_evaluations"],
            "rosenbrock_steps": s.get("rosenbrock_steps", 0), "engine": s["engine"]}
print(json.dumps(out))
"""


def child(constants: dict, runs: int, methods: list[str], build: str,
          rosenbrock: str = "rodas4") -> dict:
    spec = {"scenarios": SCENARIOS, "methods": methods, "rosenbrock": rosenbrock}
    # an empty C cache of its own: the translated driver is cached by the hash of the
    # sources, which a constant set at run time does not change
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, FEEDDRIVE_ENGINE=build, FEEDDRIVE_C_CACHE=cache)
        done = subprocess.run([sys.executable, "-c", CHILD, json.dumps(constants), str(runs),
                               json.dumps(spec)], cwd=ROOT, env=env, capture_output=True,
                              text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args()
    sys.path.insert(0, str(ROOT / "src"))
    from feeddrive.solvers import driver
    try:
        import numba  # noqa: F401
        builds = ["c", "numba"]
    except ImportError:
        builds = ["c"]
    load0 = os.getloadavg()[0]
    record: dict = {"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
                    "runs": args.runs, "shipped": driver.RODAS4_COST,
                    "shipped_rodas5p": driver.RODAS5P_COST,
                    "per_step": {}, "modal": {}}
    for build in builds:
        rows = child({}, args.runs, ["rodas4", "rodas5p", "dopri5-dense"], build)
        for name in SCENARIOS:
            r4, r5, dp = (rows[f"{name}/{m}"] for m in ("rodas4", "rodas5p", "dopri5-dense"))
            per_r4 = r4["cpu_s"] / (r4["steps"] + r4["rejected"])
            per_r5 = r5["cpu_s"] / (r5["steps"] + r5["rejected"])
            per_dp = dp["cpu_s"] / (dp["steps"] + dp["rejected"])
            record["per_step"][f"{build}/{name}"] = {
                "rodas4_us": 1e6 * per_r4, "rodas5p_us": 1e6 * per_r5, "dopri5_us": 1e6 * per_dp,
                "ratio": per_r4 / per_dp, "ratio_rodas5p": per_r5 / per_dp,
                "engine": r4["engine"]}
        if build != "c":
            continue  # numba's cache does not see the constant change (its text names it)
        settings = [{"RODAS4_COST": c} for c in sorted({1.0, 2.0, 3.0, 4.0, driver.RODAS4_COST})]
        for constants in settings:
            rows = child(constants, args.runs, ["modal"], build)
            label = ",".join(f"{k}={v:g}" for k, v in constants.items())
            for name in SCENARIOS:
                record["modal"][f"{build}/{name}/{label}"] = rows[f"{name}/modal"]
        for constants in [{"RODAS5P_COST": c}
                          for c in sorted({3.0, 5.0, 8.0, 10.0, driver.RODAS5P_COST})]:
            rows = child(constants, args.runs, ["modal"], build, "rodas5p")
            label = ",".join(f"{k}={v:g}" for k, v in constants.items())
            for name in SCENARIOS:
                record["modal"][f"{build}/{name}/rodas5p,{label}"] = rows[f"{name}/modal"]
    record["load"] = [load0, os.getloadavg()[0]]
    out = ROOT / "benchmarks" / "results"
    (out / "bench_switch_cost.json").write_text(json.dumps(record, indent=1) + "\n",
                                                encoding="utf-8")
    lines = [f"# RODAS4 and RODAS5P steps against DOPRI5 step, and the cost-aware switch "
             f"({record['date']}, "
             f"load {record['load'][0]:.1f} → {record['load'][1]:.1f} on 2 CPUs)", "",
             "10 s simulated per run (100 s where the name says so), default settings, "
             f"medians of {args.runs} rounds, CPU seconds.", "",
             "| build / scenario | RODAS4 µs/step | RODAS5P µs/step | DOPRI5 µs/step | "
             "ratio RODAS4 | ratio RODAS5P |",
             "| --- | ---: | ---: | ---: | ---: | ---: |"]
    for key, v in record["per_step"].items():
        lines.append(f"| {key} | {v['rodas4_us']:.2f} | {v['rodas5p_us']:.2f} | "
                     f"{v['dopri5_us']:.2f} | {v['ratio']:.2f} | {v['ratio_rodas5p']:.2f} |")
    lines += ["", "`modal` with RODAS4 steps and RODAS4_COST = 1 (the rule before), 2, 3, 4 and "
              f"{driver.RODAS4_COST:g} (shipped); with RODAS5P steps and RODAS5P_COST = 3, 5, "
              f"8, 10 and {driver.RODAS5P_COST:g} (shipped):", "",
              "| build / scenario / setting | CPU ms | steps | Rosenbrock steps | RHS calls |",
              "| --- | ---: | ---: | ---: | ---: |"]
    for key, v in record["modal"].items():
        lines.append(f"| {key} | {1e3 * v['cpu_s']:.2f} | {v['steps']} | "
                     f"{v['rosenbrock_steps']} | {v['rhs']} |")
    (out / "bench_switch_cost.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
