"""The machinery of parameter sets: the component base, the friction-site base and the
composition container :class:`DriveParameters`.  SI units throughout.

A parameter set is a composition chosen by name (issue 19 item 1): its ``mechanism`` kind
names the parts it needs, and each part's section (``[screw]``, ``[controller]``,
``[friction]``, ``[rack_pinion]`` …) is read by the parameter class that part registers in
:mod:`feeddrive.registry` (group ``feeddrive.sections``), from the part's own module: the
ball screw's in :mod:`feeddrive.model.mechanisms.ball_screw_parameters`, the loops' in
:mod:`feeddrive.model.loops`, LuGre's in :mod:`feeddrive.model.friction.lugre_parameters`,
GMS's in :mod:`feeddrive.model.friction.gms` and so on.  This package imports none of them.

Ranges are plausibility bounds for machine-tool feed drives; they exist to catch wrong units
(a lead of 5 instead of 0.005 m) and impossible values, not to restrict design studies.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field, fields, is_dataclass, replace
from typing import Any, Self

from .. import registry
from .validation import MISSING, ParameterError, did_you_mean, validate

#: the mechanism kind of a file that names none: every parameter file before the
#: composition (v2) describes the ball-screw drive's parts
DEFAULT_MECHANISM = "ball-screw"
#: longest parameter-set name [characters] (it is printed on one line)
MAX_NAME = 200
#: longest parameter-set description [characters]
MAX_DESCRIPTION = 10_000

#: the integrator settings a parameter file's ``[solver]`` table gives, in the order they are
#: written, each with its kind (``"text"``, ``"number"``, ``"count"``: a whole number) and its
#: unit (SI, as the API takes them; the command line takes the
#: lengths in mm and the speeds in mm/s).  The names are
#: :data:`feeddrive.engine.options.SETTINGS` (this package does not import the engine; a test
#: holds the two to each other): their ranges are checked where the settings are used
#: (:class:`feeddrive.SolverOptions`), not here
SOLVER_SETTINGS: dict[str, tuple[str, str]] = {
    "method": ("text", ""), "rtol": ("number", "-"), "position_tolerance": ("number", "m"),
    "speed_tolerance": ("number", "m/s"), "current_tolerance": ("number", "A"),
    "accuracy": ("number", "-"), "output_interval": ("number", "s"),
    "max_step": ("number", "s"), "max_steps": ("count", ""), "rosenbrock": ("text", ""),
}
#: the source of the settings of a ``[solver]`` table given without one
SET_SOURCE = "[solver] of the parameter set"
#: the settings of :data:`SOLVER_SETTINGS` that are tolerances (``accuracy`` multiplies those
#: left at their defaults: the two are not given in one table)
SOLVER_TOLERANCES = ("rtol", "position_tolerance", "speed_tolerance", "current_tolerance")


def solver_table(settings: Any, source: str) -> tuple[tuple[str, Any, str], ...]:
    """A ``[solver]`` table checked by name and kind, as a parameter set carries it
    (:attr:`~feeddrive.DriveParameters.solver`).

    Each setting must be one of ``SOLVER_SETTINGS`` and of its kind (a number, text or
    a whole number), and ``accuracy`` may not come with an explicit tolerance (ambiguous, as
    on the command line).  The values (a positive ``rtol`` at most 0.1, a known method …)
    are :class:`feeddrive.SolverOptions`' to check where the settings are used: before a
    run starts, naming the setting and its source.

    Parameters
    ----------
    settings : mapping or iterable of (str, object, str)
        The table as read from TOML (setting → value, all from ``source``), or the
        (setting, value, source) triples of :attr:`~feeddrive.DriveParameters.solver`.
    source : str
        Where a mapping's settings come from (``"[solver] in run.toml"``), named by the
        refusals and by :meth:`feeddrive.SolverOptions.describe`.

    Returns
    -------
    tuple of (str, object, str)
        (setting, value, source) triples in ``SOLVER_SETTINGS``' order.

    Raises
    ------
    ParameterError
        For a table that is not a table, an unknown setting, a value of the wrong kind, or
        ``accuracy`` with a tolerance.
    """
    if isinstance(settings, Mapping):
        items = [(name, value, source) for name, value in settings.items()]
    elif isinstance(settings, Iterable) and not isinstance(settings, str | bytes):
        items = []
        for entry in settings:
            if not (isinstance(entry, tuple | list) and len(entry) == 3
                    and isinstance(entry[0], str) and isinstance(entry[2], str)):
                raise ParameterError("solver", entry, "expected (setting, value, source) "
                                     "triples or a table of settings")
            items.append((entry[0], entry[1], entry[2]))
    else:
        raise ParameterError("solver", settings, f"expected a table [solver] ({source})")
    seen: dict[str, tuple[Any, str]] = {}
    for name, value, where in items:
        if name not in SOLVER_SETTINGS:
            hint = did_you_mean(name, SOLVER_SETTINGS)
            raise ParameterError(f"solver.{name}", value, f"expected one of "
                                 f"{', '.join(SOLVER_SETTINGS)}{hint} ({where})")
        kind, unit = SOLVER_SETTINGS[name]
        if kind == "text":
            ok = isinstance(value, str)
            expected = "expected text"
        elif kind == "count":
            ok = isinstance(value, int) and not isinstance(value, bool)
            expected = "expected a whole number"
        else:
            ok = isinstance(value, int | float) and not isinstance(value, bool)
            expected = f"expected a number [{unit}]"
        if not ok:
            raise ParameterError(f"solver.{name}", value, f"{expected} ({where})")
        seen[name] = (float(value) if kind == "number" else value, where)
    tolerances = [n for n in SOLVER_TOLERANCES if n in seen]
    if "accuracy" in seen and tolerances:  # worded as feeddrive.engine.options.layered
        raise ParameterError("solver.accuracy", seen["accuracy"][0],
                             f"given with solver.{tolerances[0]} ({seen['accuracy'][1]}): "
                             "give either an accuracy factor or explicit tolerances")
    return tuple((name, *seen[name]) for name in SOLVER_SETTINGS if name in seen)


def solver_over(lower: Any, upper: Any) -> tuple[tuple[str, Any, str], ...]:
    """The settings of ``[solver]`` table ``upper`` over those of ``lower`` (a sweep
    configuration's over its parameter file's), as one table a set can carry.

    ``upper``'s settings replace ``lower``'s of the same name, and an ``accuracy`` of
    ``upper``'s replaces ``lower``'s explicit tolerances as well (as a higher setting's does,
    :func:`feeddrive.engine.options.layered`).  Tolerances of ``upper``'s over an
    ``accuracy`` of ``lower``'s are refused: one table cannot hold both (it would be refused
    where it is read back, in a worker process).

    Parameters
    ----------
    lower, upper : tuple of (str, object, str)
        (setting, value, source) triples (:func:`~feeddrive.parameters.components.solver_table`).

    Returns
    -------
    tuple of (str, object, str)
        The merged triples.

    Raises
    ------
    ParameterError
        For ``upper``'s tolerances over ``lower``'s ``accuracy``.
    """
    below = {name: (value, source) for name, value, source in lower}
    above = {name: (value, source) for name, value, source in upper}
    tolerances = [n for n in SOLVER_TOLERANCES if n in above]
    if "accuracy" in below and "accuracy" not in above and tolerances:
        name = tolerances[0]
        raise ParameterError(f"solver.{name}", above[name][0],
                             f"given in {above[name][1]} over accuracy in "
                             f"{below['accuracy'][1]}: give the accuracy factor or the "
                             "explicit tolerances in one of the two tables")
    if "accuracy" in above:
        below = {n: v for n, v in below.items() if n not in SOLVER_TOLERANCES}
    merged = {**below, **above}
    return tuple((name, *merged[name]) for name in SOLVER_SETTINGS if name in merged)


class _Component:
    """Mixin: validate on construction, ``replace`` with re-validation."""

    _label = "component"

    def __post_init__(self) -> None:
        validate(self, self._label)
        self._check()

    def _check(self) -> None:
        """Cross-field checks; override where needed."""

    def with_values(self, **changes: Any) -> Self:
        """A copy with some fields replaced, validated like the original.

        Parameters
        ----------
        **changes
            Field name → new value [SI unit of the field].

        Returns
        -------
        Component
            The new component.

        Raises
        ------
        ParameterError
            For an unknown field or a refused value.
        """
        # a misspelt field was the dataclass's TypeError ("__init__() got an unexpected
        # keyword argument": an API sweep of session 29)
        names = [f.name for f in fields(self)]  # type: ignore[arg-type]
        for name, value in changes.items():
            # a DriveParameters takes its sections by name too, and names an unknown one
            if name not in names and "sections" not in names:
                raise ParameterError(f"{self._label}.{name}", value, "unknown field; expected "
                                     f"one of {', '.join(names)}{did_you_mean(name, names)}")
        return replace(self, **changes)  # type: ignore[type-var]


#: the base of every parameter component: a part's own section subclasses it
Component = _Component


@dataclass(frozen=True)
class SiteParameters(_Component):
    """Base of the parameters of one friction site.  Its ``law`` picks the class: each
    friction law names its parameter class (``FrictionLaw.parameters_class``), so a law with
    parameters of its own (e.g. GMS) brings them in its own module; laws without (LuGre,
    Stribeck, Dahl, none) share ``LuGreParameters``."""

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
        cls = getattr(laws[law], "parameters_class", None)
        if not (isinstance(cls, type) and issubclass(cls, SiteParameters)):
            raise ParameterError(f"{path}.law", law, "this law declares no parameter class "
                                 "(FrictionLaw.parameters_class)")
        return cls

    def require(self, kind: type[SiteParameters], path: str, what: str) -> Any:
        """This site as ``kind``, or a refusal naming the site, its law and what needs it.

        Parameters
        ----------
        kind : type of SiteParameters
            The parameter class the caller works with (e.g. ``LuGreParameters``).
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


def laws_of(kind: type[SiteParameters]) -> list[str]:
    """The registered friction laws whose sites take the parameter class ``kind``.

    Parameters
    ----------
    kind : type of SiteParameters
        A site parameter class.

    Returns
    -------
    list of str
        The law names, sorted.
    """
    return [name for name, law in registry.table(registry.FRICTION_LAWS).items()
            if getattr(law, "parameters_class", None) is kind]


_laws_of = laws_of


@dataclass(frozen=True)
class Composition:
    """What a mechanism kind is made of: the parts (sections) a parameter set of that kind
    must have, and those it gets by default.  A mechanism's module registers one under its
    kind's name (registry group ``feeddrive.mechanism_kinds``).

    Parameters
    ----------
    required : tuple of str
        Section names the set must give (``"screw"``, ``"friction"`` …), in the order a file
        writes them.
    defaults : tuple of (str, callable)
        Section names with a factory of their default parameters, used when the set gives
        none (``("controller", default_controller)``); written after ``required``.
    description : str, default ""
        One line on the kind, for messages and ``feeddrive params show``.
    file_note : str, default ""
        What a reader of a file of this kind must know about its values (a comment line
        at the top of a written file, e.g. how rotary sites' friction is stored).
    """

    required: tuple[str, ...]
    defaults: tuple[tuple[str, Callable[[], Any]], ...] = ()
    description: str = ""
    file_note: str = ""

    def order(self) -> tuple[str, ...]:
        """The section names of this kind, in file order.

        Returns
        -------
        tuple of str
            ``required``, then the names of ``defaults``.
        """
        return self.required + tuple(name for name, _ in self.defaults)


def composition(kind: Any) -> Composition:
    """The registered :class:`Composition` of mechanism kind ``kind``.

    Parameters
    ----------
    kind : str
        A mechanism kind (``"ball-screw"``).

    Returns
    -------
    Composition
        Its parts; an unknown kind is refused with one line naming the kinds.
    """
    kinds = registry.table(registry.MECHANISM_KINDS)
    if not isinstance(kind, str) or kind not in kinds:
        raise ParameterError("mechanism", kind, "unknown mechanism kind; expected one of "
                             f"{', '.join(kinds) or '(none registered)'}")
    found: Composition = kinds[kind]
    return found


@dataclass(frozen=True, init=False)
class DriveParameters(_Component):
    """A feed drive's parameters: a composition of its parts' sections, chosen by name.

    All values SI (the TOML files and ``feeddrive params show`` too).  The ``mechanism`` kind
    names the parts the set must have (:class:`~feeddrive.parameters.Composition`); each
    part's section is an instance of the parameter class its module registers (registry
    group ``feeddrive.sections``), which validates its own fields with units and ranges
    (:mod:`feeddrive.parameters.validation`).  Sections read like fields
    (``params.screw.lead``, ``params.controller``); an optional section a set does not give
    reads as None (``params.linear_motor``).

    Parameters
    ----------
    name : str
        Name of the set (printed in reports, results and exports).
    description : str
        What the set is and where its values come from.
    mechanism : str, default "ball-screw"
        The mechanism kind (registry group ``feeddrive.mechanism_kinds``).  The
        ``"ball-screw"`` kind needs ``screw``, ``coupling``, ``screw_motor``,
        ``hollow_motor``, ``table`` and ``friction`` and gives ``stiffness``, ``controller``
        and ``disturbances`` their defaults.
    sections : tuple of (str, Component), default ()
        The parts' sections by name.
    solver : tuple of (str, object, str) or mapping, default ()
        The integrator settings stored with the set: a parameter file's ``[solver]`` table
        (:func:`feeddrive.parameters.load`), as (setting, value, source) triples
        (:func:`~feeddrive.parameters.components.solver_table`; a mapping is taken as
        settings of the source ``"[solver] of the parameter set"``).  Not a parameter: not
        compared, not hashed, not in :func:`~feeddrive.parameters.to_dict`; written as
        ``[solver]`` by :func:`~feeddrive.parameters.dumps`, kept by :meth:`replace_path`,
        and layered under the options of every run of the set (precedence: the command
        line, the API, this table, the defaults; :func:`feeddrive.engine.simulate.run_options`).
    **parts : Component or None
        Sections given by keyword (``screw=BallScrew(...)``); they replace those of
        ``sections`` of the same name, None removes one.
    """

    name: str
    description: str
    mechanism: str = DEFAULT_MECHANISM
    # every part's section by name, sorted: registry group feeddrive.sections
    sections: tuple[tuple[str, Any], ...] = ()
    # a file's [solver] table: a record, not a parameter (not compared, hashed or in to_dict)
    solver: tuple[tuple[str, Any, str], ...] = field(
        default=(), compare=False, repr=False, metadata={"not_a_parameter": True})
    _label = "parameters"

    def __init__(self, name: str, description: str, mechanism: str = DEFAULT_MECHANISM,
                 sections: Any = (), *, solver: Any = (), **parts: Any) -> None:
        kind = composition(mechanism)
        try:
            merged = dict(sections)
        except (TypeError, ValueError):
            raise ParameterError("sections", sections,
                                 "expected (name, section) pairs") from None
        for key, value in parts.items():
            if value is None:
                merged.pop(key, None)
            else:
                merged[key] = value
        for key, factory in kind.defaults:
            if key not in merged:
                merged[key] = factory()
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "description", description)
        object.__setattr__(self, "mechanism", mechanism)
        object.__setattr__(self, "sections", tuple(sorted(merged.items())))
        object.__setattr__(self, "solver", solver_table(solver, SET_SOURCE) if solver else ())
        self.__post_init__()

    def __repr__(self) -> str:
        first = self.description.split(". ")[0].rstrip(".")
        if len(first) > 80:
            first = first[:79] + "…"
        names = ", ".join(name for name, _ in self.ordered_sections())
        return (f"<feeddrive DriveParameters {self.name!r}: {first}; sections {names}; "
                "feeddrive.parameters.dumps(p) prints every field>")

    def _check(self) -> None:
        _check_text("name", self.name, MAX_NAME, lines=False)
        _check_text("description", self.description, MAX_DESCRIPTION, lines=True)
        known = registry.table(registry.SECTIONS)
        for name, value in self.sections:
            cls = known.get(name)
            if cls is None:
                raise ParameterError(name, "…", f"unknown section; expected one of "
                                     f"{', '.join(known) or '(none registered)'}")
            if not isinstance(value, cls):
                raise ParameterError(name, type(value).__name__, f"expected {cls.__name__}")
        given = {name for name, _ in self.sections}
        for name in composition(self.mechanism).required:
            if name not in given:
                raise ParameterError(name, MISSING, 'missing field (a partial file starts with '
                                     'extends = "wang2021" or another preset)')

    def ordered_sections(self) -> list[tuple[str, Any]]:
        """The sections in file order: the kind's parts as its
        :class:`~feeddrive.parameters.Composition` lists them, then the others by name.

        Returns
        -------
        list of (str, Component)
            (section name, its parameters) pairs.
        """
        order = composition(self.mechanism).order()
        rank = {name: i for i, name in enumerate(order)}
        return sorted(self.sections, key=lambda kv: (rank.get(kv[0], len(order)), kv[0]))

    def section(self, name: str) -> Any:
        """A part's own parameter section (e.g. ``"rack_pinion"``), or None if absent.

        Parameters
        ----------
        name : str
            The section's name in the parameter file.

        Returns
        -------
        Component or None
            The section's parameters; None for a registered section the set does not give,
            and for a name no installed part registers (a plugin's section, its package not
            installed here: no set can give it).

        Raises
        ------
        ParameterError
            For a name that is not a string (``['x']`` was "unhashable type", ``3`` read as
            an absent section: session 29), or an unregistered one close to a registered
            section's, a misspelling (``"backlsh"`` read as an absent section: session 30),
            in one line with the sections' names.
        """
        known, given = registry.table(registry.SECTIONS), dict(self.sections)
        if isinstance(name, str) and (name in known or name in given):
            return given.get(name)
        names = sorted({*given, *known})
        if not isinstance(name, str):
            raise ParameterError("name", name, "expected a section's name (str), e.g. one of "
                                 + ", ".join(names))
        hint = did_you_mean(name, names)
        if hint:
            raise ParameterError("name", name, f"no section of that name{hint}; expected "
                                 "one of " + ", ".join(names))
        return None

    def __getattr__(self, name: str) -> Any:
        # sections read like fields (params.screw, params.rack_pinion, dotted paths); an
        # optional section the set does not give reads as None; only called when normal
        # attribute lookup fails
        if name.startswith("_") or name in ("sections", "name", "description", "mechanism",
                                            "solver"):
            raise AttributeError(name)
        for key, value in object.__getattribute__(self, "sections"):
            if key == name:
                return value
        if name in registry.table(registry.SECTIONS):
            return None
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
        if not isinstance(path, str) or not path:
            raise ParameterError("path", path, "expected a dotted field name as text, e.g. "
                                 "'controller.velocity_gain'")
        return _replace_path(self, path.split("."), value, path)


def _not_a_parameter(obj: Any, name: str) -> bool:
    """Whether field ``name`` of ``obj`` is a record carried with the set, not a parameter
    (:attr:`DriveParameters.solver`)."""
    found = {f.name: f for f in fields(obj)}.get(name)
    return found is not None and bool(found.metadata.get("not_a_parameter"))


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


def unit_of(component: type, path: str) -> str | None:
    """The unit a parameter class declares for a dotted path below it.

    Parameters
    ----------
    component : type
        A parameter component class (e.g. ``LuGreParameters``).
    path : str
        Dotted path, entries of a tuple field with ``[i]``
        (``"positive.coulomb_force"``, ``"element_stiffness[2]"``).

    Returns
    -------
    str or None
        The unit of the field's metadata (``"-"`` for dimensionless), None when the path
        names no quantity of the class.
    """
    meta = field_metadata(component, path)
    unit = None if meta is None else meta.get("unit")
    return None if unit is None else str(unit)


def field_metadata(component: type, path: str) -> Mapping[str, Any] | None:
    """The declaration (:func:`~feeddrive.parameters.validation.quantity` metadata: unit,
    ``low``, ``high``, ``low_inclusive``, hint) of the quantity a dotted path names below a
    parameter class: what a parameter file's value at that path is checked against.

    Parameters
    ----------
    component : type
        A parameter component class (e.g. ``LuGreParameters``, ``DriveParameters``).
    path : str
        Dotted path, entries of a tuple field with ``[i]``
        (``"positive.coulomb_force"``, ``"element_stiffness[2]"``, ``"table.mass"``).

    Returns
    -------
    Mapping or None
        The field's metadata, None when the path names no quantity of the class.
    """
    import typing

    for i, part in enumerate(path.split(".")):
        name = part.split("[", 1)[0]
        found = {f.name: f for f in fields(component)}.get(name)
        if found is None and "sections" in {f.name for f in fields(component)}:
            section = registry.table(registry.SECTIONS).get(name)
            if section is None:
                return None
            component = section  # a part's section of the composition
            continue
        if found is None:
            return None
        hint = typing.get_type_hints(component).get(name)
        if isinstance(hint, type) and hasattr(hint, "__dataclass_fields__"):
            component = hint
            continue
        if "unit" not in found.metadata or i != path.count("."):
            return None
        return found.metadata
    return None


def _replace_path(obj: Any, parts: list[str], value: Any, full: str) -> Any:
    names = {f.name for f in fields(obj)}
    head = parts[0]
    sections = dict(getattr(obj, "sections", ()) if head not in names else ())
    if len(parts) == 1 and head not in names and "sections" in names and (
            head in registry.table(registry.SECTIONS)):
        return replace(obj, **{head: value})  # a whole section, given or added
    if head in sections:
        changed = (_replace_path(sections[head], parts[1:], value, full) if len(parts) > 1
                   else value)
        return replace(obj, sections=tuple(sorted({**sections, head: changed}.items())))
    if head not in names:
        raise ParameterError(full, value, f"unknown field {head!r}")
    if _not_a_parameter(obj, head):
        raise ParameterError(full, value, "not a parameter (the set's [solver] table: "
                             "integrator settings, given to SolverOptions or in the file)")
    if len(parts) == 1:
        try:
            return replace(obj, **{head: value})
        except ParameterError as err:
            # component labels are local ("motor.inertia"); name the full path instead
            prefix = full.rsplit(".", 1)[0] if "." in full else ""
            local = err.field.split(".", 1)[-1]
            raise ParameterError(f"{prefix}.{local}" if prefix else local, err.value,
                                 err.message) from None
    inner = getattr(obj, head)
    if not is_dataclass(inner):  # "x.y" past a value was dataclasses' TypeError (session 29)
        raise ParameterError(full, value, f"unknown field {parts[1]!r}: {head} is a value, "
                             "not a section")
    return replace(obj, **{head: _replace_path(inner, parts[1:], value, full)})


def __getattr__(name: str) -> Any:
    """Names that moved from here before 0.2.0: importable until 0.3.0, with a
    DeprecationWarning naming their new place (:mod:`feeddrive._compat`)."""
    from .. import _compat

    return _compat.moved(__name__, name)
