"""Published parameter sets, one module per paper, registered by name.

The core never imports this package at module level: :func:`feeddrive.parameters.preset`
looks names up here when asked, so a preset may use any part of the package (the stiffness
chain, say) without an import cycle.  Add a set with :func:`register_preset`.
"""

from __future__ import annotations

from collections.abc import Callable

from ..parameters.components import DriveParameters
from . import linear_motor, wang2021

PRESETS: dict[str, Callable[[], DriveParameters]] = {
    "wang2021": wang2021.shipped,
    "wang2021-literal": wang2021.literal,
    "linear-motor-example": linear_motor.example,
}


def register_preset(name: str, factory: Callable[[], DriveParameters]) -> None:
    """Make ``factory()`` available as ``preset(name)`` and ``extends = "name"``."""
    PRESETS[name] = factory
