"""Compiled Dormand–Prince 5(4) integrator for the closed-loop drive, with declared breakpoints.

Breakpoints are the instants of the model's sample schedule (every sampled part's clock,
:mod:`feeddrive.solvers.schedule`; the zero-order-hold outputs jump there) and the output
instants; the integrator lands on each exactly, applies the sampled parts' update where one is
due, and restarts the step from there, so no step straddles a jump in the right-hand side
(the "declare your discontinuities" lesson of diffrax; python-control issue #933).  The step
is the one explicit step of :mod:`feeddrive.solvers.steps` for the tableau
:data:`feeddrive.solvers.tableaux.DOPRI5`, written into :func:`integrate_template`'s text.

Error control: mixed absolute/relative weights per state; states whose absolute size carries no
meaning (shaft angles, positions) use absolute tolerance only.  Step-size control is Hairer's
PI controller (Hairer, Nørsett & Wanner, Solving ODEs I, Sect. II.4).  With ``adaptive = 0`` the
same tableau runs at a fixed step (used to verify the order).
"""

from __future__ import annotations

import functools
import inspect
import math
from typing import TYPE_CHECKING, Any

import numpy as np

from . import steps
from .schedule import due, next_instant
from .tableaux import DOPRI5

if TYPE_CHECKING:
    from ..model.assemble import Model

ORDER = DOPRI5.order
# module constants the generated module imports from here
CONSTANTS = ("STATUS_OK", "STATUS_MAX_STEPS", "STATUS_STEP_UNDERFLOW", "STATUS_NON_FINITE",
             "STATUS_STOPPED", "STATUS_DIVERGED")

STATUS_OK = 0
STATUS_MAX_STEPS = 1
STATUS_STEP_UNDERFLOW = 2
STATUS_NON_FINITE = 3
STATUS_STOPPED = 4  # another thread asked the running call to stop (new_memory's stop slot)
# a state beyond its divergence bound (feeddrive.engine.simulate.divergence_bounds): the run
# stops early, the state there recorded as its last sample; not an error, the verdict is "unstable"
STATUS_DIVERGED = 5
STATUS_MESSAGES = {
    STATUS_OK: "success",
    STATUS_MAX_STEPS: "maximum number of steps reached",
    STATUS_STEP_UNDERFLOW: "step size fell below its minimum",
    STATUS_NON_FINITE: "state became non-finite (NaN or Inf)",
    STATUS_STOPPED: "stopped on request",
    STATUS_DIVERGED: "a state left its divergence bound (the loop diverges)",
}


# The solver never imports a model.  ``integrate_template`` is compiled once per assembled
# model: its text is placed in the model's generated module (feeddrive.model.codegen), where
# ``rhs``, ``sample_update``, ``N_AUX`` and ``N_HELD`` are that model's.  These placeholders
# only make this file importable and checkable on its own.
N_AUX = 0
N_HELD = 1


def rhs(*args: Any) -> None:  # pragma: no cover - replaced in the generated module
    raise NotImplementedError("placeholder: the assembled model's right-hand side")


def sample_update(*args: Any) -> None:  # pragma: no cover - replaced in the generated module
    raise NotImplementedError("placeholder: the assembled model's sampled-controller update")


_dp5_step: Any = None  # the generated module's DOPRI5 step (feeddrive.solvers.steps)
_dp5_error: Any = None
_error_norm: Any = None
_pi_factor: Any = None
_reject_factor: Any = None


@functools.lru_cache(maxsize=1)
def template_sources() -> list[str]:
    """Text placed in each generated model module: the status codes and the integrator (its
    step is the one of :mod:`feeddrive.solvers.steps`, placed beside it)."""
    names = ", ".join(CONSTANTS)
    src = steps.inline_steps(inspect.getsource(integrate_template)).replace(
        "def integrate_template(", "def integrate(", 1)
    aux = inspect.getsource(auxiliary_template).replace("def auxiliary_template(",
                                                        "def auxiliary(", 1)
    return [f"from feeddrive.solvers.dopri5 import ({names})",
            "from feeddrive.solvers.schedule import due, next_instant", "@kernel\n" + src,
            "@kernel\n" + aux]


def auxiliary_template(t_out: np.ndarray, y_out: np.ndarray, P: np.ndarray,
                       T: np.ndarray) -> np.ndarray:
    """The auxiliary signals at recorded (t, y) of a run with continuous loops (where they
    depend on nothing else): evaluated only when a Result is asked for one."""
    n = t_out.size
    out = np.empty((n, N_AUX))
    held = np.zeros(N_HELD)
    dy = np.empty(y_out.shape[1])
    aux = np.empty(N_AUX)
    for i in range(n):
        rhs(t_out[i], y_out[i], held, P, T, dy, aux)
        out[i, :] = aux
    return out


def new_memory(n_states: int, h_init: float) -> np.ndarray:
    """The carried-over state (step size, last error, first stage) of a run that has not
    started (:func:`integrate`).  Its last two slots are a *stop request* (non-zero: the
    call ends after its current step with STATUS_STOPPED) and the *live time* (the time [s]
    of the last accepted step, written as the solver goes): another thread reads a long
    call's progress and stops it while it runs (the kernels release the GIL;
    feeddrive.engine.simulate.Simulation.live_time and request_stop)."""
    memory = np.zeros(4 + n_states)
    memory[:2] = (h_init, 1e-4)
    return memory


def integrate(model: Model, y0: np.ndarray, t_end: float, out_every: int, base: float,
              schedule: np.ndarray, rtol: float, atol: np.ndarray,
              rel_mask: np.ndarray, h_init: float, h_max: float, adaptive: int,
              max_steps: int, *, start: int = 0, held: np.ndarray | None = None,
              memory: np.ndarray | None = None, bound: np.ndarray | None = None,
              P: np.ndarray | None = None,
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Integrate ``model`` from breakpoint ``start`` (t = start·base, state ``y0``) to
    ``t_end`` (see :func:`integrate_template`; ``schedule``: the run's sample schedule,
    :func:`feeddrive.engine.simulate.sampling`).  ``held`` (the sampled controller's values)
    and ``memory`` (step size, last error) are updated in place, so that a run continued
    from where a previous call stopped is bit-identical to one call over the whole span.
    ``bound``: the largest |state| per state before the run stops as diverged (None: none);
    ``P``: the parameter vector (None: the model's; a run passes the periods on its grid,
    :meth:`feeddrive.engine.simulate.Sampling.parameters`)."""
    held = np.zeros(model.n_held) if held is None else held
    memory = new_memory(len(model.states), h_init) if memory is None else memory
    bound = np.full(len(model.states), np.inf) if bound is None else bound
    result: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray] = (
        model.module.integrate(y0, t_end, out_every, base,
                               np.ascontiguousarray(schedule, dtype=np.int64),
                               model.P if P is None else P, model.T,
                               rtol, atol, rel_mask, h_max, adaptive, max_steps, start, held,
                               memory, bound))
    return result


# error_model="numpy" (feeddrive._jit): a division by zero gives inf/NaN (caught below as a
# rejected step or STATUS_NON_FINITE) instead of Python's ZeroDivisionError check on every
# division of the inlined right-hand side; bit-identical results, about 25 % less time.
def integrate_template(y0: np.ndarray, t_end: float, out_every: int, base: float,
                       schedule: np.ndarray, P: np.ndarray, T: np.ndarray, rtol: float,
                       atol: np.ndarray, rel_mask: np.ndarray, h_max: float, adaptive: int,
                       max_steps: int, start: int, held: np.ndarray, memory: np.ndarray,
                       bound: np.ndarray,
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Integrate from breakpoint ``start`` to ``t_end`` over a grid of breakpoints spaced
    ``base`` [s], from the state ``y0`` at t = start·base.  ``schedule``: the sample schedule, the
    breakpoints between two instants of each clock (:mod:`feeddrive.solvers.schedule`); at an
    instant the sampled parts are updated and the step restarts from the new derivative.

    Output is recorded every ``out_every`` breakpoints (counted from 0).  ``held`` (sampled
    controller) and ``memory`` = [step size, last error, last stage k7 …] are read and left
    updated, so that consecutive calls continue one integration bit for bit (with continuous
    control the first stage of a step is the previous step's last one, evaluated where that
    step ended — a hair off the breakpoint when the step was not cut to it).  Returns
    (t_out, y_out, aux_out, stats, held) with stats = [status, steps, rejected,
    rhs_evaluations, t_reached].  A state with |y_i| > ``bound[i]`` at a step end stops the run
    with ``STATUS_DIVERGED``; that step end is recorded as the last output sample.
    """
    n = y0.size
    n_break = int(round(t_end / base))
    n_out = n_break // out_every - (start + out_every - 1) // out_every + 1
    t_out = np.empty(n_out)
    y_out = np.empty((n_out, n))
    aux_out = np.empty((n_out, N_AUX))
    y = y0.copy()
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    k5 = np.empty(n)
    k6 = np.empty(n)
    k7 = np.empty(n)
    yt = np.empty(n)
    y_new = np.empty(n)
    e = np.empty(n)
    aux = np.empty(N_AUX)
    steps = 0
    rejected = 0
    n_rhs = 0
    status = STATUS_OK
    h = memory[0]
    err_old = memory[1]
    beta = 0.04
    alpha = 0.2 - 0.75 * beta
    t = 0.0
    i_out = 0
    h_min = 1e-14
    # With every loop continuous nothing jumps at a breakpoint: the last stage of the step that
    # ended there, evaluated at exactly t_break, is the derivative there (first same as last).
    continuous = next_instant(0, schedule) < 0
    tick = np.empty(schedule.size, dtype=np.int64)
    for kb in range(start, n_break + 1):
        t_break = kb * base
        # the sample instants of the schedule at this breakpoint: the sampled parts' update
        # (a continued run applied the update at its first breakpoint in the previous call)
        n_due = due(kb, schedule, tick)
        if n_due > 0 and (kb > start or start == 0):
            sample_update(t_break, y, held, P, T, tick)
        if kb == start and start > 0 and continuous:
            rhs(t_break, y, held, P, T, k1, aux)
            n_rhs += 1
            for i in range(n):
                k1[i] = memory[2 + i]
        elif kb == start or n_due > 0:
            rhs(t_break, y, held, P, T, k1, aux)
            n_rhs += 1
        if kb % out_every == 0 and i_out < n_out:
            t_out[i_out] = t_break
            y_out[i_out, :] = y
            aux_out[i_out, :] = aux
            i_out += 1
        if kb == n_break:
            break
        t = t_break
        t_next = (kb + 1) * base
        fresh = True
        while t < t_next - 1e-15 * t_next:
            if not fresh:
                rhs(t, y, held, P, T, k1, aux)
                n_rhs += 1
            fresh = False
            last = False
            if h >= t_next - t:
                h_try = t_next - t
                last = True
            else:
                h_try = h
            while True:
                t_new = t_next if last else t + h_try
                _dp5_step(t, h_try, y, k1, held, P, T, k2, k3, k4, k5, k6, k7, yt, y_new, aux,
                          t_new)
                n_rhs += 6
                steps += 1
                if adaptive == 0:
                    err = 0.0
                    break
                _dp5_error(h_try, k1, k2, k3, k4, k5, k6, k7, e)
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
            for i in range(n):
                y[i] = y_new[i]
                k1[i] = k7[i]
            fresh = True
            t = t_next if last else t + h_try
            if memory.shape[0] > 3 + n:  # the live time and stop slots (new_memory)
                memory[memory.shape[0] - 1] = t
                if memory[memory.shape[0] - 2] != 0.0:
                    status = STATUS_STOPPED
                    break
            if adaptive == 1:
                fac = _pi_factor(err, err_old, alpha, beta)
                err_old = max(err, 1e-4)
                h_new = h_try * fac
                if not last or h_new < h:
                    h = min(h_new, h_max)
            if steps > max_steps:
                status = STATUS_MAX_STEPS
                break
            finite = True
            diverged = False
            for i in range(n):
                if not math.isfinite(y[i]):
                    finite = False
                elif abs(y[i]) > bound[i]:
                    diverged = True
            if not finite:
                status = STATUS_NON_FINITE
                break
            if diverged:
                status = STATUS_DIVERGED
                if i_out < n_out:  # the last rhs call was at (t, y): aux is that of y
                    t_out[i_out] = t
                    y_out[i_out, :] = y
                    aux_out[i_out, :] = aux
                    i_out += 1
                break
        if status != STATUS_OK:
            break
    memory[0] = h
    memory[1] = err_old
    for i in range(n):
        memory[2 + i] = k1[i]
    stats = np.array([float(status), float(steps), float(rejected), float(n_rhs), t])
    return t_out[:i_out], y_out[:i_out], aux_out[:i_out], stats, held
