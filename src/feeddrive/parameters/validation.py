"""Field declarations with units and plausible ranges, and the one validation routine.

Every numeric parameter is declared with :func:`quantity`, which records its SI unit, the
range a physically sensible value lies in, and (optionally) the unit a user most likely typed
by mistake.  :func:`validate` checks a frozen dataclass against those declarations and raises
:class:`ParameterError` naming the field, the value and the expected unit.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import reprlib
from collections.abc import Sequence
from typing import Any, TypeGuard

from ..units import LARGEST_SPEED, MM_PER_S

#: longest field name, file name or value shown in a message [characters]; longer ones are
#: cut (a 10-MB value is not echoed whole)
MAX_SHOWN = 200

_REPR = reprlib.Repr()
_REPR.maxstring = MAX_SHOWN
_REPR.maxother = MAX_SHOWN
_REPR.maxlist = _REPR.maxtuple = 20
_REPR.maxdict = 10
_REPR.maxlevel = 4


class _Missing:
    """The value of a field or option that was not given at all (:data:`MISSING`)."""

    __slots__ = ()

    def __repr__(self) -> str:
        return "MISSING"

    def __reduce__(self) -> str:
        return "MISSING"  # one object, across pickling too


#: what :class:`ParameterError` carries as the value of a field or option that was not
#: given: its message then reads ``field: missing field`` instead of showing a value the
#: user never wrote (``= None``)
MISSING = _Missing()


def shown_value(value: object) -> str:
    """``repr(value)`` for a message: long text and deep or long lists cut (``...``).

    Parameters
    ----------
    value : object
        The value.

    Returns
    -------
    str
        Its shortened ``repr``.
    """
    if isinstance(value, str) and len(value) > MAX_SHOWN:
        return f"{value[:MAX_SHOWN]!r}… ({len(value)} characters)"
    text = repr(value) if isinstance(value, int | float | bool | None) else _REPR.repr(value)
    return _cut(text)


def is_real(value: object) -> TypeGuard[float]:
    """Whether ``value`` is a real number: an int or a float, NumPy's scalars included; not a
    bool, a str, a list or an array.

    Parameters
    ----------
    value : object
        What was given.

    Returns
    -------
    bool
        True for a real number (to a type checker: a float).
    """
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def real_array(name: str, value: object, unit: str) -> Any:
    """``value`` as an array of floats, or a one-line refusal naming ``name``, the first value
    that is not a real number and the unit: the one check of an array of numbers the API is
    given (a trace, a tabulated profile, a frequency grid).  NumPy casts complex numbers to
    their real part with only a warning, booleans to 0 and 1, and text failed in its words
    ("could not convert string to float": an API sweep of session 29).

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : array_like
        What was given: a sequence, an array, a pandas Series or an xarray DataArray
        [``unit``].
    unit : str
        The unit its numbers are read in, for the message.

    Returns
    -------
    numpy.ndarray
        The values as floats [``unit``], shaped as given (the caller checks the shape).

    Raises
    ------
    ParameterError
        For text, complex numbers, booleans, dates or other objects that are not real
        numbers, naming the first one (``time[3] = 'a': expected real numbers [s]``).
    """
    import numpy as np

    try:
        a = np.asarray(value)
    except (TypeError, ValueError):  # a ragged nested list
        raise ParameterError(name, value, f"expected an array of real numbers [{unit}]") \
            from None
    if a.dtype.kind in "iuf":
        return a.astype(float, copy=False)
    flat = a.ravel()
    bad = 0
    if a.dtype.kind == "O":  # a list of mixed objects, a pandas Series of objects
        bad = next((i for i, v in enumerate(flat) if not is_real(v)), -1)
        if bad < 0:
            return a.astype(float)
    if not flat.size:
        raise ParameterError(name, MISSING, f"expected an array of real numbers [{unit}], "
                             f"not of {a.dtype}")
    shown = flat[bad] if a.dtype.kind == "O" else flat[bad].item()
    where = name if a.ndim == 0 else \
        f"{name}[{', '.join(str(int(i)) for i in np.unravel_index(bad, a.shape))}]"
    raise ParameterError(where, shown, f"expected real numbers [{unit}]")


def check_speed(name: str, value: object, *, sign: str = "positive",
                limit: tuple[float, str] | None = None) -> float:
    """A speed argument [m/s] as a float, or a one-line refusal naming it: the one check of a
    speed the API is given, which the profiles (``feeddrive.model.reference``) and the
    analyses (``feeddrive.analysis``) both call.

    Parameters
    ----------
    name : str
        The argument's name in the message (``speed_range[1]``, ``profile.table_speed``).
    value : object
        What was given [m/s].
    sign : str, default "positive"
        ``"positive"`` (> 0), ``"nonzero"`` or ``"any"``.
    limit : tuple of (float, str) or None, default None
        The largest |speed| [m/s] and what sets it (the axis's,
        :func:`~feeddrive.analysis.positioning_run.axis_speed_limit`); ``units.LARGEST_SPEED``
        by default.

    Returns
    -------
    float
        The speed [m/s].

    Raises
    ------
    ParameterError
        For a non-number ("expected a number [m/s]"; with ``sign="any"`` "expected a finite
        speed [m/s]", as for a non-finite one), a non-finite speed, one of the wrong sign or
        above the limit; a speed above the limit that would be within it in mm/s says so
        (the API takes m/s).
    """
    if not is_real(value):
        # with any sign, "a finite speed" is the whole expectation (the profiles' wording);
        # a signed one names the number first
        raise ParameterError(name, value, "expected a finite speed [m/s]" if sign == "any"
                             else "expected a number [m/s]")
    try:
        v = float(value)
    except OverflowError:  # an int beyond any float
        v = math.inf
    if sign == "positive" and not (math.isfinite(v) and v > 0.0):
        raise ParameterError(name, value, "expected a finite speed > 0 [m/s]")
    if sign == "nonzero" and not (math.isfinite(v) and v != 0.0):
        raise ParameterError(name, value, "expected a finite, non-zero speed [m/s]")
    if not math.isfinite(v):
        raise ParameterError(name, value, "expected a finite speed [m/s]")
    bound, why = limit if limit is not None else (LARGEST_SPEED, "no feed drive is faster")
    if abs(v) > bound:
        raise ParameterError(name, value, f"expected |speed| ≤ {bound:.6g} [m/s] ({why})"
                             + mm_s_hint(v, abs(v) * MM_PER_S <= bound))
    return v


def mm_s_hint(value: float, fits: bool) -> str:
    """``"; the API takes m/s: 3 mm/s is 0.003"`` for a speed refused as too large that
    ``fits`` its bound when read as mm/s (a value in the CLI's unit); ``""`` otherwise.

    Parameters
    ----------
    value : float
        The refused speed, as given [m/s].
    fits : bool
        Whether ``value`` mm/s is within the bound it broke.

    Returns
    -------
    str
        The hint, with a leading ``"; "``, or an empty string.
    """
    return f"; the API takes m/s: {value:g} mm/s is {value * 1e-3:g}" if fits else ""


def is_flag(value: object) -> TypeGuard[bool]:
    """Whether ``value`` is a boolean: Python's ``bool`` or NumPy's ``np.bool_`` (what a
    comparison of arrays gives, ``bool(np.all(...))`` not needed); not ``1``, ``"yes"`` or
    None, which a flag argument read as true or false without a word (an API sweep of
    session 29).

    Parameters
    ----------
    value : object
        What was given.

    Returns
    -------
    bool
        True for a boolean (to a type checker: a bool).
    """
    if isinstance(value, bool):
        return True
    import numpy as np

    return isinstance(value, np.bool_)


def check_flag(name: str, value: object, expected: str = "expected True or False") -> bool:
    """A flag argument as a Python ``bool``, or a one-line refusal naming it: the one check of
    the API's boolean arguments (``frictionless``, ``frequency``, ``hold``, …) and of a
    parameter set's flags.  ``np.bool_`` is taken (as ``True``/``False``); anything else
    truthy or falsy (``"yes"``, ``1``, None) is refused.

    Parameters
    ----------
    name : str
        The argument's name in the message (``frictionless``, ``profile.hold``).
    value : object
        What was given.
    expected : str, default "expected True or False"
        What was expected, for the message (a parameter file's flag: ``"expected true or
        false"``, TOML's words).

    Returns
    -------
    bool
        The flag.

    Raises
    ------
    ParameterError
        For anything but a ``bool`` or ``np.bool_``.
    """
    if not is_flag(value):
        raise ParameterError(name, value, expected)
    return bool(value)


def check_callback(name: str, value: object, call: str) -> None:
    """Refuse, naming the argument ``name``, a ``value`` that is neither None nor callable
    (a progress callback given as a number or a string failed at its first call).

    Parameters
    ----------
    name : str
        The argument, e.g. ``"progress"``.
    value : object
        What was given.
    call : str
        How it is called, for the message, e.g. ``"progress(done, total)"``.

    Raises
    ------
    ParameterError
        When ``value`` is not None and not callable.
    """
    if value is not None and not callable(value):
        raise ParameterError(name, type(value).__name__, f"expected None or a callable {call}")


def did_you_mean(given: object, known: Any) -> str:
    """The closest known name to a misspelt one, for a message: ``" (did you mean 'cdfs'?)"``,
    or ``""`` when none is close (:func:`difflib.get_close_matches`, cutoff 0.6).

    Parameters
    ----------
    given : object
        What was given.
    known : iterable of str
        The names it should have been one of.

    Returns
    -------
    str
        The hint, with a leading space, or an empty string.
    """
    import difflib

    if not isinstance(given, str) or len(given) > MAX_SHOWN:
        return ""
    close = difflib.get_close_matches(given, [str(k) for k in known], n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def refuse_repeats(name: str, items: Sequence[object], expected: str, *,
                   shown: Sequence[object] | None = None) -> None:
    """Refuse, in one line naming ``name`` and the entry, a list whose entry repeats an
    earlier one (equal by ``==``: 200 and 200.0 are one position): a row or a run made twice,
    or a value counted twice, without a word (``stiffness --positions 100,100`` printed its
    row twice, ``compensate --schemes none,none`` ran its scheme twice: session 30).

    Parameters
    ----------
    name : str
        The argument or option, e.g. ``"--positions"`` or ``"names"``.
    items : sequence
        The entries, as compared.
    expected : str
        What is expected instead, after "given twice; expected", e.g. ``"each position once
        [mm], e.g. 200,400"``.
    shown : sequence, optional
        The entries as the message shows them (the option's text, ``"200.0"``), one per item;
        default the items.

    Raises
    ------
    ParameterError
        For the first entry equal to an earlier one.
    """
    seen: list[object] = []
    for k, item in enumerate(items):
        if any(item == s for s in seen):
            raise ParameterError(name, item if shown is None else shown[k],
                                 f"given twice; expected {expected}")
        seen.append(item)


def _cut(text: str) -> str:
    if len(text) <= MAX_SHOWN:
        return text
    return f"{text[:MAX_SHOWN]}… ({len(text)} characters)"


def _parameter_error(cls: type[ParameterError], field: str, value: object, message: str,
                     source: str | None) -> ParameterError:
    """A :class:`ParameterError` (or subclass) from its pickled arguments."""
    return cls(field, value, message, source=source)


class ParameterError(ValueError):
    """A parameter value was refused.

    The message names field, value and expected unit, and the file it came from when there is
    one (``source``).  Long field names, values and file names are cut in the message
    (``MAX_SHOWN``); the attributes keep them.

    Parameters
    ----------
    field : str
        Dotted name of the refused field (e.g. ``"table.mass"``).
    value : object
        The refused value; ``feeddrive.parameters.validation.MISSING`` when none was given
        (the message then shows none).
    message : str
        What was expected, with its unit.
    source : str or None, default None
        The file the value came from.
    """

    def __init__(self, field: str, value: object, message: str, *,
                 source: str | None = None) -> None:
        self.field = field
        self.value = value
        self.message = message
        self.source = source
        where = f"{_cut(source)}: " if source else ""
        shown = "" if value is MISSING else f" = {shown_value(value)}"
        super().__init__(f"{where}{_cut(str(field))}{shown}: {message}")

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickled by its arguments (a worker process's refusal reaches its parent whole:
        the default pickling of an exception passes only the message, which this
        constructor does not take, and the pool broke)."""
        return (_parameter_error, (type(self), self.field, self.value, self.message,
                                   getattr(self, "source", None)))

    def in_file(self, source: str) -> ParameterError:
        """The same refusal, naming the file it came from.

        Parameters
        ----------
        source : str
            The file; an error already naming its file (e.g. from a file it extends) is kept.

        Returns
        -------
        ParameterError
            An error whose message names ``source``.
        """
        if self.source is not None:
            return self
        return ParameterError(self.field, self.value, self.message, source=source)


def quantity(
    unit: str,
    *,
    low: float,
    high: float,
    low_inclusive: bool = False,
    hint: str = "",
    default: Any = dataclasses.MISSING,
    table_unit: str = "",
) -> Any:
    """Declare a float field in SI ``unit`` whose sensible values lie in [low, high].

    ``hint`` is appended to the message when a value falls outside the range, e.g.
    "a lead of 5 looks like millimetres; give metres".  ``table_unit``: the unit instead when
    the component's ``velocity_gain_basis`` is "table" (a velocity-loop gain acting on m/s of
    table motion rather than rad/s of the motor; :func:`resolved_unit`).

    Parameters
    ----------
    unit : str
        The SI unit.
    low : float
        Lowest sensible value [unit].
    high : float
        Highest sensible value [unit].
    low_inclusive : bool, default False
        Whether ``low`` itself is allowed.
    hint : str, default ""
        Appended to the message of a value out of range.
    default : object, optional
        The default; the field is required without it.
    table_unit : str, default ""
        The unit on the table basis.

    Returns
    -------
    dataclasses.Field
        The field, its metadata read by :func:`validate`.
    """
    meta = {"unit": unit, "low": low, "high": high, "low_inclusive": low_inclusive, "hint": hint}
    if table_unit:
        meta["table_unit"] = table_unit
    if default is dataclasses.MISSING:
        return dataclasses.field(metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


def quantities(unit: str, *, low: float, high: float, low_inclusive: bool = True,
               hint: str = "") -> Any:
    """Declare a tuple of floats in SI ``unit`` (e.g. harmonic amplitudes), default empty.

    Parameters
    ----------
    unit : str
        The SI unit of every element.
    low : float
        Lowest sensible element [unit].
    high : float
        Highest sensible element [unit].
    low_inclusive : bool, default True
        Whether ``low`` itself is allowed.
    hint : str, default ""
        Appended to the message of a value out of range.

    Returns
    -------
    dataclasses.Field
        The field, its metadata read by :func:`validate`.
    """
    meta = {"unit": unit, "low": low, "high": high, "low_inclusive": low_inclusive,
            "hint": hint, "vector": True}
    return dataclasses.field(default=(), metadata=meta)


def choice(options: tuple[str, ...], *, default: str) -> Any:
    """Declare a string field restricted to ``options``.

    Parameters
    ----------
    options : tuple of str
        The allowed values.
    default : str
        The default, one of ``options``.

    Returns
    -------
    dataclasses.Field
        The field, its metadata read by :func:`validate`.
    """
    return dataclasses.field(default=default, metadata={"options": options})


def flag(*, default: bool) -> Any:
    """Declare a boolean field.

    Parameters
    ----------
    default : bool
        The default.

    Returns
    -------
    dataclasses.Field
        The field, its metadata read by :func:`validate`.
    """
    return dataclasses.field(default=default, metadata={"flag": True})


def _format_range(meta: dict[str, Any]) -> str:
    lo, hi, unit = meta["low"], meta["high"], meta["unit"]
    lo_txt = f"{lo:g}" if lo != 0 else "0"
    op = "≥" if meta["low_inclusive"] else ">"
    if math.isinf(hi):
        return f"expected a value {op} {lo_txt} [{unit}]"
    return f"expected {lo_txt} … {hi:g} [{unit}]"


def check_quantity(path: str, value: object, meta: dict[str, Any]) -> float:
    """Return ``value`` as float or raise :class:`ParameterError` for ``path``.

    Parameters
    ----------
    path : str
        The field's dotted path, for the message.
    value : object
        The value given.
    meta : dict
        The field's metadata (unit, low, high, hint).

    Returns
    -------
    float
        The value [the field's unit].

    Raises
    ------
    ParameterError
        For a non-number, a non-finite number or one outside the field's range, naming the
        path, the value and the expected unit.
    """
    unit = meta["unit"]
    # NumPy's scalars are numbers (np.float32(45.0) and np.int64(45) were "expected a
    # number", an API sweep of session 29); a 0-d array, a bool or a complex is not
    if not is_real(value):
        raise ParameterError(path, value, f"expected a number [{unit}]")
    v = float(value)
    if not math.isfinite(v):
        raise ParameterError(path, value, f"not finite; {_format_range(meta)}")
    lo, hi = meta["low"], meta["high"]
    below = v < lo if meta["low_inclusive"] else v <= lo
    if below or v > hi:
        msg = _format_range(meta)
        if meta["hint"]:
            msg += f" ({meta['hint']})"
        raise ParameterError(path, value, msg)
    return v


def resolved_unit(obj: object, name: str) -> str:
    """The unit field ``name`` of the dataclass ``obj`` is read in, resolved for the object's
    ``velocity_gain_basis`` (a velocity-loop gain on the table basis is per m/s of table
    speed, not per rad/s of the motor: a factor H ≈ 10⁻³ apart).

    Parameters
    ----------
    obj : object
        A parameter dataclass.
    name : str
        One of its fields.

    Returns
    -------
    str
        The unit.
    """
    meta = _metadata(obj, name)
    return _unit_in(meta, obj)


#: what a unit label adds for a velocity-loop gain on the table basis
TABLE_BASIS_NOTE = "per table speed"


def unit_label(obj: object, name: str) -> str:
    """The one unit label of field ``name`` of ``obj``, as every output shows it (``fit``,
    fitted files, ``params show``, the explorer): :func:`resolved_unit`, the unit of the
    model's slot, with :data:`TABLE_BASIS_NOTE` when the velocity-loop gain is per m/s of
    table speed — the factor H ≈ 10⁻³ that decides whether anything creeps.

    Parameters
    ----------
    obj : object
        A parameter dataclass.
    name : str
        One of its fields.

    Returns
    -------
    str
        E.g. ``"A/m, per table speed"`` (wang2021) or ``"A/rad"`` (wang2021-literal).
    """
    meta = _metadata(obj, name)
    unit = _unit_in(meta, obj)
    return f"{unit}, {TABLE_BASIS_NOTE}" if unit != str(meta.get("unit", "")) else unit


def path_unit_label(params: object, path: str) -> str:
    """:func:`unit_label` of a parameter by its dotted path in a set (an index such as
    ``amplitudes[0]`` names its list).

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    path : str
        E.g. ``"controller.velocity_integral_gain"``.

    Returns
    -------
    str
        The label.

    Raises
    ------
    KeyError
        When ``path`` names no field of a parameter dataclass in ``params``.
    """
    import re

    parts = [re.sub(r"\[\d+\]$", "", p) for p in path.split(".")]
    obj: Any = params
    for part in parts[:-1]:
        obj = getattr(obj, part, None)
        if obj is None:
            raise KeyError(path)
    try:
        return unit_label(obj, parts[-1])
    except TypeError:  # not a dataclass
        raise KeyError(path) from None


def _metadata(obj: object, name: str) -> Any:
    for f in dataclasses.fields(obj):  # type: ignore[arg-type]
        if f.name == name:
            return f.metadata
    raise KeyError(name)


def _unit_in(meta: Any, obj: object) -> str:
    if meta.get("table_unit") and getattr(obj, "velocity_gain_basis", "") == "table":
        return str(meta["table_unit"])
    return str(meta.get("unit", ""))


def validate(obj: object, prefix: str) -> None:
    """Check every declared field of the dataclass ``obj``; ``prefix`` names it in messages.

    Parameters
    ----------
    obj : object
        A parameter dataclass.
    prefix : str
        Its dotted path (``friction.screw``).

    Raises
    ------
    ParameterError
        At the first field refused, naming its full path, the value and the expected unit.
    """
    for f in dataclasses.fields(obj):  # type: ignore[arg-type]
        value = getattr(obj, f.name)
        path = f"{prefix}.{f.name}"
        meta: Any = f.metadata
        if "table_unit" in meta:  # messages in the unit the value is read in
            meta = {**meta, "unit": _unit_in(meta, obj)}
        if meta.get("vector"):
            if isinstance(value, str) or not isinstance(value, list | tuple):
                raise ParameterError(path, value, f"expected a list of numbers [{meta['unit']}]")
            coerced_all = tuple(check_quantity(f"{path}[{i}]", v, dict(meta))
                                for i, v in enumerate(value))
            object.__setattr__(obj, f.name, coerced_all)
        elif "unit" in meta:
            if value is None and f.default is None:
                continue
            coerced = check_quantity(path, value, dict(meta))
            if coerced is not value:
                object.__setattr__(obj, f.name, coerced)
        elif "options" in meta:
            if value not in meta["options"]:
                raise ParameterError(path, value, f"expected one of {', '.join(meta['options'])}")
        elif "flag" in meta:  # np.bool_ taken as a bool (SampledSpeed.hold took it)
            checked = check_flag(path, value, "expected true or false")
            if checked is not value:
                object.__setattr__(obj, f.name, checked)
