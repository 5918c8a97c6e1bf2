"""Open-loop replay: a measured signal drives the model, the controller loops bypassed.

A replay is a profile (it takes the reference profile's place in ``simulate`` and ``fit``):
its time series reaches the generated code as data in ``T`` — a piecewise-linear table whose
breakpoints are the record's own sample instants (irregular steps kept, no resampling),
declared to the dense-output integrators as step ends — and the generated right-hand side
reads it through :func:`replay_value`, never through a Python callback.  What it imposes:

* :class:`CurrentReplay` — the current [A] of the motor that drives the table; its torque
  (or a linear motor's force) is K·i;
* :class:`TorqueReplay` — that motor's torque [N m] (a linear motor's force [N]): i = τ/K_t;
* :class:`ForceReplay` — the motor's force referred to the table through the transmission
  [N] (the "motor force" of a rig record such as EMPS's ``vir``): i = F·H/K_t, H the table
  travel per motor radian (a linear motor: i = F/K_f).  It is the force the motor applies,
  not a load-cell force measured after the drive's compliance;
* :class:`MotorSpeedReplay` — the motor's speed [rad/s] (the motor side a kinematic input):
  the coupling, screw or mesh compliance, the table and the friction that acts on them are
  simulated; motor-side friction and the motor's current then do not act.

The imposed state keeps its start value (its rate is 0); the imposed value is the output
``replay_input`` [the role's SI unit].  The axis' loops still compute their commands, but
their integrators are frozen and nothing they command reaches the mechanics.  The reference
is zero.  A drive whose table is driven by two motors (DDFS) has no single current, torque or
force path; a drive with no motor shaft (the linear motor) has no motor speed apart from the
table's: both are refused in one line, as is a drive with its motor torque off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from .._jit import kernel
from ..parameters import ParameterError
from .reference import KIND, REF_CONSTANT, TABLE_COLUMNS, TABLE_OFFSET

#: the local variable of the generated code that holds the replayed value [SI]
REPLAY_VARIABLE = "replay_u"


@kernel
def replay_value(t: float, P: np.ndarray, o: int, T: np.ndarray) -> float:
    """The replayed signal at time t, interpolated linearly between its samples.

    ``P[o:]`` is the profile block; its table (``T[to:to + 4n]``, rows: sample instants [s],
    values, zeros, zeros) has the record's instants as breakpoints.  Before the first and
    after the last sample the end values are held.

    Parameters
    ----------
    t : float
        Time [s].
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the profile block in ``P``.
    T : numpy.ndarray
        The packed tables [SI].

    Returns
    -------
    float
        The signal at t [the role's SI unit].
    """
    to = int(P[o + TABLE_OFFSET])
    n = int(P[o + TABLE_COLUMNS])
    if t <= T[to]:
        return T[to + n]
    if t >= T[to + n - 1]:
        return T[to + 2 * n - 1]
    lo, hi = 0, n - 1
    while hi - lo > 1:  # bisection over the sample instants
        mid = (lo + hi) // 2
        if T[to + mid] <= t:
            lo = mid
        else:
            hi = mid
    t0, t1 = T[to + lo], T[to + hi]
    v0, v1 = T[to + n + lo], T[to + n + hi]
    return v0 + (v1 - v0) * (t - t0) / (t1 - t0)


@dataclass(frozen=True, eq=False)
class Replay:
    """A measured time series that drives the model (see the module).

    Parameters
    ----------
    time : numpy.ndarray
        Increasing sample instants from 0 [s] (irregular steps allowed).
    value : numpy.ndarray
        The signal at each instant [SI unit of the role].
    speed_scale : float, default 0.0
        The largest table speed the run is expected to reach [m/s]: the run's speed scale
        (default tolerances, divergence bound), since a replay commands no speed.  0: the
        engine's floor, and a run that reaches the floor's divergence bound (0.1 m/s) is
        refused (``SimulationError``), not ended early.
    """

    time: np.ndarray
    value: np.ndarray
    speed_scale: float = 0.0
    #: the role's name (``--input``) and its SI unit
    role: ClassVar[str] = ""
    unit: ClassVar[str] = ""

    @property
    def table_speed(self) -> float:
        """The speed scale [m/s] (``engine.simulate.command_speed`` reads it); not a command."""
        return float(self.speed_scale)

    def _checked(self) -> tuple[np.ndarray, np.ndarray]:
        t = np.asarray(self.time, dtype=float)
        v = np.asarray(self.value, dtype=float)
        if t.ndim != 1 or t.size < 2 or v.shape != t.shape:
            raise ParameterError(f"replay.{self.role}", f"{t.size} instants, {v.size} values",
                                 "expected two 1-D arrays of one length ≥ 2")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
            raise ParameterError(f"replay.{self.role}", "non-finite samples",
                                 f"expected finite times [s] and values [{self.unit}]")
        if abs(t[0]) > 1e-12 or np.any(np.diff(t) <= 0):
            raise ParameterError("replay.time", f"{t[0]:g} … {t[-1]:g} s",
                                 "expected strictly increasing instants from 0 [s]")
        if not (math.isfinite(self.speed_scale) and self.speed_scale >= 0):
            raise ParameterError("replay.speed_scale", self.speed_scale, "expected ≥ 0 [m/s]")
        return t, v

    def encode(self) -> tuple[dict[int, float], np.ndarray]:
        """The replay as (profile slots, data table): a zero reference and a 4 × n table.

        Returns
        -------
        tuple of (dict, numpy.ndarray)
            The profile block's slots (a constant zero reference) and the table (rows:
            sample instants [s], values [SI], two zero rows: the nut's, which the reference
            kernel's checks read).
        """
        t, v = self._checked()
        table = np.zeros((4, t.size))
        table[0], table[1] = t, v
        return {KIND: REF_CONSTANT}, table

    def breakpoints(self, t_end: float) -> np.ndarray:
        """The sample instants inside (0, t_end): every one a kink of the interpolant.

        Parameters
        ----------
        t_end : float
            End of the run [s].

        Returns
        -------
        numpy.ndarray
            The instants [s].
        """
        t = np.asarray(self.time, dtype=float)
        return t[(t > 0.0) & (t < t_end)]

    @classmethod
    def imposed(cls, mech: Any) -> tuple[str, str]:
        """The state this replay imposes and the motor axis it acts on.

        Parameters
        ----------
        mech : Mechanism
            The drive's topology.

        Returns
        -------
        tuple of (str, str)
            (state name, axis name).

        Raises
        ------
        ParameterError
            For a drive without a single motor path for this role.
        """
        if mech.params.controller.mode == "torque_off":
            raise ParameterError("controller.mode", "torque_off",
                                 f"a {cls.role} replay drives the motor; expected 'cascade'")
        axes = mech.live_axes()
        if len(axes) != 1:
            raise ParameterError(f"--input {cls.role}", mech.drive,
                                 f"the {mech.drive.upper()} drives its table with {len(axes)} "
                                 f"motors ({', '.join(axes)}): no single {cls.role} path; "
                                 "expected a drive with one motor on the table")
        return f"{axes[0]}_current", axes[0]

    def scale_code(self, b: Any, mech: Any, axis: str) -> str:
        """Code of the factor that turns the replayed value into the imposed state.

        Parameters
        ----------
        b : Builder
            The model builder (the factor reads parameter slots, so a fitted K_t or H
            moves it).
        mech : Mechanism
            The drive's topology.
        axis : str
            The motor axis.

        Returns
        -------
        str
            The code [SI: imposed state per replayed unit]; ``"1.0"`` for a current or speed.
        """
        return "1.0"


class CurrentReplay(Replay):
    """The measured motor current [A] drives the model (module docstring).

    Parameters
    ----------
    time : numpy.ndarray
        Increasing sample instants from 0 [s].
    value : numpy.ndarray
        The signal at each instant [A].
    speed_scale : float, default 0.0
        The largest table speed the run is expected to reach [m/s] (:class:`Replay`).
    """

    role = "current"
    unit = "A"


class TorqueReplay(Replay):
    """The measured motor torque [N m] (a linear motor's force [N]) drives the model.

    Parameters
    ----------
    time : numpy.ndarray
        Increasing sample instants from 0 [s].
    value : numpy.ndarray
        The signal at each instant [N m].
    speed_scale : float, default 0.0
        The largest table speed the run is expected to reach [m/s] (:class:`Replay`).
    """

    role = "torque"
    unit = "N m"

    def scale_code(self, b: Any, mech: Any, axis: str) -> str:  # i = τ / K_t
        return f"1.0 / {b.p(mech.motor_output(axis)[0])}"


class ForceReplay(Replay):
    """The motor's force referred to the table [N] drives the model: i = F·H/K_t.

    Parameters
    ----------
    time : numpy.ndarray
        Increasing sample instants from 0 [s].
    value : numpy.ndarray
        The signal at each instant [N].
    speed_scale : float, default 0.0
        The largest table speed the run is expected to reach [m/s] (:class:`Replay`).
    """

    role = "force"
    unit = "N"

    def scale_code(self, b: Any, mech: Any, axis: str) -> str:
        return f"{b.p(f'controller.{axis}.H')} / {b.p(mech.motor_output(axis)[0])}"


class MotorSpeedReplay(Replay):
    """The measured motor speed [rad/s] drives the mechanism (the motor side kinematic).

    Parameters
    ----------
    time : numpy.ndarray
        Increasing sample instants from 0 [s].
    value : numpy.ndarray
        The signal at each instant [rad/s].
    speed_scale : float, default 0.0
        The largest table speed the run is expected to reach [m/s] (:class:`Replay`).
    """

    role = "speed"
    unit = "rad/s"

    @classmethod
    def imposed(cls, mech: Any) -> tuple[str, str]:
        """The motor's speed state (the rate state of its angle) and its axis.

        Parameters
        ----------
        mech : Mechanism
            The drive's topology.

        Returns
        -------
        tuple of (str, str)
            (state name, axis name).

        Raises
        ------
        ParameterError
            For a drive whose motor has no shaft apart from the table.
        """
        _, axis = super().imposed(mech)
        motor = next((m for m in mech.drive_motors if m.name == axis), None)
        rates = mech.steady_motion(0.0, 0.0)
        if motor is None or not motor.angle or motor.angle not in rates:
            raise ParameterError("--input speed", mech.drive,
                                 f"the {mech.drive} drive has no motor shaft apart from the "
                                 "table (its motor speed is the table's): expected a drive "
                                 "with a motor shaft (cdfs, rack-pinion)")
        return rates[motor.angle][0], axis


#: replay classes by role (``fit --input``)
REPLAYS: dict[str, type[Replay]] = {cls.role: cls for cls in (
    CurrentReplay, TorqueReplay, ForceReplay, MotorSpeedReplay)}


def declare_replay(b: Any, replay: Replay, mech: Any) -> tuple[str, str]:
    """Before the mechanism declares itself: make every read of the imposed state read the
    replayed value (:attr:`Builder.imposed <feeddrive.model.codegen.Builder.imposed>`).

    Parameters
    ----------
    b : Builder
        The model builder.
    replay : Replay
        The replay.
    mech : Mechanism
        The drive's topology.

    Returns
    -------
    tuple of (str, str)
        The imposed state's and the motor axis' names.
    """
    if b.namespace:
        raise ParameterError("profile", type(replay).__name__,
                             "a replay drives a single drive, not an axis of a machine")
    state, axis = replay.imposed(mech)
    b.imposed[b.q(state)] = REPLAY_VARIABLE
    b.add_aux("replay_input", replay.unit, f"the replayed {replay.role} (open-loop input)")
    return state, axis


def emit_replay_value(b: Any, replay: Replay, mech: Any, axis: str, profile_offset: int) -> None:
    """Write the replayed value's line at the head of the right-hand side and of the sampled
    update (before any part reads the imposed state).

    Parameters
    ----------
    b : Builder
        The model builder.
    replay : Replay
        The replay.
    mech : Mechanism
        The drive's topology.
    axis : str
        The motor axis.
    profile_offset : int
        Offset of the profile block in ``P``.
    """
    value = f"{b.use(replay_value)}({{t}}, P, {profile_offset}, T)"
    line = f"{{{REPLAY_VARIABLE}}} = {replay.scale_code(b, mech, axis)} * {value}"
    b.emit(line)
    b.emit(line, sampled=True)
    b.emit(f"{{replay_input}} = {value}")


def emit_replay_rates(b: Any, state: str, axis: str) -> None:
    """After the mechanism's equations: the imposed state and the axis' loop integrators
    keep their values (the loops bypassed); with the speed imposed, the current too.

    Parameters
    ----------
    b : Builder
        The model builder.
    state : str
        The imposed state.
    axis : str
        The motor axis.
    """
    for name in dict.fromkeys((state, f"{axis}_current", f"{axis}_velocity_integral",
                               f"{axis}_current_integral")):
        b.emit(f"{{der({name})}} = 0.0")
