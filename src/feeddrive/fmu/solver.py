"""The FMU's integrator: advance a model to a communication point, sample instants as events.

The integrator is the one driver of :mod:`feeddrive.solvers.driver` specialised ``COMM``
(:func:`template_source`, :func:`advance_function`): written once, in the restricted Python of
the package's kernels, and built twice from that one text — by numba into a model's generated
module (next to its ``rhs``, ``sample_update`` and the DOPRI5 step, error estimate and error
norm it calls: the one explicit step of :mod:`feeddrive.solvers.steps` written for the tableau
:data:`feeddrive.solvers.tableaux.DOPRI5`, the same text every use of the driver calls), and by
the C translator (:mod:`feeddrive.backends.c_backend`) into the FMU's C source.  The tests run
both on the same model and inputs and require the same trajectory.

It is the driver's explicit DOPRI5 with the same step, error norm and PI step-size controller
(Hairer, Nørsett & Wanner, Solving ODEs I, Sect. II.4) as the ``dense`` methods, on the event
schedule of its use: the sampled-controller instants ``t0 + k·base`` are exact step ends where
``sample_update`` runs and the derivative is re-evaluated (the zero-order-hold outputs jump
there), and the communication point is the end.  A sample instant within 1e-9·base of the
communication point is taken as that point.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from ..solvers import driver_text

# memory[...] (written with these literal indices in the driver's COMM branches: the C
# translator takes a name inside an assignment target for a local): step size, PI
# controller's last error, index of the last sample instant applied, 1 if that instant is the
# current time (its update may be redone with new inputs), and the counters: accepted steps,
# rejected steps, right-hand-side evaluations
MEM_H, MEM_ERR, MEM_KB, MEM_AT_SAMPLE, MEM_STEPS, MEM_REJECTED, MEM_RHS = range(7)
MEMORY_SIZE = 7
STATUS_OK, STATUS_MAX_STEPS, STATUS_STEP_UNDERFLOW, STATUS_NON_FINITE = 0, 1, 2, 3
STATUS_MESSAGES = {
    STATUS_OK: "success",
    STATUS_MAX_STEPS: "maximum number of steps in one communication step reached",
    STATUS_STEP_UNDERFLOW: "step size fell below its minimum",
    STATUS_NON_FINITE: "state became non-finite (NaN or Inf)",
}
CONSTANTS = {"MEM_H": MEM_H, "MEM_ERR": MEM_ERR, "MEM_KB": MEM_KB,
             "MEM_AT_SAMPLE": MEM_AT_SAMPLE, "MEM_STEPS": MEM_STEPS,
             "MEM_REJECTED": MEM_REJECTED, "MEM_RHS": MEM_RHS, "STATUS_OK": STATUS_OK,
             "STATUS_MAX_STEPS": STATUS_MAX_STEPS,
             "STATUS_STEP_UNDERFLOW": STATUS_STEP_UNDERFLOW,
             "STATUS_NON_FINITE": STATUS_NON_FINITE}


def new_memory(h_init: float) -> np.ndarray:
    """The solver memory of a run that has not started (``memory`` of the driver's ``COMM``
    specialisation, :func:`advance_function`).

    Parameters
    ----------
    h_init : float
        First step size [s].

    Returns
    -------
    numpy.ndarray
        The memory (``MEMORY_SIZE`` values) [mixed, see MEM_*].
    """
    memory = np.zeros(MEMORY_SIZE)
    memory[MEM_H] = h_init
    memory[MEM_ERR] = 1e-4
    return memory


def template_source() -> str:
    """The driver specialised ``COMM`` as placed in a model's generated module (named
    ``advance``; it calls the step functions the module holds, as the C translation does).

    Returns
    -------
    str
        Python source.
    """
    consts = "\n".join(f"{k} = {v!r}" for k, v in CONSTANTS.items())
    return (consts + "\nfrom feeddrive.solvers.schedule import due, next_instant\n\n\n@kernel\n"
            + driver_text.source("advance", inline=False))


@functools.cache
def advance_function() -> Any:
    """The Python function of the FMU's integrator (the driver specialised ``COMM``, named
    ``advance``), which the C translator reads (:func:`feeddrive.fmu.build.solver_c`).

    ``advance(t, t_end, t0, n, y, held, held_prev, P, T, schedule, tick, base, rtol, atol,
    rel_mask, h_max, max_steps, redo, memory, f0, k2, k3, k4, k5, k6, f_new, yt, y_new, e,
    aux) -> status`` integrates the ``n`` states ``y`` from ``t`` to ``t_end`` [s].  Sample
    instants are ``t0 + k·base`` for the breakpoints k of the schedule ``schedule``
    (:mod:`feeddrive.solvers.schedule`; ``t0``: the start of the run, where the caller applied
    the update of breakpoint 0; ``tick``: work space, one per clock); ``memory``
    (:data:`MEM_H` …) carries the step size, controller memory and the index of the last
    instant applied from one call to the next.  ``redo`` = 1: the inputs changed since the
    last call; if that call ended on a sample instant, its update is repeated from
    ``held_prev`` with the new inputs (an instant on a communication point takes the inputs
    of the step that starts there).  ``held`` is left updated, ``aux`` holds the signals at
    ``t_end``.  The other arrays (length ``n``) are work space.  The status is
    ``STATUS_OK``, ``STATUS_MAX_STEPS``, ``STATUS_STEP_UNDERFLOW`` or ``STATUS_NON_FINITE``.

    Returns
    -------
    function
        The integrator.

    References
    ----------
    .. [1] J. R. Dormand, P. J. Prince, "A family of embedded Runge-Kutta formulae", J. Comput.
       Appl. Math. 6 (1980) 19–26.
    """
    return driver_text.define(driver_text.source("advance", inline=False), "advance")
