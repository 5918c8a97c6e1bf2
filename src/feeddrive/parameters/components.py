"""Frozen, validated parameter dataclasses, one per component.  SI units throughout.

Ranges are plausibility bounds for machine-tool feed drives; they exist to catch wrong units
(a lead of 5 instead of 0.005 m) and impossible values, not to restrict design studies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from typing import Any, Self

import numpy as np

from .. import registry
from .validation import ParameterError, choice, flag, quantities, quantity, validate

_MM_HINT = "looks like millimetres; give metres"
#: shortest sampling period of a discrete loop [s]: 1 µs (a faster loop is continuous: 0)
MIN_PERIOD = 1e-6
#: finest linear-scale resolution [m]: 1 nm
MIN_GRATING = 1e-9
#: longest parameter-set name [characters] (it is printed on one line)
MAX_NAME = 200
#: longest parameter-set description [characters]
MAX_DESCRIPTION = 10_000


class _Component:
    """Mixin: validate on construction, ``replace`` with re-validation."""

    _label = "component"

    def __post_init__(self) -> None:
        validate(self, self._label)
        self._check()

    def _check(self) -> None:
        """Cross-field checks; override where needed."""

    def with_values(self, **changes: Any) -> Self:
        return replace(self, **changes)  # type: ignore[type-var]


#: the base of every parameter component: a part's own section subclasses it
Component = _Component


@dataclass(frozen=True)
class FrictionBranch(_Component):
    """One direction of a LuGre/Stribeck friction law, as magnitudes.  Wang2021 Table 1.

    Table 1 prints the negative branch with minus signs on F_c, F_s and v_s; here every branch
    is stored as magnitudes and the sign comes from the direction of motion.
    """

    coulomb_force: float = quantity(
        "N", low=0, high=1e5, hint="give the magnitude; the sign comes from the branch"
    )
    static_force: float = quantity(
        "N", low=0, high=1e5, hint="give the magnitude; the sign comes from the branch"
    )
    stribeck_velocity: float = quantity(
        "m/s", low=1e-7, high=0.1, hint="give the magnitude in m/s (1 mm/s = 0.001 m/s)"
    )
    viscous_coefficient: float = quantity("N s/m", low=0, high=1e7, low_inclusive=True)
    _label = "friction_branch"

    def _check(self) -> None:
        if self.static_force < self.coulomb_force:
            raise ParameterError(
                f"{self._label}.static_force",
                self.static_force,
                f"F_s must be ≥ F_c = {self.coulomb_force} [N] "
                "(breakaway exceeds sliding friction)",
            )


@dataclass(frozen=True)
class SiteParameters(_Component):
    """Base of the parameters of one friction site.  Its ``law`` picks the class: each
    friction law names its parameter class (``FrictionLaw.parameters_class``), so a law with
    parameters of its own (e.g. GMS) brings them in its own module; laws without (LuGre,
    Stribeck, Dahl, none) share :class:`LuGreParameters`."""

    _label = "friction"

    @property
    def law_name(self) -> str:
        """The site's friction law."""
        return str(vars(self).get("law", ""))

    @staticmethod
    def class_for(data: Any, path: str) -> type[SiteParameters]:
        """The parameter class of a site table (its ``law``, default ``"lugre"``).

        Parameters
        ----------
        data : dict
            The site's table as read from TOML.
        path : str
            Its dotted path, for messages (``"friction.guide"``).

        Returns
        -------
        type of SiteParameters
            The class the site's law declares.
        """
        law = data.get("law", "lugre") if isinstance(data, dict) else "lugre"
        laws = registry.table(registry.FRICTION_LAWS)
        if not isinstance(law, str) or law not in laws:
            raise ParameterError(f"{path}.law", law,
                                 f"unknown friction law; expected one of {', '.join(laws)}")
        cls: type[SiteParameters] = getattr(laws[law], "parameters_class", LuGreParameters)
        return cls

    def require(self, kind: type[SiteParameters], path: str, what: str) -> Any:
        """This site as ``kind``, or a refusal naming the site, its law and what needs it.

        Parameters
        ----------
        kind : type of SiteParameters
            The parameter class the caller works with (e.g. :class:`LuGreParameters`).
        path : str
            The site's dotted path, for the message (``"friction.guide"``).
        what : str
            What needs that class (``"friction compensation"``).

        Returns
        -------
        SiteParameters
            ``self``, of class ``kind``.
        """
        if not isinstance(self, kind):
            raise ParameterError(f"{path}.law", self.law_name,
                                 f"{what} works with {kind.__name__} sites (laws "
                                 f"{', '.join(_laws_of(kind))}); this site's law has "
                                 f"parameters of its own ({type(self).__name__})")
        return self


def _laws_of(kind: type[SiteParameters]) -> list[str]:
    return [name for name, law in registry.table(registry.FRICTION_LAWS).items()
            if getattr(law, "parameters_class", LuGreParameters) is kind]


@dataclass(frozen=True)
class LuGreParameters(SiteParameters):
    """LuGre friction at one site, linear (force) form.  Wang2021 Eqs. (9)–(11), Table 1.

    Rotary sites (screw and hollow shafts) are stored as the paper does: torques divided by
    H = p_h/2π, angles multiplied by H, so forces in N and speeds in m/s of the equivalent
    nut/table motion.  σ0 and σ1 are shared by both branches, as in Table 1.
    """

    positive: FrictionBranch
    negative: FrictionBranch
    bristle_stiffness: float = quantity("N/m", low=0, high=1e12)
    bristle_damping: float = quantity("N s/m", low=0, high=1e8, low_inclusive=True)
    law: str = "lugre"
    smoothing_velocity: float = quantity(
        "m/s", low=0, high=0.1, default=1e-6,
        hint="sign-function smoothing of the static law only; 1 µm/s = 1e-6 m/s")
    _label = "friction"

    def _check(self) -> None:
        if not isinstance(self.law, str):
            raise ParameterError(f"{self._label}.law", self.law, "expected a law name")
        laws = registry.table(registry.FRICTION_LAWS)
        if self.law not in laws:
            raise ParameterError(f"{self._label}.law", self.law,
                                 f"unknown friction law; expected one of {', '.join(laws)}")
        own = getattr(laws[self.law], "parameters_class", LuGreParameters)
        if own is not LuGreParameters:
            raise ParameterError(f"{self._label}.law", self.law,
                                 f"this law takes the parameters of {own.__name__}, not "
                                 "LuGre's (give the site's table in that form)")

    def mismatched(self, coulomb: float, static: float, stribeck_velocity: float,
                   viscous: float) -> LuGreParameters:
        """The site as a compensator with model errors sees it: F_c, F_s, v_s and σ2 of both
        branches times the given factors (σ0, σ1 unchanged)."""
        def br(b: FrictionBranch) -> FrictionBranch:
            return replace(b, coulomb_force=b.coulomb_force * coulomb,
                           static_force=b.static_force * static,
                           stribeck_velocity=b.stribeck_velocity * stribeck_velocity,
                           viscous_coefficient=b.viscous_coefficient * viscous)
        return replace(self, positive=br(self.positive), negative=br(self.negative))

    def scaled(self, factor: float) -> LuGreParameters:
        """This site with every force and coefficient times ``factor`` (0 < factor ≤ 1); the
        Stribeck velocities and the bristle dynamics (z, ż) are unchanged, the force scales."""
        def br(b: FrictionBranch) -> FrictionBranch:
            return replace(b, coulomb_force=b.coulomb_force * factor,
                           static_force=b.static_force * factor,
                           viscous_coefficient=b.viscous_coefficient * factor)
        return replace(self, positive=br(self.positive), negative=br(self.negative),
                       bristle_stiffness=self.bristle_stiffness * factor,
                       bristle_damping=self.bristle_damping * factor)

    def as_array(self) -> np.ndarray:
        """Pack as float64[10]: (F_c, F_s, v_s, σ2) for +, then −, then σ0, σ1."""
        p, n = self.positive, self.negative
        return np.array(
            [
                p.coulomb_force, p.static_force, p.stribeck_velocity, p.viscous_coefficient,
                n.coulomb_force, n.static_force, n.stribeck_velocity, n.viscous_coefficient,
                self.bristle_stiffness, self.bristle_damping,
            ],
            dtype=np.float64,
        )

    def branch(self, name: str) -> FrictionBranch:
        if name not in ("positive", "negative"):
            raise ParameterError("branch", name, "expected positive or negative")
        return self.positive if name == "positive" else self.negative


@dataclass(frozen=True)
class FrictionSites(_Component):
    """Friction at the three sites of Wang2021 Sect. 4, each with its law.

    ``ball_nut_share`` f: the fraction of the screw-shaft friction (Table 1, identified on the
    CDFS with the nut fixed) that acts at the ball–nut contact, i.e. at the *relative* speed
    H(ω_s − ω_n) between screw and nut, with its reaction on the nut; the rest (1 − f) acts
    between screw shaft and ground (support bearings) at the screw speed.  f = 0 is the paper's
    reading (every friction at its own shaft's speed); with the nut held (CDFS) f has no effect.
    """

    screw: SiteParameters
    nut: SiteParameters
    guide: SiteParameters
    ball_nut_share: float = quantity("-", low=0, high=1, low_inclusive=True, default=0.0,
                                     hint="a fraction between 0 and 1")
    _label = "friction"


@dataclass(frozen=True)
class BallScrew(_Component):
    """Ball screw, its supports and nut.  Wang2021 Table 2 and Eqs. (2)–(5)."""

    length: float = quantity("m", low=0.01, high=20, hint=_MM_HINT)
    diameter: float = quantity("m", low=1e-3, high=0.5, hint=_MM_HINT)
    lead: float = quantity("m", low=1e-4, high=0.1, hint=_MM_HINT)
    youngs_modulus: float = quantity("Pa", low=1e9, high=1e12, hint="206 GPa = 2.06e11 Pa")
    torsional_stiffness: float = quantity("N m/rad", low=1, high=1e9)
    nut_axial_stiffness: float = quantity(
        "N/m", low=1e5, high=1e11, hint="1 N/µm = 1e6 N/m"
    )
    nut_bearing_axial_stiffness: float = quantity(
        "N/m", low=1e5, high=1e11, hint="1 N/µm = 1e6 N/m"
    )
    support_bearing_axial_stiffness: float = quantity(
        "N/m", low=1e5, high=1e11, hint="1 N/µm = 1e6 N/m"
    )
    efficiency: float = quantity(
        "-", low=0, high=1.0, hint="transmission efficiency η is a fraction"
    )
    shaft_inertia: float = quantity("kg m^2", low=0, high=10, low_inclusive=True)
    nut_inertia: float = quantity("kg m^2", low=0, high=10, low_inclusive=True)
    _label = "screw"

    @property
    def transmission_ratio(self) -> float:
        """H = p_h / 2π [m/rad].  Wang2021 Eq. (8)."""
        return self.lead / (2.0 * math.pi)


@dataclass(frozen=True)
class Coupling(_Component):
    torsional_stiffness: float = quantity("N m/rad", low=1, high=1e9)
    _label = "coupling"


@dataclass(frozen=True)
class Motor(_Component):
    """Permanent-magnet servo motor as an R-L armature with back-EMF.  Wang2021 Table 2."""

    torque_constant: float = quantity("N m/A", low=1e-3, high=100)
    back_emf_constant: float = quantity("V s/rad", low=1e-3, high=100)
    inductance: float = quantity("H", low=1e-6, high=1.0, hint="5.9 mH = 0.0059 H")
    resistance: float = quantity("ohm", low=1e-3, high=1e3)
    inertia: float = quantity(
        "kg m^2",
        low=1e-7,
        high=10,
        hint="Wang2021 Table 2 prints 1.38×10³; a servo motor of this size has 1.38×10⁻³",
    )
    _label = "motor"


@dataclass(frozen=True)
class Table(_Component):
    mass: float = quantity("kg", low=0.01, high=1e5)
    _label = "table"


@dataclass(frozen=True)
class StiffnessModel(_Component):
    """How Eqs. (2)–(5) are read, and the structural damping the paper does not give.

    ``equivalent_stiffness`` set to a positive value overrides the chain (e.g. the paper's
    stated 2.16e7 N/m); 0 means "compute from Eqs. (2)–(5) at the table position".
    """

    screw_support: str = choice(("fixed-fixed", "fixed-free"), default="fixed-fixed")
    support_bearing_count: float = quantity("-", low=0, high=8, default=2.0)
    include_torsion: bool = flag(default=True)
    equivalent_stiffness: float = quantity(
        "N/m", low=0, high=1e11, low_inclusive=True, default=0.0, hint="1 N/µm = 1e6 N/m"
    )
    axial_damping: float = quantity("N s/m", low=0, high=1e8, low_inclusive=True, default=0.0)
    position_dependent: bool = flag(default=True)
    _label = "stiffness"


@dataclass(frozen=True)
class Compensation(_Component):
    """Friction compensation on the table-driving motor (screw motor or linear motor).

    ``mode``: ``none``; ``feedforward`` — the static Stribeck + Coulomb + viscous curve of the
    compensated sites at the *commanded* speed, added as current (model-based feed-forward,
    Armstrong-Hélouvry et al., Automatica 30 (1994) 1083–1138); ``observer`` — a LuGre
    observer at the *measured* speeds, ẑ' = v − σ0|v|ẑ/g(v) − k·e with e the table position
    error, F̂ = σ0ẑ + σ1ẑ' + σ2v (Canudas de Wit, Olsson, Åström, Lischinsky, IEEE TAC 40
    (1995) 419–425, Sect. V), added as current.  Compensated sites: the screw shaft and the
    guide (the guide only, for a linear motor).  The ``*_scale`` factors give the model
    mismatch the compensator works with (1 = exact; 1.2 = its value is 20 % high).
    """

    mode: str = choice(("none", "feedforward", "observer"), default="none")
    # a model a thousand times off is no compensator: the lower bounds keep the products
    # physical (a factor 1e-320 passed and the run then overflowed)
    coulomb_scale: float = quantity("-", low=1e-3, high=10, low_inclusive=True, default=1.0)
    static_scale: float = quantity("-", low=1e-3, high=10, low_inclusive=True, default=1.0)
    stribeck_velocity_scale: float = quantity("-", low=1e-3, high=10, low_inclusive=True,
                                              default=1.0)
    viscous_scale: float = quantity("-", low=0, high=10, low_inclusive=True, default=1.0)
    observer_gain: float = quantity("1/s", low=0, high=1e6, low_inclusive=True, default=0.0,
                                    hint="k of the observer's correction −k·e [1/s]")
    _label = "compensation"


@dataclass(frozen=True)
class Controller(_Component):
    """Cascade servo (position → velocity → current) shared by both motors.  Wang2021 Sect. 2.1.

    The block diagram (Fig. 5) is an image; the structure is an explicit choice, see
    docs/model.md.  Gains are in the units stated; a period of 0 means a continuous loop.
    """

    position_gain: float = quantity("1/s", low=0, high=1e5, low_inclusive=True)
    # per rad/s of the motor, or per m/s of table speed with velocity_gain_basis = "table"
    velocity_gain: float = quantity("A s/rad", low=0, high=1e5, low_inclusive=True,
                                    table_unit="A s/m")
    current_gain: float = quantity("V/A", low=0, high=1e5, low_inclusive=True)
    velocity_command_gain: float = quantity("rad/(V s)", low=0, high=1e6)
    velocity_integral_gain: float = quantity(
        "A/rad", low=0, high=1e9, low_inclusive=True, default=0.0, table_unit="A/m"
    )
    current_integral_gain: float = quantity(
        "V/(A s)", low=0, high=1e9, low_inclusive=True, default=0.0
    )
    kv_placement: str = choice(("none", "position_output", "velocity_error"), default="none")
    velocity_gain_basis: str = choice(("motor", "table"), default="motor")
    velocity_feedback: str = choice(("motor", "table"), default="motor")
    velocity_feedforward: bool = flag(default=True)
    nut_loop: str = choice(("position", "speed"), default="position")
    mode: str = choice(("cascade", "torque_off"), default="cascade")
    compensation: Compensation = field(default_factory=lambda: Compensation())
    current_limit: float = quantity("A", low=0, high=1e4, default=1e4)
    voltage_limit: float = quantity("V", low=0, high=1e5, default=1e5)
    position_period: float = quantity("s", low=0, high=0.1, low_inclusive=True, default=0.0)
    velocity_period: float = quantity("s", low=0, high=0.1, low_inclusive=True, default=0.0)
    current_period: float = quantity("s", low=0, high=0.1, low_inclusive=True, default=0.0)
    encoder_counts: float = quantity(
        "counts/rev", low=0, high=1e10, low_inclusive=True, default=0.0
    )
    grating_resolution: float = quantity(
        "m", low=0, high=1e-3, low_inclusive=True, default=0.0, hint="1 µm = 1e-6 m"
    )
    _label = "controller"

    def _check(self) -> None:
        periods = [p for p in (self.position_period, self.velocity_period, self.current_period)]
        for name, p in zip(("position", "velocity", "current"), periods, strict=True):
            if 0 < p < MIN_PERIOD:
                raise ParameterError(f"controller.{name}_period", p,
                                     f"expected 0 (a continuous loop) or {MIN_PERIOD:g} … 0.1 "
                                     "[s] (1 µs = 1e-6 s)")
        if 0 < self.grating_resolution < MIN_GRATING:
            raise ParameterError("controller.grating_resolution", self.grating_resolution,
                                 f"expected 0 (no quantisation) or {MIN_GRATING:g} … 0.001 [m]")
        if 0 < self.encoder_counts < 1:
            raise ParameterError("controller.encoder_counts", self.encoder_counts,
                                 "expected 0 (no quantisation) or ≥ 1 [counts/rev]")
        nonzero = [p for p in periods if p > 0]
        if nonzero:
            base = min(nonzero)
            for name, p in zip(("position", "velocity", "current"), periods, strict=True):
                if p > 0 and abs(p / base - round(p / base)) > 1e-9:
                    raise ParameterError(
                        f"controller.{name}_period",
                        p,
                        f"must be an integer multiple of the fastest period {base:g} [s]",
                    )


@dataclass(frozen=True)
class TorqueRipple(_Component):
    """Motor torque ripple and cogging: T_r(θ) = Σ_k A_k·sin(n_k·θ + φ_k), θ the motor shaft
    angle [rad].  ``orders`` n_k per revolution, ``amplitudes`` A_k [N m], ``phases`` φ_k [rad]."""

    orders: tuple[float, ...] = quantities("-", low=0, high=1e4)
    amplitudes: tuple[float, ...] = quantities("N m", low=0, high=1e3)
    phases: tuple[float, ...] = quantities("rad", low=-1e3, high=1e3)
    _label = "ripple"

    def _check(self) -> None:
        _same_length(self, ("orders", "amplitudes", "phases"))


@dataclass(frozen=True)
class LeadError(_Component):
    """Screw lead error: the nut advances H·θ + Σ_k a_k·sin(n_k·θ + φ_k) [m] for a relative
    screw–nut angle θ [rad]; ``amplitudes`` a_k [m] (typically a few µm)."""

    orders: tuple[float, ...] = quantities("-", low=0, high=1e4)
    amplitudes: tuple[float, ...] = quantities("m", low=0, high=1e-3, hint="1 µm = 1e-6 m")
    phases: tuple[float, ...] = quantities("rad", low=-1e3, high=1e3)
    _label = "lead_error"

    def _check(self) -> None:
        _same_length(self, ("orders", "amplitudes", "phases"))


def _same_length(obj: Any, names: tuple[str, ...]) -> None:
    lengths = {len(getattr(obj, n)) for n in names}
    if len(lengths) > 1:
        raise ParameterError(f"{obj._label}.{names[1]}", getattr(obj, names[1]),
                             f"expected as many entries as {names[0]} "
                             f"({len(getattr(obj, names[0]))})")


@dataclass(frozen=True)
class Disturbances(_Component):
    """Forces and errors acting on the drive besides friction (all zero by default).

    ``load_force`` [N] acts on the table against positive motion (a cutting force resisting
    the feed is positive), from ``load_start`` [s]; a time profile is given through the API
    (:class:`feeddrive.LoadProfile`).
    """

    load_force: float = quantity("N", low=-1e6, high=1e6, default=0.0)
    load_start: float = quantity("s", low=0, high=1e9, low_inclusive=True, default=0.0)
    screw_motor_ripple: TorqueRipple = field(default_factory=lambda: TorqueRipple())
    hollow_motor_ripple: TorqueRipple = field(default_factory=lambda: TorqueRipple())
    lead_error: LeadError = field(default_factory=lambda: LeadError())
    _label = "disturbances"


@dataclass(frozen=True)
class LinearMotor(_Component):
    """Linear motor of a direct-drive table: force constant, back-EMF, R-L winding, forcer."""

    force_constant: float = quantity("N/A", low=1e-2, high=1e4)
    back_emf_constant: float = quantity("V s/m", low=1e-2, high=1e4)
    inductance: float = quantity("H", low=1e-6, high=1.0, hint="20 mH = 0.02 H")
    resistance: float = quantity("ohm", low=1e-3, high=1e3)
    forcer_mass: float = quantity("kg", low=0, high=1e4, low_inclusive=True)
    _label = "linear_motor"


@dataclass(frozen=True)
class DriveParameters(_Component):
    """Everything that defines a feed drive: mechanics, motors, friction, stiffness, control.

    All values SI (the TOML files and ``feeddrive params show`` too); each component validates
    its own fields with units and ranges (:mod:`feeddrive.parameters.validation`).

    Parameters
    ----------
    name : str
        Name of the set (printed in reports, results and exports).
    description : str
        What the set is and where its values come from.
    screw : BallScrew
        Ball screw: lead, diameter, length, inertia (Wang2021 Table 2).
    coupling : Coupling
        Motor–screw coupling.
    screw_motor : Motor
        The screw's servo motor (R-L circuit, torque and back-EMF constants).
    hollow_motor : Motor
        The hollow motor driving the nut (DDFS).
    table : Table
        Table mass and guide.
    friction : FrictionSites
        Friction at the screw shaft, the hollow (nut) shaft and the guide, each with its law.
    stiffness : StiffnessModel, default StiffnessModel()
        Axial stiffness chain (Wang2021 Eqs. (2)–(5)) and structural damping.
    controller : Controller, default the Table 2 gains
        Cascade loops (position, velocity, current) of the screw motor.
    disturbances : Disturbances, default Disturbances()
        Load force, motor torque ripple, lead error.
    linear_motor : LinearMotor or None, default None
        The forcer of the ``linear-motor`` drive.
    hollow_controller : Controller or None, default None
        The hollow motor's own loops; None: it uses ``controller``.
    sections : tuple of (str, Component), default ()
        Parts' own sections by name, sorted (``[rack_pinion]``, ``[acceleration_feedforward]``;
        registry group ``feeddrive.sections``); read like fields (``params.rack_pinion``).
    """

    name: str
    description: str
    screw: BallScrew
    coupling: Coupling
    screw_motor: Motor
    hollow_motor: Motor
    table: Table
    friction: FrictionSites
    stiffness: StiffnessModel = field(default_factory=StiffnessModel)
    controller: Controller = field(default_factory=lambda: _default_controller())
    disturbances: Disturbances = field(default_factory=lambda: Disturbances())
    linear_motor: LinearMotor | None = None
    # the hollow motor's own loops; absent: it uses ``controller`` as the screw motor does
    hollow_controller: Controller | None = None
    # parts' own sections ([rack_pinion], ...), by name: registry group feeddrive.sections
    sections: tuple[tuple[str, Any], ...] = ()
    _label = "parameters"

    def _check(self) -> None:
        _check_text("name", self.name, MAX_NAME, lines=False)
        _check_text("description", self.description, MAX_DESCRIPTION, lines=True)
        known = registry.table(registry.SECTIONS)
        names = [name for name, _ in self.sections]
        if names != sorted(set(names)):
            raise ParameterError("sections", names, "expected each section once, sorted")
        for name, value in self.sections:
            cls = known.get(name)
            if cls is None:
                raise ParameterError(name, "…", f"unknown section; expected one of "
                                     f"{', '.join(known) or '(none registered)'}")
            if not isinstance(value, cls):
                raise ParameterError(name, type(value).__name__, f"expected {cls.__name__}")

    def section(self, name: str) -> Any:
        """A part's own parameter section (e.g. ``"rack_pinion"``), or None if absent.

        Parameters
        ----------
        name : str
            The section's name in the parameter file.

        Returns
        -------
        Component or None
            The section's parameters.
        """
        return dict(self.sections).get(name)

    def __getattr__(self, name: str) -> Any:
        # sections read like fields (params.rack_pinion, dotted paths); only called when
        # normal attribute lookup fails
        if name.startswith("_") or name == "sections":
            raise AttributeError(name)
        for key, value in object.__getattribute__(self, "sections"):
            if key == name:
                return value
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def replace_path(self, path: str, value: Any) -> DriveParameters:
        """A copy with one value, addressed by its dotted path, replaced.

        Parameters
        ----------
        path : str
            Dotted path, e.g. ``"controller.velocity_gain"``.
        value : object
            The new value, in the field's SI unit [unit of ``path``]; validated as on loading.

        Returns
        -------
        DriveParameters
            The changed copy (this set is unchanged).
        """
        return _replace_path(self, path.split("."), value, path)


def _check_text(key: str, text: Any, limit: int, *, lines: bool) -> None:
    """A name or description: text, at most ``limit`` characters, no control characters
    (a description may have line breaks and tabs)."""
    if not isinstance(text, str):
        raise ParameterError(key, text, "expected text")
    if len(text) > limit:
        raise ParameterError(key, text, f"{len(text)} characters; at most {limit}")
    allowed = "\n\t" if lines else ""
    bad = next((c for c in text if not c.isprintable() and c not in allowed), None)
    if bad is not None:
        raise ParameterError(key, text, f"contains the control character {bad!r}; expected "
                             "plain text")


def _default_controller() -> Controller:
    return Controller(position_gain=8.0, velocity_gain=45.0, current_gain=2.0,
                      velocity_command_gain=250.0)


def unit_of(cls: type, path: str) -> str | None:
    """The unit a parameter class declares for a dotted path below it.

    Parameters
    ----------
    cls : type
        A parameter component class (e.g. :class:`LuGreParameters`).
    path : str
        Dotted path, entries of a tuple field with ``[i]``
        (``"positive.coulomb_force"``, ``"element_stiffness[2]"``).

    Returns
    -------
    str or None
        The unit of the field's metadata (``"-"`` for dimensionless), None when the path
        names no quantity of the class.
    """
    import typing

    for i, part in enumerate(path.split(".")):
        name = part.split("[", 1)[0]
        found = {f.name: f for f in fields(cls)}.get(name)
        if found is None:
            return None
        hint = typing.get_type_hints(cls).get(name)
        if isinstance(hint, type) and hasattr(hint, "__dataclass_fields__"):
            cls = hint
            continue
        unit = found.metadata.get("unit")
        return str(unit) if unit is not None and i == path.count(".") else None
    return None


def _replace_path(obj: Any, parts: list[str], value: Any, full: str) -> Any:
    names = {f.name for f in fields(obj)}
    head = parts[0]
    sections = dict(getattr(obj, "sections", ()) if head not in names else ())
    if head in sections:
        changed = (_replace_path(sections[head], parts[1:], value, full) if len(parts) > 1
                   else value)
        return replace(obj, sections=tuple(sorted({**sections, head: changed}.items())))
    if head not in names:
        raise ParameterError(full, value, f"unknown field {head!r}")
    if len(parts) == 1:
        try:
            return replace(obj, **{head: value})
        except ParameterError as err:
            # component labels are local ("motor.inertia"); name the full path instead
            prefix = full.rsplit(".", 1)[0] if "." in full else ""
            local = err.field.split(".", 1)[-1]
            raise ParameterError(f"{prefix}.{local}" if prefix else local, err.value,
                                 err.message) from None
    return replace(obj, **{head: _replace_path(getattr(obj, head), parts[1:], value, full)})
