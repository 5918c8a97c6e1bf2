"""Linearisation of an assembled drive at steady sliding, loop analysis, stability band.

* :func:`linearize` — A, B, C, D of the closed loop at steady sliding at a table speed (or
  frictionless), with named states, inputs and outputs; ``.to_control()`` gives a
  python-control ``StateSpace``.  The steady state is solved for (Newton on the compiled
  right-hand side, positions moving with the reference); the Jacobians are central
  differences of the compiled right-hand side, each state perturbed on its own tolerance
  scale.  The friction laws' analytic linearisations (``FrictionLaw.linearise``) serve the
  sliding-stability indicators of :mod:`feeddrive.model.friction.stribeck` and are checked
  against this.
* :func:`loop_analysis` — poles with frequency and damping ratio, and the velocity- and
  position-loop transfer functions L(s) of each motor axis (loop broken at the current and
  speed commands by zero-valued injection inputs, L = 1/S − 1), with gain/phase margins and
  bandwidths.
* :func:`stability_band` — the speeds at which steady sliding is linearly unstable (full model,
  every friction site and bristle state), edges refined by bisection to a stated tolerance,
  with the unstable mode's frequency.

* :func:`frequency_response` — a named transfer (tracking, dynamic compliance, disturbance
  sensitivity, a loop gain) or any input → output pair, on a frequency grid [Hz].

Inputs, named as the simulation's signals (:data:`INPUT_UNITS`): ``table_position_reference``
[m] and ``table_speed_reference`` [m/s] (the profile's commanded table position and speed —
the speed is the position loop's feed-forward), for a DDFS also ``nut_position_reference``,
``nut_speed_reference`` [m/s] (the hollow motor's), ``load_force`` [N] on the table (against
positive motion), and per motor axis ``a``: ``a_speed_command_disturbance`` [rad/s, or m/s
for a linear motor] added to the position loop's output and ``a_current_command_disturbance``
[A] added to the velocity loop's output.  Outputs (:data:`OUTPUT_UNITS`): ``table_position``
[m], ``table_speed`` [m/s], ``following_error`` [m] (commanded − table position), and per
axis ``a_speed_command``, ``a_current_command`` (the loop signals *after* the injection), the
motor current ``a_current`` [A] and its torque ``a_motor_torque`` [N m] (a linear motor's
force ``motor_force`` [N]).

Rigid-body poles — the free motions no loop holds, zero eigenvalues that finite differences
place at ±1e-9…1e-6 1/s — are recognised by one rule (:func:`classify_poles`, :data:`MARGINAL`)
that ``loops``, ``stability``, the report and the explorer share; they are listed as such,
without a damping ratio.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np

from .. import units
from ..engine.simulate import DriveSystem
from ..model.assemble import Model
from ..model.disturbances import LeadError, TorqueRipple
from ..model.friction.lugre_parameters import LuGreParameters
from ..model.loops import INJ_CURRENT, INJ_SPEED
from ..model.mechanisms import mechanism
from ..model.reference import REFERENCE_INPUTS, ConstantSpeed
from ..parameters import ParameterError, SiteParameters
from ..parameters.validation import check_callback, check_flag, check_speed, is_real, real_array
from ..solvers import builds
from . import protocol
from .newton import pulled_gauss_newton

_T0 = 1.0  # [s] operating-point time (after the reference's start ramp)
_PULL = 1e-8  # weight of the operating point's pull to its start (free directions)
_ACCEPT = 0.1  # largest accepted steady-state residual [rate / solver tolerance]
_STATE_STEP = 1e-2  # central-difference step of a state [its solver tolerance]


@dataclass(frozen=True)
class LinearModel:
    """The drive's closed loop linearised at steady sliding: δẋ = A δx + B δu, δy = C δx + D δu.

    Parameters
    ----------
    A : numpy.ndarray
        (n, n) state matrix [SI].
    B : numpy.ndarray
        (n, m) input matrix [SI].
    C : numpy.ndarray
        (p, n) output matrix [SI].
    D : numpy.ndarray
        (p, m) feed-through matrix [SI].
    states : tuple of str
        State names, in ``x`` order.
    inputs : tuple of str
        Input names (references, loop-breaking injections, disturbances); units by
        :func:`unit_of`.
    outputs : tuple of str
        Output names; units by :func:`unit_of`.
    operating_point : dict of str to float
        The steady state, by state name [SI, per state].
    table_speed : float
        Table speed of the operating point [m/s].
    nut_speed : float
        Nut speed of the operating point [m/s].
    frictionless : bool
        Whether the friction sites were left out.
    notes : tuple of str, default ()
        Warnings, e.g. the averaged model's (:func:`averaged`).
    axes : tuple of str, default ()
        The live controller axes, as the model declares them (``Model.control_axes``):
        each has the inputs ``<axis>_speed_command_disturbance`` and
        ``<axis>_current_command_disturbance``; the first drives the table.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    operating_point: dict[str, float]
    table_speed: float  # [m/s]
    nut_speed: float  # [m/s]
    frictionless: bool
    notes: tuple[str, ...] = field(default=())
    axes: tuple[str, ...] = field(default=())

    def __repr__(self) -> str:
        return (f"<feeddrive LinearModel: {len(self.states)} states, {len(self.inputs)} "
                f"inputs, {len(self.outputs)} outputs; at {_mm_s(self.table_speed)} table, "
                f"v_n {_mm_s(self.nut_speed)}, {FRICTION_WORDS[self.frictionless]}; .A .B .C "
                ".D, .poles(), .to_control()>")

    def poles(self) -> np.ndarray:
        """Eigenvalues of ``A``: the closed loop's poles at the operating point.

        Returns
        -------
        numpy.ndarray
            Complex poles [1/s].
        """
        return np.linalg.eigvals(self.A)

    def to_control(self) -> Any:
        """The model as a python-control ``StateSpace``.

        Returns
        -------
        control.StateSpace
            With the state, input and output names.
        """
        import control

        return control.ss(self.A, self.B, self.C, self.D, states=list(self.states),
                          inputs=list(self.inputs), outputs=list(self.outputs))


@dataclass(frozen=True)
class Pole:
    """One eigenvalue of the linearised closed loop.

    Parameters
    ----------
    real : float
        Real part [1/s].
    imag : float
        Imaginary part [rad/s].
    rigid_body : bool, default False
        A free motion no loop holds (see :func:`classify_poles`), which has no damping ratio.
    """

    real: float  # [1/s]
    imag: float  # [rad/s]
    rigid_body: bool = False

    @property
    def frequency_hz(self) -> float:
        """Natural frequency |p|/(2π) [Hz]."""
        return abs(complex(self.real, self.imag)) / (2 * math.pi)

    @property
    def damping_ratio(self) -> float:
        """Damping ratio −Re(p)/|p| [-]; 1 for a pole at the origin."""
        mag = abs(complex(self.real, self.imag))
        return -self.real / mag if mag > 0 else 1.0

    def as_dict(self) -> dict[str, Any]:
        """The pole for the JSON report.

        Returns
        -------
        dict
            ``kind`` (rigid-body, oscillatory, real), real [1/s] and imaginary [rad/s] parts and,
            except for a rigid-body pole, frequency [Hz] and damping ratio [-].
        """
        if self.rigid_body:
            return {"kind": "rigid-body", "real_1_per_s": self.real,
                    "imag_rad_per_s": self.imag,
                    "note": "a free motion no loop holds (an eigenvalue 0 that finite "
                            "differences place near 0); no damping ratio"}
        return {"kind": "oscillatory" if abs(self.imag) > 0 else "real",
                "real_1_per_s": self.real, "imag_rad_per_s": self.imag,
                "frequency_hz": self.frequency_hz, "damping_ratio": self.damping_ratio}


# Free directions (e.g. the nut angle of a hollow motor on a speed loop, which no loop holds)
# give real poles at 0 that finite differences place at ±1e-9…1e-6 1/s; real poles smaller
# than this fraction of the fastest pole are treated as those marginal modes.
MARGINAL = 1e-7


def _mm_s(speed: float) -> str:
    """A speed [m/s] as a repr shows it [mm/s]."""
    return f"{1e3 * speed:.4g} mm/s"


def margin_text(name: str, value: float | None, spec: str = ".2f", unit: str = "") -> str:
    """A loop's value (:meth:`LoopResult.as_dict`) as the text outputs print it: a gain margin
    the loop does not have (its phase never crosses −180°) is infinite, "∞"; any other value it
    does not have (no gain crossover: no crossover frequency, phase margin or bandwidth) is
    "—" (``feeddrive.units.absent_value``, ``feeddrive.units.number_text``).

    Parameters
    ----------
    name : str
        The value's name (``"gain_margin_db"``, ``"phase_margin_deg"``, ``"crossover_hz"``,
        ``"closed_loop_bandwidth_hz"``).
    value : float or None
        The value [dB, deg or Hz, as its name says]; None where the analysis found none.
    spec, unit : str
        Its format specification (default ".2f") and the unit printed after a number or ∞
        (default none).

    Returns
    -------
    str
        The value's text, e.g. the wang2021 CDFS screw velocity loop's gain margin:

        >>> margin_text("gain_margin_db", None, unit="dB")
        '∞ dB'
    """
    return units.number_text(units.absent_value(name) if value is None else value, spec, unit)


def _margins_text(loop: LoopResult) -> str:
    """A loop's crossover and margins in a repr (∞ for a gain margin the loop has not, — for
    any other value: :func:`margin_text`)."""
    return (f"crossover {margin_text('crossover_hz', loop.crossover_hz, '.3g')} Hz, GM "
            f"{margin_text('gain_margin_db', loop.gain_margin_db, '.3g')} dB, PM "
            f"{margin_text('phase_margin_deg', loop.phase_margin_deg, '.3g')}°")


def classify_poles(eigenvalues: np.ndarray) -> list[Pole]:
    """Mark the free rigid-body poles, the one rule every analysis uses, and sort by frequency.

    An eigenvalue whose real and imaginary parts are both below :data:`MARGINAL` × the fastest
    pole's magnitude is a free rigid-body motion (listed as such, without a damping ratio);
    every other eigenvalue — a genuinely unstable real pole included — is kept as it is.

    Parameters
    ----------
    eigenvalues : numpy.ndarray
        The closed loop's eigenvalues [1/s].

    Returns
    -------
    list of Pole
        Sorted by frequency.
    """
    ev = np.asarray(eigenvalues, dtype=complex)
    fastest = float(np.max(np.abs(ev))) if ev.size else 0.0
    limit = MARGINAL * fastest
    poles = [Pole(float(z.real), float(z.imag),
                  rigid_body=bool(abs(z.imag) < limit and abs(z) < limit)) for z in ev]
    return sorted(poles, key=lambda p: p.frequency_hz)


def dominant_pole(poles: list[Pole]) -> Pole:
    """The least-damped oscillatory pole pair of classified poles (:func:`classify_poles`):
    the mode friction destabilises first; the rigid-body poles are never it; without an
    oscillatory pole, the slowest real one.

    Parameters
    ----------
    poles : list of Pole
        The classified poles.

    Returns
    -------
    Pole
        The dominant pole (Im > 0 for a pair).
    """
    modes = [p for p in poles if not p.rigid_body] or list(poles)
    osc = [p for p in modes if p.imag > 1e-6]
    return min(osc, key=lambda p: p.damping_ratio) if osc else min(
        modes, key=lambda p: -p.real)


def _no_friction(site: Any) -> LuGreParameters:
    """A site with the law "none" (a law with parameters of its own becomes a LuGre-form
    site on its Stribeck branches, which "none" ignores)."""
    if isinstance(site, LuGreParameters):
        return site.with_values(law="none")
    return LuGreParameters(positive=site.positive, negative=site.negative,
                           bristle_stiffness=1.0, bristle_damping=0.0, law="none")


def _frictionless(system: DriveSystem) -> DriveSystem:
    """Every friction site of the set — ``[friction.*]`` and those of a part's own section —
    with the law "none"."""
    p = system.parameters
    sites = [(f"friction.{f.name}", getattr(p.friction, f.name)) for f in fields(p.friction)]
    sites += [(f"{name}.{f.name}", getattr(section, f.name)) for name, section in p.sections
              for f in fields(section)]
    for path, site in sites:
        if isinstance(site, SiteParameters):
            p = p.replace_path(path, _no_friction(site))
    return replace(system, parameters=p)


def _check_continuous(system: DriveSystem) -> None:
    c = system.parameters.controller
    for name in ("position_period", "velocity_period", "current_period"):
        if getattr(c, name) > 0:
            raise ParameterError(f"controller.{name}", getattr(c, name),
                                 "linearisation needs continuous loops (period 0 [s]); a "
                                 "sampled loop is a discrete-time system")


def _live_states(model: Model, system: DriveSystem) -> list[int]:
    """States that move: the states a drive holds still (the CDFS's locked nut) are dropped."""
    frozen, _ = system.topology().held()
    return [k for k, name in enumerate(model.state_names) if not name.startswith(frozen)]


def _scales(model: Model) -> np.ndarray:
    atol, _ = model.tolerances(1e-7, 1e-6, 1e-4)
    return atol


class _Evaluator:
    """Calls the model's right-hand side at the operating-point time, through the shared
    drivers (:mod:`feeddrive.solvers.evaluate`: no second compilation of the model's
    ``rhs`` beside its first-class function), and its state Jacobian's central differences
    (:meth:`columns`)."""

    def __init__(self, model: Model) -> None:
        self.model = model
        self.held = np.zeros(model.n_held)
        self.aux = np.zeros(len(model.aux))
        self.n = len(model.states)
        # C-contiguous float64, as the compiled entry points take them unchecked
        # (shared.Bound.compiled)
        self.P = np.ascontiguousarray(self._continuous(model.P), dtype=float)
        self.T = np.ascontiguousarray(model.T, dtype=float)
        self._rates = builds.compiled(model, "_ev_rates")
        self._columns = builds.compiled(model, "_ev_central_columns")

    def _continuous(self, P: np.ndarray) -> np.ndarray:
        if any(P[k] != 0.0 for _, k in self.model.clocks):  # the loops as continuous ones
            P = P.copy()
            for _, k in self.model.clocks:
                P[k] = 0.0
        return P

    def __call__(self, y: np.ndarray, P: np.ndarray | None = None) -> tuple[np.ndarray,
                                                                               np.ndarray]:
        dy = np.empty(self.n)
        aux = np.empty(len(self.model.aux))
        P = self.P if P is None else np.ascontiguousarray(self._continuous(P), dtype=float)
        self._rates(_T0, np.ascontiguousarray(y, dtype=float), self.held, P, self.T,
                    dy, aux)
        return dy, aux

    def columns(self, y: np.ndarray, live: list[int], scale: np.ndarray) -> np.ndarray:
        """The state Jacobian over ``live`` by central differences, each step a hundredth of
        the state's solver tolerance: what :func:`_state_steps` gives, column by column, in
        one compiled call."""
        at = np.asarray(live, dtype=np.int64)
        steps = _STATE_STEP * scale[at]
        A = np.empty((at.size, at.size))
        self._columns(_T0, np.ascontiguousarray(y, dtype=float), self.held, self.P,
                      self.T, at, steps, at, A, np.empty(self.n), np.empty(self.n),
                      np.empty(self.n), np.empty(len(self.model.aux)))
        return A


def _solve_steady(model: Model, f: _Evaluator, y0: np.ndarray, at: np.ndarray,
                  rows: np.ndarray, at_scale: np.ndarray, row_scale: np.ndarray,
                  u0: np.ndarray) -> tuple[np.ndarray, str, float]:
    """The scaled unknowns of the steady state: Gauss–Newton on the model's compiled grouped
    Jacobian (:func:`feeddrive.analysis.newton.pulled_gauss_newton`; ≈ 3 Jacobians, one
    compiled call each), and, when that leaves a residual above the acceptance limit, scipy's
    Levenberg–Marquardt on finite differences from the start (the method before issue 21's
    fifth round: 3–5× the time, the same point to ≈ 1e-10 of its scale).  Returns the
    unknowns, the method's word and the largest residual left."""
    n = y0.size
    jac_fn = builds.compiled(model, "_r4_fd_jacobian")
    J, ft, yp, fp = np.empty((n, n)), np.empty(n), np.empty(n), np.empty(n)
    aux = np.empty(len(model.aux))
    every = np.ones(n, dtype=np.bool_)
    atol = np.ascontiguousarray(_scales(model), dtype=float)
    pattern = np.ascontiguousarray(model.jacobian_pattern)  # (the dtype every model's is)
    colours = np.ascontiguousarray(model.jacobian_colours)
    cols = np.ix_(rows, at)
    col_scale = at_scale / row_scale[:, None]

    def state(u: np.ndarray) -> np.ndarray:
        y = y0.copy()
        y[at] = u * at_scale
        return y

    def residual(u: np.ndarray) -> np.ndarray:
        return f(state(u))[0][rows] / row_scale

    def linearised(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        y = state(u)
        dy = f(y)[0]
        jac_fn(_T0, y, dy, f.held, f.P, f.T, atol, J, ft, yp, fp, aux, every,
               pattern, colours)
        return dy[rows] / row_scale, J[cols] * col_scale

    u, _ = pulled_gauss_newton(residual, linearised, u0, _PULL)
    worst = float(np.max(np.abs(residual(u))))
    if worst <= _ACCEPT:  # (False for NaN)
        return u, "Gauss–Newton", worst

    def regularised(v: np.ndarray) -> np.ndarray:
        return np.concatenate([residual(v), _PULL * (v - u0)])

    from scipy import optimize  # here: `simulate` imports this module, not scipy (issue 21)

    sol = optimize.least_squares(regularised, u0, method="lm", xtol=1e-15, ftol=1e-15,
                                 gtol=1e-15)
    return sol.x, str(sol.message), float(np.max(np.abs(residual(sol.x))))


def check_operating_point(system: object, table_speed: object, nut_speed: object,
                          frictionless: bool = False) -> None:
    """Refuse, before any linear algebra, an operating point that is not one: a system that
    is not a DriveSystem, a table speed beyond the axis's speed limit
    (:func:`~feeddrive.analysis.positioning_run.axis_speed_limit`; 1e300 m/s printed eleven
    LAPACK lines and raised LinAlgError: an outside check, 2026-12-07) or zero unless
    ``frictionless``, or a nut speed beyond ``units.LARGEST_SPEED``; a speed that is not a
    finite number is refused naming the argument (it was refused by the profile the steady
    state is found on, as ``profile.table_speed``, a name the caller never wrote).

    Parameters
    ----------
    system : DriveSystem
        The drive.
    table_speed, nut_speed : float
        The operating point [m/s].
    frictionless : bool, default False
        Whether the drive is linearised without friction (then the table may rest).

    Raises
    ------
    ParameterError
        Naming the argument, its value and what was expected [m/s].
    """
    from .critical import check_kinds, table_speed_limit

    check_kinds(system)
    assert isinstance(system, DriveSystem)
    for name, value, limit in (("table_speed", table_speed, table_speed_limit(system)),
                               ("nut_speed", nut_speed, None)):
        check_speed(name, value, sign="any", limit=limit)
    if table_speed == 0.0 and not frictionless:
        raise ParameterError("table_speed", 0.0, "steady sliding needs a non-zero speed [m/s]")


def steady_state(system: DriveSystem, table_speed: float, nut_speed: float = 0.0
                 ) -> tuple[Model, np.ndarray]:
    """The model's state in steady sliding at a table speed, at t = 1 s.

    Accelerations and the bristle, current and integrator rates are zero; positions move with
    the reference at the drive's kinematic rates.

    Parameters
    ----------
    system : DriveSystem
        The drive (continuous loops).
    table_speed : float
        Steady table speed [m/s].
    nut_speed : float, default 0.0
        Steady nut speed [m/s].

    Returns
    -------
    model : Model
        The assembled model of the constant-speed profile.
    state : numpy.ndarray
        The steady state [SI, per state].

    Raises
    ------
    ParameterError
        When no steady state is found, the operating point is not one
        (``check_operating_point``), or the loops are sampled.
    """
    check_operating_point(system, table_speed, nut_speed, frictionless=True)
    _check_continuous(system)
    profile = ConstantSpeed(table_speed, nut_speed, ramp_time=0.0)
    model = system.model(profile)
    f = _Evaluator(model)
    names = model.state_names
    n = len(names)
    y0 = np.zeros(n)
    # the drive's kinematics: position-like state -> (its rate state, the steady rate);
    # positions move with the reference, their rates are fixed
    motion = {pos: pair for pos, pair in system.topology().steady_motion(
        table_speed, nut_speed).items() if pos in names and pair[0] in names}
    kinematic = {pos: rate_state for pos, (rate_state, _) in motion.items()}
    for pos, (rate_state, rate) in motion.items():
        y0[names.index(rate_state)] = rate
        y0[names.index(pos)] = rate * _T0
    live = _live_states(model, system)
    fixed_speed = [names.index(rate_state) for rate_state in kinematic.values()]
    unknown = [k for k in live if k not in fixed_speed]
    scale = _scales(model)

    # the equations: each unknown's own rate, except a kinematic position's (its rate is the
    # fixed speed: the rate state's equation is used instead), in that order
    rows = np.array([k for k in unknown if names[k] not in kinematic]
                    + [names.index(rate) for name, rate in kinematic.items()
                       if names.index(name) in unknown], dtype=np.intp)
    row_scale = scale[rows]
    at = np.array(unknown, dtype=np.intp)
    at_scale = scale[at]

    # Directions no equation holds (the common rotation of screw and nut under a hollow motor
    # on a speed loop, the table position with the position loop open) make the Jacobian
    # singular: a least-squares solver then walks along them on rounding noise (the DDFS nut
    # angle ended 10³ rad from its start, at a different place on each call).  A weak pull to
    # the start (1e-8 of the equations' weight) holds them there and moves the other states
    # by ~1e-16 of their tolerance.
    u0 = y0[unknown] / scale[unknown]

    u, message, worst = _solve_steady(model, f, y0, at, rows, at_scale, row_scale, u0)
    y = y0.copy()
    y[unknown] = u * scale[unknown]
    # residuals are rates divided by the solver tolerances: 0.1 is a table acceleration of
    # 1e-7 m/s² (a force imbalance of ~1e-7 of the friction force), far below anything that
    # moves the linearisation; the finite-difference Newton steps stall around 1e-3
    if not worst <= _ACCEPT or not np.all(np.isfinite(y)):
        raise ParameterError("table_speed", table_speed * 1e3,
                             f"no steady sliding state found [mm/s] ({message})")
    return model, y


#: units of the linear model's inputs (a linear motor's speed-command disturbance is m/s)
INPUT_UNITS = {"table_position_reference": "m", "table_speed_reference": "m/s",
               "nut_position_reference": "m", "nut_speed_reference": "m/s",
               "load_force": "N", "speed_command_disturbance": "rad/s",
               "current_command_disturbance": "A"}
#: units of its outputs (by name, or by the part after the axis name)
OUTPUT_UNITS = {"table_position": "m", "table_speed": "m/s", "following_error": "m",
                "speed_command": "rad/s", "current_command": "A", "current": "A",
                "motor_torque": "N m", "motor_force": "N"}
# finite-difference step of each kind of input (every input enters the right-hand side
# linearly except through friction compensation at the commanded speed)
_INPUT_STEP = {"m": 1e-8, "m/s": 1e-8, "N": 1e-3, "rad/s": 1e-6, "A": 1e-6}


def unit_of(name: str, names: tuple[str, ...] = ()) -> str:
    """The unit of an input or output of :func:`linearize`.

    Parameters
    ----------
    name : str
        The input or output name (``screw_speed_command``, ``table_position``, …).
    names : tuple of str, optional
        Not used by the lookup (no caller passes it).

    Returns
    -------
    str
        The unit; ``"m/s"`` for the linear motor's speed command and its disturbance, ``""``
        when unknown.
    """
    if name in INPUT_UNITS:
        return INPUT_UNITS[name]
    if name in OUTPUT_UNITS:
        return OUTPUT_UNITS[name]
    axis, _, rest = name.partition("_")
    if axis == "motor" and rest.startswith("speed_command"):
        return "m/s"
    return INPUT_UNITS.get(rest, OUTPUT_UNITS.get(rest, ""))


def averaged(system: DriveSystem) -> tuple[DriveSystem, tuple[str, ...]]:
    """The system without what gives it no steady state: torque ripple and lead error.

    Both are zero-mean harmonics of a shaft angle, so their average over a revolution is
    nothing; the drive is linearised on that averaged model and the returned note says so.

    Parameters
    ----------
    system : DriveSystem
        The drive.

    Returns
    -------
    system : DriveSystem
        The drive with ripple and lead error removed (``system`` itself when it has none).
    notes : tuple of str
        The warning naming what was left out; empty when nothing was.
    """
    d = system.parameters.disturbances
    motors = {m.ripple: m for m in mechanism(system.drive).drive_motors if m.ripple}
    harmonic = [f.name for f in fields(d)
                if isinstance(getattr(d, f.name), (TorqueRipple, LeadError))]
    left = [f"{(motors[name].label or f'{motors[name].name} motor').replace(' ', '-')} "
            "torque ripple"
            if name in motors else name.replace("_", " ")
            for name in harmonic if any(a != 0.0 for a in getattr(d, name).amplitudes)]
    if not left:
        return system, ()
    quiet = dataclasses.replace(d, **{name: type(getattr(d, name))() for name in harmonic})
    params = system.parameters.with_values(disturbances=quiet)
    note = (f"warning: {' and '.join(left)} of the parameter set give no steady state; "
            "linearised on the averaged model (their harmonics average to zero over a "
            "revolution and are left out)")
    return replace(system, parameters=params), (note,)


def _state_steps(f: _Evaluator, y: np.ndarray, live: list[int], scale: np.ndarray) -> Any:
    """The central differences of the state Jacobian, column by column: (column, step [SI],
    (y + h, its rates, its aux), (y − h, its rates, its aux)) for each live state; the step
    is a hundredth of the state's solver tolerance."""
    for j, k in enumerate(live):
        h = _STATE_STEP * scale[k]
        yp, ym = y.copy(), y.copy()
        yp[k] += h
        ym[k] -= h
        dp, ap = f(yp)
        dm, am = f(ym)
        yield j, h, (yp, dp, ap), (ym, dm, am)


def _input_columns(f: _Evaluator, model: Model, y: np.ndarray, live: list[int],
                   outputs: Any, inputs: list[tuple[int, float]]
                   ) -> tuple[np.ndarray, np.ndarray]:
    """B and D by central differences: each input a parameter slot stepped by ±h [SI];
    ``outputs(y, aux)`` the output vector."""
    B = np.empty((len(live), len(inputs)))
    D = np.empty((len(outputs(y, f(y)[1])), len(inputs)))
    for j, (slot, h) in enumerate(inputs):
        Pp, Pm = model.P.copy(), model.P.copy()
        Pp[slot] += h
        Pm[slot] -= h
        dp, ap = f(y, Pp)
        dm, am = f(y, Pm)
        B[:, j] = (dp[live] - dm[live]) / (2 * h)
        D[:, j] = (outputs(y, ap) - outputs(y, am)) / (2 * h)
    return B, D


def state_matrix(system: DriveSystem, table_speed: float, nut_speed: float = 0.0, *,
                 frictionless: bool = False) -> np.ndarray:
    """The A matrix of :func:`linearize` alone (the same steady state and the same
    differences, bit for bit), without the inputs' and outputs' matrices it does not need:
    what :func:`rightmost_pole` and :func:`stability_band` judge.

    Parameters
    ----------
    system : DriveSystem
        The drive (continuous loops).
    table_speed : float
        Steady table speed of the operating point [m/s], non-zero.
    nut_speed : float, default 0.0
        Steady nut speed of the operating point [m/s] (DDFS).
    frictionless : bool, default False
        Linearise with every friction law set to "none" (then the speed may be 0).

    Returns
    -------
    numpy.ndarray
        A over the live states [1/s and the states' unit ratios], as ``linearize(...).A``.
    """
    frictionless = check_flag("frictionless", frictionless)  # "yes" was taken as True
    check_operating_point(system, table_speed, nut_speed, frictionless)
    sys_, _ = averaged(_frictionless(system) if frictionless else system)
    model, y = steady_state(sys_, table_speed, nut_speed)
    return _Evaluator(model).columns(y, _live_states(model, sys_), _scales(model))


def linearize(system: DriveSystem, table_speed: float = 1e-3, nut_speed: float = 0.0, *,
              frictionless: bool = False) -> LinearModel:
    """Linearise the closed loop of ``system`` at steady sliding.

    A set with torque ripple or lead error (no steady state) is linearised on its averaged
    model (:func:`averaged`), with a warning in ``notes``.

    Parameters
    ----------
    system : DriveSystem
        The drive (continuous loops).
    table_speed : float, default 1e-3
        Steady table speed of the operating point [m/s].
    nut_speed : float, default 0
        Steady nut speed of the operating point [m/s] (DDFS).
    frictionless : bool, default False
        Linearise with every friction law set to "none".

    Returns
    -------
    LinearModel
        A, B, C, D over the live states with named inputs and outputs (``to_control()``: a
        python-control StateSpace), the operating point and notes.
    """
    frictionless = check_flag("frictionless", frictionless)  # "yes" was taken as True
    check_operating_point(system, table_speed, nut_speed, frictionless)
    sys_, notes = averaged(_frictionless(system) if frictionless else system)
    model, y = steady_state(sys_, table_speed, nut_speed)
    f = _Evaluator(model)
    live = _live_states(model, sys_)
    scale = _scales(model)
    n = len(live)
    A = np.empty((n, n))
    aux_names = [a.name for a in model.aux]
    st = model.state_names
    # the controller axes as their loops declared them (model.control_axes)
    idle = sys_.topology().held()[1]
    control = [a for a in model.control_axes if a.name not in idle]
    axes = [a.name for a in control]
    pidx = model.parameter_names.index
    # inputs: (name, parameter slot)
    refs = [r for r in REFERENCE_INPUTS
            if not r.startswith("nut_") or sys_.topology().follows("nut")]
    ins: list[tuple[str, int]] = [(r, pidx(f"inputs.{r}")) for r in refs]
    ins.append(("load_force", pidx("inputs.load_force")))
    for c in control:
        ins += [(f"{c.name}_speed_command_disturbance", c.block + INJ_SPEED),
                (f"{c.name}_current_command_disturbance", c.block + INJ_CURRENT)]
    # outputs: (name, function of (state vector, aux vector))
    k_x, k_v = st.index("table_position"), st.index("table_speed")
    k_ref = aux_names.index("table_position_reference")
    outs: list[tuple[str, Any]] = [
        ("table_position", lambda yv, av: yv[k_x]),
        ("table_speed", lambda yv, av: yv[k_v]),
        ("following_error", lambda yv, av: av[k_ref] - yv[k_x]),
    ]
    for kind in ("speed_command", "current_command"):
        for c in control:
            j = aux_names.index(getattr(c, kind))
            outs.append((f"{c.name}_{kind}", lambda yv, av, j=j: av[j]))
    topology = sys_.topology()
    for c in control:
        j = st.index(c.current)
        kt_name, torque_name = topology.motor_output(c.name)
        kt = model.parameter(kt_name)
        outs.append((f"{c.name}_current", lambda yv, av, j=j: yv[j]))
        outs.append((torque_name, lambda yv, av, j=j, kt=kt: kt * yv[j]))

    def outputs(yv: np.ndarray, aux: np.ndarray) -> np.ndarray:
        return np.array([fn(yv, aux) for _, fn in outs])

    C = np.empty((len(outs), n))
    for j, h, (yp, dp, ap), (ym, dm, am) in _state_steps(f, y, live, scale):
        A[:, j] = (dp[live] - dm[live]) / (2 * h)
        C[:, j] = (outputs(yp, ap) - outputs(ym, am)) / (2 * h)
    B, D = _input_columns(f, model, y, live, outputs,
                          [(slot, _INPUT_STEP[unit_of(name)]) for name, slot in ins])
    in_names = tuple(name for name, _ in ins)
    names = tuple(model.state_names[k] for k in live)
    return LinearModel(A=A, B=B, C=C, D=D, states=names, inputs=in_names,
                       outputs=tuple(name for name, _ in outs),
                       operating_point={model.state_names[k]: float(y[k]) for k in live},
                       table_speed=table_speed, nut_speed=nut_speed, frictionless=frictionless,
                       notes=notes, axes=tuple(axes))


# ---------------------------------------------------------------- loops


@dataclass(frozen=True)
class LoopResult:
    """One loop's open-loop transfer L(jω) and its margins.

    Parameters
    ----------
    name : str
        The loop (``"screw velocity loop"``, ``"screw position loop"``, …).
    frequency_hz : numpy.ndarray
        Frequency grid [Hz].
    magnitude_db : numpy.ndarray
        |L(jω)| [dB].
    phase_deg : numpy.ndarray
        ∠L(jω), unwrapped [deg].
    gain_margin_db : float or None
        Gain margin [dB]; None when the phase never crosses −180°: an infinite margin, printed
        "∞" (:func:`margin_text`).
    phase_margin_deg : float or None
        Phase margin [deg]; None when the gain never crosses 0 dB.
    crossover_hz : float or None
        Gain-crossover frequency [Hz].
    bandwidth_hz : float or None
        Closed-loop −3 dB bandwidth [Hz].
    """

    name: str
    frequency_hz: np.ndarray
    magnitude_db: np.ndarray
    phase_deg: np.ndarray
    gain_margin_db: float | None
    phase_margin_deg: float | None
    crossover_hz: float | None
    bandwidth_hz: float | None  # closed loop −3 dB

    def __repr__(self) -> str:
        return f"<feeddrive LoopResult {self.name}: {_margins_text(self)}>"

    def as_dict(self) -> dict[str, Any]:
        """The loop's margins for the JSON report.

        Returns
        -------
        dict
            Loop name, gain margin [dB], phase margin [deg], crossover and closed-loop bandwidth
            [Hz].
        """
        return {"loop": self.name, "gain_margin_db": self.gain_margin_db,
                "phase_margin_deg": self.phase_margin_deg, "crossover_hz": self.crossover_hz,
                "closed_loop_bandwidth_hz": self.bandwidth_hz}


def _freq_response(lin: LinearModel, inp: str, out: str, w: np.ndarray) -> np.ndarray:
    i, o = lin.inputs.index(inp), lin.outputs.index(out)
    n = lin.A.shape[0]
    eye = np.eye(n)
    resp = np.empty(w.size, dtype=complex)
    for k, wk in enumerate(w):
        x = np.linalg.solve(1j * wk * eye - lin.A, lin.B[:, i])
        resp[k] = lin.C[o] @ x + lin.D[o, i]
    return resp


def _at_frequency(lin: LinearModel, inp: str, out: str) -> Callable[[float], complex]:
    """The transfer from ``inp`` to ``out`` as a function of frequency [Hz]."""
    def at(f: float) -> complex:
        return complex(_freq_response(lin, inp, out, np.array([2 * np.pi * f]))[0])

    return at


def _crossing(fn: Callable[[float], float], a: float, b: float) -> float:
    """The frequency in [a, b] [Hz] where ``fn`` changes sign (it does between a and b),
    bisected on a log scale to 1e-12 relative — the grid's points only bracket a margin's
    frequency.  (A bisection, not scipy.optimize.brentq: importing scipy.optimize costs a
    `feeddrive loops` run ≈ 0.3–0.6 s, more than the 45 evaluations of the loop's transfer.)"""
    fa = fn(a)
    for _ in range(200):
        if b <= a * (1.0 + 1e-12):
            break
        m = math.sqrt(a * b)
        fm = fn(m)
        if (fm > 0) == (fa > 0):
            a, fa = m, fm
        else:
            b = m
    return math.sqrt(a * b)


#: a loop's DC gain, when its model has a rigid-body pole, is the limit f → 0 read at this
#: fraction of its slowest other pole's frequency [-]: |T| there differs from the limit by
#: ~(fraction)² relative (T is real at DC, so |T| moves to second order): 9e-12 dB at 1e-6
#: for the CDFS velocity loop, 9e-8 dB at 1e-4, 1e-14 dB at 1e-8 (an outside check,
#: 2026-12-07), while the rigid-body pole (±1e-13…1e-6 1/s) stays far below it
DC_LIMIT_FRACTION = 1e-6


def _dc_frequency(lin: LinearModel) -> float:
    """The frequency [Hz] at which a loop transfer of ``lin`` gives its DC gain: 0 when ``lin``
    has no rigid-body pole (:func:`classify_poles`); else the limit f → 0, read at
    :data:`DC_LIMIT_FRACTION` × its slowest other pole's frequency.  A rigid-body pole makes
    ``A`` singular, and the loop's transfer at f = 0 a 0/0 left to rounding: the CDFS velocity
    loop (its position loop open, the table free) read |T(0)| = +2.02 dB at 300 mm and a
    singular matrix at 400 mm, so its bandwidth jumped between 7.89 and 8.54 Hz with the
    table's position (python-control, on the same transfer with the cancelling pole and zero at
    0 removed, gives 8.54 Hz at both: an outside check, 2026-12-07)."""
    poles = classify_poles(lin.poles())
    if not any(p.rigid_body for p in poles):
        return 0.0
    live = [abs(complex(p.real, p.imag)) for p in poles if not p.rigid_body]
    return DC_LIMIT_FRACTION * min(live) / (2 * np.pi) if live else 0.0


def _margins(freq: np.ndarray, S: np.ndarray, name: str,
             S_at: Callable[[float], complex], dc_hz: float = 0.0) -> LoopResult:
    """A loop's crossover, margins and bandwidth from the sensitivity S at its break (open
    loop L = 1/S − 1, closed loop T = 1 − S): ``S`` on ``freq`` [Hz] for the Bode arrays and to
    bracket each crossing, ``S_at`` at any frequency to locate it between the grid's points;
    the closed loop's DC gain is read at ``dc_hz`` [Hz] (:func:`_dc_frequency`).
    Interpolated on the grid, the wang2021 CDFS position loop's gain margin at its 5.6-Hz
    resonance read 3.02 dB on the default 400 points, 2.62 on 800, 4.32 on 150 —
    python-control's ``margin`` of the same transfer gives 2.589 dB (an outside check,
    2026-12-07; tests/unit/test_api_bad_values_s24.py)."""
    def L_at(f: float) -> complex:
        return 1.0 / S_at(f) - 1.0

    def T_db(f: float) -> float:
        return 20 * math.log10(abs(1.0 - S_at(f)))

    L = 1.0 / S - 1.0
    mag = 20 * np.log10(np.abs(L))
    phase = np.degrees(np.unwrap(np.angle(L)))
    phase -= 360.0 * np.ceil(phase[0] / 360.0)  # start in (−360°, 0°]: a loop lags
    crossover = phase_margin = gain_margin = bandwidth = None
    idx = np.where((mag[:-1] >= 0) & (mag[1:] < 0))[0]
    if idx.size:
        k = idx[0]
        crossover = _crossing(lambda x: abs(L_at(x)) - 1.0, freq[k], freq[k + 1])
        ph = math.degrees(np.angle(L_at(crossover)))
        phase_margin = float(((ph + 180.0) + 180.0) % 360.0 - 180.0)
    # phase crossings of −180° (mod 360) above the gain crossover: ``wrapped`` is the phase's
    # distance from −180° (mod 360), zero on the crossing (before issue 23 it was the distance
    # from 0°, so the margin was read at the −360° crossing: 76 dB for the wang2021 position
    # loop, whose real margin is 1 dB at the 5.5-Hz velocity-loop resonance)
    wrapped = (phase + 360.0) % 360.0 - 180.0
    cross = np.where(np.abs(np.diff(np.sign(wrapped))) > 0)[0]
    for k in cross:
        if abs(wrapped[k] - wrapped[k + 1]) > 180.0:  # a jump of the wrap, not a crossing
            continue
        if crossover is None or freq[k] > crossover:
            # where L crosses the negative real axis: its imaginary part changes sign
            f = _crossing(lambda x: L_at(x).imag, freq[k], freq[k + 1])
            gain_margin = -20.0 * math.log10(abs(L_at(f)))
            break
    tmag = 20 * np.log10(np.abs(1.0 - S))
    # −3 dB below the closed loop's DC gain, as python-control's ``bandwidth`` (it was below
    # |T| at the grid's first frequency, so the bandwidth moved with f_min: the position
    # loop's read 1.61 Hz from 0.5 Hz, where |T| is already −0.6 dB; from DC it is 1.37);
    # with a rigid-body pole the limit f → 0, read at ``dc_hz`` (:func:`_dc_frequency`)
    try:
        dc = abs(1.0 - S_at(dc_hz))
    except np.linalg.LinAlgError:  # a free rigid-body motion: the limit far below f_min
        dc = abs(1.0 - S_at(freq[0] * 1e-6))
    level = (20 * math.log10(dc) if math.isfinite(dc) and dc > 0 else tmag[0]) - 3.0
    below = np.where(tmag < level)[0]
    if below.size:
        k = int(below[0])
        bandwidth = _crossing(lambda x: T_db(x) - level, freq[k - 1] if k else freq[0] * 1e-6,
                              freq[k])
    return LoopResult(name, freq, mag, phase, gain_margin, phase_margin, crossover, bandwidth)


def _speed_loop_only(system: DriveSystem, axis: str, table_speed: float,
                     nut_speed: float) -> bool:
    """Whether ``axis`` runs a speed loop only (its parameter block's speed-mode slot, as its
    mechanism wires it — the hollow motor with ``controller.nut_loop = "speed"``): it then
    has no position loop."""
    model = system.model(ConstantSpeed(table_speed, nut_speed, ramp_time=0.0))
    slot = f"controller.{axis}.speed_mode"
    return slot in model.parameter_names and model.parameter(slot) > 0.5


#: how friction entered a linearisation (frictionless?) → the words of every title
FRICTION_WORDS = {True: "without friction (frictionless loops)",
                  False: "with friction linearised at steady sliding"}


@dataclass(frozen=True)
class LoopAnalysis:
    """Poles and loop margins of the drive linearised at one table speed.

    Parameters
    ----------
    poles : list of Pole
        The closed loop's poles (:func:`classify_poles`).
    loops : list of LoopResult
        Each loop opened at its injection point.
    linear : LinearModel
        The linear model they come from.
    """
    poles: list[Pole]
    loops: list[LoopResult]
    linear: LinearModel

    def dominant(self) -> Pole:
        """The least-damped oscillatory pole pair: the mode friction destabilises first.

        The rigid-body poles are not modes and are never it; without an oscillatory pole, the
        slowest real one.

        Returns
        -------
        Pole
            The dominant pole (Im > 0 for a pair).
        """
        return dominant_pole(self.poles)

    @property
    def friction(self) -> str:
        """How friction entered the linearisation, in the words every title uses (``loops``,
        its plots, the explorer): their margins differ by it — the CDFS at 1.5 mm/s has a
        3.02-dB gain margin without friction and 1.34 dB with it (issue 41 item 4)."""
        return FRICTION_WORDS[self.linear.frictionless]

    def __repr__(self) -> str:
        p = self.dominant()
        loops = "; ".join(f"{r.name} {_margins_text(r)}" for r in self.loops)
        return (f"<feeddrive LoopAnalysis at {_mm_s(self.linear.table_speed)}, "
                f"{self.friction}: least-damped mode {p.frequency_hz:.4g} Hz, "
                f"ζ {p.damping_ratio:.3g}; {loops}; .poles .loops .linear, .as_dict()>")

    def as_dict(self) -> dict[str, Any]:
        """The analysis for the JSON report (``feeddrive loops --json``).

        Returns
        -------
        dict
            Table speed [mm/s], the least-damped mode's frequency [Hz] and damping ratio [-], the
            pole rule, the poles (each pair once), the loops' margins and the notes.
        """
        d = self.dominant()
        return {
            "table_speed_mm_s": 1e3 * self.linear.table_speed,
            "frictionless": self.linear.frictionless,
            "friction": self.friction,
            "least_damped_mode": {"frequency_hz": d.frequency_hz,
                                  "damping_ratio": d.damping_ratio},
            "pole_rule": (f"rigid-body: |Re| and |Im| below {MARGINAL:g} × the fastest pole "
                          "(free motions no loop holds; no damping ratio); each complex pair "
                          "listed once (Im ≥ 0)"),
            "poles": [p.as_dict() for p in self.poles if p.imag >= 0],
            "loops": [lp.as_dict() for lp in self.loops],
            "notes": list(self.linear.notes),
        }


#: the fewest frequency points per decade a loop's grid has: the grid brackets each
#: crossing, located between its points (:func:`_margins`); 3 points in all missed the
#: resonance and read a 2.6-dB gain margin as 65.5 dB (an outside check, 2026-12-07)
MIN_POINTS_PER_DECADE = 10
#: the most frequencies a response or a loop analysis is evaluated at [-] (a linear solve
#: each)
MAX_FREQUENCIES = 1_000_000


def _check_frequencies(f_min: float, f_max: float, points: int) -> None:
    """The grid of :func:`loop_analysis`: 0 < f_min < f_max, finite, and a whole number of
    points, at least :data:`MIN_POINTS_PER_DECADE` a decade."""
    for name, value in (("f_min", f_min), ("f_max", f_max)):
        if not (is_real(value) and math.isfinite(value) and value > 0):  # NumPy's too
            raise ParameterError(name, value, "expected a finite frequency > 0 [Hz]")
    if not f_min < f_max:
        raise ParameterError("f_max", f_max, f"expected > f_min = {f_min:g} [Hz]")
    fewest = max(2, math.ceil(MIN_POINTS_PER_DECADE * math.log10(f_max / f_min)))
    if isinstance(points, bool) or not isinstance(points, int | np.integer) \
            or not fewest <= points <= MAX_FREQUENCIES:
        raise ParameterError("points", points, f"expected a whole number {fewest} … "
                             f"{MAX_FREQUENCIES} "
                             f"({MIN_POINTS_PER_DECADE} a decade of f_min … f_max at least) "
                             "[-]")


def loop_analysis(system: DriveSystem, table_speed: float = 1e-3, nut_speed: float = 0.0, *,
                  frictionless: bool = True, f_min: float = 0.5, f_max: float = 500.0,
                  points: int = 400) -> LoopAnalysis:
    """Poles and velocity/position loop transfers of every motor axis.

    The velocity loop is analysed with the position loop open (K_pp = 0).

    Parameters
    ----------
    system : DriveSystem
        The drive (continuous loops).
    table_speed : float, default 1e-3
        Steady table speed of the operating point [m/s].
    nut_speed : float, default 0
        Steady nut speed of the operating point [m/s] (DDFS).
    frictionless : bool, default True
        Linearise with every friction law set to "none".
    f_min : float, default 0.5
        Lowest frequency of the loop transfers [Hz].
    f_max : float, default 500
        Highest frequency [Hz].
    points : int, default 400
        Number of log-spaced frequencies.

    Returns
    -------
    LoopAnalysis
        Classified poles, the least-damped mode and each loop's margins, crossover and
        bandwidth.

    Examples
    --------
    The CDFS at mid-screw: its least-damped mode is the velocity loop's (frictionless, the
    default):

    >>> import feeddrive as fd
    >>> system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    >>> mode = fd.loop_analysis(system).dominant()
    >>> print(f"{mode.frequency_hz:.2f} Hz, damping ratio {mode.damping_ratio:.3f}")
    5.47 Hz, damping ratio 0.034
    """
    frictionless = check_flag("frictionless", frictionless)
    _check_frequencies(f_min, f_max, points)
    lin = linearize(system, table_speed, nut_speed, frictionless=frictionless)
    freq = np.logspace(np.log10(f_min), np.log10(f_max), points)
    w = 2 * np.pi * freq
    open_pos = replace(system, parameters=system.parameters.replace_path(
        "controller.position_gain", 0.0))
    lin_v = linearize(open_pos, table_speed, nut_speed, frictionless=frictionless)
    loops = []
    for axis in lin.axes:  # the controller axes the model declares, in order
        # a hollow motor on a speed loop (say) has no position loop
        if not _speed_loop_only(system, axis, table_speed, nut_speed):
            pair = (f"{axis}_speed_command_disturbance", f"{axis}_speed_command")
            S = _freq_response(lin, *pair, w)
            loops.append(_margins(freq, S, f"{axis} position loop",
                                  _at_frequency(lin, *pair), _dc_frequency(lin)))
        pair = (f"{axis}_current_command_disturbance", f"{axis}_current_command")
        S = _freq_response(lin_v, *pair, w)
        loops.append(_margins(freq, S, f"{axis} velocity loop",
                              _at_frequency(lin_v, *pair), _dc_frequency(lin_v)))
    return LoopAnalysis(poles=classify_poles(lin.poles()), loops=loops, linear=lin)


# ---------------------------------------------------------------- named frequency responses


#: the named transfers of :func:`frequency_response`: (input, output, what it is)
NAMED_RESPONSES: dict[str, tuple[str, str, str]] = {
    "tracking": ("table_position_reference", "table_position",
                 "table position per commanded table position, the command's speed "
                 "feed-forward included (position reference r with speed reference s·r)"),
    "following_error": ("table_position_reference", "following_error",
                        "following error per commanded table position (1 − tracking)"),
    "dynamic_compliance": ("load_force", "table_position",
                           "table position per load force on the table [m/N] (the load acts "
                           "against positive motion: a positive load pushes the table back)"),
    "disturbance_sensitivity": ("current_command_disturbance", "table_position",
                                "table position per current disturbance at the table-driving "
                                "motor's current command [m/A] (a motor torque disturbance "
                                "÷ K_t), loops closed"),
}


@dataclass(frozen=True)
class FrequencyResponse:
    """One transfer function evaluated on a frequency grid.

    Parameters
    ----------
    name : str
        The transfer's name.
    input : str
        Its input.
    output : str
        Its output.
    unit : str
        Unit of the response (output unit per input unit).
    frequency_hz : numpy.ndarray
        Frequency grid [Hz].
    response : numpy.ndarray
        Complex response at each frequency [unit].
    description : str, default ""
        What the transfer shows.
    notes : tuple of str, default ()
        Warnings carried from the linear model.
    """

    name: str
    input: str
    output: str
    unit: str
    frequency_hz: np.ndarray
    response: np.ndarray
    description: str = ""
    notes: tuple[str, ...] = ()

    def __repr__(self) -> str:
        f = self.frequency_hz
        return (f"<feeddrive FrequencyResponse {self.name}: {self.input} → {self.output} "
                f"[{self.unit}], {f.size} frequencies {f[0]:.3g}–{f[-1]:.4g} Hz; "
                ".response .magnitude_db .phase_deg>")

    @property
    def magnitude(self) -> np.ndarray:
        """|G(jω)| at each frequency, in :attr:`unit`."""
        return np.abs(self.response)

    @property
    def magnitude_db(self) -> np.ndarray:
        """20·log10 |G(jω)| at each frequency [dB]."""
        return 20 * np.log10(np.abs(self.response))

    @property
    def phase_deg(self) -> np.ndarray:
        """∠G(jω), unwrapped along the grid [deg]."""
        return np.degrees(np.unwrap(np.angle(self.response)))

    def as_dict(self) -> dict[str, Any]:
        """The response for the JSON report.

        Returns
        -------
        dict
            Names, unit, description, the grid [Hz], magnitude [unit], phase [deg] and notes.
        """
        return {"name": self.name, "input": self.input, "output": self.output,
                "unit": self.unit, "description": self.description,
                "frequency_hz": self.frequency_hz.tolist(),
                "magnitude": self.magnitude.tolist(), "phase_deg": self.phase_deg.tolist(),
                "notes": list(self.notes)}


def _axis_name(lin: LinearModel) -> str:
    """The table-driving motor axis: the mechanism's first axis (the screw motor, a linear
    motor, the rack-and-pinion's motor), the first whose inputs the linear model has."""
    if not lin.axes:
        raise ValueError("the linear model has no table-driving motor axis")
    return lin.axes[0]


#: the operating point a DriveSystem is linearised at when the caller names none
#: (:func:`frequency_response`): table speed [m/s], nut speed [m/s], frictionless
_DEFAULT_POINT = (1e-3, 0.0, True)


def _operating_point(system: DriveSystem | LinearModel, table_speed: float | None,
                     nut_speed: float | None, frictionless: bool | None
                     ) -> tuple[float, float, bool]:
    """The operating point to linearise a DriveSystem at, each argument left None taking its
    default (:data:`_DEFAULT_POINT`); for a LinearModel, already linearised at its own
    point, any of them given is refused naming it (they were dropped without a word: an
    earlier sweep, session 30).

    Raises
    ------
    ParameterError
        For the first of ``table_speed``, ``nut_speed``, ``frictionless`` given (not None)
        beside a LinearModel.
    """
    given = {"table_speed": table_speed, "nut_speed": nut_speed, "frictionless": frictionless}
    if isinstance(system, LinearModel):
        for name, value in given.items():
            if value is not None:
                raise ParameterError(name, value, "not with a LinearModel: it keeps the point "
                                     f"it was linearised at ({_mm_s(system.table_speed)} "
                                     f"table, v_n {_mm_s(system.nut_speed)}, frictionless "
                                     f"{system.frictionless}); expected None, or "
                                     f"linearize(system, {name}=…) for another")
    speed, nut, flag = _DEFAULT_POINT
    return (speed if table_speed is None else table_speed,
            nut if nut_speed is None else nut_speed,
            check_flag("frictionless", flag if frictionless is None else frictionless))


def frequency_response(system: DriveSystem | LinearModel, input: str,  # noqa: A002
                       output: str | None = None, frequency_hz: np.ndarray | None = None, *,
                       table_speed: float | None = None, nut_speed: float | None = None,
                       frictionless: bool | None = None) -> FrequencyResponse:
    """A transfer of the closed loop linearised at steady sliding (:func:`linearize`).

    Parameters
    ----------
    system : DriveSystem or LinearModel
        The drive (linearised at ``table_speed``, frictionless by default) or a linear model
        already made, at its own operating point (then ``table_speed``, ``nut_speed`` and
        ``frictionless`` are not given; loop gains need a DriveSystem).
    input : str
        A name of :data:`NAMED_RESPONSES` (``"tracking"``, ``"dynamic_compliance"``, …;
        ``output`` then omitted), a loop gain ``"<axis>_position_loop"`` /
        ``"<axis>_velocity_loop"`` (L = 1/S − 1 at the loop break, as :func:`loop_analysis`;
        the velocity loop with the position loop open), or any input of the linear model.
    output : str or None, default None
        Any output of the linear model (with an input name), e.g.
        ``frequency_response(system, "load_force", "table_position")``.
    frequency_hz : numpy.ndarray or None, default None
        Frequencies [Hz]; None: 200 log-spaced from 0.1 to 1000 Hz.
    table_speed : float or None, default None
        Steady table speed of the operating point [m/s]; None: 1e-3 for a DriveSystem.
    nut_speed : float or None, default None
        Steady nut speed of the operating point [m/s] (DDFS); None: 0 for a DriveSystem.
    frictionless : bool or None, default None
        Linearise with every friction law set to "none"; None: True for a DriveSystem.

    Returns
    -------
    FrequencyResponse
        Complex response, magnitude [dB] and phase [deg] over ``frequency_hz``, with its units.

    Raises
    ------
    ParameterError
        Among others, for ``table_speed``, ``nut_speed`` or ``frictionless`` given with a
        LinearModel: it keeps the operating point it was linearised at (:func:`linearize`
        another for another point).
    """
    if not isinstance(input, str):
        raise ParameterError("input", input, "expected a name (str): a response of "
                             "NAMED_RESPONSES, a loop gain '<axis>_position_loop' or an input "
                             "of the linear model; the operating point is a keyword, "
                             "frequency_response(system, 'tracking', table_speed=1.5e-3) [m/s]")
    if not (output is None or isinstance(output, str)):
        raise ParameterError("output", output, "expected None or the name (str) of an output "
                             "of the linear model")
    if not isinstance(system, DriveSystem | LinearModel):  # a bare AssertionError (session 29)
        raise ParameterError("system", type(system).__name__, "expected a DriveSystem, e.g. "
                             "DriveSystem(params, drive='cdfs', table_position=0.4), or the "
                             "LinearModel of linearize(system)")
    table_speed, nut_speed, frictionless = _operating_point(system, table_speed, nut_speed,
                                                            frictionless)
    if frequency_hz is None:
        freq = np.logspace(-1, 3, 200)
    else:  # ["a"] raised numpy's bare ValueError (an outside check, 2026-12-07); complex
        # ones were cast to their real part with a warning (session 29): refused below
        try:
            freq = real_array("frequency_hz", frequency_hz, "Hz")
        except ParameterError:
            freq = np.full(1, np.nan)
    if freq.ndim != 1 or not 0 < freq.size <= MAX_FREQUENCIES \
            or not np.all(np.isfinite(freq) & (freq > 0)):
        raise ParameterError("frequency_hz", frequency_hz, "expected a sequence of 1 … "
                             f"{MAX_FREQUENCIES} finite, positive frequencies [Hz]")
    w = 2 * np.pi * freq
    is_lin = isinstance(system, LinearModel)
    if input.endswith(("_position_loop", "_velocity_loop")) and output is None:
        if is_lin:
            raise ParameterError("system", "LinearModel", "a loop gain needs the DriveSystem "
                                 "(its velocity loop is linearised with the position loop open)")
        assert isinstance(system, DriveSystem)
        axis, _, kind = input.rpartition("_")[0].rpartition("_")
        lin = linearize(system, table_speed, nut_speed, frictionless=frictionless)
        if f"{axis}_current_command_disturbance" not in lin.inputs:
            raise ParameterError("input", input, "no such motor axis in this drive; expected "
                                 + ", ".join(f"{a}_{k}_loop" for a in _axes(lin)
                                             for k in ("position", "velocity")))
        if kind == "position" and _speed_loop_only(system, axis, table_speed, nut_speed):
            raise ParameterError("input", input, f"the {axis} axis runs a speed loop only "
                                 "(e.g. controller.nut_loop = speed): it has no position loop")
        # the loop broken where loop_analysis breaks it: the velocity loop at the current
        # command (the position loop open), the position loop at the speed command; the
        # response names that break (it named "<axis>_velocity_command…", no signal of the
        # model: an outside check, 2026-12-07)
        broken = "current" if kind == "velocity" else "speed"
        if kind == "velocity":
            open_pos = replace(system, parameters=system.parameters.replace_path(
                "controller.position_gain", 0.0))
            lin = linearize(open_pos, table_speed, nut_speed, frictionless=frictionless)
        S = _freq_response(lin, f"{axis}_{broken}_command_disturbance",
                           f"{axis}_{broken}_command", w)
        return FrequencyResponse(input, f"{axis}_{broken}_command_disturbance",
                                 f"{axis}_{broken}_command", "-", freq, 1.0 / S - 1.0,
                                 f"{axis} {kind}-loop gain L = 1/S − 1, broken at "
                                 f"{axis}_{broken}_command", lin.notes)
    if is_lin:
        assert isinstance(system, LinearModel)
        lin = system
    else:
        assert isinstance(system, DriveSystem)
        lin = linearize(system, table_speed, nut_speed, frictionless=frictionless)
    name, description = f"{input} → {output}", ""
    if input in NAMED_RESPONSES:
        if output is not None:
            raise ParameterError("output", output, f"{input!r} names its output; omit it")
        name = input
        inp, output, description = NAMED_RESPONSES[input]
        if inp == "current_command_disturbance":
            inp = f"{_axis_name(lin)}_current_command_disturbance"
    else:
        inp = input
    if inp not in lin.inputs:
        raise ParameterError("input", input, "expected one of " + ", ".join(
            [*NAMED_RESPONSES, *(f"{a}_{k}_loop" for a in _axes(lin)
                                 for k in ("position", "velocity")), *lin.inputs]))
    if output is None or output not in lin.outputs:
        raise ParameterError("output", output, "expected one of " + ", ".join(lin.outputs))
    resp = _freq_response(lin, inp, output, w)
    if name in ("tracking", "following_error"):
        # the profile commands the speed with the position: r and its rate s·r together
        resp = resp + 1j * w * _freq_response(lin, "table_speed_reference", output, w)
    out_unit, in_unit = unit_of(output), unit_of(inp)
    unit = "-" if out_unit == in_unit else f"{out_unit}/{in_unit}"
    return FrequencyResponse(name, inp, output, unit, freq, resp, description, lin.notes)


def _axes(lin: LinearModel) -> list[str]:
    return list(lin.axes)


# ---------------------------------------------------------------- stability band


@dataclass(frozen=True)
class StabilityBand:
    """Speeds at which steady sliding is linearly unstable, with the unstable mode.

    Parameters
    ----------
    intervals : list of (float, float)
        (lower, upper) edges of each unstable band [m/s]; an edge at the scan's end is that
        end, not an edge found (:attr:`edges_at_scan_ends`).
    mode_frequency_hz : list of float
        Frequency of the rightmost pole at each band's geometric middle √(lower·upper)
        (:attr:`mode_speed`) [Hz].
    speeds : numpy.ndarray
        The scanned speeds [m/s].
    max_real_part : numpy.ndarray
        Real part of the rightmost pole at each scanned speed [1/s].
    frequency_hz : numpy.ndarray
        Frequency of that pole [Hz].
    tolerance : float
        Bisection tolerance of the edges [m/s].
    nut_speed : float
        Nut speed of the scan [m/s].
    notes : tuple of str, default ()
        Warnings, e.g. the averaged model's (:func:`averaged`), and a band cut by the scan's
        range.
    mode_frequency_range_hz : list of (float, float), default []
        Lowest and highest frequency of the rightmost pole in each band [Hz], at the speeds
        evaluated in it: the scan's, and the edges' bisection's (within ``tolerance`` of each
        edge); an extreme inside the band is the grid's nearest point to it (the wang2021
        CDFS's 5.482-Hz top reads 5.479 on a 20-point scan, 5.473 on 10).
    """

    intervals: list[tuple[float, float]]  # (lower, upper) edges [m/s]
    mode_frequency_hz: list[float]  # of the rightmost pole, at each interval's √(lo·hi)
    speeds: np.ndarray  # scanned speeds [m/s]
    max_real_part: np.ndarray  # [1/s] rightmost pole at each scanned speed
    frequency_hz: np.ndarray  # of the rightmost pole
    tolerance: float  # [m/s] bisection tolerance of the edges
    nut_speed: float
    notes: tuple[str, ...] = ()  # e.g. the averaged model's warning (:func:`averaged`)
    mode_frequency_range_hz: list[tuple[float, float]] = field(default_factory=list)

    @property
    def mode_speed(self) -> list[float]:
        """The speed each band's :attr:`mode_frequency_hz` is taken at: its geometric middle
        √(lower·upper) [m/s] (of the part scanned, for a band cut by the scan's range)."""
        return [math.sqrt(lo * hi) for lo, hi in self.intervals]

    @property
    def edges_at_scan_ends(self) -> list[tuple[bool, bool]]:
        """Per band, whether its (lower, upper) edge is the scan's end rather than an edge
        found: steady sliding is unstable at the lowest (highest) speed scanned, so the band
        goes on below (above) it."""
        n = len(self.intervals)
        low = bool(self.max_real_part[0] > 0) if self.max_real_part.size else False
        high = bool(self.max_real_part[-1] > 0) if self.max_real_part.size else False
        return [(k == 0 and low, k == n - 1 and high) for k in range(n)]

    def edge_texts(self, digits: int = 3) -> list[tuple[str, str]]:
        """Each band's edges [mm/s] as printed, ``≤ low`` / ``≥ high`` where an edge is the
        scan's end (:func:`band_edge_texts`).

        Parameters
        ----------
        digits : int, default 3
            Decimals [mm/s].

        Returns
        -------
        list of (str, str)
            Per band, its lower and upper edge's text.
        """
        return band_edge_texts(self._bands_mm_s(), self.edges_at_scan_ends, digits)

    def text(self, digits: int = 3, unit: str = "") -> str:
        """The bands as one text, ``low–high`` each [mm/s], an edge at the scan's end marked
        ≤ / ≥ (:func:`bands_text`); "" for none.

        Parameters
        ----------
        digits : int, default 3
            Decimals [mm/s].
        unit : str, default ""
            Printed after each band (``"mm/s"``).

        Returns
        -------
        str
            The bands' text.
        """
        return bands_text(self._bands_mm_s(), self.edges_at_scan_ends, digits, unit)

    def _bands_mm_s(self) -> list[tuple[float, float]]:
        return [(1e3 * lo, 1e3 * hi) for lo, hi in self.intervals]

    def __repr__(self) -> str:
        bands = "; ".join(f"unstable {lo}–{hi} mm/s (mode {fr:.3g} Hz)"
                          for (lo, hi), fr in zip(self.edge_texts(), self.mode_frequency_hz,
                                                  strict=True)) or "stable at every speed"
        return (f"<feeddrive StabilityBand: {bands}; {self.speeds.size} speeds "
                f"{1e3 * self.speeds[0]:.3g}–{1e3 * self.speeds[-1]:.3g} mm/s scanned, "
                f"v_n {_mm_s(self.nut_speed)}; .intervals [m/s], .as_dict()>")

    def as_dict(self) -> dict[str, Any]:
        """The band for the JSON report (``feeddrive stability --json``).

        Returns
        -------
        dict
            The rule, nut speed, bands and edge tolerance [mm/s], which band edges are the
            scan's ends, the unstable modes' frequencies [Hz] with the speed each is taken at
            [mm/s] and their range over each band [Hz], the scan's range [mm/s] and size, and
            the notes.
        """
        return {
            "rule": "steady sliding is unstable where the closed loop linearised at that speed "
                    "(every friction site and bristle state) has a pole with positive real "
                    f"part (real poles below {MARGINAL:g} × the fastest pole are the free "
                    "rigid-body motions and are not counted)",
            "nut_speed_mm_s": 1e3 * self.nut_speed,
            "unstable_bands_mm_s": [[1e3 * lo, 1e3 * hi] for lo, hi in self.intervals],
            "unstable_band_edges_at_scan_ends": [list(e) for e in self.edges_at_scan_ends],
            "unstable_mode_frequency_hz": self.mode_frequency_hz,
            "unstable_mode_speed_mm_s": [1e3 * v for v in self.mode_speed],
            "unstable_mode_frequency_range_hz": [list(r) for r in self.mode_frequency_range_hz],
            "edge_tolerance_mm_s": 1e3 * self.tolerance,
            "scan_mm_s": [float(1e3 * self.speeds[0]), float(1e3 * self.speeds[-1]),
                          int(self.speeds.size)],
            "notes": list(self.notes),
        }


def band_edge_texts(bands_mm_s: Sequence[Sequence[float]], cut: Sequence[Sequence[bool]],
                    digits: int = 3) -> list[tuple[str, str]]:
    """Each unstable band's edges as every output prints them: ``≤ low`` / ``≥ high`` where
    the edge is the scan's end (:attr:`StabilityBand.edges_at_scan_ends`), not an edge found —
    the band goes on beyond it.

    Parameters
    ----------
    bands_mm_s : sequence of (float, float)
        (lower, upper) edge of each band [mm/s].
    cut : sequence of (bool, bool)
        Per band, whether its lower (upper) edge is the scan's end.
    digits : int, default 3
        Decimals [mm/s].

    Returns
    -------
    list of (str, str)
        Per band, its lower and upper edge's text (no unit).

    Examples
    --------
    >>> band_edge_texts([(0.17, 5.0)], [(False, True)], 2)
    [('0.17', '≥ 5.00')]
    """
    return [(f"{'≤ ' if cut_lo else ''}{lo:.{digits}f}",
             f"{'≥ ' if cut_hi else ''}{hi:.{digits}f}")
            for (lo, hi), (cut_lo, cut_hi) in zip(bands_mm_s, cut, strict=True)]


def bands_text(bands_mm_s: Sequence[Sequence[float]], cut: Sequence[Sequence[bool]],
               digits: int = 3, unit: str = "") -> str:
    """The unstable bands as one text, ``low–high`` each, comma-separated, an edge at the
    scan's end marked ≤ / ≥ (:func:`band_edge_texts`); "" for none.

    Parameters
    ----------
    bands_mm_s, cut, digits
        As :func:`band_edge_texts`.
    unit : str, default ""
        Printed after each band (``"mm/s"``), one space apart.

    Returns
    -------
    str
        The bands' text.

    Examples
    --------
    >>> bands_text([(0.01, 5.0)], [(True, True)], 2, "mm/s")
    '≤ 0.01–≥ 5.00 mm/s'
    """
    after = f" {unit}" if unit else ""
    return ", ".join(f"{lo}–{hi}{after}" for lo, hi in band_edge_texts(bands_mm_s, cut, digits))


def stored_band_cuts(bands_mm_s: Sequence[Sequence[float]],
                     scan: tuple[float, float] = protocol.LINEAR_SPEED_RANGE
                     ) -> list[tuple[bool, bool]]:
    """:attr:`StabilityBand.edges_at_scan_ends` of bands stored without it (the compensation
    study's rows keep ``[[lower, upper], …]`` [mm/s] of a scan of :func:`stability_band`'s
    default range): an edge at the scan's end *is* that end, as :func:`stability_band` gives
    it, while a bisected edge lies inside the scan, half a bisection step (≥ 0.5 ×
    ``tolerance``) from any scanned speed.

    Parameters
    ----------
    bands_mm_s : sequence of (float, float)
        (lower, upper) edge of each band [mm/s].
    scan : (float, float), default ``protocol.LINEAR_SPEED_RANGE``
        The scan's lowest and highest speed [m/s].

    Returns
    -------
    list of (bool, bool)
        Per band, whether its lower (upper) edge is the scan's end.

    Examples
    --------
    >>> stored_band_cuts([[0.01, 0.42], [1.1, 5.0]], (1e-5, 5e-3))
    [(True, False), (False, True)]
    """
    low, high = 1e3 * scan[0], 1e3 * scan[1]
    return [(math.isclose(lo, low, rel_tol=1e-9), math.isclose(hi, high, rel_tol=1e-9))
            for lo, hi in bands_mm_s]


def rightmost_pole(system: DriveSystem, v: float, nut_speed: float = 0.0
                   ) -> tuple[float, float]:
    """The rightmost pole of the closed loop linearised at one steady sliding speed.

    The marginal free-motion poles (:data:`MARGINAL`) are left out: this is the quantity
    :func:`stability_band` judges.

    Parameters
    ----------
    system : DriveSystem
        The drive (continuous loops).
    v : float
        Steady table speed [m/s].
    nut_speed : float, default 0.0
        Steady nut speed [m/s].

    Returns
    -------
    real : float
        Its real part [1/s]; positive means unstable.
    frequency : float
        Its frequency |Im|/(2π) [Hz].
    """
    live = [p for p in classify_poles(np.linalg.eigvals(state_matrix(system, v, nut_speed)))
            if not p.rigid_body]
    p = max(live, key=lambda q: q.real)
    return p.real, abs(p.imag) / (2 * np.pi)


def _check_tolerance(tolerance: float) -> None:
    """A band edge's bisection stops within ``tolerance``: 0 or less never stopped, NaN
    stopped at once with a wrong edge (an outside check, 2026-12-07)."""
    if not (is_real(tolerance) and math.isfinite(tolerance) and tolerance > 0):
        raise ParameterError("tolerance", tolerance, "expected a finite speed > 0 [m/s]")


def _check_range(system: DriveSystem, nut_speed: float, low: float, high: float,
                 points: int) -> None:
    """The scan's speeds [m/s], in m/s as given (they were refused in mm/s:
    ``low = 5.0: expected 0 < low < high = 0.01 [mm/s]`` for ``low=5e-3``), its top within the
    axis's speed limit, and its points; the system and the nut speed (an outside check,
    2026-12-07)."""
    from .critical import check_kinds, table_speed_limit

    check_kinds(system)
    low = check_speed("low", low)
    high = check_speed("high", high, limit=table_speed_limit(system))
    if not low < high:
        raise ParameterError("low", low, f"expected < high = {high:g} [m/s]")
    check_speed("nut_speed", nut_speed, sign="any")
    if not (isinstance(points, (int, np.integer)) and not isinstance(points, bool)
            and 2 <= points <= protocol.MAX_LINEAR_POINTS):
        raise ParameterError("points", points, f"expected a whole number 2 … "
                             f"{protocol.MAX_LINEAR_POINTS} (a scan needs two speeds to see a "
                             "change, and linearises the drive at each)")


def _bisect_edge(system: DriveSystem, nut_speed: float, a: float, b: float, unstable_a: bool,
                 tolerance: float,
                 seen: list[tuple[float, float, float]] | None = None) -> float:
    """The speed between ``a`` and ``b`` [m/s] where steady sliding changes from
    ``unstable_a`` to its opposite, bisected to ``tolerance`` [m/s]; each midpoint's
    (speed, real part, frequency) of the rightmost pole is added to ``seen``."""
    while b - a > tolerance:
        m = 0.5 * (a + b)
        real, freq = rightmost_pole(system, m, nut_speed)
        if seen is not None:
            seen.append((m, real, freq))
        if (real > 0) == unstable_a:
            a = m
        else:
            b = m
    return 0.5 * (a + b)


def stability_band(system: DriveSystem, nut_speed: float = 0.0, *,
                   low: float = protocol.LINEAR_SPEED_RANGE[0],
                   high: float = protocol.LINEAR_SPEED_RANGE[1],
                   points: int = protocol.LINEAR_POINTS, tolerance: float = 1e-6,
                   progress: Any = None) -> StabilityBand:
    """Speeds at which steady sliding is linearly unstable.

    Scans table speeds from ``low`` to ``high`` (log-spaced; the default is
    ``feeddrive.analysis.protocol.LINEAR_SPEED_RANGE``), then bisects every stable/unstable
    change to ``tolerance``.

    Parameters
    ----------
    system : DriveSystem
        The drive (continuous loops).
    nut_speed : float, default 0
        Nut speed of every operating point [m/s] (DDFS).
    low : float, default 1e-5
        Lowest table speed scanned [m/s].
    high : float, default 5e-3
        Highest table speed scanned [m/s].
    points : int, default 40
        Number of scanned speeds (at least 2).
    tolerance : float, default 1e-6
        Resolution of the bisected band edges [m/s].
    progress : callable or None, default None
        Called as ``progress(done, total)`` after each operating point.

    Returns
    -------
    StabilityBand
        The unstable intervals with the unstable mode's frequency, and the scan.

    Examples
    --------
    Steady sliding of the CDFS at mid-screw is linearly unstable between 0.17 and 1.40 mm/s:

    >>> import feeddrive as fd
    >>> band = fd.stability_band(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4))
    >>> [(round(1e3 * lo, 2), round(1e3 * hi, 2)) for lo, hi in band.intervals]
    [(0.17, 1.4)]
    """
    _check_range(system, nut_speed, low, high, points)
    _check_tolerance(tolerance)
    check_callback("progress", progress, "progress(done, total)")
    speeds = np.geomspace(low, high, points)
    re = np.empty(points)
    fr = np.empty(points)
    for k, v in enumerate(speeds):
        re[k], fr[k] = rightmost_pole(system, float(v), nut_speed)
        if progress is not None:
            progress(k + 1, points)
    unstable = re > 0
    edges: list[float] = []
    seen = [(float(v), float(r), float(f)) for v, r, f in zip(speeds, re, fr, strict=True)]
    for k in range(points - 1):
        if unstable[k] != unstable[k + 1]:
            edges.append(_bisect_edge(system, nut_speed, float(speeds[k]), float(speeds[k + 1]),
                                      bool(unstable[k]), tolerance, seen))
    intervals: list[tuple[float, float]] = []
    start = float(speeds[0]) if unstable[0] else None
    it = iter(edges)
    for k in range(points - 1):
        if unstable[k] != unstable[k + 1]:
            e = next(it)
            if unstable[k + 1]:
                start = e
            else:
                intervals.append((start if start is not None else float(speeds[0]), e))
                start = None
    if start is not None:
        intervals.append((start, float(speeds[-1])))
    # the mode's frequency at the band's geometric middle (said: StabilityBand.mode_speed),
    # and its range over the band from the speeds already evaluated in it — it is not one
    # number: 5.38 Hz at the CDFS band's lower edge, 5.48 at 0.8 mm/s, 5.45 at the upper edge
    freqs = [rightmost_pole(system, math.sqrt(lo * hi), nut_speed)[1] for lo, hi in intervals]
    ranges = []
    for lo, hi in intervals:
        inside = [f for v, r, f in seen if lo <= v <= hi and r > 0]
        ranges.append((min(inside), max(inside)))
    band = StabilityBand(intervals=intervals, mode_frequency_hz=freqs, speeds=speeds,
                         max_real_part=re, frequency_hz=fr, tolerance=tolerance,
                         nut_speed=nut_speed, mode_frequency_range_hz=ranges)
    notes = list(averaged(system)[1])
    if intervals and band.edges_at_scan_ends[0][0]:
        notes.append(f"steady sliding is unstable at the scan's lowest speed, "
                     f"{1e3 * float(speeds[0]):g} mm/s: the band's lower edge is below it, "
                     "not found (scan lower); the band is given from that speed")
    if intervals and band.edges_at_scan_ends[-1][1]:
        notes.append(f"steady sliding is unstable at the scan's highest speed, "
                     f"{1e3 * float(speeds[-1]):g} mm/s: the band's upper edge is above it, "
                     "not found (scan higher); the band is given up to that speed")
    return replace(band, notes=tuple(notes))


def upper_band_edge(system: DriveSystem, nut_speed: float = 0.0, *,
                    low: float = protocol.LINEAR_SPEED_RANGE[0],
                    high: float = protocol.LINEAR_SPEED_RANGE[1],
                    points: int = protocol.LINEAR_POINTS, tolerance: float = 1e-6) -> float:
    """The upper edge of the highest linearly unstable band: ``stability_band(...)``'s
    ``intervals[-1][1]``, bit for bit, with the operating points that edge needs only.

    The scan goes down from ``high`` over the same grid and stops at its first unstable speed;
    only the band's top change is bisected (the same midpoints), and no lower edge or mode
    frequency is computed: on the report's sensitivity grid 15 linearisations instead of 37.
    A steady state not found at a speed below the top band, which makes
    :func:`stability_band` raise, is not looked for here.

    Parameters
    ----------
    system : DriveSystem
        The drive (continuous loops).
    nut_speed : float, default 0
        Nut speed of every operating point [m/s] (DDFS).
    low : float, default 1e-5
        Lowest table speed scanned [m/s].
    high : float, default 5e-3
        Highest table speed scanned [m/s].
    points : int, default 40
        Number of scanned speeds (at least 2).
    tolerance : float, default 1e-6
        Resolution of the bisected edge [m/s].

    Returns
    -------
    float
        The edge [m/s]; ``high`` when steady sliding is unstable there, NaN when it is stable
        at every scanned speed.
    """
    _check_range(system, nut_speed, low, high, points)
    _check_tolerance(tolerance)
    speeds = np.geomspace(low, high, points)
    for k in range(points - 1, -1, -1):
        if rightmost_pole(system, float(speeds[k]), nut_speed)[0] > 0:
            break
    else:
        return math.nan
    if k == points - 1:
        return float(speeds[-1])
    return _bisect_edge(system, nut_speed, float(speeds[k]), float(speeds[k + 1]), True,
                        tolerance)


__all__ = ["INPUT_UNITS", "MARGINAL", "NAMED_RESPONSES", "OUTPUT_UNITS", "FrequencyResponse",
           "LinearModel", "LoopAnalysis", "LoopResult", "Pole", "StabilityBand", "averaged",
           "band_edge_texts", "bands_text", "classify_poles", "dominant_pole",
           "frequency_response", "linearize", "loop_analysis", "margin_text", "rightmost_pole",
           "stability_band", "state_matrix", "steady_state", "stored_band_cuts", "unit_of",
           "upper_band_edge"]
