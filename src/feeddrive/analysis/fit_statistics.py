"""Statistics of a least-squares fit: estimates with confidence intervals, identifiability,
the noise of a record.  SI units.

Confidence intervals come from the Jacobian at the optimum, s²(JᵀJ)⁻¹ with the Student t
quantile for n − p degrees of freedom (Seber & Wild, *Nonlinear Regression*, Wiley 1989,
Sect. 5.1).  A value is *identifiable* when its interval is finite and narrower than
±:data:`MAX_RELATIVE_HALF_WIDTH` of it and it does not correlate beyond
:data:`MAX_CORRELATION` with another fitted value.  Shared by the friction fits
(:mod:`~feeddrive.analysis.static_fit`, :mod:`~feeddrive.analysis.presliding`) and the
whole-drive fit (:mod:`~feeddrive.analysis.fit`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["MAX_CORRELATION", "MAX_RELATIVE_HALF_WIDTH", "NOISE_MIN_SAMPLES", "Estimate",
           "correlation",
           "covariance", "estimate", "finite_or_none", "locate", "noise_level", "t_quantile",
           "with_correlation"]


#: a fitted value is flagged unidentifiable when its confidence interval's half-width
#: exceeds this fraction of |value| (the data do not pin it down to within ±50 %)
MAX_RELATIVE_HALF_WIDTH = 0.5

#: ... or when its estimate correlates more than this (in magnitude) with another fitted
#: parameter: the data fix only a combination of the two
MAX_CORRELATION = 0.995

#: fewest samples :func:`noise_level` estimates a noise σ from (nan below)
NOISE_MIN_SAMPLES = 8


@dataclass(frozen=True)
class Estimate:
    """A fitted value with its standard error and two-sided confidence interval (SI unit).

    ``max_correlation`` is the largest |correlation| of this estimate with another fitted
    parameter (``correlated_with``); with the interval it decides :attr:`identifiable`.

    Parameters
    ----------
    value : float
        The estimate [unit].
    stderr : float
        Its standard error [unit].
    low : float
        Lower end of the confidence interval [unit].
    high : float
        Upper end [unit].
    unit : str
        The SI unit.
    confidence : float
        Level of the interval [-].
    max_correlation : float, default nan
        Largest |correlation| with another fitted parameter [-].
    correlated_with : str, optional
        That parameter.
    """

    value: float
    stderr: float
    low: float
    high: float
    unit: str
    confidence: float
    max_correlation: float = math.nan
    correlated_with: str | None = None

    @property
    def relative_stderr(self) -> float:
        """|stderr / value| [-]; inf for a zero value."""
        return abs(self.stderr / self.value) if self.value != 0 else math.inf

    @property
    def identifiability_issue(self) -> str | None:
        """Why the data do not determine this value, or None when they do."""
        level = f"{100 * self.confidence:.0f} %"
        if not (math.isfinite(self.low) and math.isfinite(self.high)):
            return f"{level} interval not determined"
        half = 0.5 * (self.high - self.low)
        if self.value == 0.0 or half > MAX_RELATIVE_HALF_WIDTH * abs(self.value):
            return (f"{level} interval wider than ±{100 * MAX_RELATIVE_HALF_WIDTH:.0f} % of the "
                    "value")
        if math.isfinite(self.max_correlation) and abs(self.max_correlation) > MAX_CORRELATION:
            return (f"correlation {self.max_correlation:+.4f} with {self.correlated_with}: the "
                    "data fix only a combination of the two")
        return None

    @property
    def identifiable(self) -> bool:
        """Whether the data determine the value (no ``identifiability_issue``)."""
        return self.identifiability_issue is None

    def to_dict(self, scale: float = 1.0, unit: str | None = None) -> dict[str, Any]:
        """The estimate for JSON, optionally rescaled for display.

        Parameters
        ----------
        scale : float, default 1.0
            Factor applied to the value, error and interval [display unit per SI unit].
        unit : str, optional
            The display unit; the SI unit by default.

        Returns
        -------
        dict
            ``value``, ``stderr``, ``ci_low``, ``ci_high`` [unit], ``unit``, ``confidence``, the
            largest correlation and its partner, and the identifiability verdict.
        """
        return {
            "value": self.value * scale,
            "stderr": finite_or_none(self.stderr * scale),
            "ci_low": finite_or_none(self.low * scale),
            "ci_high": finite_or_none(self.high * scale),
            "unit": unit or self.unit,
            "confidence": self.confidence,
            "max_correlation": finite_or_none(self.max_correlation),
            "correlated_with": self.correlated_with,
            "identifiable": self.identifiable,
            "identifiability_issue": self.identifiability_issue,
        }


def with_correlation(est: Estimate, corr: np.ndarray, i: int,
                     names: tuple[str, ...]) -> Estimate:
    """``est`` (parameter ``i`` of ``names``) with its largest correlation to another.

    Parameters
    ----------
    est : Estimate
        The estimate.
    corr : numpy.ndarray
        Correlation matrix of the fitted parameters [-].
    i : int
        Its index.
    names : tuple of str
        The parameters' names.

    Returns
    -------
    Estimate
        ``est`` with ``max_correlation`` and ``correlated_with`` set.
    """
    row = np.where(np.arange(corr.shape[0]) == i, 0.0, np.nan_to_num(np.abs(corr[i]), nan=0.0))
    j = int(np.argmax(row))
    if row.size < 2 or not np.isfinite(corr[i, j]):
        return est
    return dataclasses.replace(est, max_correlation=float(corr[i, j]),
                               correlated_with=names[j])


def correlation(cov: np.ndarray) -> np.ndarray:
    """The correlation matrix of covariance ``cov`` (NaN where a variance is not finite).

    Parameters
    ----------
    cov : numpy.ndarray
        Covariance matrix [SI, per pair].

    Returns
    -------
    numpy.ndarray
        Correlation matrix [-].
    """
    with np.errstate(all="ignore"):
        sd = np.sqrt(np.where(np.isfinite(np.diag(cov)), np.diag(cov), np.nan))
        return np.asarray(cov / np.outer(sd, sd))


def finite_or_none(x: float) -> float | None:
    """``x``, or None when it is not finite (JSON has no inf).

    Parameters
    ----------
    x : float
        The value [any unit].

    Returns
    -------
    float or None
        ``x`` or None.
    """
    return float(x) if math.isfinite(x) else None


def t_quantile(confidence: float, dof: int) -> float:
    """Two-sided Student t quantile at ``confidence`` for ``dof`` degrees of freedom.

    Parameters
    ----------
    confidence : float
        Two-sided level, e.g. 0.95 [-].
    dof : int
        Degrees of freedom.

    Returns
    -------
    float
        The quantile [-]; inf without degrees of freedom.
    """
    from scipy import stats  # here: ≈ 0.7 s to import, for the fits only

    return float(stats.t.ppf(0.5 + confidence / 2.0, dof)) if dof > 0 else math.inf


def covariance(jac: np.ndarray, ssr: float, dof: int) -> np.ndarray:
    """s²(JᵀJ)⁻¹ by SVD.  Parameters that move along a (numerically) null direction of J
    get infinite variance; the others keep the pseudo-inverse variance.

    Parameters
    ----------
    jac : numpy.ndarray
        Jacobian of the residuals at the optimum [residual unit per parameter unit].
    ssr : float
        Sum of squared residuals [residual unit²].
    dof : int
        Degrees of freedom.

    Returns
    -------
    numpy.ndarray
        Covariance of the parameters [parameter units²].

    References
    ----------
    .. [1] D. M. Bates, D. G. Watts, Nonlinear Regression Analysis and Its Applications,
       Wiley, 1988, Sect. 2.3.
    """
    s2 = ssr / dof if dof > 0 else math.inf
    _, sv, vt = np.linalg.svd(jac, full_matrices=False)
    tol = float(sv.max(initial=0.0)) * max(jac.shape) * np.finfo(float).eps
    keep = sv > tol
    cov = (vt[keep].T / sv[keep] ** 2) @ vt[keep] * s2
    null = vt[~keep]
    if null.size:
        loose = np.any(np.abs(null) > 1e-8, axis=0)
        cov[loose, :] = math.inf
        cov[:, loose] = math.inf
    return np.asarray(cov)


def estimate(value: float, var: float, tq: float, unit: str, confidence: float) -> Estimate:
    """An :class:`Estimate` of ``value`` with variance ``var`` and t quantile ``tq``.

    Parameters
    ----------
    value : float
        The value [unit].
    var : float
        Its variance [unit²].
    tq : float
        The t quantile [-].
    unit : str
        The unit.
    confidence : float
        Level of the interval [-].

    Returns
    -------
    Estimate
        Value ± tq·√var.
    """
    se = math.sqrt(var) if var >= 0 and math.isfinite(var) else math.inf
    return Estimate(value=float(value), stderr=se, low=value - tq * se, high=value + tq * se,
                    unit=unit, confidence=confidence)


def locate(lines: np.ndarray | None, i: int) -> str:
    """Where sample ``i`` came from, for a message: its file line, else its index.

    Parameters
    ----------
    lines : numpy.ndarray of int or None
        File line of every sample.
    i : int
        The sample.

    Returns
    -------
    str
        ``"line N"`` or ``"index i"``.
    """
    return f"line {int(lines[i])}" if lines is not None else f"index {i}"


def noise_level(values: np.ndarray) -> float:
    """The noise σ of a sampled signal from the data alone: the robust (median absolute
    deviation) scale of its second differences / √6 (white noise e: var Δ²e = 6σ²), never
    below the record's resolution q/√12 (q the smallest step between samples: encoder or
    interferometer counts, or the printed digits).

    Parameters
    ----------
    values : numpy.ndarray
        The signal [its unit].

    Returns
    -------
    float
        σ [unit of the signal]; nan for fewer than :data:`NOISE_MIN_SAMPLES` (8) samples.
    """
    x = np.asarray(values, dtype=float)
    if x.size < NOISE_MIN_SAMPLES:
        return math.nan
    d2 = np.diff(x, 2)
    mad = float(np.median(np.abs(d2 - np.median(d2)))) * 1.4826 / math.sqrt(6.0)
    steps = np.abs(np.diff(x))
    steps = steps[steps > 1e-12 * max(float(np.max(np.abs(x))), 1e-300)]
    q = float(np.min(steps)) if steps.size else 0.0
    floor = 1e-9 * float(np.max(np.abs(x))) if x.size else 0.0
    return max(mad, q / math.sqrt(12.0), floor, 1e-300)
