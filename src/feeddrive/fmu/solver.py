"""The FMU's integrator: advance a model to a communication point, sample instants as events.

:func:`advance_template` is written once, in the restricted Python of the package's kernels,
and built twice from that one text: by numba into a model's generated module (next to its
``rhs``, ``sample_update`` and the DOPRI5 step, error estimate and error norm it calls — the
one explicit step of :mod:`feeddrive.solvers.steps` written for the tableau
:data:`feeddrive.solvers.tableaux.DOPRI5`, the same text every driver calls), and by
the C translator (:mod:`feeddrive.backends.c_backend`) into the FMU's C source.  The tests run
both on the same model and inputs and require the same trajectory.

It is the ``MODE_DOPRI5`` part of :func:`feeddrive.solvers.switching.integrate_template` with
the same step, error norm and PI step-size controller (Hairer, Nørsett & Wanner, Solving ODEs
I, Sect. II.4), on an event schedule of its own: the sampled-controller instants
``t0 + k·base`` are exact step ends where ``sample_update`` runs and the derivative is
re-evaluated (the zero-order-hold outputs jump there), and the communication point is the end.
A sample instant within 1e-9·base of the communication point is taken as that point.
"""

from __future__ import annotations

import inspect
import math
from typing import Any

import numpy as np

from ..solvers.schedule import due, next_instant

# memory[...] (written with these literal indices in advance_template: the C translator takes a
# name inside an assignment target for a local): step size, PI controller's last error, index
# of the last sample instant applied, 1 if that instant is the current time (its update may
# be redone with new inputs), and the counters: accepted steps, rejected steps, right-hand-side
# evaluations
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

# Placeholders: the generated module supplies these (see feeddrive.solvers.dopri5).
_dp5_step: Any = None
_dp5_error: Any = None
_error_norm: Any = None
_pi_factor: Any = None
_reject_factor: Any = None


def rhs(*args: Any) -> None:  # pragma: no cover - replaced in the generated module
    raise NotImplementedError("placeholder: the assembled model's right-hand side")


def sample_update(*args: Any) -> None:  # pragma: no cover - replaced in the generated module
    raise NotImplementedError("placeholder: the assembled model's sampled-controller update")


def new_memory(h_init: float) -> np.ndarray:
    """The solver memory of a run that has not started (see :func:`advance_template`)."""
    memory = np.zeros(MEMORY_SIZE)
    memory[MEM_H] = h_init
    memory[MEM_ERR] = 1e-4
    return memory


def advance_template(t: float, t_end: float, t0: float, n: int, y: np.ndarray,
                     held: np.ndarray, held_prev: np.ndarray, P: np.ndarray, T: np.ndarray,
                     schedule: np.ndarray, tick: np.ndarray, base: float, rtol: float,
                     atol: np.ndarray, rel_mask: np.ndarray, h_max: float, max_steps: int,
                     redo: int, memory: np.ndarray, f0: np.ndarray, k2: np.ndarray,
                     k3: np.ndarray, k4: np.ndarray, k5: np.ndarray, k6: np.ndarray,
                     f_new: np.ndarray, yt: np.ndarray, y_new: np.ndarray, e: np.ndarray,
                     aux: np.ndarray) -> int:
    """Integrate the ``n`` states ``y`` from ``t`` to ``t_end`` [s]; return a status.

    Sample instants are ``t0 + k·base`` for the breakpoints k of the schedule ``schedule``
    (:mod:`feeddrive.solvers.schedule`; ``t0``: the start of the run, where the caller applied
    the update of breakpoint 0; ``tick``: work space, one per clock); ``memory``
    (:data:`MEM_H` …) carries the step size, controller memory and the index of the last
    instant applied from one call to the next.  ``redo`` = 1: the inputs changed since the
    last call; if that call ended on a sample instant, its update is repeated from
    ``held_prev`` with the new inputs (an instant on a communication point takes the inputs
    of the step that starts there).  ``held`` is left updated, ``aux`` holds
    the signals at ``t_end``.  The other arrays (length ``n``) are work space.
    """
    kb = int(memory[MEM_KB])
    if redo == 1 and memory[MEM_AT_SAMPLE] > 0.5:
        for i in range(held.size):
            held[i] = held_prev[i]
        due(kb, schedule, tick)
        sample_update(t, y, held, P, T, tick)
    h = memory[MEM_H]
    err_old = memory[MEM_ERR]
    steps = 0
    rejected = 0
    n_rhs = 0
    beta = 0.04
    alpha = 0.2 - 0.75 * beta
    h_min = 1e-14
    status = STATUS_OK
    rhs(t, y, held, P, T, f0, aux)
    n_rhs += 1
    memory[3] = 0.0  # MEM_AT_SAMPLE
    while t < t_end and status == STATUS_OK:
        # ---- the next event: a sample instant or the communication point
        t_ev = t_end
        is_sample = False
        kb_next = next_instant(kb, schedule)  # the schedule's next instant (-1: none)
        if kb_next >= 0:
            t_s = t0 + kb_next * base
            if t_s <= t_end + 1e-9 * base:
                is_sample = True
                if t_s < t_end - 1e-9 * base:
                    t_ev = t_s
        while t < t_ev and status == STATUS_OK:
            last = False
            h_try = min(h, h_max)
            if t + h_try >= t_ev - 1e-12 * max(1.0, abs(t_ev)):
                h_try = t_ev - t
                last = True
            err = 0.0
            t_new = t_ev
            while True:
                t_new = t_ev if last else t + h_try
                _dp5_step(t, h_try, y, f0, held, P, T, k2, k3, k4, k5, k6, f_new, yt, y_new,
                          aux, t_new)
                n_rhs += 6
                steps += 1
                _dp5_error(h_try, f0, k2, k3, k4, k5, k6, f_new, e)
                err = _error_norm(e, y, y_new, rtol, atol, rel_mask)
                if err <= 1.0:
                    break
                rejected += 1
                fac = _reject_factor(err)
                h_try *= fac
                last = False
                if h_try < h_min:
                    status = STATUS_STEP_UNDERFLOW
                    break
                if steps > max_steps:
                    status = STATUS_MAX_STEPS
                    break
            if status != STATUS_OK:
                break
            # ---- accepted: PI step-size control for the next step
            fac = _pi_factor(err, err_old, alpha, beta)
            if err != 0.0:
                err_old = max(err, 1e-4)
            h_new = h_try * fac
            if not last or h_new < h:
                h = min(h_new, h_max)
            finite = True
            for i in range(n):
                y[i] = y_new[i]
                f0[i] = f_new[i]
                if not math.isfinite(y_new[i]):
                    finite = False
            t = t_new
            if not finite:
                status = STATUS_NON_FINITE
            elif steps > max_steps:
                status = STATUS_MAX_STEPS
        if status != STATUS_OK:
            break
        # ---- at the event
        if is_sample:
            kb = kb_next
            if t_ev == t_end:
                for i in range(held.size):
                    held_prev[i] = held[i]
                memory[3] = 1.0  # MEM_AT_SAMPLE
            due(kb, schedule, tick)
            sample_update(t, y, held, P, T, tick)
            rhs(t, y, held, P, T, f0, aux)
            n_rhs += 1
    memory[0] = h  # MEM_H
    memory[1] = err_old  # MEM_ERR
    memory[2] = kb  # MEM_KB
    memory[4] += steps  # MEM_STEPS
    memory[5] += rejected  # MEM_REJECTED
    memory[6] += n_rhs  # MEM_RHS
    return status


def template_source() -> str:
    """The text of :func:`advance_template` as placed in a model's generated module (named
    ``advance``)."""
    src = inspect.getsource(advance_template).replace("def advance_template(", "def advance(", 1)
    consts = "\n".join(f"{k} = {v!r}" for k, v in CONSTANTS.items())
    return (consts + "\nfrom feeddrive.solvers.schedule import due, next_instant\n\n\n@kernel\n"
            + src)
