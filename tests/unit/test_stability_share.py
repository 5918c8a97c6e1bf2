"""``dopri5`` below accuracy 1 caps each step at accuracy^(1/5) × DOPRI5's stability bound
3.3/ρ, ρ the error-weighted stiffness estimate of the step before (issue 35 item 2: where
stability, not the tolerances, bounds the steps the error did not fall with the accuracy).

The estimate is checked on a linear system written here (f = A·y, so f(y_new) − f(yt) =
A·(y_new − yt) exactly): along an eigenvector it is h·|λ|, and it does not depend on the units a
state is written in when its tolerance is written in the same units.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.engine.options import SolverOptions
from feeddrive.solvers import driver

A = np.array([[-1.0, 2.0, 0.0],
              [0.0, -1500.0, 30.0],
              [0.0, 0.0, -40.0]])


def estimate(A: np.ndarray, dy: np.ndarray, atol: np.ndarray,
             S: np.ndarray | None = None, h: float = 1e-3) -> float:
    """The estimate at y (written in the units S makes of them), the sixth stage's argument
    ``dy`` away from the step's end."""
    S = np.eye(3) if S is None else S
    y = S @ np.array([0.3, -0.2, 0.1])
    y_new = y + S @ np.full(3, 0.01)
    yt = y_new - dy
    return driver.weighted_stiffness_estimate(h, A @ y_new, A @ yt, y, y_new, yt, 1e-6, atol,
                                              np.ones(3))


def test_along_an_eigenvector_it_is_h_times_the_eigenvalue() -> None:
    lam, vec = np.linalg.eig(A)
    atol = np.array([1e-8, 1e-6, 1e-4])
    for k in range(3):
        assert estimate(A, 1e-3 * vec[:, k].real, atol) == pytest.approx(1e-3 * abs(lam[k]),
                                                                        rel=1e-9)


def test_it_does_not_depend_on_a_states_units() -> None:
    """State 1 written in mm instead of m (× 1000), its tolerance too: the same estimate; the
    unweighted estimate of dopri5.f moves."""
    dy = np.array([1e-6, 3e-7, -2e-7])
    atol = np.array([1e-8, 1e-6, 1e-4])
    S = np.diag([1.0, 1000.0, 1.0])
    scaled_A = S @ A @ np.linalg.inv(S)
    weighted = estimate(A, dy, atol)
    assert estimate(scaled_A, S @ dy, S @ atol, S) == pytest.approx(weighted, rel=1e-9)
    y_new = np.zeros(3)
    plain = driver.stiffness_estimate(1e-3, A @ dy, np.zeros(3), dy, y_new)
    plain_scaled = driver.stiffness_estimate(1e-3, scaled_A @ S @ dy, np.zeros(3), S @ dy,
                                             y_new)
    assert not math.isclose(plain, plain_scaled, rel_tol=1e-3)


def test_coinciding_points_give_no_estimate() -> None:
    assert estimate(A, np.zeros(3), np.ones(3)) == 0.0


@pytest.mark.parametrize(("method", "accuracy", "share"), [
    ("dopri5", 1.0, 1.0), ("dopri5", 10.0, 1.0), ("dopri5", 0.1, 0.1 ** 0.2),
    ("dopri5", 1e-3, 1e-3 ** 0.2), ("dopri5-dense", 0.1, 1.0), ("modal", 0.01, 1.0)])
def test_the_share_is_the_orders_rule_for_dopri5_below_accuracy_1(
        method: str, accuracy: float, share: float) -> None:
    assert SolverOptions(method=method, accuracy=accuracy).stability_share == \
        pytest.approx(share, rel=1e-12)


def test_the_label_states_the_cap(monkeypatch: pytest.MonkeyPatch) -> None:
    text = SolverOptions(method="dopri5", accuracy=0.1).describe()
    assert f"≤ {0.1 ** 0.2:.3g} × DOPRI5's stability bound {driver.DOPRI5_STABILITY:g}/ρ" in text
    assert "steps ≤ 0.000631 s and ≤ 0.631 × " in text
    assert "stability bound" not in SolverOptions(method="dopri5").describe()
    monkeypatch.setattr(driver, "DOPRI5_STABILITY", 2.9)  # the label follows the constant
    assert "stability bound 2.9/ρ" in SolverOptions(method="dopri5", accuracy=0.1).describe()


def test_the_cap_binds_only_below_accuracy_1(monkeypatch: pytest.MonkeyPatch) -> None:
    """The stiff DDFS's first second: at accuracy 1 the run is bit for bit the one without the
    rule; at accuracy 0.1 the rule changes the steps (it binds where the stiffness does)."""
    system = fd.DriveSystem(fd.preset("wang2021"), "ddfs", 0.4)
    profile = fd.ConstantSpeed(0.5e-3, 16e-3)

    def runs() -> list[fd.Result]:
        return [fd.simulate(system, profile, 1.0,
                            options=SolverOptions(method="dopri5", accuracy=a))
                for a in (1.0, 0.1)]

    with_rule = runs()
    monkeypatch.setattr(SolverOptions, "stability_share", property(lambda self: 1.0))
    without = runs()
    np.testing.assert_array_equal(with_rule[0]["table_speed"], without[0]["table_speed"])
    assert with_rule[0].solver_stats["steps"] == without[0].solver_stats["steps"]
    assert with_rule[1].solver_stats["steps"] != without[1].solver_stats["steps"]
