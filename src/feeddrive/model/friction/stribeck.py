"""LuGre friction with Stribeck effect.  Wang2021 Eqs. (9)–(11), Table 1.

The LuGre force itself is :mod:`feeddrive.model.friction.lugre` (the engine's); this module
is its array API and the analytic indicators.  All functions use the linear (force) form of
Table 1: force in N, speed in m/s, bristle
deflection z in m.  The screw and hollow shafts are rotary sites; the paper divides their
torques by H = p_h/2π
(:attr:`feeddrive.model.mechanisms.ball_screw_parameters.BallScrew.transmission_ratio`):
T = H·F, ω = v/H.

The scalar kernels (``*_kernel``) are shared with the simulation engine (which runs them in
C), so the physics exists once; called from Python here, they are numba-compiled where numba
is installed and plain Python otherwise.  ``p`` is the float64[10] vector of
:meth:`feeddrive.model.friction.lugre_parameters.LuGreParameters.as_array`:
(F_c+, F_s+, v_s+, σ2+, F_c−, F_s−, v_s−, σ2−, σ0, σ1).

Sign convention: the friction force has the sign of the sliding speed (it opposes motion when
subtracted in the equation of motion); the + branch applies for v ≥ 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..._jit import kernel
from ...parameters.validation import ParameterError, is_real
from . import lugre
from .lugre_parameters import FrictionBranch, LuGreParameters

# ---------------------------------------------------------------- compiled scalar kernels


@kernel
def stribeck_magnitude_kernel(v: float, p: np.ndarray) -> float:
    """Stribeck magnitude σ0·g(v) = F_c + (F_s − F_c)·exp(−(v/v_s)²), branch by the sign of v.

    Parameters
    ----------
    v : float
        Sliding speed [m/s].
    p : numpy.ndarray
        One site's packed LuGre parameters [SI, per slot]
        (:meth:`~feeddrive.model.friction.lugre_parameters.LuGreParameters.as_array`).

    Returns
    -------
    float
        The magnitude [N].

    References
    ----------
    .. [1] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    .. [2] Wang2021 Eq. (11).
    """
    return lugre.stribeck_magnitude(v, p, 0)


@kernel
def steady_force_kernel(v: float, p: np.ndarray) -> float:
    """Steady friction sgn(v)·σ0·g(v) + σ2·v, zero at v = 0.

    Parameters
    ----------
    v : float
        Sliding speed [m/s].
    p : numpy.ndarray
        One site's packed LuGre parameters [SI, per slot]
        (:meth:`~feeddrive.model.friction.lugre_parameters.LuGreParameters.as_array`).

    Returns
    -------
    float
        Friction force [N].
    """
    if v == 0.0:
        return 0.0
    s = 1.0 if v > 0.0 else -1.0
    return s * lugre.stribeck_magnitude(v, p, 0) + p[lugre.branch(v, 0) + lugre.VISCOUS] * v


@kernel
def bristle_rate_kernel(v: float, z: float, p: np.ndarray) -> float:
    """LuGre bristle rate dz/dt = v − σ0·|v|·z / (σ0·g(v)); safe at v = 0 (g ≥ F_c > 0).

    Parameters
    ----------
    v : float
        Sliding speed [m/s].
    z : float
        Bristle deflection [m].
    p : numpy.ndarray
        One site's packed LuGre parameters [SI, per slot]
        (:meth:`~feeddrive.model.friction.lugre_parameters.LuGreParameters.as_array`).

    Returns
    -------
    float
        dz/dt [m/s].

    References
    ----------
    .. [1] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    .. [2] Wang2021 Eq. (11).
    """
    return lugre.bristle_rate(v, z, p, 0)


@kernel
def force_kernel(v: float, z: float, p: np.ndarray) -> float:
    """LuGre force F = σ0·z + σ1·dz/dt + σ2·v with dz/dt from the bristle rate.

    Parameters
    ----------
    v : float
        Sliding speed [m/s].
    z : float
        Bristle deflection [m].
    p : numpy.ndarray
        One site's packed LuGre parameters [SI, per slot]
        (:meth:`~feeddrive.model.friction.lugre_parameters.LuGreParameters.as_array`).

    Returns
    -------
    float
        Friction force [N].

    References
    ----------
    .. [1] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    .. [2] Wang2021 Eq. (11).
    """
    return lugre.force(v, z, lugre.bristle_rate(v, z, p, 0), p, 0)


@kernel
def bristle_step_kernel(z: float, v: float, h: float, p: np.ndarray) -> float:
    """Exact bristle update over a step with the speed held: z relaxes exponentially.

    dz/dt = v − λz with λ = σ0|v|/(σ0·g(v)) ≥ 0, so z(h) = z_ss + (z − z_ss)·exp(−λh),
    z_ss = v/λ; for v = 0, z stays.

    Parameters
    ----------
    z : float
        Bristle deflection at the start of the step [m].
    v : float
        Sliding speed, held over the step [m/s].
    h : float
        Step length [s].
    p : numpy.ndarray
        One site's packed LuGre parameters [SI, per slot]
        (:meth:`~feeddrive.model.friction.lugre_parameters.LuGreParameters.as_array`).

    Returns
    -------
    float
        Bristle deflection at the end of the step [m].
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
    # a whole parameter set, a string or a NaN speed failed inside numpy or came back NaN
    # (an outside check, 2026-12-07)
    if not callable(getattr(params, "as_array", None)):
        raise ParameterError("params", type(params).__name__, "expected one friction site's "
                             "LuGreParameters, e.g. params.friction.screw")
    v = _finite_array("velocity", velocity, "m/s")
    z = np.broadcast_to(_finite_array("bristle", bristle, "m"), v.shape)
    out = _map1(fn_id, np.ascontiguousarray(v).ravel(), np.ascontiguousarray(z).ravel(),
                params.as_array())
    return out.reshape(v.shape)


def _finite_array(name: str, value: object, unit: str) -> np.ndarray:
    """``value`` as a float array, refused naming ``name`` unless every element is finite."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(name, value, f"expected numbers [{unit}]") from None
    if not np.all(np.isfinite(arr)):
        raise ParameterError(name, value, f"expected finite numbers [{unit}]")
    return arr


def stribeck_magnitude(velocity: object, params: LuGreParameters) -> np.ndarray:
    """Stribeck magnitude σ0·g(v) of a LuGre site, elementwise.

    Parameters
    ----------
    velocity : array_like
        Sliding speed(s) [m/s].
    params : LuGreParameters
        The friction site's parameters.

    Returns
    -------
    numpy.ndarray
        σ0·g(v), shaped like ``velocity`` [N].

    References
    ----------
    .. [1] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    .. [2] Wang2021 Eq. (11).
    """
    return _apply(0, velocity, 0.0, params)


def steady_friction(velocity: object, params: LuGreParameters) -> np.ndarray:
    """Steady (Stribeck + Coulomb + viscous) friction force of a LuGre site, elementwise.

    Parameters
    ----------
    velocity : array_like
        Sliding speed(s) [m/s].
    params : LuGreParameters
        The friction site's parameters.

    Returns
    -------
    numpy.ndarray
        Friction force, shaped like ``velocity`` [N].
    """
    return _apply(1, velocity, 0.0, params)


def bristle_rate(velocity: object, bristle: object, params: LuGreParameters) -> np.ndarray:
    """LuGre bristle rate dz/dt, elementwise.

    Parameters
    ----------
    velocity : array_like
        Sliding speed(s) [m/s].
    bristle : array_like
        Bristle deflection(s) z [m], broadcast against ``velocity``.
    params : LuGreParameters
        The friction site's parameters.

    Returns
    -------
    numpy.ndarray
        dz/dt [m/s].

    References
    ----------
    .. [1] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    .. [2] Wang2021 Eq. (11).
    """
    return _apply(2, velocity, bristle, params)


def friction_force(velocity: object, bristle: object, params: LuGreParameters) -> np.ndarray:
    """LuGre friction force F = σ0·z + σ1·dz/dt + σ2·v, elementwise.

    Parameters
    ----------
    velocity : array_like
        Sliding speed(s) [m/s].
    bristle : array_like
        Bristle deflection(s) z [m], broadcast against ``velocity``.
    params : LuGreParameters
        The friction site's parameters.

    Returns
    -------
    numpy.ndarray
        Friction force [N].

    References
    ----------
    .. [1] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    .. [2] Wang2021 Eq. (11).
    """
    return _apply(3, velocity, bristle, params)


def bristle_step(bristle: float, velocity: float, step: float, params: LuGreParameters) -> float:
    """Exact bristle deflection after a step with the speed held (see
    :func:`bristle_step_kernel`).

    Parameters
    ----------
    bristle : float
        Bristle deflection at the start [m].
    velocity : float
        Sliding speed, held [m/s].
    step : float
        Step length [s].
    params : LuGreParameters
        The friction site's parameters.

    Returns
    -------
    float
        Bristle deflection at the end of the step [m].
    """
    return float(bristle_step_kernel(float(bristle), float(velocity), float(step),
                                     params.as_array()))


def bristle_bound(params: LuGreParameters) -> float:
    """The bristle bound max(F_s)/σ0: once inside, |z| never leaves it.

    Parameters
    ----------
    params : LuGreParameters
        The friction site's parameters.

    Returns
    -------
    float
        The bound [m].

    References
    ----------
    .. [1] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    """
    static = max(params.positive.static_force, params.negative.static_force)
    return static / params.bristle_stiffness


# ---------------------------------------------------------------- analytic indicators


@dataclass(frozen=True)
class NegativeSlopeBand:
    """Speeds between which the steady friction curve falls (negative damping).

    Parameters
    ----------
    lower : float
        Lower edge [m/s] (0 without viscous friction).
    upper : float
        Upper edge, the zero-slope speed [m/s]; ``inf`` without viscous friction (σ2 = 0:
        the steady curve falls at every speed, its slope only tending to zero).
    """

    lower: float
    upper: float

    @property
    def zero_slope_speed(self) -> float:
        """The upper edge: above it steady friction rises with speed (``inf``: never)."""
        return self.upper

    @property
    def bounded(self) -> bool:
        """Whether the band ends (σ2 > 0): a zero-slope speed exists."""
        return math.isfinite(self.upper)


def _stribeck_slope(v: float, b: FrictionBranch) -> float:
    u = v / b.stribeck_velocity
    return (b.static_force - b.coulomb_force) * 2.0 * u / b.stribeck_velocity * math.exp(-u * u)


def negative_slope_band(branch: FrictionBranch) -> NegativeSlopeBand | None:
    """Speed band where d(steady friction)/dv < 0, for one direction branch.

    slope(v) = σ2 − (F_s − F_c)·2v/v_s²·exp(−(v/v_s)²).  With u = v/v_s the edges solve
    u·exp(−u²) = c, c = σ2·v_s / (2(F_s − F_c)), so that −2u²·exp(−2u²) = −2c² and
    u² = −W(−2c²)/2 with Lambert's W: its principal branch gives the lower edge, its −1 branch
    the upper (closed form; the Stribeck term's slope peaks at u = 1/√2, where −2c² reaches
    the branch point −1/e).  Without viscous friction (σ2 = 0) the band is [0, ∞): the curve
    falls at every speed (a root search had stopped where the slope underflowed, 39.1 mm/s
    for the ``wang2021`` screw's + branch, and called that the zero-slope speed).

    Parameters
    ----------
    branch : FrictionBranch
        One direction's F_c, F_s [N], v_s [m/s], σ2 [N s/m] (speeds as magnitudes).

    Returns
    -------
    NegativeSlopeBand or None
        The band; None when σ2 exceeds the Stribeck slope's peak (never negative damping).
    """
    vs = branch.stribeck_velocity
    v_peak = vs / math.sqrt(2.0)
    s2 = branch.viscous_coefficient
    if _stribeck_slope(v_peak, branch) <= s2:
        return None
    if s2 == 0.0:
        return NegativeSlopeBand(lower=0.0, upper=math.inf)
    # here: a simulation never needs it (issue 21 item 4); scipy.special, lighter to import
    # than scipy.optimize, which a root search needed (0.12 against 0.29 CPU s)
    from scipy.special import lambertw

    c = s2 * vs / (2.0 * (branch.static_force - branch.coulomb_force))
    x = max(-2.0 * c * c, -1.0 / math.e)  # at the peak itself, to rounding
    lower = vs * math.sqrt(-float(lambertw(x, 0).real) / 2.0)
    upper = vs * math.sqrt(-float(lambertw(x, -1).real) / 2.0)
    return NegativeSlopeBand(lower=lower, upper=upper)


def passivity_margin(branch: FrictionBranch, params: LuGreParameters) -> float:
    """Passivity margin σ2 − σ1·(F_s − F_c)/F_c of the LuGre map v ↦ F.

    A positive margin is a sufficient condition for the map to be dissipative.

    Parameters
    ----------
    branch : FrictionBranch
        One direction's F_c, F_s [N] and σ2 [N s/m].
    params : LuGreParameters
        The friction site's parameters.

    Returns
    -------
    float
        The margin [N s/m]; positive means passive.

    References
    ----------
    .. [1] N. Barabanov, R. Ortega, "Necessary and sufficient conditions for passivity of the
       LuGre friction model", IEEE Trans. Autom. Control 45 (2000) 830–832.
    .. [2] K. J. Åström, C. Canudas de Wit, "Revisiting the LuGre friction model", IEEE Control
       Systems Magazine 28 (2008) 101–114.
    """
    b = branch
    return b.viscous_coefficient - params.bristle_damping * (
        b.static_force - b.coulomb_force) / b.coulomb_force


@dataclass(frozen=True)
class SlidingStability:
    """Linear stability of steady sliding at each speed of a scan.

    Parameters
    ----------
    speed : numpy.ndarray
        The speeds scanned [m/s].
    stable : numpy.ndarray of bool
        Whether steady sliding is stable at each speed.
    max_real_part : numpy.ndarray
        Largest real part of the closed-loop poles at each speed [1/s].
    coefficients : numpy.ndarray
        Characteristic polynomial per speed, highest power first [SI].
    """

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
    """Characteristic polynomial of a mass sliding on LuGre sites, pulled through a spring.

    Mass ``mass`` pulled at constant ``speed`` through a spring, a damper and optionally an
    integral term (a PI servo), every site in ``sites`` sliding at the same speed.  For one site
    and no integral term this is the cubic of Åström & Canudas de Wit (2008):
    m s³ + (mλ + c + σ2 − aσ1) s² + (cλ + k + σ2λ − aσ0) s + kλ.

    Parameters
    ----------
    speed : float
        Steady sliding speed [m/s], non-zero.
    sites : list of LuGreParameters
        The friction sites.
    mass : float
        The sliding mass [kg].
    stiffness : float
        Spring stiffness k [N/m].
    damping : float
        Damping c [N s/m].
    integral : float, default 0.0
        Integral gain of a PI servo [N/(m s)].

    Returns
    -------
    numpy.ndarray
        Coefficients, highest power first [SI].

    References
    ----------
    .. [1] K. J. Åström, C. Canudas de Wit, "Revisiting the LuGre friction model", IEEE Control
       Systems Magazine 28 (2008) 101–114.
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
    """Hurwitz stability of steady sliding over a scan of speeds.

    See :func:`characteristic_polynomial`; unstable speeds are where stick-slip can start.

    Parameters
    ----------
    speed : array_like
        Steady sliding speeds, finite and non-zero [m/s].
    sites : list of LuGreParameters
        The friction sites.
    mass : float
        The sliding mass [kg].
    stiffness : float
        Spring stiffness [N/m].
    damping : float
        Damping [N s/m].
    integral : float, default 0.0
        Integral gain of a PI servo [N/(m s)].

    Returns
    -------
    SlidingStability
        Stability, largest real part and polynomial per speed.

    Raises
    ------
    ParameterError
        For a zero or non-finite speed, a mass that is not > 0, or a stiffness, damping or
        integral gain that is not finite and ≥ 0.
    """
    v = np.atleast_1d(_finite_array("speed", speed, "m/s"))
    if np.any(v == 0.0):
        raise ParameterError("speed", speed, "steady sliding needs finite, non-zero speeds "
                             "[m/s]")
    # a zero mass read as "stable", a NaN one failed in LAPACK (an outside check, 2026-12-07)
    for name, value, unit, low in (("mass", mass, "kg", 0.0),
                                   ("stiffness", stiffness, "N/m", None),
                                   ("damping", damping, "N s/m", None),
                                   ("integral", integral, "N/(m s)", None)):
        number = is_real(value) and math.isfinite(value)
        if not number or (low is not None and not value > low) or (low is None and value < 0):
            raise ParameterError(name, value, f"expected a finite value "
                                 f"{'> 0' if low is not None else '≥ 0'} [{unit}]")
    coeffs = [characteristic_polynomial(float(x), sites, mass, stiffness, damping, integral)
              for x in v]
    max_re = np.array([np.max(np.roots(c).real) for c in coeffs])
    return SlidingStability(speed=v, stable=max_re < 0.0, max_real_part=max_re,
                            coefficients=np.array(coeffs))


def unstable_speed_band(stability: SlidingStability) -> tuple[float, float] | None:
    """The lowest and highest unstable speed of a stability scan.

    Parameters
    ----------
    stability : SlidingStability
        A scan from :func:`sliding_stability`.

    Returns
    -------
    tuple of (float, float) or None
        (lowest, highest) unstable speed magnitude [m/s]; None when every speed is stable.
    """
    bad = stability.speed[~stability.stable]
    if bad.size == 0:
        return None
    return float(np.min(np.abs(bad))), float(np.max(np.abs(bad)))
