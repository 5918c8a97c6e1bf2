"""The RODAS5 and RODAS5P prototypes of benchmarks/bench_rosenbrock_order.py: their tableaux
(G. Di Marzo 1993 and G. Steinebach 2023, the numbers as in OrdinaryDiffEq.jl's
``Rodas5Tableau`` and ``Rodas5PTableau``) and the generic Rosenbrock stepper have the orders
they claim, checked independently of the benchmark's run on the DDFS.

* feeddrive's order-condition check (``check_rosenbrock``: c_i and d_i against the matrices,
  every rooted tree's condition to the stated orders, 5 and 4) accepts RODAS5 (RODAS5P is the
  engine's tableau, checked when it is built);
* fixed-step convergence slopes on a smooth non-autonomous problem (reference: scipy DOP853 at
  rtol 1e-13) and on a stiff linear system (eigenvalues −0.5 ± 4i and −1e6; reference: the
  matrix exponential): 5 for RODAS5's and RODAS5P's solutions, 4 for their embedded ones;
  4 and 3 for RODAS4 through the same stepper (feeddrive's tableau: the stepper is not the
  tableau's accident).  On the linear problem the main solution converges with the order of
  the stability function R(z) as an approximation of e^z: 4, 5 and 6 (RODAS5P's
  R − e^z = O(z^7)), so there RODAS5P's slope is ≈ 6;
* L-stability: |R(−1e8)| tiny, |R(iy)| ≤ 1 on the imaginary axis;
* RODAS5P's continuous extension (rows h_2j … h_4j, evaluated in OrdinaryDiffEq.jl's form
  (1 − θ) y0 + θ (y1 + (1 − θ)(k1 + θ (k2 + θ k3)))): the largest error over θ ∈ [0.05, 0.95]
  falls with slope 5 in the step count both locally (each step from the exact solution:
  local error O(h^5), i.e. a dense output of order 4) and globally (min(5, 4 + 1)).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

_spec = importlib.util.spec_from_file_location(
    "bench_rosenbrock_order", ROOT / "benchmarks" / "bench_rosenbrock_order.py")
assert _spec is not None and _spec.loader is not None
bench = importlib.util.module_from_spec(_spec)
sys.modules["bench_rosenbrock_order"] = bench
_spec.loader.exec_module(bench)


@pytest.mark.parametrize("name", ["RODAS4", "RODAS5", "RODAS5P"])
def test_tableau_orders(name: str) -> None:
    method = getattr(bench, name)
    conv = bench.verify(method)  # asserts the slopes within 0.3 and the stability checks
    # and, stated here once more with the expected numbers
    p, q, r = {"RODAS4": (4, 3, 4), "RODAS5": (5, 4, 5), "RODAS5P": (5, 4, 6)}[name]
    assert abs(conv["nonstiff_main_slope"] - p) < 0.3
    assert abs(conv["nonstiff_embedded_slope"] - q) < 0.3
    assert abs(conv["linear_order"] - r) < 0.4
    assert abs(conv["stiff_main_slope"] - r) < 0.3
    assert abs(conv["stiff_embedded_slope"] - q) < 0.3
    assert conv["R_at_-1e8"] < 1e-6
    assert conv["max_R_imaginary_axis"] <= 1.0 + 1e-12
    if name == "RODAS5P":
        assert abs(conv["dense_local_slope"] - 5) < 0.3
        assert abs(conv["dense_global_slope"] - 5) < 0.3


def test_rodas5p_dense_output_ends() -> None:
    # θ = 0 and θ = 1 reproduce the step's ends; θ = 0.5 is within 1e-6 of the exact solution
    # of y' = −y + sin t over one step h = 0.1 (the dense output's local error ~ h^5)
    import math

    import numpy as np

    m = bench.RODAS5P

    def f(t: float, y: np.ndarray) -> np.ndarray:
        return -y + math.sin(t)

    y0, h = np.array([1.0]), 0.1
    y1, _, _, us = bench.rosenbrock_stages(m, f, 0.0, y0, h, f(0.0, y0), np.array([[-1.0]]),
                                           np.array([1.0]))
    assert bench.dense_output(m, y0, y1, us, 0.0) == pytest.approx(y0, abs=1e-15)
    assert bench.dense_output(m, y0, y1, us, 1.0) == pytest.approx(y1, abs=1e-15)

    def exact(t: float) -> float:  # y = 1.5 e^(−t) + (sin t − cos t)/2
        return 1.5 * math.exp(-t) + (math.sin(t) - math.cos(t)) / 2

    assert abs(y1[0] - exact(h)) < 1e-8
    mid = bench.dense_output(m, y0, y1, us, 0.5)[0]
    assert abs(mid - exact(0.05)) < 1e-6
    # and not the linear interpolation's (error ~ h²/8 · |y''| ≈ 2e-3)
    assert abs((y0[0] + y1[0]) / 2 - exact(0.05)) > 1e-4


def test_rodas5_is_more_accurate_than_rodas4_at_the_same_steps() -> None:
    # on the smooth problem, at every step count: the order-5 solutions' errors are below
    # RODAS4's
    e4 = bench.convergence(bench.RODAS4)["nonstiff_main_errors"]
    for m in (bench.RODAS5, bench.RODAS5P):
        e5 = bench.convergence(m)["nonstiff_main_errors"]
        assert all(b < a for a, b in zip(e4, e5, strict=True))


def test_a_wrong_coefficient_is_caught() -> None:
    # the checks can fail: one RODAS5 coefficient off in its 4th digit
    import dataclasses

    bad = dataclasses.replace(bench.RODAS5, cc=(*bench.RODAS5.cc[:3],
                                                (32.2275, *bench.RODAS5.cc[3][1:]),
                                                *bench.RODAS5.cc[4:]))
    with pytest.raises(Exception):  # noqa: B017 - OrderConditionError or AssertionError
        bench.verify(bad)


def test_a_wrong_dense_coefficient_is_caught() -> None:
    # one of RODAS5P's dense-output numbers off in its 4th digit: the order-4 extension is lost
    import dataclasses

    rows = bench.RODAS5P.dense
    bad = dataclasses.replace(bench.RODAS5P, dense=(rows[0], (-9.915, *rows[1][1:]), rows[2]))
    with pytest.raises(AssertionError):
        bench.verify(bad)
