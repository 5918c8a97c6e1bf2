"""The model-exchange FMU's directional derivatives in the importers (issue 38 item 4).

* **PathSim** (pathsim-fmi's ``ModelExchangeFMU``, which asks its implicit solvers' Jacobian
  through ``fmi2GetDirectionalDerivative`` when the FMU provides it): the DDFS at 0.5 mm/s with
  v_n = 16 mm/s from rest, ESDIRK4 at a fixed 0.1-ms step, fixed-point tolerance 1e-12 —
  with the FMU's directional derivatives, and without (PathSim's own central differences);
* **CVODE** (fmpy's SUNDIALS 7 CVODE, BDF, dense, rtol 1e-8, atol = rtol·nominal): fmpy does
  not set a Jacobian function; this harness runs CVODE on the FMU's derivatives with its own
  difference-quotient Jacobian, and with a Jacobian callback (``CVodeSetJacFn``, bound from
  fmpy's library) that asks the FMU, column by column.

Counted by the FMU itself (``evaluations.derivatives``, ``evaluations.tangents``); CPU time
(``process_time``).  The traces: table position, max |Δ| over the stroke.

    python benchmarks/bench_fmu_jacobian.py [--pathsim-time 0.05] [--cvode-time 2]

Results: ``benchmarks/results/bench_fmu_jacobian.json`` and benchmarks/README.md.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "validation"))
RESULTS = ROOT / "benchmarks" / "results" / "bench_fmu_jacobian.json"

from fmu_helpers import pathsim_model_exchange  # noqa: E402

from feeddrive.fmu import export_fmu  # noqa: E402
from feeddrive.parameters import preset  # noqa: E402


def pathsim_run(path: Path, duration: float, use_them: bool) -> dict:
    (rhs, tangents), _, x, cpu = pathsim_model_exchange(path, duration, use_them)
    return {"cpu_s": cpu, "derivatives": rhs, "tangents": tangents, "x": x}


def cvode_run(path: Path, table_speed: float, nut_speed: float, duration: float,
              use_them: bool) -> dict:
    import fmpy.sundials as S
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Model
    from fmpy.sundials.cvode import CVRhsFn
    from fmpy.sundials.libraries import sundials_cvode, sundials_sunmatrixdense

    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    inputs = {v.name for v in md.modelVariables if v.causality == "input"}
    f = FMU2Model(guid=md.guid, unzipDirectory=extract(str(path)),
                  modelIdentifier=md.modelExchange.modelIdentifier, instanceName="cvode")
    f.instantiate()
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    f.setReal([vr["table_speed_reference"]], [table_speed])
    if "nut_speed_reference" in inputs:
        f.setReal([vr["nut_speed_reference"]], [nut_speed])
    f.exitInitializationMode()
    f.newDiscreteStates()
    f.enterContinuousTimeMode()
    nx = len(md.derivatives)
    ders = [d.variable.valueReference for d in md.derivatives]
    states = [d.variable.derivative.valueReference for d in md.derivatives]
    pos = [d.variable.derivative.name for d in md.derivatives].index("table_position")

    def ptr(a: np.ndarray):  # type: ignore[no-untyped-def]
        return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))

    x0, nominal = np.zeros(nx), np.zeros(nx)
    f.getContinuousStates(ptr(x0), nx)
    f.getNominalsOfContinuousStates(ptr(nominal), nx)

    def rhs(t, y, ydot, user):  # type: ignore[no-untyped-def]
        f.setTime(t)
        f.setContinuousStates(S.NV_DATA_S(y), nx)
        f.getDerivatives(S.NV_DATA_S(ydot), nx)
        return 0

    jac_type = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_double, S.N_Vector, S.N_Vector,
                                S.SUNMatrix, ctypes.c_void_p, S.N_Vector, S.N_Vector,
                                S.N_Vector)
    data = sundials_sunmatrixdense.SUNDenseMatrix_Data
    data.argtypes, data.restype = [S.SUNMatrix], ctypes.POINTER(ctypes.c_double)

    def jac(t, y, fy, J, user, t1, t2, t3):  # type: ignore[no-untyped-def]
        f.setTime(t)
        f.setContinuousStates(S.NV_DATA_S(y), nx)
        out = np.ctypeslib.as_array(data(J), (nx * nx,))  # column-major
        for j in range(nx):
            seed = [0.0] * nx
            seed[j] = 1.0
            out[j * nx:(j + 1) * nx] = f.getDirectionalDerivative(ders, states, seed)
        return 0

    ctx = S.SUNContext()
    S.SUNContext_Create(S.SUN_COMM_NULL, ctypes.byref(ctx))
    y = S.N_VNew_Serial(nx, ctx)
    atol = S.N_VNew_Serial(nx, ctx)
    rtol = 1e-8
    np.ctypeslib.as_array(S.NV_DATA_S(y), (nx,))[:] = x0
    np.ctypeslib.as_array(S.NV_DATA_S(atol), (nx,))[:] = rtol * nominal
    mem = S.CVodeCreate(S.CV_BDF, ctx)
    rhs_c = CVRhsFn(rhs)
    S.CVodeInit(mem, rhs_c, 0.0, y)
    S.CVodeSVtolerances(mem, rtol, atol)
    A = S.SUNDenseMatrix(nx, nx, ctx)
    LS = S.SUNLinSol_Dense(y, A, ctx)
    S.CVodeSetLinearSolver(mem, LS, A)
    S.CVodeSetMaxNumSteps(mem, 10_000_000)
    jac_c = jac_type(jac)
    if use_them:
        set_jac = sundials_cvode.CVodeSetJacFn
        set_jac.argtypes, set_jac.restype = [ctypes.c_void_p, jac_type], ctypes.c_int
        assert set_jac(mem, jac_c) == 0
    tret = S.realtype(0.0)
    trace = []
    t0 = time.process_time()
    for k in range(1, int(round(duration / 1e-3)) + 1):
        assert S.CVode(mem, k * 1e-3, y, ctypes.byref(tret), S.CV_NORMAL) >= 0
        trace.append(float(np.ctypeslib.as_array(S.NV_DATA_S(y), (nx,))[pos]))
    cpu = time.process_time() - t0
    counts = f.getInteger([vr["evaluations.derivatives"], vr["evaluations.tangents"]])
    steps, jacs = ctypes.c_long(), ctypes.c_long()
    for name, out in (("CVodeGetNumSteps", steps), ("CVodeGetNumJacEvals", jacs)):
        fn = getattr(sundials_cvode, name)
        fn.argtypes, fn.restype = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_long)], ctypes.c_int
        fn(mem, ctypes.byref(out))
    S.CVodeFree(ctypes.byref(ctypes.c_void_p(mem)))
    return {"cpu_s": cpu, "derivatives": int(counts[0]), "tangents": int(counts[1]),
            "steps": steps.value, "jacobians": jacs.value, "x": np.array(trace)}


def _deviation(a: np.ndarray, b: np.ndarray) -> float:
    n = min(a.size, b.size)
    return float(np.max(np.abs(a[:n] - b[:n])) / abs(a[n - 1] - a[0]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pathsim-time", type=float, default=0.05)
    ap.add_argument("--cvode-time", type=float, default=2.0)
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        fmus = {}
        for drive in ("cdfs", "ddfs"):
            fmus[drive] = Path(tmp) / f"{drive}-me.fmu"
            export_fmu(preset("wang2021"), drive, fmus[drive], kind="me")
        runs = [pathsim_run(fmus["ddfs"], args.pathsim_time, use) for use in (False, True)]
        rows.append({"importer": "PathSim ESDIRK4 dt=0.1 ms", "scenario": "ddfs-0.5-16",
                     "duration_s": args.pathsim_time,
                     **{f"{k}_{tag}": r[k] for tag, r in zip(("without", "with"), runs,
                                                             strict=True)
                        for k in ("cpu_s", "derivatives", "tangents")},
                     "trace_dev_rel": _deviation(runs[0]["x"], runs[1]["x"])})
        print(json.dumps(rows[-1]), flush=True)
        for name, drive, vt, vn in (("cdfs-1.2", "cdfs", 1.2e-3, 0.0),
                                    ("ddfs-0.5-16", "ddfs", 0.5e-3, 16e-3)):
            runs = [cvode_run(fmus[drive], vt, vn, args.cvode_time, use)
                    for use in (False, True)]
            rows.append({"importer": "CVODE (fmpy's SUNDIALS) rtol 1e-8", "scenario": name,
                         "duration_s": args.cvode_time,
                         **{f"{k}_{tag}": r[k] for tag, r in zip(("without", "with"), runs,
                                                                 strict=True)
                            for k in ("cpu_s", "derivatives", "tangents", "steps",
                                      "jacobians")},
                         "trace_dev_rel": _deviation(runs[0]["x"], runs[1]["x"])})
            print(json.dumps(rows[-1]), flush=True)
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps({"machine": platform.processor() or platform.machine(),
                                   "python": platform.python_version(), "rows": rows},
                                  indent=2) + "\n", encoding="utf-8")
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
