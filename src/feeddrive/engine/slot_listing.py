"""The parameter slots a run would use, without running it (``feeddrive params slots``).

One drive's model (:func:`drive_slot_model`) and a machine's (:func:`machine_slot_model`)
are assembled at rest, following a zero command, as a run assembles them: their slots
(:func:`feeddrive.model.slots.slot_table`) are those a run of the same drive or machine
records, but for the reference profile's block, which holds the command, not a parameter
(:func:`listed_slots` leaves it out).  A machine's slots could only be seen by running it
(session 27).
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..machine import Machine
    from ..model.assemble import Model
    from ..parameters import DriveParameters

#: the reference profile's block: one drive's ``profile[…]``, a machine axis' ``x.profile[…]``
_PROFILE = re.compile(r"(\w+\.)?profile\[")


def drive_slot_model(params: DriveParameters, drive: str, table_position: float) -> Model:
    """One drive's assembled model at rest (a zero command).

    Parameters
    ----------
    params : DriveParameters
        Its parameter set [SI].
    drive : str
        A registered topology (``"cdfs"`` …).
    table_position : float
        Start position of a ball-screw nut from the motor-side support [m].

    Returns
    -------
    Model
        The model a run of the drive assembles, its profile block a zero command.
    """
    from ..model.reference import ConstantSpeed
    from .simulate import DriveSystem

    system = DriveSystem(params, drive=drive, table_position=table_position)
    return system.model(ConstantSpeed(0.0))


def machine_slot_model(machine: Machine) -> Model:
    """A machine's assembled model at rest (every axis following a zero command): its axes'
    slots ``<axis>.<slot>`` and its coupling parts' ``couplings.<name>.<field>``.

    Parameters
    ----------
    machine : Machine
        The machine (:func:`feeddrive.machine.load_machine`).

    Returns
    -------
    Model
        The model a run of the machine assembles, its axes' profile blocks a zero command.
    """
    from ..machine import MachineProfile, MachineSystem
    from ..model.reference import SampledSpeed

    t = np.array([0.0, 1.0])
    rest = MachineProfile.common(machine, SampledSpeed(time=t, table_speed=np.zeros_like(t)))
    return MachineSystem(machine).model(rest)


def listed_slots(model: Model) -> list[tuple[str, float, str]]:
    """The model's slots as ``feeddrive params slots`` lists them: (name, value [SI], unit)
    in ``P`` order, without the reference profile's block (``profile[…]``, a machine's
    ``<axis>.profile[…]``: the command, not a parameter).

    Parameters
    ----------
    model : Model
        The assembled model.

    Returns
    -------
    list of (str, float, str)
        One row per slot.
    """
    from ..model.slots import slot_table

    return [row for row in slot_table(model) if not _PROFILE.match(row[0])]


__all__ = ["drive_slot_model", "listed_slots", "machine_slot_model"]
