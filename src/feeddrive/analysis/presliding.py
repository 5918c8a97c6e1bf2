"""Pre-sliding friction identification: σ0 and σ1 of a LuGre contact.  SI units.

Below breakaway the bristles deflect with the body (pre-sliding, z ≈ x), so a mass m under a
measured force F(t) obeys m ẍ + σ0 z + σ1 ż + σ2 ẋ = F — the second step of the standard
two-step procedure for the LuGre model (Canudas de Wit et al., IEEE TAC 40(3), 1995; Åström &
Canudas de Wit, IEEE CSM 28(6), 2008), after the static fit of the branches
(:mod:`feeddrive.analysis.static_fit`).  σ0 and σ1 are fitted to the measured displacement by
simulating that model (output error) on the package's engine
(:mod:`feeddrive.analysis.presliding_rig`), either the full LuGre bristle equation with the
static branches known (``model="lugre"``) or its linearisation
m ẍ + (σ1 + σ2) ẋ + σ0 x = F (``model="linear"``, valid for |F| ≪ F_s).

σ1 is often poorly determined (it only shows in fast transients); the fit reports a
profile-likelihood interval and says so plainly.  The moving mass of a test at a drive's
friction site is what the drive's mechanism declares (:func:`site_mass`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from scipy import stats
from scipy.optimize import brentq, least_squares

from ..model.friction.lugre_parameters import FrictionBranch, LuGreParameters
from ..model.mechanisms import mechanism
from ..parameters import DriveParameters, ParameterError
from .fit_statistics import (
    Estimate,
    covariance,
    estimate,
    finite_or_none,
    locate,
    noise_level,
    t_quantile,
)
from .presliding_rig import simulate_presliding
from .static_fit import StaticFit

__all__ = ["LINEAR_MAX_FORCE_RATIO", "MAX_PRESLIDING_DISPLACEMENT", "MAX_RESIDUAL_RATIO",
           "MAX_STEP_RATIO", "SIGMA1_MAX_RELATIVE_STDERR", "DynamicFit", "fit_presliding",
           "site_mass"]


@dataclass(frozen=True)
class DynamicFit:
    """Pre-sliding identification of σ0 [N/m] and σ1 [N s/m].

    ``sigma1_determined`` is False when the data do not pin σ1 down (relative standard
    error above ``SIGMA1_MAX_RELATIVE_STDERR`` or an unbounded profile interval); then
    report ``sigma1_interval`` rather than ``bristle_damping.value``.

    Parameters
    ----------
    model : str
        ``"lugre"`` or ``"linear"``.
    mass : float
        The moving mass [kg].
    bristle_stiffness : Estimate
        σ0 [N/m].
    bristle_damping : Estimate
        σ1 [N s/m].
    viscous_coefficient : float
        σ2 held fixed [N s/m].
    sigma1_determined : bool
        Whether the data pin σ1 down.
    sigma1_interval : tuple of (float, float)
        Profile interval of σ1; the upper end may be inf [N s/m].
    note : str
        What to make of σ1, in words.
    time : numpy.ndarray
        Sample times [s].
    force : numpy.ndarray
        Applied force [N].
    position : numpy.ndarray
        Measured displacement [m].
    fitted : numpy.ndarray
        Model displacement, offset included [m].
    position_offset : float
        The measurement's zero relative to the rest position [m].
    rmse : float
        RMS residual [m].
    dof : int
        Degrees of freedom.
    profile_sigma1 : numpy.ndarray
        σ1 grid of the profile [N s/m].
    profile_ssr : numpy.ndarray
        Residual sum of squares along it [m²].
    ssr_threshold : float
        The F-test bound [m²].
    force_ratio : float or None
        max|F| / F_s [-]; None when F_s is unknown.
    correlation : float
        Correlation between the σ0 and σ1 estimates [-].
    source : str, optional
        The data file.
    lines : numpy.ndarray of int, optional
        File line of every sample.
    noise : float, default nan
        The record's noise level, from the data alone [m].
    residual_ok : bool, default True
        Whether the RMS residual is within the allowed multiple of the noise.
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
        """Measured minus fitted displacement [m]."""
        return self.position - self.fitted

    def lugre(self, static: LuGreParameters | StaticFit) -> LuGreParameters:
        """Combine with static branches into the parameters the simulation takes.

        σ1 is taken as fitted even when it is poorly determined (a value is needed to
        simulate); check ``sigma1_determined`` and ``note``.

        Parameters
        ----------
        static : LuGreParameters or StaticFit
            The static branches (and σ2).

        Returns
        -------
        LuGreParameters
            The site with the fitted σ0 and σ1.

        Raises
        ------
        ValueError
            For a static fit with one direction only.
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
        """The fit for the JSON report (``feeddrive identify dynamic --json``).

        Returns
        -------
        dict
            Source, model, mass [kg], the σ0 and σ1 estimates, whether σ1 is determined and its
            profile interval, the fit's residual and noise, and the note.
        """
        low, high = self.sigma1_interval
        return {
            "source": self.source,
            "model": self.model,
            "mass": self.mass,
            "bristle_stiffness": self.bristle_stiffness.to_dict(),
            "bristle_damping": self.bristle_damping.to_dict(),
            "bristle_damping_determined": self.sigma1_determined,
            "bristle_damping_profile_interval": [low, finite_or_none(high)],
            "viscous_coefficient_fixed": self.viscous_coefficient,
            "correlation_sigma0_sigma1": finite_or_none(self.correlation),
            "position_offset": self.position_offset,
            "rmse": self.rmse,
            "points": int(self.time.size),
            "force_ratio": self.force_ratio,
            "noise": finite_or_none(self.noise),
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
#: robust scale of its second differences,
#: :func:`~feeddrive.analysis.fit_statistics.noise_level`) does not explain the record:
#: nothing is called determined (issue 22: a 1.04e3-nm residual on a 3.5-µm record was
#: reported with σ1 "determined ±1 %")
MAX_RESIDUAL_RATIO = 2.0


#: largest displacement span [m] of a pre-sliding record.  Pre-sliding is the micrometre
#: regime below breakaway (Wang2021 Sect. 4; Al-Bender et al. 2004: a few µm to tens of µm).
#: A record that spans more has slid; a fit to it returns a meaningless σ0 (a 10-mm sliding
#: record gave 4.5e-5 N/µm against 36.4, issue 12 item 5).
MAX_PRESLIDING_DISPLACEMENT = 100e-6

#: points of the geometric σ1 grid (1e-3 … 1 × ten times critical damping) the profile is
#: first evaluated on.  It only brackets the interval's edges: each edge is then located
#: where the profile itself crosses its threshold (a root-finder on the refitted SSR,
#: ``PROFILE_EDGE_RTOL``), so the bound does not depend on this number (interpolated
#: linearly between these points it moved 3–4 % with the grid: 4.09e+04 at 13 points,
#: 4.24e+04 at 49 or 193; an outside check, 2026-12-07).
PROFILE_GRID_POINTS = 13

#: relative tolerance [-] of a σ1 profile interval's edge (scipy.optimize.brentq's ``rtol``):
#: well below the three significant digits the interval is printed with
PROFILE_EDGE_RTOL = 1e-6


def _check_presliding(t: np.ndarray, f: np.ndarray, x: np.ndarray, mass: float,
                      lines: np.ndarray | None, prefix: str) -> None:
    for name, arr in (("time", t), ("force", f), ("position", x)):
        if arr.ndim != 1:
            raise ValueError(f"{prefix}{name}: expected a 1-D array")
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise ValueError(f"{prefix}{locate(lines, int(bad[0]))}: {name} is not finite")
    if not (t.size == f.size == x.size):
        raise ValueError(f"{prefix}force, position: expected one value per time sample")
    if t.size < 20:
        raise ValueError(f"{prefix}time: {t.size} samples; the pre-sliding fit needs at least 20")
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0)
    if bad.size:
        raise ValueError(f"{prefix}{locate(lines, int(bad[0]) + 1)}: time does not increase")
    # the model is integrated with a fixed number of steps per sample interval, set by the
    # longest one: a gap would multiply the work of every interval
    k = int(np.argmax(steps))
    median = float(np.median(steps))
    if steps[k] > MAX_STEP_RATIO * median:
        raise ValueError(f"{prefix}{locate(lines, k + 1)}: time jumps by {steps[k]:.6g} s, "
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

    σ1 is profiled: for each σ1 on a grid, σ0 is refitted; the interval where the residual
    stays within the F-test bound for ``confidence`` is ``sigma1_interval``, each edge the
    root of the profile itself between the grid points that bracket it (to a relative
    ``PROFILE_EDGE_RTOL``), so that it does not depend on the grid.

    Parameters
    ----------
    time : array_like
        Sample times [s]; the test must start at rest.
    force : array_like
        Applied force, below breakaway (|F| < F_s) [N].
    position : array_like
        Displacement (any zero: an offset is fitted) [m].
    mass : float
        The moving mass the force acts on (for a rotary site, the inertia referred to the
        table: J/H²) [kg].
    friction : LuGreParameters, optional
        Static branches and σ2 of the site (e.g. from
        :func:`~feeddrive.analysis.static_fit.fit_static` via
        :meth:`~feeddrive.analysis.static_fit.StaticFit.lugre`, or a parameter set); its σ0,
        σ1 only seed the fit.  Required for ``model="lugre"``; for ``model="linear"`` σ2 is
        taken from it (mean of the branches) or 0 without it, in which case the fitted σ1 is
        σ1 + σ2.
    model : {"lugre", "linear"}, default "lugre"
        ``"lugre"`` simulates the full bristle equation (Wang2021 Eq. (11)); ``"linear"`` the
        linearised pre-sliding dynamics m ẍ + (σ1 + σ2) ẋ + σ0 x = F.  The LuGre bristle
        equation softens with load, so the linear fit underestimates σ0 by up to about
        2·max|F|/F_s after force steps (less under symmetric sines): keep |F| ≤ 0.02 F_s with
        it.
    confidence : float, default 0.95
        Level of the intervals [-].
    lines : numpy.ndarray of int, optional
        File line of every sample, for messages.
    source : str, optional
        The file name, for messages.
    progress : callable, optional
        Receives a short line at each stage of a long fit (start k of 3, profile point i of
        n, the interval's edges).

    Returns
    -------
    DynamicFit
        σ0, σ1 with their intervals, and the fit's residuals.

    Raises
    ------
    ValueError
        For arrays that are not 1-D of one length or not finite, fewer than 20 samples, time
        that does not increase or jumps, a non-positive mass, a constant or too large
        displacement (the table slid), a constant force, an unknown model, or the LuGre model
        without ``friction``.

    References
    ----------
    .. [1] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    .. [2] D. M. Bates, D. G. Watts, Nonlinear Regression Analysis and Its Applications,
       Wiley, 1988 (profile intervals).
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
            raise ValueError(f"{prefix}{locate(lines, k)}: |force| = {abs(f[k]):.4g} N reaches "
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
            return simulate_presliding(t, f, mass, params, model=model)
        except ValueError:  # out of the parameters' range, or the simulation failed
            return np.full(t.size, np.nan)

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
    cov = covariance(jac, ssr, dof)
    tq = t_quantile(confidence, dof)
    sd = np.sqrt(np.abs(np.diag(cov)))
    corr = float(cov[0, 1] / (sd[0] * sd[1])) if np.all(sd > 0) and np.all(np.isfinite(sd)) \
        else math.nan

    # profile of σ1: refit σ0 at each σ1 of a grid spanning 0 … 10× critical damping
    s1_max = 10.0 * 2.0 * math.sqrt(s0_hat * mass)
    grid = np.unique(np.concatenate([
        [0.0], np.geomspace(1e-3, 1.0, PROFILE_GRID_POINTS) * s1_max,
        s1_hat + sd[1] * np.array([-3.0, -2.0, -1.0, 1.0, 2.0, 3.0]) if np.isfinite(sd[1])
        else np.array([]),
        [s1_hat],
    ]))
    grid = grid[(grid >= 0.0) & (grid <= s1_max)]
    prof = np.empty(grid.size)
    s0_at = np.empty(grid.size)  # the refitted σ0 at each grid point [N/m]
    i_hat = int(np.argmin(np.abs(grid - s1_hat)))
    prof[i_hat], s0_at[i_hat] = ssr, s0_hat
    # continuation: walk away from the optimum, each refit starting from its neighbour's σ0
    done = 0
    for order in (range(i_hat + 1, grid.size), range(i_hat - 1, -1, -1)):
        s0_prev = s0_hat
        for i in order:
            done += 1
            say(f"profiling σ1: point {done} of {grid.size - 1}")
            res = fit(float(grid[i]), (s0_prev, float(grid[i])))
            prof[i] = 2.0 * res.cost * scale**2
            s0_prev = s0_at[i] = float(res.x[0] * s0_init)
    threshold = ssr * (1.0 + float(stats.f.ppf(confidence, 1, dof)) / dof)

    def profile(s1: float, s0_start: float) -> float:
        """The profiled SSR at σ1 [m²]: σ0 refitted from ``s0_start``."""
        return float(2.0 * fit(s1, (s0_start, s1)).cost * scale**2)

    say("profiling σ1: locating the interval's edges")
    low, high, edges = _profile_interval(grid, prof, threshold, s1_hat, profile, s0_at)
    if edges:  # the edges on the profile, so that it crosses the threshold where they are
        where = np.concatenate([grid, [e[0] for e in edges]])
        by_s1 = np.argsort(where, kind="stable")
        grid, prof = where[by_s1], np.concatenate([prof, [e[1] for e in edges]])[by_s1]

    s0_est = estimate(s0_hat, cov[0, 0], tq, "N/m", confidence)
    s1_est = estimate(s1_hat, cov[1, 1], tq, "N s/m", confidence)
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


def _profile_interval(grid: np.ndarray, prof: np.ndarray, threshold: float, s1_hat: float,
                      profile: Callable[[float, float], float], s0_at: np.ndarray,
                      ) -> tuple[float, float, list[tuple[float, float]]]:
    """Where the profiled SSR crosses ``threshold`` on each side of the optimum [N s/m]: the
    grid brackets each crossing (the first grid point outside, walking away from the
    optimum, and its inner neighbour); the edge is the root of ``profile(σ1, σ0 start) −
    threshold`` in that bracket (:func:`scipy.optimize.brentq`, relative tolerance
    :data:`PROFILE_EDGE_RTOL`, σ0 refitted from the inner point's), not a linear
    interpolation between the grid points, which moved with the grid.  Returns (low, high,
    the edges located as (σ1, SSR) pairs); ``low`` is the grid's first point (0) and
    ``high`` inf when the profile stays within the threshold to that end."""
    inside = prof <= threshold
    i_hat = int(np.argmin(np.abs(grid - s1_hat)))
    edges: list[tuple[float, float]] = []

    def edge(inner: int, outer: int) -> float:
        known = {float(grid[inner]): float(prof[inner]), float(grid[outer]): float(prof[outer])}
        start = float(s0_at[inner])

        def excess(s1: float) -> float:
            value = known[s1] if s1 in known else profile(s1, start)
            known[s1] = value
            return value - threshold

        a, b = sorted((float(grid[inner]), float(grid[outer])))
        root = float(brentq(excess, a, b, xtol=1e-12 * max(abs(b), 1.0),
                            rtol=PROFILE_EDGE_RTOL))
        edges.append((root, known[root] if root in known else threshold))
        return root

    lo_i = i_hat
    while lo_i > 0 and inside[lo_i - 1]:
        lo_i -= 1
    low = float(grid[0]) if lo_i == 0 and inside[0] else edge(lo_i, lo_i - 1)
    hi_i = i_hat
    while hi_i < grid.size - 1 and inside[hi_i + 1]:
        hi_i += 1
    high = math.inf if hi_i == grid.size - 1 and inside[-1] else edge(hi_i, hi_i + 1)
    return low, high, edges


def site_mass(params: DriveParameters, site: str, drive: str) -> float:
    """Moving mass of a pre-sliding test at a friction site, as the drive's mechanism
    declares it (:meth:`~feeddrive.model.mechanisms.base.Mechanism.site_masses`).

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    site : str
        The site's friction parameters: ``friction.<site>`` (e.g. ``"screw"``), or the dotted
        path a part keeps them at.
    drive : str
        The drive topology (``"cdfs"``, ``"ddfs"``, ``"linear-motor"``, ``"rack-pinion"``).

    Returns
    -------
    float
        The mass [kg], referred to the site's sliding speed (a rotary site: inertia / H²).
    """
    # a site's moving mass depends on neither the table position nor how a nut is held
    masses = mechanism(drive)(params, drive, 0.0, "locked").site_masses()
    if site not in masses:
        raise ParameterError("site", site, f"expected one of {', '.join(masses)} "
                             f"(the friction sites of the {drive} drive)")
    return masses[site]
