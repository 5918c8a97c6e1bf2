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
from scipy.optimize import least_squares

from ..model.mechanisms import mechanism
from ..parameters import DriveParameters, FrictionBranch, LuGreParameters, ParameterError
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

    Parameters
    ----------
    time, force, position:
        Samples [s], applied force [N] and displacement [m] (any zero: an offset is fitted).
        The test must start at rest; the force must stay below breakaway (|F| < F_s).
    mass:
        The moving mass [kg] the force acts on (for a rotary site, the inertia referred to
        the table: J/H²).
    friction:
        Static branches and σ2 of the site (e.g. from
        :func:`~feeddrive.analysis.static_fit.fit_static` via
        :meth:`~feeddrive.analysis.static_fit.StaticFit.lugre`, or a parameter set); its σ0,
        σ1 only seed the fit.  Required for ``model="lugre"``; for ``model="linear"`` σ2 is
        taken from it (mean of the branches) or 0 without it, in which case the fitted σ1 is
        σ1 + σ2.
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
