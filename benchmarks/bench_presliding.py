"""Benchmark (issue 19 item 6): the pre-sliding test simulated on the engine.

Run from the repository root::

    python benchmarks/bench_presliding.py [--repeats N]

The record: the screw-site step test of tests/unit/test_identification.py (wang2021 Table 1
screw friction, the mechanism's screw-site mass 2243 kg, 30 N over 2 ms at 50 ms, 1 s at
2 kHz).  Timed in the same run:

* **engine**: :func:`feeddrive.analysis.presliding_rig.simulate_presliding` (the LuGre law's
  compiled kernel, the DOPRI5 driver at its fixed step, two steps per sample here);
* **scipy**: ``solve_ivp`` (RK45 at rtol 1e-8, the force interpolated linearly) on the same
  model written in plain Python — the plain scipy implementation;
* **fit**: one :func:`feeddrive.analysis.presliding.fit_presliding` of the record with 1 %
  position noise (3 starts and the σ1 profile).

Each run's error against scipy's DOP853 at rtol 1e-10 is reported beside its time.  Writes
``benchmarks/results/bench_presliding.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]

import feeddrive as fd  # noqa: E402
from feeddrive.analysis.presliding import fit_presliding, site_mass  # noqa: E402
from feeddrive.analysis.presliding_rig import simulate_presliding  # noqa: E402
from feeddrive.model.friction.stribeck import bristle_rate  # noqa: E402

PARAMS = fd.preset("wang2021")
SCREW = PARAMS.friction.screw
MASS = site_mass(PARAMS, "screw", "cdfs")


def force(t: np.ndarray) -> np.ndarray:
    return 30.0 * np.clip((t - 0.05) / 0.002, 0.0, 1.0)


def scipy_run(t: np.ndarray, f: np.ndarray, method: str, rtol: float) -> np.ndarray:
    s0, s1 = SCREW.bristle_stiffness, SCREW.bristle_damping

    def rhs(time: float, y: np.ndarray) -> list[float]:
        x, v, z = y
        zdot = float(bristle_rate(v, z, SCREW))
        s2 = (SCREW.positive if v >= 0 else SCREW.negative).viscous_coefficient
        return [v, (float(np.interp(time, t, f)) - s0 * z - s1 * zdot - s2 * v) / MASS, zdot]

    sol = solve_ivp(rhs, (0.0, t[-1]), [0.0, 0.0, 0.0], method=method, t_eval=t, rtol=rtol,
                    atol=1e-16, max_step=t[1] - t[0])
    assert sol.success
    return np.asarray(sol.y[0])


def timed(fn, repeats: int) -> tuple[float, object]:
    out = fn()  # warm (compile, caches)
    start = time.perf_counter()
    for _ in range(repeats):
        out = fn()
    return (time.perf_counter() - start) / repeats, out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=20)
    args = ap.parse_args()
    t = np.arange(0.0, 1.0, 1.0 / 2000.0)
    f = force(t)
    reference = scipy_run(t, f, "DOP853", 1e-10)
    span = float(np.ptp(reference))
    engine_s, engine_x = timed(lambda: simulate_presliding(t, f, MASS, SCREW), args.repeats)
    scipy_s, scipy_x = timed(lambda: scipy_run(t, f, "RK45", 1e-8), max(1, args.repeats // 10))
    x = reference + 0.01 * span * np.random.default_rng(0).standard_normal(t.size)
    fit_s, fit = timed(lambda: fit_presliding(t, f, x, mass=MASS, friction=SCREW), 1)
    result = {
        "record": "screw-site step test, 2000 samples at 2 kHz",
        "engine_seconds": engine_s,
        "engine_error": float(np.max(np.abs(np.asarray(engine_x) - reference)) / span),
        "scipy_rk45_seconds": scipy_s,
        "scipy_rk45_error": float(np.max(np.abs(np.asarray(scipy_x) - reference)) / span),
        "scipy_over_engine": scipy_s / engine_s,
        "fit_seconds": fit_s,
        "fit_sigma0": fit.bristle_stiffness.value,  # type: ignore[attr-defined]
        "fit_sigma1": fit.bristle_damping.value,  # type: ignore[attr-defined]
    }
    out = ROOT / "benchmarks" / "results" / "bench_presliding.json"
    out.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    json.dump(result, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
