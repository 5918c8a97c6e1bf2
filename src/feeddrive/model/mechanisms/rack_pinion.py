"""A rack-and-pinion drive: servo motor → gearbox → pinion → rack on the table.

    F_mesh  = k_m·(H·θ_m − x_t) + c_m·(H·ω_m − v_t),          H = r_p / G  [m/rad]
    J·ω̇_m  = K_t·i − H·F_gearbox − H·F_mesh,                 J = J_m + J_g + J_p / G²
    m_t·v̇_t = F_mesh − F_guide − F_load,                     L·i̇ = u − R·i − K_e·ω_m

θ_m, ω_m: motor angle and speed; G: gearbox ratio (motor turns per pinion turn); r_p: pinion
pitch radius; k_m, c_m: the tooth mesh's stiffness and damping (gearbox torsion and rack
compliance lumped into it, as one spring between the pinion's pitch line and the table);
F_gearbox: the gearbox and pinion-bearing friction, a friction site at the motor shaft stored as
force at the pitch line (torque ÷ H, the convention of the ball screw's shaft sites).  One
controller axis (``[controller]``), position from the table's grating, speed from the motor.

The parameters live in the drive file's ``[rack_pinion]`` section (:class:`RackPinion`, with
``[rack_pinion.motor]`` and ``[rack_pinion.gearbox_friction]``); the table and its guide
friction are the file's ``[table]`` and ``[friction.guide]``.
"""

from __future__ import annotations

from dataclasses import dataclass

from ... import registry
from ...parameters import Component, DriveParameters, ParameterError, SiteParameters
from ...parameters.validation import quantity
from ..codegen import Builder
from ..loops import ENC_Q, GRAT_Q, H_AX, V_FEEDBACK, Axis, Channel, axis_parameters
from .base import Body, DriveMotor, Mechanics, Mechanism, Site, register_mechanism
from .shared import Motor


@dataclass(frozen=True)
class RackPinion(Component):
    """Parameters of a rack-and-pinion drive (the ``[rack_pinion]`` section).

    Parameters
    ----------
    motor : Motor
        The servo motor (R-L armature, torque and back-EMF constants, rotor inertia).
    gearbox_friction : SiteParameters
        Friction of the gearbox and pinion bearings, as force at the pinion's pitch line
        [N] (torque ÷ H) against its speed [m/s]; any friction law.
    gear_ratio : float
        Gearbox ratio G, motor turns per pinion turn [-].
    pinion_radius : float
        Pitch radius r_p of the pinion [m].
    mesh_stiffness : float
        Stiffness k_m of the tooth mesh between pinion and rack, gearbox torsion and rack
        compliance lumped in [N/m].
    mesh_damping : float
        Damping c_m of the mesh [N s/m].
    gearbox_inertia : float, default 0
        Inertia of the gearbox at its input (motor) shaft [kg m^2].
    pinion_inertia : float, default 0
        Inertia of the pinion at its own shaft [kg m^2].
    """

    motor: Motor
    gearbox_friction: SiteParameters
    gear_ratio: float = quantity("-", low=1, high=1000, low_inclusive=True,
                                 hint="motor turns per pinion turn (1: direct drive)")
    pinion_radius: float = quantity("m", low=1e-3, high=1.0, hint="30 mm = 0.03 m")
    mesh_stiffness: float = quantity("N/m", low=1e4, high=1e11, hint="1 N/µm = 1e6 N/m")
    mesh_damping: float = quantity("N s/m", low=0, high=1e8, low_inclusive=True)
    gearbox_inertia: float = quantity("kg m^2", low=0, high=10, low_inclusive=True,
                                      default=0.0)
    pinion_inertia: float = quantity("kg m^2", low=0, high=10, low_inclusive=True,
                                     default=0.0)
    _label = "rack_pinion"

    @property
    def transmission_ratio(self) -> float:
        """H = r_p / G: table travel per motor radian [m/rad]."""
        return self.pinion_radius / self.gear_ratio


registry.register(registry.SECTIONS, "rack_pinion", RackPinion)


@register_mechanism
class RackPinionDrive(Mechanism):
    """Rack-and-pinion drive (see the module docstring for its equations).

    Parameters
    ----------
    params : DriveParameters
        The parameter set (SI); needs its ``[rack_pinion]`` section.
    drive : {"rack-pinion"}
        The drive name.
    table_position : float
        Table position [m] (no stiffness depends on it here).
    nut_hold : str
        Unused (the drive has no nut).
    """

    drives = ("rack-pinion",)
    example_preset = "rack-pinion-example"
    single_motor = ("motor.torque_constant", "motor_torque")
    drive_motors = (DriveMotor("motor", "motor_angle", "motor"),)  # no torque ripple modelled
    part_name = "rack and pinion"
    own_sections = ("rack_pinion",)
    published = False  # a textbook topology, not one publication's model

    @classmethod
    def check(cls, params: DriveParameters, drive: str, table_position: float) -> None:
        """Parameters
        ----------
        params : DriveParameters
            The parameter set [SI].
        drive : str
            The drive name.
        table_position : float
            Table position at the start [m].

        Raises
        ------
        ParameterError
            When the parameter set has no ``[rack_pinion]`` section.
        """
        if params.section("rack_pinion") is None:
            raise ParameterError("rack_pinion", f"no such section in {params.name}",
                                 "the rack-pinion drive needs a [rack_pinion] section "
                                 "(e.g. --preset rack-pinion-example)")

    @property
    def section(self) -> RackPinion:
        """The parameter set's ``[rack_pinion]`` section (:class:`RackPinion`)."""
        rp = self.params.section("rack_pinion")
        assert isinstance(rp, RackPinion)
        return rp

    def declare(self, b: Builder) -> None:
        H = self.section.transmission_ratio
        b.state("motor_angle", "rad", "motor shaft angle θ_m", "angle", H)
        b.state("motor_speed", "rad/s", "motor speed", "rotary_speed", H)
        b.state("table_position", "m", "table displacement from its start x_t", "position")
        b.state("table_speed", "m/s", "table speed", "speed")

    def parameters(self, b: Builder) -> None:
        rp = self.section
        b.param("rack_pinion.H", rp.transmission_ratio)
        b.param("rack_pinion.J", rp.motor.inertia + rp.gearbox_inertia
                + rp.pinion_inertia / rp.gear_ratio**2)
        b.param("rack_pinion.mesh_stiffness", rp.mesh_stiffness)
        b.param("rack_pinion.mesh_damping", rp.mesh_damping)
        b.param("table.mass", self.params.table.mass)
        for name in ("torque_constant", "back_emf_constant", "inductance", "resistance"):
            b.param(f"motor.{name}", getattr(rp.motor, name))

    def motors(self, b: Builder) -> None:
        b.state("motor_current", "A", "motor current", "current")

    def sites(self, b: Builder) -> list[Site]:
        H = b.p("rack_pinion.H")
        return [Site("gearbox", "rack_pinion.gearbox_friction", f"{H} * {{w_m}}",
                     (("motor", H),), rotary=True),
                Site("guide", "guide", "{v_t}", (("table", "1.0"),))]

    def axes(self, b: Builder) -> tuple[list[Axis], list[Channel]]:
        o = axis_parameters(b, "motor", self.params.controller, self.section.transmission_ratio,
                            speed_mode=False)
        Hp = f"P[{o + H_AX}]"
        fb = f"int(P[{o + V_FEEDBACK}]) == 1"
        channels = [
            Channel("motor_angle", b.y("motor_angle"), b.y("motor_speed"), f"P[{o + ENC_Q}]"),
            Channel("table", b.y("table_position"), b.y("table_speed"), f"P[{o + GRAT_Q}]"),
        ]
        motor = Axis(name="motor", param_offset=o, reference="{ref_x}", feedforward="{ref_v}",
                     position="{table_position}", position_q="q_table",
                     speed=f"({{table_speed}} / {Hp} if {fb} else {{motor_speed}})",
                     speed_q=f"(s_table / {Hp} if {fb} else s_motor_angle)",
                     current_state="{motor_current}")
        return [motor], channels

    def steady_motion(self, table_speed: float, nut_speed: float
                      ) -> dict[str, tuple[str, float]]:
        """Motor at v_t/H, table at v_t.

        Parameters
        ----------
        table_speed : float
            Commanded table speed [m/s].
        nut_speed : float
            Unused (no nut) [m/s].

        Returns
        -------
        dict
            Angle/position state → (rate state, steady rate [rad/s or m/s]).
        """
        return {"motor_angle": ("motor_speed", table_speed / self.section.transmission_ratio),
                "table_position": ("table_speed", table_speed)}

    def site_masses(self) -> dict[str, float]:
        """gearbox: the motor-side inertia J = J_m + J_g + J_p/G² as J/H²; guide: the table.

        Returns
        -------
        dict
            Site parameters key → effective mass [kg].
        """
        self.check(self.params, self.drive, self.table_position)
        rp = self.section
        inertia = rp.motor.inertia + rp.gearbox_inertia + rp.pinion_inertia / rp.gear_ratio**2
        return {"rack_pinion.gearbox_friction": inertia / rp.transmission_ratio**2,
                "guide": self.params.table.mass}

    def emit(self, b: Builder, m: Mechanics) -> None:
        H = b.p("rack_pinion.H")
        b.emit("{w_m} = {motor_speed}")
        b.emit("{v_t} = {table_speed}")
        for ln in m.always:
            b.emit(ln)
        b.emit(f"{{f_d}} = ({b.p('rack_pinion.mesh_stiffness')} * ({H} * {{motor_angle}} - "
               f"{{table_position}}) + {b.p('rack_pinion.mesh_damping')} * "
               f"({H} * {{w_m}} - {{v_t}}))")
        motor = Body(drive=[] if m.torque_off else
                     [f"{b.p('motor.torque_constant')} * {{motor_current}}"],
                     external=list(m.forces.get("motor", [])), reaction=[f"- {H} * {{f_d}}"])
        table = Body(drive=["{f_d}"], external=list(m.forces.get("table", [])))
        if m.load is not None:
            table.external.append(f"- {m.load}")
        b.emit("{der(motor_angle)} = {w_m}")
        b.emit(f"{{der(motor_speed)}} = ({motor.expression()}) / {b.p('rack_pinion.J')}")
        b.emit("{der(table_position)} = {v_t}")
        b.emit(f"{{der(table_speed)}} = ({table.expression()}) / {b.p('table.mass')}")
        if m.torque_off:
            b.emit("{der(motor_current)} = 0.0")
        else:
            b.emit(f"{{der(motor_current)}} = ({{motor_voltage}} - "
                   f"{b.p('motor.resistance')} * {{motor_current}} - "
                   f"{b.p('motor.back_emf_constant')} * {{w_m}}) / {b.p('motor.inductance')}")
