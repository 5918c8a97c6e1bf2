"""Parameter sets to and from TOML.  Lossless: floats are written with ``repr``.

The writer is ours (not tomli-w) because it annotates every value with its unit, which is
what a user editing the file needs (tomli-w writes no comments; tomlkit would, at the cost of
a dependency for one small function).  Every string goes through :func:`toml_string`, which
escapes per the TOML 1.0 basic-string rules (backslash, quote and every control character),
and every comment through :func:`toml_comment`, so no value or file name can end a line
and inject a key; a test round-trips arbitrary text through ``tomllib``.  The reader is
the standard library's ``tomllib``, behind :func:`parse_toml`, which refuses deeply nested
input with one line instead of a ``RecursionError``.
"""

from __future__ import annotations

import dataclasses
import functools
import os
import re
import stat
import threading
import tomllib
import types
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from typing import Any, Union, get_args, get_origin, get_type_hints

from .. import registry
from .components import (
    SET_SOURCE,
    SOLVER_SETTINGS,
    DriveParameters,
    composition,
    solver_table,
)
from .validation import MISSING, ParameterError, did_you_mean, unit_label


def _is_component(tp: Any) -> bool:
    return isinstance(tp, type) and dataclasses.is_dataclass(tp)


def _component_type(tp: Any) -> Any:
    """The dataclass of a field typed ``Component`` or ``Component | None``, else None."""
    if _is_component(tp):
        return tp
    if get_origin(tp) in (Union, types.UnionType):
        inner = [a for a in get_args(tp) if a is not type(None)]
        if len(inner) == 1 and _is_component(inner[0]):
            return inner[0]
    return None


def to_dict(obj: Any) -> dict[str, Any]:
    """Nested plain dict of a parameter dataclass.

    Parameters
    ----------
    obj : object
        A parameter dataclass.

    Returns
    -------
    dict
        Field → value, nested for components [SI].
    """
    out: dict[str, Any] = {}
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if value is None or f.metadata.get("not_a_parameter"):  # the set's [solver] table
            continue
        if f.name == "sections":  # parts' sections are tables of the file's top level
            out.update({name: to_dict(section) for name, section in _in_file_order(obj)})
            continue
        out[f.name] = to_dict(value) if dataclasses.is_dataclass(value) else value
    return out


def _in_file_order(obj: Any) -> list[tuple[str, Any]]:
    """A composition's sections in the order its mechanism kind writes them."""
    ordered = getattr(obj, "ordered_sections", None)
    return list(ordered() if ordered is not None else obj.sections)


#: deepest table/array nesting accepted in a TOML file (a parameter set needs 4)
MAX_TOML_DEPTH = 16

_TOML_ESCAPES = {"\\": "\\\\", '"': '\\"', "\b": "\\b", "\t": "\\t", "\n": "\\n",
                 "\f": "\\f", "\r": "\\r"}


_NEEDS_ESCAPE = re.compile('[\\\\"\\x00-\\x1f\\x7f]')


def toml_string(text: str) -> str:
    """``text`` as a TOML basic string: quoted, with backslash, quote and every control
    character (U+0000–U+001F, U+007F) escaped (TOML 1.0, "String").

    Parameters
    ----------
    text : str
        The text.

    Returns
    -------
    str
        The TOML string, with its quotes.
    """
    if not _NEEDS_ESCAPE.search(text):  # the common case, without a loop per character
        return f'"{text}"'
    out = []
    for c in text:
        if c in _TOML_ESCAPES:
            out.append(_TOML_ESCAPES[c])
        elif ord(c) < 0x20 or ord(c) == 0x7F:
            out.append(f"\\u{ord(c):04X}")
        else:
            out.append(c)
    return '"' + "".join(out) + '"'


def toml_comment(text: str) -> str:
    """``text`` made safe inside a ``#`` comment: control characters shown escaped, so a
    newline in a file name cannot start a new TOML line.

    Parameters
    ----------
    text : str
        The text.

    Returns
    -------
    str
        The text with control characters escaped.
    """
    return "".join(c if c.isprintable() or c == " " else
                   c.encode("unicode_escape").decode("ascii") for c in text)


def _depth(value: Any) -> int:
    """Nesting depth of parsed TOML, without recursion."""
    deepest = 0
    stack: list[tuple[Any, int]] = [(value, 0)]
    while stack:
        item, level = stack.pop()
        deepest = max(deepest, level)
        if isinstance(item, dict):
            stack.extend((v, level + 1) for v in item.values())
        elif isinstance(item, list):
            stack.extend((v, level + 1) for v in item)
    return deepest


def parse_toml(text: str, *, field: str = "file", source: str = "<toml>") -> dict[str, Any]:
    """``tomllib.loads`` with one-line errors naming ``source``: invalid TOML, or nesting
    deeper than :data:`MAX_TOML_DEPTH` (which would otherwise end in ``RecursionError``).

    Parameters
    ----------
    text : str
        The TOML text.
    field : str, default "file"
        The field named in messages.
    source : str, default "<toml>"
        Where the text came from, for messages.

    Returns
    -------
    dict
        The parsed tables.

    Raises
    ------
    ParameterError
        For invalid or too deeply nested TOML.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ParameterError(field, source, f"not valid TOML: {err}") from None
    except RecursionError:
        data = None
    if data is None or _depth(data) > MAX_TOML_DEPTH:
        raise ParameterError(field, source, f"tables or arrays nested more than "
                             f"{MAX_TOML_DEPTH} deep; not a parameter file")
    return data


#: largest TOML file read [bytes] (a parameter set is a few kB)
MAX_TOML_BYTES = 16 * 1024 * 1024


def read_toml_file(path: str | Path, *, field: str = "file") -> dict[str, Any]:
    """Parse a TOML file; a missing file, a folder, a FIFO or device, a name the system
    refuses (too long), non-UTF-8 bytes, invalid or deeply nested TOML are refused with one
    line naming the file.

    Parameters
    ----------
    path : str or Path
        The file.
    field : str, default "file"
        The field named in messages.

    Returns
    -------
    dict
        The parsed tables.

    Raises
    ------
    ParameterError
        For a file that cannot be read as TOML, with one line naming it.
    """
    p = Path(path)
    try:
        info = p.stat()
    except (FileNotFoundError, NotADirectoryError):
        raise ParameterError(field, str(p), "no such file") from None
    except OSError as err:
        raise ParameterError(field, str(p), f"cannot be read ({err.strerror or err})") from None
    if stat.S_ISDIR(info.st_mode):
        raise ParameterError(field, str(p), "is a folder, not a TOML file")
    if not stat.S_ISREG(info.st_mode):
        raise ParameterError(field, str(p), "is not a regular file (a FIFO, device or "
                             "socket); expected a TOML file")
    if info.st_size > MAX_TOML_BYTES:
        raise ParameterError(field, str(p), f"{info.st_size} bytes; a parameter or sweep "
                             f"file is at most {MAX_TOML_BYTES // 1024 // 1024} MB")
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as err:
        raise ParameterError(field, str(p), f"not UTF-8 text (byte {err.start}); expected a "
                             "TOML file") from None
    return parse_toml(text, field=field, source=str(p))


def _format_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, int):
        return repr(float(value))
    if isinstance(value, str):
        return toml_string(value)
    if isinstance(value, tuple | list):
        return "[" + ", ".join(_format_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {value!r} to TOML")


def _limit_note(f: dataclasses.Field[Any], value: Any) -> str:
    """Says so when a limit sits at the top of its range: the value means "no limit"."""
    if f.name.endswith("_limit") and isinstance(value, float) and value >= f.metadata["high"]:
        return " (no limit in effect: the top of the allowed range)"
    return ""


def _emit(obj: Any, path: str, lines: list[str]) -> None:
    scalars = []
    nested = []
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if value is None or f.metadata.get("not_a_parameter"):  # [solver]: written by dumps
            continue
        if f.name == "sections":
            nested += _in_file_order(obj)
            continue
        if dataclasses.is_dataclass(value):
            nested.append((f.name, value))
        else:
            scalars.append((f, value))
    if scalars:
        if path:
            lines.append(f"\n[{path}]")
        for f, value in scalars:
            unit = f.metadata.get("unit")
            options = f.metadata.get("options")
            if unit:
                comment = f"  # [{unit_label(obj, f.name)}]{_limit_note(f, value)}"
            elif options:
                comment = f"  # one of {', '.join(options)}"
            else:
                comment = ""
            lines.append(f"{f.name} = {_format_value(value)}{comment}")
    for name, value in nested:
        _emit(value, f"{path}.{name}" if path else name, lines)


def dumps(params: DriveParameters) -> str:
    """TOML text of a parameter set, SI units noted beside each value; the integrator
    settings it carries (:attr:`~feeddrive.DriveParameters.solver`, a file's ``[solver]``
    table) last, as ``[solver]``.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.

    Returns
    -------
    str
        TOML that :func:`loads` reads back to an equal set with the same ``[solver]``
        settings.  A set without them is written as before they were carried: its text (a
        cache or store key's part) does not change.
    """
    note = composition(params.mechanism).file_note
    lines = [
        "# feeddrive parameter set. SI units throughout (m, s, N, kg, A, V, rad).",
        *([f"# {toml_comment(note)}"] if note else []),
        "# `mechanism` names the kind of drive the sections describe (docs/parameters.md).",
    ]
    _emit(params, "", lines)
    lines += solver_lines(params.solver)
    return "\n".join(lines) + "\n"


def solver_lines(solver: Any) -> list[str]:
    """The ``[solver]`` table of a set's integrator settings as TOML lines, each value with
    its unit (SI); no lines for none.

    Parameters
    ----------
    solver : tuple of (str, object, str)
        :attr:`~feeddrive.DriveParameters.solver`.

    Returns
    -------
    list of str
        The lines, from a blank one and ``[solver]``.
    """
    if not solver:
        return []
    lines = ["", "[solver]  # integrator settings, SI (docs/parameters.md, \"[solver]\")"]
    for name, value, _source in solver:
        kind, unit = SOLVER_SETTINGS[name]
        text = str(value) if kind == "count" else _format_value(value)
        lines.append(f"{name} = {text}" + (f"  # [{unit}]" if unit else ""))
    return lines


def save(params: DriveParameters, path: str | Path) -> None:
    """Write a parameter set as TOML (SI units), readable by :func:`load`.

    Parameters
    ----------
    params : DriveParameters
        The set to write.
    path : str or pathlib.Path
        The file to write: a ``.toml`` name (the format :func:`load` and ``--params`` read).

    Raises
    ------
    ParameterError
        For another file name (``x.json``): the set is TOML whatever the name says;
        ``feeddrive.parameters.to_dict`` gives a dict for ``json.dump``.
    """
    from ..io.outputs import atomic_path

    # the arguments swapped, or a preset's name, failed deep inside (an outside check,
    # 2026-12-07)
    if not isinstance(params, DriveParameters):
        raise ParameterError("params", type(params).__name__, "expected DriveParameters, e.g. "
                             "feeddrive.preset('wang2021'); save(params, path)")
    if not isinstance(path, str | os.PathLike):
        raise ParameterError("path", type(path).__name__, "expected a file name (str or "
                             "pathlib.Path) ending in .toml")
    if Path(path).suffix.lower() != ".toml":
        raise ParameterError("path", str(path), "expected a .toml file name: a parameter set "
                             "is written as TOML (for JSON: json.dump(feeddrive.parameters."
                             "to_dict(params), file))")
    with atomic_path(path) as tmp:  # nothing partial under the name (a full disk)
        tmp.write_text(dumps(params), encoding="utf-8")


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    """The resolved field types of parameter class ``cls`` (``typing.get_type_hints``
    evaluates every annotation string anew: 42 % of a parse's time, measured in a fit's
    parameter points, 2026-12-07)."""
    return get_type_hints(cls)


def _build(cls: type, data: Any, path: str) -> Any:
    if not isinstance(data, dict):
        raise ParameterError(path, data, "expected a table of values")
    hints = _hints(cls)
    names = {f.name for f in dataclasses.fields(cls)}
    if "sections" in names:  # a part's own section: its class is registered under its name
        known = registry.table(registry.SECTIONS)
        found = {key: _build(known[key], data[key], f"{path}.{key}" if path else key)
                 for key in sorted(set(data) - names) if key in known}
        data = {k: v for k, v in data.items() if k not in found}
        if found:
            data["sections"] = tuple(found.items())
    unknown = sorted(set(data) - names)
    if unknown:
        key = unknown[0]
        hint = did_you_mean(key, [*names, *(registry.table(registry.SECTIONS)
                                             if "sections" in names else ())])
        raise ParameterError(f"{path}.{key}" if path else key, data[key], "unknown key" + hint)
    kwargs: dict[str, Any] = {}
    for f in dataclasses.fields(cls):
        sub = f"{path}.{f.name}" if path else f.name
        if f.name not in data:
            has_default = (
                f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING
            )
            if has_default:
                continue
            hint = (' (a partial file starts with extends = "wang2021" or another preset)'
                    if not path or "." not in path else "")
            raise ParameterError(sub, MISSING, "missing field" + hint)
        comp = _component_type(hints[f.name])
        if comp is not None and hasattr(comp, "class_for"):  # chosen by the table (its law)
            comp = comp.class_for(data[f.name], sub)
        kwargs[f.name] = _build(comp, data[f.name], sub) if comp else data[f.name]
    try:
        return cls(**kwargs)
    except ParameterError as err:
        # component labels are local ("motor.inertia"); name the full path instead
        local = err.field.split(".", 1)[-1]
        raise ParameterError(f"{path}.{local}" if path else local, err.value,
                             err.message) from None


def _merge(base: dict[str, Any], changes: dict[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for key, value in changes.items():
        if _new_site_class(out.get(key), value):
            out[key] = value  # a law with other parameters: its table replaces the parent's
        elif isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = _merge(out[key], value)
        else:
            out[key] = value
    return out


def _new_site_class(base: Any, change: Any) -> bool:
    """True when ``change`` sets a friction law whose parameter class differs from the law's
    of ``base`` (both site tables)."""
    if not (isinstance(base, dict) and isinstance(change, dict) and "law" in change
            and "law" in base):
        return False
    laws = registry.table(registry.FRICTION_LAWS)
    if change["law"] not in laws or base["law"] not in laws:
        return False
    classes = {getattr(laws[name], "parameters_class", None) for name in (change["law"],
                                                                          base["law"])}
    return len(classes) > 1


def from_dict(data: dict[str, Any], *, base_dir: Path | None = None,
              source: str | None = None) -> DriveParameters:
    """Build a parameter set.  ``extends = "NAME"`` (a preset) or ``"FILE.toml"`` (relative to
    ``base_dir``) starts from that set; the other values replace its values.  A ``[fit]``
    table (written by ``feeddrive fit``: the data, free parameters and intervals of the fit
    that made the set) is a record, not a parameter, and is not read here.  A ``[solver]``
    table (the integrator settings stored with the set) is not a parameter either: the set
    carries it (:attr:`~feeddrive.DriveParameters.solver`, checked by name and kind:
    :func:`~feeddrive.parameters.components.solver_table`) and its runs take it under the
    API's and the command line's settings.  It is the file's own: a set ``extends`` brings in
    keeps its table to itself.

    Parameters
    ----------
    data : dict
        Parsed TOML.
    base_dir : Path, optional
        Folder a relative ``extends`` file is read from.
    source : str, optional
        Where ``data`` came from (a file name), as the ``[solver]`` settings' source
        (``"[solver] in run.toml"``); None: ``"[solver] of the parameter set"``.

    Returns
    -------
    DriveParameters
        The validated set.

    Raises
    ------
    ParameterError
        For an unknown key or a refused value, naming its path.
    """
    table = data.get("solver")
    solver = () if table is None else solver_table(
        table, f"[solver] in {source}" if source is not None else SET_SOURCE)
    data = {k: v for k, v in data.items() if k not in ("fit", "solver")}
    if "extends" in data:
        parent_name = data["extends"]
        if not isinstance(parent_name, str):
            raise ParameterError("extends", parent_name, "expected a preset name or a file path")
        presets = registry.table(registry.PRESETS)
        if parent_name in presets:
            parent = presets[parent_name]()
        elif parent_name.endswith(".toml"):
            parent_path = (base_dir or Path.cwd()) / parent_name
            try:
                parent = load(parent_path)
            except ParameterError as err:
                if err.field == "file" and err.value == str(parent_path):
                    # the named file itself cannot be read: say so about extends
                    raise ParameterError("extends", parent_name, err.message) from None
                raise
        else:
            raise ParameterError("extends", parent_name,
                                 f"expected one of {', '.join(presets)} or a .toml file")
        changes = {k: v for k, v in data.items() if k != "extends"}
        changes.setdefault("name", parent.name if parent.name.endswith("+changes")
                           else f"{parent.name}+changes")
        data = _merge(to_dict(parent), changes)
    result: DriveParameters = _build(DriveParameters, data, "")
    if solver:
        result = dataclasses.replace(result, solver=solver)
    return result


def loads(text: str, *, base_dir: Path | None = None) -> DriveParameters:
    """A parameter set from TOML text (``parse_toml``, then ``from_dict``).

    Parameters
    ----------
    text : str
        The TOML text.
    base_dir : Path, optional
        Folder a relative ``extends`` file is read from.

    Returns
    -------
    DriveParameters
        The validated set.

    Raises
    ------
    ParameterError
        For invalid TOML, an unknown key or a refused value.

    Examples
    --------
    A set that changes one value of a preset:

    >>> from feeddrive.parameters import loads
    >>> params = loads('''
    ... extends = "wang2021"
    ... [controller]
    ... velocity_gain = 50.0
    ... ''')
    >>> print(params.name, params.controller.velocity_gain)
    wang2021+changes 50.0
    """
    return from_dict(parse_toml(text), base_dir=base_dir)


#: longest chain of files each extending the next
MAX_EXTENDS = 32
_loading = threading.local()  # the files being read, outermost first (extends chains)


def load(path: str | Path) -> DriveParameters:
    """Read a parameter set from a TOML file (``extends = "NAME"`` or ``"FILE.toml"`` allowed).

    ``extends`` chains are followed; a cycle (``a.toml`` extends ``b.toml`` extends
    ``a.toml``) or a chain longer than ``MAX_EXTENDS`` files is refused naming its files.
    The file's ``[solver]`` table is carried by the set (:attr:`~feeddrive.DriveParameters.solver`,
    source ``"[solver] in PATH"``): every run of the set takes it where the API and the
    command line give no setting of their own (:func:`~feeddrive.parameters.from_dict`).

    Parameters
    ----------
    path : str or pathlib.Path
        The file.

    Returns
    -------
    DriveParameters
        The validated set; a refusal names the file, the field, the value and the unit.
    """
    if not isinstance(path, str | os.PathLike):  # os.fspath's TypeError (session 29)
        raise ParameterError("path", path, "expected a TOML file's path (str or pathlib.Path);"
                             " a preset by its name is feeddrive.preset(name)")
    chain: list[tuple[Path, str]] = _loading.__dict__.setdefault("chain", [])
    resolved = resolved_path(path)
    names = [name for _, name in chain]
    if any(r == resolved for r, _ in chain):
        start = next(i for i, (r, _) in enumerate(chain) if r == resolved)
        cycle = " → ".join([*names[start:], str(path)])
        raise ParameterError("extends", str(path), f"a cycle of extends: {cycle}")
    if len(chain) >= MAX_EXTENDS:
        raise ParameterError("extends", str(path), f"a chain of more than {MAX_EXTENDS} "
                             f"files ({names[0]} → {names[1]} → … → {names[-1]}); extend a "
                             "preset or a shorter chain")
    chain.append((resolved, str(path)))
    try:
        data = read_toml_file(path)
        carried = _APPLIED.get().get(resolved)
        if carried is None:
            return from_dict(data, base_dir=Path(path).parent, source=str(path))
        data = {k: v for k, v in data.items() if k != "solver"}
        params = from_dict(data, base_dir=Path(path).parent)
        return dataclasses.replace(params, solver=carried) if carried else params
    except ParameterError as err:
        raise err.in_file(str(path)) from None
    finally:
        chain.pop()


#: the files whose ``[solver]`` tables a command merged into the options in force, by
#: resolved path, each with the settings :func:`load` gives its set instead
_APPLIED: ContextVar[Mapping[Path, tuple[tuple[str, Any, str], ...]]] = ContextVar(
    "feeddrive_solver_tables_applied", default=types.MappingProxyType({}))


def resolved_path(path: str | Path) -> Path:
    """A file's path as :func:`load` and :func:`tables_applied` compare it (resolved; as
    given when it cannot be).

    Parameters
    ----------
    path : str or pathlib.Path
        The file.

    Returns
    -------
    pathlib.Path
        The path.
    """
    try:
        return Path(path).resolve()
    except (OSError, RuntimeError):
        return Path(path).absolute()


def table_applied(path: str | Path) -> tuple[tuple[str, Any, str], ...] | None:
    """The settings a command gave in place of file ``path``'s ``[solver]`` table
    (:func:`tables_applied`), or None outside such a command.

    Parameters
    ----------
    path : str or pathlib.Path
        The file.

    Returns
    -------
    tuple of (str, object, str) or None
        (setting, value, source) triples, or None.
    """
    return _APPLIED.get().get(resolved_path(path))


@contextmanager
def tables_applied(tables: Mapping[str | Path, Any]) -> Iterator[None]:
    """Within the block, :func:`load` gives the set of each file named here the settings
    given with it in place of the file's own ``[solver]`` table.

    A command (``feeddrive.cli._solver``) merges its files' tables under its command line
    into the options in force (:func:`feeddrive.engine.options.using`), and has their sets
    carry those tables as they stand under the command line: each setting of a table with
    the command line's value where the command line gives it.  A run then takes the same
    settings in a worker process, which reads the set from its TOML and the options from a
    record without their sources (:meth:`feeddrive.SolverOptions.from_record`), as in this
    one: a setting the command line gives at its default value (``--accuracy 1`` over a
    file's ``accuracy = 0.01``) is not taken for one left to the file.

    Parameters
    ----------
    tables : mapping of (str or pathlib.Path) to (tuple of (str, object, str))
        File → the (setting, value, source) triples its set carries (empty: none).

    Yields
    ------
    None
        Inside the block.
    """
    merged = dict(_APPLIED.get())
    merged.update({resolved_path(path): solver_table(table, "") if table else ()
                   for path, table in tables.items()})
    token = _APPLIED.set(merged)
    try:
        yield
    finally:
        _APPLIED.reset(token)
