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
    """Offset of the direction branch (+ for v ≥ 0, − otherwise) in a site's parameter block.

    Parameters
    ----------
    v : float
        Sliding speed [m/s].
    o : int
        Offset of the site's block in ``P``.

    Returns
    -------
    int
        ``o`` for the + branch, ``o + NEGATIVE`` for the − branch.
    """
    return o if v >= 0.0 else o + NEGATIVE


@kernel
def stribeck_magnitude(v: float, P: np.ndarray, o: int) -> float:
    """Stribeck magnitude σ0·g(v) = F_c + (F_s − F_c)·exp(−(v/v_s)²) of the LuGre law.

    Wang2021 Eq. (11), third line, with the branch's (F_c, F_s, v_s) chosen by the sign of v.

    Parameters
    ----------
    v : float
        Sliding speed [m/s].
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the site's block in ``P``.

    Returns
    -------
    float
        The magnitude, between F_c and F_s [N].

    References
    ----------
    .. [1] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    .. [2] Wang2021 Eqs. (9)–(11), Table 1.
    """
    b = branch(v, o)
    u = v / P[b + STRIBECK_VELOCITY]
    return P[b + COULOMB] + (P[b + STATIC] - P[b + COULOMB]) * math.exp(-u * u)


@kernel
def bristle_rate(v: float, z: float, P: np.ndarray, o: int) -> float:
    """LuGre bristle rate dz/dt = v − σ0·|v|·z / (σ0·g(v)).

    Wang2021 Eq. (11), first line.  Safe at v = 0 because σ0·g(v) ≥ F_c > 0.

    Parameters
    ----------
    v : float
        Sliding speed [m/s].
    z : float
        Bristle deflection [m].
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the site's block in ``P``.

    Returns
    -------
    float
        dz/dt [m/s].

    References
    ----------
    .. [1] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    .. [2] Wang2021 Eqs. (9)–(11), Table 1.
    """
    return v - P[o + SIGMA0] * abs(v) * z / stribeck_magnitude(v, P, o)


@kernel
def force(v: float, z: float, dz: float, P: np.ndarray, o: int) -> float:
    """LuGre friction force F = σ0·z + σ1·dz/dt + σ2·v.

    Wang2021 Eq. (11), second line, σ2 of the branch of v.

    Parameters
    ----------
    v : float
        Sliding speed [m/s].
    z : float
        Bristle deflection [m].
    dz : float
        Bristle rate dz/dt from :func:`bristle_rate` [m/s].
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the site's block in ``P``.

    Returns
    -------
    float
        Friction force [N].

    References
    ----------
    .. [1] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    .. [2] Wang2021 Eqs. (9)–(11), Table 1.
    """
    return P[o + SIGMA0] * z + P[o + SIGMA1] * dz + P[branch(v, o) + VISCOUS] * v


@kernel
def lugre_kernel(v: float, y: np.ndarray, k: int, P: np.ndarray, o: int,
                 dy: np.ndarray) -> float:
    """The LuGre law's kernel: writes the bristle rate and returns the friction force.

    Parameters
    ----------
    v : float
        Sliding speed [m/s].
    y : numpy.ndarray
        The model's state vector; this law's states are ``y[k : k + n_states]`` [m].
    k : int
        Index of the law's first state in ``y``.
    P : numpy.ndarray
        The model's packed parameter vector [SI, per slot].
    o : int
        Offset of this site's parameter block in ``P``.
    dy : numpy.ndarray
        The state-rate vector; the kernel writes its states' rates at ``dy[k : k + n_states]``
        [m/s].

    Returns
    -------
    float
        Friction force with the sign of the sliding speed [N].

    References
    ----------
    .. [1] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    .. [2] Wang2021 Eqs. (9)–(11), Table 1.
    """
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
    kink_at_zero_speed = True

    def steady_state(self, v: float, site):
        """Bristle deflection in steady sliding, z = sgn(v)·σ0·g(v)/σ0.

        Parameters
        ----------
        v : float
            Constant sliding speed [m/s].
        site : LuGreParameters
            The friction site's parameters.

        Returns
        -------
        numpy.ndarray
            The one state z [m]; 0 at v = 0.
        """
        if v == 0.0:
            return np.zeros(1)
        G = float(stribeck_magnitude(v, site.as_array(), 0))
        return np.array([math.copysign(G, v) / site.bristle_stiffness])

    def linearise(self, v: float, site) -> LinearFriction:
        """Analytic linearisation at steady sliding.

        δż = −λ δz + a δv with λ = σ0|v|/G, a = v·G'(v)/G, and δF = σ0 δz + σ1 δż + σ2 δv, G the
        Stribeck magnitude (Åström & Canudas de Wit 2008).

        Parameters
        ----------
        v : float
            Steady sliding speed of the operating point [m/s], v ≠ 0.
        site : LuGreParameters
            The friction site's parameters.

        Returns
        -------
        LinearFriction
            (A, B, C, D) of the small-signal model at ``v``.

        Raises
        ------
        ValueError
            At v = 0, where the bristle has no steady sliding state.

        References
        ----------
        .. [1] K. J. Åström, C. Canudas de Wit, "Revisiting the LuGre friction model", IEEE Control
           Systems Magazine 28 (2008) 101–114.
        """
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
