"""Parameter sets: validated component dataclasses, named presets, TOML io."""

from __future__ import annotations

from collections.abc import Callable, Mapping

from .. import registry
from .components import (
    BallScrew,
    Compensation,
    Component,
    Controller,
    Coupling,
    Disturbances,
    DriveParameters,
    FrictionBranch,
    FrictionSites,
    LeadError,
    LinearMotor,
    LuGreParameters,
    Motor,
    SiteParameters,
    StiffnessModel,
    Table,
    TorqueRipple,
)
from .toml_io import dumps, from_dict, load, loads, save, to_dict
from .validation import ParameterError


class _Presets(Mapping[str, Callable[[], DriveParameters]]):
    """The registered presets (:mod:`feeddrive.registry`, group ``feeddrive.presets``: the
    package's own in :mod:`feeddrive.presets` and any installed plug-in's), loaded on first
    use."""

    def _table(self) -> dict[str, Callable[[], DriveParameters]]:
        return registry.table(registry.PRESETS)

    def __getitem__(self, name: str) -> Callable[[], DriveParameters]:
        return self._table()[name]

    def __iter__(self):
        return iter(self._table())

    def __len__(self) -> int:
        return len(self._table())


PRESETS = _Presets()


def preset(name: str) -> DriveParameters:
    """The named parameter set.

    Parameters
    ----------
    name : str
        A registered preset, e.g. ``"wang2021"`` or ``"wang2021-literal"``.

    Returns
    -------
    DriveParameters
        A new copy of the set.
    """
    if name not in PRESETS:
        raise ParameterError(
            "preset", name, f"unknown preset; expected one of {', '.join(PRESETS)}"
        )
    return PRESETS[name]()


__all__ = [
    "BallScrew", "Component", "Compensation", "Controller", "Coupling", "Disturbances",
    "DriveParameters", "FrictionBranch",
    "FrictionSites", "LeadError", "LinearMotor", "LuGreParameters", "Motor", "ParameterError",
    "PRESETS", "SiteParameters", "StiffnessModel", "Table", "TorqueRipple", "dumps", "from_dict",
    "load", "loads", "preset", "save", "to_dict",
]
