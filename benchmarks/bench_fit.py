"""Benchmark: one whole-drive fit, feeddrive against a plain scipy fit of the same records.

Run from the repository root (about 3 minutes on 2 cores)::

    python benchmarks/bench_fit.py [--seeds 3]

The records: the independent calibration's (reference/fit_traces.py: ``wang2021``'s CDFS
with the velocity-loop integral gain ×1.2, the screw's viscous coefficient ×0.8 and static
force ×1.1, integrated by scipy Radau on the plain-Python model at 1, 2 and 5 mm/s for 2 s,
measured as a rig does: 0.05-µm position counts, 1 % current noise), one set per seed.

Contestants, each fitting the same three parameters from ``wang2021``'s values:

* **feeddrive**: ``fit_drive`` (its defaults: trust-region least squares with continuation,
  the accuracy checks, the HAC intervals), on one process;
* **scipy**: what a user writes by hand — ``scipy.optimize.least_squares`` (``trf``, forward
  differences of 1e-3 relative, the factors on the truth's scale 1) on the residuals of the plain-Python model
  (``reference.scipy_model.ReferenceModel``) integrated by ``solve_ivp(LSODA, rtol=1e-6)``
  with the model's absolute tolerances, position offset-free and both signals divided by
  their noise levels, as feeddrive weighs them.  No accuracy check, no intervals.

Reported per contestant: CPU seconds of the fit (``time.process_time``, one process), the
simulations it ran (one per record and parameter point), CPU per simulation, the estimates'
largest relative error against the truth; and the ratios scipy / feeddrive of the whole fit
and of one simulation.  Results: benchmarks/results/bench_fit.json and .md.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.fit_traces import (  # noqa: E402
    FACTORS,
    RAMP_TIME,
    SPEEDS,
    calibration_truth,
    measured,
    radau_trace,
)
from reference.scipy_model import ReferenceModel  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.analysis.fit import fit_drive  # noqa: E402
from feeddrive.model.reference import ConstantSpeed  # noqa: E402

OUT = ROOT / "benchmarks" / "results"
FREE = list(FACTORS)


def _get(p: Any, path: str) -> Any:
    for part in path.split("."):
        p = getattr(p, part)
    return p


def _set(base: Any, factors: np.ndarray) -> Any:
    """``base`` with each free parameter × its factor."""
    p = base
    for path, f in zip(FREE, factors, strict=True):
        p = p.replace_path(path, float(_get(base, path)) * float(f))
    return p


def scipy_fit(base: Any, experiments: list[Any]) -> dict[str, Any]:
    """The hand-written fit: least_squares over LSODA runs of the plain-Python model."""
    count = {"simulations": 0}

    def residual(factors: np.ndarray) -> np.ndarray:
        params = _set(base, factors)
        parts = []
        for speed, e in zip(SPEEDS, experiments, strict=True):  # the records' commands
            model = ReferenceModel(params, "cdfs", 0.4,
                                   ConstantSpeed(speed, ramp_time=RAMP_TIME))
            sol = solve_ivp(model, (0.0, float(e.time[-1])), np.zeros(model.n_state),
                            method="LSODA", rtol=1e-6, atol=model.tolerances(), t_eval=e.time)
            count["simulations"] += 1
            if sol.status != 0:
                return np.full(sum(2 * x.time.size for x in experiments), 1e6)
            names = model.state_names
            x = sol.y[names.index("table_position")] - e.signals["table_position"]
            i = sol.y[names.index("screw_current")] - e.signals["screw_current"]
            parts += [(x - x.mean()) / e.noise["table_position"],
                      i / e.noise["screw_current"]]
        return np.concatenate(parts)

    started = time.process_time()
    # forward differences of 1e-3 relative: scipy's default step (1.5e-8) is below LSODA's
    # rtol 1e-6, and the viscous coefficient's column came out zero (the fit never moved it)
    sol = least_squares(residual, np.ones(len(FREE)), method="trf", x_scale=1.0,
                        bounds=(0.1, 10.0), diff_step=1e-3)
    cpu = time.process_time() - started
    start = [float(_get(base, p)) for p in FREE]
    return {"cpu_s": cpu, "simulations": count["simulations"],
            "values": [s * f for s, f in zip(start, sol.x, strict=True)]}


def feeddrive_fit(base: Any, experiments: list[Any]) -> dict[str, Any]:
    started = time.process_time()
    result = fit_drive(base, experiments, FREE)
    cpu = time.process_time() - started
    by_path = {e.path: e.value for e in result.estimates}
    return {"cpu_s": cpu, "simulations": int(result.evaluations) * len(experiments),
            "values": [float(by_path[p]) for p in FREE]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=3, help="record sets (one fit each)")
    args = parser.parse_args()
    base = fd.preset("wang2021")
    truth, values = calibration_truth()
    traces = [radau_trace(truth, v, 2.0) for v in SPEEDS]
    exact = np.array([values[p] for p in FREE])
    # compile and import once, outside the timing
    feeddrive_fit(base, [measured(tr, 99 + k) for k, tr in enumerate(traces)])
    rows = []
    for seed in range(args.seeds):
        experiments = [measured(tr, 1000 * seed + k) for k, tr in enumerate(traces)]
        row: dict[str, Any] = {"seed": seed}
        for name, fit in (("feeddrive", feeddrive_fit), ("scipy", scipy_fit)):
            r = fit(base, experiments)
            r["cpu_per_simulation_ms"] = 1e3 * r["cpu_s"] / r["simulations"]
            r["largest_relative_error"] = float(np.max(np.abs(np.array(r["values"]) / exact
                                                              - 1.0)))
            row[name] = r
        row["ratio_fit"] = row["scipy"]["cpu_s"] / row["feeddrive"]["cpu_s"]
        row["ratio_simulation"] = (row["scipy"]["cpu_per_simulation_ms"]
                                   / row["feeddrive"]["cpu_per_simulation_ms"])
        rows.append(row)
        f, s = row["feeddrive"], row["scipy"]
        print(f"seed {seed}: feeddrive {f['cpu_s']:.2f} CPU s, {f['simulations']} simulations "
              f"({f['cpu_per_simulation_ms']:.2f} ms each), error {f['largest_relative_error']:.2e}"
              f" | scipy {s['cpu_s']:.2f} CPU s, {s['simulations']} simulations "
              f"({s['cpu_per_simulation_ms']:.1f} ms each), error "
              f"{s['largest_relative_error']:.2e} | × {row['ratio_fit']:.1f} fit, "
              f"× {row['ratio_simulation']:.1f} a simulation", flush=True)
    import os

    summary = {"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
               "load_average": os.getloadavg(), "rows": rows,
               "median_ratio_fit": float(np.median([r["ratio_fit"] for r in rows])),
               "median_ratio_simulation": float(np.median([r["ratio_simulation"]
                                                           for r in rows]))}
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "bench_fit.json").write_text(json.dumps(summary, indent=2), encoding="utf-8")
    lines = [f"Fit benchmark, {summary['date']} (load average "
             f"{', '.join(f'{x:.2f}' for x in summary['load_average'])})", "",
             "| seed | feeddrive CPU s | simulations | ms each | largest rel. error "
             "| scipy CPU s | simulations | ms each | largest rel. error | × fit "
             "| × simulation |", "|" + " --- |" * 11]
    for r in rows:
        f, s = r["feeddrive"], r["scipy"]
        lines.append(f"| {r['seed']} | {f['cpu_s']:.2f} | {f['simulations']} | "
                     f"{f['cpu_per_simulation_ms']:.2f} | {f['largest_relative_error']:.1e} | "
                     f"{s['cpu_s']:.1f} | {s['simulations']} | {s['cpu_per_simulation_ms']:.1f}"
                     f" | {s['largest_relative_error']:.1e} | {r['ratio_fit']:.1f} | "
                     f"{r['ratio_simulation']:.1f} |")
    (OUT / "bench_fit.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"median × {summary['median_ratio_fit']:.1f} fit, "
          f"× {summary['median_ratio_simulation']:.1f} a simulation → {OUT / 'bench_fit.json'}")


if __name__ == "__main__":
    main()
