"""Parameter sets: the machinery — validation, the composition container, TOML io, presets.

A set is a composition of its parts' sections (:class:`DriveParameters`); each part's
parameter class lives with the part (registry group ``feeddrive.sections``):

* ``screw``, ``coupling``, ``stiffness``, ``friction``: ``BallScrew``, ``Coupling``,
  ``StiffnessModel``, ``FrictionSites`` (:mod:`feeddrive.model.mechanisms.ball_screw_parameters`,
  which also registers the mechanism kind ``"ball-screw"``);
* ``screw_motor``, ``hollow_motor``, ``table``: ``Motor``, ``Table``
  (:mod:`feeddrive.model.mechanisms.shared`);
* ``linear_motor``: ``LinearMotor`` (:mod:`feeddrive.model.mechanisms.linear_motor`);
* ``rack_pinion``: ``RackPinion`` (:mod:`feeddrive.model.mechanisms.rack_pinion`);
* ``controller``, ``hollow_controller``: ``Controller`` with its ``Compensation``
  (:mod:`feeddrive.model.loops`);
* ``disturbances``: ``Disturbances``, ``TorqueRipple``, ``LeadError``
  (:mod:`feeddrive.model.disturbances`);
* ``acceleration_feedforward``: ``AccelerationFeedforward``
  (``feeddrive.model.parts.acceleration_feedforward``);
* ``reset_integrator``: ``ResetIntegrator`` (``feeddrive.model.parts.reset_integrator``);
* ``disturbance_observer``: ``DisturbanceObserver``
  (``feeddrive.model.parts.disturbance_observer``);
* ``friction.<site>``, by the site's law: ``LuGreParameters`` and ``FrictionBranch``
  (:mod:`feeddrive.model.friction.lugre_parameters`), ``GMSParameters``
  (:mod:`feeddrive.model.friction.gms`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from .. import registry
from .components import (
    Component,
    Composition,
    DriveParameters,
    SiteParameters,
    composition,
)
from .toml_io import dumps, from_dict, load, loads, save, to_dict
from .validation import ParameterError, did_you_mean


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

    Examples
    --------
    >>> import feeddrive as fd
    >>> params = fd.preset("wang2021")
    >>> params.controller.velocity_integral_gain  # the one fitted number
    3925.28
    """
    if not isinstance(name, str) or name not in PRESETS:  # a list was "unhashable type"
        raise ParameterError(
            "preset", name, f"unknown preset; expected one of {', '.join(PRESETS)}"
            + did_you_mean(name, PRESETS)
        )
    return PRESETS[name]()


__all__ = [
    "Component", "Composition", "DriveParameters", "ParameterError", "PRESETS",
    "SiteParameters", "composition", "dumps", "from_dict", "load", "loads", "preset", "save",
    "to_dict",
]


def __getattr__(name: str) -> Any:
    """Names that moved from here before 0.2.0: importable until 0.3.0, with a
    DeprecationWarning naming their new place (:mod:`feeddrive._compat`)."""
    from .. import _compat

    return _compat.moved(__name__, name)
