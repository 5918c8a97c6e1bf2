"""The values each parameter slot of an assembled model may take: the parameter file's ranges.

A model's numbers live in named slots (``Model.parameter_names``).  A slot filled from one
field of the parameter set (``table.mass``, ``friction.screw.bristle_stiffness``,
``controller.<axis>.kvp`` from ``controller.velocity_gain``) takes the range that field is
declared with (:func:`feeddrive.parameters.validation.quantity`, read through
:func:`feeddrive.parameters.components.field_metadata`) — the range a parameter file is
checked against.  A value a mechanism derives from several fields (the screw's H = lead/2π,
an axis' inertia sum, the screw's E·A) takes the range those fields' ranges give through the
same formula (interval arithmetic on non-negative intervals, :class:`SlotRange`).  The split
ranges a part checks in its own ``_check`` ("0 (a continuous loop) or 1e-6 … 0.1 s") are
:attr:`SlotRange.zero`; switches and enumerations are :attr:`SlotRange.integer`.

The FMU declares these as ``min``/``max`` and refuses a value outside them when it is set
(:mod:`feeddrive.fmu.description`), so an importer cannot set what a parameter file could
not hold.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..parameters import DriveParameters, ParameterError
from ..parameters.components import field_metadata
from ..parameters.validation import MISSING
from .friction import friction_law
from .friction.lugre_parameters import LuGreParameters
from .loops import MIN_GRATING, MIN_PERIOD, Compensation, Controller
from .slots import AXIS_SLOT_FIELDS, axis_scope, slot_unit

if TYPE_CHECKING:
    from .assemble import Model


@dataclass(frozen=True)
class SlotRange:
    """The values a parameter slot may take.

    Parameters
    ----------
    low : float
        Lowest value [unit] (``-inf``: none).
    high : float
        Highest value [unit] (``inf``: none).
    low_inclusive : bool, default True
        Whether ``low`` itself is allowed.
    zero : bool, default False
        0 is allowed besides ``low … high`` (a split range: "0 or 1e-6 … 0.1 s").
    integer : bool, default False
        A switch or enumeration: only the integers ``low … high``.
    unit : str, default ""
        The unit, for messages.
    """

    low: float
    high: float
    low_inclusive: bool = True
    zero: bool = False
    integer: bool = False
    unit: str = ""

    @classmethod
    def of(cls, meta: Mapping[str, Any], unit: str | None = None) -> SlotRange:
        """The range a field's declaration (``quantity`` metadata) gives.

        Parameters
        ----------
        meta : Mapping
            The field's metadata (``low``, ``high``, ``low_inclusive``, ``unit``).
        unit : str, optional
            The unit instead of the declaration's (a gain on the table basis).

        Returns
        -------
        SlotRange
            The range.
        """
        return cls(float(meta["low"]), float(meta["high"]), bool(meta["low_inclusive"]),
                   unit=str(meta["unit"]) if unit is None else unit)

    def contains(self, value: float) -> bool:
        """Whether ``value`` lies in the range (never for NaN or ±inf).

        Parameters
        ----------
        value : float
            The value [unit].

        Returns
        -------
        bool
            True when allowed.
        """
        if not math.isfinite(value):
            return False
        if self.zero and value == 0.0:
            return True
        if self.integer and value != math.floor(value):
            return False
        above = value >= self.low if self.low_inclusive else value > self.low
        return above and value <= self.high

    @property
    def minimum(self) -> float:
        """The nearest inclusive lower bound (FMI ``min``): 0 for a split range with zero,
        else ``low`` (an exclusive ``low`` is refused when set, not by the declaration)."""
        return min(0.0, self.low) if self.zero else self.low

    @property
    def maximum(self) -> float:
        """The inclusive upper bound (FMI ``max``)."""
        return self.high

    def expected(self) -> str:
        """What a refusal says was expected, as a parameter file's message says it:
        ``"expected 0.01 … 100000 [kg]"``.

        Returns
        -------
        str
            The text.
        """
        from ..parameters.validation import _format_range

        unit = self.unit or "-"
        if self.integer and math.isinf(self.high):
            return f"expected an integer ≥ {self.low:g}"
        if self.integer and self.high - self.low > 10:
            return f"expected an integer {self.low:.0f} … {self.high:.0f}"
        if self.integer:
            values = range(int(self.low), int(self.high) + 1)
            return f"expected one of {', '.join(str(v) for v in values)}"
        if math.isinf(self.low) and math.isinf(self.high):
            return f"expected a finite value [{unit}]"
        text = _format_range({"low": self.low, "high": self.high, "unit": unit,
                              "low_inclusive": self.low_inclusive})
        if self.zero:
            text = text.replace("expected ", "expected 0 or ", 1)
        return text

    # interval arithmetic on non-negative ranges (derived slots)
    def __add__(self, other: SlotRange) -> SlotRange:
        return SlotRange(self.low + other.low, self.high + other.high,
                         self.low_inclusive and other.low_inclusive, unit=self.unit)

    def __mul__(self, other: SlotRange | float) -> SlotRange:
        if isinstance(other, SlotRange):
            return SlotRange(self.low * other.low, self.high * other.high,
                             self.low_inclusive and other.low_inclusive, unit=self.unit)
        return SlotRange(self.low * other, self.high * other, self.low_inclusive,
                         unit=self.unit)

    def __truediv__(self, other: SlotRange | float) -> SlotRange:
        if isinstance(other, SlotRange):
            return SlotRange(self.low / other.high, self.high / other.low,
                             self.low_inclusive, unit=self.unit)
        return self * (1.0 / other)

    def with_unit(self, unit: str) -> SlotRange:
        """The same range in the slot's unit (for messages).

        Parameters
        ----------
        unit : str
            The unit.

        Returns
        -------
        SlotRange
            The range.
        """
        return SlotRange(self.low, self.high, self.low_inclusive, self.zero, self.integer,
                         unit)


#: any finite value (a slot no parameter-file field fills: the loop-breaking injections)
FINITE = SlotRange(-math.inf, math.inf)
#: a switch stored as 0/1
SWITCH = SlotRange(0.0, 1.0, integer=True)
#: positive (a derived compliance: no field holds it, only its sign is known)
POSITIVE = SlotRange(0.0, math.inf, low_inclusive=False)

#: axis slots that are enumerations (feeddrive.model.loops.axis_parameters)
_AXIS_SWITCHES = {"kv_place": SlotRange(0.0, 2.0, integer=True), "v_basis": SWITCH,
                  "v_feedback": SWITCH, "ff": SWITCH, "speed_mode": SWITCH}


def _field(path: str) -> SlotRange:
    meta = field_metadata(DriveParameters, path)
    if meta is None:
        raise KeyError(path)
    return SlotRange.of(meta)


def _rack_h(f: Callable[[str], SlotRange]) -> SlotRange:
    return f("rack_pinion.pinion_radius") / f("rack_pinion.gear_ratio")


#: slots a mechanism derives from several fields: their range through the same formula
#: (feeddrive.model.mechanisms.ball_screw / rack_pinion ``parameters``)
DERIVED: dict[str, Callable[[Callable[[str], SlotRange]], SlotRange]] = {
    "screw.H": lambda f: f("screw.lead") / (2.0 * math.pi),
    "screw.J": lambda f: f("screw_motor.inertia") + f("screw.shaft_inertia"),
    "nut.J": lambda f: f("hollow_motor.inertia") + f("screw.nut_inertia"),
    "nut.active": lambda f: SWITCH,
    # 0: the chain of Eqs. (2)-(5); else the fixed K_eq (the field's own range holds both)
    "stiffness.k_fixed": lambda f: f("stiffness.equivalent_stiffness"),
    "stiffness.c0": lambda f: POSITIVE,
    "stiffness.ea": lambda f: (f("screw.diameter") * f("screw.diameter")
                               * f("screw.youngs_modulus") * (math.pi / 4.0)),
    "stiffness.length": lambda f: f("screw.length"),
    "stiffness.support": lambda f: SWITCH,
    # the nut's start position: strictly between the supports (BallScrewDrive.check)
    "stiffness.x0": lambda f: SlotRange(0.0, f("screw.length").high, low_inclusive=False),
    "nut_motor.torque_constant": lambda f: f("hollow_motor.torque_constant"),
    "nut_motor.back_emf_constant": lambda f: f("hollow_motor.back_emf_constant"),
    "nut_motor.inductance": lambda f: f("hollow_motor.inductance"),
    "nut_motor.resistance": lambda f: f("hollow_motor.resistance"),
    "rack_pinion.H": _rack_h,
    "rack_pinion.J": lambda f: (f("rack_pinion.motor.inertia") + f("rack_pinion.gearbox_inertia")
                                + f("rack_pinion.pinion_inertia")
                                / (f("rack_pinion.gear_ratio") * f("rack_pinion.gear_ratio"))),
    "motor.torque_constant": lambda f: f("rack_pinion.motor.torque_constant"),
}
#: the linear motor's slots (feeddrive.model.mechanisms.linear_motor): the forcer rides on
#: the table
LINEAR_MOTOR: dict[str, Callable[[Callable[[str], SlotRange]], SlotRange]] = {
    "table.mass": lambda f: f("table.mass") + f("linear_motor.forcer_mass"),
    "motor.force_constant": lambda f: f("linear_motor.force_constant"),
    "motor.back_emf_constant": lambda f: f("linear_motor.back_emf_constant"),
    "motor.inductance": lambda f: f("linear_motor.inductance"),
    "motor.resistance": lambda f: f("linear_motor.resistance"),
}
#: the rack-and-pinion drive's motor slots
RACK_MOTOR = ("motor.back_emf_constant", "motor.inductance", "motor.resistance")
#: a compensator's site slot = the site's value × its mismatch factor
#: (LuGreParameters.mismatched)
_COMPENSATION_SCALES = {"coulomb_force": "coulomb_scale", "static_force": "static_scale",
                        "stribeck_velocity": "stribeck_velocity_scale",
                        "viscous_coefficient": "viscous_scale"}
#: the loops' split ranges (Controller._check): 0 or MIN … the field's high
_SPLIT = {"position_period": MIN_PERIOD, "velocity_period": MIN_PERIOD,
          "current_period": MIN_PERIOD, "grating_resolution": MIN_GRATING}


def controller_range(name: str) -> SlotRange:
    """The range of a :class:`~feeddrive.model.loops.Controller` field, its split range
    ("0 or 1e-6 … 0.1 s") where ``Controller._check`` refuses the values between.

    Parameters
    ----------
    name : str
        The field (``position_period``, ``velocity_gain`` …).

    Returns
    -------
    SlotRange
        The range.
    """
    meta = Controller.__dataclass_fields__[name].metadata
    r = SlotRange.of(meta)
    if name in _SPLIT:
        return SlotRange(_SPLIT[name], r.high, True, zero=True, unit=r.unit)
    return r


def slot_range(model: Model, name: str) -> SlotRange:
    """The values the model's parameter slot ``name`` may take: the range of the
    parameter-file field it is filled from (or, for a derived value, of the fields it is
    derived from), in the slot's unit (:func:`feeddrive.model.slots.slot_unit`).

    Parameters
    ----------
    model : feeddrive.model.Model
        The assembled model.
    name : str
        One of its slot names (``Model.parameter_names``).

    Returns
    -------
    SlotRange
        The range (:data:`FINITE` for a slot no field fills: the profile block, the
        linearisation's inputs, the loop-breaking injections).

    Raises
    ------
    ParameterError
        For a machine's coupling slot (``couplings.<name>.<field>``): its part declares no
        range (it checks the value when the machine is built); one line naming the slot.

    Notes
    -----
    A machine's slot ``<axis>.<slot>`` has the range of the axis' own ``<slot>`` (as its
    unit, :func:`~feeddrive.model.slots.slot_unit`); it, and a coupling slot, raised a bare
    ``KeyError`` (session 27).
    """
    unit = slot_unit(model, name)
    if name in dict(model.slot_units):  # a coupling part's parameter: declared with a unit
        raise ParameterError(name, MISSING, f"no range is declared for a machine's coupling "
                             f"slot [{unit}]; its part checks the value when the machine is "
                             "built")
    prefix, own = axis_scope(model, name)
    return _slot_range(model, own, prefix).with_unit(unit)


def _slot_range(model: Model, name: str, prefix: str = "") -> SlotRange:
    """The range of slot ``name`` of the drive whose names in ``model`` start with ``prefix``
    (``""``: the model is one drive; ``"x."``: a machine's axis x)."""
    names = tuple(p[len(prefix):] for p in model.parameter_names if p.startswith(prefix))
    if name.startswith(("profile[", "inputs.")):
        return FINITE
    axis = re.fullmatch(r"controller\.(\w+)\.(\w+)", name)
    if axis:
        return _axis_range(names, axis.group(1), axis.group(2))
    loop = re.fullmatch(r"controller\.(\w+_period)", name)
    if loop:
        return controller_range(loop.group(1))
    site = re.fullmatch(r"(friction|compensation)\.(\w+)\.(.+)", name)
    if site:
        group, where, slot = site.groups()
        if group == "compensation":
            meta = field_metadata(LuGreParameters, slot)
            assert meta is not None, name
            r = SlotRange.of(meta)
            scale = _COMPENSATION_SCALES.get(slot.rsplit(".", 1)[-1])
            if scale is not None:
                r = r * SlotRange.of(Compensation.__dataclass_fields__[scale].metadata)
            return r
        if slot == "element_count":  # a structure count, fixed at export
            return SlotRange(1.0, math.inf, integer=True)
        law = friction_law(dict(model.sites).get(prefix + where, "lugre")).parameters_class
        meta = field_metadata(law, re.sub(r"\[\d+\]$", "[0]", slot))
        assert meta is not None, name
        return SlotRange.of(meta)
    if name == "compensation.observer_gain":
        return SlotRange.of(Compensation.__dataclass_fields__["observer_gain"].metadata)
    harmonic = re.fullmatch(r"disturbances\.(\w+)\[(\d+)\]", name)
    if harmonic:  # orders, then amplitudes, then phases
        field, i = harmonic.group(1), int(harmonic.group(2))
        n = sum(1 for p in names if p.startswith(f"disturbances.{field}["))
        part = ("orders", "amplitudes", "phases")[min(i // max(n // 3, 1), 2)]
        return _field(f"disturbances.{field}.{part}")
    linear = "motor.force_constant" in names
    if linear and name in LINEAR_MOTOR:
        return LINEAR_MOTOR[name](_field)
    if not linear and name in RACK_MOTOR:
        return _field(f"rack_pinion.{name}")
    if name in DERIVED:
        return DERIVED[name](_field)
    if name.startswith("disturbances.load_") and name != "disturbances.load_start":
        return FINITE  # the load record's encoding (the FMU's load_force input drives it)
    meta = field_metadata(DriveParameters, name)
    if meta is None:
        raise KeyError(f"no declared range for the model slot {name!r}")
    return SlotRange.of(meta)


def _axis_range(names: tuple[str, ...], axis: str, slot: str) -> SlotRange:
    if slot in _AXIS_SWITCHES:
        return _AXIS_SWITCHES[slot]
    if slot in AXIS_SLOT_FIELDS:
        return controller_range(AXIS_SLOT_FIELDS[slot])
    if slot == "enc_q":  # 2π / encoder_counts: 0 (ideal) or counts 1 … the field's high
        high = controller_range("encoder_counts").high
        return SlotRange(2.0 * math.pi / high, 2.0 * math.pi, zero=True)
    if slot == "H":  # the axis' transmission: its mechanism's, 1 on a linear axis
        if "motor.force_constant" in names:
            return SlotRange(1.0, 1.0)
        key = "rack_pinion.H" if "rack_pinion.H" in names else "screw.H"
        return DERIVED[key](_field)
    return FINITE  # inj_speed, inj_current: the linearisation's loop-breaking inputs


__all__ = ["SlotRange", "slot_range", "controller_range", "FINITE", "SWITCH", "POSITIVE"]
