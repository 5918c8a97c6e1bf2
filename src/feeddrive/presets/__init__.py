"""Published parameter sets, one module per paper, registered by name.

The core never imports this package: :func:`feeddrive.parameters.preset` looks names up in
:mod:`feeddrive.registry` (group ``feeddrive.presets``), which imports this package when first
asked, so a preset may use any part of the package (the stiffness chain, say) without an import
cycle.  Add a set with :func:`register_preset`, or from another distribution with an entry point
in group ``feeddrive.presets``.
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable

from .. import registry
from ..parameters.components import DriveParameters

PRESETS: dict[str, Callable[[], DriveParameters]] = {}
# every module of this package lists its sets in a module-level ``PRESETS`` dict
for _info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
    PRESETS.update(getattr(importlib.import_module(f"{__name__}.{_info.name}"), "PRESETS", {}))
for _name, _factory in PRESETS.items():
    registry.register(registry.PRESETS, _name, _factory)


def register_preset(name: str, factory: Callable[[], DriveParameters]) -> None:
    """Make a parameter set available by name, to ``preset(name)``, ``--preset`` and
    ``extends = "name"`` in a parameter file.

    Parameters
    ----------
    name : str
        The preset's name.
    factory : callable
        Called with no arguments, returns the :class:`DriveParameters` (built on each use).
    """
    PRESETS[name] = factory
    registry.register(registry.PRESETS, name, factory)
