"""RODAS4 and the dense-output driver on problems with an exact answer.

* order: with friction off the closed loop is linear (``reference/linear_model.py``); RODAS4 at
  fixed steps must converge with order 4 (log–log slope), as DOPRI5 with order 5 does in
  ``test_solver_order.py``;
* dense output: at default tolerances the interpolated outputs of every dense-output method
  follow the exact response to within the tolerances, while the steps are much longer than the
  output interval (so almost every output is interpolated);
* the small LU kernels against numpy; the spectral-radius estimate against ``eigvals``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.scipy_model import STATE_NAMES  # noqa: E402
from test_solver_order import (  # noqa: E402
    BREAK,
    DURATION,
    STEPS,
    exact,
    frictionless_params,
    run_engine,
    scaled_error,
)

from feeddrive.engine.simulate import DriveSystem, SolverOptions, simulate  # noqa: E402
from feeddrive.model.reference import ConstantSpeed  # noqa: E402
from feeddrive.solvers import rodas4  # noqa: E402

IX = {name: k for k, name in enumerate(STATE_NAMES)}


@pytest.mark.parametrize(("drive", "nut_speed"), [("cdfs", 0.0), ("ddfs", 16e-3)])
def test_rodas4_fixed_step_converges_with_order_4(drive: str, nut_speed: float) -> None:
    params = frictionless_params()
    profile = ConstantSpeed(table_speed=1.5e-3, nut_speed=nut_speed, ramp_time=0.0)
    errors = []
    y_exact = None
    for h in STEPS:
        options = SolverOptions(method="rodas4-fixed", fixed_step=float(h), output_interval=BREAK)
        t, y = run_engine(params, drive, profile, DURATION, adaptive=1, options=options)
        if y_exact is None:
            y_exact = exact(params, drive, profile, t)
        errors.append(scaled_error(y, y_exact))
    slope = np.polyfit(np.log(STEPS), np.log(errors), 1)[0]
    assert slope == pytest.approx(rodas4.ORDER, abs=0.3), (slope, errors)


def test_rodas4_handles_a_time_dependent_command() -> None:
    """The ramp makes f depend on t: without the f_t term the order would drop.  The ramp end
    is a declared breakpoint, so errors fall with order 4 across it too."""
    params = frictionless_params()
    profile = ConstantSpeed(table_speed=1.5e-3, ramp_time=0.02)
    steps = BREAK / np.array([8, 16])
    errors = []
    y_exact = None
    for h in steps:
        options = SolverOptions(method="rodas4-fixed", fixed_step=float(h), output_interval=BREAK)
        r = simulate(DriveSystem(params, "cdfs", 0.4), profile, DURATION, options=options)
        if y_exact is None:
            y_exact = _exact_ramp(params, profile, r.time)
        errors.append(float(np.max(np.abs(r["table_speed"] - y_exact))))
    assert errors[0] / errors[1] > 2 ** 3.5, errors


def _exact_ramp(params: object, profile: ConstantSpeed, times: np.ndarray) -> np.ndarray:
    """Table speed of the frictionless loop following the ramp, from a tight DOPRI5 run
    (fixed 1-µs steps; the ramp is polynomial in t, exact to round-off at that step)."""
    options = SolverOptions(method="dopri5-fixed", fixed_step=1e-6, output_interval=BREAK)
    r = simulate(DriveSystem(params, "cdfs", 0.4), profile, DURATION,  # type: ignore[arg-type]
                 options=options)
    np.testing.assert_allclose(r.time, times, atol=1e-12)
    return r["table_speed"]


@pytest.mark.parametrize("method", ["modal", "auto", "rodas4", "dopri5-dense"])
def test_dense_output_follows_the_exact_response_within_tolerance(method: str) -> None:
    """Tolerances 10× below the defaults (speed 1e-9 m/s, position 1e-11 m, rtol 1e-7): the
    recorded samples, most of them interpolated, follow the exact response to 5e-8 m/s and
    5e-10 m (the bounds the default-tolerance DOPRI5 run meets with 1-ms steps).  The global
    error of the speed is some 30× its local target: the 200-Hz table mode accumulates it."""
    params = frictionless_params(controller__velocity_gain_basis="table")
    profile = ConstantSpeed(table_speed=1.5e-3, ramp_time=0.0)
    options = SolverOptions(method=method, rtol=1e-7, position_tolerance=1e-11,
                            speed_tolerance=1e-9, current_tolerance=1e-7)
    r = simulate(DriveSystem(params, "cdfs", 0.4), profile, 0.5, options=options)
    y_exact = exact(params, "cdfs", profile, r.time)
    assert r.time.size == 501
    np.testing.assert_allclose(np.diff(r.time), 1e-3, rtol=1e-9)
    # the step is no longer tied to the output grid: fewer steps than samples
    assert r.solver_stats["steps"] < r.time.size - 100, r.solver_stats
    err_v = np.max(np.abs(r["table_speed"] - y_exact[:, IX["table_speed"]]))
    err_x = np.max(np.abs(r["table_position"] - y_exact[:, IX["table_position"]]))
    assert err_v < 5e-8, err_v
    assert err_x < 5e-10, err_x


def test_interpolated_samples_match_step_end_samples() -> None:
    """The same RODAS4 run recorded every 1 ms and every 0.1 ms: the coarse samples are a
    subset of the fine ones, so they must agree to the tolerance (both interpolated from the
    same kind of steps), and the fine record must not cost more steps."""
    params = frictionless_params(controller__velocity_gain_basis="table")
    profile = ConstantSpeed(table_speed=1.5e-3, ramp_time=0.0)
    system = DriveSystem(params, "ddfs", 0.4)
    coarse = simulate(system, profile, 0.3, options=SolverOptions(method="rodas4"))
    fine = simulate(system, profile, 0.3,
                    options=SolverOptions(method="rodas4", output_interval=1e-4))
    assert fine.solver_stats["steps"] == coarse.solver_stats["steps"]
    np.testing.assert_allclose(fine.time[::10], coarse.time, atol=1e-12)
    np.testing.assert_allclose(fine["table_speed"][::10], coarse["table_speed"], rtol=0,
                               atol=1e-12)
    y_exact = exact(params, "ddfs", profile, fine.time)
    # default tolerances: the global error of the speed stays below 1e-6 m/s (0.07 %)
    assert np.max(np.abs(fine["table_speed"] - y_exact[:, IX["table_speed"]])) < 1e-6


def test_lu_kernels_solve_like_numpy() -> None:
    rng = np.random.default_rng(9)
    for n in (2, 3, 15):
        A = rng.normal(size=(n, n)) + np.diag(rng.uniform(-3, 3, n))
        A[0, 0] = 0.0  # forces a pivot swap
        b = rng.normal(size=n)
        M = A.copy()
        piv = np.zeros(n, dtype=np.int64)
        assert rodas4.lu_factor(M, piv)
        # the factors and pivots of LAPACK's getrf (scipy), which pivots alike
        lu, lapack_piv = scipy.linalg.lu_factor(A)
        assert piv.tolist() == lapack_piv.tolist()
        np.testing.assert_allclose(M, lu, rtol=1e-12, atol=1e-12)
        x = b.copy()
        rodas4.lu_solve(M, piv, x)
        np.testing.assert_allclose(A @ x, b, rtol=1e-10, atol=1e-10)
    assert not rodas4.lu_factor(np.zeros((2, 2)), np.zeros(2, dtype=np.int64))


def _dense_substitution(M: np.ndarray, piv: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The triangular solves with every term subtracted, zeros too, written here as the
    reference: the loops of the reference BLAS ``dtrsv`` (Netlib), by columns — L unit lower,
    j rising; U upper, j falling, x_j divided by u_jj before its column is subtracted."""
    x = b.copy()
    n = M.shape[0]
    for k in range(n):
        x[k], x[piv[k]] = x[piv[k]], x[k]
    for j in range(n):
        for i in range(j + 1, n):
            x[i] -= x[j] * M[i, j]
    for j in range(n - 1, -1, -1):
        x[j] = x[j] / M[j, j]
        for i in range(j - 1, -1, -1):
            x[i] -= x[j] * M[i, j]
    return x


def test_lu_solve_skips_the_factors_zeros_bit_for_bit() -> None:
    """On matrices shaped like a drive's Rosenbrock matrix I/(γh) − J (a sparse J, so the LU
    keeps exact zeros), the solve that skips the zeros gives the dense loops' solution bit for
    bit (finite right-hand sides of both signs), and solves the system (numpy)."""
    rng = np.random.default_rng(11)
    for n, density in ((15, 0.2), (15, 0.35), (19, 0.25), (6, 0.5)):
        J = rng.normal(size=(n, n)) * (rng.uniform(size=(n, n)) < density)
        A = np.eye(n) / 1e-3 - J * rng.uniform(1.0, 1e4)
        M = A.copy()
        piv = np.zeros(n, dtype=np.int64)
        assert rodas4.lu_factor(M, piv)
        assert np.count_nonzero(M == 0.0) > 0  # there are zeros to skip
        for _ in range(5):
            b = rng.normal(size=n) * 10.0 ** rng.uniform(-8, 3, n)
            x = b.copy()
            rodas4.lu_solve(M, piv, x)
            assert np.array_equal(x, _dense_substitution(M, piv, b))
            np.testing.assert_allclose(A @ x, b, rtol=1e-9, atol=1e-9 * np.abs(b).max())


def test_spectral_radius_estimate_matches_eigenvalues() -> None:
    """The power-iteration estimate used to switch back to DOPRI5, on the frictionless
    loop's Jacobian (a dominant complex pair) and on a diagonal stiff matrix."""
    model = DriveSystem(frictionless_params(), "ddfs", 0.4).model(ConstantSpeed(1e-3))
    n = len(model.state_names)
    y = np.zeros(n)
    f0 = np.empty(n)
    aux = np.empty(len(model.aux))
    held = np.zeros(model.n_held)
    model.module.rhs(0.2, y, held, model.P, model.T, f0, aux)
    J = np.zeros((n, n))
    atol, _ = model.tolerances(1e-10, 1e-8, 1e-6)
    calls = model.module._r4_fd_jacobian(0.2, y, f0, held, model.P, model.T, atol, J,
                                         np.empty(n), np.empty(n), np.empty(n), aux,
                                         np.ones(n, dtype=np.bool_), model.jacobian_pattern,
                                         model.jacobian_colours)
    assert calls == model.jacobian_colours.max() + 1
    true = np.max(np.abs(np.linalg.eigvals(J)))
    est = model.module._r4_spectral_radius(J, atol, np.empty(n), np.empty(n), 40)
    assert est == pytest.approx(true, rel=0.25)
    D = np.diag([-1.0, -10.0, -8000.0])
    est = model.module._r4_spectral_radius(D, np.ones(3), np.empty(3), np.empty(3), 12)
    assert est == pytest.approx(8000.0, rel=1e-3)
