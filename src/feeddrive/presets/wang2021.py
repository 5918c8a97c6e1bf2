"""The Wang2021 parameter set: Wang, Feng, Yang, Jin, Mech. Sci. 12, 791–800 (2021).

Every value cites its table.  Values the paper does not give are listed in ``ASSUMPTIONS``
(the one place where they are decided) and marked ``assumption:<id>`` in ``SOURCES``.

Two presets are built here:

* ``wang2021-literal`` – Table 2 read literally in SI: a motor-side velocity loop of
  45 A s/rad, no axial damping, continuous control.  It does not creep at the paper's speeds
  (see docs/model-reading.md).
* ``wang2021`` – the reading shipped as default; the controller reading and the fitted values
  are documented in ``ASSUMPTIONS`` and in the report.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..model.mechanisms.ball_screw_stiffness import equivalent_stiffness
from ..parameters.components import (
    BallScrew,
    Controller,
    Coupling,
    DriveParameters,
    FrictionBranch,
    FrictionSites,
    LuGreParameters,
    Motor,
    StiffnessModel,
    Table,
)

CITATION = (
    "Z. Wang, X. Feng, H. Yang, H. Jin, 'Research on low-speed characteristics of differential "
    "double-drive feed system', Mechanical Sciences 12, 791-800 (2021), "
    "doi:10.5194/ms-12-791-2021"
)


@dataclass(frozen=True)
class Assumption:
    """A value or choice the paper does not give (or gives wrongly), and why we chose it."""

    id: str
    fields: tuple[str, ...]
    value: str
    rationale: str
    fitted: bool = False


_STEEL_DENSITY = 7850.0  # kg/m^3, for the screw shaft's own inertia
_SCREW_DIAMETER = 0.016
_SCREW_LENGTH = 0.8
_SCREW_SHAFT_INERTIA = math.pi * _STEEL_DENSITY * _SCREW_DIAMETER**4 * _SCREW_LENGTH / 32.0

ASSUMPTIONS: tuple[Assumption, ...] = (
    Assumption(
        "J-typo", ("screw_motor.inertia", "hollow_motor.inertia"), "1.38e-3 kg m^2",
        "Table 2 prints 1.38×10³ kg m²; a servo motor with K_t = 0.55 N m/A has about "
        "1.38×10⁻³ kg m². Read as a typo.",
    ),
    Assumption(
        "E", ("screw.youngs_modulus",), "206 GPa",
        "Not stated. 206 GPa reproduces Table 3's k_sa row with Eq. (4), d = 16 mm, "
        "l = 800 mm, a = x_t to 0.01 %.",
    ),
    Assumption(
        "eta", ("screw.efficiency",), "0.95",
        "Not stated. η enters only Eq. (5)'s torsion term (H²/η·1/K_t1 ≈ 3e-11 m/N, "
        "0.1 % of the chain) and is otherwise absorbed in the identified friction.",
    ),
    Assumption(
        "screw-inertia", ("screw.shaft_inertia",), f"{_SCREW_SHAFT_INERTIA:.3e} kg m^2",
        "Not stated. Solid steel shaft (ρ = 7850 kg/m³), d = 16 mm, l = 800 mm; the "
        "coupling's inertia is neglected.",
    ),
    Assumption(
        "nut-inertia", ("screw.nut_inertia",), "1.0e-4 kg m^2",
        "Not stated. Nut plus connecting flange of a 16-mm screw, order-of-magnitude "
        "estimate; small against the hollow motor's 1.38e-3 kg m².",
    ),
    Assumption(
        "Keq", ("stiffness.equivalent_stiffness",), "0 (chain, position dependent)",
        "Eqs. (2)–(5) with Table 2 give K_eq ≈ 3.23e7 N/m at mid-screw, not the 2.16e7 N/m "
        "the text states; no tested reading reproduces it exactly (closest: fixed–free screw "
        "over the full span, 2.20e7 N/m). The chain is used so that Table 3's position "
        "study follows from k_sa; set stiffness.equivalent_stiffness = 2.16e7 to use the "
        "paper's number.",
    ),
    Assumption(
        "axial-damping", ("stiffness.axial_damping",), "0 (literal)",
        "Not stated. The paper's model has no structural damping on the table spring.",
    ),
    Assumption(
        "cascade", ("controller.*",), "P position → P velocity → P current, motor encoder",
        "Fig. 5 is an image. Literal reading (wang2021-literal): ω_cmd = K_pp·e/H (+ velocity "
        "feed-forward), i_cmd = K_vp·(ω_cmd − ω), u = K_ip·(i_cmd − i); K_v unused; "
        "continuous loops.",
    ),
    Assumption(
        "velocity-basis", ("controller.velocity_gain_basis",), "table (wang2021 only)",
        "wang2021 reads K_vp = 45 as A per m/s of table-equivalent speed (the paper states "
        "every speed at the table, in mm/s). Literally (A s/rad at the motor) the loop damps "
        "with ~4e7 N s/m, 10³× the steepest friction slope, and nothing can creep.",
    ),
    Assumption(
        "current-PI", ("controller.current_integral_gain",), "K_ii = K_ip·R/L (wang2021 only)",
        "A P current loop with K_ip = 2 V/A passes back-EMF damping K_t·K_emf/(R + K_ip)/H² "
        "≈ 3.5e4 N s/m to the table, more than any friction slope: no creep at any speed. "
        "Servo drives run PI current loops; the integral is set by the textbook pole-zero "
        "cancellation K_ii/K_ip = R/L.",
    ),
    Assumption(
        "axial-damping-shipped", ("stiffness.axial_damping",), "ζ = 5 % (wang2021 only)",
        "Without damping the ~200-Hz table mode self-excites through the guide's LuGre σ1 "
        "(the guide fails the passivity test). wang2021 gives it 5 % structural damping, "
        "c_ax = 2ζ·sqrt(K_eq·m_t) at mid-screw ≈ 2.5e3 N s/m.",
    ),
    Assumption(
        "hollow-speed-loop", ("controller.nut_loop",), "speed (wang2021 only)",
        "Sect. 2.1 closes the table position on the screw motor only; the hollow motor runs "
        "at the commanded nut speed. wang2021 gives it a speed loop without a position loop. "
        "With a position loop of its own as well, the two integrating loops fight through the "
        "table and the DDFS oscillates below 2.05 mm/s (worse than the CDFS); see "
        "docs/model-reading.md.",
    ),
    Assumption(
        "velocity-integral", ("controller.velocity_integral_gain",), "fitted",
        "Table 2 gives no velocity-loop integral. wang2021 fits it (feeddrive calibrate) to the "
        "paper's simulated CDFS critical speed at mid-screw, 1.56 mm/s, judged by the "
        "window-independent creep verdict (sustained oscillation at 1.55, smooth at 1.56): "
        "3900.6–3950.1 give that speed, 3925.28 is their geometric mean; it is the only "
        "fitted number.",
        fitted=True,
    ),
)

SOURCES: dict[str, str] = {
    "screw.length": "Wang2021 Table 2",
    "screw.diameter": "Wang2021 Table 2",
    "screw.lead": "Wang2021 Table 2",
    "screw.torsional_stiffness": "Wang2021 Table 2",
    "screw.nut_axial_stiffness": "Wang2021 Table 2",
    "screw.nut_bearing_axial_stiffness": "Wang2021 Table 2",
    "screw.support_bearing_axial_stiffness": "Wang2021 Table 2",
    "screw.youngs_modulus": "assumption:E",
    "screw.efficiency": "assumption:eta",
    "screw.shaft_inertia": "assumption:screw-inertia",
    "screw.nut_inertia": "assumption:nut-inertia",
    "coupling.torsional_stiffness": "Wang2021 Table 2",
    "screw_motor.torque_constant": "Wang2021 Table 2",
    "screw_motor.back_emf_constant": "Wang2021 Table 2",
    "screw_motor.inductance": "Wang2021 Table 2",
    "screw_motor.resistance": "Wang2021 Table 2",
    "screw_motor.inertia": "Wang2021 Table 2 (typo corrected, assumption:J-typo)",
    "table.mass": "Wang2021 Table 2",
    "controller.position_gain": "Wang2021 Table 2 (K_pp)",
    "controller.velocity_gain": "Wang2021 Table 2 (K_vp)",
    "controller.current_gain": "Wang2021 Table 2 (K_ip)",
    "controller.velocity_command_gain": "Wang2021 Table 2 (K_v)",
    "friction.*": "Wang2021 Table 1 (forces = torques / H)",
    "stiffness.*": "assumption:Keq, assumption:axial-damping",
}
for _k in ("torque_constant", "back_emf_constant", "inductance", "resistance", "inertia"):
    SOURCES[f"hollow_motor.{_k}"] = SOURCES[f"screw_motor.{_k}"]


def _branch(fc: float, fs: float, vs: float, s2: float) -> FrictionBranch:
    return FrictionBranch(
        coulomb_force=fc, static_force=fs, stribeck_velocity=vs, viscous_coefficient=s2
    )


def friction_sites() -> FrictionSites:
    """Wang2021 Table 1, negative branch stored as magnitudes."""
    return FrictionSites(
        screw=LuGreParameters(
            positive=_branch(73.4, 96.4, 8.64e-4, 3.14e3),
            negative=_branch(68.5, 94.6, 9.01e-4, 2.76e3),
            bristle_stiffness=3.64e7,
            bristle_damping=5.26e3,
        ),
        nut=LuGreParameters(
            positive=_branch(76.2, 108.4, 9.38e-4, 3.12e3),
            negative=_branch(72.1, 102.3, 9.56e-4, 3.01e3),
            bristle_stiffness=3.61e5,
            bristle_damping=5.76e3,
        ),
        guide=LuGreParameters(
            positive=_branch(14.7, 22.5, 1.45e-3, 61.6),
            negative=_branch(14.3, 22.9, 1.36e-3, 62.3),
            bristle_stiffness=4.38e5,
            bristle_damping=1.86e3,
        ),
    )


def motor() -> Motor:
    """Wang2021 Table 2, the same motor for screw and hollow shaft."""
    return Motor(
        torque_constant=0.55,
        back_emf_constant=0.15,
        inductance=5.9e-3,
        resistance=1.7,
        inertia=1.38e-3,
    )


def ball_screw() -> BallScrew:
    return BallScrew(
        length=_SCREW_LENGTH,
        diameter=_SCREW_DIAMETER,
        lead=5e-3,
        youngs_modulus=206e9,
        torsional_stiffness=61368.0,
        nut_axial_stiffness=2.48e8,
        nut_bearing_axial_stiffness=3.12e8,
        support_bearing_axial_stiffness=1.06e8,
        efficiency=0.95,
        shaft_inertia=_SCREW_SHAFT_INERTIA,
        nut_inertia=1.0e-4,
    )


def literal_controller() -> Controller:
    """Table 2 gains read literally in SI (see ASSUMPTIONS 'cascade')."""
    return Controller(
        position_gain=8.0,
        velocity_gain=45.0,
        current_gain=2.0,
        velocity_command_gain=250.0,
    )


def literal() -> DriveParameters:
    """``wang2021-literal``: Tables 1 and 2 read literally in SI."""
    return DriveParameters(
        name="wang2021-literal",
        description="Wang2021 Tables 1-2 read literally in SI units. " + CITATION,
        screw=ball_screw(),
        coupling=Coupling(torsional_stiffness=2.81e4),
        screw_motor=motor(),
        hollow_motor=motor(),
        table=Table(mass=20.0),
        friction=friction_sites(),
        stiffness=StiffnessModel(),
        controller=literal_controller(),
    )


# The shipped reading (docs/model-reading.md).  Only VELOCITY_INTEGRAL_GAIN is fitted, by
# `feeddrive calibrate` to the paper's simulated CDFS critical speed at mid-screw (1.56 mm/s,
# Sect. 5.2 / Fig. 6); every other number is a prediction.
AXIAL_DAMPING_RATIO = 0.05
# [A/m] on the table-equivalent position error; fitted by `feeddrive calibrate --tolerance
# 0.002` under the window-independent creep verdict (issue 15; 26 evaluations): values
# 3900.6–3950.1 give 1.56 mm/s, this is their geometric mean (was 3872.12 under the 12-s window)
VELOCITY_INTEGRAL_GAIN = 3925.28


def _axial_damping(params: DriveParameters) -> float:
    """c_ax = 2ζ·sqrt(K_eq·m_t) at mid-screw [N s/m]: ζ = 5 % structural damping."""
    k_eq = equivalent_stiffness(params, params.screw.length / 2.0)
    return 2.0 * AXIAL_DAMPING_RATIO * math.sqrt(k_eq * params.table.mass)


def shipped() -> DriveParameters:
    """``wang2021``: the default reading.  See ASSUMPTIONS and docs/model-reading.md."""
    base = literal()
    controller = base.controller.with_values(
        velocity_gain_basis="table",
        current_integral_gain=base.controller.current_gain * base.screw_motor.resistance
        / base.screw_motor.inductance,
        velocity_integral_gain=VELOCITY_INTEGRAL_GAIN,
        nut_loop="speed",
    )
    stiffness = base.stiffness.with_values(axial_damping=_axial_damping(base))
    return DriveParameters(
        name="wang2021",
        description="Wang2021 with the default reading of the unstated model details "
        "(docs/model-reading.md). " + CITATION,
        screw=base.screw,
        coupling=base.coupling,
        screw_motor=base.screw_motor,
        hollow_motor=base.hollow_motor,
        table=base.table,
        friction=base.friction,
        stiffness=stiffness,
        controller=controller,
    )


# ---- readings beyond the paper's model (issue 14), each a named preset

RIPPLE_AMPLITUDE = 0.0135  # [N m], fitted: DDFS 0.50 mm/s at v_n = 16 mm/s (50 % threshold)
RIPPLE_ORDER = 6.0  # per revolution

RIPPLE_ASSUMPTIONS: tuple[Assumption, ...] = (
    Assumption(
        "torque-ripple", ("disturbances.screw_motor_ripple", "disturbances.hollow_motor_ripple"),
        f"{RIPPLE_AMPLITUDE} N m at {RIPPLE_ORDER:g} per revolution, both motors (fitted)",
        "Not in Wang2021's model; the authors' companion paper on the DDFS (Mech. Sci. 11, 163, "
        "2020) studies the motors' torque harmonics.  0.0135 N m is about 0.6 % of the rated "
        "torque of a servo motor with K_t = 0.55 N m/A (≈ 2.4 N m), the size cogging and "
        "ripple have; 6 per revolution is the usual lowest cogging order.  The amplitude is "
        "fitted to the DDFS critical speed 0.50 mm/s at v_n = 16 mm/s, where the critical "
        "speed is defined by a 50 % ripple threshold (feeddrive.analysis.forced).",
        fitted=True,
    ),
)


def ripple() -> DriveParameters:
    """``wang2021-ripple``: the shipped reading plus motor torque ripple on both motors."""
    from ..parameters.components import Disturbances, TorqueRipple

    r = TorqueRipple((RIPPLE_ORDER,), (RIPPLE_AMPLITUDE,), (0.0,))
    base = shipped()
    return base.with_values(
        name="wang2021-ripple",
        description="wang2021 plus motor torque ripple (0.0135 N m, 6 per revolution, both "
        "motors; fitted to the DDFS critical speed by the 50 % ripple threshold). " + CITATION,
        disturbances=Disturbances(screw_motor_ripple=r, hollow_motor_ripple=r))


DRIVE_ASSUMPTIONS: tuple[Assumption, ...] = (
    Assumption(
        "drive-limits", ("controller.current_limit", "controller.voltage_limit"),
        "17 A, 300 V",
        "Table 2's motor (K_t = 0.55 N m/A, R = 1.7 Ω, L = 5.9 mH) is the size of a 750-W "
        "AC servo motor (rated ≈ 2.4 N m, peak ≈ 3× rated ≈ 7–8 N m, i.e. ≈ 14–17 A at this "
        "K_t); 300 V is the DC bus of a drive on a 230-V single-phase supply.  Typical "
        "catalogue orders of magnitude, not one product's data sheet.",
    ),
    Assumption(
        "drive-sampling", ("controller.current_period", "controller.velocity_period",
                           "controller.position_period"),
        "125 µs / 250 µs / 500 µs",
        "Current loop at 8 kHz, velocity loop at 4 kHz, position loop at 2 kHz: the rates of "
        "current servo drives (zero-order hold in the model).",
    ),
    Assumption(
        "drive-feedback", ("controller.encoder_counts", "controller.grating_resolution"),
        "2^20 counts/rev, 0.05 µm",
        "A 20-bit absolute motor encoder and a 0.05-µm linear-scale resolution, common on "
        "machine-tool axes.",
    ),
)


def drive() -> DriveParameters:
    """``wang2021-drive``: the shipped reading with a real drive's limits, sampled loops and
    quantised feedback (DRIVE_ASSUMPTIONS)."""
    base = shipped()
    controller = base.controller.with_values(
        current_limit=17.0, voltage_limit=300.0, current_period=1.25e-4,
        velocity_period=2.5e-4, position_period=5e-4, encoder_counts=float(2**20),
        grating_resolution=5e-8)
    return base.with_values(
        name="wang2021-drive",
        description="wang2021 with a real drive's current/voltage limits, 8/4/2-kHz sampled "
        "loops and quantised encoder and scale (see DRIVE_ASSUMPTIONS). " + CITATION,
        controller=controller)


PRESETS = {"wang2021": shipped, "wang2021-literal": literal, "wang2021-ripple": ripple,
           "wang2021-drive": drive}
