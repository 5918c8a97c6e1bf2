"""Calibration of `feeddrive fit`'s intervals on traces from an independent integrator
(issue 36 item 6; docs/fitting.md, "Calibration").

The truth is ``wang2021``'s CDFS with ``controller.velocity_integral_gain`` ×1.2,
``friction.screw.positive.viscous_coefficient`` ×0.8, ``friction.screw.positive.static_force``
×1.1, integrated by scipy's Radau on the plain-Python model (``reference/fit_traces.py``,
rtol 1e-9) at 1, 2 and 5 mm/s; each seed measures it as a rig does — table position in
0.05-µm counts from a start drawn within a count, screw current with 1 % white noise — and the
three values are fitted from the unchanged set.  Recorded per parameter: coverage of the 95 %
intervals, mean (estimate − truth)/s.e. and mean |…|, median relative half-width; then the
same with half the noise (0.025-µm counts, 0.5 %), whose median half-width should halve.
This tests the numerical part (integration error, quantised records), not the model's
structure against a real machine.

Run niced (the machine is shared)::

    nice -n 10 python benchmarks/fit_calibration_independent.py [--seeds 100] [--duration 2]
        [--out benchmarks/results/fit_calibration_independent.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.fit_traces import FACTORS as FREE  # noqa: E402
from reference.fit_traces import SPEEDS, calibration_truth, measured, radau_trace  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.analysis.fit import fit_drive  # noqa: E402

QUANTUM = 0.05e-6  # [m]
CURRENT_NOISE = 0.01  # [-] of the current's rms


def calibrate(seeds: int, duration: float, noise_scale: float = 1.0,
              say: Any = print) -> dict[str, Any]:
    """Fit ``seeds`` noisy measurements of the Radau traces; the figures per parameter."""
    truth, values = calibration_truth()
    traces = [radau_trace(truth, v, duration) for v in SPEEDS]
    base = fd.preset("wang2021")
    rows: dict[str, list[dict[str, float]]] = {p: [] for p in FREE}
    inadequate = 0
    for seed in range(seeds):
        exps = [measured(tr, 1000 * seed + k, position_quantum=QUANTUM * noise_scale,
                         current_noise=CURRENT_NOISE * noise_scale)
                for k, tr in enumerate(traces)]
        result = fit_drive(base, exps, list(FREE))
        inadequate += result.inadequate is not None
        for e in result.estimates:
            t = values[e.path]
            rows[e.path].append({"z": (e.value - t) / e.stderr,
                                 "z_white": (e.value - t) / e.stderr_white,
                                 "inside": float(e.low <= t <= e.high),
                                 "half_width": e.relative_half_width})
        say(f"seed {seed}: " + ", ".join(f"{r[-1]['z']:+.2f}" for r in rows.values()))
    out: dict[str, Any] = {"seeds": seeds, "duration_s": duration, "noise_scale": noise_scale,
                           "model_inadequate": inadequate, "parameters": {}}
    for path, r in rows.items():
        z = np.array([x["z"] for x in r])
        zw = np.array([x["z_white"] for x in r])
        out["parameters"][path] = {
            "coverage": float(np.mean([x["inside"] for x in r])),
            "mean_z": float(z.mean()), "mean_abs_z": float(np.abs(z).mean()),
            "sd_z": float(z.std(ddof=1)) if z.size > 1 else float("nan"),
            "mean_abs_z_white": float(np.abs(zw).mean()),
            "median_half_width": float(np.median([x["half_width"] for x in r]))}
    return out


def main(argv: list[str]) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=100)
    ap.add_argument("--duration", type=float, default=2.0)
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" /
                                         "fit_calibration_independent.json"))
    args = ap.parse_args(argv)
    started = time.perf_counter()
    full = calibrate(args.seeds, args.duration)
    half = calibrate(args.seeds, args.duration, noise_scale=0.5)
    ratio = {p: half["parameters"][p]["median_half_width"] /
             full["parameters"][p]["median_half_width"] for p in FREE}
    result = {"noise": full, "half_noise": half, "half_width_ratio": ratio,
              "wall_time_s": time.perf_counter() - started}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=2) + "\n", encoding="utf-8")
    for name, r in (("noise", full), ("half noise", half)):
        for p, f in r["parameters"].items():
            print(f"{name:10s} {p}: coverage {f['coverage']:.2f}, mean z {f['mean_z']:+.2f}, "
                  f"mean |z| {f['mean_abs_z']:.2f} (white s.e.: {f['mean_abs_z_white']:.2f}), "
                  f"median half-width {f['median_half_width']:.3g}")
        print(f"{name}: model inadequate in {r['model_inadequate']} of {r['seeds']}")
    print("half-width ratio (half noise / noise):",
          ", ".join(f"{p.rsplit('.', 1)[1]} {v:.2f}" for p, v in ratio.items()))
    print(f"{result['wall_time_s']:.0f} s")


if __name__ == "__main__":
    main(sys.argv[1:])
