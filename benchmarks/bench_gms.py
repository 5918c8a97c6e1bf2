"""Benchmark (issue 42 item 4): what a GMS guide costs against the LuGre guide, and why.

Run from the repository root (about two minutes on 2 cores)::

    python benchmarks/bench_gms.py [--runs 3]

The run: the CDFS of ``wang2021`` (table at mid-screw, 0.1-s start ramp) following 2 mm/s for
10 s, default settings (``SolverOptions()``: ``modal``), ``simulate`` as a user calls it.  The
guide's friction is the preset's LuGre law, or GMS (Al-Bender, Lampaert & Swevers 2005) with
N = 1, 4, 16, 64 elements: N = 4 is ``examples/gms_guide.toml``; the others keep its Stribeck
branches and attraction and split the same total stiffness (the LuGre σ0, 4.38e5 N/m) into N
elements with stiffness ∝ N + 1 − i and weight ∝ i (i = 1 … N; the example's own shape,
stiff elements light).  For information the same runs with ``method="auto"`` (no modal cap).

The independent check: the same two runs (LuGre guide, the 4-element GMS guide) by scipy's
``solve_ivp`` with LSODA, RK45 and Radau on the plain-Python model of ``reference/``
(``reference.scipy_model.ReferenceModel``, rtol 1e-6, its absolute tolerances, the settings of
``bench_engine.py``'s baselines): what the GMS guide costs an integrator feeddrive did not
make, as CPU and right-hand-side ratios to its own LuGre run.

Per row: CPU seconds of the 10-s run (``time.process_time``, median of ``--runs``, every
case of a round run in turn after a warm-up), its ratio to the LuGre run of the same method
in the same process, the solver counts, and the cause — the table mode's eigenvalue (the
complex pair between 500 and 5000 rad/s of the run's Jacobian at its end state, central
differences of the model's compiled right-hand side), its damping ratio ζ, and the modal
step cap h = ``H_LAMBDA``/|λ| it sets when ζ < ``ZETA_LIGHT``.  The load average before and
after is recorded (the machine is shared).

Writes ``benchmarks/results/bench_gms.json`` and ``benchmarks/results/bench_gms.md``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.scipy_model import ReferenceModel  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.engine.simulate import Simulation  # noqa: E402
from feeddrive.solvers.modes import H_LAMBDA, ZETA_LIGHT  # noqa: E402

SPEED = 2e-3  # [m/s]
DURATION = 10.0  # [s]
ELEMENTS = (1, 4, 16, 64)
METHODS = ("modal", "auto")
SCIPY_METHODS = ("LSODA", "RK45", "Radau")
SCIPY_GUIDES = ("lugre", "gms_4")
COUNTS = ("steps", "rejected_steps", "rhs_evaluations", "jacobians", "rosenbrock_steps",
          "method_switches", "eigen_analyses", "switch_crossings")


def gms_parameters(n: int) -> fd.DriveParameters:
    """The GMS-guide set with ``n`` elements (module docstring); the example itself at 4."""
    example = fd.load(ROOT / "examples" / "gms_guide.toml")
    if n == 4:
        return example
    total = sum(example.friction.guide.element_stiffness)
    i = np.arange(1, n + 1, dtype=float)
    stiffness = total * (n + 1 - i) / np.sum(n + 1 - i)
    weight = i / np.sum(i)
    weight[-1] = 1.0 - float(np.sum(weight[:-1]))  # the weights sum to 1 exactly
    guide = example.friction.guide.with_values(element_stiffness=tuple(stiffness.tolist()),
                                               element_weight=tuple(weight.tolist()))
    return example.replace_path("friction.guide", guide)


def cases() -> dict[str, fd.DriveParameters]:
    out = {"lugre": fd.preset("wang2021")}
    out.update({f"gms_{n}": gms_parameters(n) for n in ELEMENTS})
    return out


def table_mode(params: fd.DriveParameters, result: fd.Result) -> dict[str, float]:
    """The table mode at the run's end state (module docstring)."""
    profile = fd.ConstantSpeed(SPEED)
    sim = Simulation(fd.DriveSystem(params, "cdfs", 0.4), profile)
    model = sim.model
    names = model.state_names
    n = len(names)
    y = np.array([float(result[name][-1]) for name in names])
    rates = model.module.compiled("_ev_rates")
    held, aux = np.zeros(model.n_held), np.empty(len(model.aux))
    P = np.ascontiguousarray(sim.P, dtype=float)
    T = np.ascontiguousarray(model.T, dtype=float)

    def f(state: np.ndarray) -> np.ndarray:
        dy = np.empty(n)
        rates(DURATION, np.ascontiguousarray(state), held, P, T, dy, aux)
        return dy

    J = np.empty((n, n))
    for j in range(n):
        d = 1e-7 * max(abs(y[j]), 1e3 * float(sim.atol[j]))
        up, down = y.copy(), y.copy()
        up[j] += d
        down[j] -= d
        J[:, j] = (f(up) - f(down)) / (2.0 * d)
    ev = np.linalg.eigvals(J)
    pair = ev[(ev.imag > 500.0) & (ev.imag < 5000.0)]
    lam = complex(pair[np.argmin(np.abs(pair))]) if pair.size else complex(math.nan)
    zeta = -lam.real / abs(lam)
    return {"table_mode_real_per_s": lam.real, "table_mode_imag_rad_per_s": lam.imag,
            "table_mode_zeta": zeta,
            "modal_cap_ms": 1e3 * H_LAMBDA / abs(lam) if zeta < ZETA_LIGHT else math.inf,
            "fastest_real_eigenvalue_per_s": float(min(ev.real))}


def scipy_rows(params: dict[str, fd.DriveParameters], runs: int) -> list[dict[str, Any]]:
    """The independent check of the module docstring: per scipy method and guide, the median
    CPU s of ``runs`` 10-s runs, the counts, and the ratios to the LuGre run."""
    profile = fd.ConstantSpeed(SPEED)
    cpu: dict[tuple[str, str], list[float]] = {}
    counts: dict[tuple[str, str], tuple[int, int]] = {}
    for _ in range(runs):
        for method in SCIPY_METHODS:
            for name in SCIPY_GUIDES:
                ref = ReferenceModel(params[name], "cdfs", 0.4, profile)
                t0 = time.process_time()
                sol = solve_ivp(ref, (0.0, DURATION), np.zeros(ref.n_state), method=method,
                                rtol=1e-6, atol=ref.tolerances())
                cpu.setdefault((method, name), []).append(time.process_time() - t0)
                if sol.status != 0:
                    raise RuntimeError(f"{method} on {name}: {sol.message}")
                counts[(method, name)] = (int(sol.nfev), len(sol.t) - 1)
    rows = []
    for method in SCIPY_METHODS:
        base = float(np.median(cpu[(method, "lugre")]))
        for name in SCIPY_GUIDES:
            t = float(np.median(cpu[(method, name)]))
            nfev, steps = counts[(method, name)]
            rows.append({"method": method, "guide": name, "cpu_s": round(t, 4),
                         "cpu_ratio_to_lugre": round(t / base, 2), "rhs_evaluations": nfev,
                         "rhs_ratio_to_lugre": round(nfev / counts[(method, "lugre")][0], 2),
                         "steps": steps})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    params = cases()
    systems = {name: fd.DriveSystem(p, "cdfs", 0.4) for name, p in params.items()}
    profile = fd.ConstantSpeed(SPEED)
    load_before = os.getloadavg()
    cpu: dict[tuple[str, str], list[float]] = {}
    last: dict[tuple[str, str], fd.Result] = {}
    for method in METHODS:
        options = fd.SolverOptions(method=method)
        for system in systems.values():  # warm-up: compile or load the cache
            fd.simulate(system, profile, 0.05, options=options)
        for _ in range(args.runs):
            for name, system in systems.items():
                t0 = time.process_time()
                result = fd.simulate(system, profile, DURATION, options=options)
                cpu.setdefault((method, name), []).append(time.process_time() - t0)
                last[(method, name)] = result
    independent = scipy_rows(params, args.runs)
    load_after = os.getloadavg()
    modes = {name: table_mode(params[name], last[("modal", name)]) for name in params}
    rows = []
    for method in METHODS:
        base = float(np.median(cpu[(method, "lugre")]))
        base_rhs = last[(method, "lugre")].solver_stats["rhs_evaluations"]
        for name in params:
            stats = last[(method, name)].solver_stats
            t = float(np.median(cpu[(method, name)]))
            rows.append({"method": method, "guide": name,
                         "elements": 0 if name == "lugre" else int(name.split("_")[1]),
                         "states": len(last[(method, name)].dataset.data_vars),
                         "cpu_s": round(t, 5), "cpu_ratio_to_lugre": round(t / base, 2),
                         "rhs_ratio_to_lugre": round(stats["rhs_evaluations"] / base_rhs, 2),
                         **{k: stats[k] for k in COUNTS},
                         **({k: (round(v, 6) if math.isfinite(v) else None)
                             for k, v in modes[name].items()} if method == "modal" else {})})
    record: dict[str, Any] = {
        "scenario": f"CDFS wang2021, table at 0.4 m, {SPEED * 1e3:g} mm/s, {DURATION:g} s, "
                    "default settings but the method",
        "runs": args.runs, "rows": rows, "scipy_rows": independent, "zeta_light": ZETA_LIGHT,
        "h_lambda": H_LAMBDA,
        "load_average_1min_before": round(load_before[0], 2),
        "load_average_1min_after": round(load_after[0], 2),
        "cpus": os.cpu_count(), "platform": platform.platform(),
        "python": platform.python_version(),
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
    }
    out = ROOT / "benchmarks" / "results"
    (out / "bench_gms.json").write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")
    lines = [f"# GMS guide against LuGre guide ({record['scenario']})", "",
             f"{record['date']}, {args.runs} runs (median CPU s), load average "
             f"{record['load_average_1min_before']} → {record['load_average_1min_after']} on "
             f"{record['cpus']} CPUs.", "",
             "| method | guide | CPU s | CPU ratio | RHS ratio | steps | RODAS4 steps | RHS "
             "| switches | eigen-analyses | table mode λ [1/s] | ζ | modal cap [ms] |",
             "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- | ---: "
             "| ---: |"]
    for r in rows:
        mode = (f"{r['table_mode_real_per_s']:.1f} ± {r['table_mode_imag_rad_per_s']:.0f}i | "
                f"{r['table_mode_zeta']:.4f} | "
                + (f"{r['modal_cap_ms']:.3f}" if r["modal_cap_ms"] is not None else "none")
                if r["method"] == "modal" else "| |")
        lines.append(f"| {r['method']} | {r['guide']} | {r['cpu_s']:.4f} | "
                     f"{r['cpu_ratio_to_lugre']:.2f} | {r['rhs_ratio_to_lugre']:.2f} | "
                     f"{r['steps']} | {r['rosenbrock_steps']} | {r['rhs_evaluations']} | "
                     f"{r['method_switches']} | {r['eigen_analyses']} | {mode} |")
    lines += ["", "The same two runs by scipy (`solve_ivp`, rtol 1e-6, the plain-Python model of "
              "`reference/`), ratios to its own LuGre run:", "",
              "| scipy method | guide | CPU s | CPU ratio | RHS | RHS ratio | steps |",
              "| --- | --- | ---: | ---: | ---: | ---: | ---: |"]
    lines += [f"| {r['method']} | {r['guide']} | {r['cpu_s']:.3f} | {r['cpu_ratio_to_lugre']:.2f} "
              f"| {r['rhs_evaluations']} | {r['rhs_ratio_to_lugre']:.2f} | {r['steps']} |"
              for r in independent]
    (out / "bench_gms.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
