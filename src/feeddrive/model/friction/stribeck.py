"""LuGre friction with Stribeck effect.  Wang2021 Eqs. (9)–(11), Table 1.

The LuGre force itself is :mod:`feeddrive.model.friction.lugre` (the engine's); this module
is its array API and the analytic indicators.  All functions use the linear (force) form of
Table 1: force in N, speed in m/s, bristle
deflection z in m.  The screw and hollow shafts are rotary sites; the paper divides their
torques by H = p_h/2π (:attr:`feeddrive.parameters.BallScrew.transmission_ratio`): T = H·F,
ω = v/H.

The scalar kernels (``*_kernel``) are numba-compiled and shared with the simulation engine,
so the physics exists once.  ``p`` is the float64[10] vector of
:meth:`feeddrive.parameters.LuGreParameters.as_array`:
(F_c+, F_s+, v_s+, σ2+, F_c−, F_s−, v_s−, σ2−, σ0, σ1).

Sign convention: the friction force has the sign of the sliding speed (it opposes motion when
subtracted in the equation of motion); the + branch applies for v ≥ 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ..._jit import kernel
from ...parameters import FrictionBranch, LuGreParameters
from . import lugre

# ---------------------------------------------------------------- compiled scalar kernels


@kernel
def stribeck_magnitude_kernel(v: float, p: np.ndarray) -> float:
    """σ0·g(v) = F_c + (F_s − F_c)·exp(−(v/v_s)²) [N] (Eq. 11, third line), branch by sign."""
    return lugre.stribeck_magnitude(v, p, 0)


@kernel
def steady_force_kernel(v: float, p: np.ndarray) -> float:
    """Steady-state friction: sign(v)·σ0·g(v) + σ2·v [N]; zero at v = 0."""
    if v == 0.0:
        return 0.0
    s = 1.0 if v > 0.0 else -1.0
    return s * lugre.stribeck_magnitude(v, p, 0) + p[lugre.branch(v, 0) + 3] * v


@kernel
def bristle_rate_kernel(v: float, z: float, p: np.ndarray) -> float:
    """dz/dt = v − σ0·|v|·z / (σ0·g(v)) [m/s].  Safe at v = 0 (g ≥ F_c > 0)."""
    return lugre.bristle_rate(v, z, p, 0)


@kernel
def force_kernel(v: float, z: float, p: np.ndarray) -> float:
    """F = σ0·z + σ1·dz/dt + σ2·v [N]."""
    return lugre.force(v, z, lugre.bristle_rate(v, z, p, 0), p, 0)


@kernel
def bristle_step_kernel(z: float, v: float, h: float, p: np.ndarray) -> float:
    """Exact bristle update over a step h with v held: z relaxes exponentially.

    dz/dt = v − λ z with λ = σ0|v|/(σ0 g(v)) ≥ 0, so
    z(h) = z_ss + (z − z_ss)·exp(−λh), z_ss = v/λ; for v = 0, z stays.
    """
    if v == 0.0:
        return z
    g = stribeck_magnitude_kernel(v, p)
    lam = p[lugre.SIGMA0] * abs(v) / g
    z_ss = v / lam
    return z_ss + (z - z_ss) * math.exp(-lam * h)


@kernel
def _map1(fn_id: int, v: np.ndarray, z: np.ndarray, p: np.ndarray) -> np.ndarray:
    out = np.empty(v.size)
    for i in range(v.size):
        if fn_id == 0:
            out[i] = stribeck_magnitude_kernel(v[i], p)
        elif fn_id == 1:
            out[i] = steady_force_kernel(v[i], p)
        elif fn_id == 2:
            out[i] = bristle_rate_kernel(v[i], z[i], p)
        else:
            out[i] = force_kernel(v[i], z[i], p)
    return out


# ---------------------------------------------------------------- array API


def _apply(fn_id: int, velocity: object, bristle: object, params: LuGreParameters) -> np.ndarray:
    v = np.asarray(velocity, dtype=np.float64)
    z = np.broadcast_to(np.asarray(bristle, dtype=np.float64), v.shape)
    out = _map1(fn_id, np.ascontiguousarray(v).ravel(), np.ascontiguousarray(z).ravel(),
                params.as_array())
    return out.reshape(v.shape)


def stribeck_magnitude(velocity: object, params: LuGreParameters) -> np.ndarray:
    """σ0·g(v) [N] at sliding speed ``velocity`` [m/s].  Wang2021 Eq. (11)."""
    return _apply(0, velocity, 0.0, params)


def steady_friction(velocity: object, params: LuGreParameters) -> np.ndarray:
    """Steady-state (Stribeck + Coulomb + viscous) friction force [N] at ``velocity`` [m/s]."""
    return _apply(1, velocity, 0.0, params)


def bristle_rate(velocity: object, bristle: object, params: LuGreParameters) -> np.ndarray:
    """dz/dt [m/s] for sliding speed [m/s] and bristle deflection z [m].  Wang2021 Eq. (11)."""
    return _apply(2, velocity, bristle, params)


def friction_force(velocity: object, bristle: object, params: LuGreParameters) -> np.ndarray:
    """LuGre friction force [N].  Wang2021 Eq. (11), first line."""
    return _apply(3, velocity, bristle, params)


def bristle_step(bristle: float, velocity: float, step: float, params: LuGreParameters) -> float:
    """Exact z after ``step`` [s] with ``velocity`` [m/s] held (see kernel)."""
    return float(bristle_step_kernel(float(bristle), float(velocity), float(step),
                                     params.as_array()))


def bristle_bound(params: LuGreParameters) -> float:
    """max(F_s)/σ0 [m]: |z| never leaves this bound once inside (Canudas de Wit 1995)."""
    static = max(params.positive.static_force, params.negative.static_force)
    return static / params.bristle_stiffness


# ---------------------------------------------------------------- analytic indicators


@dataclass(frozen=True)
class NegativeSlopeBand:
    """Speeds [m/s] between which the steady friction curve falls (negative damping)."""

    lower: float
    upper: float

    @property
    def zero_slope_speed(self) -> float:
        """The upper edge: above it steady friction rises with speed."""
        return self.upper


def _stribeck_slope(v: float, b: FrictionBranch) -> float:
    u = v / b.stribeck_velocity
    return (b.static_force - b.coulomb_force) * 2.0 * u / b.stribeck_velocity * math.exp(-u * u)


def negative_slope_band(branch: FrictionBranch) -> NegativeSlopeBand | None:
    """Speed band where d(steady friction)/dv < 0, for one branch (speeds as magnitudes).

    slope(v) = σ2 − (F_s − F_c)·2v/v_s²·exp(−(v/v_s)²); the Stribeck term peaks at
    v = v_s/√2.  None if σ2 exceeds that peak (friction never has negative damping).
    """
    vs = branch.stribeck_velocity
    v_peak = vs / math.sqrt(2.0)
    s2 = branch.viscous_coefficient
    if _stribeck_slope(v_peak, branch) <= s2:
        return None

    def f(v: float) -> float:
        return _stribeck_slope(v, branch) - s2

    lower = 0.0 if s2 == 0.0 else brentq(f, 0.0, v_peak, xtol=1e-15, rtol=1e-12)
    hi = v_peak
    while f(hi) > 0.0:
        hi *= 2.0
    upper = brentq(f, v_peak, hi, xtol=1e-15, rtol=1e-12)
    return NegativeSlopeBand(lower=lower, upper=upper)


def passivity_margin(branch: FrictionBranch, params: LuGreParameters) -> float:
    """σ2 − σ1·(F_s − F_c)/F_c [N s/m]; positive means the LuGre map is passive.

    Sufficient condition for dissipativity of v ↦ F (Barabanov & Ortega 2000; Åström &
    Canudas de Wit, IEEE CSM 2008).
    """
    b = branch
    return b.viscous_coefficient - params.bristle_damping * (
        b.static_force - b.coulomb_force) / b.coulomb_force


@dataclass(frozen=True)
class SlidingStability:
    """Linear stability of steady sliding at each speed of ``speed`` [m/s]."""

    speed: np.ndarray
    stable: np.ndarray
    max_real_part: np.ndarray  # [1/s], largest real part of the closed-loop poles
    coefficients: np.ndarray  # characteristic polynomial, highest power first, per speed


def _site_linearisation(v: float, params: LuGreParameters) -> tuple[float, float, float, float,
                                                                     float]:
    """(σ0, σ1, σ2, a, λ) of the LuGre map linearised at steady sliding speed v ≠ 0.

    δż = −a·δv − λ·δz with λ = σ0|v|/G(v), a = −v·G'(v)/G(v), G = σ0 g.
    """
    b = params.positive if v >= 0 else params.negative
    G = float(stribeck_magnitude_kernel(v, params.as_array()))
    u = abs(v) / b.stribeck_velocity
    dG_dabs = -(b.static_force - b.coulomb_force) * 2.0 * u / b.stribeck_velocity * math.exp(-u * u)
    a = -abs(v) * dG_dabs / G
    lam = params.bristle_stiffness * abs(v) / G
    return params.bristle_stiffness, params.bristle_damping, b.viscous_coefficient, a, lam


def characteristic_polynomial(
    speed: float,
    sites: list[LuGreParameters],
    mass: float,
    stiffness: float,
    damping: float,
    integral: float = 0.0,
) -> np.ndarray:
    """Characteristic polynomial (highest power first) of a mass sliding on LuGre sites.

    Mass ``mass`` [kg] pulled at constant ``speed`` [m/s] through a spring ``stiffness``
    [N/m], a damper ``damping`` [N s/m] and optionally an integral term ``integral`` [N/(m s)]
    (a PI servo), with every site in ``sites`` sliding at the same speed.  For one site and
    no integral term this is the cubic of Åström & Canudas de Wit (IEEE CSM 2008):
    m s³ + (mλ + c + σ2 − aσ1) s² + (cλ + k + σ2λ − aσ0) s + kλ.
    """
    P = np.polynomial.polynomial
    # drive: s·(m s² + c s + k) + k_i, i.e. the motion equation multiplied by s
    drive = np.array([integral, stiffness, damping, mass])
    lin = [_site_linearisation(speed, p) for p in sites]
    dens = [np.array([lam, 1.0]) for (_, _, _, _, lam) in lin]
    total = drive
    for d in dens:
        total = P.polymul(total, d)
    for i, (s0, s1, s2, a, lam) in enumerate(lin):
        # s·[σ2(s+λ) − a(σ0 + σ1 s)] · s (from the overall ·s) · Π_{j≠i}(s+λ_j)
        term = np.array([0.0, 0.0, s2 * lam - a * s0, s2 - a * s1])
        for j, d in enumerate(dens):
            if j != i:
                term = P.polymul(term, d)
        total = P.polyadd(total, term)
    if integral == 0.0:
        # drop the common factor s introduced above
        total = total[1:]
    return np.asarray(total[::-1], dtype=float)


def sliding_stability(
    speed: object,
    sites: list[LuGreParameters],
    mass: float,
    stiffness: float,
    damping: float,
    integral: float = 0.0,
) -> SlidingStability:
    """Hurwitz stability of steady sliding over an array of speeds [m/s]; see
    :func:`characteristic_polynomial`.  Unstable speeds are where stick-slip can start."""
    v = np.atleast_1d(np.asarray(speed, dtype=float))
    if np.any(v == 0.0) or not np.all(np.isfinite(v)):
        raise ValueError("speed: steady sliding needs finite, non-zero speeds [m/s]")
    coeffs = [characteristic_polynomial(float(x), sites, mass, stiffness, damping, integral)
              for x in v]
    max_re = np.array([np.max(np.roots(c).real) for c in coeffs])
    return SlidingStability(speed=v, stable=max_re < 0.0, max_real_part=max_re,
                            coefficients=np.array(coeffs))


def unstable_speed_band(stability: SlidingStability) -> tuple[float, float] | None:
    """(lowest, highest) unstable speed of a stability scan, or None if all stable."""
    bad = stability.speed[~stability.stable]
    if bad.size == 0:
        return None
    return float(np.min(np.abs(bad))), float(np.max(np.abs(bad)))
