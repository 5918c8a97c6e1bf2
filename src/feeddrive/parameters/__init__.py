"""Parameter sets: validated component dataclasses, named presets, TOML io."""

from __future__ import annotations

from collections.abc import Callable

from .components import (
    BallScrew,
    Controller,
    Coupling,
    DriveParameters,
    FrictionBranch,
    FrictionSites,
    LuGreParameters,
    Motor,
    StiffnessModel,
    Table,
)
from .sets import wang2021
from .toml_io import dumps, from_dict, load, loads, save, to_dict
from .validation import ParameterError

PRESETS: dict[str, Callable[[], DriveParameters]] = {
    "wang2021": wang2021.shipped,
    "wang2021-literal": wang2021.literal,
}


def preset(name: str) -> DriveParameters:
    """The named parameter set, e.g. ``preset("wang2021")``."""
    if name not in PRESETS:
        raise ParameterError(
            "preset", name, f"unknown preset; expected one of {', '.join(PRESETS)}"
        )
    return PRESETS[name]()


__all__ = [
    "BallScrew", "Controller", "Coupling", "DriveParameters", "FrictionBranch", "FrictionSites",
    "LuGreParameters", "Motor", "ParameterError", "PRESETS", "StiffnessModel", "Table",
    "dumps", "from_dict", "load", "loads", "preset", "save", "to_dict", "wang2021",
]
