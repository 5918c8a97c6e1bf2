"""Benchmark (issue 35): the global error against ``accuracy``, per method, on references
feeddrive did not make — and what the accuracy costs.

Run from the repository root (about a minute)::

    python benchmarks/bench_accuracy.py

Cases:

* frictionless velocity steps (``wang2021-literal``, friction off, table basis, axial damping
  2000 N s/m, K_eq frozen, no ramp; 1 s) of the CDFS and of the DDFS (hollow motor 16 mm/s)
  at 0.1, 1 and 10 mm/s against the hand-written matrix exponential of
  ``reference/linear_model.py``: the largest table-speed error over the peak table speed;
* smooth LuGre runs of ``wang2021`` (CDFS 2.0 mm/s, DDFS 0.5 mm/s with v_n = 16 mm/s; 3 s)
  against scipy Radau on the plain-Python model (``tests/data/accuracy_*.npz``, made by
  ``reference/make_accuracy_reference.py``): the largest table-position error over the
  stroke, with the floor the reference resolves.

For each method (``modal``, ``auto``, ``rodas4``, ``dopri5-dense``; ``dopri5`` with a 10-ms
output, its step cap; ``modal`` and ``auto`` with RODAS5P, opt-in) and ``accuracy`` 1, 0.1,
0.01, 0.001: the error, the steps and the
right-hand-side calls; and the legacy fixed tolerances (1e-10 m, 1e-8 m/s, 1e-6 A, rtol 1e-6)
for comparison.  Writes ``benchmarks/results/bench_accuracy.json`` and ``.md``.
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

from reference.linear_model import augmented_matrix, exact_response  # noqa: E402
from reference.scipy_model import STATE_NAMES  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.engine.options import LEGACY_TOLERANCES  # noqa: E402
from feeddrive.model.mechanisms.ball_screw_stiffness import equivalent_stiffness  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
DATA = ROOT / "tests" / "data"
#: the rows: label → the SolverOptions settings besides the tolerances (RODAS5P, opt-in, as the
#: Rosenbrock method of modal and auto: docs/model.md, "RODAS5P")
METHODS: dict[str, dict[str, str]] = {
    **{m: {"method": m} for m in ("modal", "auto", "rodas4", "dopri5-dense", "dopri5")},
    "modal, rodas5p": {"method": "modal", "rosenbrock": "rodas5p"},
    "auto, rodas5p": {"method": "auto", "rosenbrock": "rodas5p"}}
SETTINGS: tuple[tuple[str, dict[str, Any]], ...] = (
    ("legacy", dict(LEGACY_TOLERANCES)),
    *((f"accuracy {a:g}", {"accuracy": a}) for a in (1.0, 0.1, 0.01, 0.001)))


def frictionless() -> fd.DriveParameters:
    p = (fd.preset("wang2021-literal").replace_path("stiffness.axial_damping", 2000.0)
         .replace_path("stiffness.position_dependent", False)
         .replace_path("controller.velocity_gain_basis", "table"))
    for site in ("screw", "nut", "guide"):
        p = p.replace_path(f"friction.{site}.law", "none")
    return p


def step_case(drive: str, speed: float) -> list[dict[str, Any]]:
    params = frictionless()
    nut = 16e-3 if drive == "ddfs" else 0.0
    profile = fd.ConstantSpeed(speed, nut, ramp_time=0.0)
    A = augmented_matrix(params, drive, speed, nut, equivalent_stiffness(params, 0.4))
    k = STATE_NAMES.index("table_speed")
    rows = []
    for method, chosen in METHODS.items():
        for label, settings in SETTINGS:
            options = fd.SolverOptions(**chosen, **settings,
                                       output_interval=1e-2 if method == "dopri5" else 1e-3)
            started = time.process_time()
            r = fd.simulate(fd.DriveSystem(params, drive, 0.4), profile, 1.0, options=options)
            cpu = time.process_time() - started
            exact = exact_response(A, r.time)[:, k]
            rows.append({"case": f"step {drive} {speed * 1e3:g} mm/s", "method": method,
                         "setting": label,
                         "error": float(np.max(np.abs(r["table_speed"] - exact))
                                        / np.max(np.abs(exact))),
                         "steps": r.solver_stats["steps"],
                         "rhs": r.solver_stats["rhs_evaluations"], "cpu_ms": 1e3 * cpu})
    return rows


def lugre_case(name: str) -> list[dict[str, Any]]:
    with np.load(DATA / f"accuracy_{name}.npz") as f:
        ref = {k: f[k] for k in f.files}
    system = fd.DriveSystem(fd.preset("wang2021"), str(ref["drive"]), 0.4)
    profile = fd.ConstantSpeed(float(ref["table_speed_command"]),
                               float(ref["nut_speed_command"]))
    span = float(np.ptp(ref["table_position"]))
    rows = []
    for method, chosen in METHODS.items():
        for label, settings in SETTINGS:
            started = time.process_time()
            r = fd.simulate(system, profile, float(ref["time"][-1]),
                            options=fd.SolverOptions(**chosen, **settings))
            cpu = time.process_time() - started
            rows.append({"case": f"LuGre {name}", "method": method, "setting": label,
                         "error": float(np.max(np.abs(r["table_position"]
                                                      - ref["table_position"]))) / span,
                         "floor": float(ref["reference_error_table_position"]) / span,
                         "steps": r.solver_stats["steps"],
                         "rhs": r.solver_stats["rhs_evaluations"], "cpu_ms": 1e3 * cpu})
    return rows


def markdown(rows: list[dict[str, Any]]) -> str:
    labels = [label for label, _ in SETTINGS]
    lines = ["| case | method | " + " | ".join(labels) + " |",
             "| --- | --- | " + " | ".join("---" for _ in labels) + " |"]
    keys = sorted({(r["case"], r["method"]) for r in rows},
                  key=lambda k: (k[0], list(METHODS).index(k[1])))
    for case, method in keys:
        cells = []
        for label in labels:
            r = next(x for x in rows if (x["case"], x["method"], x["setting"])
                     == (case, method, label))
            cells.append(f"{r['error']:.1e} ({r['rhs']})")
        lines.append(f"| {case} | {method} | " + " | ".join(cells) + " |")
    floors = {r["case"]: r["floor"] for r in rows if "floor" in r}
    notes = [f"* {case}: the reference resolves {floor:.1e} of the stroke"
             for case, floor in sorted(floors.items())]
    return ("Error (frictionless steps: table speed over its peak; LuGre: table position over "
            "the stroke) and right-hand-side calls in brackets, per setting.\n\n"
            + "\n".join(lines) + "\n\n" + "\n".join(notes) + "\n")


def main() -> None:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    rows: list[dict[str, Any]] = []
    for drive in ("cdfs", "ddfs"):
        for speed in (1e-4, 1e-3, 1e-2):
            rows += step_case(drive, speed)
            print(f"step {drive} {speed * 1e3:g} mm/s done", flush=True)
    for name in ("cdfs_2p0", "ddfs_0p5_vn16"):
        rows += lugre_case(name)
        print(f"LuGre {name} done", flush=True)
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "bench_accuracy.json").write_text(json.dumps(rows, indent=1) + "\n")
    table = markdown(rows)
    (RESULTS / "bench_accuracy.md").write_text(table)
    print(table)


if __name__ == "__main__":
    main()
