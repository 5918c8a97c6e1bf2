"""Friction laws behind one interface: LuGre, static Stribeck, Dahl, none; and a registry."""

from __future__ import annotations

from . import builtin  # noqa: F401
from .base import FrictionLaw, LinearFriction, friction_law, law_names, register_friction_law

__all__ = ["FrictionLaw", "LinearFriction", "friction_law", "law_names",
           "register_friction_law"]
