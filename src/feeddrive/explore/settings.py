"""What the explorer page's fields hold, checked as the CLI checks them; URL and TOML forms.

The page sends every field as the text the user typed.  Checking turns that text into a
drive system and a command, or into one message per field — the message the CLI prints for
the same mistake:

* run fields are the options of ``feeddrive simulate`` (``--table-speed`` [mm/s],
  ``--nut-speed`` [mm/s], ``--position`` [mm], ``--duration`` [s]) and are checked by the
  CLI's own edge code (:mod:`feeddrive.cli._units`), warnings included;
* knob fields are parameter values (gains, torque ripple, compensation) and are applied to
  the parameter set through the TOML reader's path (:func:`feeddrive.parameters.from_dict`),
  so a refused value reads exactly as ``feeddrive params check`` reports it in a file;
* the friction scale multiplies every friction force of the set
  (:meth:`LuGreParameters.scaled`) and is checked like a parameter (``friction_scale``).

A knob whose text equals the parameter set's own value is not an override: the address
(:func:`to_query`) carries only the overrides, the parameter set by name — or, for a set
imported from a file, as compressed TOML.
"""

from __future__ import annotations

import base64
import binascii
import dataclasses
import math
import operator
import re
import threading
import tomllib
import zlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any
from urllib.parse import parse_qsl, urlencode

from ..model.loops import Compensation
from ..parameters import (
    PRESETS,
    DriveParameters,
    ParameterError,
    dumps,
    from_dict,
    preset,
    to_dict,
)
from ..parameters.validation import check_quantity, unit_label

#: longest simulated time the page runs [s]; `feeddrive simulate` runs longer ones
MAX_DURATION = 120.0
#: the hollow-motor speed a DDFS runs at in Wang2021 Fig. 8 [mm/s]
PAPER_NUT_SPEED_MM_S = 16.0
#: a plain harmonic of the motor shaft: 6 per revolution is a common cogging order
DEFAULT_RIPPLE_ORDER = 6.0

# a thousandth of the set's friction is the least the page runs (1e-320 passed the check
# and then broke the run): a physical lower bound, as the compensation scales have
_FRICTION_SCALE = {"unit": "-", "low": 1e-3, "high": 10.0, "low_inclusive": True,
                   "hint": "1 is the parameter set's friction"}
_RIPPLE = "disturbances.screw_motor_ripple"


@dataclass(frozen=True)
class Field:
    """One field of the page: ``name`` is its key in settings and in the address.

    Parameters
    ----------
    name : str
        The field's key.
    label : str
        Its label on the page.
    unit : str
        Its unit on the page (mm, mm/s, N/µm, otherwise SI).
    group : str
        The form section it belongs to.
    option : str, default ""
        The matching ``feeddrive simulate`` option.
    path : str, default ""
        The parameter it sets (a knob), if any.
    help : str, default ""
        Its help text.
    """

    name: str
    label: str
    unit: str
    group: str  # "run", "knob" or "choice"
    option: str = ""  # the CLI option (run fields)
    path: str = ""  # the parameter path (knobs)
    help: str = ""


FIELDS: tuple[Field, ...] = (
    Field("preset", "parameter set", "", "choice", "--preset",
          help="a named set; Import replaces it by a file's set"),
    Field("drive", "drive", "", "choice", "--drive",
          help="CDFS: screw motor only; DDFS: screw and hollow (nut) motors; linear motor"),
    Field("table_speed", "table speed", "mm/s", "run", "--table-speed",
          help="the commanded constant table speed"),
    Field("nut_speed", "hollow-motor speed", "mm/s", "run", "--nut-speed",
          help="DDFS only: the nut's speed (× H), Wang2021 Fig. 8 runs 16 mm/s"),
    Field("position", "table position", "mm", "run", "--position",
          help="distance of the nut from the motor-side screw support"),
    Field("duration", "simulated time", "s", "run", "--duration",
          help=f"at most {MAX_DURATION:g} s here"),
    Field("position_gain", "position gain K_pp", "1/s", "knob", path="controller.position_gain"),
    Field("velocity_gain", "velocity gain K_vp", "A s/rad", "knob",
          path="controller.velocity_gain"),
    Field("velocity_integral_gain", "velocity integral gain K_vi", "A/rad", "knob",
          path="controller.velocity_integral_gain"),
    Field("friction_scale", "friction scale", "-", "knob",
          help="every friction force of the set × this factor"),
    Field("ripple_amplitude", "screw-motor torque ripple", "N m", "knob",
          path=f"{_RIPPLE}.amplitudes[0]", help="amplitude of one harmonic of the shaft angle"),
    Field("ripple_order", "ripple order", "per rev", "knob", path=f"{_RIPPLE}.orders[0]"),
    Field("compensation", "friction compensation", "", "knob",
          path="controller.compensation.mode",
          help="feedforward: the static friction curve at the commanded speed; observer: a "
               "LuGre observer at the measured speeds (docs/linear.md)"),
)
FIELD = {f.name: f for f in FIELDS}
KNOBS = tuple(f.name for f in FIELDS if f.group == "knob")

DEFAULTS: dict[str, str] = {
    "preset": "wang2021", "drive": "cdfs", "table_speed": "1", "nut_speed": "16",
    "position": "400", "duration": "10",
}


def compensation_modes() -> tuple[str, ...]:
    """The friction-compensation modes (``controller.compensation.mode``).

    Returns
    -------
    tuple of str
        ``"none"``, ``"feedforward"``, ``"observer"``.
    """
    for f in dataclasses.fields(Compensation):
        if f.name == "mode":
            return tuple(f.metadata["options"])
    raise AssertionError("Compensation has no mode")  # pragma: no cover


def knob_values(params: DriveParameters) -> dict[str, str]:
    """The knob fields as the parameter set ``params`` has them.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.

    Returns
    -------
    dict of str to str
        Field name → value in the field's unit, as text.
    """
    c = params.controller
    ripple = params.disturbances.screw_motor_ripple
    out = {
        "position_gain": _text(c.position_gain),
        "velocity_gain": _text(c.velocity_gain),
        "velocity_integral_gain": _text(c.velocity_integral_gain),
        "friction_scale": "1",
        "ripple_amplitude": _text(ripple.amplitudes[0] if ripple.amplitudes else 0.0),
        "ripple_order": _text(ripple.orders[0] if ripple.orders else DEFAULT_RIPPLE_ORDER),
        "compensation": c.compensation.mode,
    }
    return out


def _text(value: float) -> str:
    return f"{value:.12g}"


def _number(text: Any) -> float | None:
    """The float a field's text stands for, None when it stands for none."""
    if isinstance(text, bool):
        return None
    if isinstance(text, int | float):
        return float(text)
    try:
        return float(str(text).strip())
    except ValueError:
        return None


def _same(text: Any, value: str) -> bool:
    a, b = _number(text), _number(value)
    if a is not None and b is not None:
        return a == b or (math.isnan(a) and math.isnan(b))
    return str(text).strip() == value


# ---------------------------------------------------------------- the CLI's edge checks

_units_lock = threading.Lock()


def _cli_number(option: str, text: Any) -> float:
    """A run field's number, refused as the CLI refuses a non-number for ``option``."""
    value = _number(text)
    if value is None:
        raise UsageError(option, text)
    return value


class UsageError(ParameterError):
    """What the CLI (typer) prints for an option given something that is not a number; a
    test keeps the two equal.

    Parameters
    ----------
    option : str
        The option, e.g. ``--table-speed``.
    text : object
        What was given.
    """

    def __init__(self, option: str, text: Any) -> None:
        self.field, self.value = option, text
        self.message = ("Input should be a valid number, unable to parse string as a number")
        ValueError.__init__(self, f"Invalid value for '{option}': {self.message}")

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickled by its two arguments."""
        return (UsageError, (self.field, self.value))


def _with_cli_warnings(fn: Any, *args: Any) -> tuple[Any, str]:
    """Call one of the CLI's edge checks and keep the warning it prints (a value that looks
    like SI given in mm) instead of printing it."""
    from ..cli._common import err_console

    with _units_lock, err_console.capture() as captured:
        value = fn(*args)
    text = captured.get().strip()
    return value, text.removeprefix("warning: ").replace("\n", " ")


# ---------------------------------------------------------------- parameter sets


#: longest parameter text the page sends or an address carries [characters, decompressed]
MAX_PARAMS_TEXT = 256 * 1024


def loads_params(text: str) -> DriveParameters:
    """A parameter set from the page (an imported file or the address): TOML, whose
    ``extends`` may name a preset but not a file (the server reads no file for a page).
    Read as the CLI reads a file: nesting deeper than the CLI accepts is refused.

    Parameters
    ----------
    text : str
        The TOML text.

    Returns
    -------
    DriveParameters
        The parameter set.

    Raises
    ------
    ParameterError
        For a refused file, an ``extends`` that names a file, or too deep nesting.
    """
    from ..parameters.toml_io import parse_toml

    if len(text) > MAX_PARAMS_TEXT:
        raise ParameterError("file", "<toml>", f"{len(text)} characters; a parameter file "
                             f"is at most {MAX_PARAMS_TEXT // 1024} kB here")
    data = parse_toml(text, source="<toml>")
    parent = data.get("extends")
    if parent is not None and parent not in PRESETS:
        raise ParameterError("extends", parent, f"expected one of {', '.join(PRESETS)} (the "
                             "explorer reads no other file; start it with --params FILE)")
    return from_dict(data)


def encode_params(text: str) -> str:
    """TOML text → compact address form (zlib, base64url).

    Parameters
    ----------
    text : str
        The TOML text.

    Returns
    -------
    str
        The address form.
    """
    packed = zlib.compress(text.encode("utf-8"), 9)
    return base64.urlsafe_b64encode(packed).decode("ascii").rstrip("=")


def decode_params(blob: str) -> str:
    """Address form → TOML text, decompressing at most :data:`MAX_PARAMS_TEXT` bytes (a
    small address that inflates to megabytes is refused, not inflated).

    Parameters
    ----------
    blob : str
        The address form.

    Returns
    -------
    str
        The TOML text.

    Raises
    ------
    ParameterError
        For a blob that is not valid or inflates beyond the limit.
    """
    shown_blob = blob[:20] + ("…" if len(blob) > 20 else "")
    try:
        raw = base64.urlsafe_b64decode(blob + "=" * (-len(blob) % 4))
        inflate = zlib.decompressobj()
        text = inflate.decompress(raw, MAX_PARAMS_TEXT)
        if inflate.unconsumed_tail or not inflate.eof:
            if inflate.unconsumed_tail:
                raise ParameterError("params", shown_blob, "the parameter set it carries is "
                                     f"larger than {MAX_PARAMS_TEXT // 1024} kB; not one "
                                     "this page wrote")
            raise zlib.error("truncated")
        return text.decode("utf-8")
    except (binascii.Error, zlib.error, UnicodeDecodeError, ValueError) as err:
        if isinstance(err, ParameterError):
            raise
        raise ParameterError("params", shown_blob,
                             "not a parameter set (the address was cut or changed)") from None


# ---------------------------------------------------------------- checking


@dataclass
class Checked:
    """Settings checked: the system and command to run, or a message per field.

    Parameters
    ----------
    settings : dict of str to str
        The settings as given, normalised.
    errors : dict of str to str
        Field → message, for refused values.
    warnings : dict of str to str
        Field → message, for suspicious values.
    base : DriveParameters, optional
        The parameter set before the knobs.
    params : DriveParameters, optional
        The set with the knobs applied.
    system : DriveSystem, optional
        The drive to run.
    drive : str, default "cdfs"
        The drive name.
    table_speed : float, default 0.0
        Commanded table speed [m/s].
    nut_speed : float, default 0.0
        Commanded nut speed [m/s].
    duration : float, default 10.0
        Simulated time [s].
    overrides : dict of str to str
        The knobs that differ from the set's own values.
    disabled : list of str
        Fields this drive does not use.
    """

    settings: dict[str, str]
    errors: dict[str, str] = field(default_factory=dict)
    warnings: dict[str, str] = field(default_factory=dict)
    base: DriveParameters | None = None
    params: DriveParameters | None = None
    system: Any = None  # feeddrive.DriveSystem
    drive: str = "cdfs"
    table_speed: float = 0.0  # [m/s]
    nut_speed: float = 0.0  # [m/s]
    duration: float = 10.0  # [s]
    overrides: dict[str, str] = field(default_factory=dict)
    disabled: list[str] = field(default_factory=list)  # fields this drive does not use

    @property
    def ok(self) -> bool:
        """Whether no field was refused."""
        return not self.errors

    def as_dict(self) -> dict[str, Any]:
        """What the page needs: messages, the parameter set's own knob values, the address.

        Returns
        -------
        dict
            Settings, errors, warnings, the fields' units, the base set's knob values and name,
            the overridden knobs, the disabled fields and the address query.
        """
        return {"settings": self.settings, "errors": self.errors, "warnings": self.warnings,
                "units": field_units(self.base),
                "base": knob_values(self.base) if self.base is not None else None,
                "base_name": self.base.name if self.base is not None else None,
                "overrides": sorted(self.overrides), "disabled": self.disabled,
                "query": to_query(self.settings, self)}


def normalise(settings: Mapping[str, Any] | None) -> dict[str, str]:
    """Every field present, as text; unknown keys dropped.

    Parameters
    ----------
    settings : mapping or None
        The settings as received.

    Returns
    -------
    dict of str to str
        Every field, with the defaults where absent.
    """
    out = dict(DEFAULTS)
    params_text = None
    for key, value in (settings or {}).items():
        if key == "params":
            params_text = None if value in (None, "") else str(value)
        elif key in FIELD and value is not None:
            out[key] = value if isinstance(value, str) else _text(float(value)) \
                if isinstance(value, int | float) and not isinstance(value, bool) else str(value)
    if params_text is not None:
        out["params"] = params_text
    return out


def base_parameters(settings: Mapping[str, str]) -> DriveParameters:
    """The parameter set the settings start from: the imported file, else the named preset.

    Parameters
    ----------
    settings : mapping of str to str
        The page's settings.

    Returns
    -------
    DriveParameters
        The set.

    Raises
    ------
    ParameterError
        For a refused file or an unknown preset.
    """
    if settings.get("params"):
        return loads_params(settings["params"])
    return preset(settings.get("preset", DEFAULTS["preset"]))


def check(settings: Mapping[str, Any] | None) -> Checked:
    """Check every field; never raises for a bad value (each lands in ``errors``).

    Parameters
    ----------
    settings : mapping or None
        The page's settings.

    Returns
    -------
    Checked
        The system and command to run, or the messages.
    """
    from ..engine.simulate import DriveSystem
    from ..model import drive_names, mechanism
    from ..model.mechanisms.base import DEFAULT_TABLE_POSITION

    s = normalise(settings)
    out = Checked(settings=s)
    try:
        out.base = base_parameters(s)
    except ParameterError as err:
        out.errors["params" if s.get("params") else "preset"] = str(err)
        return out
    base = out.base
    drive = s["drive"]
    if drive not in drive_names():
        out.errors["drive"] = str(ParameterError("--drive", drive,
                                                 f"expected one of {', '.join(drive_names())}"))
        return out
    out.drive = drive
    # the explorer's system holds a nut locked (DriveSystem's default): the topology says
    # whether the drive then follows a nut speed
    drives_nut = mechanism(drive)(base, drive, 0.4, "locked").follows("nut")
    if not drives_nut:
        out.disabled.append("nut_speed")
    if not any(m.ripple for m in mechanism(drive).drive_motors):
        out.disabled += ["ripple_amplitude", "ripple_order"]
    if not mechanism(drive).uses_table_position:  # its model does not read where it starts
        out.disabled.append("position")
    from ..cli import _units

    def run_field(name: str, convert: Any) -> float | None:
        f = FIELD[name]
        try:
            value, warning = _with_cli_warnings(convert, f.option, _cli_number(f.option,
                                                                                s[name]))
        except ParameterError as err:
            out.errors[name] = str(err)
            return None
        if warning:
            out.warnings[name] = warning
        return float(value)

    v_t = run_field("table_speed", _units.speed)
    out.table_speed = v_t if v_t is not None else 0.0
    if drives_nut:
        v_n = run_field("nut_speed", _units.speed)
        out.nut_speed = v_n if v_n is not None else 0.0
    position = (DEFAULT_TABLE_POSITION if "position" in out.disabled else
                run_field("position", lambda o, v: _units.position(o, v, base, drive)))
    try:
        duration = _cli_number("--duration", s["duration"])
        if not (math.isfinite(duration) and duration > 0):  # as `feeddrive simulate`
            raise ParameterError("--duration", duration, "expected a finite time > 0 [s]")
        if duration > MAX_DURATION:
            raise ParameterError("--duration", duration, f"expected ≤ {MAX_DURATION:g} [s] in "
                                 "the explorer (feeddrive simulate runs longer ones)")
        out.duration = duration
    except ParameterError as err:
        out.errors["duration"] = str(err)

    own = knob_values(base)
    for name in KNOBS:
        s.setdefault(name, own[name])  # a knob the page or the address leaves out
    for name in KNOBS:
        if name in out.disabled:
            continue
        if not _same(s[name], own[name]):
            out.overrides[name] = s[name]
    data = to_dict(base)
    for name in list(out.overrides):
        try:
            trial = to_dict(base)
            _apply(trial, name, s, own, base)
            from_dict(trial)
            _apply(data, name, s, own, base)
        except ParameterError as err:
            out.errors[name] = str(err)
    if out.errors:
        return out
    try:
        out.params = from_dict(data) if out.overrides else base
        out.system = DriveSystem(out.params, drive=drive,
                                 table_position=float(position))  # type: ignore[arg-type]
    except ParameterError as err:
        out.errors[_field_of(err)] = str(err)
    else:
        try:
            _check_samples(out)
        except ParameterError as err:
            out.errors["duration"] = str(err)
    return out


#: the most samples a run on the page keeps: 120 s at the default 1-ms output interval (the
#: server keeps the last runs whole for the downloads; a file's `[solver]` output_interval of
#: 1e-5 s made a 60-s run of 6 million samples and 5 GB: an outside check, 2026-12-07)
MAX_SAMPLES = 120_001


def _check_samples(out: Checked) -> None:
    """Refuse, before the run, a duration whose samples at the run's own output interval (a
    parameter file's ``[solver]`` table, else the default) are too few for the summary or
    more than :data:`MAX_SAMPLES` (``/api/check`` passed 1e-9 s, which every run refused)."""
    from ..engine.budget import SUMMARY_SAMPLES, check_output_samples, recorded_samples
    from ..engine.simulate import run_options

    options = run_options(out.system, None)
    check_output_samples(out.duration, options, samples=SUMMARY_SAMPLES, purpose="the summary")
    kept = recorded_samples(out.duration, options.output_interval)
    if kept > MAX_SAMPLES:
        raise ParameterError("--duration", out.duration, f"keeps {kept} samples at the output "
                             f"interval {options.output_interval:g} s; expected ≤ "
                             f"{MAX_SAMPLES} in the explorer (a shorter run or a larger "
                             "output_interval; feeddrive simulate --output streams longer "
                             "ones)")


def _apply(data: dict[str, Any], name: str, s: Mapping[str, str], own: Mapping[str, str],
           base: DriveParameters) -> None:
    """Put knob ``name`` into the nested parameter dict ``data`` (as a file would)."""
    if name == "friction_scale":
        k = check_quantity("friction_scale", _value(s[name]), dict(_FRICTION_SCALE))
        for path in _friction_paths(base, s["drive"]):
            *where, last = path.split(".")
            node = data
            for part in where:
                node = node[part]
            node[last] = to_dict(operator.attrgetter(path)(base).scaled(k))
    elif name.startswith("ripple"):
        ripple = base.disturbances.screw_motor_ripple
        data["disturbances"]["screw_motor_ripple"] = {
            "orders": [_value(s["ripple_order"])], "amplitudes": [_value(s["ripple_amplitude"])],
            "phases": [ripple.phases[0] if ripple.phases else 0.0]}
    elif name == "compensation":
        data["controller"]["compensation"]["mode"] = s[name]
    else:
        section, key = FIELD[name].path.split(".")
        data[section][key] = _value(s[name])


def _friction_paths(base: DriveParameters, drive: str) -> list[str]:
    """Every friction site of the set: the ``[friction]`` section's sites and those the
    drive's topology places in a part's own section (the rack-and-pinion's gearbox)."""
    from ..model import mechanism

    paths = [f"friction.{f.name}" for f in dataclasses.fields(base.friction)
             if hasattr(getattr(base.friction, f.name), "scaled")]
    topology = mechanism(drive)
    try:
        topology.check(base, drive, 0.4)
    except ParameterError:
        return paths  # a set without the drive's parts: the system's check says so
    for site in topology(base, drive, 0.4, "locked").acting_sites():
        if "." in site.parameters_key and site.parameters_key not in paths:
            paths.append(site.parameters_key)
    return paths


def _value(text: str) -> Any:
    """A knob's number, or its text unchanged so that the parameter's own check refuses it
    with its message ("expected a number [unit]")."""
    value = _number(text)
    return text if value is None else value


def _field_of(err: ParameterError) -> str:
    f = str(err.field)
    if "position" in f:
        return "position"
    for knob in KNOBS:
        path = FIELD[knob].path
        if path and f.startswith(path.split("[")[0]):
            return knob
    return "drive"


# ---------------------------------------------------------------- address and file forms


def to_query(settings: Mapping[str, str], checked: Checked | None = None) -> str:
    """The address's query: the parameter set, the run fields, the knobs that override it.

    Parameters
    ----------
    settings : mapping of str to str
        The page's settings.
    checked : Checked, optional
        The check, for the knobs that differ from the set's own values.

    Returns
    -------
    str
        The query string.
    """
    s = normalise(settings)
    pairs: list[tuple[str, str]] = []
    if s.get("params"):
        pairs.append(("params", encode_params(s["params"])))
    else:
        pairs.append(("preset", s["preset"]))
    pairs += [(name, s[name]) for name in ("drive", "table_speed", "nut_speed", "position",
                                           "duration")]
    overrides = checked.overrides if checked is not None else {
        k: s[k] for k in KNOBS if k in (settings or {})}
    pairs += [(name, s[name]) for name in KNOBS if name in overrides]
    return urlencode(pairs)


def from_query(query: str) -> tuple[dict[str, str], dict[str, str]]:
    """Settings from an address's query (knobs the address leaves out: the set's own values),
    and a message for a parameter blob that cannot be read.

    Parameters
    ----------
    query : str
        The address's query string.

    Returns
    -------
    settings : dict of str to str
        The settings.
    errors : dict of str to str
        Field → message for a blob that cannot be read.
    """
    given = dict(parse_qsl(query.lstrip("?"), keep_blank_values=True))
    errors: dict[str, str] = {}
    raw: dict[str, Any] = {k: v for k, v in given.items() if k in FIELD}
    if given.get("params"):
        try:
            raw["params"] = decode_params(given["params"])
        except ParameterError as err:
            errors["params"] = str(err)
    s = normalise(raw)
    try:
        own = knob_values(base_parameters(s))
    except ParameterError as err:
        errors.setdefault("params" if s.get("params") else "preset", str(err))
        own = {}
    for name in KNOBS:
        if name not in given and name in own:
            s[name] = own[name]
    return s, errors


_HEADER = "# explore."
_HEADER_LINE = re.compile(r"^# explore\.([a-z_]+) = (.+)$")
_RUN_IN_FILE = {"drive": "drive", "table_speed": "table_speed_mm_s",
                "nut_speed": "nut_speed_mm_s", "position": "position_mm",
                "duration": "duration_s"}


def export_toml(checked: Checked) -> str:
    """The checked settings as a parameter file: the parameter set with the knobs applied,
    and the run fields in comment lines (ignored by ``feeddrive.load``; read back by
    :func:`import_toml`).

    Parameters
    ----------
    checked : Checked
        The checked settings.

    Returns
    -------
    str
        The TOML text.
    """
    assert checked.params is not None
    params = checked.params
    if checked.overrides:
        params = dataclasses.replace(params, name=f"{params.name}+explore")
    s = checked.settings
    lines = ["# Saved by `feeddrive explore`: a parameter file (feeddrive params check / "
             "--params FILE);",
             "# the explorer's Import also reads the run settings from the lines below."]
    for key, label in _RUN_IN_FILE.items():
        value = f'"{s[key]}"' if key == "drive" else _text(float(s[key]))
        lines.append(f"{_HEADER}{label} = {value}")
    if "friction_scale" in checked.overrides:
        lines.append(f"# (friction scale {s['friction_scale']} is applied to the friction "
                     "values below)")
    return "\n".join(lines) + "\n" + dumps(params)


def import_toml(text: str, current: Mapping[str, Any] | None = None) -> dict[str, str]:
    """Settings from a parameter file (exported or hand-written): its parameter set becomes
    the base, the knobs take its values, run settings come from its ``# explore.`` lines
    (else stay as they are).  Raises :class:`ParameterError` for a file that is refused.

    Parameters
    ----------
    text : str
        The TOML text.
    current : mapping, optional
        The page's current settings.

    Returns
    -------
    dict of str to str
        The new settings.

    Raises
    ------
    ParameterError
        For a refused file.
    """
    params = loads_params(text)
    s = normalise(current)
    s["params"] = dumps(params)
    s.update(knob_values(params))
    names = {v: k for k, v in _RUN_IN_FILE.items()}
    for line in text.splitlines():
        m = _HEADER_LINE.match(line.strip())
        if m and m.group(1) in names:
            try:
                value = tomllib.loads(f"v = {m.group(2)}")["v"]
            except (tomllib.TOMLDecodeError, RecursionError):
                continue
            if not isinstance(value, str | int | float) or isinstance(value, bool):
                continue
            s[names[m.group(1)]] = value if isinstance(value, str) else _text(float(value))
    return s

# ---- the page's knob units from the parameters' own metadata, resolved for the parameter set
# (a velocity-loop gain is per rad/s of the motor, or per m/s of table speed on the set's
# velocity_gain_basis = "table": A s/rad or A s/m, a factor H ≈ 10⁻³ apart)


def field_unit(f: Field, params: DriveParameters | None) -> str:
    """The unit of field ``f`` for ``params``: its parameter's metadata when it has a path
    (``controller.velocity_gain``, ``disturbances.screw_motor_ripple.amplitudes[0]``), else
    the field's own.

    Parameters
    ----------
    f : Field
        The field.
    params : DriveParameters or None
        The parameter set; None before one is loaded.

    Returns
    -------
    str
        The unit.
    """
    if not f.path or params is None:
        return f.unit
    parts = [re.sub(r"\[\d+\]$", "", p) for p in f.path.split(".")]
    obj: Any = params
    for part in parts[:-1]:
        obj = getattr(obj, part, None)
        if obj is None:
            return f.unit
    try:
        unit = unit_label(obj, parts[-1])  # the one label of every output (issue 41 item 3)
    except (KeyError, TypeError):
        return f.unit
    if unit == "-" and f.unit not in ("", "-"):
        return f.unit  # e.g. a ripple order: "per rev" says more than "-"
    return unit or f.unit


def field_units(params: DriveParameters | None) -> dict[str, str]:
    """Every field's unit for ``params``.

    Parameters
    ----------
    params : DriveParameters or None
        The parameter set; None before one is loaded.

    Returns
    -------
    dict of str to str
        Field name → unit.
    """
    return {f.name: field_unit(f, params) for f in FIELDS}
