"""What a fit's residual says, and intervals that stay valid when it is not white noise.

The residual of a quantised, closed-loop record is correlated (a ramp read by an encoder
leaves a sawtooth, a loop leaves its own dynamics in the misfit), so the textbook covariance
s²(JᵀJ)⁻¹, which assumes independent errors, can be far too narrow.  Here, per fitted signal:

* the residual's **autocorrelation** at lags 1 … :data:`DIAGNOSTIC_LAGS` (Box, Jenkins &
  Reinsel [1]_, Sect. 2.1);
* the **runs test** of its signs (Wald & Wolfowitz [2]_): the number of runs above and below
  zero against its expectation under independence, as a z score;
* its **spectrum**: the periodogram's largest peak (mean removed), its frequency and the share
  of the residual's variance it holds;

and for the parameters the **heteroscedasticity- and autocorrelation-consistent (HAC)
sandwich covariance** (Newey & West [3]_) of the least-squares estimating equation Jᵀr = 0:

    cov = (JᵀJ)⁻¹ S (JᵀJ)⁻¹,   S = Σ_records [Γ₀ + Σ_{l≥1} k(l/b) (Γ_l + Γ_lᵀ)],

with g_t the score of sample time t (Σ over the record's signals of J_{t,·} r_t: the signals
of one record share its clock, so their cross-correlation is kept), Γ_l = Σ_t g_t g_{t−l}ᵀ,
the Bartlett kernel k(x) = 1 − |x| (|x| < 1) and the bandwidth b chosen from the data by
Andrews' AR(1) plug-in rule [4]_, b = 1.1447 (α̂(1) T)^{1/3}, per record.  Records are
independent of each other.  The bandwidth is shown stable: the standard errors are recomputed
with b/2 and 2b (:data:`BANDWIDTH_FACTORS`); when one moves by more than
:data:`STABILITY_LIMIT` the largest of the three is used and the result says so.

References
----------
.. [1] G. E. P. Box, G. M. Jenkins, G. C. Reinsel, Time Series Analysis, 4th ed., Wiley, 2008.
.. [2] A. Wald, J. Wolfowitz, "On a test whether two samples are from the same population",
   Ann. Math. Statist. 11 (1940) 147–162.
.. [3] W. K. Newey, K. D. West, "A simple, positive semi-definite, heteroskedasticity and
   autocorrelation consistent covariance matrix", Econometrica 55 (1987) 703–708.
.. [4] D. W. K. Andrews, "Heteroskedasticity and autocorrelation consistent covariance matrix
   estimation", Econometrica 59 (1991) 817–858 (Sect. 6, Eq. (6.4); the Bartlett constant
   1.1447).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["BANDWIDTH_FACTORS", "DIAGNOSTIC_LAGS", "MAX_AR_COEFFICIENT", "STABILITY_LIMIT",
           "HacCovariance", "ResidualDiagnostics", "andrews_bandwidth", "diagnose",
           "hac_covariance"]

#: lags of the autocorrelation reported [samples]
DIAGNOSTIC_LAGS = 10
#: the AR(1) coefficient of a score component is capped here before the bandwidth rule
#: (ρ → 1 makes α̂(1) unbounded; Andrews 1991 Sect. 6 caps it likewise)
MAX_AR_COEFFICIENT = 0.97
#: the bandwidth never exceeds this fraction of the record's samples
MAX_BANDWIDTH_FRACTION = 0.25
#: the bandwidth factors of the stability check
BANDWIDTH_FACTORS = (0.5, 2.0)
#: a standard error that moves by more than this fraction between b/2, b and 2b: unstable
STABILITY_LIMIT = 0.25


@dataclass(frozen=True)
class ResidualDiagnostics:
    """The structure of one fitted signal's residual.

    Parameters
    ----------
    autocorrelation : tuple of float
        At lags 1 … :data:`DIAGNOSTIC_LAGS` [-].
    runs : int
        Runs of equal sign [-].
    runs_expected : float
        Their expectation under independence [-].
    runs_z : float
        (runs − expected) / sd [-]; strongly negative: long runs, a structured residual.
    peak_frequency : float
        Frequency of the periodogram's largest peak [Hz].
    peak_share : float
        Share of the residual's variance in that peak's bin [-].
    """

    autocorrelation: tuple[float, ...]
    runs: int
    runs_expected: float
    runs_z: float
    peak_frequency: float
    peak_share: float

    def describe(self) -> str:
        """One phrase: lag-1 autocorrelation, runs z score, spectral peak.

        Returns
        -------
        str
            The phrase.
        """
        acf1 = self.autocorrelation[0] if self.autocorrelation else math.nan
        return (f"lag-1 autocorrelation {acf1:+.2f}, runs z {self.runs_z:+.1f}, spectrum "
                f"peak at {self.peak_frequency:.3g} Hz ({100 * self.peak_share:.0f} % of the "
                "variance)")

    def to_dict(self) -> dict[str, Any]:
        """The diagnostics for JSON (non-finite numbers as None).

        Returns
        -------
        dict
            The fields.
        """
        def fin(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None

        return {"autocorrelation": [fin(a) for a in self.autocorrelation], "runs": self.runs,
                "runs_expected": fin(self.runs_expected), "runs_z": fin(self.runs_z),
                "peak_frequency_hz": fin(self.peak_frequency),
                "peak_share": fin(self.peak_share)}


def diagnose(residual: np.ndarray, time: np.ndarray) -> ResidualDiagnostics:
    """Autocorrelation, runs test and spectral peak of one residual series.

    Parameters
    ----------
    residual : numpy.ndarray
        The residual [any unit], on ``time``.
    time : numpy.ndarray
        Sample times [s] (the median step is taken as the sampling interval).

    Returns
    -------
    ResidualDiagnostics
        The structure found.
    """
    r = np.asarray(residual, dtype=float)
    n = r.size
    x = r - r.mean()
    var = float(x @ x)
    lags = min(DIAGNOSTIC_LAGS, max(n - 1, 0))
    acf = tuple(float(x[k:] @ x[:-k] / var) if var > 0 else math.nan
                for k in range(1, lags + 1))
    # Wald–Wolfowitz runs of sign about zero (the residual of a right model has mean ≈ 0)
    signs = r[r != 0] > 0
    n1, n2 = int(signs.sum()), int((~signs).sum())
    runs = int(1 + np.count_nonzero(signs[1:] != signs[:-1])) if signs.size else 0
    m = n1 + n2
    if n1 and n2:
        expected = 1.0 + 2.0 * n1 * n2 / m
        sd2 = 2.0 * n1 * n2 * (2.0 * n1 * n2 - m) / (m * m * (m - 1.0))
        z = (runs - expected) / math.sqrt(sd2) if sd2 > 0 else math.nan
    else:
        expected, z = math.nan, math.nan
    dt = float(np.median(np.diff(time))) if n > 1 else math.nan
    power = np.abs(np.fft.rfft(x)) ** 2
    power[0] = 0.0
    total = float(power.sum())
    if total > 0 and power.size > 1 and dt > 0:
        k = int(np.argmax(power))
        peak_f, share = k / (n * dt), float(power[k] / total)
    else:
        peak_f, share = math.nan, math.nan
    return ResidualDiagnostics(autocorrelation=acf, runs=runs, runs_expected=expected,
                               runs_z=z, peak_frequency=peak_f, peak_share=share)


def andrews_bandwidth(scores: np.ndarray) -> float:
    """Andrews' (1991) AR(1) plug-in bandwidth of the Bartlett kernel for a series of score
    vectors: each component fitted by AR(1) (coefficient ρ_a, innovation variance σ_a²,
    ρ_a capped at ±:data:`MAX_AR_COEFFICIENT`), equal weights,

        α̂(1) = Σ 4ρ²σ⁴/((1−ρ)⁶(1+ρ)²) / Σ σ⁴/(1−ρ)⁴,   b = 1.1447 (α̂(1) T)^{1/3},

    at least 1 and at most ``MAX_BANDWIDTH_FRACTION`` of T.

    Parameters
    ----------
    scores : numpy.ndarray
        T × p scores [any unit].

    Returns
    -------
    float
        The bandwidth b [samples].

    References
    ----------
    .. [1] D. W. K. Andrews, Econometrica 59 (1991) 817–858, Eqs. (6.2)–(6.4).
    """
    g = np.asarray(scores, dtype=float)
    t = g.shape[0]
    num = den = 0.0
    for a in range(g.shape[1]):
        y = g[:, a]
        y0, y1 = y[:-1], y[1:]
        s00 = float(y0 @ y0)
        if s00 <= 0:
            continue
        rho = float(np.clip((y0 @ y1) / s00, -MAX_AR_COEFFICIENT, MAX_AR_COEFFICIENT))
        sig2 = float(np.mean((y1 - rho * y0) ** 2))
        num += 4 * rho ** 2 * sig2 ** 2 / ((1 - rho) ** 6 * (1 + rho) ** 2)
        den += sig2 ** 2 / (1 - rho) ** 4
    alpha = num / den if den > 0 else 0.0
    b = 1.1447 * (alpha * t) ** (1.0 / 3.0)
    return float(min(max(b, 1.0), MAX_BANDWIDTH_FRACTION * t))


def _long_run(g: np.ndarray, b: float) -> np.ndarray:
    """Γ₀ + Σ_{l<b} (1 − l/b)(Γ_l + Γ_lᵀ) of scores ``g`` (Bartlett kernel, bandwidth b)."""
    s = g.T @ g
    for lag in range(1, int(math.ceil(b))):
        w = 1.0 - lag / b
        if w <= 0:
            break
        gamma = g[lag:].T @ g[:-lag]
        s = s + w * (gamma + gamma.T)
    return np.asarray(s)


@dataclass(frozen=True)
class HacCovariance:
    """A HAC sandwich covariance and how it was made.

    Parameters
    ----------
    covariance : numpy.ndarray
        p × p covariance [parameter units²].
    bandwidths : tuple of float
        The bandwidth of each record [samples].
    stderr_ratio : tuple of tuple of float
        Per parameter, its standard error at b/2 and 2b over that at b [-].
    stable : bool
        Whether every ratio is within 1 ± :data:`STABILITY_LIMIT`.
    """

    covariance: np.ndarray
    bandwidths: tuple[float, ...]
    stderr_ratio: tuple[tuple[float, ...], ...]
    stable: bool

    def to_dict(self) -> dict[str, Any]:
        """How the covariance was made, for JSON.

        Returns
        -------
        dict
            ``method``, ``kernel``, ``bandwidth_rule``, ``bandwidths_samples``,
            ``stderr_ratio_half_double`` and ``stable``.
        """
        return {"method": "HAC sandwich (Newey & West 1987)", "kernel": "Bartlett",
                "bandwidth_rule": "Andrews (1991) AR(1) plug-in, per record",
                "bandwidths_samples": [float(b) for b in self.bandwidths],
                "stderr_ratio_half_double": [list(r) for r in self.stderr_ratio],
                "stable": self.stable}


def hac_covariance(jac: np.ndarray, residual: np.ndarray,
                   records: Sequence[Sequence[slice]]) -> HacCovariance:
    """The HAC sandwich covariance of a least-squares estimate (module docstring).

    Parameters
    ----------
    jac : numpy.ndarray
        n × p Jacobian of the (weighted) residual at the optimum [residual unit per
        parameter unit].
    residual : numpy.ndarray
        The n residuals there [residual unit].
    records : sequence of sequence of slice
        Per record, the slices of its signals in ``residual`` (the same length each: the
        signals of a record share its sample times).

    Returns
    -------
    HacCovariance
        The covariance, the bandwidths and the stability check; a parameter on a null
        direction of J has infinite variance.
    """
    jac = np.asarray(jac, dtype=float)
    p = jac.shape[1]
    scores = []
    for slices in records:
        g = sum(jac[s] * residual[s, None] for s in slices)
        scores.append(np.asarray(g))
    bands = tuple(andrews_bandwidth(g) for g in scores)
    _, sv, vt = np.linalg.svd(jac, full_matrices=False)
    tol = float(sv.max(initial=0.0)) * max(jac.shape) * np.finfo(float).eps
    keep = sv > tol
    bread = (vt[keep].T / sv[keep] ** 2) @ vt[keep]  # (JᵀJ)⁺

    def sandwich(factor: float) -> np.ndarray:
        meat = np.zeros((p, p))
        for g, b in zip(scores, bands, strict=True):
            meat += _long_run(g, max(1.0, factor * b))
        cov = bread @ meat @ bread
        null = vt[~keep]
        if null.size:
            loose = np.any(np.abs(null) > 1e-8, axis=0)
            cov[loose, :] = math.inf
            cov[:, loose] = math.inf
        return np.asarray(cov)

    cov = sandwich(1.0)
    with np.errstate(all="ignore"):
        se = np.sqrt(np.diag(cov))
        others = [np.sqrt(np.diag(sandwich(f))) / se for f in BANDWIDTH_FACTORS]
    ratios = tuple(tuple(float(o[j]) for o in others) for j in range(p))
    finite = [r for row in ratios for r in row if math.isfinite(r)]
    stable = all(abs(r - 1.0) <= STABILITY_LIMIT for r in finite)
    if not stable:  # the widest of the three: never a bandwidth that happens to be narrow
        worst = np.maximum.reduce([np.diag(cov)] + [o ** 2 * np.diag(cov) for o in others])
        with np.errstate(all="ignore"):
            scale = np.sqrt(np.where(np.diag(cov) > 0, worst / np.diag(cov), 1.0))
        cov = cov * np.outer(scale, scale)
    return HacCovariance(covariance=cov, bandwidths=bands, stderr_ratio=ratios, stable=stable)
