"""Dense-output integration with automatic stiffness switching: DOPRI5 ⇄ RODAS4.

The one driver of :mod:`feeddrive.solvers.driver`, specialised ``DENSE`` and placed in the
shared drivers' module as ``integrate_dense``, runs in four modes:

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
  test) — and back to DOPRI5 after ``NONSTIFF_STEPS`` Rosenbrock steps that an explicit
  step of that size would take stably (h times the power-iteration estimate of the
  Jacobian's spectral radius below ``NONSTIFF_HRHO``) or that are not ``RODAS4_COST`` times
  the step DOPRI5 took when it handed over — what a Rosenbrock step costs against an explicit
  one (a share of a Jacobian, an LU and six solves against six right-hand sides; LSODA's
  cost-weighted switch).  Steps growing back from a switch or a rejection are not counted;
  after a switch for cost alone the switch to RODAS4 is refused for ``MODAL_RETRY`` steps;
  DOPRI5 resumes with at most the step it handed over with (a Rosenbrock step can lie outside
  its stability region: docs/model.md, "DOPRI5 resumes from its own step");
* ``MODE_MODAL``: ``MODE_AUTO`` with the steps capped on lightly damped modes
  (:mod:`feeddrive.solvers.modes`); the switch to RODAS4 is refused, and a Rosenbrock
  stretch ends, where the cap leaves RODAS4 less than ``MODAL_SWITCH_GAIN`` × DOPRI5's step
  (from RODAS4: its stable step ``NONSTIFF_HRHO``/ρ).

Dense output: the step is not capped by the output interval.  Outputs on the grid
t_i = i·out_every·base are interpolated inside the step that contains them.  Event times are
exact step ends: the instants of the sample schedule ``schedule`` — every clock's, merged
(:mod:`feeddrive.solvers.schedule`; the zero-order-hold outputs jump there:
``sample_update`` runs, the derivative is re-evaluated),
the profile breakpoints ``stops`` (kinks of the command: the Jacobian's f_t changes) and the end.
With ``adaptive = 0`` the chosen method runs at the fixed step ``h_init`` and the output grid
points are step ends too (used to verify the order).

The solver never imports a model: the driver is compiled once, in the shared drivers' module
(:mod:`feeddrive.solvers.shared`), and each model passes its ``rhs`` and ``sample_update``
(:func:`template_sources`).  The modes and switching
thresholds are defined with the driver (:mod:`feeddrive.solvers.driver`) and read from here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from . import builds, driver, driver_text
from .driver import (  # noqa: F401 - the modes and thresholds, read from here
    MEMORY_SCALARS,
    MODAL_EVERY,
    MODAL_RETRY,
    MODAL_SWITCH_GAIN,
    MODE_AUTO,
    MODE_DOPRI5,
    MODE_MODAL,
    MODE_RODAS4,
    NONSTIFF_HRHO,
    NONSTIFF_STEPS,
    POWER_ITERATIONS,
    RODAS4_COST,
    RODAS5P_COST,
    ROSENBROCK_5,
    STIFF_HLAMBDA,
    STIFF_STEPS,
)

if TYPE_CHECKING:
    from ..model.assemble import Model

STAT_NAMES = ("status", "steps", "rejected", "rhs_evaluations", "t_reached", "jacobians",
              "rosenbrock_steps", "switches", "output_rhs_evaluations", "eigen_analyses",
              "switch_crossings", "spectral_radii")

CONSTANTS = ("MEMORY_SCALARS", "MODE_DOPRI5", "MODE_RODAS4", "MODE_AUTO", "MODE_MODAL",
             "STIFF_HLAMBDA", "STIFF_STEPS",
             "NONSTIFF_HRHO", "NONSTIFF_STEPS", "POWER_ITERATIONS", "MODAL_SWITCH_GAIN",
             "RODAS4_COST", "RODAS5P_COST", "ROSENBROCK_5",
             "MODAL_RETRY", "MODAL_EVERY")


def new_memory(n_states: int, error_estimate: bool = False) -> np.ndarray:
    """The carried-over state of a run that has not started (the ``memory`` of
    :func:`feeddrive.solvers.driver.driver_template`).  Its last two slots are a *stop request*
    (non-zero: the call ends after its current step with STATUS_STOPPED) and the *live time*
    (the time [s] of the last accepted step, written as the solver goes): another thread reads
    a long call's progress and stops it while it runs (the kernels release the GIL;
    feeddrive.engine.simulate.Simulation.live_time and request_stop).

    With ``error_estimate``, ``3 n_states`` slots before those two carry the embedded
    global-error estimate (:mod:`feeddrive.solvers.global_error`): the propagated error E,
    the largest |E| so far and the local errors of the current interval, per state
    (:func:`error_estimate`); the run's own arithmetic is the same with or without them.

    Parameters
    ----------
    n_states : int
        Number of states.
    error_estimate : bool, default False
        Carry the embedded global-error estimate.

    Returns
    -------
    numpy.ndarray
        Zeros [mixed, see :func:`feeddrive.solvers.driver.driver_template`].
    """
    extra = 3 * n_states if error_estimate else 0
    return np.zeros(MEMORY_SCALARS + n_states + n_states * n_states + extra + 2)


def error_estimate(memory: np.ndarray, n_states: int) -> tuple[np.ndarray, np.ndarray] | None:
    """The embedded global-error estimate a memory of :func:`new_memory` carries: (E at the
    last accepted step, the largest |E| so far) per state, or None without the estimate.

    Parameters
    ----------
    memory : numpy.ndarray
        The driver's memory after a call [mixed, see :func:`new_memory`].
    n_states : int
        Number of states.

    Returns
    -------
    tuple of numpy.ndarray or None
        E and the largest |E| [SI, per state] (copies).
    """
    at = MEMORY_SCALARS + n_states + n_states * n_states
    if memory.shape[0] != at + 3 * n_states + 2:
        return None
    return memory[at:at + n_states].copy(), memory[at + n_states:at + 2 * n_states].copy()


def integrate(model: Model, y0: np.ndarray, t_end: float, out_every: int, base: float,
              schedule: np.ndarray, rtol: float, atol: np.ndarray,
              rel_mask: np.ndarray, h_init: float, h_max: float, adaptive: int,
              max_steps: int, mode: int, stops: np.ndarray, want_aux: bool = True, *,
              start: int = 0, held: np.ndarray | None = None,
              memory: np.ndarray | None = None, bound: np.ndarray | None = None,
              P: np.ndarray | None = None,
              out: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
              switch_rows: np.ndarray | None = None,
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Integrate ``model`` from breakpoint ``start`` (t = start·base, state ``y0``; a multiple
    of ``out_every``) to ``t_end`` (the driver
    :func:`feeddrive.solvers.driver.driver_template`, specialised ``DENSE``).  ``held`` and
    ``memory`` are updated in place, so a run continued from where a call stopped is
    bit-identical to one call in which that instant is a step end (a profile breakpoint, a
    sample instant). ``bound``: the largest |state| per state before the run stops as diverged
    (None: none); ``P``: the parameter vector (None: the model's; a run passes the periods on
    its grid).

    Parameters
    ----------
    model : Model
        The assembled model.
    y0 : numpy.ndarray
        State at t = start·base [SI, per state].
    t_end : float
        End of the run [s].
    out_every : int
        Output stride in breakpoints.
    base : float
        Breakpoint spacing [s].
    schedule : numpy.ndarray of int
        Breakpoints between two instants of each clock; 0 = continuous
        (:mod:`feeddrive.solvers.schedule`).
    rtol : float
        Relative tolerance [-].
    atol : numpy.ndarray
        Absolute tolerance per state [SI, per state].
    rel_mask : numpy.ndarray
        1 where the relative tolerance applies [-].
    h_init : float
        First step size [s].
    h_max : float
        Largest step [s].
    adaptive : int
        1 for error-controlled steps, 0 for a fixed step (used to verify the order).
    max_steps : int
        Step limit of the call.
    mode : int
        ``MODE_DOPRI5``, ``MODE_RODAS4``, ``MODE_AUTO`` or ``MODE_MODAL`` (see the module).
    stops : numpy.ndarray
        Sorted profile breakpoints, exact step ends [s].
    want_aux : bool, default True
        Evaluate the auxiliary signals at the outputs.
    start : int, default 0
        Breakpoint index the call starts from.
    held : numpy.ndarray, optional
        Held controller values, updated in place [SI, per value].
    memory : numpy.ndarray, optional
        Driver memory, updated in place (:func:`new_memory`) [mixed, see the driver].
    bound : numpy.ndarray, optional
        Largest |state| per state before the run stops as diverged [SI, per state]; none by
        default.
    P : numpy.ndarray, optional
        The parameter vector; the model's by default [SI, per slot].
    out : tuple of numpy.ndarray, optional
        Output buffers (:func:`new_output`) reused from call to call: when they are large
        enough the outputs are written into them and ``t_out``, ``y_out``, ``aux_out`` are
        views of their first rows, valid until the buffers' next use (a caller that runs many
        integrations and keeps none of their arrays saves a fresh array's page faults per
        call: ~3 ms for a 100-s run's 12 MB); new arrays by default [s; SI].
    switch_rows : numpy.ndarray, optional
        (m, n) switching surfaces W·y (a friction site's sliding speed) whose zero crossings
        are located on the continuous extension and made step ends
        (:mod:`feeddrive.solvers.events`); none by default [state units → m/s].

    Returns
    -------
    t_out : numpy.ndarray
        Output times [s].
    y_out : numpy.ndarray
        States at them [SI, per state].
    aux_out : numpy.ndarray
        Auxiliary signals at them [SI, per signal].
    stats : numpy.ndarray
        As :data:`STAT_NAMES`: status, steps, rejected, right-hand-side evaluations, time
        reached [s], Jacobians, … [mixed].
    held : numpy.ndarray
        The held controller values at the end [SI, per value].

    Raises
    ------
    ValueError
        When ``start`` is not a multiple of ``out_every``.

    References
    ----------
    .. [1] J. R. Dormand, P. J. Prince, "A family of embedded Runge-Kutta formulae", J. Comput.
       Appl. Math. 6 (1980) 19–26.
    .. [2] E. Hairer, G. Wanner, Solving Ordinary Differential Equations II, 2nd ed., Springer,
       1996, Sect. IV.7 (RODAS4).
    """
    if start % out_every:
        raise ValueError(f"start = {start}: expected a multiple of out_every = {out_every}")
    held = np.zeros(model.n_held) if held is None else held
    memory = new_memory(len(model.states)) if memory is None else memory
    bound = np.full(len(model.states), np.inf) if bound is None else bound
    schedule = np.ascontiguousarray(schedule, dtype=np.int64)
    n_out = max(0, (int(round(t_end / base)) - start) // out_every + 1)
    n_aux_out = n_out if want_aux else 0
    t_buf, y_buf, aux_buf = _NO_OUTPUT if out is None else out
    if not (t_buf.shape[0] >= n_out and y_buf.shape[0] >= n_out
            and y_buf.shape[1] == len(model.states) and aux_buf.shape[0] >= n_aux_out
            and aux_buf.shape[1] == len(model.aux)):  # new: every row returned is written
        t_buf, y_buf, aux_buf = new_output(model, n_out, want_aux)
    result: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray] = (
        builds.driver(model, 'integrate_dense')(
            y0, t_end, out_every, base, schedule,
            model.P if P is None else P, model.T, rtol, atol, rel_mask, h_init, h_max,
            adaptive, max_steps, mode,
            np.ascontiguousarray(stops, dtype=np.float64), bool(want_aux),
            model.jacobian_pattern, model.jacobian_colours, start, held, memory, bound,
            t_buf[:n_out], y_buf[:n_out], aux_buf[:n_aux_out],
            np.zeros((0, len(model.states))) if switch_rows is None
            else np.ascontiguousarray(switch_rows, dtype=np.float64),
            *driver.step_space(y0, schedule, len(model.aux)),
            *driver.work_space(y0, memory, len(model.aux))))
    return result


# no output buffers: too small for any call, the driver allocates its outputs
_NO_OUTPUT = (np.empty(0), np.empty((0, 0)), np.empty((0, 0)))


def new_output(model: Model, n_out: int, want_aux: bool = False,
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Output buffers for :func:`integrate` (``out``): room for ``n_out`` samples of the
    model's states (and auxiliary signals with ``want_aux``), uninitialised.

    Parameters
    ----------
    model : Model
        The assembled model.
    n_out : int
        Number of output samples they hold.
    want_aux : bool, default False
        Room for the auxiliary signals too.

    Returns
    -------
    tuple of numpy.ndarray
        Times [s], states [SI, per state], auxiliary signals [SI, per signal].
    """
    return (np.empty(n_out), np.empty((n_out, len(model.states))),
            np.empty((n_out if want_aux else 0, len(model.aux))))


def template_sources() -> list[str]:
    """Text placed in the shared drivers' module: the driver of
    :mod:`feeddrive.solvers.driver` specialised as ``integrate_dense`` (its steps are those
    of :mod:`feeddrive.solvers.steps`, its Jacobian kernels those of
    :mod:`feeddrive.solvers.rodas4`, placed beside it), compiled without numba's reference
    counting (:data:`feeddrive._jit.nrt_free_kernel`: its outputs and statistics written into
    its caller's arrays, :data:`feeddrive.solvers.driver.NUMBA_NRT_FREE`;
    :func:`feeddrive.solvers.builds.driver` passes them).  numba compiles a function at its
    first call, so a model run only with ``dopri5`` never compiles this one.

    Returns
    -------
    list of str
        Python sources.
    """
    src = driver_text.source("integrate_dense")
    return [f"from feeddrive.solvers.switching import ({', '.join(CONSTANTS)})",
            "from feeddrive.solvers.schedule import due, next_instant",
            "from feeddrive.solvers.events import first_crossing as switch_crossing",
            "from feeddrive.solvers.global_error import INTERVAL as GE_INTERVAL, "
            "REFRESH_STEPS as GE_REFRESH, advance as ge_advance, "
            "exponential as ge_exponential, keep_local as ge_keep",
            "from feeddrive.solvers.modes import step_cap as modal_step_cap, "
            "jacobian_moved as modal_jacobian_moved, ZETA_LIGHT as MODAL_ZETA_LIGHT, "
            "H_LAMBDA as MODAL_H_LAMBDA, REFRESH as MODAL_REFRESH",
            "from feeddrive._jit import nrt_free_kernel",
            ("@nrt_free_kernel\n" if "integrate_dense" in driver.NUMBA_NRT_FREE
             else "@kernel\n") + src]
