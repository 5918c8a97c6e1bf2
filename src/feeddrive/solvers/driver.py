"""The one driver: step-size controller, event schedule and output handling, written once.

:func:`driver_template` is the only integrator loop of the package.  It is written in the
restricted Python of the kernels and *specialised* for each use (:data:`USES`) by
:func:`feeddrive.solvers.driver_text.specialise`: the use's constant flags are folded into its
text (``LAND``, ``DENSE``, ``COMM``; ``mode`` and ``adaptive`` where the use fixes them), the
branches they make unreachable are dropped, and the locals left with one constant value are
folded too, so each use compiles only its own code:

* ``integrate`` (:mod:`feeddrive.solvers.dopri5`, the ``dopri5`` method; ``LAND``): DOPRI5 that
  lands on every breakpoint of the output grid (each breakpoint a step end, outputs there, no
  interpolation), steps capped at ``h_max``, the step-size memory of the v1 engine;
* ``integrate_dense`` (:mod:`feeddrive.solvers.switching`, ``modal``/``auto``/``rodas4``/
  ``dopri5-dense``; ``DENSE``): steps not cut by the output grid, outputs interpolated from
  the step's continuous extension, profile breakpoints as events, DOPRI5 ⇄ RODAS4 switching;
* ``advance`` (:mod:`feeddrive.fmu.solver`, the FMU; ``COMM``): explicit DOPRI5 to a
  communication point ``t_end`` from an arbitrary ``t``, the sample grid's origin ``t0``, the
  caller's work space, no allocation — the text the C translator
  (:mod:`feeddrive.backends.c_translate`) reads, free of the RODAS4 and eigen-analysis code
  that lies outside its subset.

Common to all: the sample instants of the schedule (:mod:`feeddrive.solvers.schedule`) are
exact step ends where ``sample_update`` runs and the derivative is re-evaluated (the
zero-order-hold outputs jump there; the "declare your discontinuities" lesson of diffrax,
python-control issue #933); the explicit step is the one of :mod:`feeddrive.solvers.steps`
for :data:`feeddrive.solvers.tableaux.DOPRI5` (written into the numba text by
:func:`feeddrive.solvers.steps.inline_steps`), the error norm and Hairer's PI controller are
the steps module's (Hairer, Nørsett & Wanner, Solving ODEs I, Sect. II.4); divergence bounds,
the stop request and the step limit end a run with a status.

The template calls its pieces, each a kernel of its own of at most 150 lines (:data:`PIECES`,
below the template: the Jacobian and the modal method's eigen-analysis, the stiffness estimate
and the method switching, the step-size controller, the dense output and the output samples,
the bound checks, the dense driver's next event, the memory it carries between calls and the
embedded global-error estimate), as diffrax separates controller, solver and driver.  The C
build calls them; numba inlines them (``inline="always"``) into drivers compiled without
reference counting (:data:`NUMBA_NRT_FREE`), a long call's arguments a tuple
(:func:`feeddrive.solvers.driver_text.numba_text`).

This module is the numerical driver alone: the template, its pieces and the drivers' calling
convention (:data:`USES`; the work arrays their callers make, :func:`step_space` and
:func:`work_space`).  The transforms that make each build's text from it (the specialisation,
numba's text, the outputs lowered into the caller's arrays, the pieces' texts) are
:mod:`feeddrive.solvers.driver_text`'s, which reads this module by name, never the reverse.

Each specialisation is bit-identical to the separate driver it replaced (the v1 regression,
the long-run chunking tests and the FMU's C-versus-numba test pin it).  The flags keep the
few places where the three historically differ: ``LAND``'s step is cut only when ``h`` reaches
the breakpoint (no 1e-12 tolerance), its interval is done 1e-15 short of the breakpoint, and its
PI memory takes every error (also 0).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .events import first_crossing as switch_crossing
from .global_error import INTERVAL as GE_INTERVAL
from .global_error import REFRESH_STEPS as GE_REFRESH
from .global_error import advance as ge_advance
from .global_error import exponential as ge_exponential
from .global_error import keep_local as ge_keep
from .modes import H_LAMBDA as MODAL_H_LAMBDA
from .modes import REFRESH as MODAL_REFRESH
from .modes import ZETA_LIGHT as MODAL_ZETA_LIGHT
from .modes import jacobian_moved as modal_jacobian_moved
from .modes import step_cap as modal_step_cap
from .placeholders import N_AUX, rhs, sample_update
from .schedule import due, next_instant
from .tableaux import RODAS4, RODAS5P

STATUS_OK = 0
STATUS_MAX_STEPS = 1
STATUS_STEP_UNDERFLOW = 2
STATUS_NON_FINITE = 3
STATUS_STOPPED = 4  # another thread asked the running call to stop (the memory's stop slot)
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
STATUS_NAMES = ("STATUS_OK", "STATUS_MAX_STEPS", "STATUS_STEP_UNDERFLOW", "STATUS_NON_FINITE",
                "STATUS_STOPPED", "STATUS_DIVERGED")

MODE_DOPRI5, MODE_RODAS4, MODE_AUTO, MODE_MODAL = 0, 1, 2, 3
# added to MODE_RODAS4, MODE_AUTO or MODE_MODAL: the Rosenbrock steps are RODAS5P's
# (feeddrive.solvers.tableaux.RODAS5P, order 5(4), dense output of order 4) instead of
# RODAS4's (SolverOptions.rosenbrock)
ROSENBROCK_5 = 4

# Switching thresholds of the dense driver (measured on the benchmark scenarios,
# benchmarks/README.md; feeddrive.solvers.switching)
STIFF_HLAMBDA = 3.25  # DOPRI5's stability boundary on the negative real axis is ≈ 3.3
# that boundary (|R(z)| = 1 at z ≈ -3.31; dopri5.f's stiffness test, Hairer & Wanner, Solving
# ODEs II, Sect. IV.2): the ``dopri5`` method's steps at accuracy < 1 are also capped at a
# share of DOPRI5_STABILITY / ρ (SolverOptions.stability_share)
DOPRI5_STABILITY = 3.3
STIFF_STEPS = 15  # stiff verdicts (reset after 6 non-stiff steps in a row), dopri5.f
NONSTIFF_HRHO = 3.0
NONSTIFF_STEPS = 5
POWER_ITERATIONS = 12
# MODE_MODAL: RODAS4 steps capped on lightly damped modes
# switch to RODAS4 only if the capped step is ≥ this × DOPRI5's, and back when it is not
MODAL_SWITCH_GAIN = 2.0
# what a RODAS4 step costs in DOPRI5 steps (its Jacobian share, LU and six solves against six
# cheap right-hand sides; measured 4.9-6.9 in the C build, 3.8-4.8 in numba's,
# benchmarks/bench_switch_cost.py): a Rosenbrock stretch returns to DOPRI5 when its steps are
# not this much longer than the step DOPRI5 took when it handed over, the method-switch test
# of LSODA (L. Petzold, SIAM J. Sci. Stat. Comput. 4 (1983) 136-148: each method's step
# weighed by its cost); the switch to RODAS4 is then refused for MODAL_RETRY steps
RODAS4_COST = 5.0
# the same for a RODAS5P step: 7 stage right-hand sides and 8 solves against RODAS4's 5 and 6
# (measured: benchmarks/README.md, "RODAS5P in the engine")
RODAS5P_COST = 6.5
# the Rosenbrock step-size controller's exponents 1/(q + 1), q the embedded order (rodas.f:
# 0.25 for RODAS4), and the right-hand sides of a step (its stages but the caller's f0)
R4_EXPONENT = RODAS4.step_exponent
R5_EXPONENT = RODAS5P.step_exponent
R4_STAGES = RODAS4.stages
R5_STAGES = RODAS5P.stages
# DOPRI5 steps before a refused switch is considered again, and between two eigen-analyses
# of DOPRI5 steps (their cap too: DOPRI5's |R(iy)| > 1 for 1 < y < 3.3)
MODAL_RETRY = 500
# RODAS4 steps between two eigen-analyses at least (the cap of the last one holds meanwhile)
MODAL_EVERY = 10

# The dense driver's memory: h, method, frozen states known, stiff and non-stiff counts,
# DOPRI5 error memory, RODAS4 error, step and first/rejected flags, the modal step cap,
# whether a reference Jacobian is kept, the step count until which a switch is refused and the
# DOPRI5 steps since the last eigen-analysis, the spectral radius of the switch back to
# DOPRI5 (MODE_MODAL: the reference Jacobian's), the Jacobians since the last eigen-analysis
# and whether the last moved test found the Jacobian quiet; then one live flag per state and
# the modal reference Jacobian (n × n), then (with the embedded global-error estimate,
# feeddrive.solvers.global_error) the propagated error and its largest magnitude per state,
# then the stop request and the live time
MEMORY_SCALARS = 18

# The specialisation flags: exactly one of LAND, DENSE, COMM is true in a specialisation
# (the template's own values only make this module importable)
LAND = False
DENSE = True
COMM = False


# error_model="numpy" (feeddrive._jit): a division by zero gives inf/NaN (caught below as a
# rejected step or STATUS_NON_FINITE) instead of Python's ZeroDivisionError check on every
# division of the inlined right-hand side; bit-identical results, about 25 % less time.
def driver_template(y0: np.ndarray, t_end: float, out_every: int, base: float,
                    schedule: np.ndarray, P: np.ndarray, T: np.ndarray, rtol: float,
                    atol: np.ndarray, rel_mask: np.ndarray, h_init: float, h_max: float,
                    stability_share: float, adaptive: int, max_steps: int, mode: int,
                    stops: np.ndarray,
                    want_aux: bool, S: np.ndarray, colour: np.ndarray, start: int,
                    held: np.ndarray, memory: np.ndarray, bound: np.ndarray,
                    t_buf: np.ndarray, y_buf: np.ndarray, aux_buf: np.ndarray, t: float,
                    t0: float, n: int, y: np.ndarray, held_prev: np.ndarray,
                    tick: np.ndarray, redo: int, f0: np.ndarray, k2: np.ndarray,
                    k3: np.ndarray, k4: np.ndarray, k5: np.ndarray, k6: np.ndarray,
                    f_new: np.ndarray, yt: np.ndarray, y_new: np.ndarray, e: np.ndarray,
                    aux: np.ndarray, switch_rows: np.ndarray, q1: np.ndarray,
                    q2: np.ndarray, q3: np.ndarray, u6: np.ndarray, u7: np.ndarray,
                    ft: np.ndarray, yp: np.ndarray,
                    fp: np.ndarray, v: np.ndarray, w: np.ndarray, J: np.ndarray,
                    M: np.ndarray, J_ref: np.ndarray, piv: np.ndarray, live: np.ndarray,
                    all_live: np.ndarray, ge_J: np.ndarray, ge_Phi: np.ndarray,
                    ge_A: np.ndarray, ge_B: np.ndarray, ge_w: np.ndarray, ge_d: np.ndarray,
                    ge_aux: np.ndarray) -> Any:
    """The driver of every integration (module docstring); compiled only as one of its
    specialisations (:func:`specialise`), whose signatures take a subset of these parameters.

    Parameters
    ----------
    y0 : numpy.ndarray
        State at t = start·base [SI, per state] (not ``COMM``).
    t_end : float
        End of the run; with ``COMM`` the communication point [s].
    out_every : int
        Output stride in breakpoints (not ``COMM``).
    base : float
        Breakpoint spacing, the sample grid's unit [s].
    schedule : numpy.ndarray of int
        Breakpoints between two instants of each clock; 0 = continuous
        (:mod:`feeddrive.solvers.schedule`).
    P : numpy.ndarray
        Packed parameter vector [SI, per slot].
    T : numpy.ndarray
        Packed tables [SI].
    rtol : float
        Relative tolerance [-].
    atol : numpy.ndarray
        Absolute tolerance per state [SI, per state].
    rel_mask : numpy.ndarray
        1 where the relative tolerance applies [-].
    h_init : float
        First step size [s] (``DENSE``).
    h_max : float
        Largest step [s].
    stability_share : float
        ``LAND``: below 1, each step is also capped at this share of DOPRI5's stability bound,
        :data:`DOPRI5_STABILITY` / ρ with ρ the stiffness estimate of the step before
        (:func:`weighted_stiffness_estimate`): where the steps are bound by stability, not by the
        tolerances, the error then still falls with the accuracy asked for
        (:attr:`feeddrive.engine.options.SolverOptions.stability_share`) [-].
    adaptive : int
        1 for error-controlled steps, 0 for a fixed step (used to verify the order).
    max_steps : int
        Step limit of the call.
    mode : int
        ``MODE_DOPRI5``, ``MODE_RODAS4``, ``MODE_AUTO`` or ``MODE_MODAL`` (``DENSE``; the
        others are ``MODE_DOPRI5``); ``ROSENBROCK_5`` added: RODAS5P's Rosenbrock steps.
    stops : numpy.ndarray
        Sorted profile breakpoints, exact step ends [s] (``DENSE``).
    want_aux : bool
        Evaluate the auxiliary signals at the outputs (``DENSE``).
    S : numpy.ndarray of int
        The Jacobian's sparsity pattern, (n, n + 1) (``DENSE``).
    colour : numpy.ndarray of int
        Its column groups (``DENSE``).
    start : int
        Breakpoint index the call starts from (not ``COMM``).
    held : numpy.ndarray
        Held controller values, read and left updated [SI, per value].
    memory : numpy.ndarray
        Driver memory carried between calls, read and left updated (the layout of each use:
        :func:`feeddrive.solvers.dopri5.new_memory`,
        :func:`feeddrive.solvers.switching.new_memory`, :func:`feeddrive.fmu.solver.new_memory`)
        [mixed].
    bound : numpy.ndarray
        Largest |state| per state before the run stops as diverged [SI, per state] (not
        ``COMM``).
    t_buf, y_buf, aux_buf : numpy.ndarray
        Output buffers (``DENSE``), one row per output of the call, chosen by the caller
        (:func:`feeddrive.solvers.switching.integrate`: the caller's own, reused from call
        to call, or new ones); the outputs are returned as views of their first rows [s; SI].
    t : float
        Start time of the call [s] (``COMM``).
    t0 : float
        Origin of the sample grid [s] (``COMM``).
    n : int
        Number of states (``COMM``).
    y : numpy.ndarray
        States, advanced in place [SI, per state] (``COMM``).
    held_prev : numpy.ndarray
        Held values before the last update, for ``redo`` [SI, per value] (``COMM``).
    tick : numpy.ndarray of int
        Work space, one per clock (made by the caller: :func:`step_space`).
    redo : int
        1 when the inputs changed since the last call (``COMM``).
    f0, k2, k3, k4, k5, k6, f_new, yt, y_new, e : numpy.ndarray
        Work space, length ``n`` [SI per second, per state] (:func:`step_space`).
    aux : numpy.ndarray
        The auxiliary signals at the end [SI, per signal] (``COMM``; else work space).
    switch_rows : numpy.ndarray
        (m, n) switching surfaces W·y whose zero crossings are located and made step ends
        (:mod:`feeddrive.solvers.events`); (0, n) for none [state units → m/s] (``DENSE``).
    q1, q2, q3, u6, u7, ft, yp, fp, v, w, J, M, J_ref, piv, live, all_live : numpy.ndarray
        The dense driver's work space (``DENSE``; u6, u7: RODAS5P's sixth and seventh
        increments), made by its caller (:func:`work_space`: a piece cannot allocate in the C
        subset, and the driver is shorter without) [mixed].
    ge_J, ge_Phi, ge_A, ge_B, ge_w, ge_d, ge_aux : numpy.ndarray
        The embedded global-error estimate's work space (``DENSE``; :func:`work_space`)
        [mixed].

    Returns
    -------
    object
        ``COMM``: the status; otherwise (t_out, y_out, aux_out, stats, held): output times [s],
        states and auxiliary signals there [SI], the statistics (status, steps, rejected,
        right-hand-side evaluations, time reached [s]; ``DENSE`` adds the entries of
        :data:`feeddrive.solvers.switching.STAT_NAMES`) and the held values.

    References
    ----------
    .. [1] J. R. Dormand, P. J. Prince, "A family of embedded Runge-Kutta formulae", J. Comput.
       Appl. Math. 6 (1980) 19–26.
    .. [2] E. Hairer, S. P. Nørsett, G. Wanner, Solving Ordinary Differential Equations I,
       2nd ed., Springer, 1993, Sect. II.4–II.6.
    .. [3] E. Hairer, G. Wanner, Solving Ordinary Differential Equations II, 2nd ed., Springer,
       1996, Sect. IV.7 (RODAS4).
    """
    # ---- work space and outputs (COMM: the caller's)
    if not COMM:
        n = y0.size
        n_break = int(round(t_end / base))
        if DENSE:
            t_end = n_break * base
            o0 = start // out_every  # index of the first output on the whole run's grid
            n_out = (n_break - start) // out_every + 1
        else:
            n_out = n_break // out_every - (start + out_every - 1) // out_every + 1
        t = start * base
        if DENSE:  # the caller's buffers, one row per output (switching.integrate)
            t_out = t_buf
            y_out = y_buf
            aux_out = aux_buf
        else:  # uninitialised: every row returned is written
            t_out = np.empty(n_out)
            y_out = np.empty((n_out, n))
            aux_out = np.empty((n_out if want_aux else 0, N_AUX))
        y = y0.copy()
    if DENSE:  # the work space is the caller's (step_space, work_space)
        # the statistics: output rhs calls, Jacobians, RODAS4 steps, method switches,
        # eigen-analyses, spectral-radius estimates (power iterations), surfaces crossed
        n_out_rhs = n_jac = n_rodas = switches = n_eig = n_rho = n_switch = 0
        sw_last = -1  # the surface the last accepted step landed on (-1: none)
        sw_next = -1
        # the embedded global-error estimate (feeddrive.solvers.global_error), when the
        # memory has its slots: E, the largest |E|, the local errors of the interval
        ge_at = MEMORY_SCALARS + n + n * n
        ge = memory.shape[0] == ge_at + 3 * n + 2
        ge_since = GE_REFRESH  # accepted steps since the propagator was formed (none yet)
    steps = 0
    rejected = 0
    n_rhs = 0
    status = STATUS_OK
    h_min = 1e-14
    # the method and the switching state (DENSE; the other uses are DOPRI5 throughout)
    r5 = mode >= ROSENBROCK_5  # RODAS5P's Rosenbrock steps, else RODAS4's
    r_cost = RODAS5P_COST if r5 else RODAS4_COST
    stiff = mode % ROSENBROCK_5 == MODE_RODAS4
    jac_ok = False
    jac_age = 0
    quiet = False
    h_dp = 0.0  # DOPRI5's step when it last handed over to RODAS4 [s]
    stale = False
    frozen_known = False
    stiff_count = 0
    nonstiff_count = 0
    rho = 0.0
    switching = mode % ROSENBROCK_5 == MODE_AUTO or mode % ROSENBROCK_5 == MODE_MODAL
    modal = mode % ROSENBROCK_5 == MODE_MODAL
    h_osc = math.inf  # MODE_MODAL: the step cap of the lightly damped modes
    have_ref = False
    refuse_until = 0
    since_eig = 0
    dp_since_eig = MODAL_RETRY  # the first accepted DOPRI5 step is analysed
    # step-size controller memory: DOPRI5's PI controller, Gustafsson's for RODAS4
    err_old = 1e-4
    beta = 0.04
    alpha = 0.2 - 0.75 * beta
    r4_err_old = 1e-2
    r4_h_old = 0.0
    r4_first = True
    r4_rejected = False
    i_stop = 0
    i_out = 0
    # ---- the start: the driver's state carried over, the update due at the first instant
    if COMM:
        kb = int(memory[2])  # the last sample instant applied (literal indices: see fmu.solver)
        if redo == 1 and memory[3] > 0.5:  # redo that instant's update with the new inputs
            for i in range(held.size):
                held[i] = held_prev[i]
            due(kb, schedule, tick)
            sample_update(t, y, held, P, T, tick)
        h = memory[0]
        err_old = memory[1]
    elif LAND:
        kb = start
        h = memory[0]
        err_old = memory[1]
        # (a continued run applied the update at its first breakpoint in the previous call)
        if due(start, schedule, tick) > 0 and start == 0:
            sample_update(t, y, held, P, T, tick)
    else:
        kb = start  # index of the current sample instant
        h = h_init
        if memory[0] == 0.0:  # a new run
            if due(0, schedule, tick) > 0:
                sample_update(0.0, y, held, P, T, tick)
        else:  # carried over from the call that ended at t
            (h, stiff, frozen_known, stiff_count, nonstiff_count, err_old, r4_err_old, r4_h_old,
             r4_first, r4_rejected, h_osc, have_ref, refuse_until, dp_since_eig, rho,
             since_eig, quiet, h_dp) = memory_load(memory, live, J_ref)
    # the derivative at t (a continued LAND run with every loop continuous, nothing jumping at
    # a breakpoint: the previous call's last stage, evaluated at exactly the breakpoint, or a
    # hair off it when that step was not cut to it)
    rhs(t, y, held, P, T, f0, aux)
    n_rhs += 1
    if LAND and start > 0 and next_instant(0, schedule) < 0:
        for i in range(n):
            f0[i] = memory[2 + i]
    if COMM:
        memory[3] = 0.0  # MEM_AT_SAMPLE
    if DENSE or (LAND and start % out_every == 0 and i_out < n_out):
        i_out = output_row(t, y, aux, want_aux, t_out, y_out, aux_out, i_out)
    while (kb < n_break if LAND else t < t_end) and status == STATUS_OK:
        # ---- the next event: LAND the next breakpoint; else the schedule's next instant,
        # DENSE a profile breakpoint or (fixed step) an output point, the end
        if LAND:
            t = kb * base
            t_ev = (kb + 1) * base
            t_bp = t_ev  # the breakpoint; t_ev moves to a located reversal before it
        elif COMM:  # the schedule's next instant on the grid from t0 (as next_event's)
            t_ev = t_end
            is_sample = False
            kb_next = next_instant(kb, schedule)  # the schedule's next instant (-1: none)
            if kb_next >= 0:
                t_s = t0 + kb_next * base
                if t_s <= t_end + 1e-9 * base:  # an instant this close to the end is the end
                    is_sample = True
                    if t_s < t_end - 1e-9 * base:
                        t_ev = t_s
        else:
            t_ev, is_sample, is_stop, kb_next, i_stop = next_event(
                t, t_end, kb, schedule, base, stops, i_stop, adaptive, i_out, n_out, o0,
                out_every)
        # ---- steps up to t_ev
        while (t < t_ev - 1e-15 * t_ev if LAND else t < t_ev) and status == STATUS_OK:
            if stiff and not jac_ok:  # a fresh Jacobian, its analyses
                (calls, frozen_known, rho, h_osc, have_ref, since_eig, quiet, estimates,
                 analyses) = jacobian_update(t, y, f0, held, P, T, atol, J, ft, yp, fp, aux, live,
                                             all_live, frozen_known, S, colour, switching, modal,
                                             have_ref, since_eig, quiet, rho, h_osc, J_ref, v, w)
                n_rhs += calls
                n_jac += 1
                n_rho += estimates
                n_eig += analyses
                jac_ok = True
                jac_age = 0
            if LAND:  # cut only when the step reaches the breakpoint (v1)
                last = h >= t_ev - t
                h_try = t_ev - t if last else h
            elif COMM:  # as step_attempt's
                last = False
                h_try = min(h, h_max)
                if t + h_try >= t_ev - 1e-12 * max(1.0, abs(t_ev)):
                    h_try = t_ev - t
                    last = True
            if DENSE:  # the step chosen and tried with either method (step_attempt)
                (err, t_new, h_try, last, status, stale, r4_rejected, frozen_known, steps,
                 rejected, n_rhs, n_jac, n_rodas) = step_attempt(
                    stiff, r5, adaptive, t, t_ev, h, h_max, modal, h_osc, h_min, y, f0,
                    held, P, T, rtol, atol, rel_mask, J, ft, M, piv, k2, k3, k4, k5, k6, u6, u7,
                    f_new, e, yt, yp, fp, y_new, aux, live, all_live, S, colour, frozen_known,
                    r4_rejected,
                    jac_age, steps, max_steps, rejected, n_rhs, n_jac, n_rodas)
            else:
                err = 0.0
                t_new = t_ev
                while True:
                    t_new = t_ev if last else t + h_try
                    _dp5_step(t, h_try, y, f0, held, P, T, k2, k3, k4, k5, k6, f_new, yt,
                              y_new, aux, t_new)
                    n_rhs += 6
                    steps += 1
                    if adaptive == 0:
                        err = 0.0
                    else:
                        _dp5_error(h_try, f0, k2, k3, k4, k5, k6, f_new, e)
                        err = _error_norm(e, y, y_new, rtol, atol, rel_mask)
                    if adaptive == 0 or err <= 1.0:
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
            if stale:
                stale = False
                jac_ok = False
                h = h_try
                continue
            used_rodas = stiff
            if DENSE and ge:
                ge_keep(e, ge_d)  # the accepted step's local error (e is reused below)
            if LAND and switch_rows.shape[0] > 0:
                # a friction reversal inside the step (feeddrive.solvers.events): located on
                # the DOPRI5 step's continuous extension, the step thrown away and the
                # crossing made a step end, as in the dense driver; the outputs stay at the
                # breakpoints
                th_sw, k_sw = land_crossing(h_try, y, y_new, f0, k2, k3, k4, k5, k6, f_new, e,
                                            switch_rows)
                if th_sw > 0.0 and th_sw * (t_new - t) > 1e-12 * max(1.0, t):
                    if steps > max_steps:
                        status = STATUS_MAX_STEPS
                        break
                    t_ev = t + th_sw * (t_new - t)
                    continue
            if DENSE:
                # ---- accepted: dense-output data of [t, t_new]
                h_done = t_new - t
                if stiff:
                    rhs(t_new, y_new, held, P, T, f_new, aux)
                    n_rhs += 1
                dense_coefficients(stiff, r5, h_try, y, y_new, f0, k2, k3, k4, k5, k6, u6, u7,
                                   f_new, e, q1, q2, q3)
                if switch_rows.shape[0] > 0:
                    # a switching surface crossed inside the step (a friction site's sliding
                    # speed through zero: a kink of the right-hand side): the step is thrown
                    # away and the crossing, located on its continuous extension, becomes the
                    # event the next step lands on (feeddrive.solvers.events)
                    th_sw, k_sw = switch_crossing(switch_rows, y, y_new, q1, q2, q3, e, stiff)
                    # a crossing closer to t than the event resolution is left inside (a
                    # landing there would not advance t: the speed dithering about zero)
                    if th_sw > 0.0 and th_sw * h_done > 1e-12 * max(1.0, t):
                        if steps > max_steps:
                            status = STATUS_MAX_STEPS
                            break
                        t_ev = t + th_sw * h_done
                        is_sample = False
                        is_stop = False
                        if k_sw != sw_last:  # a crossing, not a second landing on it
                            n_switch += 1
                        sw_next = k_sw
                        continue
                    sw_last = sw_next
                    sw_next = -1
                # outputs strictly inside the step (an output at t_new that is an event time
                # is written after the event below)
                i_out, calls = outputs_inside(t, t_new, last, stiff, y, y_new, q1, q2, q3, e,
                                              yp, fp, held, P, T, aux, want_aux, t_out, y_out,
                                              aux_out, i_out, n_out, o0, out_every, base)
                n_out_rhs += calls
                # ---- stiffness detection and switching
                if switching:
                    (stiff, rho, h_osc, stiff_count, nonstiff_count, switches, err_old,
                     dp_since_eig, refuse_until, r4_first, have_ref, calls,
                     analyses, h_dp) = switch_method(stiff, modal, r_cost, rho, h_done, h_osc,
                                                     r4_h_old, r4_rejected, h_dp, stiff_count,
                                                     nonstiff_count, switches, err_old,
                                                     dp_since_eig,
                                               refuse_until, steps, r4_first, have_ref, t_new,
                                               y_new, f_new, k6, yt, held, P, T, atol, J, ft,
                                               yp, fp, aux, all_live, S, colour, J_ref, v, w)
                    n_rhs += calls
                    n_jac += analyses
                    n_rho += analyses
                    n_eig += analyses
            # ---- step-size control for the next step
            if adaptive == 1 and COMM:  # the FMU's: DOPRI5's PI controller, as step_size's
                fac = _pi_factor(err, err_old, alpha, beta)
                if err != 0.0:
                    err_old = max(err, 1e-4)
                h_new = h_try * fac
                if not last or h_new < h:
                    h = min(h_new, h_max)
            elif adaptive == 1:  # LAND: v1 took every error, also 0, into DOPRI5's memory
                h, err_old, r4_first, r4_h_old, r4_err_old, r4_rejected = step_size(
                    used_rodas, r5, err, h_try, h, h_max, last, err_old, alpha, beta,
                    r4_first, r4_h_old, r4_err_old, r4_rejected, LAND,
                    stability_share if LAND else 1.0,
                    f_new, k6, y, y_new, yt, rtol, atol, rel_mask)
                if DENSE and used_rodas and not stiff and h_dp > 0.0:
                    h = min(h, h_dp)  # back to DOPRI5: from the step it handed over with
            if DENSE and ge:  # the embedded global-error estimate carried over the step
                calls, jacobians, ge_since = error_estimate_step(
                    used_rodas, ge_since, t, t_new, y, f0, held, P, T, atol, J, ge_J, ft, yp, fp,
                    ge_aux, all_live, S, colour, ge_Phi, ge_A, ge_B, memory, ge_at, ge_w, ge_d)
                n_rhs += calls
                n_jac += jacobians
            for i in range(n):
                y[i] = y_new[i]
                f0[i] = f_new[i]
            t = t_new
            if LAND and t_ev < t_bp and t >= t_ev:  # on the reversal: on to the breakpoint
                t_ev = t_bp
            # the Jacobian is taken afresh at the next step, unless quiet (MODE_MODAL)
            jac_age += 1
            if not (quiet and used_rodas and stiff and jac_age < MODAL_EVERY):
                jac_ok = False
            if COMM:  # the FMU has no stop slot and no divergence bounds
                if steps > max_steps:
                    status = STATUS_MAX_STEPS
                    break
                check = STATUS_OK
                for i in range(n):
                    if not math.isfinite(y[i]):
                        check = STATUS_NON_FINITE
                if check == STATUS_NON_FINITE:
                    status = STATUS_NON_FINITE
                    break
            else:  # the stop request, the step limit, the state's bounds
                status = step_end_status(memory, 3 + n if LAND else MEMORY_SCALARS + n + n * n
                                         + 1, t, steps, max_steps, y, bound)
                if status == STATUS_DIVERGED and i_out < n_out:  # the last output
                    if DENSE and want_aux:  # (LAND's last rhs call was at (t, y))
                        rhs(t, y, held, P, T, fp, aux)
                        n_out_rhs += 1
                    i_out = output_row(t, y, aux, want_aux, t_out, y_out, aux_out, i_out)
                if status != STATUS_OK:
                    break
        if status != STATUS_OK:
            break
        jac_ok = False  # an event (a jump of the right-hand side): a fresh Jacobian after it
        # ---- at the event t_ev
        if LAND:
            kb += 1
            if due(kb, schedule, tick) > 0:
                sample_update(t_ev, y, held, P, T, tick)
                rhs(t_ev, y, held, P, T, f0, aux)
                n_rhs += 1
            if kb % out_every == 0 and i_out < n_out:
                i_out = output_row(t_ev, y, aux, want_aux, t_out, y_out, aux_out, i_out)
        else:
            if is_sample:
                kb = kb_next
                if COMM and t_ev == t_end:  # an instant on the communication point
                    for i in range(held.size):
                        held_prev[i] = held[i]
                    memory[3] = 1.0  # MEM_AT_SAMPLE
                due(kb, schedule, tick)
                sample_update(t, y, held, P, T, tick)
                rhs(t, y, held, P, T, f0, aux)
                n_rhs += 1
        if DENSE:
            if is_stop:
                i_stop += 1
            i_out, calls = outputs_at(t, y, fp, held, P, T, aux, want_aux, t_out, y_out,
                                      aux_out, i_out, n_out, o0, out_every, base)
            n_out_rhs += calls
    # ---- the driver's state for the next call, the statistics
    if COMM:
        memory[0] = h  # MEM_H
        memory[1] = err_old  # MEM_ERR
        memory[2] = kb  # MEM_KB
        memory[4] += steps  # MEM_STEPS
        memory[5] += rejected  # MEM_REJECTED
        memory[6] += n_rhs  # MEM_RHS
        return status
    if LAND:
        memory[0] = h
        memory[1] = err_old
        for i in range(n):
            memory[2 + i] = f0[i]
        stats = np.array([float(status), float(steps), float(rejected), float(n_rhs), t])
        return t_out[:i_out], y_out[:i_out], aux_out[:i_out], stats, held
    if DENSE:
        memory_save(memory, live, J_ref, h, stiff, frozen_known, stiff_count, nonstiff_count,
                    err_old, r4_err_old, r4_h_old, r4_first, r4_rejected, h_osc, have_ref,
                    refuse_until - steps, dp_since_eig, rho, since_eig, quiet, h_dp)
        stats = np.array([float(status), float(steps), float(rejected), float(n_rhs + n_out_rhs),
                          t, float(n_jac), float(n_rodas), float(switches), float(n_out_rhs),
                          float(n_eig), float(n_switch), float(n_rho)])
        return (t_out[:i_out], y_out[:i_out], aux_out[:min(i_out, aux_out.shape[0])], stats,
                held)
    return None


# ---------------------------------------------------------------- the driver's pieces
# Each a kernel of its own, called by driver_template, compiled beside it in both builds
# (numba inlines them, ``inline="always"``; the C translation calls them): the Jacobian and
# the modal method's eigen-analysis, the stiffness test, the step-size controller, the dense
# output and the output samples (issue 42 item 3: "a driver you can read").
def jacobian_fresh(t: float, y: np.ndarray, f0: np.ndarray, held: np.ndarray, P: np.ndarray,
                   T: np.ndarray, atol: np.ndarray, J: np.ndarray, ft: np.ndarray,
                   yp: np.ndarray, fp: np.ndarray, aux: np.ndarray, live: np.ndarray,
                   all_live: np.ndarray, frozen_known: bool, S: np.ndarray,
                   colour: np.ndarray) -> tuple[int, bool]:
    """The RODAS4 step's Jacobian at (t, y) into ``J``: the columns of the states not known
    to be frozen differenced (:func:`feeddrive.solvers.rodas4.fd_jacobian_template`), all of
    them when a state taken as frozen moved; the frozen states found afresh when unknown.

    Parameters
    ----------
    t : float
        Time [s].
    y, f0 : numpy.ndarray
        State and its derivative [SI; SI/s, per state].
    held, P, T : numpy.ndarray
        Held values, parameters, tables [SI].
    atol : numpy.ndarray
        Absolute tolerance per state [SI, per state].
    J : numpy.ndarray
        The Jacobian, written (n, n) [1/s in SI units].
    ft, yp, fp, aux : numpy.ndarray
        Work space [SI].
    live : numpy.ndarray of bool
        The states not frozen; written when ``frozen_known`` is false.
    all_live : numpy.ndarray of bool
        All true.
    frozen_known : bool
        Whether ``live`` holds the frozen states.
    S, colour : numpy.ndarray of int
        Sparsity pattern and column groups.

    Returns
    -------
    calls : int
        Right-hand-side evaluations made.
    frozen_known : bool
        True: ``live`` holds the frozen states.
    """
    calls = _r4_fd_jacobian(t, y, f0, held, P, T, atol, J, ft, yp, fp, aux,
                            live if frozen_known else all_live, S, colour)
    total = 0
    if calls < 0:  # a state taken as frozen moved: difference every column
        total -= calls
        calls = _r4_fd_jacobian(t, y, f0, held, P, T, atol, J, ft, yp, fp, aux, all_live, S,
                                colour)
        frozen_known = False
    total += calls
    if not frozen_known:
        _r4_frozen_states(J, f0, live)
        frozen_known = True
    return total, frozen_known


def jacobian_update(t: float, y: np.ndarray, f0: np.ndarray, held: np.ndarray, P: np.ndarray,
                    T: np.ndarray, atol: np.ndarray, J: np.ndarray, ft: np.ndarray,
                    yp: np.ndarray, fp: np.ndarray, aux: np.ndarray, live: np.ndarray,
                    all_live: np.ndarray, frozen_known: bool, S: np.ndarray,
                    colour: np.ndarray, switching: bool, modal: bool, have_ref: bool,
                    since_eig: int, quiet: bool, rho: float, h_osc: float, J_ref: np.ndarray,
                    v: np.ndarray, w: np.ndarray
                    ) -> tuple[int, bool, float, float, bool, int, bool, int, int]:
    """The Jacobian of a RODAS4 step taken afresh (:func:`jacobian_fresh`) and what the
    switching methods derive from it: ``MODE_AUTO`` its spectral radius; ``MODE_MODAL`` the
    moved test against the reference Jacobian (a Jacobian within ``MODAL_REFRESH`` of it is
    "quiet" and kept for up to ``MODAL_EVERY`` RODAS4 steps by the driver) and, when it moved
    or there is none, a new reference (:func:`modal_reference`).

    Parameters
    ----------
    t, y, f0, held, P, T, atol, J, ft, yp, fp, aux, live, all_live, frozen_known, S, colour
        As :func:`jacobian_fresh`'s.
    switching, modal : bool
        ``MODE_AUTO`` or ``MODE_MODAL``; ``MODE_MODAL``.
    have_ref : bool
        A reference Jacobian is kept.
    since_eig : int
        Jacobians since the last eigen-analysis.
    quiet : bool
        The last moved test found the Jacobian quiet.
    rho, h_osc : float
        The spectral radius [1/s] and the modal step cap [s] so far.
    J_ref : numpy.ndarray
        The reference Jacobian, written on a new reference [1/s in SI units].
    v, w : numpy.ndarray
        Work space [-].

    Returns
    -------
    tuple
        (calls, frozen_known, rho, h_osc, have_ref, since_eig, quiet, spectral-radius
        estimates made, eigen-analyses made).
    """
    calls, frozen_known = jacobian_fresh(t, y, f0, held, P, T, atol, J, ft, yp, fp, aux, live,
                                         all_live, frozen_known, S, colour)
    estimates = 0
    analyses = 0
    if switching and not modal:
        rho = _r4_spectral_radius(J, atol, v, w, POWER_ITERATIONS)
        estimates += 1
    since_eig += 1
    moved = not have_ref
    if modal and have_ref and since_eig >= MODAL_EVERY:
        moved = modal_jacobian_moved(J, J_ref, MODAL_REFRESH)
        quiet = not moved
    if modal and moved:
        quiet = False
        since_eig = 0
        h_osc, rho = modal_reference(J, J_ref, live, atol, v, w)
        estimates += 1
        analyses += 1
        have_ref = True
    return calls, frozen_known, rho, h_osc, have_ref, since_eig, quiet, estimates, analyses


def modal_reference(J: np.ndarray, J_ref: np.ndarray, live: np.ndarray, atol: np.ndarray,
                    v: np.ndarray, w: np.ndarray) -> tuple[float, float]:
    """``MODE_MODAL``'s eigen-analysis of ``J``, kept as the reference Jacobian ``J_ref``:
    the step cap of the lightly damped modes (:func:`feeddrive.solvers.modes.step_cap`) and
    the spectral radius of the switch back to DOPRI5 (both redone when a row of J moves by
    ``MODAL_REFRESH``).

    Parameters
    ----------
    J : numpy.ndarray
        The Jacobian [1/s in SI units].
    J_ref : numpy.ndarray
        The reference Jacobian, written (a copy of J) [1/s in SI units].
    live : numpy.ndarray of bool
        The states not frozen.
    atol : numpy.ndarray
        Absolute tolerance per state [SI, per state].
    v, w : numpy.ndarray
        Work space [-].

    Returns
    -------
    h_osc : float
        The step cap [s].
    rho : float
        The spectral radius estimate [1/s].
    """
    h_osc = modal_step_cap(J, live, MODAL_ZETA_LIGHT, MODAL_H_LAMBDA)
    rho = _r4_spectral_radius(J, atol, v, w, POWER_ITERATIONS)
    n = J.shape[0]
    for i in range(n):
        for j in range(n):
            J_ref[i, j] = J[i, j]
    return h_osc, rho


def modal_refresh(t: float, y: np.ndarray, f: np.ndarray, held: np.ndarray, P: np.ndarray,
                  T: np.ndarray, atol: np.ndarray, J: np.ndarray, ft: np.ndarray,
                  yp: np.ndarray, fp: np.ndarray, aux: np.ndarray, all_live: np.ndarray,
                  S: np.ndarray, colour: np.ndarray, J_ref: np.ndarray, v: np.ndarray,
                  w: np.ndarray) -> tuple[int, float, float]:
    """The Jacobian at (t, y) with every column differenced and its :func:`modal_reference`
    (``MODE_MODAL`` on DOPRI5 steps: the periodic analysis and the test of a switch).

    Parameters
    ----------
    t : float
        Time [s].
    y, f : numpy.ndarray
        State and its derivative [SI; SI/s, per state].
    held, P, T : numpy.ndarray
        Held values, parameters, tables [SI].
    atol : numpy.ndarray
        Absolute tolerance per state [SI, per state].
    J : numpy.ndarray
        The Jacobian, written [1/s in SI units].
    ft, yp, fp, aux : numpy.ndarray
        Work space [SI].
    all_live : numpy.ndarray of bool
        All true.
    S, colour : numpy.ndarray of int
        Sparsity pattern and column groups.
    J_ref : numpy.ndarray
        The reference Jacobian, written [1/s in SI units].
    v, w : numpy.ndarray
        Work space [-].

    Returns
    -------
    calls : int
        Right-hand-side evaluations made.
    h_osc : float
        The step cap [s].
    rho : float
        The spectral radius estimate [1/s].
    """
    calls = _r4_fd_jacobian(t, y, f, held, P, T, atol, J, ft, yp, fp, aux, all_live, S, colour)
    h_osc, rho = modal_reference(J, J_ref, all_live, atol, v, w)
    return calls, h_osc, rho


def stiffness_estimate(h: float, f_new: np.ndarray, k6: np.ndarray, y_new: np.ndarray,
                       yt: np.ndarray) -> float:
    """h·|λ| of the DOPRI5 step just taken, ‖f(y_new) − k6‖/‖y_new − yt‖ (the last two stages
    evaluated at nearby points; Hairer, Nørsett & Wanner, Solving ODEs I, Sect. IV.2,
    dopri5.f); 0 where the two points coincide.

    Parameters
    ----------
    h : float
        The step [s].
    f_new, k6 : numpy.ndarray
        The derivatives at the step's end and at its sixth stage [SI/s, per state].
    y_new, yt : numpy.ndarray
        The states there [SI, per state].

    Returns
    -------
    float
        The estimate [-].
    """
    num = 0.0
    den = 0.0
    for i in range(f_new.size):
        num += (f_new[i] - k6[i]) ** 2
        den += (y_new[i] - yt[i]) ** 2
    if den > 0.0:
        return h * math.sqrt(num / den)
    return 0.0


def weighted_stiffness_estimate(h: float, f_new: np.ndarray, k6: np.ndarray, y: np.ndarray,
                                y_new: np.ndarray, yt: np.ndarray, rtol: float,
                                atol: np.ndarray, rel_mask: np.ndarray) -> float:
    """h·|λ| as :func:`stiffness_estimate`, each state's difference weighted as the error norm
    weighs it (atol + rtol·max(|y|, |y_new|)): the stiff mode the step-size controller sees,
    whatever the states' units; 0 where the two points coincide.

    Parameters
    ----------
    h : float
        The step [s].
    f_new, k6 : numpy.ndarray
        The derivatives at the step's end and at its sixth stage [SI/s, per state].
    y : numpy.ndarray
        The state at the step's start [SI, per state].
    y_new, yt : numpy.ndarray
        The states at its end and at its sixth stage [SI, per state].
    rtol : float
        Relative tolerance [-].
    atol : numpy.ndarray
        Absolute tolerance per state [SI, per state].
    rel_mask : numpy.ndarray
        1 where the relative tolerance applies [-].

    Returns
    -------
    float
        The estimate [-].
    """
    num = 0.0
    den = 0.0
    for i in range(f_new.size):
        scale = atol[i] + rtol * rel_mask[i] * max(abs(y[i]), abs(y_new[i]))
        num += ((f_new[i] - k6[i]) / scale) ** 2
        den += ((y_new[i] - yt[i]) / scale) ** 2
    if den > 0.0:
        return h * math.sqrt(num / den)
    return 0.0


def step_size(used_rodas: bool, r5: bool, err: float, h_try: float, h: float,
              h_max: float, last: bool,
              err_old: float, alpha: float, beta: float, r4_first: bool, r4_h_old: float,
              r4_err_old: float, r4_rejected: bool, every_error: bool,
              stability_share: float, f_new: np.ndarray, k6: np.ndarray, y: np.ndarray,
              y_new: np.ndarray, yt: np.ndarray, rtol: float, atol: np.ndarray,
              rel_mask: np.ndarray) -> tuple[float, float, bool, float, float, bool]:
    """The step-size controller after an accepted step: Hairer's PI controller for DOPRI5
    (:func:`feeddrive.solvers.steps.pi_factor_template`), Gustafsson's predictive controller
    for RODAS4 (Hairer & Wanner, Solving ODEs II, Sect. IV.8, Eq. (8.21)); a last step cut
    to an event only shrinks the next one.

    Parameters
    ----------
    used_rodas : bool
        The step was a Rosenbrock step.
    r5 : bool
        RODAS5P's (else RODAS4's): the controller's exponent 1/(q + 1), q the embedded order
        (:data:`R5_EXPONENT`, :data:`R4_EXPONENT`).
    err : float
        Its error norm [-].
    h_try : float
        Its size [s].
    h : float
        The step size the controller proposed before it [s].
    h_max : float
        Largest step [s].
    last : bool
        The step was cut to land on an event.
    err_old : float
        DOPRI5's error memory [-].
    alpha, beta : float
        The PI controller's exponents [-].
    r4_first, r4_h_old, r4_err_old, r4_rejected : bool, float, float, bool
        RODAS4's memory: no accepted step yet, the last accepted step [s] and its error [-],
        a rejection since.
    every_error : bool
        DOPRI5's memory takes every error, also 0 (the breakpoint driver, v1).
    stability_share : float
        Below 1 (the breakpoint driver's ``stability_share``), a DOPRI5 step is also capped at
        this share of :data:`DOPRI5_STABILITY` / ρ, ρ from
        :func:`weighted_stiffness_estimate` on the step just taken [-].
    f_new, k6, y, y_new, yt, rtol, atol, rel_mask
        That step's last stages, states and the tolerances (:func:`weighted_stiffness_estimate`).

    Returns
    -------
    tuple
        (h, err_old, r4_first, r4_h_old, r4_err_old, r4_rejected) updated.
    """
    if used_rodas:
        r_exp = R5_EXPONENT if r5 else R4_EXPONENT
        fac = 0.2 if err == 0.0 else max(1.0 / 6.0, min(5.0, err ** r_exp / 0.9))
        if not r4_first and err > 0.0:
            facpred = (r4_h_old / h_try) * (err * err / r4_err_old) ** r_exp / 0.9
            fac = max(fac, max(1.0 / 6.0, min(5.0, facpred)))
        h_new = h_try / fac
        if r4_rejected:
            h_new = min(h_new, h_try)
        r4_first = False
        r4_h_old = h_try
        r4_err_old = max(1e-2, err)
        r4_rejected = False
    else:  # DOPRI5: the explicit steps' controller (feeddrive.solvers.steps)
        fac = _pi_factor(err, err_old, alpha, beta)
        if every_error or err != 0.0:
            err_old = max(err, 1e-4)
        h_new = h_try * fac
    if not last or h_new < h:
        h = min(h_new, h_max)
    if stability_share < 1.0 and not used_rodas:  # a share of DOPRI5's stability bound
        h_lambda = weighted_stiffness_estimate(h_try, f_new, k6, y, y_new, yt, rtol, atol,
                                               rel_mask)
        if h_lambda > 0.0:
            h = min(h, stability_share * DOPRI5_STABILITY * h_try / h_lambda)
    return h, err_old, r4_first, r4_h_old, r4_err_old, r4_rejected


def dense_coefficients(stiff: bool, r5: bool, h: float, y: np.ndarray, y_new: np.ndarray,
                       f0: np.ndarray, k2: np.ndarray, k3: np.ndarray, k4: np.ndarray,
                       k5: np.ndarray, k6: np.ndarray, u6: np.ndarray, u7: np.ndarray,
                       f_new: np.ndarray, e: np.ndarray, q1: np.ndarray, q2: np.ndarray,
                       q3: np.ndarray) -> None:
    """The continuous extension of the step just accepted: a Rosenbrock step's vectors into
    q1, q2, q3 (RODAS5P's three; RODAS4's two and q3 = 0); DOPRI5's (Hairer's contd5) into q1,
    q2, q3 and e.

    Parameters
    ----------
    stiff : bool
        A Rosenbrock step.
    r5 : bool
        RODAS5P's (else RODAS4's).
    h : float
        Its size [s].
    y, y_new : numpy.ndarray
        The states at its start and end [SI, per state].
    f0, k2, k3, k4, k5, k6, u6, u7, f_new : numpy.ndarray
        Its stages (DOPRI5) [SI/s, per state], its increments (Rosenbrock: k2 … k6, u6, u7
        and e the error estimate) [SI, per state].
    e : numpy.ndarray
        DOPRI5: the fifth coefficient, written [SI, per state].
    q1, q2, q3 : numpy.ndarray
        The coefficients, written [SI, per state].
    """
    if stiff and r5:
        _r5_rodas5p_dense(k2, k3, k4, k5, k6, u6, u7, e, q1, q2, q3)
    elif stiff:
        _r4_rodas4_dense(k2, k3, k4, k5, k6, q1, q2)
        for i in range(y.size):
            q3[i] = 0.0
    else:
        for i in range(y.size):
            ydiff = y_new[i] - y[i]
            bspl = h * f0[i] - ydiff
            q1[i] = ydiff
            q2[i] = bspl
            q3[i] = ydiff - h * f_new[i] - bspl
        _dp5_dense(h, f0, k2, k3, k4, k5, k6, f_new, e)


def outputs_inside(t: float, t_new: float, last: bool, stiff: bool, y: np.ndarray,
                   y_new: np.ndarray, q1: np.ndarray, q2: np.ndarray, q3: np.ndarray,
                   e: np.ndarray, yp: np.ndarray, fp: np.ndarray, held: np.ndarray,
                   P: np.ndarray, T: np.ndarray, aux: np.ndarray, want_aux: bool,
                   t_out: np.ndarray, y_out: np.ndarray, aux_out: np.ndarray, i_out: int,
                   n_out: int, o0: int, out_every: int, base: float) -> tuple[int, int]:
    """The output samples strictly inside the step [t, t_new] (one at t_new that is an event
    time is written after the event), interpolated on its continuous extension
    (:func:`dense_coefficients`), with the auxiliary signals there if wanted.

    Parameters
    ----------
    t, t_new : float
        The step [s].
    last : bool
        It ends on an event.
    stiff : bool
        A RODAS4 step.
    y, y_new : numpy.ndarray
        The states at its ends [SI, per state].
    q1, q2, q3, e : numpy.ndarray
        Its continuous extension [SI, per state].
    yp, fp : numpy.ndarray
        Work space [SI, per state].
    held, P, T : numpy.ndarray
        Held values, parameters, tables [SI].
    aux : numpy.ndarray
        The auxiliary signals, work space [SI].
    want_aux : bool
        Write the auxiliary signals.
    t_out, y_out, aux_out : numpy.ndarray
        The outputs [s; SI].
    i_out, n_out : int
        The next output's index, the number of outputs.
    o0 : int
        The index of the call's first output on the whole run's grid.
    out_every : int
        Output stride in breakpoints.
    base : float
        Breakpoint spacing [s].

    Returns
    -------
    i_out : int
        The next output's index.
    calls : int
        Right-hand-side evaluations made.
    """
    h_done = t_new - t
    calls = 0
    while i_out < n_out:
        t_grid = ((o0 + i_out) * out_every) * base
        if t_grid > t_new or (last and t_grid >= t_new - 1e-9 * base):
            break
        th = (t_grid - t) / h_done
        th1 = 1.0 - th
        for i in range(y.size):
            if stiff:
                yp[i] = th1 * y[i] + th * (y_new[i] + th1 * (q1[i] + th * (q2[i]
                                                                          + th * q3[i])))
            else:
                yp[i] = y[i] + th * (q1[i] + th1 * (q2[i] + th * (q3[i] + th1 * e[i])))
        t_out[i_out] = t_grid
        y_out[i_out, :] = yp
        if want_aux:
            rhs(t_grid, yp, held, P, T, fp, aux)
            calls += 1
            aux_out[i_out, :] = aux
        i_out += 1
    return i_out, calls


def outputs_at(t: float, y: np.ndarray, fp: np.ndarray, held: np.ndarray, P: np.ndarray,
               T: np.ndarray, aux: np.ndarray, want_aux: bool, t_out: np.ndarray,
               y_out: np.ndarray, aux_out: np.ndarray, i_out: int, n_out: int, o0: int,
               out_every: int, base: float) -> tuple[int, int]:
    """The output samples at the event time t (within 1e-9 of the breakpoint spacing).

    Parameters
    ----------
    t : float
        The event [s].
    y : numpy.ndarray
        The state there [SI, per state].
    fp : numpy.ndarray
        Work space [SI/s, per state].
    held, P, T : numpy.ndarray
        Held values, parameters, tables [SI].
    aux : numpy.ndarray
        The auxiliary signals, work space [SI].
    want_aux : bool
        Write the auxiliary signals.
    t_out, y_out, aux_out : numpy.ndarray
        The outputs [s; SI].
    i_out, n_out : int
        The next output's index, the number of outputs.
    o0 : int
        The index of the call's first output on the whole run's grid.
    out_every : int
        Output stride in breakpoints.
    base : float
        Breakpoint spacing [s].

    Returns
    -------
    i_out : int
        The next output's index.
    calls : int
        Right-hand-side evaluations made.
    """
    calls = 0
    while i_out < n_out:
        t_grid = ((o0 + i_out) * out_every) * base
        if abs(t_grid - t) > 1e-9 * base:
            break
        t_out[i_out] = t_grid
        y_out[i_out, :] = y
        if want_aux:
            rhs(t, y, held, P, T, fp, aux)
            calls += 1
            aux_out[i_out, :] = aux
        i_out += 1
    return i_out, calls


def bounds_status(y: np.ndarray, bound: np.ndarray) -> int:
    """The state's check after a step: ``STATUS_NON_FINITE`` if a component is not finite,
    else ``STATUS_DIVERGED`` if one is beyond its divergence bound, else ``STATUS_OK``.

    Parameters
    ----------
    y : numpy.ndarray
        The state [SI, per state].
    bound : numpy.ndarray
        Largest |state| per state [SI, per state].

    Returns
    -------
    int
        The status.
    """
    finite = True
    diverged = False
    for i in range(y.size):
        if not math.isfinite(y[i]):
            finite = False
        elif abs(y[i]) > bound[i]:
            diverged = True
    if not finite:
        return STATUS_NON_FINITE
    if diverged:
        return STATUS_DIVERGED
    return STATUS_OK



def step_end_status(memory: np.ndarray, stop_at: int, t: float, taken: int, max_steps: int,
                    y: np.ndarray, bound: np.ndarray) -> int:
    """The run's status after an accepted step (not the FMU's): the live time written and the
    stop request read where the memory has their slots (its last two, beyond ``stop_at``),
    then the step limit, then the state's check (:func:`bounds_status`).

    Parameters
    ----------
    memory : numpy.ndarray
        The driver's memory [mixed].
    stop_at : int
        The memory's length without the two slots.
    t : float
        The step's end [s].
    taken, max_steps : int
        Steps taken, the call's step limit.
    y : numpy.ndarray
        The state at t [SI, per state].
    bound : numpy.ndarray
        Largest |state| per state [SI, per state].

    Returns
    -------
    int
        ``STATUS_STOPPED``, ``STATUS_MAX_STEPS``, ``STATUS_NON_FINITE``, ``STATUS_DIVERGED``
        or ``STATUS_OK``.
    """
    status = STATUS_OK
    if memory.shape[0] > stop_at:
        memory[memory.shape[0] - 1] = t
        if memory[memory.shape[0] - 2] != 0.0:
            status = STATUS_STOPPED
    if status == STATUS_OK and taken > max_steps:
        status = STATUS_MAX_STEPS
    if status == STATUS_OK:
        status = bounds_status(y, bound)
    return status


def output_row(t: float, y: np.ndarray, aux: np.ndarray, with_aux: bool, t_out: np.ndarray,
               y_out: np.ndarray, aux_out: np.ndarray, i_out: int) -> int:
    """One output sample written: t, the state and (``with_aux``) the auxiliary signals.

    Parameters
    ----------
    t : float
        The output's time [s].
    y, aux : numpy.ndarray
        The state and the auxiliary signals there [SI].
    with_aux : bool
        Write the auxiliary signals.
    t_out, y_out, aux_out : numpy.ndarray
        The outputs [s; SI].
    i_out : int
        The output's index.

    Returns
    -------
    int
        The next output's index.
    """
    t_out[i_out] = t
    y_out[i_out, :] = y
    if with_aux:
        aux_out[i_out, :] = aux
    return i_out + 1


def land_crossing(h_try: float, y: np.ndarray, y_new: np.ndarray, f0: np.ndarray,
                  k2: np.ndarray, k3: np.ndarray, k4: np.ndarray, k5: np.ndarray,
                  k6: np.ndarray, f_new: np.ndarray, e: np.ndarray, switch_rows: np.ndarray
                  ) -> tuple[float, int]:
    """The first switching surface crossed inside the breakpoint driver's DOPRI5 step,
    located on the step's continuous extension (:mod:`feeddrive.solvers.events`).  The stages
    are free once the fifth coefficient is formed: ``k2``, ``k3``, ``k4`` take the other three
    (overwritten), ``e`` the fifth.

    Parameters
    ----------
    h_try : float
        The step [s].
    y, y_new : numpy.ndarray
        The state at its start and end [SI, per state].
    f0, k2, k3, k4, k5, k6, f_new : numpy.ndarray
        The step's stages [SI/s, per state].
    e : numpy.ndarray
        Work space [SI, per state].
    switch_rows : numpy.ndarray
        (m, n) switching surfaces W·y [state units → m/s].

    Returns
    -------
    theta : float
        The crossing's fraction of the step (not in (0, 1]: none).
    k : int
        The surface crossed.
    """
    _dp5_dense(h_try, f0, k2, k3, k4, k5, k6, f_new, e)
    for i in range(y.size):
        ydiff = y_new[i] - y[i]
        bspl = h_try * f0[i] - ydiff
        k2[i] = ydiff
        k3[i] = bspl
        k4[i] = ydiff - h_try * f_new[i] - bspl
    theta, k = switch_crossing(switch_rows, y, y_new, k2, k3, k4, e, False)
    return theta, k


def next_event(t: float, t_end: float, kb: int, schedule: np.ndarray, base: float,
               stops: np.ndarray, i_stop: int, adaptive: int, i_out: int, n_out: int, o0: int,
               out_every: int) -> tuple[float, bool, bool, int, int]:
    """The event the dense driver's steps land on next: the schedule's next sample instant
    (:func:`feeddrive.solvers.schedule.next_instant`; one this close to the end is the end), a
    profile breakpoint before it, with fixed steps an output point before those, else the end.

    Parameters
    ----------
    t, t_end : float
        Now and the end of the call [s].
    kb : int
        The current sample instant's breakpoint index.
    schedule : numpy.ndarray of int
        The schedule (:mod:`feeddrive.solvers.schedule`).
    base : float
        Breakpoint spacing [s].
    stops : numpy.ndarray
        Sorted profile breakpoints [s].
    i_stop : int
        The first of them not yet passed.
    adaptive : int
        0: fixed steps, which land on the output points.
    i_out, n_out : int
        The next output's index, the number of outputs.
    o0 : int
        The index of the call's first output on the whole run's grid.
    out_every : int
        Output stride in breakpoints.

    Returns
    -------
    tuple
        (t_ev [s], a sample instant, a profile breakpoint, the instant's breakpoint index
        (-1: none), ``i_stop`` moved past the breakpoints passed).
    """
    t_ev = t_end
    is_sample = False
    kb_next = next_instant(kb, schedule)  # the schedule's next instant (-1: none)
    if kb_next >= 0:
        t_s = kb_next * base
        if t_s <= t_end + 1e-9 * base:  # an instant this close to the end is the end
            is_sample = True
            if t_s < t_end - 1e-9 * base:
                t_ev = t_s
    n_stops = stops.size
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
    return t_ev, is_sample, is_stop, kb_next, i_stop


def memory_load(memory: np.ndarray, live: np.ndarray, J_ref: np.ndarray
                ) -> tuple[float, bool, bool, int, int, float, float, float, bool, bool, float,
                           bool, int, int, float, int, bool, float]:
    """The dense driver's state carried over from the call that ended where this one starts
    (the layout of :func:`feeddrive.solvers.switching.new_memory`, ``MEMORY_SCALARS`` values,
    the live flags, the modal reference Jacobian).

    Parameters
    ----------
    memory : numpy.ndarray
        The driver's memory [mixed].
    live : numpy.ndarray of bool
        The states not frozen, written.
    J_ref : numpy.ndarray
        The modal reference Jacobian, written [1/s in SI units].

    Returns
    -------
    tuple
        (h [s], stiff, frozen states known, stiff and non-stiff counts, DOPRI5's error
        memory, RODAS4's error and step [s], its first and rejected flags, the modal step cap
        [s], a reference Jacobian kept, the step count until which a switch is refused, the
        DOPRI5 steps since the last eigen-analysis, the spectral radius [1/s], the Jacobians
        since the last eigen-analysis, the last moved test found the Jacobian quiet, DOPRI5's
        step when it last handed over to RODAS4 [s]).
    """
    n = live.size
    for i in range(n):
        live[i] = memory[MEMORY_SCALARS + i] != 0.0
        for j in range(n):
            J_ref[i, j] = memory[MEMORY_SCALARS + n + i * n + j]
    return (memory[0], memory[1] != 0.0, memory[2] != 0.0, int(memory[3]), int(memory[4]),
            memory[5], memory[6], memory[7], memory[8] != 0.0, memory[9] != 0.0, memory[10],
            memory[11] != 0.0, int(memory[12]), int(memory[13]), memory[14], int(memory[15]),
            memory[16] != 0.0, memory[17])


def memory_save(memory: np.ndarray, live: np.ndarray, J_ref: np.ndarray, h: float,
                stiff: bool, frozen_known: bool, stiff_count: int, nonstiff_count: int,
                err_old: float, r4_err_old: float, r4_h_old: float, r4_first: bool,
                r4_rejected: bool, h_osc: float, have_ref: bool, refuse_until: int,
                dp_since_eig: int, rho: float, since_eig: int, quiet: bool, h_dp: float
                ) -> None:
    """The dense driver's state kept for the next call (:func:`memory_load`'s inverse).

    Parameters
    ----------
    memory : numpy.ndarray
        The driver's memory, written [mixed].
    live : numpy.ndarray of bool
        The states not frozen.
    J_ref : numpy.ndarray
        The modal reference Jacobian [1/s in SI units].
    h : float
        The next step size [s].
    stiff, frozen_known : bool
        RODAS4 steps; the frozen states known.
    stiff_count, nonstiff_count : int
        The stiffness test's counts.
    err_old, r4_err_old : float
        DOPRI5's and RODAS4's error memory [-].
    r4_h_old : float
        RODAS4's last step [s].
    r4_first, r4_rejected : bool
        RODAS4's first-step and rejected flags.
    h_osc : float
        The modal step cap [s].
    have_ref : bool
        A reference Jacobian is kept.
    refuse_until, dp_since_eig : int
        The steps for which a switch is still refused, counted from the next call's first
        (each call counts its steps from 0); DOPRI5 steps since the last eigen-analysis.
    rho : float
        The spectral radius [1/s].
    since_eig : int
        Jacobians since the last eigen-analysis.
    quiet : bool
        The last moved test found the Jacobian quiet.
    h_dp : float
        DOPRI5's step when it last handed over to RODAS4 [s].
    """
    memory[0] = h
    memory[1] = 1.0 if stiff else 0.0
    memory[2] = 1.0 if frozen_known else 0.0
    memory[3] = stiff_count
    memory[4] = nonstiff_count
    memory[5] = err_old
    memory[6] = r4_err_old
    memory[7] = r4_h_old
    memory[8] = 1.0 if r4_first else 0.0
    memory[9] = 1.0 if r4_rejected else 0.0
    memory[10] = h_osc
    memory[11] = 1.0 if have_ref else 0.0
    memory[12] = refuse_until
    memory[13] = dp_since_eig
    memory[14] = rho
    memory[15] = since_eig
    memory[16] = 1.0 if quiet else 0.0
    memory[17] = h_dp
    n = live.size
    for i in range(n):
        memory[MEMORY_SCALARS + i] = 1.0 if live[i] else 0.0
        for j in range(n):
            memory[MEMORY_SCALARS + n + i * n + j] = J_ref[i, j]


def switch_method(stiff: bool, modal: bool, r_cost: float, rho: float, h_done: float,
                  h_osc: float,
                  r4_h_old: float, r4_rejected: bool, h_dp: float, stiff_count: int,
                  nonstiff_count: int, switches: int, err_old: float, dp_since_eig: int,
                  refuse_until: int, n_steps: int, r4_first: bool, have_ref: bool,
                  t_new: float, y_new: np.ndarray, f_new: np.ndarray, k6: np.ndarray,
                  yt: np.ndarray, held: np.ndarray, P: np.ndarray, T: np.ndarray,
                  atol: np.ndarray, J: np.ndarray, ft: np.ndarray, yp: np.ndarray,
                  fp: np.ndarray, aux: np.ndarray, all_live: np.ndarray, S: np.ndarray,
                  colour: np.ndarray, J_ref: np.ndarray, v: np.ndarray, w: np.ndarray
                  ) -> tuple[bool, float, float, int, int, int, float, int, int, bool, bool,
                             int, int, float]:
    """The stiffness detection and method switching after an accepted step (``MODE_AUTO``,
    ``MODE_MODAL``).  From RODAS4, back to DOPRI5 after ``NONSTIFF_STEPS`` steps that DOPRI5
    would take stably (ρ·h < ``NONSTIFF_HRHO``; ``MODE_MODAL``: or the cap leaves RODAS4 less
    than ``MODAL_SWITCH_GAIN`` × that step) or that are not ``r_cost`` × the step DOPRI5
    took when it handed over (``h_dp``): a RODAS4 step costs about that many DOPRI5 steps.  A
    short step longer than the one before, or the first after a rejection, is not counted
    (the step is growing back), and after a switch for cost alone the switch to RODAS4 is
    refused for ``MODAL_RETRY`` steps.  From DOPRI5, to RODAS4 after
    ``STIFF_STEPS`` stiff verdicts (:func:`stiffness_estimate` > ``STIFF_HLAMBDA``; reset
    after 6 non-stiff steps in a row), unless (``MODE_MODAL``) the cap on the lightly damped
    modes would not let RODAS4 step ``MODAL_SWITCH_GAIN`` × further: then the switch is
    refused for ``MODAL_RETRY`` steps.  ``MODE_MODAL`` analyses DOPRI5's Jacobian every
    ``MODAL_RETRY`` steps too (:func:`modal_refresh`).

    Parameters
    ----------
    stiff, modal : bool
        The step was RODAS4's; the method is ``MODE_MODAL``.
    r_cost : float
        What a Rosenbrock step costs in DOPRI5 steps (``RODAS4_COST`` or ``RODAS5P_COST``)
        [-].
    rho : float
        The spectral radius estimate [1/s].
    h_done : float
        The step [s].
    h_osc : float
        The modal step cap [s].
    r4_h_old : float
        The RODAS4 step before this one [s] (a stretch still growing its step back from
        DOPRI5's is not judged on cost).
    r4_rejected : bool
        This RODAS4 step followed a rejected one (a stretch growing back from a rejection is
        not judged on cost either).
    h_dp : float
        DOPRI5's step when it last handed over to RODAS4 [s] (0: none yet).
    stiff_count, nonstiff_count, switches : int
        The test's counts, the switches so far.
    err_old : float
        DOPRI5's error memory [-].
    dp_since_eig, refuse_until, n_steps : int
        DOPRI5 steps since the last eigen-analysis; the step count until which a switch is
        refused; the steps so far.
    r4_first, have_ref : bool
        RODAS4's first-step flag; a reference Jacobian kept.
    t_new : float
        The step's end [s].
    y_new, f_new : numpy.ndarray
        The state and its derivative there [SI; SI/s, per state].
    k6, yt : numpy.ndarray
        DOPRI5's sixth stage and the state it was evaluated at [SI/s; SI, per state].
    held, P, T : numpy.ndarray
        Held values, parameters, tables [SI].
    atol : numpy.ndarray
        Absolute tolerance per state [SI, per state].
    J, J_ref : numpy.ndarray
        The Jacobian and the modal reference Jacobian, written by an analysis [1/s in SI
        units].
    ft, yp, fp, aux : numpy.ndarray
        Work space [SI].
    all_live : numpy.ndarray of bool
        All true.
    S, colour : numpy.ndarray of int
        Sparsity pattern and column groups.
    v, w : numpy.ndarray
        Work space [-].

    Returns
    -------
    tuple
        (stiff, rho, h_osc, stiff_count, nonstiff_count, switches, err_old, dp_since_eig,
        refuse_until, r4_first, have_ref) updated, the right-hand-side evaluations made, the
        eigen-analyses made (each with a Jacobian and a spectral radius) and h_dp updated.
    """
    calls = 0
    analyses = 0
    if stiff:
        # back to DOPRI5 when its stable step would do (this step's, or (MODE_MODAL) when
        # the cap leaves RODAS4 less than MODAL_SWITCH_GAIN × that step, the test that
        # refuses the switch the other way) or when RODAS4's steps do not pay for their cost
        # against the step DOPRI5 took when it handed over (h_dp)
        stable = rho * min(h_done, h_osc / MODAL_SWITCH_GAIN) < NONSTIFF_HRHO
        short = h_done < r_cost * h_dp
        if not stable and short and (h_done > r4_h_old or r4_rejected):
            pass  # growing back from DOPRI5's step or from a rejection: not judged yet
        elif stable or short:
            nonstiff_count += 1
            if nonstiff_count >= NONSTIFF_STEPS:
                stiff = False
                switches += 1
                stiff_count = 0
                nonstiff_count = 0
                err_old = 1e-4
                if not stable:
                    # DOPRI5 is not stable at RODAS4's step, only cheaper: not straight back
                    refuse_until = n_steps + MODAL_RETRY
        else:
            nonstiff_count = 0
    else:
        if modal:
            dp_since_eig += 1
        if modal and dp_since_eig >= MODAL_RETRY:
            # DOPRI5 too: its step on a lightly damped mode is capped as well
            dp_since_eig = 0
            more, h_osc, rho = modal_refresh(t_new, y_new, f_new, held, P, T, atol, J, ft, yp,
                                             fp, aux, all_live, S, colour, J_ref, v, w)
            calls += more
            analyses += 1
            have_ref = True
        if n_steps < refuse_until:
            pass  # MODE_MODAL: a switch was refused recently
        elif stiffness_estimate(h_done, f_new, k6, y_new, yt) > STIFF_HLAMBDA:
            nonstiff_count = 0
            stiff_count += 1
            go = stiff_count >= STIFF_STEPS
            if go and modal:
                # would RODAS4, capped on the lightly damped modes, step further?
                more, h_osc, rho = modal_refresh(t_new, y_new, f_new, held, P, T, atol, J, ft,
                                                 yp, fp, aux, all_live, S, colour, J_ref, v, w)
                calls += more
                analyses += 1
                have_ref = True
                if h_osc < MODAL_SWITCH_GAIN * h_done:
                    go = False
                    stiff_count = 0
                    refuse_until = n_steps + MODAL_RETRY
            if go:
                stiff = True
                switches += 1
                stiff_count = 0
                r4_first = True
                h_dp = h_done
        else:
            nonstiff_count += 1
            if nonstiff_count >= 6:
                stiff_count = 0
    return (stiff, rho, h_osc, stiff_count, nonstiff_count, switches, err_old, dp_since_eig,
            refuse_until, r4_first, have_ref, calls, analyses, h_dp)


def error_estimate_step(used_rodas: bool, ge_since: int, t: float, t_new: float,
                        y: np.ndarray, f0: np.ndarray, held: np.ndarray, P: np.ndarray,
                        T: np.ndarray, atol: np.ndarray, J: np.ndarray, ge_J: np.ndarray,
                        ft: np.ndarray, yp: np.ndarray, fp: np.ndarray, ge_aux: np.ndarray,
                        all_live: np.ndarray, S: np.ndarray, colour: np.ndarray,
                        ge_Phi: np.ndarray, ge_A: np.ndarray, ge_B: np.ndarray,
                        memory: np.ndarray, ge_at: int, ge_w: np.ndarray,
                        ge_d: np.ndarray) -> tuple[int, int, int]:
    """The embedded global-error estimate (:mod:`feeddrive.solvers.global_error`) carried
    over the accepted step [t, t_new]: the propagator exp(H J) formed afresh every
    ``GE_REFRESH`` steps (from the RODAS4 step's own Jacobian, else from one taken at (t, y)),
    then the step's local error added and propagated.

    Parameters
    ----------
    used_rodas : bool
        The step was RODAS4's (``J`` is its Jacobian).
    ge_since : int
        Accepted steps since the propagator was formed.
    t, t_new : float
        The step [s].
    y, f0 : numpy.ndarray
        The state at t and its derivative [SI; SI/s, per state].
    held, P, T : numpy.ndarray
        Held values, parameters, tables [SI].
    atol : numpy.ndarray
        Absolute tolerance per state, the scaling of the exponential [SI, per state].
    J, ge_J : numpy.ndarray
        The step's Jacobian; the estimate's own, written [1/s in SI units].
    ft, yp, fp, ge_aux : numpy.ndarray
        Work space [SI].
    all_live : numpy.ndarray of bool
        All true.
    S, colour : numpy.ndarray of int
        Sparsity pattern and column groups.
    ge_Phi, ge_A, ge_B : numpy.ndarray
        The propagator, written, and work space [-].
    memory : numpy.ndarray
        The driver's memory, whose slots from ``ge_at`` hold the estimate [mixed].
    ge_at : int
        Where those slots start.
    ge_w : numpy.ndarray
        Work space [SI, per state].
    ge_d : numpy.ndarray
        The step's local error estimate [SI, per state].

    Returns
    -------
    calls : int
        Right-hand-side evaluations made.
    jacobians : int
        Jacobians taken.
    ge_since : int
        Updated.
    """
    calls = 0
    jacobians = 0
    if ge_since >= GE_REFRESH:
        if used_rodas:  # the step's own Jacobian
            ge_exponential(J, GE_INTERVAL, ge_Phi, ge_A, ge_B, atol)
        else:
            calls = _r4_fd_jacobian(t, y, f0, held, P, T, atol, ge_J, ft, yp, fp, ge_aux,
                                    all_live, S, colour)
            jacobians = 1
            ge_exponential(ge_J, GE_INTERVAL, ge_Phi, ge_A, ge_B, atol)
        ge_since = 0
    ge_since += 1
    ge_advance(t, t_new, ge_Phi, memory, ge_at, GE_INTERVAL, ge_w, ge_d)
    return calls, jacobians, ge_since


def step_attempt(stiff: bool, r5: bool, adaptive: int, t: float, t_ev: float, h: float,
                 h_max: float, modal: bool, h_osc: float, h_min: float, y: np.ndarray,
                 f0: np.ndarray, held: np.ndarray, P: np.ndarray, T: np.ndarray, rtol: float,
                 atol: np.ndarray, rel_mask: np.ndarray, J: np.ndarray, ft: np.ndarray,
                 M: np.ndarray, piv: np.ndarray, k2: np.ndarray, k3: np.ndarray, k4: np.ndarray,
                 k5: np.ndarray, k6: np.ndarray, u6: np.ndarray, u7: np.ndarray,
                 f_new: np.ndarray, e: np.ndarray, yt: np.ndarray, yp: np.ndarray,
                 fp: np.ndarray, y_new: np.ndarray, aux: np.ndarray, live: np.ndarray,
                 all_live: np.ndarray, S: np.ndarray, colour: np.ndarray, frozen_known: bool,
                 r4_rejected: bool, jac_age: int, steps: int, max_steps: int, rejected: int,
                 n_rhs: int, n_jac: int, n_rodas: int) -> tuple[
                     float, float, float, bool, int, bool, bool, bool, int, int, int, int, int]:
    """The dense driver's step from ``t`` (``h`` capped by ``h_max`` and, ``modal``, ``h_osc``,
    cut to land on ``t_ev``) tried until accepted: Rosenbrock (``stiff``; a moved frozen state
    retakes the Jacobian; a rejection with a kept one ends as ``stale``) or DOPRI5, each shrunk
    on rejection by its rule (Hairer & Wanner II, IV.7; Hairer, Nørsett & Wanner I, II.4).

    Parameters
    ----------
    stiff, r5, adaptive, modal : bool, bool, int, bool
        Rosenbrock (else DOPRI5); RODAS5P's (else RODAS4's); 1 for error-controlled steps, 0
        for a fixed step; the cap.
    t, t_ev, h, h_max, h_osc, h_min : float
        The step's start, the next event, the step size, its largest, the modal cap (DOPRI5
        amplifies a mode at 1 < h|λ| < 3.3), the smallest step [s].
    y, f0, held, P, T, rtol, atol, rel_mask : numpy.ndarray, float
        The state and its derivative at t, held values, parameters, tables, tolerances [SI].
    J, ft, M, piv, k2, k3, k4, k5, k6, u6, u7, f_new, e, yt, yp, fp, y_new, aux : numpy.ndarray
        The Jacobian (retaken on a moved frozen state), work space, the step's end [mixed].
    live, all_live, S, colour : numpy.ndarray
        The states the Jacobian is taken for, all, its sparsity pattern, column groups [-].
    frozen_known, r4_rejected, jac_age : bool, bool, int
        Frozen states known; a Rosenbrock rejection since the last step; the Jacobian's age.
    steps, max_steps, rejected, n_rhs, n_jac, n_rodas : int
        Counts so far (the step limit).

    Returns
    -------
    tuple
        (err, t_new, h_try, last, status, stale, r4_rejected, frozen_known, steps, rejected,
        n_rhs, n_jac, n_rodas): the accepted step's error norm, end, size, landing, status,
        whether to retake the Jacobian first, the flags and counts updated.
    """
    last = False
    h_try = min(h, h_max)
    if modal:
        h_try = min(h_try, h_osc)
    if t + h_try >= t_ev - 1e-12 * max(1.0, abs(t_ev)):
        h_try = t_ev - t
        last = True
    err = 0.0
    t_new = t_ev
    status = STATUS_OK
    stale = False
    while True:
        t_new = t_ev if last else t + h_try
        if stiff and r5:
            calls = _r5_rodas5p_step(t, h_try, y, f0, J, ft, held, P, T, M, piv, k2, k3,
                                     k4, k5, k6, u6, u7, e, yt, fp, y_new, aux, live)
        elif stiff:
            calls = _r4_rodas4_step(t, h_try, y, f0, J, ft, held, P, T, M, piv, k2, k3,
                                    k4, k5, k6, e, yt, fp, y_new, aux, live)
        if stiff:
            if calls == -2:  # a frozen state moved: retry with the full Jacobian
                n_rhs += R5_STAGES if r5 else R4_STAGES
                frozen_known = False
                for i in range(y.size):
                    live[i] = True
                calls = _r4_fd_jacobian(t, y, f0, held, P, T, atol, J, ft, yp, fp, aux,
                                        all_live, S, colour)
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
            _dp5_step(t, h_try, y, f0, held, P, T, k2, k3, k4, k5, k6, f_new, yt, y_new,
                      aux, t_new)
            n_rhs += 6
            steps += 1
            if adaptive == 0:
                err = 0.0
            else:
                _dp5_error(h_try, f0, k2, k3, k4, k5, k6, f_new, e)
                err = _error_norm(e, y, y_new, rtol, atol, rel_mask)
        if adaptive == 0 or err <= 1.0:
            break
        rejected += 1
        if stiff:
            fac = max(1.0 / 6.0, min(5.0, err ** (R5_EXPONENT if r5 else R4_EXPONENT) / 0.9))
            h_try /= fac
            r4_rejected = True
            if jac_age > 0:  # a kept Jacobian: the retry takes a fresh one
                stale = True
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
        if stale:
            break
    return (err, t_new, h_try, last, status, stale, r4_rejected, frozen_known, steps,
            rejected, n_rhs, n_jac, n_rodas)


#: the pieces, in the order they are placed in the compiled module
PIECES = ("jacobian_fresh", "modal_reference", "jacobian_update", "modal_refresh",
          "stiffness_estimate", "weighted_stiffness_estimate", "step_size",
          "dense_coefficients", "outputs_inside", "outputs_at", "bounds_status",
          "next_event", "memory_load", "memory_save", "switch_method",
          "error_estimate_step", "step_end_status", "output_row", "land_crossing",
          "step_attempt")


# the generated module's kernels the template calls (feeddrive.solvers.steps,
# feeddrive.solvers.rodas4): placeholders that make this module importable on its own
_dp5_step: Any = None
_dp5_error: Any = None
_dp5_dense: Any = None
_error_norm: Any = None
_pi_factor: Any = None
_reject_factor: Any = None
_r4_fd_jacobian: Any = None
_r4_frozen_states: Any = None
_r4_rodas4_step: Any = None
_r4_rodas4_dense: Any = None
_r5_rodas5p_step: Any = None
_r5_rodas5p_dense: Any = None
_r4_spectral_radius: Any = None


# ---------------------------------------------------------------- the drivers' calling convention
#: the explicit step's work arrays, the drivers' parameters (made by :func:`step_space`)
STEP_WORK = ("tick", "f0", "k2", "k3", "k4", "k5", "k6", "f_new", "yt", "y_new", "e", "aux")
_LAND_PARAMS = ("y0", "t_end", "out_every", "base", "schedule", "P", "T", "rtol", "atol",
                "rel_mask", "h_max", "stability_share", "adaptive", "max_steps", "start", "held",
                "memory", "bound", "switch_rows", *STEP_WORK)
#: the dense driver's work space beyond the explicit step's (made by :func:`work_space`)
DENSE_WORK = ("q1", "q2", "q3", "u6", "u7", "ft", "yp", "fp", "v", "w", "J", "M", "J_ref",
              "piv", "live", "all_live", "ge_J", "ge_Phi", "ge_A", "ge_B", "ge_w", "ge_d", "ge_aux")


def step_space(y0: np.ndarray, schedule: np.ndarray, n_aux: int) -> tuple[np.ndarray, ...]:
    """The drivers' (``integrate``'s, ``integrate_dense``'s) work arrays of the explicit step,
    made by their caller (a piece cannot allocate in the C subset; the drivers read shorter
    without them): ``tick`` and ``f0`` … ``e``, ``aux``, in the order of their parameters.
    numba's callers (:func:`feeddrive.solvers.dopri5.integrate`,
    :func:`feeddrive.solvers.switching.integrate`) call it; the C build's entries run its text
    (:func:`feeddrive.backends.c_engine.lowered_source`: arrays on the stack).

    Parameters
    ----------
    y0 : numpy.ndarray
        The state [SI, per state].
    schedule : numpy.ndarray of int
        The sample schedule, one entry per clock.
    n_aux : int
        Number of auxiliary signals.

    Returns
    -------
    tuple of numpy.ndarray
        The arrays.
    """
    n = y0.size
    tick = np.empty(schedule.size, dtype=np.int64)
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
    aux = np.empty(n_aux)
    return (tick, f0, k2, k3, k4, k5, k6, f_new, yt, y_new, e, aux)


def work_space(y0: np.ndarray, memory: np.ndarray, n_aux: int) -> tuple[np.ndarray, ...]:
    """The dense driver's (``integrate_dense``'s) other work arrays (:data:`DENSE_WORK`, in
    the order of its parameters), made by its caller as :func:`step_space`'s are; the
    global-error estimate's have ``n`` rows where ``memory`` has its slots, else none.

    Parameters
    ----------
    y0 : numpy.ndarray
        The state [SI, per state].
    memory : numpy.ndarray
        The driver's memory (its length says whether the error estimate runs) [mixed].
    n_aux : int
        Number of auxiliary signals.

    Returns
    -------
    tuple of numpy.ndarray
        The arrays.
    """
    n = y0.size
    ng = n if memory.shape[0] == MEMORY_SCALARS + n + n * n + 3 * n + 2 else 0
    q1 = np.empty(n)
    q2 = np.empty(n)
    q3 = np.empty(n)
    u6 = np.empty(n)
    u7 = np.empty(n)
    ft = np.zeros(n)
    yp = np.empty(n)
    fp = np.empty(n)
    v = np.empty(n)
    w = np.empty(n)
    J = np.zeros((n, n))
    M = np.empty((n, n))
    J_ref = np.zeros((n, n))
    piv = np.zeros(n, dtype=np.int64)
    live = np.ones(n, dtype=np.bool_)
    all_live = np.ones(n, dtype=np.bool_)
    ge_J = np.zeros((ng, ng))
    ge_Phi = np.zeros((ng, ng))
    ge_A = np.zeros((ng, ng))
    ge_B = np.zeros((ng, ng))
    ge_w = np.zeros(ng)
    ge_d = np.zeros(ng)
    ge_aux = np.empty(n_aux)
    return (q1, q2, q3, u6, u7, ft, yp, fp, v, w, J, M, J_ref, piv, live, all_live, ge_J,
            ge_Phi, ge_A, ge_B, ge_w, ge_d, ge_aux)


_DENSE_PARAMS = ("y0", "t_end", "out_every", "base", "schedule", "P", "T", "rtol", "atol",
                 "rel_mask", "h_init", "h_max", "adaptive", "max_steps", "mode", "stops",
                 "want_aux", "S", "colour", "start", "held", "memory", "bound", "t_buf",
                 "y_buf", "aux_buf", "switch_rows", *STEP_WORK, *DENSE_WORK)
_COMM_PARAMS = ("t", "t_end", "t0", "n", "y", "held", "held_prev", "P", "T", "schedule",
                "tick", "base", "rtol", "atol", "rel_mask", "h_max", "max_steps", "redo",
                "memory", "f0", "k2", "k3", "k4", "k5", "k6", "f_new", "yt", "y_new", "e",
                "aux")
#: each use of the driver: its parameters (in order), the flags and parameters it fixes, and
#: its docstring (:func:`feeddrive.solvers.driver_text.source` specialises the template so)
USES: dict[str, tuple[tuple[str, ...], dict[str, Any], str]] = {
    "integrate": (_LAND_PARAMS, {"LAND": True, "mode": MODE_DOPRI5, "want_aux": True},
                  "The breakpoint driver (feeddrive.solvers.dopri5): "
                  "feeddrive.solvers.driver.driver_template specialised (LAND)."),
    "integrate_dense": (_DENSE_PARAMS, {"DENSE": True},
                        "The dense-output driver (feeddrive.solvers.switching): "
                        "feeddrive.solvers.driver.driver_template specialised (DENSE)."),
    "advance": (_COMM_PARAMS, {"COMM": True, "mode": MODE_DOPRI5, "adaptive": 1},
                "The FMU's driver (feeddrive.fmu.solver): "
                "feeddrive.solvers.driver.driver_template specialised (COMM)."),
}


#: the uses numba compiles without its runtime (:data:`feeddrive._jit.nrt_free_kernel`): both
#: drivers, their text lowered to write their outputs and statistics into their caller's arrays
#: (:func:`feeddrive.solvers.driver_text.lower_outputs`) and to advance the caller's copy of the
#: initial state (``y0``).  Without numba's reference counting its inlining of their pieces costs
#: nothing, where with it — a count at every array argument of every inlined call — the pieces
#: called at every step had to be written into numba's text (10–20 % of a ``modal`` run, 4–8 % of a
#: ``dopri5`` run otherwise: benchmarks/README.md, "the driver split"), the dense driver's 352
#: lines; numba's text passes the two pieces that take more arguments than its inliner does their
#: later ones as a tuple (:func:`feeddrive.solvers.driver_text.numba_text`).  The C build calls them
#: all.
NUMBA_NRT_FREE = ("integrate", "integrate_dense")
#: the length of each use's statistics (``stats``; :data:`feeddrive.solvers.switching.STAT_NAMES`
#: the dense driver's): the array a caller passes a lowered text
#: (:func:`feeddrive.solvers.driver_text.lower_outputs`)
N_STATS = {"integrate": 5, "integrate_dense": 12}
