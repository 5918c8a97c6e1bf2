"""The ``dopri5`` method: Dormand–Prince 5(4) landing on every breakpoint (the v1 engine).

Breakpoints are the instants of the model's sample schedule (every sampled part's clock,
:mod:`feeddrive.solvers.schedule`; the zero-order-hold outputs jump there) and the output
instants; the integrator lands on each exactly, applies the sampled parts' update where one is
due, and restarts the step from there, so no step straddles a jump in the right-hand side
(the "declare your discontinuities" lesson of diffrax; python-control issue #933).  The
integrator is the one driver of :mod:`feeddrive.solvers.driver` specialised for this use
(``LAND``: every breakpoint a step end, outputs there, steps capped at ``h_max``), its step the
one explicit step of :mod:`feeddrive.solvers.steps` for the tableau
:data:`feeddrive.solvers.tableaux.DOPRI5`.

Friction reversals (a site's sliding speed through zero, where a LuGre or Dahl law has a kink)
are located on the step's continuous extension and made step ends, as in the dense driver
(:mod:`feeddrive.solvers.events`), although the outputs are step ends; without the rows
(``SolverOptions(locate_reversals=False)``) the steps cross them, as the v1 engine's did.

Error control: mixed absolute/relative weights per state; states whose absolute size carries no
meaning (shaft angles, positions) use absolute tolerance only.  Step-size control is Hairer's
PI controller (Hairer, Nørsett & Wanner, Solving ODEs I, Sect. II.4).  With ``adaptive = 0`` the
same tableau runs at a fixed step (used to verify the order).
"""

from __future__ import annotations

import functools
import inspect
from typing import TYPE_CHECKING

import numpy as np

from . import builds, driver, driver_text
from .driver import (  # noqa: F401 - the status codes, read from here by the engine
    STATUS_DIVERGED,
    STATUS_MAX_STEPS,
    STATUS_MESSAGES,
    STATUS_NON_FINITE,
    STATUS_OK,
    STATUS_STEP_UNDERFLOW,
    STATUS_STOPPED,
)
from .placeholders import N_AUX, N_HELD, rhs
from .tableaux import DOPRI5

if TYPE_CHECKING:
    from ..model.assemble import Model

ORDER = DOPRI5.order
# module constants the generated module imports (feeddrive.solvers.driver)
CONSTANTS = driver.STATUS_NAMES


@functools.lru_cache(maxsize=1)
def template_sources() -> list[str]:
    """Text placed in the shared drivers' module: the status codes and the driver of
    :mod:`feeddrive.solvers.driver` specialised as ``integrate`` (its step, the one of
    :mod:`feeddrive.solvers.steps`, written in), compiled without numba's reference counting
    (:data:`feeddrive._jit.nrt_free_kernel`: its outputs and statistics written into its
    caller's arrays, :data:`feeddrive.solvers.driver.NUMBA_NRT_FREE`;
    :func:`feeddrive.solvers.builds.driver` makes them).

    Returns
    -------
    list of str
        Python sources.
    """
    names = ", ".join(CONSTANTS)
    src = driver_text.source("integrate")
    aux = inspect.getsource(auxiliary_template).replace("def auxiliary_template(",
                                                        "def auxiliary(", 1)
    return [f"from feeddrive.solvers.driver import ({names})",
            "from feeddrive.solvers.schedule import due, next_instant",
            "from feeddrive.solvers.events import first_crossing as switch_crossing",
            "from feeddrive._jit import nrt_free_kernel",
            ("@nrt_free_kernel\n" if "integrate" in driver.NUMBA_NRT_FREE else "@kernel\n")
            + src,
            "@kernel\n" + aux]


def auxiliary_template(t_out: np.ndarray, y_out: np.ndarray, P: np.ndarray,
                       T: np.ndarray) -> np.ndarray:
    """The auxiliary signals at recorded (t, y) of a run with continuous loops (where they
    depend on nothing else): evaluated only when a Result is asked for one.

    Parameters
    ----------
    t_out : numpy.ndarray
        Recorded times [s].
    y_out : numpy.ndarray
        Recorded states [SI, per state].
    P : numpy.ndarray
        Packed parameter vector [SI, per slot].
    T : numpy.ndarray
        Packed tables [SI].

    Returns
    -------
    numpy.ndarray
        Auxiliary signals at each recorded time [SI, per signal].
    """
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
    started (:func:`integrate`; the ``memory`` of
    :func:`feeddrive.solvers.driver.driver_template`).  Its last two slots are a *stop request*
    (non-zero: the call ends after its current step with STATUS_STOPPED) and the *live time*
    (the time [s] of the last accepted step, written as the solver goes): another thread reads
    a long call's progress and stops it while it runs (the kernels release the GIL;
    feeddrive.engine.simulate.Simulation.live_time and request_stop).

    Parameters
    ----------
    n_states : int
        Number of states.
    h_init : float
        First step size [s].

    Returns
    -------
    numpy.ndarray
        The memory [mixed: s, -, state rates].
    """
    memory = np.zeros(4 + n_states)
    memory[:2] = (h_init, 1e-4)
    return memory


def integrate(model: Model, y0: np.ndarray, t_end: float, out_every: int, base: float,
              schedule: np.ndarray, rtol: float, atol: np.ndarray,
              rel_mask: np.ndarray, h_init: float, h_max: float, adaptive: int,
              max_steps: int, *, stability_share: float = 1.0, start: int = 0,
              held: np.ndarray | None = None,
              memory: np.ndarray | None = None, bound: np.ndarray | None = None,
              P: np.ndarray | None = None, switch_rows: np.ndarray | None = None,
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Integrate ``model`` from breakpoint ``start`` (t = start·base, state ``y0``) to
    ``t_end`` (the driver :func:`feeddrive.solvers.driver.driver_template`, specialised
    ``LAND``; ``schedule``: the run's sample schedule,
    :func:`feeddrive.engine.simulate.sampling`).  ``held`` (the sampled controller's values)
    and ``memory`` (step size, last error) are updated in place, so that a run continued
    from where a previous call stopped is bit-identical to one call over the whole span.
    ``bound``: the largest |state| per state before the run stops as diverged (None: none);
    ``P``: the parameter vector (None: the model's; a run passes the periods on its grid,
    :meth:`feeddrive.engine.simulate.Sampling.parameters`); ``switch_rows``: the friction
    reversals located and made step ends (:mod:`feeddrive.solvers.events`; None: none, the v1
    engine).

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
    stability_share : float, default 1
        Below 1, each step is also capped at this share of DOPRI5's stability bound
        estimated on the step before (the driver's ``stability_share``;
        :attr:`feeddrive.engine.options.SolverOptions.stability_share`) [-].
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
    switch_rows : numpy.ndarray, optional
        (m, n) switching surfaces W·y (a friction site's sliding speed) whose zero crossings
        are located on the step's continuous extension and made step ends
        (:func:`feeddrive.engine.simulate.switching_rows`); none by default
        [state units → m/s].

    Returns
    -------
    t_out : numpy.ndarray
        Output times [s].
    y_out : numpy.ndarray
        States at them [SI, per state].
    aux_out : numpy.ndarray
        Auxiliary signals at them [SI, per signal].
    stats : numpy.ndarray
        Status, steps, rejected steps, right-hand-side evaluations, time reached [s]
        [mixed].
    held : numpy.ndarray
        The held controller values at the end [SI, per value].

    References
    ----------
    .. [1] J. R. Dormand, P. J. Prince, "A family of embedded Runge-Kutta formulae", J. Comput.
       Appl. Math. 6 (1980) 19–26.
    .. [2] E. Hairer, S. P. Nørsett, G. Wanner, Solving Ordinary Differential Equations I,
       2nd ed., Springer, 1993, Sect. II.4–II.6.
    """
    held = np.zeros(model.n_held) if held is None else held
    memory = new_memory(len(model.states), h_init) if memory is None else memory
    bound = np.full(len(model.states), np.inf) if bound is None else bound
    schedule = np.ascontiguousarray(schedule, dtype=np.int64)
    result: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray] = (
        builds.driver(model, 'integrate')(y0, t_end, out_every, base, schedule,
                               model.P if P is None else P, model.T,
                               rtol, atol, rel_mask, h_max, stability_share, adaptive,
                               max_steps, start, held,
                               memory, bound,
                               np.zeros((0, len(model.states))) if switch_rows is None
                               else np.ascontiguousarray(switch_rows, dtype=np.float64),
                               *driver.step_space(y0, schedule, len(model.aux))))
    return result
