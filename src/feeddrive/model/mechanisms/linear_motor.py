"""A direct-drive table: a linear motor's forcer on the table, guide friction only.

    (m_t + m_f) v̇_t = K_f i − F_guide − F_load,     L i̇ = u − R i − K_e v_t

One controller axis ("motor") with the table's grating as position and speed feedback; its
gains act on m/s (transmission 1).  Needs the ``[linear_motor]`` parameter section.
"""

from __future__ import annotations

from dataclasses import dataclass

from ... import registry
from ...parameters import Component, DriveParameters, ParameterError
from ...parameters.validation import quantity
from ..codegen import Builder
from ..loops import GRAT_Q, Axis, Channel, axis_parameters
from .base import Body, DriveMotor, Mechanics, Mechanism, Site, register_mechanism


@dataclass(frozen=True)
class LinearMotor(Component):
    """Linear motor of a direct-drive table: force constant, back-EMF, R-L winding, forcer.

    Parameters
    ----------
    force_constant : float
        K_f [N/A].
    back_emf_constant : float
        K_e [V s/m].
    inductance : float
        Winding inductance L [H].
    resistance : float
        Winding resistance R [ohm].
    forcer_mass : float
        Mass of the forcer, moving with the table [kg].
    """

    force_constant: float = quantity("N/A", low=1e-2, high=1e4)
    back_emf_constant: float = quantity("V s/m", low=1e-2, high=1e4)
    inductance: float = quantity("H", low=1e-6, high=1.0, hint="20 mH = 0.02 H")
    resistance: float = quantity("ohm", low=1e-3, high=1e3)
    forcer_mass: float = quantity("kg", low=0, high=1e4, low_inclusive=True)
    _label = "linear_motor"


registry.register(registry.SECTIONS, "linear_motor", LinearMotor)


@register_mechanism
class LinearMotorDrive(Mechanism):
    """A direct-drive table: a linear motor's forcer on the table, guide friction only.

    (m_t + m_f)·dv_t/dt = K_f·i − F_guide − F_load,  L·di/dt = u − R·i − K_e·v_t.

    Parameters
    ----------
    params : DriveParameters
        The parameter set (SI); needs its ``linear_motor`` section.
    drive : {"linear-motor"}
        The drive name.
    table_position : float
        Table position [m] (no stiffness depends on it here).
    nut_hold : str
        Unused (the drive has no nut).
    """
    drives = ("linear-motor",)
    example_preset = "linear-motor-example"
    single_motor = ("motor.force_constant", "motor_force")
    drive_motors = (DriveMotor("motor", "", "table"),)  # no torque ripple modelled
    part_name = "linear motor"
    own_sections = ("linear_motor",)
    published = False  # a generic direct drive, not a published model

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
            When the parameter set has no ``[linear_motor]`` section.
        """
        if params.linear_motor is None:
            raise ParameterError("linear_motor", f"no such section in {params.name}",
                                 "the linear-motor drive needs a [linear_motor] section "
                                 "(e.g. --preset linear-motor-example)")

    def declare(self, b: Builder) -> None:
        b.state("table_position", "m", "table displacement from its start x_t", "position")
        b.state("table_speed", "m/s", "table speed", "speed")

    def parameters(self, b: Builder) -> None:
        lm = self.params.linear_motor
        assert lm is not None
        b.param("table.mass", self.params.table.mass + lm.forcer_mass)
        b.param("motor.force_constant", lm.force_constant)
        b.param("motor.back_emf_constant", lm.back_emf_constant)
        b.param("motor.inductance", lm.inductance)
        b.param("motor.resistance", lm.resistance)

    def motors(self, b: Builder) -> None:
        b.state("motor_current", "A", "linear motor current", "current")

    def sites(self, b: Builder) -> list[Site]:
        return [Site("guide", "guide", "{v_t}", (("table", "1.0"),))]

    def axes(self, b: Builder) -> tuple[list[Axis], list[Channel]]:
        o = axis_parameters(b, "motor", self.params.controller, 1.0, speed_mode=False)
        channels = [Channel("table", b.y("table_position"), b.y("table_speed"),
                            f"P[{o + GRAT_Q}]")]
        motor = Axis(name="motor", param_offset=o, reference="{ref_x}", feedforward="{ref_v}",
                     position="{table_position}", position_q="q_table",
                     speed="{table_speed}", speed_q="s_table",
                     current_state="{motor_current}", speed_unit="m/s")
        return [motor], channels

    def compensation(self, b: Builder
                     ) -> tuple[list[tuple[str, str, str]], str]:
        return ([("guide", "{ref_v}", "{table_speed}")],
                f"1.0 / {b.p('motor.force_constant')}")

    def site_masses(self) -> dict[str, float]:
        """guide: the table with the forcer, m_t + m_f.

        Returns
        -------
        dict
            Site parameters key → effective mass [kg].
        """
        self.check(self.params, self.drive, self.table_position)
        lm = self.params.linear_motor
        assert lm is not None
        return {"guide": self.params.table.mass + lm.forcer_mass}

    def emit(self, b: Builder, m: Mechanics) -> None:
        b.emit("{v_t} = {table_speed}")
        for ln in m.always:
            b.emit(ln)
        drive = "0.0" if m.torque_off else f"{b.p('motor.force_constant')} * {{motor_current}}"
        b.emit(f"{{f_d}} = {drive}")
        table = Body(drive=["{f_d}"], external=list(m.forces.get("table", [])))
        if m.load is not None:
            table.external.append(f"- {m.load}")
        b.emit("{der(table_position)} = {v_t}")
        b.emit(f"{{der(table_speed)}} = ({table.expression()}) / {b.p('table.mass')}")
        if m.torque_off:
            b.emit("{der(motor_current)} = 0.0")
        else:
            b.emit(f"{{der(motor_current)}} = ({{motor_voltage}} - "
                   f"{b.p('motor.resistance')} * {{motor_current}} - "
                   f"{b.p('motor.back_emf_constant')} * {{v_t}}) / {b.p('motor.inductance')}")
