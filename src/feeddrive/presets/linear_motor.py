"""``linear-motor-example``: a direct-drive table for the linear-motor topology.

Not from a paper: an example to show the topology, with values of the size a machine-tool
linear axis has.  The motor is representative of small iron-core linear motors (force
constant, back-EMF constant, winding resistance and inductance of the order catalogue data for
~200-N continuous-force motors give; not one specific catalogue entry).  The table mass and
the guide friction are Wang2021's (Table 2 table, Table 1 linear guide), so the friction at the
table is the paper's.  The loops are tuned as a servo engineer would for this plant: current
loop ≈ 1 kHz (K_ii/K_ip = R/L), velocity loop ≈ 50 Hz with an integral corner at 5 Hz,
position loop 50 1/s.  The ball-screw sections are Wang2021's and unused by this topology.
"""

from __future__ import annotations

import math

from ..model.mechanisms.linear_motor import LinearMotor
from ..parameters.components import DriveParameters
from . import wang2021

FORCE_CONSTANT = 73.0  # N/A
BACK_EMF = 60.0  # V s/m
RESISTANCE = 3.8  # ohm
INDUCTANCE = 0.03  # H
FORCER_MASS = 5.0  # kg


def example() -> DriveParameters:
    """The ``linear-motor-example`` parameter set: a direct-drive table for the linear-motor
    topology.

    Wang2021's table mass and guide friction (Table 2, Table 1) with a representative ~200-N
    iron-core linear motor; loops tuned to a ≈1 kHz current loop, ≈50 Hz velocity loop with its
    integral corner at 5 Hz and a 50 1/s position loop (see the module docstring).

    Returns
    -------
    DriveParameters
        The parameter set [SI].

    References
    ----------
    .. [1] Wang2021 Table 1 (linear-guide friction), Table 2 (table mass).
    """
    base = wang2021.literal()
    moving = base.table.mass + FORCER_MASS
    velocity_gain = 2 * math.pi * 50.0 * moving / FORCE_CONSTANT  # A per m/s
    current_gain = 2 * math.pi * 1000.0 * INDUCTANCE  # V/A
    controller = base.controller.with_values(
        position_gain=50.0, velocity_gain=velocity_gain,
        velocity_integral_gain=velocity_gain * 2 * math.pi * 5.0,
        current_gain=current_gain,
        current_integral_gain=current_gain * RESISTANCE / INDUCTANCE,
        velocity_gain_basis="table", velocity_command_gain=1.0, current_limit=20.0,
        voltage_limit=300.0)
    return base.with_values(
        name="linear-motor-example",
        description="Example direct-drive table (linear motor) with Wang2021's table mass and "
        "linear-guide friction; see feeddrive/presets/linear_motor.py.",
        controller=controller,
        linear_motor=LinearMotor(force_constant=FORCE_CONSTANT, back_emf_constant=BACK_EMF,
                                 inductance=INDUCTANCE, resistance=RESISTANCE,
                                 forcer_mass=FORCER_MASS))


PRESETS = {"linear-motor-example": example}
