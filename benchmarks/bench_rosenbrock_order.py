"""Feasibility study: would a 5th-order Rosenbrock method (RODAS5, RODAS5P) take materially
fewer steps than RODAS4 on the DDFS's stiff settling stretch?  A plain-Python prototype
(numpy/scipy on ``reference.scipy_model.ReferenceModel``), not a change to feeddrive's engine.

Run from the repository root::

    python benchmarks/bench_rosenbrock_order.py [--quick]

The run: ``wang2021`` DDFS, table at 0.4 m, ``ConstantSpeed(0.5e-3, 16e-3)`` (table 0.5 mm/s,
hollow motor 16 mm/s), the stretch t = 1 … 3 s (a lightly damped 4.5-Hz settling; no friction
reversal in it: feeddrive's runs to 1 s and to 3 s locate the same 11 crossings), and the
stretch after it, t = 3 … 10 s (where feeddrive's ``modal`` runs all-RODAS4).

1. Start state y(1) and reference end state y(3): scipy ``solve_ivp(method="Radau")`` on the
   reference model with the settings of ``reference/make_accuracy_reference.py`` (rtol 1e-11,
   absolute tolerances 1e-4 × ``ReferenceModel.tolerances()``: 1e-14 m, 1e-12 m/s, 1e-10 A),
   in pieces [0, 0.1] (the start ramp), [0.1, 1], [1, 3], [3, 10], so that y(1), y(3) and
   y(10) are step ends, not interpolated.  A check run at rtol 1e-12 and 1e-5 × bounds the
   reference's own error at t = 3 and 10 and over both stretches.
2. Tolerances: feeddrive's default per-state absolute tolerances and relative mask for this
   run (``feeddrive.engine.simulate.Simulation(...).atol``, ``.rel``; rtol 1e-6), mapped by
   state name onto the reference model (the two models name their 15 states alike; the
   mapping is by name all the same and asserted complete).  The error norm is feeddrive's
   (``feeddrive.solvers.steps.error_norm_template``): RMS of
   e_i / (atol_i + rtol·rel_i·max(|y_i|, |y_new,i|)).  "Accuracy 0.1": every tolerance × 0.1
   (rtol too, as ``SolverOptions(accuracy=0.1)``).
3. One generic Rosenbrock stepper, Hairer & Wanner II, Sect. IV.7, form (7.25) (the one
   ``feeddrive/solvers/rodas4.py``'s docstring writes out)::

       (I/(γh) − J) u_i = f(t + c_i h, y + Σ_{j<i} a_ij u_j) + Σ_{j<i} (c_ij/h) u_j + d_i h f_t

   for stiffly accurate methods (y_1 = last stage argument + u_S, error estimate u_S), a fresh
   Jacobian every step (``ReferenceModel.jacobian``: central differences, 2·15 right-hand
   sides) and f_t by a central difference (2 right-hand sides), one ``scipy.linalg.lu_factor``
   per attempted step.  Two step-size controllers, the same for both methods, q = embedded
   order + 1 (the order of the error estimate's leading term: 4 for RODAS4, 5 for RODAS5):

   * ``standard``: h_new = h·min(5, max(0.2, 0.9·err^(−1/q))); no growth right after a
     rejection; a rejected step is retried with max(0.2, 0.9·err^(−1/q));
   * ``gustafsson``: ``rodas.f``'s (and feeddrive's ``step_size``): fac = clip(err^(1/q)/0.9,
     1/6, 5), the predictive factor (h_old/h)·(err²/err_old)^(1/q)/0.9 when larger, h/fac.

   RODAS4: the numbers of ``feeddrive.solvers.tableaux.RODAS4`` (Hairer & Wanner, rodas.f).
   RODAS5: G. Di Marzo's RODAS5(4) (1993; the method of OrdinaryDiffEq.jl's ``Rodas5``), the
   numbers as in OrdinaryDiffEq.jl ``src/tableaus/rosenbrock_tableaus.jl`` (as stored at commit
   03e19047a644; ``Rodas5Tableau``; its stage
   equations use the same u-form and signs, as its RODAS4 numbers equal rodas.f's), 8 stages,
   γ = 0.19, a_7 = (a_6, 1), a_8 = (a_7, 1), c_6 = c_7 = c_8 = 1, d_6 = d_7 = d_8 = 0.
   RODAS5P: G. Steinebach's Rodas5P (BIT 63:27, 2023), the numbers as in OrdinaryDiffEq.jl
   ``lib/OrdinaryDiffEqRosenbrock/src/rosenbrock_tableaus.jl`` (as stored at commit
   0054db222947; ``Rodas5PTableau``; since 2026-12-05 read from the engine's
   ``feeddrive.solvers.tableaux.RODAS5P``), the same structure (8 stages, order 5, embedded 4,
   γ = 0.2119…), and three dense-output rows h_2j, h_3j, h_4j evaluated in the form of
   OrdinaryDiffEq.jl's ``rosenbrock_interpolants.jl`` (our code):
   y(t + θh) = (1 − θ) y0 + θ (y1 + (1 − θ)(k1 + θ (k2 + θ k3))), k_i = Σ_j h_(i+1)j u_j.
4. The tableaux are verified before use (asserted): feeddrive's order-condition check
   (``check_rosenbrock``, every rooted tree to the stated orders, also c_i and d_i against
   the matrices)
   on RODAS5 and RODAS5P; fixed-step convergence on a smooth non-stiff, non-autonomous problem
   (slopes ≈ 5 main, ≈ 4 embedded for RODAS5 and RODAS5P; 4 and 3 for RODAS4) and on a stiff
   linear system with eigenvalues −0.5 ± 4i and −1e6 (main: the order of R(z) against e^z, 4,
   5 and 6 — RODAS5P's R − e^z = O(z^7); embedded ≈ 4 / 3); the stability function
   R(z) → 0 at z = −1e8 and |R(iy)| ≤ 1 (L-stable).  RODAS5P's dense output: the largest
   error over θ = 0.05 … 0.95 on the smooth problem falls with slope 5 locally (each step
   from the exact solution; a continuous extension of order 4 has local error O(h^5)) and
   globally (min(p, 4 + 1) = 5).
5. DOPRI5 on the same stretch: the same prototype (feeddrive's DOPRI5 tableau, its PI
   controller α = 0.17, β = 0.04, limits 0.2 … 5, the same norm), and feeddrive's own counts
   from runs to 1 s and to 3 s (``dopri5-dense``, ``modal``, ``rodas4``; C build), and
   ``modal``'s and ``rodas4``'s over 3 … 10 s (runs to 3 and 10 s).

Cost in DOPRI5-step equivalents: a RODAS4 step = 5 DOPRI5 steps (feeddrive's measured
``RODAS4_COST``, ``benchmarks/bench_switch_cost.py``), a RODAS5 step = 5 × 8/6 (assumption: the
cost scales with the stages — 8 right-hand sides and 8 triangular solves against 6; the
Jacobian and the LU, the same for both, are part of the measured 5, so the true ratio is
below 8/6); RODAS5P the same (8 stages).  Writes
``benchmarks/results/bench_rosenbrock_order.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import scipy.linalg
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.scipy_model import ReferenceModel  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.engine.simulate import Simulation  # noqa: E402
from feeddrive.solvers import tableaux  # noqa: E402
from feeddrive.solvers.order_conditions import check_rosenbrock  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
T0, T1 = 1.0, 3.0  # the stretch [s]
T2 = 10.0  # the end of the second stretch, [3, 10] s
RAMP = 0.1  # ConstantSpeed's default start ramp [s]
RODAS4_COST = 5.0  # DOPRI5 steps per RODAS4 step (feeddrive.solvers.driver.RODAS4_COST)


# ---------------------------------------------------------------- tableaux


@dataclass(frozen=True)
class Rosenbrock:
    """A stiffly accurate Rosenbrock method in Hairer & Wanner's u-form (IV.7 (7.25))."""

    name: str
    order: int
    embedded_order: int
    gamma: float
    c: tuple[float, ...]
    a: tuple[tuple[float, ...], ...]  # row s: a_s1 … a_s,s-1
    cc: tuple[tuple[float, ...], ...]  # row s: c_s1 … c_s,s-1
    d: tuple[float, ...]  # weight of h·f_t per stage
    # continuous extension: rows h_2j, h_3j, h_4j (k_1, k_2, k_3 = Σ_j h_ij u_j); () if none
    dense: tuple[tuple[float, ...], ...] = ()

    @property
    def stages(self) -> int:
        return len(self.c)


R4 = tableaux.RODAS4
RODAS4 = Rosenbrock("RODAS4", R4.order, R4.embedded_order, R4.gamma, tuple(R4.c),
                    tuple(tuple(r) for r in R4.a), tuple(tuple(r) for r in R4.cc), tuple(R4.d))

# Di Marzo (1993), as in OrdinaryDiffEq.jl's Rodas5Tableau (numbers only)
_A6 = (-14.09640773051259, 6.925207756232704, -41.47510893210728, 2.343771018586405,
       24.13215229196062)
RODAS5 = Rosenbrock(
    "RODAS5", 5, 4, 0.19,
    c=(0.0, 0.38, 0.3878509998321533, 0.4839718937873840, 0.4570477008819580, 1.0, 1.0, 1.0),
    a=((),
       (2.0,),
       (3.040894194418781, 1.041747909077569),
       (2.576417536461461, 1.622083060776640, -0.9089668560264532),
       (2.760842080225597, 1.446624659844071, -0.3036980084553738, 0.2877498600325443),
       _A6,
       (*_A6, 1.0),
       (*_A6, 1.0, 1.0)),
    cc=((),
        (-10.31323885133993,),
        (-21.04823117650003, -7.234992135176716),
        (32.22751541853323, -4.943732386540191, 19.44922031041879),
        (-20.69865579590063, -8.816374604402768, 1.260436877740897, -0.7495647613787146),
        (-46.22004352711257, -17.49534862857472, -289.6389582892057, 93.60855400400906,
         318.3822534212147),
        (34.20013733472935, -14.15535402717690, 57.82335640988400, 25.83362985412365,
         1.408950972071624, -6.551835421242162),
        (42.57076742291101, -13.80770672017997, 93.98938432427124, 18.77919633714503,
         -31.58359187223370, -6.685968952921985, -5.810979938412932)),
    d=(0.19, -0.1823079225333714636, -0.319231832186874912, 0.3449828624725343,
       -0.377417564392089818, 0.0, 0.0, 0.0))


# G. Steinebach (2023), "Construction of Rosenbrock-Wanner method Rodas5P and numerical
# benchmarks within the Julia Differential Equations package", BIT 63:27: since 2026-12-05 the
# engine's own tableau (feeddrive.solvers.tableaux.RODAS5P, the numbers of OrdinaryDiffEq.jl's
# Rodas5PTableau, its order conditions checked when built), read here as RODAS4's is.
R5P = tableaux.RODAS5P
RODAS5P = Rosenbrock("RODAS5P", R5P.order, R5P.embedded_order, R5P.gamma, tuple(R5P.c),
                     tuple(tuple(r) for r in R5P.a), tuple(tuple(r) for r in R5P.cc),
                     tuple(R5P.d), tuple(tuple(r) for r in R5P.dense))
METHODS = (RODAS4, RODAS5, RODAS5P)


def rosenbrock_step(m: Rosenbrock, f: Any, t: float, y: np.ndarray, h: float, f0: np.ndarray,
                    J: np.ndarray, ft: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """(y_new, error estimate u_S, right-hand sides called) of one step of ``m``."""
    y_new, e, calls, _ = rosenbrock_stages(m, f, t, y, h, f0, J, ft)
    return y_new, e, calls


def dense_output(m: Rosenbrock, y0: np.ndarray, y1: np.ndarray, us: list[np.ndarray],
                 theta: float) -> np.ndarray:
    """The continuous extension at t + θh, the form OrdinaryDiffEq.jl evaluates for its Rodas
    methods with three rows (``rosenbrock_interpolants.jl``, interp_order 3):
    y(θ) = (1 − θ) y0 + θ (y1 + (1 − θ)(k1 + θ (k2 + θ k3))), k_i = Σ_j h_(i+1)j u_j."""
    k1, k2, k3 = (sum(hj * u for hj, u in zip(row, us, strict=True)) for row in m.dense)
    return (1 - theta) * y0 + theta * (y1 + (1 - theta) * (k1 + theta * (k2 + theta * k3)))


def rosenbrock_stages(m: Rosenbrock, f: Any, t: float, y: np.ndarray, h: float,
                      f0: np.ndarray, J: np.ndarray, ft: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, int, list[np.ndarray]]:
    """``rosenbrock_step`` and the stage increments u_1 … u_S (for the dense output)."""
    n = y.size
    lu = scipy.linalg.lu_factor(np.eye(n) / (m.gamma * h) - J)
    us: list[np.ndarray] = []
    ys = y
    calls = 0
    for s in range(m.stages):
        if s == 0:
            fs = f0
        else:
            ys = y + sum(a * u for a, u in zip(m.a[s], us, strict=True))
            fs = f(t + m.c[s] * h, ys)
            calls += 1
        rhs = fs + sum(cij / h * u for cij, u in zip(m.cc[s], us, strict=True))
        if m.d[s] != 0.0:
            rhs = rhs + m.d[s] * h * ft
        us.append(scipy.linalg.lu_solve(lu, rhs))
    return ys + us[-1], us[-1], calls, us


def error_norm(e: np.ndarray, y: np.ndarray, y_new: np.ndarray, rtol: float, atol: np.ndarray,
               rel: np.ndarray) -> float:
    """feeddrive's norm (``feeddrive.solvers.steps.error_norm_template``)."""
    scale = atol + rtol * rel * np.maximum(np.abs(y), np.abs(y_new))
    err = float(np.sqrt(np.mean((e / scale) ** 2)))
    return err if math.isfinite(err) else 1e10


@dataclass
class Counts:
    accepted: int = 0
    rejected: int = 0
    stage_rhs: int = 0  # right-hand sides of the stages (and f(t, y) of each new step)
    jacobian_rhs: int = 0  # of the Jacobians and f_t
    lu: int = 0
    # per state, the accepted steps whose weighted error it dominated
    dominant: dict[str, int] = field(default_factory=dict)
    # (t, x_t, v_t) after each accepted step
    trace: list[tuple[float, float, float]] = field(default_factory=list)


def _sample(model: ReferenceModel, t: float, y: np.ndarray) -> tuple[float, float, float]:
    return t, float(y[model.index["table_position"]]), float(y[model.index["table_speed"]])


def integrate_rosenbrock(m: Rosenbrock, model: ReferenceModel, y0: np.ndarray, t0: float,
                         t1: float, rtol: float, atol: np.ndarray, rel: np.ndarray,
                         controller: str = "standard", h0: float = 1e-3
                         ) -> tuple[np.ndarray, Counts]:
    """y(t1) and the counts of an adaptive run of ``m`` from (t0, y0)."""
    f = model.rhs
    q = m.embedded_order + 1
    cnt = Counts()
    t, y, h = t0, np.array(y0, dtype=float), h0
    f0 = f(t, y)
    cnt.stage_rhs += 1
    n = y.size
    first, rejected_last = True, False
    h_old = err_old = 0.0
    need_jac = True
    J = ft = np.empty(0)
    while t < t1:
        last = t + h >= t1 - 1e-15 * t1
        h_try = t1 - t if last else h
        if need_jac:
            J = model.jacobian(t, y)
            dt = 1e-6 * max(1.0, abs(t))
            ft = (f(t + dt, y) - f(t - dt, y)) / (2 * dt)
            cnt.jacobian_rhs += 2 * n + 2
            need_jac = False
        y_new, e, calls = rosenbrock_step(m, f, t, y, h_try, f0, J, ft)
        cnt.stage_rhs += calls
        cnt.lu += 1
        err = error_norm(e, y, y_new, rtol, atol, rel)
        if err <= 1.0:
            cnt.accepted += 1
            scale = atol + rtol * rel * np.maximum(np.abs(y), np.abs(y_new))
            top = model.state_names[int(np.argmax(np.abs(e) / scale))]
            cnt.dominant[top] = cnt.dominant.get(top, 0) + 1
            if controller == "standard":
                fac = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.9 * err ** (-1.0 / q)))
                if rejected_last:
                    fac = min(fac, 1.0)
                h_new = h_try * fac
            else:  # gustafsson (rodas.f; feeddrive.solvers.driver.step_size)
                div = 0.2 if err == 0.0 else max(1 / 6, min(5.0, err ** (1.0 / q) / 0.9))
                if not first and err > 0.0:
                    pred = (h_old / h_try) * (err * err / err_old) ** (1.0 / q) / 0.9
                    div = max(div, max(1 / 6, min(5.0, pred)))
                h_new = h_try / div
                if rejected_last:
                    h_new = min(h_new, h_try)
                h_old, err_old = h_try, max(1e-2, err)
            first, rejected_last = False, False
            t = t1 if last else t + h_try
            y = y_new
            cnt.trace.append(_sample(model, t, y))
            f0 = f(t, y)
            cnt.stage_rhs += 1
            need_jac = True
            if not last or h_new < h:
                h = h_new
        else:
            cnt.rejected += 1
            if controller == "standard":
                h = h_try * max(0.2, 0.9 * err ** (-1.0 / q))
            else:
                h = h_try / max(1 / 6, min(5.0, err ** (1.0 / q) / 0.9))
                if first:
                    h = 0.1 * h_try
            rejected_last = True
    return y, cnt


def integrate_dopri5(model: ReferenceModel, y0: np.ndarray, t0: float, t1: float, rtol: float,
                     atol: np.ndarray, rel: np.ndarray, h0: float = 1e-4
                     ) -> tuple[np.ndarray, Counts]:
    """DOPRI5 (feeddrive's tableau) with Hairer's PI controller and the same norm."""
    tab = tableaux.DOPRI5
    f = model.rhs
    beta = 0.04
    alpha = 0.2 - 0.75 * beta
    cnt = Counts()
    t, y, h = t0, np.array(y0, dtype=float), h0
    k1 = f(t, y)
    cnt.stage_rhs += 1
    err_old = 1e-4
    rejected_last = False
    while t < t1:
        last = t + h >= t1 - 1e-15 * t1
        h_try = t1 - t if last else h
        ks = [k1]
        for s in range(1, len(tab.c)):
            ys = y + h_try * sum(a * k for a, k in zip(tab.a[s], ks, strict=True))
            ks.append(f(t + tab.c[s] * h_try, ys))
        y_new = y + h_try * sum(b * k for b, k in zip(tab.b, ks, strict=True))
        k_new = f(t + h_try, y_new)
        cnt.stage_rhs += len(tab.c)
        e = h_try * sum(w * k for w, k in zip(tab.e, [*ks, k_new], strict=True))
        err = error_norm(e, y, y_new, rtol, atol, rel)
        if err <= 1.0:
            cnt.accepted += 1
            fac = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.9 * err ** (-alpha) * err_old ** beta))
            if rejected_last:
                fac = min(fac, 1.0)
            err_old = max(err, 1e-4)
            h_new = h_try * fac
            t = t1 if last else t + h_try
            y, k1 = y_new, k_new
            cnt.trace.append(_sample(model, t, y))
            rejected_last = False
            if not last or h_new < h:
                h = h_new
        else:
            cnt.rejected += 1
            h = h_try * max(0.2, 0.9 * err ** -0.2)
            rejected_last = True
    return y, cnt


# ---------------------------------------------------------------- tableau checks


def _fixed_steps(m: Rosenbrock, f: Any, jac: Any, dfdt: Any, y0: np.ndarray, t_end: float,
                 n: int, embedded: bool) -> np.ndarray:
    y, h = np.array(y0, dtype=float), t_end / n
    for k in range(n):
        t = k * h
        y_new, e, _ = rosenbrock_step(m, f, t, y, h, f(t, y), jac(t, y), dfdt(t, y))
        y = y_new - e if embedded else y_new
    return y


def _slope(errors: list[float], ns: list[int]) -> float:
    return float(-np.polyfit(np.log(ns), np.log(errors), 1)[0])


def convergence(m: Rosenbrock) -> dict[str, Any]:
    """Fixed-step convergence slopes of ``m`` (main and embedded) on a smooth non-stiff
    non-autonomous problem and on a stiff linear one; its stability function at two points."""
    # non-stiff: a forced, weakly nonlinear oscillator, 0 ≤ t ≤ 2 (reference: DOP853 1e-13)
    def f(t: float, y: np.ndarray) -> np.ndarray:
        return np.array([y[1], -y[0] - 0.3 * y[1] * (1 - y[0] ** 2) + 0.5 * math.cos(2 * t)])

    def jac(t: float, y: np.ndarray) -> np.ndarray:
        return np.array([[0.0, 1.0], [-1.0 + 0.6 * y[0] * y[1], -0.3 * (1 - y[0] ** 2)]])

    def dfdt(t: float, y: np.ndarray) -> np.ndarray:
        return np.array([0.0, -math.sin(2 * t)])

    y0 = np.array([1.0, 0.0])
    exact = solve_ivp(f, (0, 2), y0, method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1]
    ns = [20, 28, 40, 56, 80]
    out: dict[str, Any] = {"nonstiff_steps": ns}
    for emb in (False, True):
        errs = [float(np.max(np.abs(_fixed_steps(m, f, jac, dfdt, y0, 2.0, n, emb) - exact)))
                for n in ns]
        key = "embedded" if emb else "main"
        out[f"nonstiff_{key}_errors"] = errs
        out[f"nonstiff_{key}_slope"] = _slope(errs, ns)
    if m.dense:
        # the continuous extension, on the same problem and steps: the largest error over
        # θ = 0.05, 0.1, … 0.95 of every step, (a) local: each step started from the exact
        # y(t_k) (a dense output of order p* has local error O(h^(p*+1)): slope p* + 1 = 5
        # for p* = 4), (b) global: along the fixed-step solution (slope min(p, p* + 1) = 5)
        ref = solve_ivp(f, (0, 2), y0, method="DOP853", rtol=1e-13, atol=1e-15,
                        dense_output=True).sol
        thetas = np.linspace(0.05, 0.95, 19)
        for kind in ("local", "global"):
            errs = []
            for n in ns:
                h, y, worst = 2.0 / n, y0.copy(), 0.0
                for k in range(n):
                    t = k * h
                    if kind == "local":
                        y = ref(t)
                    y1, _, _, us = rosenbrock_stages(m, f, t, y, h, f(t, y), jac(t, y),
                                                     dfdt(t, y))
                    for th in thetas:
                        worst = max(worst, float(np.max(np.abs(
                            dense_output(m, y, y1, us, th) - ref(t + th * h)))))
                    y = y1
                errs.append(worst)
            out[f"dense_{kind}_errors"] = errs
            out[f"dense_{kind}_slope"] = _slope(errs, ns)
    # stiff linear: eigenvalues −0.5 ± 4i and −1e6, y(t) = expm(A t) y0, 0 ≤ t ≤ 2
    V = np.array([[1.0, 0.5, 0.2], [0.3, 1.0, 0.1], [0.4, 0.2, 1.0]])
    B = np.array([[-0.5, 4.0, 0.0], [-4.0, -0.5, 0.0], [0.0, 0.0, -1e6]])
    A = V @ B @ np.linalg.inv(V)
    y0s = np.array([1.0, 2.0, 3.0])
    exact_s = scipy.linalg.expm(2.0 * A) @ y0s
    ns_s = [16, 23, 32, 45, 64]
    for emb in (False, True):
        errs = [float(np.max(np.abs(_fixed_steps(
            m, lambda t, y: A @ y, lambda t, y: A, lambda t, y: np.zeros(3), y0s, 2.0, n, emb)
            - exact_s))) for n in ns_s]
        key = "embedded" if emb else "main"
        out[f"stiff_{key}_errors"] = errs
        out[f"stiff_{key}_slope"] = _slope(errs, ns_s)
    out["stiff_steps"] = ns_s

    # stability function R(z): one step of y' = z y from y = 1, h = 1
    def R(z: complex) -> complex:
        lu = scipy.linalg.lu_factor(np.array([[1 / m.gamma - z]], dtype=complex))
        us: list[complex] = []
        ys: complex = 1.0
        for s in range(m.stages):
            ys = 1.0 + sum(a * u for a, u in zip(m.a[s], us, strict=True))
            rhs = z * ys + sum(cij * u for cij, u in zip(m.cc[s], us, strict=True))
            us.append(complex(scipy.linalg.lu_solve(lu, np.array([rhs]))[0]))
        return ys + us[-1]

    out["R_at_-1e8"] = abs(R(-1e8))
    # the order of R(z) as an approximation of e^z (R − e^z = O(z^(r+1))): the order on linear
    # constant-coefficient problems, hence the stiff linear slope; ≥ p, can be more
    out["linear_order"] = math.log2(abs(R(0.2) - math.exp(0.2)) / abs(R(0.1) - math.exp(0.1))) - 1
    out["max_R_imaginary_axis"] = max(abs(R(1j * y)) for y in np.geomspace(1e-3, 1e4, 200))
    # numerical damping ratio ζ_num = −ln|R(iy)|/y at the modal cap h|λ| = 0.35
    # (feeddrive.solvers.modes.H_LAMBDA; RODAS4's 4.4e-7 there) and at 0.7
    for y in (0.35, 0.7):
        out[f"zeta_num_{y}"] = -math.log(abs(R(1j * y))) / y
    return out


def verify(m: Rosenbrock) -> dict[str, Any]:
    """Assert the tableau's orders; returns the figures."""
    # feeddrive's checker: c_i, d_i against the matrices and every rooted tree's condition to
    # each solution's order (order 5 for RODAS5 and RODAS5P since 2026-12-05)
    check_rosenbrock(tableaux.RosenbrockTableau(
        name=m.name.lower(), order=m.order, embedded_order=m.embedded_order,
        gamma=m.gamma, c=m.c, a=m.a, cc=m.cc, d=m.d, dense=()))
    conv = convergence(m)
    p, q = m.order, m.embedded_order
    # on the stiff linear problem the main solution converges with R's order (RODAS5P's
    # R − e^z = O(z^7): slope ≈ 6 there), asserted ≥ p
    r = round(conv["linear_order"])
    assert r >= p, (m.name, conv)
    for key, want in (("nonstiff_main", p), ("nonstiff_embedded", q), ("stiff_main", r),
                      ("stiff_embedded", q)):
        assert abs(conv[f"{key}_slope"] - want) < 0.3, (m.name, key, conv)
    assert conv["R_at_-1e8"] < 1e-6, (m.name, conv)
    assert conv["max_R_imaginary_axis"] <= 1.0 + 1e-12, (m.name, conv)
    if m.dense:  # a continuous extension of order 4: local error slope 5, global 5
        assert abs(conv["dense_local_slope"] - 5) < 0.3, (m.name, conv)
        assert abs(conv["dense_global_slope"] - 5) < 0.3, (m.name, conv)
    return conv


# ---------------------------------------------------------------- the DDFS stretch


def setup(options: Any = None) -> dict[str, Any]:
    """The reference model and feeddrive's tolerances for it (``options``: default ones)."""
    params = fd.preset("wang2021")
    profile = fd.ConstantSpeed(0.5e-3, 16e-3)
    model = ReferenceModel(params, "ddfs", 0.4, profile)
    sim = Simulation(fd.DriveSystem(params, "ddfs", 0.4), profile, options)
    names = tuple(sim.model.state_names)
    missing = set(model.state_names) ^ set(names)
    assert not missing, f"state names differ: {missing}"
    index = [names.index(s) for s in model.state_names]  # by name
    atol = np.asarray(sim.atol, dtype=float)[index]
    rel = np.asarray(sim.rel, dtype=float)[index]
    return {"model": model, "atol": atol, "rel": rel, "rtol": sim.tolerances.rtol,
            "same_order": names == tuple(model.state_names), "params": params,
            "profile": profile}


def radau_pieces(model: ReferenceModel, rtol: float, atol_scale: float
                 ) -> tuple[dict[float, np.ndarray], dict[float, Any]]:
    """States at 1, 3 and 10 s, and the dense solutions on [1, 3] and [3, 10] (keyed by their
    start), by Radau split at 0.1, 1 and 3 s (every state a step end)."""
    atol = model.tolerances() * atol_scale
    y = np.zeros(model.n_state)
    states, sols = {}, {}
    for a, b in ((0.0, RAMP), (RAMP, T0), (T0, T1), (T1, T2)):
        sol = solve_ivp(model.rhs, (a, b), y, method="Radau", rtol=rtol, atol=atol,
                        jac=model.jacobian, dense_output=a >= T0)
        assert sol.status == 0, sol.message
        y = sol.y[:, -1].copy()
        states[b] = y
        sols[a] = sol
    return states, sols


def feeddrive_counts(methods: tuple[str, ...] = ("dopri5-dense", "modal", "rodas4"),
                     span: tuple[float, float] = (T0, T1),
                     **options: Any) -> dict[str, dict[str, int]]:
    """Accepted/rejected steps of feeddrive's methods over ``span`` (runs to its two ends)."""
    params = fd.preset("wang2021")
    system = fd.DriveSystem(params, "ddfs", 0.4)
    profile = fd.ConstantSpeed(0.5e-3, 16e-3)
    out = {}
    for method in methods:
        opts = fd.SolverOptions(method=method, **options)
        s1 = fd.simulate(system, profile, span[0], options=opts).solver_stats
        s3 = fd.simulate(system, profile, span[1], options=opts).solver_stats
        out[method] = {k: int(s3[k] - s1[k]) for k in
                       ("steps", "rejected_steps", "rosenbrock_steps", "rhs_evaluations",
                        "jacobians", "switch_crossings")}
    return out


def _stretch_errors(trace: list[tuple[float, float, float]], sol: Any, ix: int,
                    iv: int) -> dict[str, float]:
    """The largest differences over the accepted step points from Radau's dense output."""
    t, x, v = (np.array(c) for c in zip(*trace, strict=True))
    ref = sol.sol(t)
    return {"max_error_table_position": float(np.max(np.abs(x - ref[ix]))),
            "max_error_table_speed": float(np.max(np.abs(v - ref[iv])))}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="skip the check run of the Radau reference")
    args = ap.parse_args(argv)
    load0 = os.getloadavg()
    started = time.perf_counter()
    record: dict[str, Any] = {"date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime())}

    checks = {m.name: verify(m) for m in METHODS}
    record["tableau_checks"] = checks
    for name, c in checks.items():
        print(f"{name}: non-stiff slopes {c['nonstiff_main_slope']:.2f} / "
              f"{c['nonstiff_embedded_slope']:.2f} (main / embedded), stiff linear "
              f"{c['stiff_main_slope']:.2f} / {c['stiff_embedded_slope']:.2f}, "
              f"|R(-1e8)| {c['R_at_-1e8']:.1e}, max |R(iy)| {c['max_R_imaginary_axis']:.6f}"
              + (f", dense output local / global {c['dense_local_slope']:.2f} / "
                 f"{c['dense_global_slope']:.2f}" if "dense_local_slope" in c else ""),
              flush=True)

    s = setup()
    model, atol, rel, rtol = s["model"], s["atol"], s["rel"], s["rtol"]
    record["state_names"] = list(model.state_names)
    record["same_state_order"] = s["same_order"]
    record["atol"], record["rel"], record["rtol"] = atol.tolist(), rel.tolist(), rtol

    tick = time.perf_counter()
    states, sols = radau_pieces(model, 1e-11, 1e-4)
    record["radau_wall_s"] = time.perf_counter() - tick
    ix, iv = model.index["table_position"], model.index["table_speed"]
    spans = {"1-3": (T0, T1), "3-10": (T1, T2)}
    grids = {k: np.linspace(a, b, 1001 * round(b - a) + 1) for k, (a, b) in spans.items()}
    dense = {k: sols[a].sol(grids[k]) for k, (a, _) in spans.items()}
    record["ranges"] = {k: {"table_position": float(np.ptp(d[ix])),
                            "table_speed": float(np.ptp(d[iv]))} for k, d in dense.items()}
    if not args.quick:
        states_c, sols_c = radau_pieces(model, 1e-12, 1e-5)
        record["reference_error"] = {}
        for k, (a, b) in spans.items():
            dense_c = sols_c[a].sol(grids[k])
            record["reference_error"][k] = {
                "table_position": float(abs(states_c[b][ix] - states[b][ix])),
                "table_speed": float(abs(states_c[b][iv] - states[b][iv])),
                "max_over_stretch_table_position": float(np.max(np.abs(dense_c[ix]
                                                                       - dense[k][ix]))),
                "max_over_stretch_table_speed": float(np.max(np.abs(dense_c[iv]
                                                                    - dense[k][iv])))}
            e = record["reference_error"][k]
            print(f"Radau reference vs check at t = {b:g}: x_t {e['table_position']:.1e} m, "
                  f"v_t {e['table_speed']:.1e} m/s; largest on [{a:g}, {b:g}] (dense outputs): "
                  f"x_t {e['max_over_stretch_table_position']:.1e} m, v_t "
                  f"{e['max_over_stretch_table_speed']:.1e} m/s", flush=True)

    rows = []
    loose = setup(fd.SolverOptions(position_tolerance=5e-12))["atol"]
    record["atol_position_tolerance_5e-12"] = loose.tolist()
    settings = [("1-3", "default", 1.0, atol), ("1-3", "accuracy 0.1", 0.1, atol * 0.1),
                ("1-3", "position_tolerance 5e-12 (diagnostic)", 1.0, loose),
                ("3-10", "default", 1.0, atol), ("3-10", "accuracy 0.1", 0.1, atol * 0.1)]
    by_name = {m.name: m for m in METHODS}
    for span, label, acc, a in settings:
        diagnostic = a is loose
        ta, tb = spans[span]
        runs = [(m.name, ctl) for m in METHODS for ctl in ("standard", "gustafsson")]
        runs.append(("DOPRI5", "PI"))
        for name, ctl in runs:
            tick = time.perf_counter()
            if name == "DOPRI5":
                if diagnostic:
                    continue
                y, cnt = integrate_dopri5(model, states[ta], ta, tb, rtol * acc, a, rel)
            else:
                y, cnt = integrate_rosenbrock(by_name[name], model, states[ta], ta, tb,
                                              rtol * acc, a, rel, ctl)
            row = {"span": span, "setting": label, "method": name, "controller": ctl,
                   "accepted": cnt.accepted, "rejected": cnt.rejected,
                   "stage_rhs": cnt.stage_rhs, "jacobian_rhs": cnt.jacobian_rhs, "lu": cnt.lu,
                   "error_table_position": float(abs(y[ix] - states[tb][ix])),
                   "error_table_speed": float(abs(y[iv] - states[tb][iv])),
                   **_stretch_errors(cnt.trace, sols[ta], ix, iv),
                   "dominant_state": dict(sorted(cnt.dominant.items(), key=lambda kv: -kv[1])),
                   "wall_s": time.perf_counter() - tick}
            rows.append(row)
            print(f"{span:5s} {label:40s} {name:7s} {ctl:10s} {cnt.accepted:5d} + "
                  f"{cnt.rejected:3d} rej, x_t err {row['error_table_position']:.1e} m, v_t err "
                  f"{row['error_table_speed']:.1e} m/s", flush=True)
    record["runs"] = rows
    record["feeddrive"] = {
        "default": feeddrive_counts(),
        "accuracy 0.1": feeddrive_counts(accuracy=0.1),
        "position_tolerance 5e-12 (diagnostic)": feeddrive_counts(("rodas4",),
                                                                  position_tolerance=5e-12),
        "default, t = 3 … 10 s": feeddrive_counts(("modal", "rodas4"), (T1, T2)),
        "accuracy 0.1, t = 3 … 10 s": feeddrive_counts(("modal", "rodas4"), (T1, T2),
                                                       accuracy=0.1)}
    record["total_wall_s"] = time.perf_counter() - started
    record["load"] = [load0[0], os.getloadavg()[0]]
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "bench_rosenbrock_order.json").write_text(json.dumps(record, indent=1) + "\n")
    (RESULTS / "bench_rosenbrock_order.md").write_text(markdown(record))
    print(markdown(record))


def _steps(record: dict[str, Any], span: str, setting: str, method: str,
           ctl: str) -> dict[str, Any]:
    return next(r for r in record["runs"] if r["span"] == span and r["setting"] == setting
                and r["method"] == method and r["controller"] == ctl)


COST = {"DOPRI5": 1.0, "RODAS4": RODAS4_COST, "RODAS5": RODAS4_COST * 8 / 6,
        "RODAS5P": RODAS4_COST * 8 / 6}


def markdown(record: dict[str, Any]) -> str:
    rng = record["ranges"]
    lines = [f"# bench_rosenbrock_order ({record['date_utc']} UTC, load "
             f"{record['load'][0]:.1f} → {record['load'][1]:.1f} on 2 CPUs)", "",
             "wang2021 DDFS, 0.4 m, table 0.5 mm/s, hollow motor 16 mm/s; t = 1 … 3 s and "
             "3 … 10 s; plain-Python prototype on reference/scipy_model.py, fresh Jacobian each "
             "step; errors at the stretch's end against Radau (rtol 1e-11), relative to the "
             "range over the stretch (1–3: x_t "
             f"{rng['1-3']['table_position']:.3e} m, v_t {rng['1-3']['table_speed']:.3e} m/s; "
             f"3–10: x_t {rng['3-10']['table_position']:.3e} m, v_t "
             f"{rng['3-10']['table_speed']:.3e} m/s).", "",
             "| t [s] | setting | method | controller | accepted | rejected | stage RHS | LU | "
             "DOPRI5-step equiv. | x_t error / range | v_t error / range | "
             "max over the stretch: x_t / range | v_t / range |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in record["runs"]:
        equiv = (r["accepted"] + r["rejected"]) * COST[r["method"]]
        g = rng[r["span"]]
        lines.append(f"| {r['span']} | {r['setting']} | {r['method']} | {r['controller']} | "
                     f"{r['accepted']} | {r['rejected']} | {r['stage_rhs']} | {r['lu']} | "
                     f"{equiv:.0f} | "
                     f"{r['error_table_position'] / g['table_position']:.1e} | "
                     f"{r['error_table_speed'] / g['table_speed']:.1e} | "
                     f"{r['max_error_table_position'] / g['table_position']:.1e} | "
                     f"{r['max_error_table_speed'] / g['table_speed']:.1e} |")
    lines += ["", "The state whose weighted error is largest, share of the accepted steps "
              "(Rosenbrock runs):", ""]
    for r in record["runs"]:
        if r["dominant_state"]:
            top = ", ".join(f"{k} {v / r['accepted']:.0%}"
                            for k, v in list(r["dominant_state"].items())[:3])
            lines.append(f"* {r['span']} s, {r['setting']}, {r['method']} {r['controller']}: "
                         f"{top}")
    lines += ["", "DOPRI5-step equivalents: attempted steps × 1 (DOPRI5), × 5 (RODAS4, "
              "feeddrive's RODAS4_COST), × 5·8/6 = 6.67 (RODAS5 and RODAS5P, 8 stages, "
              "assumed).", "",
              "feeddrive's own counts (runs to the stretch's two ends, C build):", "",
              "| setting | method | steps | rejected | Rosenbrock steps | Jacobians |",
              "| --- | --- | --- | --- | --- | --- |"]
    for acc, per in record["feeddrive"].items():
        label = acc if "…" in acc else f"{acc}, t = 1 … 3 s"
        for method, c in per.items():
            lines.append(f"| {label} | {method} | {c['steps']} | {c['rejected_steps']} | "
                         f"{c['rosenbrock_steps']} | {c['jacobians']} |")
    lines += ["", "Accepted steps, RODAS4 / RODAS5 / RODAS5P (ratios to RODAS4):", ""]
    for span, setting in dict.fromkeys((r["span"], r["setting"]) for r in record["runs"]):
        for ctl in ("standard", "gustafsson"):
            n = [_steps(record, span, setting, m, ctl)["accepted"]
                 for m in ("RODAS4", "RODAS5", "RODAS5P")]
            lines.append(f"* {span} s, {setting}, {ctl}: {n[0]} / {n[1]} / {n[2]} "
                         f"({n[0] / n[1]:.2f}, {n[0] / n[2]:.2f})")
    lines += ["", "Cost over 1 … 10 s at the defaults (DOPRI5-step equivalents of the attempted "
              "steps, 1–3 + 3–10):", ""]
    for ctl in ("standard", "gustafsson"):
        parts = []
        for m in ("RODAS4", "RODAS5", "RODAS5P"):
            tot = sum((r["accepted"] + r["rejected"]) * COST[m] for r in
                      (_steps(record, sp, "default", m, ctl) for sp in ("1-3", "3-10")))
            parts.append(f"{m} {tot:.0f}")
        lines.append(f"* {ctl}: " + ", ".join(parts))
    checks = record["tableau_checks"]
    lines += ["", "Tableau checks (fixed-step slopes main / embedded; asserted):", ""]
    for name, c in checks.items():
        dense = ""
        if "dense_local_slope" in c:
            dense = (f"; dense output (largest error over θ = 0.05 … 0.95, non-stiff problem): "
                     f"local {c['dense_local_slope']:.2f}, global {c['dense_global_slope']:.2f} "
                     "(an order-4 continuous extension: 5 and 5)")
        lines.append(f"* {name}: non-stiff {c['nonstiff_main_slope']:.2f} / "
                     f"{c['nonstiff_embedded_slope']:.2f}; stiff linear (λ = −0.5 ± 4i, −1e6) "
                     f"{c['stiff_main_slope']:.2f} / {c['stiff_embedded_slope']:.2f} (order of "
                     f"R(z) against e^z: {c['linear_order']:.2f}); "
                     f"|R(−1e8)| = {c['R_at_-1e8']:.1e}, max |R(iy)| = "
                     f"{c['max_R_imaginary_axis']:.6f}; numerical damping ratio "
                     f"−ln|R(iy)|/y at y = 0.35 (the modal cap): {c['zeta_num_0.35']:.2e}, "
                     f"at 0.7: {c['zeta_num_0.7']:.2e}{dense}")
    for span, e in record.get("reference_error", {}).items():
        lines += ["", f"Radau reference vs its check (rtol 1e-12, 1e-5 × atol), {span} s: at "
                  f"the end x_t {e['table_position']:.1e} m, v_t {e['table_speed']:.1e} m/s; "
                  "largest difference of their dense outputs over the stretch: x_t "
                  f"{e['max_over_stretch_table_position']:.1e} m, v_t "
                  f"{e['max_over_stretch_table_speed']:.1e} m/s (what the 'max over the "
                  "stretch' columns can resolve)."]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
