"""Mechanisms: bodies, compliant couplings and where motors, friction and disturbances act.

A mechanism is registered by drive name (``"cdfs"``, ``"ddfs"``, ``"linear-motor"``).  It
declares its states, parameters, friction sites, motors and controller axes to a
:class:`~feeddrive.model.codegen.Builder`, and writes its equations with the friction and
disturbance terms the assembler hands it per body.  Its code names the signals it reads and
writes in braces (``{der(table_position)} = {v_t}``, :meth:`Builder.emit
<feeddrive.model.codegen.Builder.emit>`); the assembler derives from that text alone what each
value is computed from, and the Jacobian's pattern from that.  Class attributes declare the
rest of its structure: its motors (:class:`DriveMotor`, for torque ripple), the table's travel,
whether the model depends on the table position.  The interface is :class:`Mechanism`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ... import registry

if TYPE_CHECKING:
    from ...parameters import DriveParameters
    from ..codegen import Builder, Line
    from ..loops import Axis, Channel


@dataclass
class Body:
    """The force terms of one body's equation of motion, in the order they are summed.

    Each term is a code fragment ``"+ expr"`` or ``"- expr"`` [N or N m].

    Parameters
    ----------
    drive : list of str
        Motor torque or coupling force, first.
    external : list of str
        Friction and disturbance terms.
    reaction : list of str
        Coupling reactions, last.
    """

    drive: list[str] = field(default_factory=list)  # motor torque / coupling force first
    external: list[str] = field(default_factory=list)  # friction, disturbances
    reaction: list[str] = field(default_factory=list)  # coupling reactions last

    def expression(self) -> str:
        """The body's net force as one code expression, terms joined in order.

        Returns
        -------
        str
            The sum (``"0.0"`` for a body with no terms) [N or N m].
        """
        terms = self.drive + self.external + self.reaction
        if not terms:
            return "0.0"
        text = terms[0].removeprefix("+ ")
        for t in terms[1:]:
            text += f" {t}"
        return text


@dataclass(frozen=True)
class Site:
    """A friction site the mechanism places: on one body, or between two (relative sliding).

    Parameters
    ----------
    name : str
        The site's name in the model (``"screw"``, ``"ball_nut"``, …).
    parameters_key : str
        ``friction.<key>`` of the parameter set, or a dotted path to a part's own section
        (``rack_pinion.gearbox_friction``).
    speed : str
        Code of the sliding speed at the site, signals in braces (``"P[3] * {w_s}"``) [m/s]
        (linear-equivalent for rotary sites).
    bodies : tuple of (str, str)
        (body, factor code) pairs: each body's equation gets the term −factor·F.
    scale : float, default 1.0
        Share of the site's friction acting here [-] (the ball–nut split).
    active : str, default ""
        Code of the condition under which the site acts; empty for always.
    rotary : bool, default False
        On a shaft: its torque stored as force at the lever (torque ÷ H).
    """

    name: str  # e.g. "screw", "ball_nut"
    parameters_key: str  # friction.<key> in the parameter set, or a dotted path to them
    speed: str  # code of the sliding speed [m/s]
    bodies: tuple[tuple[str, str], ...]  # (body, factor code) pairs: term = − factor·F
    scale: float = 1.0  # share of the site's friction (ball–nut split)
    active: str = ""  # condition under which the site acts ("" = always)
    rotary: bool = False  # on a shaft, its torque stored as force at the lever (torque ÷ H)

    def parameters(self, params: DriveParameters) -> Any:
        """The site's parameters: ``friction.<parameters_key>``, or the dotted path
        ``parameters_key`` names (a part's own section, e.g. ``rack_pinion.gearbox_friction``).

        Parameters
        ----------
        params : DriveParameters
            The parameter set.

        Returns
        -------
        SiteParameters
            The site's friction parameters.
        """
        obj: Any = params if "." in self.parameters_key else params.friction
        for part in self.parameters_key.split("."):
            obj = getattr(obj, part)
        return obj


@dataclass(frozen=True)
class DriveMotor:
    """A motor of a mechanism as the disturbances see it (:attr:`Mechanism.drive_motors`).

    Parameters
    ----------
    name : str
        Its key, e.g. ``"screw"``: its ripple signal is ``<name>_ripple_torque`` [N m].
    angle : str
        The state of its rotor angle [rad] ("" for a linear motor).
    body : str
        The body its torque acts on (a key of :attr:`Mechanics.forces`).
    ripple : str, default ""
        The ``[disturbances]`` field of its torque ripple ("" = not modelled: a ripple given
        for this drive is refused).
    label : str, default ""
        Its name in messages, e.g. ``"hollow motor"`` ("" = ``"<name> motor"``).
    """

    name: str
    angle: str
    body: str
    ripple: str = ""
    label: str = ""


@dataclass
class Mechanics:
    """What the assembler hands a mechanism to write its equations with.

    Code is written with its signals in braces (:meth:`Builder.emit
    <feeddrive.model.codegen.Builder.emit>`), so what it reads travels with it.

    Parameters
    ----------
    forces : dict of str to list of str
        Per body, the external force terms (friction, disturbances) [N or N m].
    always : list of Line
        Code lines of the friction sites that always act.
    gated : list of Line
        Code lines of the sites gated by their ``active`` condition.
    frozen : list of str
        Code lines that freeze the states of gated sites while they are off.
    ripple : dict of str to str
        Per motor, the code of its torque-ripple term [N m].
    lead : tuple of (int, int) or None
        Parameter offsets of the lead-error disturbance, if any.
    load : str or None
        Code of the external load force on the table [N], if any.
    torque_off : bool
        Whether the motor torque is switched off (free-running studies).
    """

    forces: dict[str, list[str]]
    always: list[Line]
    gated: list[Line]
    frozen: list[str]
    ripple: dict[str, str]
    lead: tuple[int, int] | None
    load: str | None
    torque_off: bool


class Mechanism:
    """Interface of a drive topology: bodies, couplings and where motors and friction act.

    A subclass sets ``drives`` (its registered names) and implements :meth:`declare`,
    :meth:`parameters`, :meth:`sites`, :meth:`motors`, :meth:`axes` and :meth:`emit`; see
    :class:`~feeddrive.model.mechanisms.ball_screw.BallScrewDrive` and
    :class:`~feeddrive.model.mechanisms.linear_motor.LinearMotorDrive`.

    Parameters
    ----------
    params : DriveParameters
        The parameter set [SI].
    drive : str
        The drive name the model is built for (one of ``drives``).
    table_position : float
        Table position along the axis at the start [m].
    nut_hold : str
        How a held nut is held (``"locked"`` or ``"servo"``); read only by a drive that holds
        one (:meth:`held_part`); ``"servo"`` on any other is refused
        (``feeddrive.model.mechanisms.base.check_nut_hold``).
    """

    drives: tuple[str, ...] = ()
    #: the parameter set a command uses for this drive when none is named
    example_preset: str = "wang2021"
    #: a drive with one motor: (slot of its torque or force constant, the output name of
    #: constant × current); None: per axis, ``<axis>_motor.torque_constant``
    single_motor: tuple[str, str] | None = None
    published: bool = True  # a published model: its docstring has a References section
    #: its motors: rotor-angle state, the body driven, the disturbance field of its ripple
    drive_motors: tuple[DriveMotor, ...] = ()
    has_lead_screw = False
    #: dotted parameter path of the table's travel [m] (the ball screw's ``screw.length``);
    #: "" = no travel limit known (a run's summary warns when the table leaves it)
    travel_length: str = ""
    travel_ends: str = ""  # what bounds that travel, for messages ("the screw supports")
    #: whether the model depends on the table's position (the ball screw's K_eq(a)); a run's
    #: header names the position only then
    uses_table_position = False
    #: the controller axis whose motor drives the table (its current is ``<axis>_current``,
    #: its torque constant the slot :meth:`motor_output` names)
    table_axis: str = "motor"
    #: the reference signals beyond the table's that this topology's controller axes can
    #: follow, each with its axis (a profile's ``<signal>_speed``, an FMU's
    #: ``<signal>_*_reference`` inputs); none by default (:meth:`followed_references`)
    reference_axes: dict[str, str] = {}
    #: what this topology's own parameter sections describe, for messages ("ball screw")
    part_name: str = ""
    #: the parameter-file sections only this topology reads (its parts beyond the table,
    #: friction, controller and disturbances every drive has)
    own_sections: tuple[str, ...] = ()

    def __init__(self, params: DriveParameters, drive: str, table_position: float,
                 nut_hold: str) -> None:
        self.params = params
        self.drive = drive
        self.table_position = table_position
        self.nut_hold = nut_hold

    @classmethod
    def check(cls, params: DriveParameters, drive: str, table_position: float) -> None:
        """Refuse a system this topology cannot represent, before the model is built.

        Parameters
        ----------
        params : DriveParameters
            The parameter set [SI].
        drive : str
            The drive name.
        table_position : float
            Table position at the start [m].

        Raises
        ------
        ParameterError
            One line naming the field, the value and what was expected.
        """

    @classmethod
    def drive_label(cls, drive: str) -> str:
        """How messages name one of this topology's drives.

        Parameters
        ----------
        drive : str
            One of :attr:`drives`.

        Returns
        -------
        str
            E.g. ``"a linear-motor drive"`` (the default form).
        """
        return f"a {drive} drive"

    def live_axes(self) -> tuple[str, ...]:
        """The controller axes that run in this drive (the motors of :attr:`drive_motors`
        less the idle axes of :meth:`held`).

        Returns
        -------
        tuple of str
            Axis names, in the order of :attr:`drive_motors`.
        """
        idle = self.held()[1]
        return tuple(m.name for m in self.drive_motors if m.name not in idle)

    @classmethod
    def followed_references(cls, drive: str) -> tuple[str, ...]:
        """The reference signals of :attr:`reference_axes` that ``drive`` follows when a
        profile commands them (a signal not listed must be commanded 0: :meth:`check_profile`).

        Parameters
        ----------
        drive : str
            One of :attr:`drives`.

        Returns
        -------
        tuple of str
            Signal names; by default every signal of :attr:`reference_axes`.
        """
        return tuple(cls.reference_axes)

    def follows(self, signal: str) -> bool:
        """Whether this drive follows the reference ``signal`` (:meth:`followed_references`).

        Parameters
        ----------
        signal : str
            A reference signal's name.

        Returns
        -------
        bool
            True when a profile may command it.
        """
        return signal in self.followed_references(self.drive)

    @classmethod
    def held_part(cls, drive: str) -> str:
        """The part ``drive`` holds still whose hold a setting chooses (the CDFS's nut, held
        ``"locked"`` or on its ``"servo"``: the ``nut_hold`` argument), or "" when it holds
        none (the default): then no hold setting has an effect
        (``feeddrive.model.mechanisms.base.check_nut_hold``).

        Parameters
        ----------
        drive : str
            One of :attr:`drives`.

        Returns
        -------
        str
            The part's name, or "".
        """
        return ""

    def held_parameters(self) -> tuple[tuple[str, ...], str]:
        """The parameters that cannot act in this drive because a part is held still.

        Returns
        -------
        paths : tuple of str
            Dotted parameter paths or section prefixes (``"hollow_motor"``,
            ``"friction.nut"``); empty by default.
        reason : str
            Why, for messages.
        """
        return (), ""

    def acting_sites(self) -> list[Site]:
        """The friction sites that act in this drive: :meth:`sites` as declared, less those
        whose states :meth:`held` freezes.

        Returns
        -------
        list of Site
            The sites, in declaration order.
        """
        from ..codegen import Builder

        b = Builder()
        self.declare(b)
        self.parameters(b)
        frozen = self.held()[0]
        return [s for s in self.sites(b)
                if not any(f"{s.name}_".startswith(p) for p in frozen)]

    def declare(self, b: Builder) -> None:
        """Declare the mechanism's states (name, unit, meaning, tolerance class) to the builder.

        Parameters
        ----------
        b : Builder
            The model builder the mechanism declares to and writes code through.
        """
        raise NotImplementedError

    def parameters(self, b: Builder) -> None:
        """Declare the mechanism's named parameter slots (masses, inertias, stiffnesses) [SI].

        Parameters
        ----------
        b : Builder
            The model builder the mechanism declares to and writes code through.
        """
        raise NotImplementedError

    def sites(self, b: Builder) -> list[Site]:
        """Place the friction sites of this topology.

        Parameters
        ----------
        b : Builder
            The model builder the mechanism declares to and writes code through.

        Returns
        -------
        list of Site
            The sites, each with its sliding speed and the bodies its force acts on.
        """
        raise NotImplementedError

    def motors(self, b: Builder) -> None:
        """Declare the motors' electrical states (their currents [A]).

        Parameters
        ----------
        b : Builder
            The model builder the mechanism declares to and writes code through.
        """
        raise NotImplementedError

    def axes(self, b: Builder) -> tuple[list[Axis], list[Channel]]:
        """The controller axes and the measurement channels of this topology.

        Parameters
        ----------
        b : Builder
            The model builder the mechanism declares to and writes code through.

        Returns
        -------
        axes : list of Axis
            One cascade per driven motor, with its reference, feedback and current state.
        channels : list of Channel
            The quantised encoders and scales the loops read.
        """
        raise NotImplementedError

    def signals(self, b: Builder) -> None:
        """Declare the mechanism's own auxiliary and derived outputs (after the controller's).

        Parameters
        ----------
        b : Builder
            The model builder the mechanism declares to and writes code through.
        """

    def check_profile(self, commanded: Mapping[str, tuple[float, Any]]) -> None:
        """Refuse a reference this drive cannot follow: a profile that commands a signal the
        drive does not follow (:meth:`follows`) at a speed other than 0.

        Parameters
        ----------
        commanded : mapping of str to (float, numpy.ndarray)
            The reference signals beyond the table's a profile commands
            (:func:`feeddrive.model.reference.commanded_references`): signal → (constant
            speed, tabulated speed) [m/s].

        Raises
        ------
        ParameterError
            One line naming the field (``<signal>_speed``), the value and what was expected
            (:meth:`unfollowed`).
        """
        import numpy as np

        from ...parameters import ParameterError

        for signal, (speed, table) in commanded.items():
            if not self.follows(signal) and (speed != 0.0 or np.any(table != 0.0)):
                # a tabulated or input reference (the FMU's: its constant is 0) shows its
                # first speed that is not 0, not the constant (it said "= 0", session 29)
                shown = speed if speed != 0.0 else float(table[np.flatnonzero(table)[0]])
                raise ParameterError(f"{signal}_speed", shown, self.unfollowed(signal))

    def unfollowed(self, signal: str) -> str:
        """What a message says of a commanded reference ``signal`` this drive does not follow.

        Parameters
        ----------
        signal : str
            The reference signal.

        Returns
        -------
        str
            E.g. ``"a linear-motor drive has no nut; expected 0"``.
        """
        return f"{self.drive_label(self.drive)} has no {signal}; expected 0"

    def compensation(self, b: Builder
                     ) -> tuple[list[tuple[str, str, str]], str]:
        """The friction sites a compensator on the table-driving motor models.

        Parameters
        ----------
        b : Builder
            The model builder the mechanism declares to and writes code through.

        Returns
        -------
        sites : list of (str, str, str)
            (parameter key, commanded speed code, measured speed code) per compensated site,
            signals in braces (``"{ref_v}"``, ``"{table_speed}"``).
        factor : str
            Code of the factor from force [N] to that motor's current [A].

        Raises
        ------
        ParameterError
            When the topology has no friction compensation (the default).
        """
        from ...parameters import ParameterError

        raise ParameterError("controller.compensation.mode", "—",
                             f"no friction compensation for the {self.drive} drive")

    def steady_motion(self, table_speed: float, nut_speed: float
                      ) -> dict[str, tuple[str, float]]:
        """The kinematics of steady motion, for the linear analysis' operating point.

        Parameters
        ----------
        table_speed : float
            Commanded table speed [m/s].
        nut_speed : float
            Commanded nut speed [m/s] (drives with a driven nut).

        Returns
        -------
        dict
            Position-like state → (its rate state, the steady rate in that state's unit per
            second [unit/s]); e.g. ``{"table_position": ("table_speed", v)}``.
        """
        return {"table_position": ("table_speed", table_speed)}

    def motor_output(self, axis: str) -> tuple[str, str]:
        """Where the motor of ``axis`` turns current into torque or force.

        Parameters
        ----------
        axis : str
            A controller axis of this drive.

        Returns
        -------
        tuple of (str, str)
            The model's parameter slot of its torque (or force) constant, and the name of
            the output ``constant × current`` in a linear model.
        """
        if self.single_motor is not None:
            return self.single_motor
        return f"{axis}_motor.torque_constant", f"{axis}_motor_torque"

    def held(self) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """What this drive holds still (the CDFS's locked nut).

        Returns
        -------
        tuple of (tuple of str, tuple of str)
            Prefixes of the frozen states' names, and the names of the axes that do not
            run; both empty by default.
        """
        return (), ()

    def site_masses(self) -> dict[str, float]:
        """The mass a pre-sliding test at each friction site moves (for identification).

        A site is named by where its parameters live (:attr:`Site.parameters_key`); a rotary
        site's friction is stored as force against its linear-equivalent speed (Wang2021
        Table 1 divides torques by H), so its inertia J counts as J/H².

        Returns
        -------
        dict
            Site parameters key → effective mass [kg]; empty when the topology declares none.

        References
        ----------
        .. [1] Wang2021 Table 1 (the force form of the rotary sites)..
        """
        return {}

    def emit(self, b: Builder, m: Mechanics) -> None:
        """Write the mechanism's equations of motion into the right-hand side.

        Parameters
        ----------
        b : Builder
            The model builder the mechanism declares to and writes code through.
        m : Mechanics
            The friction, disturbance and ripple terms per body from the assembler.
        """
        raise NotImplementedError


def register_mechanism(topology: type[Mechanism]) -> type[Mechanism]:
    """Make a topology available under each of its ``drives`` names.

    Parameters
    ----------
    topology : type of Mechanism
        The mechanism class; usable as a class decorator.

    Returns
    -------
    type of Mechanism
        ``topology``, registered in :mod:`feeddrive.registry` (group
        ``feeddrive.mechanisms``).
    """
    for drive in topology.drives:
        registry.register(registry.MECHANISMS, drive, topology)
    return topology


def mechanism(drive: str) -> type[Mechanism]:
    """Look up the registered topology of a drive name.

    Parameters
    ----------
    drive : str
        The drive name (``"cdfs"``, ``"ddfs"``, ``"linear-motor"``, ``"rack-pinion"`` or one a
        user registered).

    Returns
    -------
    type of Mechanism
        The topology class.

    Raises
    ------
    ParameterError
        When no topology of that name is registered; the message lists the known names.
    """
    table = registry.table(registry.MECHANISMS)
    if drive not in table:
        from ...parameters import ParameterError
        from ...parameters.validation import did_you_mean

        raise ParameterError("drive", drive, f"expected one of {', '.join(table)}"
                             + did_you_mean(drive, table))
    cls: type[Mechanism] = table[drive]
    return cls


def drive_names() -> tuple[str, ...]:
    """Names of the registered drive topologies, in registration order.

    Returns
    -------
    tuple of str
        The names ``--drive`` accepts.
    """
    return registry.names(registry.MECHANISMS)


def check_nut_hold(drive: str, nut_hold: str, *, field: str = "nut_hold",
                   given: bool = False) -> None:
    """Refuse a nut hold that has no effect on ``drive``: one whose topology holds no nut
    (:meth:`Mechanism.held_part`; the DDFS drives its nut, the linear motor and the rack and
    pinion have none).  ``"servo"`` is refused, and with ``given`` (an option typed) any
    value; ``"locked"``, the library's default, is taken on every drive.

    Parameters
    ----------
    drive : str
        A registered drive name.
    nut_hold : str
        ``"locked"`` or ``"servo"``.
    field : str, default "nut_hold"
        The name the message gives it (``"--nut-hold"``, ``"axes.x.nut_hold"``).
    given : bool, default False
        Whether the value was given explicitly (then refused whatever it is).

    Raises
    ------
    ParameterError
        One line: the value, the drives a nut hold applies to and why not this one.
    """
    topology = mechanism(drive)
    if topology.held_part(drive) == "nut" or (nut_hold == "locked" and not given):
        return
    from ...parameters import ParameterError

    holders = [d for d in drive_names() if mechanism(d).held_part(d) == "nut"]
    why = ("it drives its nut: the nut speed reference"
           if "nut" in topology.followed_references(drive) else "it has no nut")
    raise ParameterError(field, nut_hold, f"applies to a drive that holds its nut "
                         f"({', '.join(holders)}), not to {drive} ({why})")


#: where the table starts when no position is given [m]: the nut at mid-screw of Wang2021's
#: drives (Table 3: 0.2 … 0.6 m), the default of ``DriveSystem`` and ``MachineAxis``
DEFAULT_TABLE_POSITION = 0.4


def start_position(drive: str, table_position: float) -> float:
    """Where a run of ``drive`` starts from ``table_position`` [m]: that position where the
    model reads it (:attr:`Mechanism.uses_table_position`), else
    :data:`DEFAULT_TABLE_POSITION`, the only start such a drive takes
    (:func:`check_table_position`) — for a caller that computes a start for any drive (the
    first stop of a positioning test, a point on a circle, a fit record's key).

    Parameters
    ----------
    drive : str
        A registered drive name.
    table_position : float
        The start computed for it [m].

    Returns
    -------
    float
        The start its run takes [m].
    """
    return table_position if mechanism(drive).uses_table_position else DEFAULT_TABLE_POSITION


def check_table_position(drive: str, table_position: object, *,
                         field: str = "table_position", given: bool = False) -> None:
    """Refuse a start position on a drive whose model does not depend on where the table
    starts (:attr:`Mechanism.uses_table_position`: only the ball screw's K_eq(a) does; the
    linear motor and the rack and pinion read it nowhere): it was taken and dropped without
    a word.  A value other than :data:`DEFAULT_TABLE_POSITION` is refused, and with ``given``
    (a key written in a file) any value; the default, which a caller cannot tell apart from
    none given, is taken on every drive.

    Parameters
    ----------
    drive : str
        A registered drive name.
    table_position : object
        The start position given [m].
    field : str, default "table_position"
        The name the message gives it (``"axes.x.table_position"``).
    given : bool, default False
        Whether the value was given explicitly (then refused whatever it is).

    Raises
    ------
    ParameterError
        One line: the value, the drives a start position applies to and to omit it.
    """
    default = (isinstance(table_position, int | float)
               and table_position == DEFAULT_TABLE_POSITION)
    if mechanism(drive).uses_table_position or (default and not given):
        return
    from ...parameters import ParameterError

    users = [d for d in drive_names() if mechanism(d).uses_table_position]
    raise ParameterError(field, table_position, "applies to a drive whose model depends on "
                         f"the table's position ({', '.join(users)}), not to {drive}; omit it")
