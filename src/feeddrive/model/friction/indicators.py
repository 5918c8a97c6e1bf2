"""Friction indicators of one site under the site's own law (``[friction.SITE] law``).

:mod:`feeddrive.model.friction.stribeck` gives the LuGre forms (Wang2021 Eq. 11): the
analytic negative-slope band, the LuGre passivity margin and the Åström–Canudas de Wit cubic
of a mass sliding on the site.  A site may use another law (Dahl, static Stribeck, none, or a
registered one); these functions read the law's own steady curve and linearisation instead, so that
``feeddrive friction --site`` does not report LuGre numbers for a Dahl or frictionless site
(issue 24 item 7).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...parameters import LuGreParameters
from . import friction_law
from .stribeck import NegativeSlopeBand, SlidingStability, negative_slope_band, sliding_stability

#: laws whose steady curve is the Stribeck curve of Wang2021 Eq. (11) (the static law's tanh
#: smoothing only acts below its smoothing velocity, 1 µm/s by default)
STRIBECK_CURVE_LAWS = ("lugre", "stribeck")

#: speeds [m/s] of the numerical slope scan for other laws: 1 µm/s … 0.1 m/s
_SLOPE_SCAN = np.geomspace(1e-6, 0.1, 2001)


@dataclass(frozen=True)
class SteadySlope:
    """The steady curve's slope over the scan: its negative-slope band (None when the slope
    never goes negative) and its smallest slope [N s/m]."""

    band: NegativeSlopeBand | None
    min_slope: float


def steady_slope(site: LuGreParameters, branch: str) -> SteadySlope:
    """Negative-slope band of the site's steady friction curve on one branch (speeds as
    magnitudes [m/s]): analytic for the Stribeck curve (LuGre, static), from the law's own
    steady curve on a log grid otherwise."""
    sign = 1.0 if branch == "positive" else -1.0
    law = friction_law(site.law)
    v = sign * _SLOPE_SCAN
    force = sign * np.asarray(law.steady_force(v, site), dtype=float)
    slope = np.gradient(force, _SLOPE_SCAN)
    min_slope = float(np.min(slope))
    if site.law in STRIBECK_CURVE_LAWS:
        return SteadySlope(negative_slope_band(site.branch(branch)), min_slope)
    negative = _SLOPE_SCAN[slope < 0.0]
    band = (None if negative.size == 0
            else NegativeSlopeBand(lower=float(negative[0]), upper=float(negative[-1])))
    return SteadySlope(band, min_slope)


def has_passivity_criterion(site: LuGreParameters) -> bool:
    """The passivity margin σ2 − σ1(F_s − F_c)/F_c is a LuGre criterion (Barabanov & Ortega
    2000); it says nothing about another law."""
    return site.law == "lugre"


def site_sliding_stability(speed: object, site: LuGreParameters, mass: float,
                           stiffness: float, damping: float, *,
                           analytic: bool = True) -> SlidingStability:
    """Linear stability of a mass ``mass`` [kg] pulled at each ``speed`` [m/s] through a
    spring ``stiffness`` [N/m] and a damper ``damping`` [N s/m] while sliding on ``site``.
    LuGre: the cubic of :func:`feeddrive.model.friction.stribeck.sliding_stability`; any
    other law: the eigenvalues of the same oscillator with the law's own linearisation
    (:meth:`FrictionLaw.linearise`), δẋ = δu, m δu̇ = −k δx − c δu − C δz − D δu,
    δż = A δz + B δu (``analytic=False`` takes this path for LuGre too: the cross-check)."""
    if site.law == "lugre" and analytic:
        return sliding_stability(speed, [site], mass, stiffness, damping)
    law = friction_law(site.law)
    v = np.atleast_1d(np.asarray(speed, dtype=float))
    if np.any(v == 0.0) or not np.all(np.isfinite(v)):
        raise ValueError("speed: steady sliding needs finite, non-zero speeds [m/s]")
    n = len(law.state_names)
    max_re = np.empty(v.size)
    for i, s in enumerate(v):
        lin = law.linearise(float(s), site)
        M = np.zeros((2 + n, 2 + n))
        M[0, 1] = 1.0
        M[1, 0] = -stiffness / mass
        M[1, 1] = -(damping + lin.D) / mass
        if n:
            M[1, 2:] = -np.asarray(lin.C) / mass
            M[2:, 1] = np.asarray(lin.B)
            M[2:, 2:] = np.asarray(lin.A)
        max_re[i] = float(np.max(np.linalg.eigvals(M).real))
    return SlidingStability(speed=v, stable=max_re < 0.0, max_real_part=max_re,
                            coefficients=np.empty((v.size, 0)))


#: the site parameters a law does not read (printed beside its table)
UNUSED_PARAMETERS = {"dahl": "F_s, v_s and σ1", "stribeck": "σ0 and σ1",
                     "none": "all of them (no friction at this site)"}
