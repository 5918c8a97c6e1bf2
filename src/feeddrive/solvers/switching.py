"""Dense-output integrator with automatic stiffness switching: DOPRI5 ⇄ RODAS4.

One compiled driver (:func:`integrate_template`, placed in every generated model module as
``integrate_dense``) runs in three modes:

* ``MODE_DOPRI5``: Dormand–Prince 5(4) (the tableau :data:`feeddrive.solvers.tableaux.DOPRI5`
  through the one explicit step of :mod:`feeddrive.solvers.steps`) with its 4th-order
  continuous extension (Hairer, Nørsett & Wanner, Solving ODEs I, Sect. II.6,
  and their code ``dopri5.f``, ``CONTD5``; the same coefficients as scipy's RK45 ``P``);
* ``MODE_RODAS4``: the tableau :data:`~feeddrive.solvers.tableaux.RODAS4` through the one
  Rosenbrock step of :mod:`feeddrive.solvers.steps` (Jacobian kernels:
  :mod:`feeddrive.solvers.rodas4`);
* ``MODE_AUTO``: starts with DOPRI5 and switches to RODAS4 when Hairer's stiffness test says
  the step is held by stability — h·‖k7 − k6‖/‖y7 − y6‖ > 3.25, the estimate of h|λ| from the
  last two stages, in ``STIFF_STEPS`` of the recent accepted steps (``dopri5.f``, ``NSTIFF``
  test) — and back to DOPRI5 when the Rosenbrock step h times the power-iteration estimate of
  the Jacobian's spectral radius stays below ``NONSTIFF_HRHO`` for ``NONSTIFF_STEPS`` steps
  (an explicit step of that size would be stable, and costs 6 right-hand sides instead of
  6 + one per group of Jacobian columns).

Dense output: the step is not capped by the output interval.  Outputs on the grid
t_i = i·out_every·base are interpolated inside the step that contains them.  Event times are
exact step ends: the instants of the sample schedule ``schedule`` — every clock's, merged
(:mod:`feeddrive.solvers.schedule`; the zero-order-hold outputs jump there:
``sample_update`` runs, the derivative is re-evaluated),
the profile breakpoints ``stops`` (kinks of the command: the Jacobian's f_t changes) and the end.
With ``adaptive = 0`` the chosen method runs at the fixed step ``h_init`` and the output grid
points are step ends too (used to verify the order).

The solver never imports a model: the templates are compiled into each model's generated module
next to its ``rhs`` and ``sample_update`` (:func:`template_sources`).
"""

from __future__ import annotations

import inspect
import math
from typing import TYPE_CHECKING, Any

import numpy as np

from . import steps
from .modes import H_LAMBDA as MODAL_H_LAMBDA
from .modes import REFRESH as MODAL_REFRESH
from .modes import ZETA_LIGHT as MODAL_ZETA_LIGHT
from .modes import jacobian_moved as modal_jacobian_moved
from .modes import step_cap as modal_step_cap
from .schedule import due, next_instant

if TYPE_CHECKING:
    from ..model.assemble import Model

MODE_DOPRI5, MODE_RODAS4, MODE_AUTO, MODE_MODAL = 0, 1, 2, 3


# Switching thresholds (measured on the benchmark scenarios, benchmarks/README.md)
STIFF_HLAMBDA = 3.25  # DOPRI5's stability boundary on the negative real axis is ≈ 3.3
STIFF_STEPS = 15  # stiff verdicts (reset after 6 non-stiff steps in a row), dopri5.f
NONSTIFF_HRHO = 3.0
NONSTIFF_STEPS = 5
POWER_ITERATIONS = 12
# MODE_MODAL (see the module docstring): RODAS4 steps capped on lightly damped modes
MODAL_SWITCH_GAIN = 2.0  # switch to RODAS4 only if the capped step is ≥ this × DOPRI5's
# DOPRI5 steps before a refused switch is considered again, and between two eigen-analyses
# of DOPRI5 steps (their cap too: DOPRI5's |R(iy)| > 1 for 1 < y < 3.3)
MODAL_RETRY = 500
# RODAS4 steps between two eigen-analyses at least (the cap of the last one holds meanwhile)
MODAL_EVERY = 10

STAT_NAMES = ("status", "steps", "rejected", "rhs_evaluations", "t_reached", "jacobians",
              "rosenbrock_steps", "switches", "output_rhs_evaluations", "eigen_analyses")

# h, method, frozen states known, stiff and non-stiff counts, DOPRI5 error memory, RODAS4
# error, step and first/rejected flags, the modal step cap, whether a reference Jacobian is
# kept, the step count until which a switch is refused and the DOPRI5 steps since the last
# eigen-analysis; then one live flag per state and the modal reference Jacobian (n × n)
# (integrate_template)
MEMORY_SCALARS = 14

CONSTANTS = ("MEMORY_SCALARS", "MODE_DOPRI5", "MODE_RODAS4", "MODE_AUTO", "MODE_MODAL",
             "STIFF_HLAMBDA", "STIFF_STEPS",
             "NONSTIFF_HRHO", "NONSTIFF_STEPS", "POWER_ITERATIONS", "MODAL_SWITCH_GAIN",
             "MODAL_RETRY", "MODAL_EVERY")

# Placeholders: the generated module supplies these (see feeddrive.solvers.dopri5).
N_AUX = 0
N_HELD = 1
STATUS_OK, STATUS_MAX_STEPS, STATUS_STEP_UNDERFLOW, STATUS_NON_FINITE = 0, 1, 2, 3
STATUS_STOPPED = 4
STATUS_DIVERGED = 5
_r4_fd_jacobian: Any = None
_r4_frozen_states: Any = None
_r4_rodas4_step: Any = None
_r4_rodas4_dense: Any = None
_r4_spectral_radius: Any = None
_dp5_step: Any = None
_dp5_error: Any = None
_dp5_dense: Any = None
_error_norm: Any = None
_pi_factor: Any = None
_reject_factor: Any = None


def rhs(*args: Any) -> None:  # pragma: no cover - replaced in the generated module
    raise NotImplementedError("placeholder: the assembled model's right-hand side")


def sample_update(*args: Any) -> None:  # pragma: no cover - replaced in the generated module
    raise NotImplementedError("placeholder: the assembled model's sampled-controller update")


def new_memory(n_states: int) -> np.ndarray:
    """The carried-over state of a run that has not started (:func:`integrate_template`).
    Its last two slots are a *stop request* (non-zero: the call ends after its current step
    with STATUS_STOPPED) and the *live time* (the time [s] of the last accepted step, written
    as the solver goes): another thread reads a long call's progress and stops it while it
    runs (the kernels release the GIL; feeddrive.engine.simulate.Simulation.live_time and
    request_stop)."""
    return np.zeros(MEMORY_SCALARS + n_states + n_states * n_states + 2)


def integrate(model: Model, y0: np.ndarray, t_end: float, out_every: int, base: float,
              schedule: np.ndarray, rtol: float, atol: np.ndarray,
              rel_mask: np.ndarray, h_init: float, h_max: float, adaptive: int,
              max_steps: int, mode: int, stops: np.ndarray, want_aux: bool = True, *,
              start: int = 0, held: np.ndarray | None = None,
              memory: np.ndarray | None = None, bound: np.ndarray | None = None,
              P: np.ndarray | None = None,
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Integrate ``model`` from breakpoint ``start`` (t = start·base, state ``y0``; a multiple
    of ``out_every``) to ``t_end`` (see :func:`integrate_template`).  ``held`` and ``memory``
    are updated in place, so a run continued from where a call stopped is bit-identical to
    one call in which that instant is a step end (a profile breakpoint, a sample instant).
    ``bound``: the largest |state| per state before the run stops as diverged (None: none);
    ``P``: the parameter vector (None: the model's; a run passes the periods on its grid)."""
    if start % out_every:
        raise ValueError(f"start = {start}: expected a multiple of out_every = {out_every}")
    held = np.zeros(model.n_held) if held is None else held
    memory = new_memory(len(model.states)) if memory is None else memory
    bound = np.full(len(model.states), np.inf) if bound is None else bound
    result: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray] = (
        model.module.integrate_dense(
            y0, t_end, out_every, base, np.ascontiguousarray(schedule, dtype=np.int64),
            model.P if P is None else P, model.T, rtol, atol, rel_mask, h_init, h_max,
            adaptive, max_steps, mode,
            np.ascontiguousarray(stops, dtype=np.float64), bool(want_aux),
            model.jacobian_pattern, model.jacobian_colours, start, held, memory, bound))
    return result


def integrate_template(y0: np.ndarray, t_end: float, out_every: int, base: float,
                       schedule: np.ndarray, P: np.ndarray, T: np.ndarray, rtol: float,
                       atol: np.ndarray, rel_mask: np.ndarray, h_init: float, h_max: float,
                       adaptive: int, max_steps: int, mode: int, stops: np.ndarray,
                       want_aux: bool, S: np.ndarray, colour: np.ndarray, start: int,
                       held: np.ndarray, memory: np.ndarray, bound: np.ndarray,
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Integrate from t = start·base (state ``y0``) to ``t_end`` with dense output every
    ``out_every·base`` [s]; ``schedule``: the sample schedule (breakpoints of ``base`` [s] between
    two instants of each clock, 0 = continuous; :mod:`feeddrive.solvers.schedule`).

    ``held`` (the sampled controller's values) and ``memory`` (step size, method, switching
    counters, step-size controller memory, which states are frozen; all 0 before the first
    call) carry the driver's state from one call to the next: ``memory[0] == 0`` starts a
    run, with the controller sampled at t = 0.

    ``stops``: sorted profile breakpoints [s] (exact step ends).  Returns (t_out, y_out,
    aux_out, stats, held); stats as :data:`STAT_NAMES` (the first five as
    :func:`feeddrive.solvers.dopri5.integrate_template`).  Without ``want_aux`` the auxiliary
    signals are not evaluated at the outputs and ``aux_out`` has no rows.  ``S``, ``colour``:
    the Jacobian's sparsity pattern and column groups (:func:`rodas4.fd_jacobian_template`).
    A state with |y_i| > ``bound[i]`` at a step end stops the run with ``STATUS_DIVERGED``; that
    step end is recorded as the last output sample.
    """
    n = y0.size
    n_break = int(round(t_end / base))
    t_end = n_break * base
    o0 = start // out_every  # index of the first output on the whole run's grid
    n_out = (n_break - start) // out_every + 1
    tick = np.empty(schedule.size, dtype=np.int64)
    t_out = np.empty(n_out)
    y_out = np.empty((n_out, n))
    aux_out = np.empty((n_out if want_aux else 0, N_AUX))
    y = y0.copy()
    f0 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    k5 = np.empty(n)
    k6 = np.empty(n)
    f_new = np.empty(n)
    yt = np.empty(n)
    y_new = np.empty(n)
    e = np.empty(n)
    q1 = np.empty(n)
    q2 = np.empty(n)
    q3 = np.empty(n)
    J = np.zeros((n, n))
    M = np.empty((n, n))
    piv = np.zeros(n, dtype=np.int64)
    ft = np.zeros(n)
    yp = np.empty(n)
    fp = np.empty(n)
    v = np.empty(n)
    w = np.empty(n)
    live = np.ones(n, dtype=np.bool_)
    all_live = np.ones(n, dtype=np.bool_)
    aux = np.empty(N_AUX)
    steps = 0
    rejected = 0
    n_rhs = 0
    n_out_rhs = 0
    n_jac = 0
    n_rodas = 0
    switches = 0
    status = STATUS_OK
    h = h_init
    h_min = 1e-14
    stiff = mode == MODE_RODAS4
    jac_ok = False
    frozen_known = False
    stiff_count = 0
    nonstiff_count = 0
    rho = 0.0
    switching = mode == MODE_AUTO or mode == MODE_MODAL
    modal = mode == MODE_MODAL
    h_osc = math.inf  # MODE_MODAL: the step cap of the lightly damped modes
    have_ref = False
    J_ref = np.zeros((n, n))
    refuse_until = 0
    since_eig = 0
    dp_since_eig = MODAL_RETRY  # the first accepted DOPRI5 step is analysed
    n_eig = 0
    # step-size controller memory: DOPRI5 PI controller, Gustafsson's for RODAS4
    dp_err_old = 1e-4
    beta = 0.04
    alpha = 0.2 - 0.75 * beta
    r4_err_old = 1e-2
    r4_h_old = 0.0
    r4_first = True
    r4_rejected = False
    i_stop = 0
    n_stops = stops.size
    kb = start  # index of the current sample instant
    t = start * base
    i_out = 0
    if memory[0] == 0.0:  # a new run
        if due(0, schedule, tick) > 0:
            sample_update(0.0, y, held, P, T, tick)
    else:  # carried over from the call that ended at t
        h = memory[0]
        stiff = memory[1] != 0.0
        frozen_known = memory[2] != 0.0
        stiff_count = int(memory[3])
        nonstiff_count = int(memory[4])
        dp_err_old = memory[5]
        r4_err_old = memory[6]
        r4_h_old = memory[7]
        r4_first = memory[8] != 0.0
        r4_rejected = memory[9] != 0.0
        h_osc = memory[10]
        have_ref = memory[11] != 0.0
        refuse_until = int(memory[12])
        dp_since_eig = int(memory[13])
        for i in range(n):
            live[i] = memory[MEMORY_SCALARS + i] != 0.0
            for j in range(n):
                J_ref[i, j] = memory[MEMORY_SCALARS + n + i * n + j]
    # the derivative at t: what the previous call's last step (or event) left, recomputed
    rhs(t, y, held, P, T, f0, aux)
    n_rhs += 1
    t_out[0] = t
    y_out[0, :] = y
    if want_aux:
        aux_out[0, :] = aux
    i_out = 1
    while t < t_end and status == STATUS_OK:
        # ---- the next event: sample instant, profile breakpoint, output point (fixed), end
        t_ev = t_end
        is_sample = False
        kb_next = next_instant(kb, schedule)  # the schedule's next instant (-1: none)
        if kb_next >= 0 and kb_next * base <= t_ev:
            t_ev = kb_next * base
            is_sample = True
        while i_stop < n_stops and stops[i_stop] <= t + 1e-12 * max(1.0, t):
            i_stop += 1
        is_stop = False
        if i_stop < n_stops and stops[i_stop] < t_ev - 1e-12 * max(1.0, t_ev):
            t_ev = stops[i_stop]
            is_sample = False
            is_stop = True
        if adaptive == 0 and i_out < n_out:
            t_grid = ((o0 + i_out) * out_every) * base
            if t_grid < t_ev - 1e-12 * max(1.0, t_ev):
                t_ev = t_grid
                is_sample = False
                is_stop = False
        # ---- steps up to t_ev
        while t < t_ev and status == STATUS_OK:
            if stiff and not jac_ok:
                calls = _r4_fd_jacobian(t, y, f0, held, P, T, atol, J,
                                        ft, yp, fp, aux, live if frozen_known else all_live,
                                        S, colour)
                if calls < 0:  # a state taken as frozen moved: difference every column
                    n_rhs -= calls
                    calls = _r4_fd_jacobian(t, y, f0, held, P, T, atol,
                                            J, ft, yp, fp, aux, all_live, S, colour)
                    frozen_known = False
                n_rhs += calls
                n_jac += 1
                if not frozen_known:
                    _r4_frozen_states(J, f0, live)
                    frozen_known = True
                jac_ok = True
                if switching:
                    rho = _r4_spectral_radius(J, atol, v, w, POWER_ITERATIONS)
                since_eig += 1
                if modal and (not have_ref or (since_eig >= MODAL_EVERY and
                                               modal_jacobian_moved(J, J_ref, MODAL_REFRESH))):
                    since_eig = 0
                    h_osc = modal_step_cap(J, live, MODAL_ZETA_LIGHT, MODAL_H_LAMBDA)
                    n_eig += 1
                    have_ref = True
                    for i in range(n):
                        for j in range(n):
                            J_ref[i, j] = J[i, j]
            last = False
            h_try = min(h, h_max)
            if modal:  # both methods: DOPRI5 amplifies a mode at 1 < h|λ| < 3.3
                h_try = min(h_try, h_osc)
            if t + h_try >= t_ev - 1e-12 * max(1.0, t_ev):
                h_try = t_ev - t
                last = True
            while True:
                t_new = t_ev if last else t + h_try
                if stiff:
                    calls = _r4_rodas4_step(t, h_try, y, f0, J, ft, held, P, T, M, piv, k2, k3,
                                            k4, k5, k6, e, yt, fp,
                                            y_new, aux, live)
                    if calls == -2:
                        # a frozen state moved: retry with the full Jacobian
                        n_rhs += 5
                        frozen_known = False
                        for i in range(n):
                            live[i] = True
                        calls = _r4_fd_jacobian(t, y, f0, held, P, T,
                                                atol, J, ft, yp, fp, aux, all_live, S, colour)
                        n_rhs += calls
                        n_jac += 1
                        continue
                    steps += 1
                    n_rodas += 1
                    if calls < 0:
                        err = 1e10  # singular matrix: shrink the step
                    else:
                        n_rhs += calls
                        err = _error_norm(e, y, y_new, rtol, atol, rel_mask)
                else:
                    _dp5_step(t, h_try, y, f0, held, P, T, k2, k3, k4,
                              k5, k6, f_new, yt, y_new, aux, t_new)
                    n_rhs += 6
                    steps += 1
                    _dp5_error(h_try, f0, k2, k3, k4, k5, k6, f_new, e)
                    err = _error_norm(e, y, y_new, rtol, atol, rel_mask)
                if adaptive == 0 or err <= 1.0:
                    break
                rejected += 1
                if stiff:
                    fac = max(1.0 / 6.0, min(5.0, err ** 0.25 / 0.9))
                    h_try /= fac
                    r4_rejected = True
                else:
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
            # ---- accepted: dense-output data of [t, t_new]
            h_done = t_new - t
            if stiff:
                rhs(t_new, y_new, held, P, T, f_new, aux)
                n_rhs += 1
                _r4_rodas4_dense(k2, k3, k4, k5, k6, q1, q2)
            else:
                for i in range(n):
                    ydiff = y_new[i] - y[i]
                    bspl = h_try * f0[i] - ydiff
                    q1[i] = ydiff
                    q2[i] = bspl
                    q3[i] = ydiff - h_try * f_new[i] - bspl
                _dp5_dense(h_try, f0, k2, k3, k4, k5, k6, f_new, e)
            # outputs strictly inside the step (an output at t_new that is an event time is
            # written after the event below)
            while i_out < n_out:
                t_grid = ((o0 + i_out) * out_every) * base
                if t_grid > t_new or (last and t_grid >= t_new - 1e-9 * base):
                    break
                th = (t_grid - t) / h_done
                th1 = 1.0 - th
                for i in range(n):
                    if stiff:
                        yp[i] = th1 * y[i] + th * (y_new[i] + th1 * (q1[i] + th * q2[i]))
                    else:
                        yp[i] = y[i] + th * (q1[i] + th1 * (q2[i] + th * (q3[i] + th1 * e[i])))
                t_out[i_out] = t_grid
                y_out[i_out, :] = yp
                if want_aux:
                    rhs(t_grid, yp, held, P, T, fp, aux)
                    n_out_rhs += 1
                    aux_out[i_out, :] = aux
                i_out += 1
            # ---- stiffness detection and switching
            used_rodas = stiff
            if switching:
                if stiff:
                    if rho * h_done < NONSTIFF_HRHO:
                        nonstiff_count += 1
                        if nonstiff_count >= NONSTIFF_STEPS:
                            stiff = False
                            switches += 1
                            stiff_count = 0
                            nonstiff_count = 0
                            dp_err_old = 1e-4
                    else:
                        nonstiff_count = 0
                else:
                    if modal:
                        dp_since_eig += 1
                    if modal and dp_since_eig >= MODAL_RETRY:
                        # DOPRI5 too: its step on a lightly damped mode is capped as well
                        dp_since_eig = 0
                        calls = _r4_fd_jacobian(t_new, y_new, f_new, held, P, T, atol, J, ft,
                                                yp, fp, aux, all_live, S, colour)
                        n_rhs += calls
                        n_jac += 1
                        h_osc = modal_step_cap(J, all_live, MODAL_ZETA_LIGHT, MODAL_H_LAMBDA)
                        n_eig += 1
                        have_ref = True
                        for i in range(n):
                            for j in range(n):
                                J_ref[i, j] = J[i, j]
                    num = 0.0
                    den = 0.0
                    for i in range(n):
                        num += (f_new[i] - k6[i]) ** 2
                        den += (y_new[i] - yt[i]) ** 2
                    if steps < refuse_until:
                        pass  # MODE_MODAL: a switch was refused recently
                    elif den > 0.0 and h_done * math.sqrt(num / den) > STIFF_HLAMBDA:
                        nonstiff_count = 0
                        stiff_count += 1
                        go = stiff_count >= STIFF_STEPS
                        if go and modal:
                            # would RODAS4, capped on the lightly damped modes, step further?
                            calls = _r4_fd_jacobian(t_new, y_new, f_new, held, P, T, atol,
                                                    J, ft, yp, fp, aux,
                                                    all_live, S, colour)
                            n_rhs += calls
                            n_jac += 1
                            h_osc = modal_step_cap(J, all_live, MODAL_ZETA_LIGHT,
                                                   MODAL_H_LAMBDA)
                            n_eig += 1
                            have_ref = True
                            for i in range(n):
                                for j in range(n):
                                    J_ref[i, j] = J[i, j]
                            if h_osc < MODAL_SWITCH_GAIN * h_done:
                                go = False
                                stiff_count = 0
                                refuse_until = steps + MODAL_RETRY
                        if go:
                            stiff = True
                            switches += 1
                            stiff_count = 0
                            r4_first = True
                    else:
                        nonstiff_count += 1
                        if nonstiff_count >= 6:
                            stiff_count = 0
            # ---- step-size control for the next step
            if adaptive == 1:
                if used_rodas:
                    fac = 0.2 if err == 0.0 else max(1.0 / 6.0, min(5.0, err ** 0.25 / 0.9))
                    if not r4_first and err > 0.0:
                        facpred = (r4_h_old / h_try) * (err * err / r4_err_old) ** 0.25 / 0.9
                        fac = max(fac, max(1.0 / 6.0, min(5.0, facpred)))
                    h_new = h_try / fac
                    if r4_rejected:
                        h_new = min(h_new, h_try)
                    r4_first = False
                    r4_h_old = h_try
                    r4_err_old = max(1e-2, err)
                    r4_rejected = False
                else:  # DOPRI5: the explicit steps' controller (feeddrive.solvers.steps)
                    fac = _pi_factor(err, dp_err_old, alpha, beta)
                    if err != 0.0:
                        dp_err_old = max(err, 1e-4)
                    h_new = h_try * fac
                if not last or h_new < h:
                    h = min(h_new, h_max)
            for i in range(n):
                y[i] = y_new[i]
                f0[i] = f_new[i]
            t = t_new
            if memory.shape[0] > MEMORY_SCALARS + n + n * n + 1:  # live time, stop (new_memory)
                memory[memory.shape[0] - 1] = t
                if memory[memory.shape[0] - 2] != 0.0:
                    status = STATUS_STOPPED
                    break
            jac_ok = False
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
                if i_out < n_out:
                    t_out[i_out] = t
                    y_out[i_out, :] = y
                    if want_aux:
                        rhs(t, y, held, P, T, fp, aux)
                        n_out_rhs += 1
                        aux_out[i_out, :] = aux
                    i_out += 1
                break
        if status != STATUS_OK:
            break
        # ---- at the event t_ev
        if is_sample:
            kb = kb_next
            due(kb, schedule, tick)
            sample_update(t, y, held, P, T, tick)
            rhs(t, y, held, P, T, f0, aux)
            n_rhs += 1
        if is_stop:
            i_stop += 1
        while i_out < n_out:
            t_grid = ((o0 + i_out) * out_every) * base
            if abs(t_grid - t) > 1e-9 * base:
                break
            t_out[i_out] = t_grid
            y_out[i_out, :] = y
            if want_aux:
                rhs(t, y, held, P, T, fp, aux)
                n_out_rhs += 1
                aux_out[i_out, :] = aux
            i_out += 1
    memory[0] = h
    memory[1] = 1.0 if stiff else 0.0
    memory[2] = 1.0 if frozen_known else 0.0
    memory[3] = stiff_count
    memory[4] = nonstiff_count
    memory[5] = dp_err_old
    memory[6] = r4_err_old
    memory[7] = r4_h_old
    memory[8] = 1.0 if r4_first else 0.0
    memory[9] = 1.0 if r4_rejected else 0.0
    memory[10] = h_osc
    memory[11] = 1.0 if have_ref else 0.0
    memory[12] = refuse_until
    memory[13] = dp_since_eig
    for i in range(n):
        memory[MEMORY_SCALARS + i] = 1.0 if live[i] else 0.0
        for j in range(n):
            memory[MEMORY_SCALARS + n + i * n + j] = J_ref[i, j]
    stats = np.array([float(status), float(steps), float(rejected), float(n_rhs + n_out_rhs),
                      t, float(n_jac), float(n_rodas), float(switches), float(n_out_rhs),
                      float(n_eig)])
    return (t_out[:i_out], y_out[:i_out], aux_out[:min(i_out, aux_out.shape[0])], stats, held)


def template_sources() -> list[str]:
    """Text placed in each generated model module: the switching driver ``integrate_dense``
    (its steps are those of :mod:`feeddrive.solvers.steps`, its Jacobian kernels those of
    :mod:`feeddrive.solvers.rodas4`, placed beside it).  numba compiles a function at its
    first call, so a model run only with ``dopri5`` never compiles this one."""
    src = steps.inline_steps(inspect.getsource(integrate_template)).replace(
        "def integrate_template(", "def integrate_dense(", 1)
    return [f"from feeddrive.solvers.switching import ({', '.join(CONSTANTS)})",
            "from feeddrive.solvers.schedule import due, next_instant",
            "from feeddrive.solvers.modes import step_cap as modal_step_cap, "
            "jacobian_moved as modal_jacobian_moved, ZETA_LIGHT as MODAL_ZETA_LIGHT, "
            "H_LAMBDA as MODAL_H_LAMBDA, REFRESH as MODAL_REFRESH",
            "@kernel\n" + src]
