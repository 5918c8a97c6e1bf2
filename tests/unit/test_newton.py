"""The operating point's Gauss–Newton solve (issue 21, fifth round): the pure solver, and the
steady states it gives against scipy's Levenberg–Marquardt (the method before)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import optimize

import feeddrive as fd
from feeddrive.analysis import linear
from feeddrive.analysis.newton import pulled_gauss_newton

PULL = 1e-8


def _rosenbrock_like(u: np.ndarray) -> np.ndarray:
    # a nonlinear square system with the root (1, 1); the full step overshoots from (-1.2, 1)
    return np.array([10.0 * (u[1] - u[0] ** 2), 1.0 - u[0]])


def _jac(u: np.ndarray) -> np.ndarray:
    return np.array([[-20.0 * u[0], 10.0], [-1.0, 0.0]])


def test_a_nonlinear_root_is_found_to_rounding() -> None:
    u, iterations = pulled_gauss_newton(_rosenbrock_like, lambda u: (_rosenbrock_like(u),
                                                                     _jac(u)),
                                        np.array([-1.2, 1.0]), 0.0)
    assert np.allclose(u, [1.0, 1.0], rtol=0, atol=1e-12)
    assert 2 <= iterations <= 50


def test_a_direction_no_equation_holds_stays_at_its_start() -> None:
    # r depends on u0 + u1 only: u0 - u1 is free; the pull keeps it where it started
    def r(u: np.ndarray) -> np.ndarray:
        return np.array([u[0] + u[1] - 2.0])

    start = np.array([5.0, -1.0])  # u0 - u1 = 6 at the start
    u, _ = pulled_gauss_newton(r, lambda u: (r(u), np.array([[1.0, 1.0]])), start, PULL)
    assert u[0] + u[1] == pytest.approx(2.0, abs=1e-12)
    assert u[0] - u[1] == pytest.approx(6.0, abs=1e-9)


def _levenberg_marquardt(function, *args, monkeypatch: pytest.MonkeyPatch):  # type: ignore[no-untyped-def]
    """``function(*args)`` with the steady state of the method before: the Gauss–Newton
    answer made unacceptable."""
    with monkeypatch.context() as m:
        m.setattr(linear, "pulled_gauss_newton",
                  lambda residual, linearised, u0, pull: (np.full_like(u0, np.nan), 0))
        return function(*args)


@pytest.mark.parametrize(("drive", "nut_speed"), [("cdfs", 0.0), ("ddfs", 16e-3)])
@pytest.mark.parametrize("speed", [2e-5, 1.5e-3, 4e-3])
def test_the_steady_state_is_the_levenberg_marquardt_one(drive: str, nut_speed: float,
                                                         speed: float,
                                                         monkeypatch: pytest.MonkeyPatch
                                                         ) -> None:
    system = fd.DriveSystem(fd.preset("wang2021"), drive, 0.4)
    model, y = linear.steady_state(system, speed, nut_speed)
    y_lm = _levenberg_marquardt(linear.steady_state, system, speed, nut_speed,
                                monkeypatch=monkeypatch)[1]
    gap = (y - y_lm) / linear._scales(model)
    # the DDFS screw and nut turned together is a direction no equation holds: there each
    # method stops a little differently on rounding noise (seen: 1.3e-5 of the tolerance),
    # by the same angle on both
    names = model.state_names
    if drive == "ddfs":
        screw, nut = names.index("screw_angle"), names.index("nut_angle")
        assert abs(gap[screw] - gap[nut]) < 1e-6
        assert abs(gap[screw]) < 1e-3
        gap[[screw, nut]] = 0.0
    # every other state: the same point to a millionth of its solver tolerance
    assert np.max(np.abs(gap)) < 1e-6
    # … and the same linearisation: the state matrices agree to 1e-7 of their largest entry
    a = linear.state_matrix(system, speed, nut_speed)
    a_lm = _levenberg_marquardt(linear.state_matrix, system, speed, nut_speed,
                                monkeypatch=monkeypatch)
    assert np.max(np.abs(a - a_lm)) <= 1e-7 * np.max(np.abs(a_lm))


def test_the_fallback_is_scipy_least_squares(monkeypatch: pytest.MonkeyPatch) -> None:
    calls = []
    real = optimize.least_squares

    def spy(*args, **kwargs):  # type: ignore[no-untyped-def]
        calls.append(kwargs.get("method"))
        return real(*args, **kwargs)

    monkeypatch.setattr(optimize, "least_squares", spy)
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    linear.steady_state(system, 1.5e-3)
    assert calls == []  # Gauss–Newton answered
    _levenberg_marquardt(linear.steady_state, system, 1.5e-3, monkeypatch=monkeypatch)
    assert calls == ["lm"]
