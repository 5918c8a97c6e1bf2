"""Drive topologies behind one interface (:class:`Mechanism`), registered by drive name."""

from __future__ import annotations

from .base import (
    Body,
    DriveMotor,
    Mechanics,
    Mechanism,
    Site,
    drive_names,
    mechanism,
    register_mechanism,
)

__all__ = ["Body", "DriveMotor", "Mechanics", "Mechanism", "Site", "drive_names", "mechanism",
           "register_mechanism"]
