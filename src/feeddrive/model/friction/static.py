"""Static friction laws: smoothed Stribeck + Coulomb + viscous, and no friction.

The static law is the steady curve of the LuGre law without its bristle state,
F = tanh(v/v_ε)·(F_c + (F_s − F_c)·exp(−(v/v_s)²)) + σ2·v, with the sign function smoothed
over ``smoothing_velocity`` v_ε [m/s] (a site parameter, default 1 µm/s) so the right-hand
side stays continuous (Armstrong-Hélouvry, Dupont, Canudas de Wit, Automatica 30 (1994)
1083–1138, for the curve; the tanh smoothing is the usual choice for ODE solvers).  Cheap:
no stiff bristle state; for fast studies and for comparison with LuGre.  It has no
pre-sliding elasticity, so it cannot stick exactly — it creeps at |v| ≲ v_ε.
"""

from __future__ import annotations

import math

import numpy as np

from ..._jit import kernel
from .base import FrictionLaw
from .lugre import SLOTS, VISCOUS, branch, stribeck_magnitude

SMOOTHING = len(SLOTS)  # the sign-function smoothing speed v_ε, after the LuGre slots


@kernel
def stribeck_kernel(v: float, y: np.ndarray, k: int, P: np.ndarray, o: int,
                    dy: np.ndarray) -> float:
    """Kernel of the static Stribeck law: F = tanh(v/v_ε)·σ0·g(v) + σ2·v, no state.

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
    .. [1] B. Armstrong-Hélouvry, P. Dupont, C. Canudas de Wit, "A survey of models, analysis
       tools and compensation methods for the control of machines with friction",
       Automatica 30 (1994) 1083–1138.
    """
    return (math.tanh(v / P[o + SMOOTHING]) * stribeck_magnitude(v, P, o)
            + P[branch(v, o) + VISCOUS] * v)


@kernel
def no_friction_kernel(v: float, y: np.ndarray, k: int, P: np.ndarray, o: int,
                       dy: np.ndarray) -> float:
    """Kernel of the ``none`` law: zero force, no state.

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
        0.0 [N].
    """
    return 0.0


class Stribeck(FrictionLaw):
    """Static Stribeck + Coulomb + viscous friction with a smoothed sign function.

    F = tanh(v/v_ε)·(F_c + (F_s − F_c)·exp(−(v/v_s)²)) + σ2·v, no state; v_ε [m/s] is the
    site's ``smoothing_velocity``.

    References
    ----------
    .. [1] B. Armstrong-Hélouvry, P. Dupont, C. Canudas de Wit, "A survey of models, analysis
       tools and compensation methods for the control of machines with friction",
       Automatica 30 (1994) 1083–1138.
    """
    name = "stribeck"
    citation = "Armstrong-Hélouvry, Dupont, Canudas de Wit, Automatica 30 (1994) 1083-1138"
    kernel = stribeck_kernel

    slots = (*SLOTS, "smoothing_velocity")

    def pack(self, site):
        """The LuGre slots of the site followed by its smoothing speed v_ε.

        Parameters
        ----------
        site : LuGreParameters
            The friction site's parameters.

        Returns
        -------
        numpy.ndarray
            (F_c, F_s, v_s, σ2)±, σ0, σ1, v_ε [SI, per slot].
        """
        return np.append(site.as_array(), site.smoothing_velocity)


class NoFriction(FrictionLaw):
    """No friction at this site: a law with no states and zero force."""

    name = "none"
    published = False
    kernel = no_friction_kernel
