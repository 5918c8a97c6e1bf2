"""The exported FMU in fmpy against ``feeddrive.simulate`` (issue 20 item 7).

Three scenarios, 10 s each (the shipped ``wang2021`` preset, table at mid-screw, a 0.1-s start
ramp sampled at the communication step h = 1 ms and held over each step): CDFS 2 mm/s, CDFS
1.2 mm/s (stick-slip), DDFS 0.5 mm/s with v_n = 16 mm/s.

* **FMU cs**: ``fmpy.simulate_fmu`` of the FMI 2.0 co-simulation FMU (its embedded DOPRI5 at
  feeddrive's default tolerances), the reference as an input table, outputs every 1 ms;
* **feeddrive**: ``feeddrive.simulate`` (its default method, default tolerances) driven by
  the same held reference, ``SampledSpeed(hold=True)``;
* agreement of the FMU with each method it is compared to (issue 38 item 6): ``dopri5`` (the
  FMU's own integrator) and the default method, each at the default tolerances and at 1000×
  tighter ones;
* **FMU me**: the model-exchange FMU in fmpy (its SUNDIALS CVODE integrates the FMU's
  derivatives; relative tolerance 1e-8) with the speeds constant from t = 0 — the measurement
  behind the co-simulation integrator's choice (an embedded DOPRI5 generated from feeddrive's
  code against the well-kept CVODE the importer brings);
* accuracy: max |Δ table position| on the 1-ms grid against feeddrive at 1000× tighter
  tolerances (rtol 1e-9, 1e-13 m).

CPU time (``process_time``; the FMU runs in-process through ctypes), median of ``--rounds``.

    python benchmarks/bench_fmu.py [--rounds 3]

Results: ``benchmarks/results/bench_fmu.json`` and benchmarks/README.md.
"""

from __future__ import annotations

import argparse
import functools
import json
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "validation"))
RESULTS = ROOT / "benchmarks" / "results" / "bench_fmu.json"

from fmu_helpers import (  # noqa: E402
    FMU_TIGHT,
    SCENARIOS,
    TIGHT,
    Reference,
    on_grid,
    run_feeddrive,
    run_fmu,
)

from feeddrive.fmu import export_fmu  # noqa: E402
from feeddrive.parameters import preset  # noqa: E402


def _cpu(fn, rounds: int):  # type: ignore[no-untyped-def]
    times, out = [], None
    for _ in range(rounds):
        t0 = time.process_time()
        out = fn()
        times.append(time.process_time() - t0)
    return float(np.median(times)), out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--duration", type=float, default=10.0)
    args = ap.parse_args()
    from feeddrive.engine.simulate import SolverOptions

    default_method = SolverOptions().method
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, (drive, vt, vn) in SCENARIOS.items():
            cs = Path(tmp) / f"{drive}-cs.fmu"
            me = Path(tmp) / f"{drive}-me.fmu"
            t0 = time.perf_counter()
            if not cs.exists():
                export_fmu(preset("wang2021"), drive, cs)
                export_fmu(preset("wang2021"), drive, me, kind="me")
            export_s = time.perf_counter() - t0
            ref = Reference.ramp(vt, vn, args.duration)
            run_fmu(cs, ref)  # warm-up: load the library
            run_feeddrive(drive, ref)  # warm-up: numba cache
            fmu_cpu, rec = _cpu(lambda: run_fmu(cs, ref), args.rounds)  # noqa: B023
            fd_cpu, res = _cpu(lambda: run_feeddrive(drive, ref), args.rounds)  # noqa: B023
            tight = run_feeddrive(drive, ref, **TIGHT)
            x = tight["table_position"]
            stroke = abs(float(x[-1] - x[0]))
            dev_fmu = float(np.max(np.abs(on_grid(rec, tight.time, "table_position") - x)))
            dev_fd = float(np.max(np.abs(res["table_position"] - x)))
            rec_t = run_fmu(cs, ref, start_values=FMU_TIGHT)
            dev_tight = float(np.max(np.abs(on_grid(rec_t, tight.time, "table_position") - x)))
            # the FMU against each method: the same DOPRI5 (default tolerances; both tight),
            # stepping across the friction reversals as the FMU's does, and feeddrive's
            # default method (default tolerances; both tight)
            agree = {}
            for method in ("dopri5", default_method):
                same = {"locate_reversals": False} if method == "dopri5" else {}
                for label, fmu_rec, opts in (("default", rec, {}),
                                             ("tight", rec_t, dict(TIGHT))):
                    other = run_feeddrive(drive, ref, method=method, **opts, **same)
                    d = float(np.max(np.abs(on_grid(fmu_rec, other.time, "table_position")
                                            - other["table_position"])))
                    agree[f"dev_fmu_vs_{method}_{label}_m"] = d
                    agree[f"dev_fmu_vs_{method}_{label}_rel"] = d / stroke
            const = Reference.ramp(vt, vn, args.duration, ramp=0.0)
            me_cpu, me_rec = _cpu(lambda: run_fmu(me, const,  # noqa: B023
                                                  relative_tolerance=1e-8), 1)
            cs_const_cpu, cs_rec = _cpu(lambda: run_fmu(cs, const), 1)  # noqa: B023
            # few communication points (0.1 s): the FMU's own integration, little fmpy
            from fmpy import simulate_fmu
            start = {"table_speed_reference": vt * 1e-3}
            if drive == "ddfs":
                start["nut_speed_reference"] = vn * 1e-3
            coarse_cpu, _ = _cpu(functools.partial(
                simulate_fmu, str(cs), stop_time=args.duration, output_interval=0.1,
                start_values=start, output=["table_position"]), args.rounds)
            tight_c = run_feeddrive(drive, const, **TIGHT)
            xc = tight_c["table_position"]
            dev_me = float(np.max(np.abs(on_grid(me_rec, tight_c.time, "table_position") - xc)))
            dev_cs_c = float(np.max(np.abs(on_grid(cs_rec, tight_c.time, "table_position")
                                           - xc)))
            rows.append({
                "scenario": name, "duration_s": args.duration,
                "fmu_cs_cpu_s": fmu_cpu, "feeddrive_cpu_s": fd_cpu,
                "ratio_fmu_over_feeddrive": fmu_cpu / fd_cpu,
                "stroke_m": stroke, "dev_fmu_m": dev_fmu, "dev_fmu_rel": dev_fmu / stroke,
                "dev_feeddrive_default_m": dev_fd, "dev_fmu_tight_m": dev_tight,
                "dev_fmu_tight_rel": dev_tight / stroke, "fmu_cs_h100ms_cpu_s": coarse_cpu,
                "fmu_me_cvode_cpu_s": me_cpu, "dev_fmu_me_m": dev_me,
                "fmu_cs_constant_cpu_s": cs_const_cpu, "dev_fmu_cs_constant_m": dev_cs_c,
                "fmu_cs_bytes": cs.stat().st_size, "fmu_me_bytes": me.stat().st_size,
                "export_s": export_s, "default_method": default_method, **agree})
            print(json.dumps(rows[-1]), flush=True)
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps({"machine": platform.processor() or platform.machine(),
                                   "python": platform.python_version(), "rounds": args.rounds,
                                   "rows": rows}, indent=2) + "\n", encoding="utf-8")
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
