"""Solvers as data (issue 19 item 5): the tableaux, the one explicit Runge–Kutta step and the one
Rosenbrock step written for any of them (two tableaux each), and the sample schedule's event
kernels.

References: scipy's RK45 and RK23 (``scipy.integrate._ivp.rk``: their own copies of the
Dormand–Prince and Bogacki–Shampine coefficients, a matrix-form step) for the explicit step;
the exact solution exp(hλ) of y' = λy for the orders.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from scipy.integrate._ivp import rk as scipy_rk

from feeddrive.solvers import schedule, steps
from feeddrive.solvers.tableaux import (
    BS3,
    DOPRI5,
    RODAS3,
    RODAS4,
    RODAS5P,
    ExplicitTableau,
    RosenbrockTableau,
)

LAMBDA = np.array([[-1.0, 4.0], [-4.0, -1.0]])  # a damped oscillator, eigenvalues −1 ± 4i


def _linear_rhs(t: float, y: np.ndarray, held: Any, P: Any, T: Any, dy: np.ndarray,
                aux: Any) -> None:
    dy[:] = LAMBDA @ y


def _explicit(tab: ExplicitTableau, y: np.ndarray, h: float, fun: Any = _linear_rhs,
              t: float = 0.0) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """(y_new, error estimate, stages) of one step of the generic explicit step for ``tab``."""
    step = steps.explicit_step(tab, rhs=fun)
    error = steps.explicit_error(tab)
    n = y.size
    k = [np.empty(n) for _ in tab.e]
    fun(t, y, None, None, None, k[0], None)
    yt, y_new, e = np.empty(n), np.empty(n), np.empty(n)
    step(t, h, y, k[0], None, None, None, *k[1:], yt, y_new, None, t + h)
    error(h, *k, e)
    return y_new, e, k


@pytest.mark.parametrize("tab, ref", [(DOPRI5, scipy_rk.RK45), (BS3, scipy_rk.RK23)])
def test_the_generic_step_is_scipy_s_step_of_the_same_method(tab: ExplicitTableau,
                                                             ref: Any) -> None:
    """y_new and the error estimate of the written step = scipy's (same method, its own
    coefficient table and a matrix-form step: equal to rounding)."""
    y0, h = np.array([1.0, -0.5]), 0.07

    def fun(t: float, y: np.ndarray) -> np.ndarray:
        return LAMBDA @ y

    K = np.empty((ref.n_stages + 1, 2))
    y_ref, _ = scipy_rk.rk_step(fun, 0.0, y0, fun(0.0, y0), h, ref.A, ref.B, ref.C, K)
    e_ref = h * (K.T @ ref.E)
    y_new, e, _ = _explicit(tab, y0, h)
    np.testing.assert_allclose(y_new, y_ref, rtol=1e-14, atol=1e-15)
    # scipy's E is b̂ − b, ours b − b̂
    np.testing.assert_allclose(e, -e_ref, rtol=1e-10, atol=1e-17)


@pytest.mark.parametrize("tab", [DOPRI5, BS3])
def test_each_tableau_has_its_order_through_the_one_step(tab: ExplicitTableau) -> None:
    """Local error of y_new ~ h^(p+1), of the embedded solution ~ h^(q+1), on y' = Λy against
    the exact exp(hΛ)y0: the same step text gives each tableau its own order."""
    from scipy.linalg import expm

    y0 = np.array([1.0, 0.3])
    local, embedded = [], []
    for h in (0.04, 0.02):
        y_new, e, _ = _explicit(tab, y0, h)
        exact = expm(h * LAMBDA) @ y0
        local.append(np.linalg.norm(y_new - exact))
        embedded.append(np.linalg.norm(y_new - e - exact))  # ŷ = y_new − e
    assert math.log2(local[0] / local[1]) == pytest.approx(tab.order + 1, abs=0.3)
    assert math.log2(embedded[0] / embedded[1]) == pytest.approx(tab.embedded_order + 1,
                                                                 abs=0.3)


@pytest.mark.parametrize("tab", [RODAS4, RODAS3])
def test_the_rosenbrock_step_has_each_tableau_s_order_on_a_linear_system(
        tab: RosenbrockTableau) -> None:
    """RODAS4 and RODAS3 through the one Rosenbrock step: local error ~ h^(p+1) on y' = Λy
    (exact Jacobian, f_t = 0), the error estimate u_S ~ h^(q+1) (q: the embedded order)."""
    from scipy.linalg import expm

    from feeddrive.solvers.rodas4 import lu_factor, lu_solve

    step = steps.rosenbrock_step(tab, rhs=_linear_rhs)
    step.__globals__.update(lu_factor=lu_factor.py_func, lu_solve=lu_solve.py_func)
    y0, n, S = np.array([1.0, 0.3]), 2, len(tab.c)
    local, estimate = [], []
    for h in (0.04, 0.02):
        f0 = LAMBDA @ y0
        u = [np.empty(n) for _ in range(S)]
        y_new = np.empty(n)
        calls = step(0.0, h, y0, f0, LAMBDA.copy(), np.zeros(n), None, None, None,
                     np.empty((n, n)), np.zeros(n, dtype=np.int64), *u, np.empty(n),
                     np.empty(n), y_new, None, np.ones(n, dtype=bool))
        assert calls == tab.stages == S - 1
        local.append(np.linalg.norm(y_new - expm(h * LAMBDA) @ y0))
        estimate.append(np.linalg.norm(u[-1]))
    assert math.log2(local[0] / local[1]) == pytest.approx(tab.order + 1, abs=0.4)
    assert math.log2(estimate[0] / estimate[1]) == pytest.approx(tab.embedded_order + 1,
                                                                 abs=0.4)


def _pendulum(t: float, y: np.ndarray, held: Any, P: Any, T: Any, dy: np.ndarray,
              aux: Any) -> None:
    dy[0] = y[1]
    dy[1] = -math.sin(y[0]) - 0.3 * y[1] + 0.5 * math.cos(2.0 * t)


def _pendulum_jacobian(t: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(∂f/∂y, ∂f/∂t) of :func:`_pendulum`."""
    return (np.array([[0.0, 1.0], [-math.cos(y[0]), -0.3]]),
            np.array([0.0, -math.sin(2.0 * t)]))


def _pendulum_exact(t0: float, y0: np.ndarray, t: float) -> np.ndarray:
    from scipy.integrate import solve_ivp

    def fun(tt: float, y: np.ndarray) -> np.ndarray:
        dy = np.empty(2)
        _pendulum(tt, y, None, None, None, dy, None)
        return dy

    return solve_ivp(fun, (t0, t), y0, method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1]


@pytest.mark.parametrize("tab", [RODAS4, RODAS5P])
def test_the_rosenbrock_step_and_dense_output_have_their_orders_on_a_nonlinear_problem(
        tab: RosenbrockTableau) -> None:
    """The one Rosenbrock step and its written dense output, evaluated as the driver does
    (y(θ) = (1 − θ) y0 + θ (y1 + (1 − θ)(q1 + θ (q2 + θ q3))), q3 = 0 for RODAS4), on a forced
    damped pendulum (non-linear, non-autonomous: f_t enters) against scipy's DOP853 at rtol
    1e-13: local errors ~ h^(p+1) (p = 4 RODAS4, 5 RODAS5P), of the estimate u_S ~ h^(q+1),
    of the dense output at θ = 0.7 ~ h^(p*+1) (p* = 3 RODAS4, 4 RODAS5P, Steinebach 2023) and
    at θ = 0.3 no slower.  On y' = Λy RODAS5P's local error is h^7 (its stability function
    matches e^z to z^6), which is why this problem is non-linear."""
    from feeddrive.solvers.rodas4 import lu_factor, lu_solve

    step = steps.rosenbrock_step(tab, rhs=_pendulum)
    step.__globals__.update(lu_factor=lu_factor.py_func, lu_solve=lu_solve.py_func)
    name = {"rodas4": "_r4_rodas4_dense", "rodas5p": "_r5_rodas5p_dense"}[tab.name]
    dense = steps.function(name)
    t0, y0, n, S = 0.2, np.array([1.0, 0.3]), 2, len(tab.c)
    J, ft = _pendulum_jacobian(t0, y0)
    f0 = np.empty(n)
    _pendulum(t0, y0, None, None, None, f0, None)
    errors: dict[str, list[float]] = {"step": [], "estimate": [], "0.3": [], "0.7": []}
    for h in (0.1, 0.05):
        u = [np.empty(n) for _ in range(S)]
        y1 = np.empty(n)
        calls = step(t0, h, y0, f0, J.copy(), ft, None, None, None, np.empty((n, n)),
                     np.zeros(n, dtype=np.int64), *u, np.empty(n), np.empty(n), y1, None,
                     np.ones(n, dtype=bool))
        assert calls == tab.stages == S - 1
        exact = _pendulum_exact(t0, y0, t0 + h)
        errors["step"].append(float(np.linalg.norm(y1 - exact)))
        errors["estimate"].append(float(np.linalg.norm(u[-1])))
        q = [np.zeros(n) for _ in range(3)]
        dense(*u[:len(tab.dense[0])], *q[:len(tab.dense)])
        for th in (0.3, 0.7):
            y = (1 - th) * y0 + th * (y1 + (1 - th) * (q[0] + th * (q[1] + th * q[2])))
            errors[str(th)].append(float(np.linalg.norm(
                y - _pendulum_exact(t0, y0, t0 + th * h))))
    slopes = {k: math.log2(a / b) for k, (a, b) in errors.items()}
    assert slopes["step"] == pytest.approx(tab.order + 1, abs=0.4), slopes
    assert slopes["estimate"] == pytest.approx(tab.embedded_order + 1, abs=0.4), slopes
    assert tab.dense_order == tab.order - 1
    # at least the dense order everywhere; exactly it at θ = 0.7 (at θ = 0.3 RODAS5P's leading
    # error term nearly vanishes: slope 5.8, measured)
    assert min(slopes["0.3"], slopes["0.7"]) >= tab.dense_order + 1 - 0.4, slopes
    assert slopes["0.7"] == pytest.approx(tab.dense_order + 1, abs=0.4), slopes


def test_the_model_modules_hold_the_written_steps() -> None:
    """The text every generated module gets is the steps written from the tableaux (one
    DOPRI5 step for the three drivers, one RODAS4 step)."""
    from feeddrive.solvers.shared import solver_sources

    text = "\n".join(solver_sources())
    for name in ("_dp5_step", "_dp5_error", "_dp5_dense", "_r4_rodas4_step",
                 "_r4_rodas4_dense", "_r5_rodas5p_step", "_r5_rodas5p_dense", "_error_norm"):
        assert text.count(f"def {name}(") == 1, name
    assert steps.sources()["_dp5_step"] in text
    assert repr(abs(DOPRI5.a[3][1])) in steps.sources()["_dp5_step"]


def test_malformed_tableaux_are_refused() -> None:
    with pytest.raises(ValueError, match="rows of lengths"):
        ExplicitTableau("x", 1, 0, (0.0, 1.0), ((), ()), (0.5, 0.5), (0.0, 0.0), False)
    with pytest.raises(ValueError, match="stiffly accurate"):
        RosenbrockTableau("r", 1, 0, 0.5, (0.0, 1.0, 1.0), ((), (1.0,), (0.5, 0.5)),
                          ((), (0.0,), (0.0, 0.0)), (0.5, 0.0, 0.0), ())


def test_the_schedule_merges_clocks_as_breakpoint_counts() -> None:
    """Clocks every 2 and 3 breakpoints and a continuous one: instants 0, 2, 3, 4, 6, 8, 9 …,
    each clock's tick its own count there, −1 elsewhere; none at all when all are 0."""
    grid = np.array([2, 3, 0], dtype=np.int64)
    tick = np.empty(3, dtype=np.int64)
    kb, seen = 0, [0]
    while kb < 9:
        kb = schedule.next_instant(kb, grid)
        seen.append(kb)
    assert seen == [0, 2, 3, 4, 6, 8, 9]
    assert schedule.due(6, grid, tick) == 2 and list(tick) == [3, 2, -1]
    assert schedule.due(9, grid, tick) == 1 and list(tick) == [-1, 3, -1]
    assert schedule.due(0, grid, tick) == 2 and list(tick) == [0, 0, -1]
    assert schedule.next_instant(5, schedule.no_schedule(3)) == -1
    assert schedule.due(0, schedule.no_schedule(3), tick) == 0


def test_the_drivers_have_the_step_written_in_and_the_fmu_calls_it() -> None:
    """dopri5's text and the dense driver's step attempt (a piece numba inlines into it) hold
    the DOPRI5 step's statements in place of the call (steps.inline_steps); the FMU's
    integrator, which the C translator reads, calls the same step function.  All three are
    the one driver (feeddrive.solvers.driver) specialised: the explicit-only uses hold none of
    the RODAS4 / eigen-analysis code."""
    from feeddrive.fmu import solver as fmu_solver
    from feeddrive.solvers import dopri5, driver_text, switching

    def defining(sources: list[str], use: str) -> str:
        """The one source of ``sources`` that defines ``use`` (the imports sit beside it)."""
        (text,) = [t for t in sources if f"def {use}(" in t]
        return text

    integrate = defining(dopri5.template_sources(), "integrate")
    dense = defining(switching.template_sources(), "integrate_dense")
    attempt = driver_text.piece_source("step_attempt")
    assert "step_attempt(" in dense and "_dp5_" not in dense
    stage = "yt[i] = y[i] + h_try * 0.2 * f0[i]"  # the first stage, h renamed to h_try
    for text in (integrate, attempt):
        assert "_dp5_step(" not in text and "_dp5_error(" not in text
        assert "0.0012326388888888888" in text  # the first error weight, 71/57600
        assert stage in text
    assert "_dp5_step(" in fmu_solver.template_source()
    for use, text in (("integrate", integrate),
                      ("integrate_dense", dense),
                      ("advance", fmu_solver.template_source())):
        assert f"def {use}(" in text and "driver_template specialised" in text
    for text in (integrate, fmu_solver.template_source()):
        body = text.split('"""')[-1]  # after the docstring
        for name in ("_r4_", "modal_step_cap", "stiff", "MODE_", "LAND", "DENSE", "COMM"):
            assert name not in body, name
    assert "_r4_rodas4_step(" in attempt
    advance = driver_text.source("advance")
    assert "stops" not in advance and "t_out" not in advance
    with pytest.raises(ValueError, match="positional arguments"):
        steps.inline_steps("def f(h, k):\n    _dp5_error(h, k)\n")
