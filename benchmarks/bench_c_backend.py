"""Right-hand-side evaluations per second: numba (the generated module) vs the C backend.

Both run the same workload in a compiled loop — ``n`` evaluations of the model's right-hand
side at stored (t, y) points with continuous loops, the auxiliary outputs written to a row per
point: a numba loop calling the generated module's ``rhs`` (``y[i]``/``out[i]`` row views)
and the same loop in C appended to ``c_model_source(model)`` (compiled -O2, as an FMU would
be).  The two are checked to give identical outputs.  CPU time (``process_time``), median of
``--runs`` rounds, interleaved.  Results: results/bench_c_backend.json, benchmarks/README.md.

    python benchmarks/bench_c_backend.py [--runs 7] [--points 200000]
"""

from __future__ import annotations

import argparse
import ctypes
import json
import platform
import statistics
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

import feeddrive as fd
from feeddrive.backends.c_backend import c_model_source, compile_shared

DRIVER = """
void fd_bench(long n, const double *t, const double *y, const double *P, const double *T,
              double *out)
{
    double held[FD_N_HELD] = {0.0};
    double dy[FD_N_STATE];
    for (long i = 0; i < n; ++i)
        fd_rhs(t[i], y + i * FD_N_STATE, held, P, T, dy, out + i * FD_N_AUX);
}
"""

def numba_loop(rhs: object) -> object:
    """The C driver's loop, in numba, around the model's compiled ``rhs``."""

    @numba.njit(error_model="numpy")
    def loop(t, y, held, P, T, out):  # type: ignore[no-untyped-def]
        dy = np.empty(y.shape[1])
        for i in range(t.size):
            rhs(t[i], y[i], held, P, T, dy, out[i])

    return loop


SCENARIOS = {
    "wang2021-ddfs": lambda: fd.DriveSystem(fd.preset("wang2021"), "ddfs", 0.4).model(
        fd.ConstantSpeed(0.5e-3, 16e-3)),
    "wang2021-cdfs": lambda: fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4).model(
        fd.ConstantSpeed(1.2e-3)),
    "linear-motor": lambda: fd.DriveSystem(fd.preset("linear-motor-example"), "linear-motor",
                                           0.4).model(fd.ConstantSpeed(2e-3)),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--points", type=int, default=200_000)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" /
                                         "bench_c_backend.json"))
    args = ap.parse_args()
    folder = Path(tempfile.mkdtemp(prefix="bench_c_"))
    results = {}
    for name, build in SCENARIOS.items():
        model = build()
        n, n_aux = len(model.states), len(model.aux)
        lib_path = compile_shared(c_model_source(model) + DRIVER, folder,
                                  name=name.replace("-", "_"), optimise="-O2")
        lib = ctypes.CDLL(str(lib_path))
        rng = np.random.default_rng(0)
        atol, _ = model.tolerances(1e-3, 1e-3, 1.0)
        t = np.ascontiguousarray(rng.uniform(0.0, 2.0, args.points))
        y = np.ascontiguousarray(rng.normal(size=(args.points, n)) * atol)
        out_c = np.empty((args.points, n_aux))
        ptr = [a.ctypes.data_as(ctypes.c_void_p) for a in (t, y, model.P, model.T, out_c)]
        out_n = np.empty((args.points, n_aux))
        loop = numba_loop(model.module.rhs)
        held = np.zeros(model.n_held)
        loop(t[:10], y[:10], held, model.P, model.T, out_n[:10])  # compile
        times: dict[str, list[float]] = {"numba": [], "c": []}
        for _ in range(args.runs):
            start = time.process_time()
            loop(t, y, held, model.P, model.T, out_n)
            times["numba"].append(time.process_time() - start)
            start = time.process_time()
            lib.fd_bench(ctypes.c_long(args.points), *ptr)
            times["c"].append(time.process_time() - start)
        assert np.array_equal(out_n, out_c), "numba and C outputs differ"
        med = {k: statistics.median(v) for k, v in times.items()}
        results[name] = {"states": n, "points": args.points,
                         "numba_per_s": args.points / med["numba"],
                         "c_per_s": args.points / med["c"],
                         "c_over_numba": med["numba"] / med["c"]}
        r = results[name]
        print(f"{name:15s} {n:2d} states: numba {r['numba_per_s']:.3g}/s, "
              f"C {r['c_per_s']:.3g}/s, C/numba speed {r['c_over_numba']:.2f}")
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps({"machine": platform.processor() or platform.machine(),
                                          "python": platform.python_version(),
                                          "runs": args.runs, "results": results}, indent=1),
                              encoding="utf-8")


if __name__ == "__main__":
    main()
