"""Switching surfaces of the dense-output driver: the zero crossings of a friction site's
sliding speed, where the right-hand side has a kink, made exact step ends.

A friction law with a direction branch (LuGre, Dahl: ż = v − σ0·|v|·z/G(v), the branch's
F_c, F_s, v_s, σ2 chosen by the sign of v) is continuous at v = 0 but not differentiable
there.  A Runge–Kutta or Rosenbrock step across the crossing meets a kink in its stages: its
local error is O(h²) instead of O(h⁵), and its embedded error estimate, the difference of two
solutions that meet the same kink, need not see it — the error then does not fall in
proportion to the tolerance (measured on the DDFS at 0.5 mm/s with the hollow motor at
16 mm/s, whose table speed crosses zero eight times in its start transient; docs/model.md,
"Integration accuracy").  The cure is the textbook one for a discontinuity in a derivative
(Hairer, Nørsett & Wanner, *Solving ODEs I*, 2nd ed., Sect. II.6, "Discontinuities";
Shampine & Thompson, "Event location for ordinary differential equations", Comput. Math.
Appl. 39 (2000) 43–54): locate the crossing on the step's continuous extension, throw the
step away, and step to the crossing, so that no step has the kink inside.

Each surface is a linear function of the state, g(y) = W[k]·y (a site's sliding speed is a
linear combination of the bodies' speeds in every drive of the package; the rows are found by
:func:`feeddrive.engine.simulate.switching_rows`).
"""

from __future__ import annotations

import numpy as np

from .._jit import kernel

#: a crossing closer than this fraction of the step to either of its ends is left inside the
#: step (the kink's contribution to the step's error is of order this fraction squared); it
#: also keeps the step that starts at a located crossing from locating it again
THETA_MIN = 1e-4


@kernel
def _dense_value(row: np.ndarray, th: float, stiff: bool, y: np.ndarray, y_new: np.ndarray,
                 q1: np.ndarray, q2: np.ndarray, q3: np.ndarray, e: np.ndarray) -> float:
    """W[k]·y(t + θh) on the step's continuous extension (the driver's output formulas)."""
    th1 = 1.0 - th
    g = 0.0
    for i in range(y.size):
        if row[i] != 0.0:
            if stiff:
                yp = th1 * y[i] + th * (y_new[i] + th1 * (q1[i] + th * (q2[i] + th * q3[i])))
            else:
                yp = y[i] + th * (q1[i] + th1 * (q2[i] + th * (q3[i] + th1 * e[i])))
            g += row[i] * yp
    return g


@kernel
def first_crossing(W: np.ndarray, y: np.ndarray, y_new: np.ndarray, q1: np.ndarray,
                   q2: np.ndarray, q3: np.ndarray, e: np.ndarray,
                   stiff: bool) -> tuple[float, int]:
    """The fraction θ ∈ (0, 1) of the step at which the first surface W[k]·y changes sign,
    located on the step's continuous extension, and k; (−1, −1) when none does, or only
    within :data:`THETA_MIN` of the step's ends.

    Parameters
    ----------
    W : numpy.ndarray
        (m, n) surfaces, one row each [state units → m/s].
    y, y_new : numpy.ndarray
        States at the step's start and end [SI, per state].
    q1, q2, q3, e : numpy.ndarray
        The step's dense-output coefficients (DOPRI5: q1, q2, q3, e; Rosenbrock: q1, q2, q3)
        [SI, per state].
    stiff : bool
        The step was a RODAS4 step.

    Returns
    -------
    theta : float
        θ [-], or −1.
    k : int
        The surface, or −1.

    Notes
    -----
    A sign change between the step's ends is a crossing (a surface touched and left on the
    same side within one step is not seen).  The root is bracketed and refined by the
    Illinois variant of regula falsi (Dowell & Jarratt, BIT 11 (1971) 168–174) to 1e-12 of
    the step.
    """
    best = -1.0
    which = -1
    n = y.size
    for k in range(W.shape[0]):
        g0 = 0.0
        g1 = 0.0
        for i in range(n):
            g0 += W[k, i] * y[i]
            g1 += W[k, i] * y_new[i]
        if not (g0 * g1 < 0.0):
            continue
        a, b = 0.0, 1.0
        ga, gb = g0, g1
        side = 0
        th = 0.5
        for _ in range(60):
            th = (a * gb - b * ga) / (gb - ga)
            gt = _dense_value(W[k], th, stiff, y, y_new, q1, q2, q3, e)
            if gt == 0.0:
                break
            if gt * ga < 0.0:
                b, gb = th, gt
                if side == -1:
                    ga *= 0.5
                side = -1
            else:
                a, ga = th, gt
                if side == 1:
                    gb *= 0.5
                side = 1
            if b - a < 1e-12:
                break
        if THETA_MIN < th < 1.0 - THETA_MIN and (best < 0.0 or th < best):
            best = th
            which = k
    return best, which
