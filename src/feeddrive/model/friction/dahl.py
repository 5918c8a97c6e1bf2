"""The Dahl friction law (P. R. Dahl, "A solid friction model", Aerospace Corp. report
TOR-0158(3107-18)-1, 1968; in the form of Olsson, Åström, Canudas de Wit, Gäfvert,
Lischinsky, "Friction models and friction compensation", Eur. J. Control 4 (1998) 176–195,
Eq. (9) with exponent i = 1):

    dz/dt = v − σ0·|v|·z / F_c,     F = σ0·z + σ2·v

Pre-sliding elasticity (σ0) and Coulomb friction F_c per direction, no Stribeck effect and no
micro-damping; the site's F_s, v_s and σ1 are not used.  With no Stribeck drop it cannot
produce stick-slip by itself: a useful contrast to LuGre.
"""

from __future__ import annotations

import math

import numpy as np

from ..._jit import kernel
from .base import FrictionLaw
from .lugre import COULOMB, SIGMA0, VISCOUS, branch


@kernel
def dahl_kernel(v: float, y: np.ndarray, k: int, P: np.ndarray, o: int,
                dy: np.ndarray) -> float:
    """Kernel of the Dahl law: dz/dt = v − σ0·|v|·z / F_c, F = σ0·z + σ2·v.

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
        Friction force [N].

    References
    ----------
    .. [1] P. R. Dahl, "A solid friction model", Aerospace Corp. report
       TOR-0158(3107-18)-1, 1968.
    .. [2] H. Olsson, K. J. Åström, C. Canudas de Wit, M. Gäfvert, P. Lischinsky, "Friction
       models and friction compensation", Eur. J. Control 4 (1998) 176–195, Eq. (9).
    """
    b = branch(v, o)
    z = y[k]
    dy[k] = v - P[o + SIGMA0] * abs(v) * z / P[b + COULOMB]
    return P[o + SIGMA0] * z + P[b + VISCOUS] * v


class Dahl(FrictionLaw):
    """Dahl friction: pre-sliding elasticity and Coulomb friction, no Stribeck effect.

    dz/dt = v − σ0·|v|·z / F_c,  F = σ0·z + σ2·v; one bristle state z [m].  Uses F_c [N] and
    σ2 [N s/m] of each branch and σ0 [N/m] of the site.

    References
    ----------
    .. [1] P. R. Dahl, "A solid friction model", Aerospace Corp. report
       TOR-0158(3107-18)-1, 1968.
    .. [2] H. Olsson, K. J. Åström, C. Canudas de Wit, M. Gäfvert, P. Lischinsky, "Friction
       models and friction compensation", Eur. J. Control 4 (1998) 176–195, Eq. (9).
    """
    name = "dahl"
    state_names = ("bristle",)
    citation = "Dahl 1968; Olsson et al., Eur. J. Control 4 (1998) 176-195, Eq. (9)"
    kernel = dahl_kernel
    kink_at_zero_speed = True

    def steady_state(self, v: float, site):
        """Bristle deflection in steady sliding, z = sgn(v)·F_c/σ0.

        Parameters
        ----------
        v : float
            Constant sliding speed [m/s].
        site : LuGreParameters
            The friction site's parameters (F_c of the branch of v, σ0).

        Returns
        -------
        numpy.ndarray
            The one state z [m]; 0 at v = 0.
        """
        if v == 0.0:
            return np.zeros(1)
        b = site.positive if v > 0 else site.negative
        return np.array([math.copysign(b.coulomb_force, v) / site.bristle_stiffness])
