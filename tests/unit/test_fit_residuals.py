"""Residual diagnostics and the HAC sandwich covariance of `feeddrive fit` (issue 36 item 2).

Reference values: the HAC standard error is checked against the Monte Carlo scatter of the
estimate itself (a linear regression with AR(1) errors, whose true sampling distribution the
repetitions give); the bandwidth against Andrews (1991) Eq. (6.4) for a scalar AR(1), the runs
test against the Wald–Wolfowitz expectation 1 + 2 n₁n₂/(n₁ + n₂).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from feeddrive.analysis.fit_residuals import (
    STABILITY_LIMIT,
    andrews_bandwidth,
    diagnose,
    hac_covariance,
)


def _ar1(rng: np.random.Generator, n: int, rho: float) -> np.ndarray:
    e = rng.standard_normal(n)
    x = np.empty(n)
    x[0] = e[0] / math.sqrt(1 - rho ** 2)
    for k in range(1, n):
        x[k] = rho * x[k - 1] + e[k]
    return x


def test_hac_standard_error_matches_the_scatter_of_the_estimate_under_ar1_errors() -> None:
    """y = a + b t + AR(1) (ρ = 0.7), 300 repetitions: the mean HAC s.e. of b is within 20 %
    of the estimate's actual scatter and its 95 % intervals cover b in ≥ 90 %; the white-noise
    formula is too narrow by more than 40 % (why the fit uses HAC)."""
    rng = np.random.default_rng(36)
    n, reps, rho = 800, 300, 0.7
    t = np.linspace(0.0, 1.0, n)
    jac = np.column_stack([np.ones(n), t])  # residual a + b t − y: its Jacobian is X
    estimates, hac_se, white_se, covered = [], [], [], 0
    for _ in range(reps):
        y = 1.0 + 2.0 * t + _ar1(rng, n, rho)
        coef, *_ = np.linalg.lstsq(jac, y, rcond=None)
        r = jac @ coef - y
        cov = hac_covariance(jac, r, [[slice(0, n)]]).covariance
        se = math.sqrt(cov[1, 1])
        s2 = float(r @ r) / (n - 2)
        white_se.append(math.sqrt(s2 * np.linalg.inv(jac.T @ jac)[1, 1]))
        hac_se.append(se)
        estimates.append(coef[1])
        covered += abs(coef[1] - 2.0) <= 1.96 * se
    scatter = float(np.std(estimates))
    assert 0.8 <= float(np.mean(hac_se)) / scatter <= 1.2
    assert covered >= 0.90 * reps
    assert float(np.mean(white_se)) / scatter < 0.6


def test_andrews_bandwidth_of_a_scalar_ar1() -> None:
    """Andrews (1991) Eq. (6.4), Bartlett: b = 1.1447 (α T)^(1/3), α = 4ρ²/((1−ρ)²(1+ρ)²)."""
    rng = np.random.default_rng(1)
    n, rho = 20000, 0.6
    x = _ar1(rng, n, rho)
    alpha = 4 * rho ** 2 / ((1 - rho) ** 2 * (1 + rho) ** 2)
    expected = 1.1447 * (alpha * n) ** (1 / 3)
    assert andrews_bandwidth(x[:, None]) == pytest.approx(expected, rel=0.1)
    # white noise: a bandwidth of about one sample
    assert andrews_bandwidth(rng.standard_normal((n, 1))) < 3.0


def test_runs_test_and_autocorrelation() -> None:
    rng = np.random.default_rng(2)
    t = np.arange(5000) * 1e-3
    white = diagnose(rng.standard_normal(t.size), t)
    assert abs(white.runs_z) < 3.5
    assert abs(white.autocorrelation[0]) < 0.05
    n1 = n2 = 2500  # alternating signs: every sample its own run
    alternating = diagnose(np.where(np.arange(t.size) % 2 == 0, 1.0, -1.0), t)
    assert alternating.runs == t.size
    assert alternating.runs_expected == 1 + 2 * n1 * n2 / (n1 + n2)
    slow = diagnose(_ar1(rng, t.size, 0.95), t)
    assert slow.runs_z < -20
    assert slow.autocorrelation[0] > 0.9


def test_spectrum_peak_of_a_sine_in_noise() -> None:
    rng = np.random.default_rng(3)
    t = np.arange(2000) * 1e-3  # 2 s at 1 kHz: bins of 0.5 Hz
    d = diagnose(np.sin(2 * np.pi * 7.0 * t) + 0.1 * rng.standard_normal(t.size), t)
    assert d.peak_frequency == pytest.approx(7.0, abs=1e-9)
    assert d.peak_share > 0.9
    assert "7 Hz" in d.describe()


def test_bandwidth_stability_is_reported() -> None:
    """White residuals: the s.e. at b/2 and 2b within the stability limit of that at b."""
    rng = np.random.default_rng(4)
    n = 2000
    jac = np.column_stack([np.ones(n), np.linspace(0, 1, n)])
    hac = hac_covariance(jac, rng.standard_normal(n), [[slice(0, n)]])
    assert hac.stable
    assert all(abs(r - 1) <= STABILITY_LIMIT for row in hac.stderr_ratio for r in row)
    assert hac.to_dict()["bandwidth_rule"].startswith("Andrews (1991)")
