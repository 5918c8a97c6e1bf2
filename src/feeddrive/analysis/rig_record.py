"""Real rig records for ``feeddrive fit``: MATLAB ``.mat`` files with the variables named by
the user (``--map time=t position=qm reference=qg force=vir``), SI units.

The layout is that of the EMPS benchmark (Janot, Gautier & Brunot [1]_: a ball-screw axis in
closed loop; time ``t`` [s], position reference ``qg`` [m], measured position ``qm`` [m],
motor force ``vir`` [N]), but any names do.  What each role is (:data:`ROLES`):

* ``time`` — sample times [s]; the record's first sample is t = 0, the drive at rest;
* the reference that drives the model, one of ``reference`` (a table *position* reference
  [m]: its rate is the speed reference, taken so that its integral is the reference at every
  sample (:func:`reference_rate`; central differences for a quantised or noisy one), so the
  drive's own speed feed-forward and position loop follow it, ∫v = reference − its first
  value) or
  ``speed_reference`` [m/s];
* fitted signals, any of ``position`` [m] (relative to its first sample), ``speed`` [m/s],
  ``current`` [A] (the current of the motor that drives the table) and ``force`` [N] (that
  motor's force at the table, compared as its current: F / (K·ω/v), K the motor's torque or
  force constant and ω/v its rate per table speed from the drive's kinematics), and
  ``drive_force`` [N] (the force on the table from the drive, a load cell between them);
* with ``--input`` (an open-loop replay, :mod:`feeddrive.model.replay`), instead of a
  reference: the replayed ``current`` [A], ``torque`` [N m], ``force`` [N] or
  ``motor_speed`` [rad/s] (:data:`INPUT_ROLES`), which is then not fitted.

Cleaning, each step stated in one line (:attr:`RigRecord.notes`): samples where a mapped
variable is NaN or infinite are dropped (the runs of them counted and located); duplicated
time stamps keep their first sample; irregular steps are kept (the model is compared at the
measured instants) and the reference is resampled on a uniform grid of the median step.  A
time that goes backwards is refused.

A .mat carries no units, so the values are held to what a drive shows, each refusal in one
line naming ``--map ROLE=VARIABLE``, what was seen and the unit it is likelier in: any value
to the bound a CSV column is held to (``feeddrive.io.measured.LARGEST_MAGNITUDE``: 1 km,
100 m/s, 1e7 N …), and a variable read in SI for want of a unit to what the drive of the set
can show — a time to a median step below :data:`LARGEST_UNITLESS_STEP` (else likely ms), a
position or position reference to a stroke within the table's travel (the screw's length)
and a mean speed within the axis's (else likely mm), a speed to the axis's speed
(:func:`~feeddrive.analysis.positioning_run.axis_speed_limit`; else likely mm/s), a current
to :data:`CURRENT_LIMIT_MARGIN` × the controller's current limit (else likely mA).  A unit in
the map is taken as given.

A variable may be a field of a 1×1 struct, named by MATLAB's dotted path: ``rec.pos[mm]``,
``feeddrive.table_position`` (feeddrive's own ``.mat`` export keeps a run in the struct
``feeddrive``, a machine's axis in ``feeddrive.x``).  A path that ends at a struct, a field
a struct does not hold and a struct array (no indexing) are refused in one line, naming the
struct's fields.

MATLAB v7.3 files are HDF5 and ``scipy.io.loadmat`` cannot read them: they are read through
h5py when it is installed, else refused in one line.  An empty variable or field (``[]``) and
text (a char array) are refused as what they are.

References
----------
.. [1] A. Janot, M. Gautier, M. Brunot, "Data set and reference models of EMPS",
   Nonlinear System Identification Benchmarks workshop, Eindhoven, 2019.
"""

from __future__ import annotations

import importlib.util
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..io.measured import (
    CURRENT_UNITS,
    FORCE_UNITS,
    LARGEST_MAGNITUDE,
    LENGTH_UNITS,
    SPEED_UNITS,
    TIME_UNITS,
    encoding_hint,
    first_beyond_largest,
    split_unit,
    unit_factor,
)
from ..parameters import DriveParameters, ParameterError
from ..parameters.validation import MISSING
from .fit import (
    _ROTARY_SPEED_UNITS,
    _TORQUE_UNITS,
    MS_TIME_HINT,
    Experiment,
    FitError,
    _uniform_reference,
    unit_steps,
)
from .fit_statistics import noise_level

__all__ = ["CURRENT_LIMIT_MARGIN", "FITTED_ROLES", "INPUT_ROLES", "LARGEST_UNITLESS_STEP",
           "REFERENCE_ROLES", "ROLES", "ROLE_UNITS", "RigRecord", "emps_layout", "parse_map",
           "read_rig_record", "reference_rate", "role_factor",
           "table_motor_force_per_current"]

#: role → what it is [SI unit]
ROLES: dict[str, str] = {
    "time": "sample times [s]",
    "reference": "table position reference [m] (drives the model)",
    "speed_reference": "table speed reference [m/s] (drives the model)",
    "position": "measured table position [m] (fitted)",
    "speed": "measured table speed [m/s] (fitted)",
    "current": "measured current of the motor driving the table [A] (fitted)",
    "force": "measured force of the motor driving the table [N] (fitted as its current)",
    "drive_force": "measured force on the table from the drive [N] (screw–nut or mesh force, "
                   "a load cell between drive and table; fitted as drive_force)",
    "torque": "measured motor torque [N m] (with --input torque)",
    "motor_speed": "measured motor speed [rad/s] (with --input speed)",
}
#: role → (dimension, the units a variable of it may be given in, ``VARIABLE[UNIT]``): the
#: tables of a CSV header's bracketed unit (feeddrive.io.measured; a torque's and a motor
#: speed's: those of a CSV trace's, feeddrive.analysis.fit); the first is the SI unit taken
#: when none is given
ROLE_UNITS: dict[str, tuple[str, Mapping[str, float]]] = {
    "time": ("time", TIME_UNITS),
    "reference": ("length", LENGTH_UNITS),
    "speed_reference": ("speed", SPEED_UNITS),
    "position": ("length", LENGTH_UNITS),
    "speed": ("speed", SPEED_UNITS),
    "current": ("current", CURRENT_UNITS),
    "force": ("force", FORCE_UNITS),
    "drive_force": ("force", FORCE_UNITS),
    "torque": ("torque", _TORQUE_UNITS),
    "motor_speed": ("rotary speed", _ROTARY_SPEED_UNITS),
}
#: the roles a record's reference may take: a position or a speed reference
REFERENCE_ROLES = ("reference", "speed_reference")
#: the roles a record's measured, fitted channels may take
FITTED_ROLES = ("position", "speed", "current", "force", "drive_force")
#: ``--input`` (an open-loop replay, :mod:`feeddrive.model.replay`) → the role it replays
INPUT_ROLES = {"current": "current", "torque": "torque", "force": "force",
               "speed": "motor_speed"}
#: a time read in s for want of a unit whose median sample step is at least this is refused
#: as likely in ms [s]: read in s it is a record at 10 Hz or slower, at most 5 samples in the
#: fit's first 0.5-s stage (fit.FIRST_HORIZON) and none of a drive's loop dynamics; read in
#: ms it is a record at 10 kHz or slower, the rates drives are recorded at (EMPS: 1 kHz)
LARGEST_UNITLESS_STEP = 0.1
#: a current read in A for want of a unit is refused as likely in mA beyond this multiple of
#: the set's controller.current_limit (or of engine.options.NO_CURRENT_LIMIT, the current
#: feeddrive takes as no limit, when the set has none): a current held at its limit
#: overshoots it by its loop's overshoot and noise, not twofold
CURRENT_LIMIT_MARGIN = 2.0


def role_factor(role: str, unit: str | None, field: str) -> float:
    """The factor that turns a ``role``'s variable given in ``unit`` into SI
    (:data:`ROLE_UNITS`); 1 without a unit.

    Parameters
    ----------
    role : str
        A key of :data:`ROLES`.
    unit : str or None
        The unit in brackets after the variable (``t_ms[ms]``), or None.
    field : str
        The field named by a refusal (``--map time``, ``mapping.time``).

    Returns
    -------
    float
        SI value of one ``unit`` [SI unit of the role].

    Raises
    ------
    ParameterError
        For a unit that is not one of the role's.
    """
    if unit is None:
        return 1.0
    dimension, table = ROLE_UNITS[role]
    si = next(iter(table))
    try:
        if dimension in ("time", "length", "speed", "current", "force"):
            return unit_factor(unit, dimension, what=field)
        return table[unit]
    except (KeyError, ValueError):
        raise ParameterError(field, unit, f"expected a unit of {dimension} [{si}] in brackets "
                             f"after the variable, one of {', '.join(table)}"
                             f"{encoding_hint(unit)}") from None


def _variable(role: str, spec: str, field: str) -> tuple[str, str | None]:
    """``VARIABLE`` or ``VARIABLE[UNIT]`` → (variable, unit or None), the unit checked."""
    name, unit = split_unit(spec)
    if not name or "[" in name or "]" in name or unit == "":
        raise ParameterError(field, spec, "expected VARIABLE or VARIABLE[UNIT], e.g. "
                             f"t_ms[ms] [{next(iter(ROLE_UNITS[role][1]))}]")
    if any(c in name for c in "(){}"):
        raise ParameterError(field, spec, "expected VARIABLE or a 1×1 struct's field "
                             "STRUCT.FIELD, e.g. rec.pos[mm]; an element of a struct array or "
                             "cell (rec(2).pos, c{1}) is not read: save it as its own variable")
    if "" in name.split("."):
        raise ParameterError(field, spec, "expected VARIABLE or a struct's field "
                             "STRUCT.FIELD, e.g. rec.pos[mm]: a name between dots is empty")
    role_factor(role, unit, field)
    return name, unit


def parse_map(items: Sequence[str], input: str | None = None) -> dict[str, str]:
    """``ROLE=VARIABLE`` items (each may hold several, separated by spaces or commas) as
    {role: variable}; one-line refusals for an unknown role, a role given twice, a variable
    given two roles, or no time, no reference or no fitted signal.  With ``input`` (an
    open-loop replay) the record needs that input's role (:data:`INPUT_ROLES`) and no
    reference: the loops are bypassed.  A variable not in the role's SI unit carries its unit
    in brackets, as a CSV header does: ``time=t_ms[ms]``, ``position=qm[mm]``
    (:data:`ROLE_UNITS`); it is kept in the returned variable (``"t_ms[ms]"``) and converted
    by :func:`read_rig_record`.

    Parameters
    ----------
    items : sequence of str
        The ``--map`` values.
    input : str or None, default None
        ``--input``: ``"current"``, ``"torque"``, ``"force"`` or ``"speed"``.

    Returns
    -------
    dict
        Role → variable name.

    Raises
    ------
    FitError
        Naming the item.
    """
    out: dict[str, str] = {}
    for item in items:
        for part in item.replace(",", " ").split():
            role, sep, var = part.partition("=")
            role, var = role.strip(), var.strip()
            if part.startswith("["):
                raise FitError(f"--map {part!r}: a unit goes right after its variable, "
                               "without a space (e.g. time=t_ms[ms])")
            if not sep or not role or not var:
                raise FitError(f"--map {part!r}: expected ROLE=VARIABLE (e.g. time=t)")
            if role not in ROLES:
                raise FitError(f"--map {part}: unknown role {role!r}; expected one of "
                               f"{', '.join(ROLES)}")
            if role in out:
                raise FitError(f"--map {part}: role {role!r} given twice ({role}="
                               f"{out[role]})")
            name, unit = _variable(role, var, f"--map {role}")
            var = name if unit is None else f"{name}[{unit}]"
            other = next((r for r, v in out.items() if split_unit(v)[0] == name), None)
            if other is not None:
                raise FitError(f"--map {part}: variable {var!r} given two roles ({other} and "
                               f"{role})")
            out[role] = var
    if "time" not in out:
        raise FitError("--map: no time=VARIABLE given")
    refs = [r for r in REFERENCE_ROLES if r in out]
    if input is not None:
        if input not in INPUT_ROLES:
            raise FitError(f"--input {input!r}: expected one of {', '.join(INPUT_ROLES)}")
        role = INPUT_ROLES[input]
        if role not in out:
            raise FitError(f"--input {input}: no {role}=VARIABLE in --map (the replayed "
                           "signal)")
        if refs:
            raise FitError(f"--map {refs[0]}={out[refs[0]]}: with --input {input} the loops "
                           "are bypassed and a reference drives nothing; leave it out")
        extra = [r for r in INPUT_ROLES.values() if r in out and r != role
                 and r not in FITTED_ROLES]
        if extra:
            needs = next(k for k, v in INPUT_ROLES.items() if v == extra[0])
            raise FitError(f"--map {extra[0]}={out[extra[0]]}: a {extra[0]} is replayed only "
                           f"with --input {needs}")
        if not any(r in out for r in FITTED_ROLES if r != role):
            raise FitError(f"--map: no measured signal to fit besides the replayed {role}; "
                           "give one or more of "
                           f"{', '.join(f'{r}=VARIABLE' for r in FITTED_ROLES if r != role)}")
        return out
    for role in ("torque", "motor_speed"):
        if role in out:
            raise FitError(f"--map {role}={out[role]}: a {role} is replayed only with --input "
                           f"{next(k for k, v in INPUT_ROLES.items() if v == role)}")
    if len(refs) != 1:
        raise FitError("--map: give exactly one of reference=VARIABLE (a position reference "
                       "[m]) or speed_reference=VARIABLE [m/s]" +
                       (f"; got {' and '.join(refs)}" if refs else ""))
    if not any(r in out for r in FITTED_ROLES):
        raise FitError(f"--map: no measured signal to fit; give one or more of "
                       f"{', '.join(f'{r}=VARIABLE' for r in FITTED_ROLES)}")
    return out


class _PathRefused(Exception):
    """A mapped ``name`` (a variable or a struct's field) that holds no numeric array: why,
    in one line, without the role (:func:`read_rig_record` adds it)."""

    def __init__(self, name: str, reason: str) -> None:
        super().__init__(reason)
        self.name = name


def _load_mat(path: Path, names: Sequence[str]) -> dict[str, np.ndarray]:
    """The arrays ``names`` name in a MATLAB file (v5/v7 by scipy.io, v7.3 by h5py): variables
    (``qm``) or fields of 1×1 structs, MATLAB's dotted paths (``rec.pos``,
    ``feeddrive.x.table_position``); :class:`_PathRefused` for the first that names none."""
    from scipy.io import loadmat

    src = str(path)
    if not path.is_file():
        raise FitError(f"{src}: no such file")
    tops = list(dict.fromkeys(name.split(".")[0] for name in names))
    try:
        raw: dict[str, Any] = loadmat(path, variable_names=tops, struct_as_record=False)
        held = sorted(k for k in _mat_names(path) if not k.startswith("__"))
    except NotImplementedError:  # scipy: "Please use HDF reader for matlab v7.3 files"
        return _load_mat73(path, names)
    except (ValueError, TypeError, OSError) as err:
        raise FitError(f"{src}: not a readable MATLAB file ({err})") from None
    return {name: _mat5_array(raw, name, held, src) for name in names}


def _mat_names(path: Path) -> list[str]:
    from scipy.io import whosmat

    return [name for name, _, _ in whosmat(path)]


def _numeric(name: str, a: np.ndarray, src: str) -> np.ndarray:
    if a.size == 0:  # a 0×1 read as a vector of no samples: "differ in length" after
        raise _PathRefused(name, _EMPTY.format(name=name, src=src))
    if a.dtype.kind not in "fiub" or a.squeeze().ndim != 1:
        raise _PathRefused(name, f"{name!r} in {src} is not a numeric vector (shape {a.shape})")
    return a


_EMPTY = "{name!r} in {src} is empty ([] in MATLAB): no samples to read"


def _h5_numeric(name: str, node: Any, src: str) -> np.ndarray:
    """A v7.3 dataset as :func:`_numeric`: MATLAB keeps an empty array as its dimensions
    (``MATLAB_empty``; they read as the samples [0, 0]) and text as uint16 character codes
    (``MATLAB_class`` char; they passed as numbers), both refused as what they are."""
    if int(np.asarray(node.attrs.get("MATLAB_empty", 0)).ravel()[0]):
        raise _PathRefused(name, _EMPTY.format(name=name, src=src))
    kind = node.attrs.get("MATLAB_class", b"")
    if (kind.decode("ascii", "replace") if isinstance(kind, bytes) else str(kind)) == "char":
        raise _PathRefused(name, f"{name!r} in {src} is text (a MATLAB char array), not a "
                           "numeric vector")
    return _numeric(name, np.asarray(node).T, src)  # MATLAB's columns, transposed


def _struct_refusal(name: str, where: str, src: str, elements: int,
                    fields: Sequence[str], field: str | None) -> _PathRefused:
    """Why ``where`` (a struct, or a struct array of ``elements``) is not what ``name`` needs:
    a numeric vector (``field`` None) or a 1×1 struct holding ``field``."""
    if elements != 1:
        return _PathRefused(name, f"{where!r} in {src} is a struct array of {elements} "
                            "elements; the map reads a variable or a field of a 1×1 struct "
                            "(no indexing): save the element wanted as its own variable")
    listed = ", ".join(fields) or "none"
    if field is None:
        return _PathRefused(name, f"{where!r} in {src} is a struct, not a numeric vector; name "
                            f"one of its fields, {where}.FIELD (its fields: {listed})")
    return _PathRefused(name, f"no field {field!r} in struct {where!r} of {src} (its fields: "
                        f"{listed})")


def _mat5_array(raw: Mapping[str, Any], name: str, held: Sequence[str],
                src: str) -> np.ndarray:
    """The array at ``name``'s path in ``raw`` (``loadmat(..., struct_as_record=False)``:
    a struct an object array of ``mat_struct``)."""
    from scipy.io.matlab import mat_struct

    parts = name.split(".")
    if parts[0] not in raw:
        raise _PathRefused(name, f"no variable {parts[0]!r} in {src} (it holds: "
                           f"{', '.join(held) or 'nothing'})")
    value = raw[parts[0]]
    for depth in range(1, len(parts) + 1):
        where = ".".join(parts[:depth])
        field = parts[depth] if depth < len(parts) else None
        structs = isinstance(value, np.ndarray) and value.dtype == object and value.size > 0 \
            and all(isinstance(v, mat_struct) for v in value.flat)
        if not structs:
            if field is not None:
                raise _PathRefused(name, f"{where!r} in {src} is not a struct (shape "
                                   f"{np.shape(value)}): it has no field {field!r}")
            return _numeric(name, np.asarray(value), src)
        fields = list(value.flat[0]._fieldnames)
        if value.size != 1 or field is None or field not in fields:
            raise _struct_refusal(name, where, src, value.size, fields, field)
        value = getattr(value.flat[0], field)
    raise AssertionError("unreachable: the last part returns or refuses")


def _load_mat73(path: Path, names: Sequence[str]) -> dict[str, np.ndarray]:
    """:func:`_load_mat` of a MATLAB v7.3 (HDF5) file: a 1×1 struct is a group, its fields
    its members."""
    src = str(path)
    if importlib.util.find_spec("h5py") is None:
        raise FitError(f"{src}: a MATLAB v7.3 (HDF5) file; install h5py to read it, or "
                       "save it in MATLAB with save(..., '-v7')")
    import h5py

    try:
        with h5py.File(path, "r") as f:
            held = sorted(k for k in f.keys() if not k.startswith("#"))
            return {name: _h5_array(f, name, held, src) for name in names}
    except (ValueError, TypeError, OSError) as err:
        raise FitError(f"{src}: not a readable MATLAB file ({err})") from None


def _h5_array(f: Any, name: str, held: Sequence[str], src: str) -> np.ndarray:
    """The array at ``name``'s path in the open v7.3 file ``f``."""
    import h5py

    parts = name.split(".")
    if parts[0] not in held:
        raise _PathRefused(name, f"no variable {parts[0]!r} in {src} (it holds: "
                           f"{', '.join(held) or 'nothing'})")
    node = f[parts[0]]
    for depth in range(1, len(parts) + 1):
        where = ".".join(parts[:depth])
        field = parts[depth] if depth < len(parts) else None
        if not isinstance(node, h5py.Group):
            if field is not None:
                raise _PathRefused(name, f"{where!r} in {src} is not a struct (shape "
                                   f"{node.shape[::-1]}): it has no field {field!r}")
            return _h5_numeric(name, node, src)
        fields = [k for k in node.keys() if not k.startswith("#")]
        elements = _h5_struct_elements(node)
        if elements != 1 or field is None or field not in fields:
            raise _struct_refusal(name, where, src, elements, fields, field)
        node = node[field]
    raise AssertionError("unreachable: the last part returns or refuses")


def _h5_struct_elements(group: Any) -> int:
    """The elements of a v7.3 struct: 1 (a group of its fields), or those of a struct array,
    whose fields are arrays of object references, one per element, with no ``MATLAB_class``
    (a cell array's has one)."""
    import h5py

    for member in group.values():
        if isinstance(member, h5py.Dataset) and "MATLAB_class" not in member.attrs \
                and h5py.check_dtype(ref=member.dtype) is not None:
            return int(member.size)
    return 1


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(first, last) index of each run of True in ``mask``."""
    edges = np.diff(np.concatenate([[0], mask.astype(int), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1, strict=True))


@dataclass(frozen=True)
class RigRecord:
    """A rig record read for the fit, and what was done to it.

    Parameters
    ----------
    experiment : Experiment
        The record as the fit takes it (SI).
    notes : tuple of str
        One line per cleaning step taken.
    mapping : dict
        Role → variable.
    """

    experiment: Experiment
    notes: tuple[str, ...] = ()
    mapping: Mapping[str, str] = field(default_factory=dict)


def table_motor_force_per_current(params: DriveParameters, drive: str,
                                  table_position: float) -> tuple[str, float]:
    """The current signal of the motor that drives the table and its force at the table per
    ampere: K × (its rate per table speed) [N/A] (a linear motor: its force constant).

    Parameters
    ----------
    params : DriveParameters
        The set.
    drive : str
        The drive.
    table_position : float
        Table position [m].

    Returns
    -------
    tuple of (str, float)
        The current signal's name and the force per ampere [N/A].

    Raises
    ------
    FitError
        For a drive whose table is driven by more than one motor (no single motor force).
    """
    from ..engine.simulate import DriveSystem
    from ..model.reference import ConstantSpeed

    system = DriveSystem(params, drive, table_position)
    topology = system.topology()
    axes = topology.live_axes()
    if len(axes) != 1:
        raise FitError(f"--map force: the {drive.upper()} drives its table with "
                       f"{len(axes)} motors ({', '.join(axes)}); a single force is not "
                       "one of its signals: map each motor's current instead")
    axis = topology.table_axis
    slot, _ = topology.motor_output(axis)
    constant = float(system.model(ConstantSpeed(0.0)).parameter(slot))
    rates = topology.steady_motion(1.0, 0.0)
    ratio = float(rates[f"{axis}_angle"][1]) if f"{axis}_angle" in rates else 1.0
    return f"{axis}_current", constant * ratio


@dataclass(frozen=True)
class _DriveLimits:
    """What the drive of the set can show, each with what sets it: the table's travel [m]
    (None when no screw bounds it), its speed [m/s] and a motor's current [A]."""

    travel: tuple[float, str] | None
    speed: tuple[float, str]
    current: tuple[float, str]


def _drive_limits(params: DriveParameters, drive: str) -> _DriveLimits:
    from ..engine.options import NO_CURRENT_LIMIT
    from .positioning_run import axis_speed_limit, axis_travel

    limit = float(params.controller.current_limit)
    if 0.0 < limit < NO_CURRENT_LIMIT:
        current = (CURRENT_LIMIT_MARGIN * limit, f"{CURRENT_LIMIT_MARGIN:g} × the controller's "
                   f"limit, controller.current_limit = {limit:g} A")
    else:
        current = (CURRENT_LIMIT_MARGIN * NO_CURRENT_LIMIT, f"{CURRENT_LIMIT_MARGIN:g} × "
                   f"{NO_CURRENT_LIMIT:g} A, the current feeddrive takes as no limit: the set "
                   "gives none")
    return _DriveLimits(travel=axis_travel(params, drive),
                        speed=axis_speed_limit(params, drive), current=current)


def _implausible(role: str, values: np.ndarray, time: np.ndarray,
                 limits: _DriveLimits) -> tuple[str, float, float] | None:
    """Why ``values`` [SI] of ``role``, read in SI for want of a unit, are none the drive can
    show — what was seen and the bound it passes — with the value and the bound [SI]; None
    when they are plausible, and for a force, a torque or a motor speed (held only to
    LARGEST_MAGNITUDE: a force has no smaller unit to be in)."""
    dimension = ROLE_UNITS[role][0]
    if dimension == "time":
        step = float(np.median(np.diff(values)))
        if step >= LARGEST_UNITLESS_STEP:
            return (f"a median sample step of {step:.4g} s read in s (no unit given): a record "
                    f"at {1.0 / step:.3g} Hz, slower than a drive's records are taken (steps < "
                    f"{LARGEST_UNITLESS_STEP:g} s)",
                    step, LARGEST_UNITLESS_STEP)
        return None
    speed, why = limits.speed
    if dimension == "length":
        stroke = float(np.ptp(values))
        if limits.travel is not None and stroke > limits.travel[0]:
            length, path = limits.travel
            return (f"a stroke of {stroke:.4g} m read in m (no unit given), longer than the "
                    f"table's travel ({path} = {length:g} m)", stroke, length)
        span = float(time[-1] - time[0])
        if stroke > speed * span:
            return (f"a stroke of {stroke:.4g} m in {span:.4g} s read in m (no unit given): a "
                    f"mean speed of {stroke / span:.4g} m/s, beyond the axis's {speed:.4g} m/s "
                    f"({why})", stroke / span, speed)
        return None
    top = float(np.max(np.abs(values)))
    if dimension == "speed" and top > speed:
        return (f"a speed of {top:.4g} m/s read in m/s (no unit given), beyond the axis's "
                f"{speed:.4g} m/s ({why})", top, speed)
    if dimension == "current" and top > limits.current[0]:
        return (f"a current of {top:.4g} A read in A (no unit given), beyond "
                f"{limits.current[0]:g} A ({limits.current[1]})", top, limits.current[0])
    return None


def _smaller_unit(role: str, value: float, bound: float) -> str | None:
    """Of ``role``'s units a thousand, a million, a billion times smaller than its SI unit
    (mm, µm, nm; ms, µs; mm/s, µm/s; mA), the largest in which ``value`` [SI] read in SI is
    within ``bound`` [SI], else the first; None when the role has none (N, rad/s)."""
    table = ROLE_UNITS[role][1]
    smaller = [next((u for u, f in table.items() if math.isclose(f, factor)), None)
               for factor in (1e-3, 1e-6, 1e-9)]
    units = [u for u in smaller if u is not None]
    for unit, factor in ((u, table[u]) for u in units):
        if value * factor < bound:
            return unit
    return units[0] if units else None


def _check_magnitudes(src: str, mapping: Mapping[str, str],
                      specs: Mapping[str, tuple[str, str | None]],
                      columns: Mapping[str, np.ndarray], limits: _DriveLimits) -> None:
    """Refuse, in one line naming ``--map ROLE=VARIABLE``, a mapped variable with a value no
    feed drive has (the bound of a CSV column, io.measured.LARGEST_MAGNITUDE, whatever its
    unit), or one read in SI for want of a unit that the drive of the set cannot show
    (:func:`_implausible`: a record in mm, ms or mA read 1000× off); time first, as the
    others' rates are taken on it.  Each names the unit it is likelier in."""
    for role in sorted(specs, key=lambda r: r != "time"):
        name, unit = specs[role]
        dimension, table = ROLE_UNITS[role]
        si = next(iter(table))
        field = f"--map {role}={mapping[role]}"
        values = columns[role]
        k = first_beyond_largest(values, dimension) if dimension in LARGEST_MAGNITUDE else None
        if k is not None:
            shown, factor = unit or si, role_factor(role, unit, field)
            largest = LARGEST_MAGNITUDE[dimension]
            hint = _unit_hint(role, name, unit, abs(float(values[k])), largest, escape=False)
            raise ParameterError(field, MISSING, f"a value of {values[k] / factor:.6g} "
                                 f"{shown} is beyond any feed drive (|{dimension}| ≤ "
                                 f"{largest / factor:g} {shown}); {hint}", source=src)
        found = _implausible(role, values, columns["time"], limits) if unit is None else None
        if found is not None:
            seen, value, bound = found
            raise ParameterError(field, MISSING, f"{seen}; "
                                 f"{_unit_hint(role, name, unit, value, bound)}", source=src)


def _unit_hint(role: str, name: str, unit: str | None, value: float, bound: float, *,
               escape: bool = True) -> str:
    """What to write instead (no unit given): the variable with the smaller unit it is
    likelier in, and, with ``escape``, with its SI unit if it is in that after all (a unit
    given skips :func:`_implausible`); else: check its unit."""
    smaller = _smaller_unit(role, value, bound) if unit is None else None
    if smaller is None:
        return "check the variable's unit"
    si = next(iter(ROLE_UNITS[role][1]))
    return (f"if it is in {smaller} write {role}={name}[{smaller}]"
            + (f" ({role}={name}[{si}] if it is in {si})" if escape else ""))


def read_rig_record(path: str | Path, mapping: Mapping[str, str], params: DriveParameters,
                    *, drive: str = "cdfs", table_position: float = 0.4,
                    input: str | None = None) -> RigRecord:
    """Read one ``.mat`` rig record with its variables mapped to roles (module docstring).

    Parameters
    ----------
    path : str or Path
        The ``.mat`` file.
    mapping : mapping of str to str
        Role → variable (:func:`parse_map`).
    params : DriveParameters
        The set the record will be fitted with (for a force's conversion to current).
    drive : str, default "cdfs"
        The drive.
    table_position : float, default 0.4
        Table position [m].
    input : str or None, default None
        ``--input``: the mapped signal of that role (:data:`INPUT_ROLES`) drives the model
        open-loop on the record's own instants (:mod:`feeddrive.model.replay`) instead of a
        reference; it is then not a fitted signal.

    Returns
    -------
    RigRecord
        The experiment and the cleaning notes.

    Raises
    ------
    FitError
        A missing, empty or text variable, variables of different lengths, a time that goes
        backwards, too few samples, a reference that never moves; one line each, before any
        simulation.
    ParameterError
        A time read in s whose steps are those of ms; a value beyond any feed drive, or, read
        in SI for want of a unit, beyond what the drive of ``params`` shows (module
        docstring); naming ``--map ROLE=VARIABLE`` and the unit it is likelier in.
    """
    p = Path(path)
    src = str(p)
    if p.suffix.lower() != ".mat":
        raise FitError(f"{src}: --map reads MATLAB .mat records; expected a .mat file")
    specs: dict[str, tuple[str, str | None]] = {}
    for role, spec in mapping.items():
        if role not in ROLES:
            raise FitError(f"--map {role}={spec}: unknown role {role!r}; expected one of "
                           f"{', '.join(ROLES)}")
        specs[role] = _variable(role, str(spec), f"mapping.{role}")
    try:
        data = _load_mat(p, [name for name, _ in specs.values()])
    except _PathRefused as err:
        role = next(r for r, (name, _) in specs.items() if name == err.name)
        raise FitError(f"--map {role}={mapping[role]}: {err}") from None
    columns: dict[str, np.ndarray] = {}
    for role, (var, unit) in specs.items():
        a = data[var]
        factor = role_factor(role, unit, f"mapping.{role}")
        columns[role] = a.astype(float).ravel() if factor == 1.0 \
            else a.astype(float).ravel() * factor
    sizes = {r: c.size for r, c in columns.items()}
    if len(set(sizes.values())) > 1:
        raise FitError(f"{src}: the mapped variables differ in length ("
                       + ", ".join(f"{mapping[r]} {n}" for r, n in sizes.items()) + ")")
    notes: list[str] = []
    replayed = INPUT_ROLES[input] if input is not None else ""
    if "force" in columns and replayed != "force":
        current_name, per_amp = table_motor_force_per_current(params, drive, table_position)
        if "current" in columns:
            raise FitError("--map force and current: the same motor's current twice; give one")
    bad = ~np.all(np.isfinite(np.vstack(list(columns.values()))), axis=0)
    if bad.any():
        runs = _runs(bad)
        t_all = columns["time"]
        where = ", ".join(f"{t_all[a]:.6g} s" if a == b else f"{t_all[a]:.6g}–{t_all[b]:.6g} s"
                          for a, b in runs[:5]) + (" …" if len(runs) > 5 else "")
        notes.append(f"{src}: {len(runs)} run(s) of NaN or infinite samples ({int(bad.sum())} "
                     f"samples) dropped, at {where}")
        columns = {r: c[~bad] for r, c in columns.items()}
    t_raw = columns["time"]
    if t_raw.size < 16:
        raise FitError(f"{src}: {t_raw.size} usable samples; a record needs at least 16")
    steps = np.diff(t_raw)
    if np.any(steps < 0):
        i = int(np.flatnonzero(steps < 0)[0]) + 1
        raise FitError(f"--map time={mapping['time']}: the time goes backwards at sample "
                       f"{i} ({t_raw[i - 1]:.6g} → {t_raw[i]:.6g} s)")
    dup = np.concatenate([[False], steps == 0])
    if dup.any():
        notes.append(f"{src}: {int(dup.sum())} duplicated time stamp(s); the first sample of "
                     "each kept")
        columns = {r: c[~dup] for r, c in columns.items()}
        t_raw = columns["time"]
        steps = np.diff(t_raw)
    time_var, time_unit = specs["time"]
    if time_unit is None and unit_steps(t_raw):  # not guessed: said, and the unit asked for
        raise ParameterError(f"--map time={mapping['time']}", MISSING, "expected sample "
                             f"times in seconds [s]: {t_raw.size} samples, {t_raw[0]:.6g} … "
                             f"{t_raw[-1]:.6g}; {MS_TIME_HINT}: give its unit, time="
                             f"{time_var}[ms] (time={time_var}[s] for a 1-s step)", source=src)
    _check_magnitudes(src, mapping, specs, columns, _drive_limits(params, drive))
    dt = float(np.median(steps))
    unstated = [f"{role} {var} [{next(iter(ROLE_UNITS[role][1]))}]"
                for role, (var, unit) in specs.items() if unit is None]
    if unstated:  # the choice stated beside the numbers it makes
        notes.append(f"{src}: no unit in the map for {', '.join(unstated)}: read in SI; the "
                     f"record spans {float(t_raw[-1] - t_raw[0]):.6g} s ({t_raw.size} "
                     f"samples, median step {1e3 * dt:.4g} ms)")
    if float(steps.max() - steps.min()) > 0.01 * dt:
        notes.append(f"{src}: irregular sample steps ({1e3 * steps.min():.4g} … "
                     f"{1e3 * steps.max():.4g} ms): the model is compared at the measured "
                     f"instants, the reference resampled every {1e3 * dt:.4g} ms")
    t = t_raw - t_raw[0]
    if replayed:
        return _replay_record(src, t, columns, mapping, params, drive, table_position,
                              str(input), notes)
    if "reference" in columns:
        ref = columns["reference"] - columns["reference"][0]
        speed_ref, exact = reference_rate(ref, t)
        if not exact:
            notes.append(f"{src}: the position reference {mapping['reference']} is not "
                         "smooth (quantised or noisy): its rate taken by central "
                         "differences, the commanded position its integral")
    else:
        speed_ref = columns["speed_reference"]
    ref_t, ref_v = _uniform_reference(t, speed_ref)
    if not np.any(ref_v != 0.0):
        raise FitError(f"{src}: the reference never moves: nothing to fit")
    signals: dict[str, np.ndarray] = {}
    if "position" in columns:
        signals["table_position"] = columns["position"] - columns["position"][0]
    if "speed" in columns:
        signals["table_speed"] = columns["speed"]
    if "current" in columns:
        signals[_current_name(params, drive, table_position)] = columns["current"]
    if "force" in columns:
        signals[current_name] = columns["force"] / per_amp
        notes.append(f"{src}: force {mapping['force']} compared as the {current_name}: "
                     f"F / {per_amp:.6g} N/A")
    for name, v in signals.items():
        if float(np.ptp(v)) == 0.0:
            raise FitError(f"{src}: signal {name!r} is constant: no usable information")
    exp = Experiment(source=src, time=t, signals=signals, reference_time=ref_t,
                     table_speed=ref_v, noise={k: noise_level(v) for k, v in signals.items()})
    return RigRecord(experiment=exp, notes=tuple(notes), mapping=dict(mapping))


def _replay_record(src: str, t: np.ndarray, columns: Mapping[str, np.ndarray],
                   mapping: Mapping[str, str], params: DriveParameters, drive: str,
                   table_position: float, input: str, notes: list[str]) -> RigRecord:
    """The experiment of a record whose ``input`` signal drives the model (open loop)."""
    role = INPUT_ROLES[input]
    signals: dict[str, np.ndarray] = {}
    if "position" in columns:
        signals["table_position"] = columns["position"] - columns["position"][0]
    if "speed" in columns:
        signals["table_speed"] = columns["speed"]
    if "current" in columns and role != "current":
        signals[_current_name(params, drive, table_position)] = columns["current"]
    if "force" in columns and role != "force":
        current_name, per_amp = table_motor_force_per_current(params, drive, table_position)
        signals[current_name] = columns["force"] / per_amp
    if "drive_force" in columns:
        signals["drive_force"] = columns["drive_force"]
    for name, v in signals.items():
        if float(np.ptp(v)) == 0.0:
            raise FitError(f"{src}: signal {name!r} is constant: no usable information")
    # the run's speed scale (tolerances, divergence bound): the table speed the record shows
    if "speed" in columns:
        speed = columns["speed"]
    elif "position" in columns:
        speed = np.gradient(columns["position"], t)
    elif role == "motor_speed":
        from ..engine.simulate import DriveSystem

        axis = DriveSystem(params, drive, table_position).topology().table_axis
        speed = columns[role] * _axis_ratio(params, drive, table_position, axis)
    else:
        speed = np.zeros_like(t)
    notes.append(f"{src}: {role} {mapping[role]} drives the model open-loop (--input "
                 f"{input}), interpolated linearly between its {t.size} samples")
    exp = Experiment(source=src, time=t, signals=signals, reference_time=t, table_speed=speed,
                     noise={k: noise_level(v) for k, v in signals.items()}, input=input,
                     input_value=np.asarray(columns[role], dtype=float))
    return RigRecord(experiment=exp, notes=tuple(notes), mapping=dict(mapping))


def _axis_ratio(params: DriveParameters, drive: str, table_position: float, axis: str) -> float:
    """Table travel per radian of ``axis``' motor [m/rad] (1 without a motor shaft)."""
    from ..engine.simulate import DriveSystem

    rates = DriveSystem(params, drive, table_position).topology().steady_motion(1.0, 0.0)
    return 1.0 / float(rates[f"{axis}_angle"][1]) if f"{axis}_angle" in rates else 1.0


def reference_rate(reference: np.ndarray, time: np.ndarray) -> tuple[np.ndarray, bool]:
    """The speed reference [m/s] whose linear interpolation integrates to ``reference`` [m]
    at every sample — v_k = 2·(x_k − x_{k−1})/(t_k − t_{k−1}) − v_{k−1} from v_0 = 0 (the
    drive at rest) — so that the model's commanded position, the integral of its speed
    reference, is the position reference itself, not a central-difference approximation
    of it: on a 1-kHz minimum-jerk move that approximation was 0.2 µm off, of the size of a
    1-µm encoder's noise, and biased the mass and viscous estimates by 3–8 standard errors
    (Radau-made EMPS-layout records).  The recursion carries a sample's error on with
    alternating sign: where it moves the rate by more than 1 % of its range from the
    central differences (a quantised or noisy reference), those are returned instead.

    Parameters
    ----------
    reference : numpy.ndarray
        Position reference from its first value [m].
    time : numpy.ndarray
        Its sample instants [s], increasing.

    Returns
    -------
    tuple of (numpy.ndarray, bool)
        The rate [m/s], and whether it is the exact-integral one.
    """
    x = np.asarray(reference, dtype=float)
    t = np.asarray(time, dtype=float)
    central = np.gradient(x, t)
    slopes = np.diff(x) / np.diff(t)
    v = np.empty_like(x)
    v[0] = 0.0
    for k in range(1, x.size):
        v[k] = 2.0 * slopes[k - 1] - v[k - 1]
    span = float(np.ptp(central))
    if span > 0 and float(np.max(np.abs(v - central))) <= 0.01 * span:
        # rounding carried on at rest (±1e-11 m/s after a 0.2-m move) is no motion: a
        # reference that moves one way must not read as moving both ways
        v[np.abs(v) <= 1e-9 * float(np.max(np.abs(v)))] = 0.0
        return v, True
    return central, False


def _current_name(params: DriveParameters, drive: str, table_position: float) -> str:
    from ..model.mechanisms import mechanism

    topology = mechanism(drive)(params, drive, table_position, "locked")
    return f"{topology.table_axis}_current"


def emps_layout(path: str | Path, truth: DriveParameters, *, drive: str = "linear-motor",
                table_position: float = 0.4, seed: int = 0, duration: float = 1.6,
                stroke: float = 0.2, offset: float = 0.01, force_noise: float = 0.5,
                encoder: float = 1e-6) -> Path:
    """A closed-loop point-to-point record in the EMPS layout, made by simulating ``truth``
    with feeddrive (for tests and docs/fitting.md; not a calibration truth, which must come
    from an independent integrator): a minimum-jerk position reference ``qg`` (0 →
    ``stroke`` in 1 s from 0.05 s), the measured position ``qm`` in ``encoder`` counts, both
    shifted by ``offset``, and the table motor's force ``vir`` with white noise (seeded),
    sampled at 1 kHz, column vectors as MATLAB writes them (v5 file).

    Parameters
    ----------
    path : str or Path
        The ``.mat`` file written.
    truth : DriveParameters
        The generating set.
    drive : str, default "linear-motor"
        The drive (one motor driving the table).
    table_position : float, default 0.4
        Table position [m].
    seed : int, default 0
        Seed of the force noise.
    duration : float, default 1.6
        Record length [s].
    stroke : float, default 0.2
        Length of the move [m].
    offset : float, default 0.01
        Position offset of ``qg`` and ``qm`` [m].
    force_noise : float, default 0.5
        σ of the force noise [N].
    encoder : float, default 1e-6
        Count size of ``qm`` [m].

    Returns
    -------
    Path
        The file written.
    """
    import scipy.io as sio

    from ..engine.options import SolverOptions
    from ..engine.simulate import DriveSystem, simulate
    from ..model.reference import SampledSpeed

    dt = 1e-3
    t = np.arange(0.0, duration, dt)
    tau = np.clip((t - 0.05) / 1.0, 0.0, 1.0)
    qg = stroke * (10 * tau ** 3 - 15 * tau ** 4 + 6 * tau ** 5)
    system = DriveSystem(truth, drive=drive, table_position=table_position)
    run = simulate(system, SampledSpeed(time=t, table_speed=reference_rate(qg, t)[0]),
                   t[-1] + dt,
                   options=SolverOptions(output_interval=dt, sample_steps=True))
    name, per_amp = table_motor_force_per_current(truth, drive, table_position)
    rng = np.random.default_rng(seed)
    qm = np.round(np.interp(t, run.time, run["table_position"]) / encoder) * encoder
    vir = np.interp(t, run.time, run[name]) * per_amp + force_noise * rng.standard_normal(t.size)
    out = Path(path)
    sio.savemat(out, {"t": t[:, None], "qg": (qg + offset)[:, None],
                      "qm": (qm + offset)[:, None], "vir": vir[:, None]})
    return out
