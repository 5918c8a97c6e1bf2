"""The ground floor: plug-ins found by name — drive mechanisms, friction laws, parameter sets.

This module imports nothing from feeddrive, so any layer may ask it for a name without an
import cycle (:mod:`feeddrive.parameters` asks for friction-law and preset names; the parts
that provide them sit above it).  A group's providers are

* the package's own modules, listed in :data:`BUILTIN_PROVIDERS` (``"package.*"``: every
  module of that package, so a new mechanism or law module is found without a list to edit);
  importing one registers what it defines (it calls :func:`register`), and
* every installed distribution's `entry points <https://packaging.python.org/en/latest/
  specifications/entry-points/>`_ in the group of that name: ``feeddrive.mechanisms`` (name =
  drive name, value = a mechanism class), ``feeddrive.friction_laws`` (name = law name, value
  = a friction-law instance), ``feeddrive.presets`` (name = set name, value = a function
  returning the parameter set), ``feeddrive.sections`` (name = a parameter-file section
  such as ``screw``, ``controller`` or ``rack_pinion``, value = the part's parameter class)
  , ``feeddrive.mechanism_kinds`` (name = a parameter file's ``mechanism`` kind such as
  ``ball-screw``, value = a :class:`feeddrive.parameters.Composition` naming its parts)
  and ``feeddrive.couplings`` (name = a machine file's coupling ``part``, value = a
  :class:`feeddrive.machine.couplings.Coupling` subclass).

Both are imported only when a group is first read, so that ``import feeddrive.parameters``
stays cheap and a broken third-party plug-in cannot stop the package from importing.

Example ``pyproject.toml`` of a plug-in package::

    [project.entry-points."feeddrive.presets"]
    my-mill = "my_mill.params:my_mill"
"""

from __future__ import annotations

import importlib
import pkgutil
import sys
from importlib.metadata import EntryPoints, entry_points
from typing import Any

MECHANISMS = "feeddrive.mechanisms"
FRICTION_LAWS = "feeddrive.friction_laws"
PRESETS = "feeddrive.presets"
SECTIONS = "feeddrive.sections"
MECHANISM_KINDS = "feeddrive.mechanism_kinds"
COUPLINGS = "feeddrive.couplings"
#: builds of the engine other than numba (name → an object with ``driver(model, use)``,
#: :mod:`feeddrive.solvers.builds`): the C build registers itself as ``"c"``
ENGINES = "feeddrive.engines"

#: The package's own providers of each group (modules that register on import).
BUILTIN_PROVIDERS: dict[str, tuple[str, ...]] = {
    MECHANISMS: ("feeddrive.model.mechanisms.*",),
    FRICTION_LAWS: ("feeddrive.model.friction.*",),
    PRESETS: ("feeddrive.presets",),
    # parameter sections of parts (``[screw]``, ``[controller]``, ``[rack_pinion]`` …):
    # registered by the part's own module
    SECTIONS: ("feeddrive.model.mechanisms.*", "feeddrive.model.parts.*",
               "feeddrive.model.loops", "feeddrive.model.disturbances"),
    # a parameter file's ``mechanism`` kind: the parts it is composed of
    MECHANISM_KINDS: ("feeddrive.model.mechanisms.*",),
    # a machine's coupling parts (``[couplings.<name>] part = "…"``): parts joined to the
    # axes by named signals (feeddrive.machine.couplings)
    COUPLINGS: ("feeddrive.machine.couplings.*",),
    # the C build of the drivers (feeddrive.backends.c_engine), read only when a run asks
    # for a build: the core never imports the code generators
    ENGINES: ("feeddrive.backends.c_engine",),
}

_TABLES: dict[str, dict[str, Any]] = {group: {} for group in BUILTIN_PROVIDERS}
_LOADED: set[str] = set()
_LOADING: set[str] = set()
_ENTRY_POINTS: tuple[tuple[str, ...], EntryPoints] | None = None


class PluginError(RuntimeError):
    """An installed entry point of a feeddrive group could not be loaded."""


def register(group: str, name: str, obj: Any) -> Any:
    """Make ``obj`` available as ``name`` in ``group``; returns ``obj``.

    Parameters
    ----------
    group : str
        One of :data:`MECHANISMS`, :data:`FRICTION_LAWS`, :data:`PRESETS`.
    name : str
        The name users give (drive name, law name, preset name).
    obj : object
        What the name stands for.

    Returns
    -------
    object
        ``obj``, unchanged (so that ``register`` can end a definition).
    """
    _table_of(group)[name] = obj
    return obj


def table(group: str) -> dict[str, Any]:
    """Every registered name of ``group`` and what it stands for, providers loaded first.

    Parameters
    ----------
    group : str
        One of :data:`MECHANISMS`, :data:`FRICTION_LAWS`, :data:`PRESETS`.

    Returns
    -------
    dict
        Name → registered object, sorted by name (registration order depends on which module
        happened to be imported first).
    """
    tab = _table_of(group)
    if group not in _LOADED and group not in _LOADING:
        _LOADING.add(group)
        try:
            for provider in BUILTIN_PROVIDERS[group]:
                _import_provider(provider)
            for ep in _entry_points().select(group=group):
                try:
                    obj = ep.load()
                except Exception as exc:  # a third-party plug-in: name it, never a traceback
                    raise PluginError(f"entry point {ep.name!r} = {ep.value!r} of group "
                                      f"{group!r} could not be loaded: {exc}") from exc
                tab.setdefault(ep.name, obj)
            _LOADED.add(group)
        finally:
            _LOADING.discard(group)
    return dict(sorted(tab.items()))


def _entry_points() -> EntryPoints:
    """Every installed distribution's entry points, read once per ``sys.path``: each
    ``entry_points(group=...)`` call reads the metadata of every installed distribution
    again (five groups: five scans of 10–20 ms each; issue 21 item 4).  A folder added to
    ``sys.path`` later is read then."""
    global _ENTRY_POINTS
    path = tuple(sys.path)
    if _ENTRY_POINTS is None or _ENTRY_POINTS[0] != path:
        # all groups (Python 3.11: SelectableGroups, whose select() is EntryPoints')
        found: Any = entry_points()
        _ENTRY_POINTS = (path, found)
    return _ENTRY_POINTS[1]


def names(group: str) -> tuple[str, ...]:
    """The registered names of ``group`` (see :func:`table`).

    Parameters
    ----------
    group : str
        One of :data:`MECHANISMS`, :data:`FRICTION_LAWS`, :data:`PRESETS`.

    Returns
    -------
    tuple of str
        The names, sorted.
    """
    return tuple(table(group))


def _import_provider(provider: str) -> None:
    if not provider.endswith(".*"):
        importlib.import_module(provider)
        return
    package = importlib.import_module(provider[:-2])
    for info in sorted(pkgutil.iter_modules(package.__path__), key=lambda i: i.name):
        importlib.import_module(f"{package.__name__}.{info.name}")


def _table_of(group: str) -> dict[str, Any]:
    try:
        return _TABLES[group]
    except KeyError:
        raise KeyError(f"unknown plug-in group {group!r}; expected one of "
                       f"{', '.join(_TABLES)}") from None
