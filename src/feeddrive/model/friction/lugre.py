"""LuGre friction with Stribeck effect (Canudas de Wit, Olsson, Åström, Lischinsky, IEEE TAC
40 (1995) 419–425).  Wang2021 Eqs. (9)–(11), Table 1.  The package's one LuGre force.

Parameters at ``P[o : o + 10]``, named by :data:`SLOTS` (their paths below
``friction.<site>``): (F_c, F_s, v_s, σ2) of the + branch, then of the − branch, then σ0, σ1 —
:meth:`feeddrive.model.friction.lugre_parameters.LuGreParameters.as_array`.  Kernels read them
through the named offsets (``P[o + SIGMA0]``, ``P[branch(v, o) + VISCOUS]``).  Force in N,
speed in m/s, bristle deflection z in m; the + branch applies for v ≥ 0.
"""

from __future__ import annotations

import math

import numpy as np

from ..._jit import inline_kernel, kernel
from .base import SITE_SLOTS, FrictionLaw, LinearFriction

SLOTS = SITE_SLOTS
# offsets within a direction branch, of the − branch, and of the shared bristle parameters
COULOMB, STATIC, STRIBECK_VELOCITY, VISCOUS = 0, 1, 2, 3
NEGATIVE = 4
SIGMA0, SIGMA1 = SLOTS.index("bristle_stiffness"), SLOTS.index("bristle_damping")


@inline_kernel
def branch(v: float, o: int) -> int:
    """Offset of the direction branch for speed ``v``."""
    return o if v >= 0.0 else o + NEGATIVE


@kernel
def stribeck_magnitude(v: float, P: np.ndarray, o: int) -> float:
    """σ0·g(v) = F_c + (F_s − F_c)·exp(−(v/v_s)²) [N] (Eq. 11, third line)."""
    b = branch(v, o)
    u = v / P[b + STRIBECK_VELOCITY]
    return P[b + COULOMB] + (P[b + STATIC] - P[b + COULOMB]) * math.exp(-u * u)


@kernel
def bristle_rate(v: float, z: float, P: np.ndarray, o: int) -> float:
    """dz/dt = v − σ0·|v|·z / (σ0·g(v)) [m/s].  Safe at v = 0 (g ≥ F_c > 0)."""
    return v - P[o + SIGMA0] * abs(v) * z / stribeck_magnitude(v, P, o)


@kernel
def force(v: float, z: float, dz: float, P: np.ndarray, o: int) -> float:
    """F = σ0·z + σ1·dz/dt + σ2·v [N]."""
    return P[o + SIGMA0] * z + P[o + SIGMA1] * dz + P[branch(v, o) + VISCOUS] * v


@kernel
def lugre_kernel(v: float, y: np.ndarray, k: int, P: np.ndarray, o: int,
                 dy: np.ndarray) -> float:
    z = y[k]
    dz = bristle_rate(v, z, P, o)
    dy[k] = dz
    return force(v, z, dz, P, o)


class LuGre(FrictionLaw):
    """LuGre friction with Stribeck effect, per direction branch.

    dz/dt = v − σ0·|v|·z / g(v),  F = σ0·z + σ1·dz/dt + σ2·v,
    g(v) = F_c + (F_s − F_c)·exp(−(v/v_s)²); one bristle state z [m].  Parameters of a site
    (:class:`~feeddrive.model.friction.lugre_parameters.LuGreParameters`): F_c, F_s [N],
    v_s [m/s], σ2 [N s/m] per branch, σ0 [N/m], σ1 [N s/m].

    References
    ----------
    .. [1] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    .. [2] Wang2021 Eqs. (9)–(11), Table 1.
    """
    name = "lugre"
    state_names = ("bristle",)
    citation = ("Canudas de Wit, Olsson, Åström, Lischinsky, IEEE TAC 40 (1995) 419-425; "
                "Wang2021 Eqs. (9)-(11)")
    kernel = lugre_kernel

    def steady_state(self, v: float, site):
        if v == 0.0:
            return np.zeros(1)
        G = float(stribeck_magnitude(v, site.as_array(), 0))
        return np.array([math.copysign(G, v) / site.bristle_stiffness])

    def linearise(self, v: float, site) -> LinearFriction:
        """Analytic: δż = −λ δz + a δv, λ = σ0|v|/G, a = v·G'(v)/G (Åström & Canudas de Wit,
        IEEE CSM 28 (2008) 101–114); δF = σ0 δz + σ1 δż + σ2 δv."""
        if v == 0.0:
            raise ValueError("speed: the LuGre law is linearised at steady sliding (v ≠ 0)")
        b = site.positive if v >= 0 else site.negative
        G = float(stribeck_magnitude(v, site.as_array(), 0))
        u = v / b.stribeck_velocity
        dG = -(b.static_force - b.coulomb_force) * 2.0 * u / b.stribeck_velocity * math.exp(-u * u)
        lam = site.bristle_stiffness * abs(v) / G
        a = v * dG / G
        s0, s1, s2 = site.bristle_stiffness, site.bristle_damping, b.viscous_coefficient
        return LinearFriction(A=np.array([[-lam]]), B=np.array([a]),
                              C=np.array([s0 - s1 * lam]), D=s1 * a + s2)
