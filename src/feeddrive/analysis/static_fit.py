"""Static (Stribeck) friction identification from constant-speed tests.  SI units.

At constant sliding speed v the LuGre force is the steady curve
F(v) = sign(v)·[F_c + (F_s − F_c)·exp(−(v/v_s)²)] + σ2·v  (Wang2021 Eqs. 9–11), fitted per
direction by nonlinear least squares — the first step of the standard two-step procedure for
the LuGre model (Canudas de Wit et al., IEEE TAC 40(3), 1995; Åström & Canudas de Wit, IEEE
CSM 28(6), 2008); the second, the pre-sliding fit of σ0 and σ1, is
:mod:`feeddrive.analysis.presliding`.  Wang2021 Sect. 4 takes its Table 1 values from earlier
identifications (Liu et al. 2015, Du et al. 2018) and does not describe the procedure.
Intervals and identifiability: :mod:`feeddrive.analysis.fit_statistics`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from scipy.optimize import least_squares

from ..model.friction.lugre_parameters import FrictionBranch, LuGreParameters
from ..units import LARGEST_SPEED
from .fit_statistics import (
    Estimate,
    correlation,
    covariance,
    estimate,
    locate,
    t_quantile,
    with_correlation,
)

__all__ = ["MAX_TEST_FORCE", "MAX_TEST_SPEED", "MIN_SPEEDS_PER_DIRECTION", "BranchFit",
           "StaticFit", "fit_branch", "fit_static", "stribeck_curve"]

Weighting = Literal["relative", "absolute"]

#: distinct test speeds needed per direction (4 parameters + at least one degree of freedom)
MIN_SPEEDS_PER_DIRECTION = 5


@dataclass(frozen=True)
class BranchFit:
    """Fit of one direction's steady friction curve.  Speeds and forces as magnitudes.

    Parameters
    ----------
    direction : str
        ``"positive"`` or ``"negative"``.
    branch : FrictionBranch
        The fitted F_c, F_s, v_s, σ2.
    coulomb_force : Estimate
        F_c [N].
    static_force : Estimate
        F_s [N].
    stribeck_velocity : Estimate
        v_s [m/s].
    viscous_coefficient : Estimate
        σ2 [N s/m].
    speed : numpy.ndarray
        Tested speeds, magnitudes [m/s].
    force : numpy.ndarray
        Measured forces, magnitudes [N].
    fitted : numpy.ndarray
        Fitted forces [N].
    lines : numpy.ndarray of int or None
        File line of every test.
    rmse : float
        RMS of force − fitted [N].
    dof : int
        Degrees of freedom.
    correlation : numpy.ndarray
        Correlation of (F_c, F_s − F_c, v_s, σ2) [-].
    """

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
        """Measured minus fitted force at each tested speed [N]."""
        return self.force - self.fitted

    def estimates(self) -> dict[str, Estimate]:
        """The four estimates by parameter name.

        Returns
        -------
        dict of str to Estimate
            ``coulomb_force``, ``static_force``, ``stribeck_velocity``, ``viscous_coefficient``.
        """
        return {
            "coulomb_force": self.coulomb_force,
            "static_force": self.static_force,
            "stribeck_velocity": self.stribeck_velocity,
            "viscous_coefficient": self.viscous_coefficient,
        }

    def unidentifiable(self) -> dict[str, str]:
        """Name → reason of every estimate the data do not determine.

        Returns
        -------
        dict of str to str
            Empty when every estimate is determined.
        """
        return {name: est.identifiability_issue for name, est in self.estimates().items()
                if est.identifiability_issue is not None}


@dataclass(frozen=True)
class StaticFit:
    """Both directions of a static identification.

    Parameters
    ----------
    positive : BranchFit or None
        The + branch; None when no test went that way.
    negative : BranchFit or None
        The − branch.
    source : str, optional
        The data file.
    """

    positive: BranchFit | None
    negative: BranchFit | None
    source: str | None = None

    def __repr__(self) -> str:
        # what a notebook prints: the estimates per branch, never the tests' arrays
        parts = []
        for name, b in self.branches().items():
            shaky = len(b.unidentifiable())
            note = f", {shaky} not determined" if shaky else ""
            parts.append(f"{'+' if name == 'positive' else '−'} F_c {b.coulomb_force.value:.4g}"
                         f", F_s {b.static_force.value:.4g} N, v_s "
                         f"{1e3 * b.stribeck_velocity.value:.4g} mm/s, σ2 "
                         f"{b.viscous_coefficient.value:.4g} N s/m{note}")
        name = self.source or ""
        src = f" {name if len(name) <= 32 else '…' + name[-31:]!r}" if name else ""
        return f"<feeddrive.StaticFit{src}: {'; '.join(parts)}; .positive .negative, .lugre()>"

    @property
    def one_direction(self) -> str | None:
        """The only direction fitted (a record with tests in one direction), else None."""
        if self.positive is None:
            return "negative"
        return "positive" if self.negative is None else None

    def branches(self) -> dict[str, BranchFit]:
        """The fitted branches (one only for a one-direction record).

        Returns
        -------
        dict of str to BranchFit
            Direction → fit.
        """
        return {k: b for k, b in (("positive", self.positive), ("negative", self.negative))
                if b is not None}

    def lugre(self, bristle_stiffness: float, bristle_damping: float) -> LuGreParameters:
        """The LuGre parameters the simulation takes, with σ0 [N/m] and σ1 [N s/m] given
        (e.g. from a base parameter set or
        :func:`~feeddrive.analysis.presliding.fit_presliding`).

        Parameters
        ----------
        bristle_stiffness : float
            σ0 [N/m].
        bristle_damping : float
            σ1 [N s/m].

        Returns
        -------
        LuGreParameters
            The site.

        Raises
        ------
        ValueError
            When only one direction was fitted.
        """
        if self.positive is None or self.negative is None:
            raise ValueError(f"only the {self.one_direction} branch was fitted (tests in one "
                             "direction); merge the fragment into a parameter set, which keeps "
                             "its other branch")
        return LuGreParameters(positive=self.positive.branch, negative=self.negative.branch,
                               bristle_stiffness=bristle_stiffness,
                               bristle_damping=bristle_damping)

    def to_dict(self, units: Literal["SI", "mm"] = "SI") -> dict[str, Any]:
        """The fit for the JSON report (``feeddrive identify static --json``).

        Parameters
        ----------
        units : {"SI", "mm"}, default "SI"
            Unit of the Stribeck velocity.

        Returns
        -------
        dict
            Source, the one direction (if so) and, per branch, the estimates, RMS error [N], the
            unidentifiable ones, the number of tests and the degrees of freedom.
        """
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


def stribeck_curve(theta: np.ndarray, v: np.ndarray) -> np.ndarray:
    """F_c + (F_s − F_c)·exp(−(v/v_s)²) + σ2·v [N] at speeds ``v`` [m/s] (Wang2021 Eq. 11).

    Parameters
    ----------
    theta : numpy.ndarray
        (F_c [N], F_s − F_c [N], v_s [m/s], σ2 [N s/m]), the fit's parameter vector.
    v : numpy.ndarray
        Speed magnitudes [m/s].

    Returns
    -------
    numpy.ndarray
        The steady friction force magnitude [N].

    References
    ----------
    .. [1] Wang2021 Eq. (11), Table 1..
    """
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

    Parameters
    ----------
    speed : array_like
        Tested speeds, magnitudes [m/s].
    force : array_like
        Measured friction forces, magnitudes [N].
    direction : str, default "positive"
        The branch's direction, for the result and messages.
    confidence : float, default 0.95
        Level of the intervals [-].
    weighting : {"relative", "absolute"}, default "relative"
        The noise model.
    lines : numpy.ndarray of int, optional
        File line of every test, for messages.

    Returns
    -------
    BranchFit
        The fit.

    Raises
    ------
    ValueError
        For an unknown weighting.

    References
    ----------
    .. [1] M. A. Branch, T. F. Coleman, Y. Li, "A subspace, interior, and conjugate gradient
       method for large-scale bound-constrained minimization problems", SIAM J. Sci.
       Comput. 21 (1999) 1–23.
    .. [2] Wang2021 Eq. (11), Table 1 (the curve).
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
        m = stribeck_curve(th, v)
        return np.log(np.maximum(m, 1e-300)) - np.log(f) if relative else m - f

    def jac(th: np.ndarray) -> np.ndarray:
        j = _stribeck_jac(th, v)
        return j / stribeck_curve(th, v)[:, None] if relative else j

    best = None
    for vs_0 in np.geomspace(max(float(np.min(v)), 1.1e-7), min(v_scale, 0.099), 8):
        x0 = np.array([fc_0, dF_0, vs_0, s2_0])
        res = least_squares(resid, x0, jac=jac, bounds=(lower, upper), x_scale=x_scale,
                            method="trf", xtol=1e-12, ftol=1e-12, gtol=1e-12)
        if best is None or res.cost < best.cost:
            best = res
    assert best is not None
    theta = best.x
    fitted = stribeck_curve(theta, v)
    ssr = float(np.sum(resid(theta) ** 2))
    dof = n - 4
    cov = covariance(jac(theta), ssr, dof)
    tq = t_quantile(confidence, dof)
    fc, dF, vs, s2 = (float(x) for x in theta)
    var_fs = cov[0, 0] + cov[1, 1] + 2.0 * cov[0, 1]
    corr = correlation(cov)
    # the reported parameters are (F_c, F_s = F_c + ΔF, v_s, σ2): their correlations
    to_reported = np.eye(4)
    to_reported[1, 0] = 1.0
    with np.errstate(all="ignore"):
        reported = correlation(to_reported @ cov @ to_reported.T)
    names = ("F_c", "F_s", "v_s", "σ2")
    branch = FrictionBranch(coulomb_force=fc, static_force=fc + dF, stribeck_velocity=vs,
                            viscous_coefficient=s2)
    ests = [with_correlation(e, reported, i, names) for i, e in enumerate((
        estimate(fc, cov[0, 0], tq, "N", confidence),
        estimate(fc + dF, var_fs, tq, "N", confidence),
        estimate(vs, cov[2, 2], tq, "m/s", confidence),
        estimate(s2, cov[3, 3], tq, "N s/m", confidence)))]
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


#: largest |speed| [m/s] a friction test can hold (far above any feed drive)
MAX_TEST_SPEED = LARGEST_SPEED
#: largest |force| [N] a friction test can hold
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

    Each direction tested needs at least :data:`MIN_SPEEDS_PER_DIRECTION` distinct speeds,
    spread over the Stribeck region (around v_s) and the viscous region (well above it).  A
    record with tests in one direction only gives that branch only (the other is None;
    :attr:`StaticFit.one_direction` names the fitted one).

    Parameters
    ----------
    speed : array_like
        Sliding speed of each test, signed: positive tests give the + branch, negative tests
        the − branch (Wang2021 Table 1's direction convention) [m/s].
    force : array_like
        Friction force of each test, signed (friction has the sign of the speed) or as
        magnitudes; within one direction the sign must not change [N].
    confidence : float, default 0.95
        Level of the reported confidence intervals [-].
    weighting : {"relative", "absolute"}, default "relative"
        Noise proportional to the force, or of constant size; see :func:`fit_branch`.
    lines : numpy.ndarray of int, optional
        File line numbers of the tests, used in error messages.
    source : str, optional
        The file name, used in error messages.

    Returns
    -------
    StaticFit
        Both branches (or the one tested).

    Raises
    ------
    ValueError
        For mismatched or non-finite arrays, a zero speed, a value beyond any feed drive, a
        confidence outside [0.5, 1), too few distinct speeds in a direction, or a force that is
        zero or changes sign within a direction.

    References
    ----------
    .. [1] Wang2021 Table 1, Eq. (11).
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
            raise ValueError(f"{prefix}{locate(lines, int(bad[0]))}: {name} is not finite")
    zero = np.flatnonzero(v == 0.0)
    if zero.size:
        raise ValueError(f"{prefix}{locate(lines, int(zero[0]))}: speed 0 is not a sliding "
                         "test; the static fit needs constant non-zero speeds")
    # values no feed drive reaches (a wrong unit or a damaged file) would overflow the fit
    for name, arr, limit, unit, edge in (("speed", v, MAX_TEST_SPEED, "m/s", 1e3),
                                         ("force", f, MAX_TEST_FORCE, "N", 1.0)):
        big = np.flatnonzero(np.abs(arr) > limit)
        if big.size:
            k = int(big[0])
            edge_unit = "mm/s" if name == "speed" else unit
            raise ValueError(f"{prefix}{locate(lines, k)}: {name} {arr[k] * edge:.4g} "
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
            raise ValueError(f"{prefix}{locate(lines, k)}: friction force 0 while sliding")
        if np.any(signs != signs[0]):
            k = int(idx[np.flatnonzero(signs != signs[0])[0]])
            raise ValueError(f"{prefix}{locate(lines, k)}: the force changes sign within the "
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
