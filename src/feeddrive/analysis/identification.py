"""LuGre friction identification from measurements: static (Stribeck) and dynamic (σ0, σ1).

Wang2021 Sect. 4 takes its Table 1 values from earlier identifications (Liu et al. 2015,
Du et al. 2018) and does not describe the procedure.  Here the standard two-step procedure
for the LuGre model is used (Canudas de Wit et al., IEEE TAC 40(3), 1995; Åström & Canudas
de Wit, IEEE CSM 28(6), 2008):

1. **Static**: at constant sliding speed v the LuGre force is the steady curve
   F(v) = sign(v)·[F_c + (F_s − F_c)·exp(−(v/v_s)²)] + σ2·v  (Wang2021 Eqs. 9–11),
   fitted per direction by nonlinear least squares to constant-speed tests.
2. **Dynamic**: below breakaway the bristles deflect with the body (pre-sliding, z ≈ x), so a
   mass m under a measured force F(t) obeys m ẍ + σ0 z + σ1 ż + σ2 ẋ = F.  σ0 and σ1 are
   fitted to the measured displacement by simulating that model (output error), either the
   full LuGre bristle equation with the static branches known (``model="lugre"``) or its
   linearisation m ẍ + (σ1 + σ2) ẋ + σ0 x = F (``model="linear"``, valid for |F| ≪ F_s).

Confidence intervals come from the Jacobian at the optimum, s²(JᵀJ)⁻¹ with the Student t
quantile for n − p degrees of freedom.  σ1 is often poorly determined (it only shows in fast
transients); the dynamic fit reports a profile-likelihood interval and says so plainly.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from scipy import stats
from scipy.optimize import least_squares

from .. import units
from .._jit import kernel
from ..model.friction.stribeck import bristle_rate_kernel
from ..parameters import DriveParameters, FrictionBranch, LuGreParameters, ParameterError

__all__ = [
    "MIN_SPEEDS_PER_DIRECTION",
    "SITES",
    "BranchFit",
    "DynamicFit",
    "Estimate",
    "StaticFit",
    "fit_branch",
    "fit_presliding",
    "fit_static",
    "simulate_presliding",
    "site_mass",
]

Weighting = Literal["relative", "absolute"]

#: distinct test speeds needed per direction (4 parameters + at least one degree of freedom)
MIN_SPEEDS_PER_DIRECTION = 5


#: a fitted value is flagged unidentifiable when its confidence interval's half-width
#: exceeds this fraction of |value| (the data do not pin it down to within ±50 %)
MAX_RELATIVE_HALF_WIDTH = 0.5

#: ... or when its estimate correlates more than this (in magnitude) with another fitted
#: parameter: the data fix only a combination of the two
MAX_CORRELATION = 0.995


@dataclass(frozen=True)
class Estimate:
    """A fitted value with its standard error and two-sided confidence interval (SI unit).

    ``max_correlation`` is the largest |correlation| of this estimate with another fitted
    parameter (``correlated_with``); with the interval it decides :attr:`identifiable`.
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
        return self.identifiability_issue is None

    def to_dict(self, scale: float = 1.0, unit: str | None = None) -> dict[str, Any]:
        return {
            "value": self.value * scale,
            "stderr": _finite_or_none(self.stderr * scale),
            "ci_low": _finite_or_none(self.low * scale),
            "ci_high": _finite_or_none(self.high * scale),
            "unit": unit or self.unit,
            "confidence": self.confidence,
            "max_correlation": _finite_or_none(self.max_correlation),
            "correlated_with": self.correlated_with,
            "identifiable": self.identifiable,
            "identifiability_issue": self.identifiability_issue,
        }


def _with_correlation(est: Estimate, corr: np.ndarray, i: int,
                      names: tuple[str, ...]) -> Estimate:
    """``est`` (parameter ``i`` of ``names``) with its largest correlation to another."""
    row = np.where(np.arange(corr.shape[0]) == i, 0.0, np.nan_to_num(np.abs(corr[i]), nan=0.0))
    j = int(np.argmax(row))
    if row.size < 2 or not np.isfinite(corr[i, j]):
        return est
    return dataclasses.replace(est, max_correlation=float(corr[i, j]),
                               correlated_with=names[j])


def _correlation(cov: np.ndarray) -> np.ndarray:
    with np.errstate(all="ignore"):
        sd = np.sqrt(np.where(np.isfinite(np.diag(cov)), np.diag(cov), np.nan))
        return np.asarray(cov / np.outer(sd, sd))


def _finite_or_none(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _t_quantile(confidence: float, dof: int) -> float:
    return float(stats.t.ppf(0.5 + confidence / 2.0, dof)) if dof > 0 else math.inf


def _covariance(jac: np.ndarray, ssr: float, dof: int) -> np.ndarray:
    """s²(JᵀJ)⁻¹ by SVD.  Parameters that move along a (numerically) null direction of J
    get infinite variance; the others keep the pseudo-inverse variance."""
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


def _estimate(value: float, var: float, tq: float, unit: str, confidence: float) -> Estimate:
    se = math.sqrt(var) if var >= 0 and math.isfinite(var) else math.inf
    return Estimate(value=float(value), stderr=se, low=value - tq * se, high=value + tq * se,
                    unit=unit, confidence=confidence)


# ================================================================ static identification


@dataclass(frozen=True)
class BranchFit:
    """Fit of one direction's steady friction curve.  Speeds and forces as magnitudes."""

    direction: str
    branch: FrictionBranch
    coulomb_force: Estimate
    static_force: Estimate
    stribeck_velocity: Estimate
    viscous_coefficient: Estimate
    speed: np.ndarray  # [m/s], magnitudes
    force: np.ndarray  # [N], magnitudes
    fitted: np.ndarray  # [N]
    lines: np.ndarray | None
    rmse: float  # [N], root mean square of force − fitted
    dof: int
    correlation: np.ndarray  # of (F_c, F_s − F_c, v_s, σ2)

    @property
    def residual(self) -> np.ndarray:
        return self.force - self.fitted

    def estimates(self) -> dict[str, Estimate]:
        return {
            "coulomb_force": self.coulomb_force,
            "static_force": self.static_force,
            "stribeck_velocity": self.stribeck_velocity,
            "viscous_coefficient": self.viscous_coefficient,
        }

    def unidentifiable(self) -> dict[str, str]:
        """Name → reason of every estimate the data do not determine."""
        return {name: est.identifiability_issue for name, est in self.estimates().items()
                if est.identifiability_issue is not None}


@dataclass(frozen=True)
class StaticFit:
    """Both directions of a static identification."""

    positive: BranchFit | None
    negative: BranchFit | None
    source: str | None = None

    @property
    def one_direction(self) -> str | None:
        """The only direction fitted (a record with tests in one direction), else None."""
        if self.positive is None:
            return "negative"
        return "positive" if self.negative is None else None

    def branches(self) -> dict[str, BranchFit]:
        """The fitted branches (one only for a one-direction record)."""
        return {k: b for k, b in (("positive", self.positive), ("negative", self.negative))
                if b is not None}

    def lugre(self, bristle_stiffness: float, bristle_damping: float) -> LuGreParameters:
        """The LuGre parameters the simulation takes, with σ0 [N/m] and σ1 [N s/m] given
        (e.g. from a base parameter set or :func:`fit_presliding`)."""
        if self.positive is None or self.negative is None:
            raise ValueError(f"only the {self.one_direction} branch was fitted (tests in one "
                             "direction); merge the fragment into a parameter set, which keeps "
                             "its other branch")
        return LuGreParameters(positive=self.positive.branch, negative=self.negative.branch,
                               bristle_stiffness=bristle_stiffness,
                               bristle_damping=bristle_damping)

    def to_dict(self, units: Literal["SI", "mm"] = "SI") -> dict[str, Any]:
        out: dict[str, Any] = {"source": self.source, "one_direction": self.one_direction}
        for name, b in self.branches().items():
            vs_scale, vs_unit = (1.0, "m/s") if units == "SI" else (1e3, "mm/s")
            out[name] = {
                "coulomb_force": b.coulomb_force.to_dict(),
                "static_force": b.static_force.to_dict(),
                "stribeck_velocity": b.stribeck_velocity.to_dict(vs_scale, vs_unit),
                "viscous_coefficient": b.viscous_coefficient.to_dict(),
                "rmse": b.rmse,
                "unidentifiable": b.unidentifiable(),
                "points": int(b.speed.size),
                "dof": b.dof,
            }
        return out


def _stribeck_model(theta: np.ndarray, v: np.ndarray) -> np.ndarray:
    fc, dF, vs, s2 = theta
    return np.asarray(fc + dF * np.exp(-((v / vs) ** 2)) + s2 * v)


def _stribeck_jac(theta: np.ndarray, v: np.ndarray) -> np.ndarray:
    _, dF, vs, _ = theta
    e = np.exp(-((v / vs) ** 2))
    return np.column_stack([np.ones_like(v), e, dF * e * 2.0 * v**2 / vs**3, v])


def fit_branch(speed: object, force: object, *, direction: str = "positive",
               confidence: float = 0.95, weighting: Weighting = "relative",
               lines: np.ndarray | None = None) -> BranchFit:
    """Fit F = F_c + (F_s − F_c)·exp(−(v/v_s)²) + σ2·v to one direction's tests.

    ``speed`` [m/s] and ``force`` [N] are magnitudes.  Nonlinear least squares
    (scipy.optimize.least_squares, trust-region reflective, bounds F_c ≥ 0, F_s ≥ F_c,
    v_s > 0, σ2 ≥ 0), started from several Stribeck velocities spread over the tested speeds;
    the lowest residual wins.  ``weighting="relative"`` minimises log-residuals
    ln F_model − ln F (noise proportional to the force); ``"absolute"`` plain residuals
    (noise of constant size).  The confidence intervals assume the chosen noise model:
    with the wrong one they are too narrow where the noise is underestimated.
    """
    if weighting not in ("relative", "absolute"):
        raise ValueError(f"weighting = {weighting!r}: expected 'relative' or 'absolute'")
    v = np.abs(np.asarray(speed, dtype=float))
    f = np.abs(np.asarray(force, dtype=float))
    n = v.size
    order = np.argsort(v)
    # initial guesses: viscous line through the faster half, breakaway from the slowest tests
    fast = order[n // 2:]
    if np.ptp(v[fast]) > 0:
        s2_0, fc_0 = np.polyfit(v[fast], f[fast], 1)
    else:
        s2_0, fc_0 = 0.0, float(np.min(f))
    s2_0 = max(float(s2_0), 0.0)
    fc_0 = float(np.clip(fc_0, 1e-9, np.max(f)))
    slow = order[: max(2, n // 5)]
    dF_0 = max(float(np.mean(f[slow] - s2_0 * v[slow])) - fc_0, 1e-3 * fc_0 + 1e-9)
    f_scale = max(float(np.max(f)), 1e-12)
    v_scale = float(np.max(v))
    x_scale = np.array([f_scale, f_scale, v_scale, f_scale / v_scale])
    lower = np.array([0.0, 0.0, 1e-7, 0.0])
    upper = np.array([np.inf, np.inf, 0.1, np.inf])
    relative = weighting == "relative"

    def resid(th: np.ndarray) -> np.ndarray:
        m = _stribeck_model(th, v)
        return np.log(np.maximum(m, 1e-300)) - np.log(f) if relative else m - f

    def jac(th: np.ndarray) -> np.ndarray:
        j = _stribeck_jac(th, v)
        return j / _stribeck_model(th, v)[:, None] if relative else j

    best = None
    for vs_0 in np.geomspace(max(float(np.min(v)), 1.1e-7), min(v_scale, 0.099), 8):
        x0 = np.array([fc_0, dF_0, vs_0, s2_0])
        res = least_squares(resid, x0, jac=jac, bounds=(lower, upper), x_scale=x_scale,
                            method="trf", xtol=1e-12, ftol=1e-12, gtol=1e-12)
        if best is None or res.cost < best.cost:
            best = res
    assert best is not None
    theta = best.x
    fitted = _stribeck_model(theta, v)
    ssr = float(np.sum(resid(theta) ** 2))
    dof = n - 4
    cov = _covariance(jac(theta), ssr, dof)
    tq = _t_quantile(confidence, dof)
    fc, dF, vs, s2 = (float(x) for x in theta)
    var_fs = cov[0, 0] + cov[1, 1] + 2.0 * cov[0, 1]
    corr = _correlation(cov)
    # the reported parameters are (F_c, F_s = F_c + ΔF, v_s, σ2): their correlations
    to_reported = np.eye(4)
    to_reported[1, 0] = 1.0
    with np.errstate(all="ignore"):
        reported = _correlation(to_reported @ cov @ to_reported.T)
    names = ("F_c", "F_s", "v_s", "σ2")
    branch = FrictionBranch(coulomb_force=fc, static_force=fc + dF, stribeck_velocity=vs,
                            viscous_coefficient=s2)
    ests = [_with_correlation(e, reported, i, names) for i, e in enumerate((
        _estimate(fc, cov[0, 0], tq, "N", confidence),
        _estimate(fc + dF, var_fs, tq, "N", confidence),
        _estimate(vs, cov[2, 2], tq, "m/s", confidence),
        _estimate(s2, cov[3, 3], tq, "N s/m", confidence)))]
    return BranchFit(
        direction=direction,
        branch=branch,
        coulomb_force=ests[0],
        static_force=ests[1],
        stribeck_velocity=ests[2],
        viscous_coefficient=ests[3],
        speed=v,
        force=f,
        fitted=fitted,
        lines=lines,
        rmse=float(np.sqrt(np.mean((f - fitted) ** 2))),
        dof=dof,
        correlation=corr,
    )


def _locate(lines: np.ndarray | None, i: int) -> str:
    return f"line {int(lines[i])}" if lines is not None else f"index {i}"


#: largest |speed| [m/s] and |force| [N] a friction test can hold (far above any feed drive)
MAX_TEST_SPEED = 100.0
MAX_TEST_FORCE = 1e7


def fit_static(
    speed: object,
    force: object,
    *,
    confidence: float = 0.95,
    weighting: Weighting = "relative",
    lines: np.ndarray | None = None,
    source: str | None = None,
) -> StaticFit:
    """Identify both friction branches from constant-speed tests.

    Parameters
    ----------
    speed:
        Sliding speed of each test [m/s], signed: positive tests give the + branch, negative
        tests the − branch (Wang2021 Table 1's direction convention).
    force:
        Friction force of each test [N]: signed (friction has the sign of the speed) or as
        magnitudes; within one direction the sign must not change.
    confidence:
        Level of the reported confidence intervals (default 0.95).
    weighting:
        ``"relative"`` (noise proportional to the force, the default) or ``"absolute"``;
        see :func:`fit_branch`.
    lines, source:
        File line numbers of the tests and the file name, used in error messages.

    Each direction tested needs at least :data:`MIN_SPEEDS_PER_DIRECTION` distinct speeds,
    spread over the Stribeck region (around v_s) and the viscous region (well above it).  A
    record with tests in one direction only gives that branch only (the other is None;
    :attr:`StaticFit.one_direction` names the fitted one).
    """
    v = np.asarray(speed, dtype=float)
    f = np.asarray(force, dtype=float)
    prefix = f"{source}: " if source else ""
    if v.ndim != 1 or f.ndim != 1 or v.size != f.size:
        raise ValueError(f"{prefix}force: expected one value per speed (got {f.shape} forces "
                         f"for {v.shape} speeds)")
    if not (0.5 <= confidence < 1.0):
        raise ValueError(f"confidence = {confidence!r}: expected a level in [0.5, 1)")
    if lines is not None and np.asarray(lines).size != v.size:
        raise ValueError("lines: expected one line number per test")
    for name, arr in (("speed", v), ("force", f)):
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise ValueError(f"{prefix}{_locate(lines, int(bad[0]))}: {name} is not finite")
    zero = np.flatnonzero(v == 0.0)
    if zero.size:
        raise ValueError(f"{prefix}{_locate(lines, int(zero[0]))}: speed 0 is not a sliding "
                         "test; the static fit needs constant non-zero speeds")
    # values no feed drive reaches (a wrong unit or a damaged file) would overflow the fit
    for name, arr, limit, unit, edge in (("speed", v, MAX_TEST_SPEED, "m/s", 1e3),
                                         ("force", f, MAX_TEST_FORCE, "N", 1.0)):
        big = np.flatnonzero(np.abs(arr) > limit)
        if big.size:
            k = int(big[0])
            edge_unit = "mm/s" if name == "speed" else unit
            raise ValueError(f"{prefix}{_locate(lines, k)}: {name} {arr[k] * edge:.4g} "
                             f"{edge_unit}: beyond any feed drive (|{name}| ≤ "
                             f"{limit * edge:g} {edge_unit}); check the file's unit")
    fits: dict[str, BranchFit | None] = {"positive": None, "negative": None}
    for direction, mask in (("positive", v > 0), ("negative", v < 0)):
        idx = np.flatnonzero(mask)
        if idx.size == 0 and np.any(~mask):
            continue  # a one-direction record: that branch only (issue 22)
        distinct = np.unique(np.abs(v[idx])).size
        if distinct < MIN_SPEEDS_PER_DIRECTION:
            other = "negative" if direction == "positive" else "positive"
            hint = (f"; the file has tests in the {other} direction only"
                    if idx.size == 0 else "")
            raise ValueError(f"{prefix}{distinct} distinct {direction} speed(s); the static fit "
                             f"needs at least {MIN_SPEEDS_PER_DIRECTION} per direction{hint}")
        signs = np.sign(f[idx])
        if np.any(signs == 0):
            k = int(idx[np.flatnonzero(signs == 0)[0]])
            raise ValueError(f"{prefix}{_locate(lines, k)}: friction force 0 while sliding")
        if np.any(signs != signs[0]):
            k = int(idx[np.flatnonzero(signs != signs[0])[0]])
            raise ValueError(f"{prefix}{_locate(lines, k)}: the force changes sign within the "
                             f"{direction}-speed tests (give signed forces or magnitudes)")
        sub_lines = None if lines is None else np.asarray(lines)[idx]
        try:
            fits[direction] = fit_branch(v[idx], f[idx], direction=direction,
                                         confidence=confidence, weighting=weighting,
                                         lines=sub_lines)
        except ValueError as err:  # the optimiser's own refusal: name the file
            if prefix and not str(err).startswith(prefix):
                raise ValueError(f"{prefix}{direction} branch: the fit failed ({err})") from None
            raise
    return StaticFit(positive=fits["positive"], negative=fits["negative"], source=source)


# ================================================================ dynamic identification


@kernel
def _presliding_rates(f: float, v: float, z: float, mass: float, p: np.ndarray,
                      linear: bool) -> tuple[float, float]:
    """(acceleration [m/s²], bristle rate [m/s]) of the mass under force f.

    ``linear``: pre-sliding as a linear spring–damper (ż = v); otherwise the LuGre rate.
    """
    zr = v if linear else bristle_rate_kernel(v, z, p)
    s2 = p[3] if v >= 0.0 else p[7]
    return (f - p[8] * z - p[9] * zr - s2 * v) / mass, zr


@kernel
def _presliding_kernel(t: np.ndarray, force: np.ndarray, mass: float, p: np.ndarray,
                       linear: bool, substeps: int) -> np.ndarray:
    """Displacement [m] of a mass on a LuGre contact under ``force``, classical RK4.

    Starts at rest in equilibrium (v = 0, z = x = F(0)/σ0); the force is linear between
    samples; ``substeps`` RK4 steps per sample interval.
    """
    n = t.size
    out = np.empty(n)
    x = force[0] / p[8]
    z = x
    v = 0.0
    out[0] = x
    for i in range(n - 1):
        h = (t[i + 1] - t[i]) / substeps
        df = (force[i + 1] - force[i]) / substeps
        for k in range(substeps):
            fa = force[i] + df * k
            fm = fa + 0.5 * df
            a1, zr1 = _presliding_rates(fa, v, z, mass, p, linear)
            v2, z2 = v + 0.5 * h * a1, z + 0.5 * h * zr1
            a2, zr2 = _presliding_rates(fm, v2, z2, mass, p, linear)
            v3, z3 = v + 0.5 * h * a2, z + 0.5 * h * zr2
            a3, zr3 = _presliding_rates(fm, v3, z3, mass, p, linear)
            v4, z4 = v + h * a3, z + h * zr3
            a4, zr4 = _presliding_rates(fa + df, v4, z4, mass, p, linear)
            x += h / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4)
            v += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
            z += h / 6.0 * (zr1 + 2.0 * zr2 + 2.0 * zr3 + zr4)
        out[i + 1] = x
    return out


def _substeps(t: np.ndarray, mass: float, sigma0: float, damping: float) -> int:
    """RK4 steps per sample so that h·max(√(σ0/m), c/m) ≤ 0.25 (error ≪ measurement noise)."""
    rate = max(math.sqrt(sigma0 / mass), damping / mass)
    h_max = 0.25 / rate
    return max(1, math.ceil(float(np.max(np.diff(t))) / h_max))


def simulate_presliding(time: object, force: object, mass: float, friction: LuGreParameters,
                        *, model: Literal["lugre", "linear"] = "lugre") -> np.ndarray:
    """Displacement [m] of a mass ``mass`` [kg] on a LuGre contact under ``force`` [N].

    ``model="lugre"``: m ẍ = F − (σ0 z + σ1 ż + σ2 ẋ), ż from Wang2021 Eq. (11);
    ``model="linear"``: z = x, i.e. m ẍ + (σ1 + σ2) ẋ + σ0 x = F with σ2 the mean of the two
    branches.  Starts at rest in equilibrium with the initial force; the force is linear
    between the samples at ``time`` [s].
    """
    t = np.asarray(time, dtype=float)
    f = np.asarray(force, dtype=float)
    p = friction.as_array()
    if model == "linear":
        p[3] = p[7] = 0.5 * (p[3] + p[7])
    elif model != "lugre":
        raise ValueError(f"model = {model!r}: expected 'lugre' or 'linear'")
    damping = p[9] + max(p[3], p[7])
    n_sub = _substeps(t, mass, p[8], damping)
    return np.asarray(_presliding_kernel(t, f, float(mass), p, model == "linear", n_sub))


@dataclass(frozen=True)
class DynamicFit:
    """Pre-sliding identification of σ0 [N/m] and σ1 [N s/m].

    ``sigma1_determined`` is False when the data do not pin σ1 down (relative standard
    error above ``SIGMA1_MAX_RELATIVE_STDERR`` or an unbounded profile interval); then
    report ``sigma1_interval`` rather than ``bristle_damping.value``.
    """

    model: str
    mass: float
    bristle_stiffness: Estimate
    bristle_damping: Estimate
    viscous_coefficient: float  # σ2 [N s/m] held fixed (from the static fit / parameter set)
    sigma1_determined: bool
    sigma1_interval: tuple[float, float]  # profile interval [N s/m]; high may be inf
    note: str
    time: np.ndarray
    force: np.ndarray
    position: np.ndarray  # measured [m]
    fitted: np.ndarray  # model [m], offset included
    position_offset: float  # [m], the measurement's zero relative to the rest position
    rmse: float  # [m]
    dof: int
    profile_sigma1: np.ndarray
    profile_ssr: np.ndarray
    ssr_threshold: float
    force_ratio: float | None  # max|F| / F_s (None when F_s unknown)
    correlation: float  # between σ0 and σ1 estimates
    source: str | None = None
    lines: np.ndarray | None = field(default=None, repr=False)
    noise: float = math.nan  # [m] the record's noise level, from the data alone
    residual_ok: bool = True  # rms residual ≤ MAX_RESIDUAL_RATIO × noise

    @property
    def residual(self) -> np.ndarray:
        return self.position - self.fitted

    def lugre(self, static: LuGreParameters | StaticFit) -> LuGreParameters:
        """Combine with static branches into the parameters the simulation takes.

        σ1 is taken as fitted even when it is poorly determined (a value is needed to
        simulate); check ``sigma1_determined`` and ``note``.
        """
        if isinstance(static, StaticFit):
            if static.positive is None or static.negative is None:
                static.lugre(0.0, 0.0)  # raises: one direction only
            assert static.positive is not None and static.negative is not None
            pos, neg = static.positive.branch, static.negative.branch
        else:
            pos, neg = static.positive, static.negative
        return LuGreParameters(positive=pos, negative=neg,
                               bristle_stiffness=self.bristle_stiffness.value,
                               bristle_damping=self.bristle_damping.value)

    def to_dict(self) -> dict[str, Any]:
        low, high = self.sigma1_interval
        return {
            "source": self.source,
            "model": self.model,
            "mass": self.mass,
            "bristle_stiffness": self.bristle_stiffness.to_dict(),
            "bristle_damping": self.bristle_damping.to_dict(),
            "bristle_damping_determined": self.sigma1_determined,
            "bristle_damping_profile_interval": [low, _finite_or_none(high)],
            "viscous_coefficient_fixed": self.viscous_coefficient,
            "correlation_sigma0_sigma1": _finite_or_none(self.correlation),
            "position_offset": self.position_offset,
            "rmse": self.rmse,
            "points": int(self.time.size),
            "force_ratio": self.force_ratio,
            "noise": _finite_or_none(self.noise),
            "residual_check": "passed" if self.residual_ok else "failed",
            "note": self.note,
        }


#: above this max|F|/F_s the linear pre-sliding model is flagged as biased
LINEAR_MAX_FORCE_RATIO = 0.02

#: largest sample interval of a pre-sliding test, as a multiple of the median interval
MAX_STEP_RATIO = 100.0

#: σ1 counts as determined when its standard error is at most this fraction of its value
SIGMA1_MAX_RELATIVE_STDERR = 0.25

#: a fit whose rms residual exceeds this multiple of the record's own noise level (the
#: robust scale of its second differences, :func:`noise_level`) does
#: not explain the record: nothing is called determined (issue 22: a 1.04e3-nm residual on a
#: 3.5-µm record was reported with σ1 "determined ±1 %")
MAX_RESIDUAL_RATIO = 2.0


# Pre-sliding is the micrometre regime below breakaway (Wang2021 Sect. 4; Al-Bender et al.
# 2004: a few µm to tens of µm).  A record that spans more has slid; a fit to it returns a
# meaningless σ0 (a 10-mm sliding record gave 4.5e-5 N/µm against 36.4, issue 12 item 5).
MAX_PRESLIDING_DISPLACEMENT = 100e-6  # [m]


def _check_presliding(t: np.ndarray, f: np.ndarray, x: np.ndarray, mass: float,
                      lines: np.ndarray | None, prefix: str) -> None:
    for name, arr in (("time", t), ("force", f), ("position", x)):
        if arr.ndim != 1:
            raise ValueError(f"{prefix}{name}: expected a 1-D array")
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise ValueError(f"{prefix}{_locate(lines, int(bad[0]))}: {name} is not finite")
    if not (t.size == f.size == x.size):
        raise ValueError(f"{prefix}force, position: expected one value per time sample")
    if t.size < 20:
        raise ValueError(f"{prefix}time: {t.size} samples; the pre-sliding fit needs at least 20")
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0)
    if bad.size:
        raise ValueError(f"{prefix}{_locate(lines, int(bad[0]) + 1)}: time does not increase")
    # the model is integrated with a fixed number of steps per sample interval, set by the
    # longest one: a gap would multiply the work of every interval
    k = int(np.argmax(steps))
    median = float(np.median(steps))
    if steps[k] > MAX_STEP_RATIO * median:
        raise ValueError(f"{prefix}{_locate(lines, k + 1)}: time jumps by {steps[k]:.6g} s, "
                         f"more than {MAX_STEP_RATIO:g}× the median step {median:.3g} s; a "
                         "pre-sliding test must be sampled evenly (split the record at the gap)")
    if not (isinstance(mass, int | float) and math.isfinite(mass) and mass > 0):
        raise ValueError(f"mass = {mass!r}: expected a positive mass [kg]")
    if np.ptp(x) == 0.0:
        raise ValueError(f"{prefix}position: constant; the test shows no displacement")
    if np.ptp(x) > MAX_PRESLIDING_DISPLACEMENT:
        raise ValueError(
            f"{prefix}position: spans {np.ptp(x) * 1e3:.4g} mm, not a pre-sliding test; "
            f"pre-sliding moves at most {MAX_PRESLIDING_DISPLACEMENT * 1e6:.0f} µm (the bristle "
            "deflection F_s/σ0 is 2.6 µm at wang2021's screw site); the table slid: fit "
            "constant-speed sliding tests with `identify static`, or check --position-unit")
    if np.ptp(f) == 0.0:
        raise ValueError(f"{prefix}force: constant; the test needs a varying force")


def fit_presliding(
    time: object,
    force: object,
    position: object,
    *,
    mass: float,
    friction: LuGreParameters | None = None,
    model: Literal["lugre", "linear"] = "lugre",
    confidence: float = 0.95,
    lines: np.ndarray | None = None,
    source: str | None = None,
    progress: Callable[[str], None] | None = None,
) -> DynamicFit:
    """Fit σ0 and σ1 to a pre-sliding test (force below breakaway).

    Parameters
    ----------
    time, force, position:
        Samples [s], applied force [N] and displacement [m] (any zero: an offset is fitted).
        The test must start at rest; the force must stay below breakaway (|F| < F_s).
    mass:
        The moving mass [kg] the force acts on (for a rotary site, the inertia referred to
        the table: J/H²).
    friction:
        Static branches and σ2 of the site (e.g. from :func:`fit_static` via
        :meth:`StaticFit.lugre`, or a parameter set); its σ0, σ1 only seed the fit.  Required
        for ``model="lugre"``; for ``model="linear"`` σ2 is taken from it (mean of the
        branches) or 0 without it, in which case the fitted σ1 is σ1 + σ2.
    model:
        ``"lugre"`` simulates the full bristle equation; ``"linear"`` the linearised
        pre-sliding dynamics m ẍ + (σ1 + σ2) ẋ + σ0 x = F.  The LuGre bristle equation
        softens with load, so the linear fit underestimates σ0 by up to about 2·max|F|/F_s
        after force steps (less under symmetric sines): keep |F| ≤ 0.02 F_s with it.

    σ1 is profiled: for each σ1 on a grid, σ0 is refitted; the interval where the residual
    stays within the F-test bound for ``confidence`` is ``sigma1_interval``.

    ``progress`` receives a short line at each stage of a long fit (start k of 3, profile
    point i of n).
    """
    say = progress or (lambda _text: None)
    t = np.asarray(time, dtype=float)
    f = np.asarray(force, dtype=float)
    x = np.asarray(position, dtype=float)
    prefix = f"{source}: " if source else ""
    _check_presliding(t, f, x, mass, lines, prefix)
    if model not in ("lugre", "linear"):
        raise ValueError(f"model = {model!r}: expected 'lugre' or 'linear'")
    if model == "lugre" and friction is None:
        raise ValueError("friction: model 'lugre' needs the static branches and σ2 of the site "
                         "(fit them first, or take them from a parameter set)")
    force_ratio: float | None = None
    if friction is not None:
        fs = min(friction.positive.static_force, friction.negative.static_force)
        force_ratio = float(np.max(np.abs(f)) / fs)
        if force_ratio >= 1.0:
            k = int(np.flatnonzero(np.abs(f) >= fs)[0])
            raise ValueError(f"{prefix}{_locate(lines, k)}: |force| = {abs(f[k]):.4g} N reaches "
                             f"the breakaway force F_s = {fs:.4g} N; a pre-sliding test must "
                             "stay below it")
        base = friction
        sigma2 = 0.5 * (friction.positive.viscous_coefficient
                        + friction.negative.viscous_coefficient)
    else:
        huge = FrictionBranch(coulomb_force=1e5, static_force=1e5, stribeck_velocity=0.1,
                              viscous_coefficient=0.0)
        base = LuGreParameters(positive=huge, negative=huge, bristle_stiffness=1.0,
                               bristle_damping=0.0)
        sigma2 = 0.0

    # quasi-static stiffness: slope of force against displacement seeds σ0
    slope = float(np.polyfit(x, f, 1)[0])
    s0_init = slope if slope > 0 else float(np.ptp(f) / np.ptp(x))
    s0_init = float(np.clip(s0_init, 1.0, 1e12))
    crit = 2.0 * math.sqrt(s0_init * mass)  # critical damping: the scale of σ1

    def simulate(s0: float, s1: float) -> np.ndarray:
        try:
            params = base.with_values(bristle_stiffness=s0, bristle_damping=s1)
        except ParameterError:
            return np.full(t.size, np.nan)
        return simulate_presliding(t, f, mass, params, model=model)

    def residual(s0: float, s1: float) -> np.ndarray:
        r = x - simulate(s0, s1)
        if not np.all(np.isfinite(r)):
            return np.full(t.size, 1e3 * float(np.ptp(x)))
        return np.asarray(r - np.mean(r))  # the measurement's zero is free

    scale = float(np.ptp(x))

    def fit(s1_fixed: float | None, start: tuple[float, float]) -> Any:
        """Fit (σ0, σ1) scaled by (s0_init, crit), or σ0 alone with σ1 fixed."""

        def fun(th: np.ndarray) -> np.ndarray:
            s1 = th[1] * crit if s1_fixed is None else s1_fixed
            return residual(th[0] * s0_init, s1) / scale

        if s1_fixed is None:
            x0 = np.array([start[0] / s0_init, start[1] / crit])
            bounds = (np.array([1e-3, 0.0]), np.array([1e3, 1e3]))
        else:
            x0 = np.array([start[0] / s0_init])
            bounds = (np.array([1e-3]), np.array([1e3]))
        return least_squares(fun, x0, bounds=bounds, method="trf", x_scale="jac",
                             diff_step=1e-6, xtol=1e-10, ftol=1e-12)

    best = None
    for k, s1_start in enumerate((0.02 * crit, 0.2 * crit, 1.0 * crit), start=1):
        say(f"fitting σ0 and σ1: start {k} of 3")
        res = fit(None, (s0_init, s1_start))
        if best is None or res.cost < best.cost:
            best = res
    assert best is not None
    s0_hat, s1_hat = float(best.x[0] * s0_init), float(best.x[1] * crit)
    r_hat = residual(s0_hat, s1_hat)
    ssr = float(np.sum(r_hat**2))
    n_par = 3  # σ0, σ1 and the offset
    dof = t.size - n_par
    jac = best.jac * scale / np.array([s0_init, crit])  # d residual / d (σ0, σ1) in SI
    cov = _covariance(jac, ssr, dof)
    tq = _t_quantile(confidence, dof)
    sd = np.sqrt(np.abs(np.diag(cov)))
    corr = float(cov[0, 1] / (sd[0] * sd[1])) if np.all(sd > 0) and np.all(np.isfinite(sd)) \
        else math.nan

    # profile of σ1: refit σ0 at each σ1 of a grid spanning 0 … 10× critical damping
    s1_max = 10.0 * 2.0 * math.sqrt(s0_hat * mass)
    grid = np.unique(np.concatenate([
        [0.0], np.geomspace(1e-3, 1.0, 13) * s1_max,
        s1_hat + sd[1] * np.array([-3.0, -2.0, -1.0, 1.0, 2.0, 3.0]) if np.isfinite(sd[1])
        else np.array([]),
        [s1_hat],
    ]))
    grid = grid[(grid >= 0.0) & (grid <= s1_max)]
    prof = np.empty(grid.size)
    i_hat = int(np.argmin(np.abs(grid - s1_hat)))
    prof[i_hat] = ssr
    # continuation: walk away from the optimum, each refit starting from its neighbour's σ0
    done = 0
    for order in (range(i_hat + 1, grid.size), range(i_hat - 1, -1, -1)):
        s0_prev = s0_hat
        for i in order:
            done += 1
            say(f"profiling σ1: point {done} of {grid.size - 1}")
            res = fit(float(grid[i]), (s0_prev, float(grid[i])))
            prof[i] = 2.0 * res.cost * scale**2
            s0_prev = float(res.x[0] * s0_init)
    threshold = ssr * (1.0 + float(stats.f.ppf(confidence, 1, dof)) / dof)
    low, high = _profile_interval(grid, prof, threshold, s1_hat, s1_max)

    s0_est = _estimate(s0_hat, cov[0, 0], tq, "N/m", confidence)
    s1_est = _estimate(s1_hat, cov[1, 1], tq, "N s/m", confidence)
    if math.isfinite(corr):
        s0_est = dataclasses.replace(s0_est, max_correlation=corr, correlated_with="σ1")
        s1_est = dataclasses.replace(s1_est, max_correlation=corr, correlated_with="σ0")
    noise = noise_level(x)
    rmse = math.sqrt(ssr / dof)
    residual_ok = rmse <= MAX_RESIDUAL_RATIO * noise
    determined = (residual_ok and s1_est.relative_stderr <= SIGMA1_MAX_RELATIVE_STDERR
                  and math.isfinite(high))
    if not residual_ok:
        note = (f"poor fit: the rms residual {rmse * 1e9:.3g} nm is {rmse / noise:.3g}× the "
                f"record's own noise {noise * 1e9:.3g} nm (from its second differences); the "
                "model does not explain this record, so neither σ0 nor σ1 is determined. "
                "Check the mass, the force channel and that the record stays in pre-sliding.")
    elif determined:
        note = (f"σ1 determined: {s1_hat:.4g} N s/m, ±{100 * s1_est.relative_stderr:.0f} % "
                f"(1 s.e.); σ2 = {sigma2:.4g} N s/m held fixed.")
    else:
        upper = f"{high:.3g}" if math.isfinite(high) else f"more than {s1_max:.3g}"
        note = (f"σ1 poorly determined: the data are consistent with σ1 from {low:.3g} to "
                f"{upper} N s/m ({100 * confidence:.0f} % profile); the test does not excite "
                "the pre-sliding resonance √(σ0/m) enough. Use a faster force transient, or "
                "keep σ1 from another source.")
    if model == "linear" and friction is None:
        note += " No σ2 given: the fitted σ1 is σ1 + σ2."
    if force_ratio is not None and model == "linear" and force_ratio > LINEAR_MAX_FORCE_RATIO:
        note += (f" max|F| = {100 * force_ratio:.0f} % of F_s: the linear model may "
                 f"underestimate σ0 by up to ~{200 * force_ratio:.0f} % (use model 'lugre').")
    fitted = x - r_hat
    return DynamicFit(
        model=model, mass=float(mass), bristle_stiffness=s0_est, bristle_damping=s1_est,
        viscous_coefficient=sigma2, sigma1_determined=determined, sigma1_interval=(low, high),
        note=note, time=t, force=f, position=x, fitted=fitted,
        position_offset=float(np.mean(x - simulate(s0_hat, s1_hat))),
        rmse=rmse, dof=dof, profile_sigma1=grid, profile_ssr=prof,
        ssr_threshold=threshold, force_ratio=force_ratio, correlation=corr, source=source,
        lines=lines, noise=noise, residual_ok=residual_ok,
    )


def noise_level(values: np.ndarray) -> float:
    """The noise σ of a sampled signal from the data alone: the robust (median absolute
    deviation) scale of its second differences / √6 (white noise e: var Δ²e = 6σ²), never
    below the record's resolution q/√12 (q the smallest step between samples: encoder or
    interferometer counts, or the printed digits)."""
    x = np.asarray(values, dtype=float)
    if x.size < 8:
        return math.nan
    d2 = np.diff(x, 2)
    mad = float(np.median(np.abs(d2 - np.median(d2)))) * 1.4826 / math.sqrt(6.0)
    steps = np.abs(np.diff(x))
    steps = steps[steps > 1e-12 * max(float(np.max(np.abs(x))), 1e-300)]
    q = float(np.min(steps)) if steps.size else 0.0
    floor = 1e-9 * float(np.max(np.abs(x))) if x.size else 0.0
    return max(mad, q / math.sqrt(12.0), floor, 1e-300)


def _profile_interval(grid: np.ndarray, prof: np.ndarray, threshold: float, s1_hat: float,
                      s1_max: float) -> tuple[float, float]:
    """Where the profiled SSR crosses ``threshold`` on each side of the optimum."""
    inside = prof <= threshold
    i_hat = int(np.argmin(np.abs(grid - s1_hat)))
    lo_i = i_hat
    while lo_i > 0 and inside[lo_i - 1]:
        lo_i -= 1
    if lo_i == 0 and inside[0]:
        low = float(grid[0])
    else:
        a, b = lo_i - 1, lo_i
        low = float(np.interp(threshold, [prof[b], prof[a]], [grid[b], grid[a]]))
    hi_i = i_hat
    while hi_i < grid.size - 1 and inside[hi_i + 1]:
        hi_i += 1
    if hi_i == grid.size - 1 and inside[-1]:
        high = math.inf
    else:
        a, b = hi_i, hi_i + 1
        high = float(np.interp(threshold, [prof[a], prof[b]], [grid[a], grid[b]]))
    return low, high



SITES = units.SITES


def site_mass(params: DriveParameters, site: str) -> float:
    """Moving mass [kg] of a pre-sliding test at a friction site, referred to the table.

    screw: (J_screw-motor + J_screw-shaft)/H²; nut: (J_hollow-motor + J_nut)/H²;
    guide: the table mass (Wang2021 Table 2; H = lead/2π, Eq. 8).  The rotary sites are
    stored in force form (Table 1 divides torques by H), so their inertia is divided by H².
    """
    h = params.screw.transmission_ratio
    if site == "screw":
        return (params.screw_motor.inertia + params.screw.shaft_inertia) / h**2
    if site == "nut":
        return (params.hollow_motor.inertia + params.screw.nut_inertia) / h**2
    if site == "guide":
        return params.table.mass
    raise ParameterError("site", site, f"expected one of {', '.join(SITES)}")
