"""Why the embedded global-error estimate misses the true error: its causes, separated
(issue 35 item 3).

Run from the repository root::

    python benchmarks/embedded_estimate_causes.py

On the frictionless 1-mm/s velocity steps of tests/validation/test_accuracy_embedded.py (CDFS
and DDFS, 1 s, outputs every 1 ms), whose loop is linear (``reference/linear_model.py``, the
augmented matrix written from the equations), this script takes DOPRI5 steps in plain Python —
the tableau and continuous extension of :data:`feeddrive.solvers.tableaux.DOPRI5`, the weighted
RMS norm over feeddrive's states with the run's own tolerances, Hairer's PI controller — and,
because the exact flow exp(hA) is known, records for every accepted step the embedded error
estimate (the lower-order solution's local error) *and* the propagated 5th-order solution's
true local error.  Then, against the exact solution:

* the true error at the outputs, at the step ends, and the dense output's interpolation error
  alone (dense output minus the exact flow from the step's start);
* each local-error sequence carried exactly step by step (E ← exp(hA) E + δ), and summed per
  interval of a fixed grid and carried at the interval's end (the estimate up to 2026-12-05:
  5 ms), for several grids.

So the grid (phase), the lower-order local error and the interpolation error are each measured
on their own.  A step sequence close to, not identical with, feeddrive's (its run takes 714
steps on the CDFS case, this one 633; the ratios agree: 0.17 here on the 5-ms grid, 0.16 in
feeddrive).  Writes ``benchmarks/results/embedded_estimate_causes.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from scipy.linalg import expm

ROOT = Path(__file__).resolve().parents[1]
for folder in (ROOT, ROOT / "tests" / "validation"):
    if str(folder) not in sys.path:
        sys.path.insert(0, str(folder))

from reference.scipy_model import STATE_NAMES  # noqa: E402
from test_accuracy_convergence import (  # noqa: E402
    DURATION,
    NUT_SPEED,
    augmented_matrix,
    equivalent_stiffness,
    frictionless,
)

import feeddrive as fd  # noqa: E402
from feeddrive.engine.simulate import Simulation  # noqa: E402
from feeddrive.solvers.tableaux import DOPRI5  # noqa: E402

TS = STATE_NAMES.index("table_speed")
GRIDS = (5e-3, 2e-3, 1e-3, 5e-4, 2.5e-4)


def steps_of(drive: str, accuracy: float) -> tuple[np.ndarray, list[tuple], int]:
    """The augmented matrix and the accepted steps (t, h, y, y_new, stages, embedded error,
    true local error of y_new)."""
    params = frictionless()
    nut = NUT_SPEED if drive == "ddfs" else 0.0
    A = augmented_matrix(params, drive, 1e-3, nut, equivalent_stiffness(params, 0.4))
    sim = Simulation(fd.DriveSystem(params, drive, 0.4),
                     fd.ConstantSpeed(table_speed=1e-3, nut_speed=nut, ramp_time=0.0),
                     fd.SolverOptions(method="dopri5-dense", accuracy=accuracy,
                                      output_interval=1e-3))
    idx = [STATE_NAMES.index(name) for name in sim.model.state_names]
    atol, rel, rtol = np.asarray(sim.atol), np.asarray(sim.rel, float), sim.tolerances.rtol
    c, a, b, e = DOPRI5.c, DOPRI5.a, np.array(DOPRI5.b), np.array(DOPRI5.e)
    beta = 0.04
    alpha = 0.2 - 0.75 * beta
    y = np.zeros(A.shape[0])
    y[-1] = 1.0  # the augmented constant
    t, h, err_old, rejected = 0.0, 1e-5, 1e-4, 0
    k1 = A @ y
    steps = []
    while t < DURATION - 1e-15:
        h = min(h, DURATION - t)
        K = [k1]
        for s in range(1, len(c)):
            K.append(A @ (y + h * sum(a[s][j] * K[j] for j in range(s))))
        y_new = y + h * sum(b[j] * K[j] for j in range(len(b)))
        K.append(A @ y_new)
        emb = h * sum(e[j] * K[j] for j in range(len(e)))
        scale = atol + rtol * rel * np.maximum(abs(y[idx]), abs(y_new[idx]))
        err = float(np.sqrt(np.mean((emb[idx] / scale) ** 2)))
        if err <= 1.0:
            steps.append((t, h, y.copy(), y_new.copy(), K, emb, y_new - expm(A * h) @ y))
            fac = 5.0 if err == 0 else min(5.0, max(0.2, 0.9 * err ** -alpha * err_old ** beta))
            err_old = max(err, 1e-4)
            t, y, k1 = t + h, y_new, K[-1]
            h *= fac
        else:
            rejected += 1
            h *= max(0.2, 0.9 * err ** -0.2)
    return A, steps, rejected


def dense(step: tuple, theta: float) -> np.ndarray:
    """DOPRI5's continuous extension (dopri5.f CONTD5) at ``theta`` of the step."""
    _, h, y0, y1, K, _, _ = step
    d = np.array(DOPRI5.dense)
    ydiff = y1 - y0
    bspl = h * K[0] - ydiff
    cont4 = h * sum(d[j] * K[j] for j in range(len(d)))
    return y0 + theta * (ydiff + (1 - theta) * (bspl + theta * (
        ydiff - h * K[-1] - bspl + (1 - theta) * cont4)))


def carried(A: np.ndarray, steps: list[tuple], local: list[np.ndarray],
            grid: float | None) -> float:
    """The largest |table-speed component| of the local errors carried step by step
    (``grid`` None) or summed per grid interval and carried at its end."""
    E = np.zeros(A.shape[0])
    pending = np.zeros_like(E)
    largest = 0.0
    for step, d in zip(steps, local, strict=True):
        t, h = step[0], step[1]
        if grid is None:
            E = expm(A * h) @ E + d
            largest = max(largest, abs(E[TS]))
            continue
        pending += d
        for _ in range(int(np.floor((t + h) / grid)) - int(np.floor(t / grid))):
            E = expm(A * grid) @ (E + pending)
            pending[:] = 0.0
        largest = max(largest, abs(E[TS] + pending[TS]))
    return largest


def case(drive: str, accuracy: float) -> dict:
    A, steps, rejected = steps_of(drive, accuracy)
    y0 = np.zeros(A.shape[0])
    y0[-1] = 1.0
    starts = np.array([s[0] for s in steps])
    out_err, interp = [], []
    for to in np.arange(1, int(round(DURATION / 1e-3)) + 1) * 1e-3:
        i = min(int(np.searchsorted(starts, to, side="right")) - 1, len(steps) - 1)
        u = dense(steps[i], (to - steps[i][0]) / steps[i][1])
        out_err.append(u[TS] - (expm(A * to) @ y0)[TS])
        interp.append(u[TS] - (expm(A * (to - steps[i][0])) @ steps[i][2])[TS])
    end_err = [s[3][TS] - (expm(A * (s[0] + s[1])) @ y0)[TS] for s in steps]
    true = float(np.max(np.abs(out_err)))
    row = {"drive": drive, "accuracy": accuracy, "steps": len(steps), "rejected": rejected,
           "median_step_s": float(np.median([s[1] for s in steps])),
           "true_error_outputs": true,
           "true_error_step_ends": float(np.max(np.abs(end_err))),
           "interpolation_error_outputs": float(np.max(np.abs(interp))),
           "table_mode_rad_s": float(np.max(np.abs(np.linalg.eigvals(A).imag)))}
    for name, local in (("embedded", [s[5] for s in steps]),
                        ("true_local_5th_order", [s[6] for s in steps])):
        row[f"{name}_per_step_over_true"] = carried(A, steps, local, None) / true
        row[f"{name}_grid_over_true"] = {f"{g * 1e3:g} ms": carried(A, steps, local, g) / true
                                         for g in GRIDS}
    return row


def main() -> None:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    rows = []
    for accuracy in (1.0, 0.01):
        for drive in ("cdfs", "ddfs"):
            row = case(drive, accuracy)
            rows.append(row)
            print(f"{drive} accuracy {accuracy:g}: true {row['true_error_outputs']:.3e} "
                  f"(interpolation part {row['interpolation_error_outputs']:.2e}); "
                  f"embedded per step ×{row['embedded_per_step_over_true']:.3g}, "
                  f"on 5 ms ×{row['embedded_grid_over_true']['5 ms']:.3g}; true local per "
                  f"step ×{row['true_local_5th_order_per_step_over_true']:.3g}, on 5 ms "
                  f"×{row['true_local_5th_order_grid_over_true']['5 ms']:.3g}", flush=True)
    path = ROOT / "benchmarks" / "results" / "embedded_estimate_causes.json"
    path.write_text(json.dumps({"cases": rows}, indent=2) + "\n")


if __name__ == "__main__":
    main()
