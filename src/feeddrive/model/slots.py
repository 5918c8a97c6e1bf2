"""The parameters a run used, written from the assembled model's named slots.

A model's numbers live in its packed vector ``P``, each under a slot name
(``Model.parameter_names``, ``Model.parameter(name)``).  :func:`slot_table` writes those
slots with their SI units, so a run's record (its NetCDF/MAT attribute ``parameter_slots``,
:attr:`feeddrive.Result.parameter_slots`) is what the kernels read, not the parameter set
serialised again: a value the mechanism derives (the screw's H, an axis' inertia sum, the
stiffness chain's compliance) is recorded as the model computed it.  :func:`packed_vector`
reads such a record back into the packed vector.

A slot's unit comes from the declaration that fills it: a slot declared with its unit has
it (a machine's coupling parameters, ``Model.slot_units``); a
slot named by a path into the parameter set (``table.mass``,
``friction.screw.bristle_stiffness``, ``rack_pinion.mesh_stiffness``) has the unit its part's
parameter class declares (:func:`feeddrive.parameters.components.unit_of`; a friction site's
through its law's class), an axis slot (``controller.<axis>.kvp``) that of the
:class:`~feeddrive.model.loops.Controller` field it is packed from, resolved for the axis'
gain basis; the values a mechanism derives are listed in :data:`DERIVED_UNITS`.
"""

from __future__ import annotations

import json
import re
from typing import TYPE_CHECKING, Any

import numpy as np

from ..parameters import DriveParameters, ParameterError
from ..parameters.components import unit_of
from .friction import friction_law
from .friction.lugre_parameters import LuGreParameters
from .loops import Compensation, Controller

if TYPE_CHECKING:
    from .assemble import Model

#: the record's format (the attribute ``parameter_slots``)
FORMAT = "feeddrive.parameter_slots/1"

#: axis slot → the Controller field it is packed from (its unit), or its own unit
AXIS_SLOT_FIELDS: dict[str, str] = {
    "kpp": "position_gain", "kvp": "velocity_gain", "kvi": "velocity_integral_gain",
    "kip": "current_gain", "kii": "current_integral_gain", "kv": "velocity_command_gain",
    "i_max": "current_limit", "u_max": "voltage_limit", "grat_q": "grating_resolution"}
AXIS_SLOT_UNITS: dict[str, str] = {
    "kv_place": "-", "v_basis": "-", "v_feedback": "-", "ff": "-", "speed_mode": "-",
    "enc_q": "rad", "inj_current": "A"}

#: units of the slots a mechanism or part derives from several values (not a path into
#: the parameter set)
DERIVED_UNITS: dict[str, str] = {
    "screw.H": "m/rad", "screw.J": "kg m^2", "nut.J": "kg m^2", "nut.active": "-",
    "stiffness.k_fixed": "N/m", "stiffness.c0": "m/N", "stiffness.ea": "N",
    "stiffness.length": "m", "stiffness.support": "-", "stiffness.x0": "m",
    "rack_pinion.H": "m/rad", "rack_pinion.J": "kg m^2",
    "nut_motor.torque_constant": "N m/A", "nut_motor.back_emf_constant": "V s/rad",
    "nut_motor.inductance": "H", "nut_motor.resistance": "ohm",
    "motor.torque_constant": "N m/A", "motor.force_constant": "N/A",
    "motor.back_emf_constant": "V s/rad", "motor.inductance": "H", "motor.resistance": "ohm",
    "disturbances.load_step": "s", "disturbances.load_offset": "-",
    "disturbances.load_points": "-",
    "inputs.table_position_reference": "m", "inputs.table_speed_reference": "m/s",
    "inputs.nut_position_reference": "m", "inputs.nut_speed_reference": "m/s",
    "inputs.load_force": "N",
}
_HARMONIC_UNITS = {"lead_error": "m", "screw_motor_ripple": "N m",
                   "hollow_motor_ripple": "N m"}


def slot_unit(model: Model, name: str) -> str:
    """The SI unit of the model's parameter slot ``name`` ("-": dimensionless; "": a slot
    of mixed meaning, the reference profile's block).

    A machine's slot ``<axis>.<slot>`` (its model scopes each axis' names) has the unit of
    the axis' own ``<slot>``: a machine run recorded every one of them without a unit
    (``['x.table.mass', 20.0, '']``: session 27).
    A slot declared with its unit (``Model.slot_units``: a machine's coupling parameter
    ``couplings.<name>.<field>``, in the unit its part's class declares) has that unit: they
    too were recorded without one (``['couplings.beam.mass', 100.0, '']``: session 27).

    Parameters
    ----------
    model : feeddrive.model.Model
        The assembled model.
    name : str
        One of its slot names (``Model.parameter_names``).

    Returns
    -------
    str
        The unit.
    """
    declared = dict(model.slot_units).get(name)
    if declared is not None:
        return declared
    prefix, rest = axis_scope(model, name)
    return _scoped_unit(model, rest, prefix)


def axis_scope(model: Model, name: str) -> tuple[str, str]:
    """The axis prefix of a machine's slot and the axis' own slot name.

    Parameters
    ----------
    model : feeddrive.model.Model
        The assembled model (one drive, or a machine whose model scopes each axis' names).
    name : str
        A slot name.

    Returns
    -------
    tuple of (str, str)
        ``("x.", "table.mass")`` for a machine's ``x.table.mass``; ``("", name)`` for a
        slot of one drive's model or a machine's coupling slot.
    """
    scope, _, rest = name.partition(".")
    if rest and f"{scope}.table_position" in model.state_names:  # a machine's axis
        return f"{scope}.", rest
    return "", name


def _scoped_unit(model: Model, name: str, prefix: str) -> str:
    """The unit of slot ``name`` of the drive whose names in ``model`` start with ``prefix``
    (``""``: the model is one drive; ``"x."``: a machine's axis x)."""
    if name.startswith("profile["):
        return ""  # the reference profile's encoded block (feeddrive.model.reference)
    axis = re.fullmatch(r"controller\.(\w+)\.(\w+)", name)
    if axis:
        return _axis_unit(model, prefix, axis.group(1), axis.group(2))
    site = re.fullmatch(r"(friction|compensation)\.(\w+)\.(.+)", name)
    if site and site.group(3) in ("observer_gain",):
        site = None
    if site:
        group, where, slot = site.groups()
        cls = (friction_law(dict(model.sites).get(prefix + where, "lugre")).parameters_class
               if group == "friction" else LuGreParameters)
        if slot == "element_count":
            return "-"
        return unit_of(cls, re.sub(r"\[\d+\]$", "[0]", slot)) or ""
    harmonic = re.fullmatch(r"disturbances\.(\w+)\[(\d+)\]", name)
    if harmonic:  # orders, then amplitudes, then phases
        field, i = harmonic.group(1), int(harmonic.group(2))
        n = sum(1 for p in model.parameter_names
                if p.startswith(f"{prefix}disturbances.{field}["))
        return ("-", _HARMONIC_UNITS.get(field, ""), "rad")[min(i // max(n // 3, 1), 2)]
    if name == "motor.back_emf_constant" \
            and f"{prefix}motor.force_constant" in model.parameter_names:
        return "V s/m"  # a linear motor's
    if name in DERIVED_UNITS:
        return DERIVED_UNITS[name]
    if name == "compensation.observer_gain":
        return unit_of(Compensation, "observer_gain") or ""
    return unit_of(DriveParameters, name) or ""


def _axis_unit(model: Model, prefix: str, axis: str, slot: str) -> str:
    if slot in AXIS_SLOT_UNITS:
        return AXIS_SLOT_UNITS[slot]
    # a machine's axes each have their controller axes of these names: the one of this drive
    command = next((c.speed_command for c in model.control_axes
                    if c.name == axis and c.speed_command.startswith(prefix)), "")
    speed = next((s.unit for s in model.aux if s.name == command), "rad/s")
    if slot == "inj_speed":
        return speed
    if slot == "H":
        return "m/rad" if speed == "rad/s" else "-"
    field = AXIS_SLOT_FIELDS[slot]
    on_table = model.parameter(f"{prefix}controller.{axis}.v_basis") > 0.5
    meta = {f.name: f.metadata for f in Controller.__dataclass_fields__.values()}[field]
    return str(meta["table_unit"] if on_table and meta.get("table_unit") else meta["unit"])


def slot_table(model: Model) -> list[tuple[str, float, str]]:
    """Every parameter slot of the model: (name, value [SI], unit), in ``P`` order.

    Parameters
    ----------
    model : feeddrive.model.Model
        The assembled model.

    Returns
    -------
    list of (str, float, str)
        One row per slot.
    """
    return [(name, float(model.P[i]), slot_unit(model, name))
            for i, name in enumerate(model.parameter_names)]


def slots_json(model: Model) -> str:
    """The slot table as JSON text (the attribute ``parameter_slots`` of a run's record).

    Floats are written with their shortest exact representation, so
    :func:`packed_vector` reads back the same vector bit for bit.

    Parameters
    ----------
    model : feeddrive.model.Model
        The assembled model.

    Returns
    -------
    str
        ``{"format": FORMAT, "drive": …, "slots": [[name, value, unit], …]}``.
    """
    return json.dumps({"format": FORMAT, "drive": model.drive,
                       "slots": [list(row) for row in slot_table(model)]},
                      allow_nan=False, separators=(",", ":"))


def packed_vector(record: str | dict[str, Any]) -> tuple[tuple[str, ...], np.ndarray]:
    """The slot names and packed vector of a written slot table.

    Parameters
    ----------
    record : str or dict
        :func:`slots_json`'s text (or its parsed form).

    Returns
    -------
    tuple of (tuple of str, numpy.ndarray)
        The slot names and their values [SI], in ``P`` order.
    """
    data = json.loads(record) if isinstance(record, str) else record
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise ParameterError("parameter_slots", str(record)[:80],
                             f"expected a {FORMAT} record")
    rows = data["slots"]
    return tuple(str(r[0]) for r in rows), np.array([float(r[1]) for r in rows])
