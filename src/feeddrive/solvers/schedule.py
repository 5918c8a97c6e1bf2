"""The event schedule of the driver: the sample instants of any number of clocks, merged.

A model declares a clock for each sampled part (the three loops, a feed-forward with its own
rate …; :meth:`feeddrive.model.codegen.Builder.clock`), its period a parameter slot.  A run
puts every instant on one breakpoint grid t = k·base [s]
(:func:`feeddrive.engine.simulate.sampling`: ``base`` is the fastest period, every period a
multiple of it) and gives the driver the
schedule as ``steps``: clock c has its instants at the breakpoints k with k mod steps[c] = 0
(steps[c] = 0: the part runs continuously).  The driver lands on each merged instant exactly
(:func:`next_instant`), and calls the model's ``sample_update(t, y, held, P, T, tick)`` there
with ``tick`` from :func:`due`: an instant is an exact breakpoint count, not a sum of floats,
so instants of different clocks that coincide are one event.

Both kernels are compiled into the generated driver modules by import and translated to C with the
FMU's integrator (the driver of :mod:`feeddrive.solvers.driver` specialised for
:mod:`feeddrive.fmu.solver`).
"""

from __future__ import annotations

import numpy as np

from .._jit import kernel


@kernel
def due(kb: int, steps: np.ndarray, tick: np.ndarray) -> int:
    """Write ``tick[c]`` = the count of clock c's instant at breakpoint ``kb`` (kb / steps[c]),
    or −1 if clock c has none there; return how many clocks have one.

    Parameters
    ----------
    kb : int
        The breakpoint index.
    steps : numpy.ndarray of int
        Period of each clock in breakpoints; 0 for a continuous part.
    tick : numpy.ndarray of int
        Output: each clock's instant count, or −1.

    Returns
    -------
    int
        Number of clocks with an instant at ``kb``.
    """
    count = 0
    for c in range(steps.size):
        if steps[c] > 0 and kb % steps[c] == 0:
            tick[c] = kb // steps[c]
            count += 1
        else:
            tick[c] = -1
    return count


@kernel
def next_instant(kb: int, steps: np.ndarray) -> int:
    """The first breakpoint after ``kb`` at which some clock has an instant (−1: every part
    runs continuously).

    Parameters
    ----------
    kb : int
        The current breakpoint index.
    steps : numpy.ndarray of int
        Period of each clock in breakpoints; 0 for a continuous part.

    Returns
    -------
    int
        The next breakpoint index with an instant, or −1.
    """
    best = -1
    for c in range(steps.size):
        if steps[c] > 0:
            k = (kb // steps[c] + 1) * steps[c]
            if best < 0 or k < best:
                best = k
    return best


def no_schedule(n_clocks: int) -> np.ndarray:
    """``steps`` of a run with every part continuous.

    Parameters
    ----------
    n_clocks : int
        Number of clocks the model declares.

    Returns
    -------
    numpy.ndarray of int
        Zeros, at least one.
    """
    return np.zeros(max(1, n_clocks), dtype=np.int64)
