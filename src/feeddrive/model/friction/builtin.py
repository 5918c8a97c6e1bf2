"""Registers the package's friction laws."""

from __future__ import annotations

from .base import register_friction_law
from .dahl import Dahl
from .lugre import LuGre
from .static import NoFriction, Stribeck

for _law in (LuGre(), Stribeck(), Dahl(), NoFriction()):
    register_friction_law(_law)
