"""A damped Gauss–Newton solve of a square or over-determined residual with a weak pull to
its start: the operating points of :func:`feeddrive.analysis.linear.steady_state`.  Pure
numerics, no model.

The residual r(u) is solved together with ``pull·(u − u₀)``: directions no equation holds
(a singular Jacobian) stay at their start instead of wandering on rounding noise.  Each
iteration solves the linear least-squares problem ``[J; pull·I] Δu = −[r; pull·(u − u₀)]``
(:func:`numpy.linalg.lstsq`) and halves the step until the sum of squares falls (Armijo-free
backtracking, as in Nocedal & Wright, *Numerical Optimization*, 2nd ed., Sect. 10.3).  It
stops when no halving lowers the sum of squares, when a full (undamped) step leaves more than
``stall`` of it (Newton converges much faster than that until the residual's rounding floor),
or when ``max_iterations`` Jacobians are spent.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["pulled_gauss_newton"]


def pulled_gauss_newton(residual: Callable[[np.ndarray], np.ndarray],
                        linearised: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
                        u0: np.ndarray, pull: float, *, max_iterations: int = 50,
                        stall: float = 0.25, max_halvings: int = 10) -> tuple[np.ndarray, int]:
    """Solve ``residual(u) = 0`` in the least-squares sense with a weak pull to ``u0``.

    Parameters
    ----------
    residual : callable
        ``residual(u)`` → r [-, per equation].
    linearised : callable
        ``linearised(u)`` → (r, J): the residual and its Jacobian ∂r/∂u at ``u``.
    u0 : numpy.ndarray
        Start, and the point the pull holds free directions at [-, per unknown].
    pull : float
        Weight of ``u − u0`` beside the equations [-].
    max_iterations : int, default 50
        Jacobians evaluated at most [-].
    stall : float, default 0.25
        Stop once a full step leaves more than this share of the sum of squares [-].
    max_halvings : int, default 10
        Halvings of a step that does not lower the sum of squares before stopping [-].

    Returns
    -------
    u : numpy.ndarray
        The solution (the last point that lowered the sum of squares).
    iterations : int
        Jacobians evaluated.
    """
    u = np.array(u0, dtype=float)
    eye = pull * np.eye(u.size)
    r, jac = linearised(u)
    full = np.concatenate([r, pull * (u - u0)])
    cost = float(full @ full)
    iterations = 1
    while cost > 0.0:
        step = np.linalg.lstsq(np.vstack([jac, eye]), -full, rcond=None)[0]
        halvings = 0
        while True:
            trial = u + step
            got = np.concatenate([residual(trial), pull * (trial - u0)])
            trial_cost = float(got @ got)
            if trial_cost < cost or halvings == max_halvings:
                break
            step = 0.5 * step
            halvings += 1
        if not trial_cost < cost:
            break  # no step lowers it: the rounding floor
        u, previous, cost = trial, cost, trial_cost
        if (halvings == 0 and cost > stall * previous) or iterations >= max_iterations:
            break  # a full step that no longer converges fast: the rounding floor
        r, jac = linearised(u)
        full = np.concatenate([r, pull * (u - u0)])
        iterations += 1
    return u, iterations
