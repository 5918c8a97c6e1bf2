"""``rack-pinion-example``: a rack-and-pinion table axis for the ``rack-pinion`` topology.

Not from a paper: an example to show the topology, with values of the size a long machine axis
has.  The motor is Wang2021's servo motor (Table 2, inertia read as 1.38e-3 kg m²); a 10:1
gearbox and a 30-mm pitch-radius pinion give H = 3 mm/rad; the tooth mesh (2e8 N/m, gearbox
torsion and rack compliance lumped in) puts the drive's first resonance near 500 Hz.  The
gearbox friction is a LuGre site of the size of Wang2021's screw-shaft friction at the pitch
line; the table mass and the guide friction are Wang2021's (Table 2, Table 1).  The loops are
tuned as a servo engineer would: current loop ≈ 1 kHz (K_ii/K_ip = R/L), velocity loop on the
motor speed ≈ 30 Hz with its integral corner at 3 Hz, position loop 30 1/s.
"""

from __future__ import annotations

import math

from ..model.friction.lugre_parameters import FrictionBranch, LuGreParameters
from ..model.mechanisms.rack_pinion import RackPinion
from ..parameters.components import DriveParameters
from . import wang2021

GEAR_RATIO = 10.0
PINION_RADIUS = 0.03  # m
GEARBOX_INERTIA = 2e-4  # kg m², at the motor shaft
PINION_INERTIA = 5e-4  # kg m², at the pinion


def example() -> DriveParameters:
    """The ``rack-pinion-example`` parameter set: a rack-and-pinion table axis.

    Wang2021's servo motor, table mass and guide friction (Tables 1–2) behind a 10:1 gearbox and
    a 30-mm pinion (H = 3 mm/rad), a 2e8 N/m tooth mesh (first resonance near 500 Hz) and
    gearbox friction of the size of Wang2021's screw-shaft site; loops tuned to ≈1 kHz current,
    ≈30 Hz velocity (integral corner 3 Hz) and a 30 1/s position loop.

    Returns
    -------
    DriveParameters
        The parameter set [SI].

    References
    ----------
    .. [1] Wang2021 Table 1 (friction), Table 2 (motor, table mass).
    """
    base = wang2021.literal()
    motor = base.screw_motor
    H = PINION_RADIUS / GEAR_RATIO
    inertia = (motor.inertia + GEARBOX_INERTIA + PINION_INERTIA / GEAR_RATIO**2
               + base.table.mass * H**2)  # at the motor shaft [kg m²]
    velocity_gain = 2 * math.pi * 30.0 * inertia / motor.torque_constant  # A s/rad
    current_gain = 2 * math.pi * 1000.0 * motor.inductance  # V/A
    controller = base.controller.with_values(
        position_gain=30.0, velocity_gain=velocity_gain,
        velocity_integral_gain=velocity_gain * 2 * math.pi * 3.0,
        current_gain=current_gain,
        current_integral_gain=current_gain * motor.resistance / motor.inductance,
        velocity_gain_basis="motor", velocity_feedback="motor", velocity_command_gain=1.0,
        current_limit=20.0, voltage_limit=300.0)
    branch = FrictionBranch(coulomb_force=30.0, static_force=40.0, stribeck_velocity=2e-3,
                            viscous_coefficient=200.0)
    gearbox = LuGreParameters(positive=branch, negative=branch, bristle_stiffness=2e6,
                              bristle_damping=500.0)
    section = RackPinion(motor=motor, gearbox_friction=gearbox, gear_ratio=GEAR_RATIO,
                         pinion_radius=PINION_RADIUS, mesh_stiffness=2e8, mesh_damping=2000.0,
                         gearbox_inertia=GEARBOX_INERTIA, pinion_inertia=PINION_INERTIA)
    return base.with_values(
        name="rack-pinion-example",
        description="Example rack-and-pinion axis: Wang2021's motor, table mass and guide "
        "friction, a 10:1 gearbox and 30-mm pinion; see feeddrive/presets/rack_pinion.py.",
        controller=controller, rack_pinion=section)


PRESETS = {"rack-pinion-example": example}
