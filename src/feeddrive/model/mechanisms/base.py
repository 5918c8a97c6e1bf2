"""Mechanisms: bodies, compliant couplings and where motors, friction and disturbances act.

A mechanism is registered by drive name (``"cdfs"``, ``"ddfs"``, ``"linear-motor"``).  It
declares its states, parameters, friction sites, motors and controller axes to a
:class:`~feeddrive.model.codegen.Builder`, and writes its equations with the friction and
disturbance terms the assembler hands it per body.  The interface is :class:`Mechanism`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ... import registry

if TYPE_CHECKING:
    from ...parameters import DriveParameters
    from ..codegen import Builder
    from ..loops import Axis, Channel


@dataclass
class Body:
    """Terms of one body's equation, in the order they are summed."""

    drive: list[str] = field(default_factory=list)  # motor torque / coupling force first
    external: list[str] = field(default_factory=list)  # friction, disturbances
    reaction: list[str] = field(default_factory=list)  # coupling reactions last

    def expression(self) -> str:
        terms = self.drive + self.external + self.reaction
        if not terms:
            return "0.0"
        text = terms[0].removeprefix("+ ")
        for t in terms[1:]:
            text += f" {t}"
        return text


@dataclass(frozen=True)
class Site:
    """A friction site placed by the mechanism: on one body, or between two (relative)."""

    name: str  # e.g. "screw", "ball_nut"
    parameters_key: str  # friction.<key> in the parameter set, or a dotted path to them
    speed: str  # code of the sliding speed [m/s]
    bodies: tuple[tuple[str, str], ...]  # (body, factor code) pairs: term = − factor·F
    scale: float = 1.0  # share of the site's friction (ball–nut split)
    active: str = ""  # condition under which the site acts ("" = always)

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


@dataclass
class Mechanics:
    """What the assembler hands a mechanism to write its equations: per-body external force
    terms, the friction-site code lines (always-on and gated by a site's condition), the lines
    that freeze gated sites' states, and the disturbance terms."""

    forces: dict[str, list[str]]
    always: list[str]
    gated: list[str]
    frozen: list[str]
    ripple: dict[str, str]
    lead: tuple[int, int] | None
    load: str | None
    torque_off: bool


class Mechanism:
    """Interface of a topology; see :class:`~feeddrive.model.mechanisms.ball_screw.BallScrewDrive`
    and :class:`~feeddrive.model.mechanisms.linear_motor.LinearMotorDrive`."""

    drives: tuple[str, ...] = ()
    #: the parameter set a command uses for this drive when none is named
    example_preset: str = "wang2021"
    #: a drive with one motor: (slot of its torque or force constant, the output name of
    #: constant × current); None: per axis, ``<axis>_motor.torque_constant``
    single_motor: tuple[str, str] | None = None
    published: bool = True  # a published model: its docstring has a References section
    ripple_motors: tuple[str, ...] = ()  # motors whose torque ripple this topology models
    has_lead_screw = False

    def __init__(self, params: DriveParameters, drive: str, table_position: float,
                 nut_hold: str) -> None:
        self.params = params
        self.drive = drive
        self.table_position = table_position
        self.nut_hold = nut_hold

    @classmethod
    def check(cls, params: DriveParameters, drive: str, table_position: float) -> None:
        """Refuse a system this topology cannot represent (one-line ParameterError)."""

    def declare(self, b: Builder) -> None:
        raise NotImplementedError

    def parameters(self, b: Builder) -> None:
        raise NotImplementedError

    def sites(self, b: Builder) -> list[Site]:
        raise NotImplementedError

    def motors(self, b: Builder) -> None:
        raise NotImplementedError

    def axes(self, b: Builder) -> tuple[list[Axis], list[Channel]]:
        raise NotImplementedError

    def signals(self, b: Builder) -> None:
        """Auxiliary outputs of the mechanism itself (after the controller's)."""

    def check_profile(self, nut_speed: float, nut_table: Any) -> None:
        """Refuse a reference this topology cannot follow."""

    def compensation(self, b: Builder) -> tuple[list[tuple[str, str, str]], str]:
        """Friction sites a compensator on the table-driving motor models, as (parameter key,
        commanded speed code, measured speed code), and the code of the factor from force [N]
        to that motor's current [A]."""
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
        """
        return {}

    def emit(self, b: Builder, m: Mechanics) -> None:
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
    """The registered topology of drive name ``drive``."""
    table = registry.table(registry.MECHANISMS)
    if drive not in table:
        from ...parameters import ParameterError

        raise ParameterError("drive", drive, f"expected one of {', '.join(table)}")
    cls: type[Mechanism] = table[drive]
    return cls


def drive_names() -> tuple[str, ...]:
    """The names of the registered drive topologies."""
    return registry.names(registry.MECHANISMS)
