"""The FMU's variables from the model's declarations, as ``modelDescription.xml`` and C tables.

Every state, auxiliary signal and parameter of the assembled model becomes a variable with
its name, unit and description (states and signals carry theirs in the model; a parameter's
unit and meaning follow from its slot name, :func:`parameter_info`).  Inputs are named as
the linear model names its reference and load inputs; outputs are the table's position and
speed, the motors' angles, speeds, currents and torques, the friction force of every site
and the following error.  A value reference is the variable's index in one table; the C
wrapper reads ``VR_KIND``/``VR_A``/``VR_B`` to find the value (``wrapper.c``).
"""

from __future__ import annotations

import math
import re
import uuid
from dataclasses import dataclass
from xml.sax.saxutils import escape, quoteattr

import numpy as np

from ..engine import options
from ..model.friction import friction_law
from ..model.loops import AXIS_PARAMS
from ..model.slot_ranges import FINITE, SlotRange, controller_range, slot_range
from ..model.slots import slot_unit
from ..parameters.components import unit_of
from ..units import DISPLAY_UNITS
from .model import FmuModel

# value-reference kinds (wrapper.c)
(K_TIME, K_STATE, K_DER, K_AUX, K_PARAM, K_INPUT, K_SETTING, K_PRODUCT, K_ERROR, K_BOOLEAN,
 K_INTEGER, K_COUNTER, K_EVALUATIONS) = range(13)
# value types (wrapper.c VR_TYPE): FMI 2 Real/Boolean/Integer, FMI 3 Float64/Boolean/Int64
T_REAL, T_BOOLEAN, T_INTEGER = range(3)
_TYPES = {"Real": T_REAL, "Boolean": T_BOOLEAN, "Integer": T_INTEGER}

# input slots u[...] of the wrapper
INPUTS = ("table_position_reference", "table_speed_reference", "nut_position_reference",
          "nut_speed_reference", "load_force")
IN_XT, IN_VT, IN_XN, IN_VN, IN_LOAD = range(5)
INPUT_INFO = {
    "table_position_reference": ("m", "commanded table position; read when "
                                 "integrate_speed_reference is false"),
    "table_speed_reference": ("m/s", "commanded table speed (also the velocity "
                              "feed-forward), held over a communication step"),
    "nut_position_reference": ("m", "commanded nut position (linear: H·θ_n); read when "
                               "integrate_speed_reference is false"),
    "nut_speed_reference": ("m/s", "commanded nut speed (linear: H·ω_n, also the hollow "
                            "motor's feed-forward), held over a communication step"),
    "load_force": ("N", "load force on the table, against positive motion, from "
                   "disturbances.load_start on"),
}

#: the default bound on integrator steps and on sample instants in one communication step
#: (``solver.max_steps_per_call``): ≈ 1.2 s of the 8-kHz sampled drive (wang2021-drive,
#: ~8000 steps per second) or 2–5 s of the continuous ones in one step; a host whose step
#: would take longer gets Error naming the setting instead of a frozen call
MAX_STEPS_PER_CALL = 10_000
#: the solver settings' range: a tolerance within the range the command line and the API
#: take (``MIN_RELATIVE``, ``MIN_ABSOLUTE``, ``MAX_RTOL``, ``MAX_ABSOLUTE`` of
#: :mod:`feeddrive.engine.options`), the step cap below (``_MAX_STEP``)


def _tolerance_range(name: str) -> SlotRange:
    """The range of a tolerance setting: what ``SolverOptions`` takes for ``name``
    (``options.MIN_RELATIVE`` … ``MAX_RTOL``, ``MIN_ABSOLUTE`` … ``MAX_ABSOLUTE``)."""
    low, high = ((options.MIN_RELATIVE, options.MAX_RTOL) if name == "rtol" else
                 (options.MIN_ABSOLUTE[name], options.MAX_ABSOLUTE[name]))
    return SlotRange(low, high,
                     unit={"rtol": "", "position_tolerance": "m",
                           "speed_tolerance": "m/s"}.get(name, "A"))


_STEP_COUNT = SlotRange(1.0, 2.0**31 - 1.0, integer=True)  # an FMI 2 Integer
#: the integrator's step cap: at least a nanosecond (1e-300 s was taken, and every
#: communication step then failed, or with the largest step limit ran for most of an hour:
#: an outside check, 2026-12-07)
_MAX_STEP = SlotRange(1e-9, math.inf, unit="s")

# wrapper settings s[...]: (name, unit, description, start or None: from the parameters,
# range)
SETTINGS: tuple[tuple[str, str, str, float | None, SlotRange | None], ...] = (
    ("solver.relative_tolerance", "1", "relative error target of the embedded DOPRI5 "
     "(speeds and currents)", 1e-6, _tolerance_range("rtol")),
    ("solver.position_tolerance", "m", "absolute error target on positions (angles: ÷ H)",
     1e-10, _tolerance_range("position_tolerance")),
    ("solver.speed_tolerance", "m/s", "absolute error target on speeds (angular: ÷ H)", 1e-8,
     _tolerance_range("speed_tolerance")),
    ("solver.current_tolerance", "A", "absolute error target on currents", 1e-6,
     _tolerance_range("current_tolerance")),
    ("solver.max_step", "s", "largest integrator step", 1e-3, _MAX_STEP),
    ("controller.position_period", "s", "position-loop sample period (0: continuous)", None,
     controller_range("position_period")),
    ("controller.velocity_period", "s", "velocity-loop sample period (0: continuous)", None,
     controller_range("velocity_period")),
    ("controller.current_period", "s", "current-loop sample period (0: continuous)", None,
     controller_range("current_period")),
    ("integrate_speed_reference", "", "true: the commanded positions are the integrals of the "
     "speed-reference inputs from the start (the position inputs give their start values); "
     "false: the position-reference inputs are the commanded positions, advanced within a "
     "step by the speed references", 1.0, None),
    ("solver.max_steps_per_call", "", "most integrator steps (accepted and rejected) and most "
     f"sample instants in one communication step (default {MAX_STEPS_PER_CALL}); a step "
     "that needs more returns Error naming this setting (co-simulation)",
     float(MAX_STEPS_PER_CALL), _STEP_COUNT),
)
S_INDEX = {name: i for i, (name, *_rest) in enumerate(SETTINGS)}
_PERIODS = ("controller.position_period", "controller.velocity_period",
            "controller.current_period")


def fmu_settings(fm: FmuModel) -> tuple[tuple[str, str, str, float | None, SlotRange | None],
                                        ...]:
    """The wrapper's settings ``s[...]`` of ``fm``: :data:`SETTINGS` for one drive; on a
    machine each loop-period setting once per axis, named ``<axis>.controller.<loop>_period``.

    Parameters
    ----------
    fm : FmuModel
        The assembled model.

    Returns
    -------
    tuple
        (name, unit, description, start or None: from the parameters, range) per setting.
    """
    if not fm.blocks:
        return SETTINGS
    out: list[tuple[str, str, str, float | None, SlotRange | None]] = []
    for entry in SETTINGS:
        if entry[0] == _PERIODS[0]:
            for block in fm.blocks:
                out += [(f"{block.prefix}{name}", unit, f"{block.prefix[:-1]} axis: {text}",
                         start, bounds)
                        for name, unit, text, start, bounds in SETTINGS
                        if name in _PERIODS]
        elif entry[0] not in _PERIODS:
            out.append(entry)
    return tuple(out)


def period_start(fm: FmuModel, name: str) -> float:
    """The start value of the loop-period setting ``name`` [s] (the exported parameters').

    Parameters
    ----------
    fm : FmuModel
        The assembled model.
    name : str
        The setting (``controller.position_period``, or ``x.controller.position_period``).

    Returns
    -------
    float
        The period [s] (0: continuous).
    """
    return fm.periods[name] if name in fm.periods else fm.periods[name.split(".")[1]]
#: the embedded integrator's counters (co-simulation): name, memory slot
#: (feeddrive.fmu.solver MEM_*), description
COUNTERS = (("solver.steps", "MEM_STEPS", "integrator steps taken since initialisation "
             "(accepted and rejected)"),
            ("solver.rejected_steps", "MEM_REJECTED", "rejected integrator steps since "
             "initialisation"),
            ("solver.rhs_evaluations", "MEM_RHS", "right-hand-side evaluations of the "
             "embedded integrator since initialisation"))
#: what a model-exchange FMU evaluated for its importer (wrapper.c ``m->evaluations``): name,
#: description
EVALUATIONS = (("evaluations.derivatives", "evaluations of the model's right-hand side "
                "(derivatives and signals) since instantiation or reset"),
               ("evaluations.tangents", "evaluations of the model's tangent (one directional "
                "derivative of every derivative and signal) since instantiation or reset"))

_FIXED_PARAMETERS = {  # enumerations and switches: settable before initialisation only
    "stiffness.support", "nut.active", "kv_place", "v_basis", "v_feedback", "ff",
    "speed_mode"}
# (the slots of the model's clocks are fixed too: the sample schedule is set at
# initialisation, wrapper.c fmu_sampling)
# "inputs.": the linearisation's zero-valued reference and load slots (feeddrive.analysis.linear);
# the FMU's own inputs carry those signals
_HIDDEN = ("profile[", "disturbances.load_force", "disturbances.load_step",
           "disturbances.load_offset", "disturbances.load_points", "inputs.",
           # the loops' periods: settings of their own (SETTINGS), written into these slots
           "controller.position_period", "controller.velocity_period",
           "controller.current_period")

#: descriptions of the model's own slots (the unit is the model's: feeddrive.model.slots)
_DESCRIPTIONS = {
    "screw.H": "lead per radian H (transmission ratio)",
    "screw.J": "screw motor and shaft inertia",
    "nut.J": "hollow motor and nut inertia",
    "table.mass": "table (and forcer) mass",
    "stiffness.axial_damping": "screw–nut–table axial damping c_ax",
    "stiffness.k_fixed": "fixed equivalent stiffness K_eq (0: from the chain)",
    "stiffness.c0": "axial compliance of bearings, nut and (torsion) coupling",
    "stiffness.ea": "screw axial rigidity E·A",
    "stiffness.length": "screw length between supports",
    "stiffness.support": "screw support: 0 fixed–fixed, 1 fixed–free",
    "stiffness.x0": "nut position a at the start (distance from the motor support)",
    "nut.active": "1: the hollow motor and nut are live; 0: held",
    "screw_motor.torque_constant": "screw motor torque constant K_t",
    "screw_motor.back_emf_constant": "screw motor back-EMF constant K_e",
    "screw_motor.inductance": "screw motor armature inductance L",
    "screw_motor.resistance": "screw motor armature resistance R",
    "nut_motor.torque_constant": "hollow motor torque constant K_t",
    "nut_motor.back_emf_constant": "hollow motor back-EMF constant K_e",
    "nut_motor.inductance": "hollow motor armature inductance L",
    "nut_motor.resistance": "hollow motor armature resistance R",
    "motor.force_constant": "linear motor force constant K_f",
    "motor.back_emf_constant": "linear motor back-EMF constant K_e",
    "motor.inductance": "linear motor inductance L",
    "motor.resistance": "linear motor resistance R",
    "disturbances.load_start": "time from which the load_force input acts",
    "compensation.observer_gain": "friction observer gain (compensation)",
}


@dataclass(frozen=True)
class Variable:
    """One FMU variable: where its value lives (kind, a, b) and how it is declared.

    Parameters
    ----------
    name : str
        The variable's FMU name.
    kind : int
        Where its value lives: ``K_TIME``, ``K_STATE``, ``K_DER``, ``K_AUX``, ``K_PARAM``,
        ``K_INPUT``, ``K_SETTING``, ``K_PRODUCT``, ``K_ERROR`` or ``K_BOOLEAN``.
    a : int
        First index of its location (e.g. the state or parameter index).
    b : int
        Second index (e.g. the factor of a product variable); 0 when unused.
    causality : str
        FMI causality (``"parameter"``, ``"input"``, ``"output"``, ``"local"``, …).
    variability : str
        FMI variability (``"fixed"``, ``"tunable"``, ``"continuous"``, …).
    initial : str or None
        FMI ``initial`` attribute, if declared.
    start : float or None
        Start value [its unit], if declared.
    unit : str
        Its unit.
    description : str
        Its description.
    type : str, default "Real"
        ``"Real"``, ``"Boolean"`` or ``"Integer"`` (FMI 3: ``Float64``, ``Boolean``,
        ``Int64``).
    derivative : int, optional
        Value reference of the state a ``der(…)`` variable belongs to.
    range : SlotRange, optional
        The values it may be set to (declared as ``min``/``max``, checked when set); None:
        not settable, or no bound.
    nominal : float, optional
        Its nominal magnitude (continuous states) [its unit].
    display_unit : str, optional
        The unit an importer shows it in (``feeddrive.units.DISPLAY_UNITS``).
    dependencies : tuple of int, optional
        Value references of the states and inputs a derivative depends on (the model's
        declared sparsity; model exchange).
    """

    name: str
    kind: int
    a: int
    b: int
    causality: str
    variability: str
    initial: str | None
    start: float | None
    unit: str
    description: str
    type: str = "Real"  # or "Boolean", "Integer"
    derivative: int | None = None  # value reference of the state (der variables)
    range: SlotRange | None = None  # the values it may be set to (min/max, set-time check)
    nominal: float | None = None  # nominal magnitude (continuous states)
    display_unit: str | None = None  # the unit an importer shows it in
    dependencies: tuple[int, ...] | None = None  # knowns a derivative depends on

    @property
    def settable(self) -> int:
        """When the importer may set it (FMI 2.0.4 Sect. 4.2.4, FMI 3.0 Sect. 3.2.3): 0 never
        (outputs, locals computed by the FMU, time), 1 until the end of initialisation
        (fixed parameters, start values ``initial = "exact"``), 2 at any time (inputs,
        tunable parameters)."""
        if self.causality == "input" or (self.causality == "parameter"
                                         and self.variability == "tunable"):
            return 2
        if self.causality == "parameter" or (self.causality == "local"
                                             and self.initial == "exact"):
            return 1
        return 0


def _axis_units(fm: FmuModel, axis: str) -> tuple[str, str]:
    """(speed unit of the axis' commands, unit of its velocity-loop error)."""
    m = fm.model
    command = next(c.speed_command for c in m.control_axes if c.name == axis)
    speed_unit = next(a.unit for a in m.aux if a.name == command)
    basis = m.parameter(f"controller.{axis}.v_basis")
    err = "m/s" if basis > 0.5 else speed_unit
    return speed_unit, err


def parameter_info(fm: FmuModel, name: str) -> tuple[str, str, str, bool]:
    """(FMU name, unit, description, fixed) of the model parameter slot ``name``.

    Parameters
    ----------
    fm : FmuModel
        The assembled model and where its inputs live.
    name : str
        A model parameter slot (``friction.screw.bristle_stiffness``).

    Returns
    -------
    tuple of (str, str, str, bool)
        The FMU variable name, its unit, description and whether it is fixed.
    """
    if name in _DESCRIPTIONS:
        unit = fmi_unit(slot_unit(fm.model, name))
        return name, unit, _DESCRIPTIONS[name], name in _FIXED_PARAMETERS
    match = re.fullmatch(r"controller\.(\w+)\.(\w+)", name)
    if match:
        axis, slot = match.groups()
        speed, err = _axis_units(fm, axis)
        angle = "rad" if speed == "rad/s" else "m"
        e_pos = err.replace("/s", "")
        units = {"kpp": ("1/s", "position-loop gain K_pp"),
                 "kvp": (f"A s/{e_pos}", "velocity-loop proportional gain K_vp"),
                 "kvi": (f"A/{e_pos}", "velocity-loop integral gain K_vi"),
                 "kip": ("V/A", "current-loop proportional gain K_ip"),
                 "kii": ("V/(A s)", "current-loop integral gain K_ii"),
                 "kv": ("1", "velocity-adjusting gain K_v"),
                 "kv_place": ("1", "where K_v acts: 0 none, 1 position output, 2 velocity "
                              "error"),
                 "v_basis": ("1", "velocity gains on 0: motor speed, 1: table speed"),
                 "v_feedback": ("1", "velocity feedback from 0: motor encoder, 1: table"),
                 "ff": ("1", "velocity feed-forward on (1) or off (0)"),
                 "i_max": ("A", "current command limit"),
                 "u_max": ("V", "voltage limit"),
                 "enc_q": ("rad", "encoder count size (0: ideal)"),
                 "grat_q": ("m", "linear-scale resolution (0: ideal)"),
                 "speed_mode": ("1", "1: speed loop only (no position feedback)"),
                 "H": (f"m/{angle}" if angle == "rad" else "1", "transmission of the axis"),
                 "inj_speed": (speed, "speed-command injection (loop breaking; 0)"),
                 "inj_current": ("A", "current-command injection (loop breaking; 0)")}
        unit, text = units[slot]
        return name, unit, f"{axis} axis: {text}", slot in _FIXED_PARAMETERS
    match = re.fullmatch(r"(friction|compensation)\.(\w+)\.([\w.\[\]]+)", name)
    if match:  # a named slot of a site's law (its parameter class declares the unit)
        group, site, slot = match.groups()
        law = dict(fm.model.sites).get(site, "lugre") if group == "friction" else "lugre"
        where = (f"{site.replace('_', '–')} friction" if group == "friction"
                 else f"{site} friction as the compensator assumes it")
        declared = unit_of(friction_law(law).parameters_class, slot)
        if declared is None:  # a structural count (GMS elements): fixed at export
            return name, "1", f"{where} ({law}): {slot} (fixed at export)", True
        return name, "1" if declared == "-" else declared, f"{where} ({law}): {slot}", False
    match = re.fullmatch(r"disturbances\.(\w+)\[(\d+)\]", name)
    if match:
        field, i = match.group(1), int(match.group(2))
        n = sum(1 for p in fm.model.parameter_names if p.startswith(f"disturbances.{field}["))
        k, part = i % (n // 3), ("order", "amplitude", "phase")[i // (n // 3)]
        amp = "m" if field == "lead_error" else "N m"
        unit = {"order": "1" if field != "lead_error" else "1", "amplitude": amp,
                "phase": "rad"}[part]
        return (f"disturbances.{field}.{part}[{k + 1}]", unit,
                f"{field.replace('_', ' ')}: harmonic {k + 1} {part}", False)
    return name, fmi_unit(slot_unit(fm.model, name)), "model parameter", False


def fmi_unit(unit: str) -> str:
    """A unit of the model's slot table (:func:`feeddrive.model.slots.slot_unit`) as the
    FMU's unit definitions spell it: ``"-"`` → ``"1"``, ``"kg m^2"`` → ``"kg m2"``,
    ``"ohm"`` → ``"Ohm"``.

    Parameters
    ----------
    unit : str
        The unit as the model declares it ("" for a slot of mixed meaning).

    Returns
    -------
    str
        The FMU's spelling (:func:`base_units` parses it).
    """
    if unit == "-":
        return "1"
    return " ".join("Ohm" if t == "ohm" else t for t in unit.replace("^", "").split(" "))


def _outputs(fm: FmuModel) -> set[str]:
    m = fm.model
    names = {"table_position", "table_speed"}
    for s in m.state_names:
        if s.endswith(("_angle", "_speed", "_current")) and not s.endswith("_integral"):
            if s.startswith("nut_") and not fm.nut_inputs:
                continue
            names.add(s)
    names |= {f"{site}_friction" for site, _ in m.sites}
    return names


def display_unit(name: str, unit: str) -> str | None:
    """The unit an importer shows the variable ``name`` of SI ``unit`` in: the CLI's
    (``feeddrive.units.DISPLAY_UNITS``: mm, mm/s, rpm, N/µm; µm for the following error,
    the scale resolution and the lead error's amplitudes).

    Parameters
    ----------
    name : str
        The variable's name.
    unit : str
        Its SI unit.

    Returns
    -------
    str or None
        The display unit, None when it is shown in its own unit.
    """
    options = DISPLAY_UNITS.get(unit)
    if not options:
        return None
    if unit == "m" and (name == "following_error" or name.endswith(".grat_q")
                        or name.startswith("disturbances.lead_error.amplitude")):
        return next(u for u, _ in options if u == "µm")
    return options[0][0]


def state_nominals(fm: FmuModel) -> np.ndarray:
    """Nominal magnitudes of the continuous states (the model's, then the two reference
    integrals) [their units]: fixed, 1e-10 m, 1e-8 m/s, 1e-6 A (÷ H for angles and rotary
    speeds) over 1e-6 — feeddrive's absolute tolerances before they scaled with the run.
    Magnitudes to scale by, not the export's tolerances (those set the co-simulation FMU's
    DOPRI5: :func:`feeddrive.fmu.solver_starts`); docs/fmu.md says what an importer that takes
    atol = rtol·nominal then weighs.

    Parameters
    ----------
    fm : FmuModel
        The assembled model.

    Returns
    -------
    numpy.ndarray
        One nominal per continuous state.
    """
    return np.array([*(fm.model.tolerances(1e-10, 1e-8, 1e-6)[0] / 1e-6),
                     *[1e-4] * (2 * len(fm.input_blocks))])


def variables(fm: FmuModel, kind: str) -> list[Variable]:
    """Every variable of the FMU (value reference = position in the list).

    Parameters
    ----------
    fm : FmuModel
        The assembled model and where its inputs live.
    kind : str
        ``"cs"`` or ``"me"``.

    Returns
    -------
    list of Variable
        The variables.
    """
    m = fm.model
    me = kind == "me"
    out_names = _outputs(fm)
    v: list[Variable] = [Variable("time", K_TIME, 0, 0, "independent", "continuous", None, None,
                                  "s", "simulation time")]
    starts = {"table_speed_reference": float(m.T[fm.table_offset + 2]),
              "nut_speed_reference": float(m.T[fm.table_offset + 6]),
              "load_force": float(m.P[fm.load_slot])}
    present = ["table_position_reference", "table_speed_reference"]
    if fm.nut_inputs:
        present += ["nut_position_reference"] if fm.nut_position_input else []
        present += ["nut_speed_reference"]
    present.append("load_force")
    for name in present:
        unit, text = INPUT_INFO[name]
        v.append(Variable(name, K_INPUT, INPUTS.index(name), 0, "input", "continuous", None,
                          starts.get(name, 0.0), unit, text, range=FINITE.with_unit(unit),
                          display_unit=display_unit(name, unit)))
    input_names = set(present)
    # states: outputs are computed (not settable, FMI); the others take start values
    nominal = state_nominals(fm)
    for i, s in enumerate(m.states):
        out = s.name in out_names
        v.append(Variable(s.name, K_STATE, i, 0, "output" if out else "local", "continuous",
                          "calculated" if out else "exact", None if out else 0.0, s.unit,
                          s.description, range=None if out else FINITE.with_unit(s.unit),
                          nominal=float(nominal[i]), display_unit=display_unit(s.name, s.unit)))
    n = len(m.states)
    ref_states = [("reference.table_position", "integral of table_speed_reference (the "
                   "commanded table position when integrate_speed_reference)")]
    ref_states.append(("reference.nut_position", "integral of nut_speed_reference (the "
                       "commanded nut position when integrate_speed_reference)"))
    for j, (name, text) in enumerate(ref_states):
        v.append(Variable(name, K_STATE, n + j, 0, "local", "continuous", "calculated", None,
                          "m", text, nominal=float(nominal[n + j]),
                          display_unit=display_unit(name, "m")))
    if me:
        v += rate_variables(fm, v)
    # auxiliary signals
    for j, a in enumerate(m.aux):
        name = a.name if a.name not in input_names else f"model.{a.name}"
        v.append(Variable(name, K_AUX, j, 0, "output" if a.name in out_names else "local",
                          "continuous", "calculated", None, a.unit, a.description,
                          display_unit=display_unit(name, a.unit)))
    # derived outputs: each live motor's torque (or force), the following error; where the
    # motor turns current into torque the topology says (Mechanism.motor_output)
    from ..model.mechanisms import mechanism

    mech = mechanism(fm.drive)(fm.parameters, fm.drive, fm.table_position, fm.nut_hold)
    for c in m.control_axes:  # the controller axes as their loops declared them
        axis = c.name
        if c.current not in m.state_names:
            continue
        if axis == "nut" and not fm.nut_inputs:
            continue
        slot, product = mech.motor_output(axis)
        unit = "N" if product.endswith("_force") else "N m"
        v.append(Variable(product, K_PRODUCT, m.parameter_names.index(slot),
                          m.index(c.current), "output", "continuous", "calculated",
                          None, unit,
                          f"{axis} motor {'force' if unit == 'N' else 'torque'} "
                          f"({slot.rsplit('.', 1)[-1].replace('_', ' ')} × current)"))
    aux_names = [a.name for a in m.aux]
    v.append(Variable("following_error", K_ERROR, aux_names.index("table_position_reference"),
                      m.index("table_position"), "output", "continuous", "calculated", None,
                      "m", "commanded minus actual table position",
                      display_unit=display_unit("following_error", "m")))
    # parameters: the range of the parameter-file field each slot is filled from
    clocks = {k for _, k in m.clocks}
    for k, pname in enumerate(m.parameter_names):
        if pname.startswith(_HIDDEN):
            continue
        name, unit, text, fixed = parameter_info(fm, pname)
        fixed = fixed or k in clocks  # the sample schedule is set at initialisation
        v.append(Variable(name, K_PARAM, k, 0, "parameter", "fixed" if fixed else "tunable",
                          "exact", float(m.P[k]), unit, text,
                          range=slot_range(m, pname).with_unit(unit),
                          display_unit=display_unit(name, unit)))
    v += setting_variables(fm, kind)
    return check_unique(v)


def check_unique(v: list[Variable]) -> list[Variable]:
    """``v``, checked for a name declared twice.

    Parameters
    ----------
    v : list of Variable
        The variables.

    Returns
    -------
    list of Variable
        ``v``.

    Raises
    ------
    ValueError
        Naming the duplicated names.
    """
    names = [x.name for x in v]
    if len(set(names)) != len(names):
        dup = sorted({x for x in names if names.count(x) > 1})
        raise ValueError(f"FMU variable names not unique: {', '.join(dup)}")
    return v


def setting_variables(fm: FmuModel, kind: str) -> list[Variable]:
    """The FMU's own settings (:func:`fmu_settings`) and the embedded solver's counters
    (co-simulation) or the evaluation counters (model exchange).

    Parameters
    ----------
    fm : FmuModel
        The assembled model.
    kind : str
        ``"cs"`` or ``"me"``.

    Returns
    -------
    list of Variable
        The variables.
    """
    me = kind == "me"
    v: list[Variable] = []
    for i, (name, unit, text, start, bounds) in enumerate(fmu_settings(fm)):
        value = (fm.solver_starts[name] if name in fm.solver_starts
                 else start if start is not None else period_start(fm, name))
        if name == "integrate_speed_reference":
            v.append(Variable(name, K_BOOLEAN, i, 0, "parameter", "fixed", "exact", value, "",
                              text, type="Boolean"))
        elif name == "solver.max_steps_per_call":
            if not me:
                v.append(Variable(name, K_INTEGER, i, 0, "parameter", "tunable", "exact",
                                  value, "", text, type="Integer", range=bounds))
        else:
            assert bounds is not None
            v.append(Variable(name, K_SETTING, i, 0, "parameter", "fixed", "exact", value, unit,
                              text, range=bounds.with_unit(unit)))
    if not me:
        from .solver import CONSTANTS

        for name, slot, text in COUNTERS:
            v.append(Variable(name, K_COUNTER, CONSTANTS[slot], 0, "local", "discrete",
                              "calculated", None, "", text, type="Integer"))
    else:
        for k, (name, text) in enumerate(EVALUATIONS):
            v.append(Variable(name, K_EVALUATIONS, k, 0, "local", "discrete", "calculated",
                              None, "", text, type="Integer"))
    return v


def rate_variables(fm: FmuModel, v: list[Variable]) -> list[Variable]:
    """``der(<state>)`` of every continuous state (the model's, then the two reference
    integrals of each input block) for a model-exchange FMU, with the dependencies
    :func:`derivative_dependencies` declares.

    Parameters
    ----------
    fm : FmuModel
        The assembled model (one drive or a machine).
    v : list of Variable
        The variables so far, every continuous state and input among them; the rates'
        value references continue it.

    Returns
    -------
    list of Variable
        One rate per continuous state, in state order.
    """
    state_vr = {x.a: vr for vr, x in enumerate(v) if x.kind == K_STATE}
    deps = derivative_dependencies(fm, state_vr, {x.a: vr for vr, x in enumerate(v)
                                                  if x.kind == K_INPUT})
    out = []
    for i in range(len(fm.model.states) + 2 * len(fm.input_blocks)):
        sv = v[state_vr[i]]
        unit = rate_unit(sv.unit)
        out.append(Variable(f"der({sv.name})", K_DER, i, 0, "local", "continuous",
                            "calculated", None, unit, f"rate of {sv.name}",
                            derivative=state_vr[i], display_unit=display_unit("", unit),
                            dependencies=deps[i]))
    return out


def derivative_dependencies(fm: FmuModel, state_vr: dict[int, int], input_vr: dict[int, int]
                            ) -> list[tuple[int, ...]]:
    """The states and inputs each continuous state's derivative depends on (value
    references), from the model's declared sparsity (:attr:`Model.jacobian_pattern`, the
    parts' declarations): model state j where the pattern says so; the reference integrals and
    the inputs where it depends on time (the reference and the load reach the model through
    t); a reference integral's rate on its speed input.

    Parameters
    ----------
    fm : FmuModel
        The assembled model.
    state_vr : dict of int to int
        Continuous state index → value reference (the model's states, then the two reference
        integrals of each input block).
    input_vr : dict of int to int
        Input slot (block · len(:data:`INPUTS`) + :data:`INPUTS` index) → value reference,
        for the inputs present.

    Returns
    -------
    list of tuple of int
        Per continuous state, the value references of what its derivative depends on.
    """
    S = fm.model.jacobian_pattern
    n = S.shape[0]
    blocks = len(fm.input_blocks)
    refs = tuple(state_vr[n + j] for j in range(2 * blocks))
    inputs = tuple(sorted(input_vr.values()))
    out = []
    for i in range(n):
        deps = [state_vr[j] for j in range(n) if S[i, j]]
        if S[i, n]:  # time: the reference (inputs, integrals) and the load force
            deps += [*refs, *inputs]
        out.append(tuple(sorted(deps)))
    for k in range(blocks):  # each input block's two reference integrals (a machine's axes)
        for slot in (IN_VT, IN_VN):
            a = k * len(INPUTS) + slot
            out.append((input_vr[a],) if a in input_vr else ())
    return out


def rate_unit(unit: str) -> str:
    """The unit of a state's rate (FMI spelling): ``"m"`` → ``"m/s"``, ``"m/s"`` →
    ``"m/s2"``, ``"A s"`` → ``"A"``, ``"m s"`` → ``"m"``.

    Parameters
    ----------
    unit : str
        The state's unit.

    Returns
    -------
    str
        Its rate's unit.
    """
    if unit in ("", "1"):
        return "1/s"
    if unit.endswith("/s"):
        return unit[:-2] + "/s2"
    if unit.endswith(" s"):  # a loop's integral (A s, m s): its integrand's unit
        return unit[:-2]
    return f"{unit}/s"


# ---------------------------------------------------------------- units
_BASE = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
_SYMBOLS: dict[str, dict[str, int]] = {
    "kg": {"kg": 1}, "m": {"m": 1}, "s": {"s": 1}, "A": {"A": 1}, "rad": {"rad": 1},
    "N": {"kg": 1, "m": 1, "s": -2}, "V": {"kg": 1, "m": 2, "s": -3, "A": -1},
    "Ohm": {"kg": 1, "m": 2, "s": -3, "A": -2}, "H": {"kg": 1, "m": 2, "s": -2, "A": -2},
}


def base_units(unit: str) -> dict[str, int]:
    """SI base-unit exponents of a unit string such as ``"N s/m"``, ``"V/(A s)"``, ``"kg m2"``.

    Parameters
    ----------
    unit : str
        The unit.

    Returns
    -------
    dict of str to int
        Base unit (``kg``, ``m``, ``s``, ``A``, ``K``, ``mol``, ``cd``, ``rad``) → exponent.

    Raises
    ------
    ValueError
        For a unit the parser does not know.
    """
    out: dict[str, int] = {}
    text = unit.replace("(", "").replace(")", "")
    parts = text.split("/")
    for sign, part in zip((1, *([-1] * (len(parts) - 1))), parts, strict=True):
        for token in part.split():
            if token == "1":
                continue
            match = re.fullmatch(r"([A-Za-z]+)(-?\d*)", token)
            if not match or match.group(1) not in _SYMBOLS:
                raise ValueError(f"unit {unit!r}: unknown symbol {token!r}")
            power = int(match.group(2) or 1) * sign
            for base, e in _SYMBOLS[match.group(1)].items():
                out[base] = out.get(base, 0) + e * power
    return {k: e for k, e in out.items() if e}


# ---------------------------------------------------------------- XML
def _attrs(**kw: object) -> str:
    return " ".join(f"{k}={quoteattr(str(val))}" for k, val in kw.items() if val is not None)


@dataclass(frozen=True)
class Provenance:
    """Who made the FMU and under which licence (the attributes ``author``, ``version``,
    ``copyright``, ``license``, ``generationTool`` and ``generationDateAndTime`` of
    ``modelDescription.xml``).

    Parameters
    ----------
    author : str
        The package's authors (its metadata).
    version : str
        The package's version (the model's version: it is generated by that release).
    copyright : str
        The copyright lines of the package and of the FMI headers the FMU carries.
    license : str
        The licences (SPDX), pointing at ``documentation/licenses/``.
    generation_tool : str
        ``"feeddrive <version>"``.
    generation_time : str
        UTC time of the export, ISO 8601 (``SOURCE_DATE_EPOCH`` when set, for reproducible
        builds).
    """

    author: str
    version: str
    copyright: str
    license: str
    generation_tool: str
    generation_time: str


def _number(x: float) -> str:
    if not math.isfinite(x):
        raise ValueError(f"start value {x!r} is not finite")
    return repr(float(x))


def _bounds(x: Variable) -> dict[str, str | None]:
    """min/max attributes: the nearest inclusive bounds of the variable's range."""
    r = x.range
    if r is None:
        return {"min": None, "max": None}
    fmt = (lambda y: str(int(y))) if x.type == "Integer" else _number
    return {"min": fmt(r.minimum) if math.isfinite(r.minimum) else None,
            "max": fmt(r.maximum) if math.isfinite(r.maximum) else None}


def model_description(fm: FmuModel, vs: list[Variable], *, fmi: int, kind: str,
                      identifier: str, token: str, description: str,
                      provenance: Provenance) -> str:
    """The text of ``modelDescription.xml`` (FMI 2.0 or 3.0).

    Parameters
    ----------
    fm : FmuModel
        The assembled model and where its inputs live.
    vs : list of Variable
        The FMU's variables (:func:`variables`).
    fmi : int
        FMI version, 2 or 3.
    kind : str
        ``"cs"`` or ``"me"``.
    identifier : str
        The model identifier.
    token : str
        The instantiation token (GUID).
    description : str
        The model's description text.
    provenance : Provenance
        Author, version, copyright, licence, generation tool and time.

    Returns
    -------
    str
        The XML.

    References
    ----------
    .. [1] Modelica Association, Functional Mock-up Interface 2.0.4 and 3.0,
       https://fmi-standard.org/.
    """
    units = sorted({x.unit for x in vs if x.unit})
    me = kind == "me"
    pv = provenance
    who = {"author": pv.author, "version": pv.version, "copyright": pv.copyright,
           "license": pv.license, "generationTool": pv.generation_tool,
           "generationDateAndTime": pv.generation_time}
    lines = ['<?xml version="1.0" encoding="UTF-8"?>']
    if fmi == 2:
        lines.append("<fmiModelDescription " + _attrs(
            fmiVersion="2.0", modelName=identifier, guid=token, description=description,
            **who, variableNamingConvention="structured", numberOfEventIndicators=0) + ">")
        if me:
            lines.append("  <ModelExchange " + _attrs(
                modelIdentifier=identifier, canGetAndSetFMUstate="true",
                canSerializeFMUstate="true", canNotUseMemoryManagementFunctions="true",
                providesDirectionalDerivative="true") + ">")
            lines.append('    <SourceFiles><File name="fmu.c"/></SourceFiles>')
            lines.append("  </ModelExchange>")
        else:
            lines.append("  <CoSimulation " + _attrs(
                modelIdentifier=identifier, canHandleVariableCommunicationStepSize="true",
                canInterpolateInputs="true", maxOutputDerivativeOrder=0,
                canGetAndSetFMUstate="true", canSerializeFMUstate="true",
                canNotUseMemoryManagementFunctions="true") + ">")
            lines.append('    <SourceFiles><File name="fmu.c"/></SourceFiles>')
            lines.append("  </CoSimulation>")
    else:
        lines.append("<fmiModelDescription " + _attrs(
            fmiVersion="3.0", modelName=identifier, instantiationToken=token,
            description=description, **who, variableNamingConvention="structured") + ">")
        if me:
            lines.append("  <ModelExchange " + _attrs(
                modelIdentifier=identifier, canGetAndSetFMUState="true",
                canSerializeFMUState="true", providesDirectionalDerivatives="true") + "/>")
        else:
            lines.append("  <CoSimulation " + _attrs(
                modelIdentifier=identifier, canHandleVariableCommunicationStepSize="true",
                canGetAndSetFMUState="true", canSerializeFMUState="true",
                hasEventMode="false") + "/>")
    lines.append("  <UnitDefinitions>")
    shown = {(x.unit, x.display_unit) for x in vs if x.display_unit}
    for u in units:
        base = base_units(u)
        display = "".join(
            "<DisplayUnit " + _attrs(name=name, factor=_number(factor)) + "/>"
            for name, factor in DISPLAY_UNITS.get(u, ()) if (u, name) in shown)
        lines.append(f"    <Unit name={quoteattr(u)}><BaseUnit "
                     + _attrs(**{k: base[k] for k in _BASE if k in base}) + "/>"
                     + display + "</Unit>")
    lines.append("  </UnitDefinitions>")
    lines.append("  <DefaultExperiment " + _attrs(startTime="0.0", stopTime="10.0",
                                                  stepSize="0.001") + "/>")
    lines.append("  <ModelVariables>")
    index = {}
    for vr, x in enumerate(vs):
        index[vr] = vr + 1  # FMI 2 indices are 1-based positions in ModelVariables
        common = _attrs(name=x.name, valueReference=vr, description=x.description,
                        causality=x.causality, variability=x.variability, initial=x.initial)
        start = None
        if x.start is not None:
            start = (("true" if x.start else "false") if x.type == "Boolean"
                     else str(int(x.start)) if x.type == "Integer" else _number(x.start))
        real = x.type == "Real"
        extra = {"unit": x.unit or None, "displayUnit": x.display_unit,
                 **(_bounds(x) if x.type != "Boolean" else {}),
                 "nominal": _number(x.nominal) if real and x.nominal is not None else None,
                 "start": start}
        if fmi == 2:
            inner = _attrs(**extra,
                           derivative=None if x.derivative is None else x.derivative + 1)
            lines.append(f"    <ScalarVariable {common}><{x.type} {inner}/></ScalarVariable>")
        else:
            tag = {"Real": "Float64", "Integer": "Int64"}.get(x.type, x.type)
            inner = _attrs(**extra, derivative=x.derivative)
            lines.append(f"    <{tag} {common} {inner}/>".replace("  /", " /"))
    lines.append("  </ModelVariables>")
    lines.append("  <ModelStructure>")
    outputs = [vr for vr, x in enumerate(vs) if x.causality == "output"]
    ders = [vr for vr, x in enumerate(vs) if x.derivative is not None]
    initial = [vr for vr, x in enumerate(vs)
               if (x.causality == "output" and x.initial in ("approx", "calculated"))
               or (me and (x.derivative is not None or (x.kind == K_STATE
                                                          and x.initial == "calculated")))]
    def deps(vr: int, fmi2: bool) -> str:
        d = vs[vr].dependencies
        if d is None:
            return ""
        return f' dependencies="{" ".join(str(index[k] if fmi2 else k) for k in d)}"'

    if fmi == 2:
        for tag, vrs in (("Outputs", outputs), ("Derivatives", ders),
                         ("InitialUnknowns", initial)):
            if vrs:
                lines.append(f"    <{tag}>")
                lines += [f'      <Unknown index="{index[vr]}"'
                          f'{deps(vr, True) if tag == "Derivatives" else ""}/>' for vr in vrs]
                lines.append(f"    </{tag}>")
    else:
        lines += [f'    <Output valueReference="{vr}"/>' for vr in outputs]
        lines += [f'    <ContinuousStateDerivative valueReference="{vr}"{deps(vr, False)}/>'
                  for vr in ders]
        lines += [f'    <InitialUnknown valueReference="{vr}"/>' for vr in initial]
    lines.append("  </ModelStructure>")
    lines.append("</fmiModelDescription>")
    return "\n".join(lines) + "\n"


def new_token() -> str:
    """A new instantiation token: a random UUID in braces.

    Returns
    -------
    str
        E.g. ``"{0f8e…}"``.
    """
    return "{" + str(uuid.uuid4()) + "}"


# ---------------------------------------------------------------- C tables
def _c_double(x: float) -> str:
    if math.isinf(x):
        return "HUGE_VAL" if x > 0 else "-HUGE_VAL"
    return repr(float(x))


def _c_array(ctype: str, name: str, values: list[float] | list[int] | np.ndarray) -> str:
    items = [_c_double(x) if ctype == "double" else str(int(x)) for x in values] or ["0"]
    rows = [", ".join(items[i:i + 8]) for i in range(0, len(items), 8)]
    return f"static const {ctype} {name}[] = {{\n    " + ",\n    ".join(rows) + "\n};"


def c_tables(fm: FmuModel, vs: list[Variable], *, fmi: int, kind: str, token: str) -> str:
    """The C definitions the wrapper reads: sizes, value-reference table, start values.

    Parameters
    ----------
    fm : FmuModel
        The assembled model and where its inputs live.
    vs : list of Variable
        The FMU's variables (:func:`variables`).
    fmi : int
        FMI version, 2 or 3.
    kind : str
        ``"cs"`` or ``"me"``.
    token : str
        The instantiation token.

    Returns
    -------
    str
        C text.
    """
    m = fm.model
    n_colours = int(m.jacobian_colours[:len(m.states)].max()) + 1
    pos, _ = m.tolerances(1.0, 0.0, 0.0)
    spd, _ = m.tolerances(0.0, 1.0, 0.0)
    cur, rel = m.tolerances(0.0, 0.0, 1.0)
    blocks = fm.input_blocks
    settings = fmu_settings(fm)
    index = {name: i for i, (name, *_rest) in enumerate(settings)}
    periods = [f"{b.prefix}{slot}" for b in blocks for slot in b.periods]
    u_start = [0.0] * (len(INPUTS) * len(blocks))
    for x in vs:
        if x.kind == K_INPUT:
            u_start[x.a] = float(x.start or 0.0)
    s_start = [start if start is not None else period_start(fm, name)
               for name, _, _, start, _ in settings]
    for x in vs:
        if x.kind in (K_SETTING, K_BOOLEAN, K_INTEGER):
            s_start[x.a] = float(x.start or 0.0)
    out = [
        f"#define FMU_FMI_VERSION {fmi}",
        f"#define FMU_KIND_ME {1 if kind == 'me' else 0}",
        f"#define INSTANTIATION_TOKEN {quote_c(token)}",
        f"#define N_VR {len(vs)}",
        f"#define N_IN_BLOCK {len(INPUTS)}",
        f"#define N_BLOCK {len(blocks)}",
        f"#define N_INPUT {len(INPUTS) * len(blocks)}",
        f"#define N_SETTING {len(settings)}",
        f"#define N_PERIOD {len(periods)}",
        # each input block (one drive, or each axis of a machine): its reference block in T,
        # the slots of its input instant and load force in P (wrapper.c fmu_write_inputs)
        _c_array("int", "BLOCK_TABLE", [b.table_offset for b in blocks]),
        _c_array("int", "BLOCK_INSTANT", [b.instant_slot for b in blocks]),
        _c_array("int", "BLOCK_LOAD", [b.load_slot for b in blocks]),
        # the loop periods: their settings and parameter slots (wrapper.c fmu_sampling)
        _c_array("int", "PERIOD_SETTING", [index[name] for name in periods]),
        _c_array("int", "PERIOD_SLOT", [m.parameter_names.index(name) for name in periods]),
        _c_array("int", "IS_PERIOD_SETTING", [int(name in periods) for name, *_r in settings]),
        "static const char *const PERIOD_NAMES[] = {"
        + ", ".join(quote_c(name) for name in periods) + "};",
        *[f"#define IN_{k} {i}" for k, i in (("XT", IN_XT), ("VT", IN_VT), ("XN", IN_XN),
                                             ("VN", IN_VN), ("LOAD", IN_LOAD))],
        *[f"#define {n} {i}" for n, i in (
            ("S_RTOL", index["solver.relative_tolerance"]),
            ("S_POSITION_TOL", index["solver.position_tolerance"]),
            ("S_SPEED_TOL", index["solver.speed_tolerance"]),
            ("S_CURRENT_TOL", index["solver.current_tolerance"]),
            ("S_MAX_STEP", index["solver.max_step"]),
            ("S_INTEGRATE", index["integrate_speed_reference"]),
            ("S_MAX_STEPS", index["solver.max_steps_per_call"]),
            # the importer's tolerance (fmi2SetupExperiment) is checked against this one's range
            ("VR_RTOL", next(i for i, x in enumerate(vs)
                             if x.name == "solver.relative_tolerance")))],
        *[f"#define {name} {value}" for name, value in (
            ("K_TIME", K_TIME), ("K_STATE", K_STATE), ("K_DER", K_DER), ("K_AUX", K_AUX),
            ("K_PARAM", K_PARAM), ("K_INPUT", K_INPUT), ("K_SETTING", K_SETTING),
            ("K_PRODUCT", K_PRODUCT), ("K_ERROR", K_ERROR), ("K_BOOLEAN", K_BOOLEAN),
            ("K_INTEGER", K_INTEGER), ("K_COUNTER", K_COUNTER),
            ("K_EVALUATIONS", K_EVALUATIONS), ("T_REAL", T_REAL),
            ("T_BOOLEAN", T_BOOLEAN), ("T_INTEGER", T_INTEGER))],
        _c_array("int", "VR_KIND", [x.kind for x in vs]),
        _c_array("int", "VR_A", [x.a for x in vs]),
        _c_array("int", "VR_B", [x.b for x in vs]),
        _c_array("int", "VR_TYPE", [_TYPES[x.type] for x in vs]),
        # when the importer may set it: 0 never, 1 until initialised, 2 always
        _c_array("int", "VR_SET", [x.settable for x in vs]),
        # the range a set value is checked against (wrapper.c fmu_check_range)
        _c_array("double", "VR_LOW", [x.range.low if x.range else -math.inf for x in vs]),
        _c_array("double", "VR_HIGH", [x.range.high if x.range else math.inf for x in vs]),
        _c_array("int", "VR_RANGE", [_range_flags(x.range) for x in vs]),
        "static const char *const VR_NAME[] = {\n    "
        + ",\n    ".join(quote_c(x.name) for x in vs) + "};",
        "static const char *const VR_EXPECTED[] = {\n    "
        + ",\n    ".join(quote_c(x.range.expected() if x.range else "") for x in vs) + "};",
        _c_array("double", "Y_START", [0.0] * len(m.states)),
        _c_array("double", "P_START", m.P),
        _c_array("double", "T_START", m.T),
        _c_array("double", "U_START", u_start),
        _c_array("double", "S_START", s_start),
        _c_array("double", "ATOL_POSITION", pos),
        _c_array("double", "ATOL_SPEED", spd),
        _c_array("double", "ATOL_CURRENT", cur),
        _c_array("double", "REL_MASK", rel),
        # nominal magnitudes of the continuous states (model exchange; state_nominals)
        _c_array("double", "NOMINAL", state_nominals(fm)),
        # the Jacobian's declared pattern and its column groups (model exchange: the
        # directional derivatives, wrapper.c fmu_jacobian): the model's colouring, each
        # reference integral (two per input block) a group of its own
        *([_c_array("int", "JAC_PATTERN", m.jacobian_pattern[:, :len(m.states)].ravel()),
           _c_array("int", "JAC_GROUP", [*m.jacobian_colours[:len(m.states)],
                                         *range(n_colours, n_colours + 2 * len(blocks))]),
           f"#define JAC_N_GROUPS {n_colours + 2 * len(blocks)}"] if kind == "me" else []),
        "static const char *const SETTING_NAMES[] = {"
        + ", ".join(quote_c(s[0]) for s in settings) + "};",
        # the sample schedule: the parameter slot of every clock's period (C fmu_sampling)
        _c_array("int", "CLOCK_SLOT", [k for _, k in m.clocks]),
        "static const char *const CLOCK_NAMES[] = {"
        + ", ".join(quote_c(name) for name, _ in m.clocks) + "};",
        "static const char *const STATUS_MESSAGES[] = {"
        + ", ".join(quote_c(t) for t in _status_messages()) + "};",
    ]
    return "\n".join(out) + "\n"


def _range_flags(r: SlotRange | None) -> int:
    """VR_RANGE bits: 1 the low end excluded, 2 zero allowed besides, 4 integers only."""
    if r is None:
        return 0
    return (0 if r.low_inclusive else 1) | (2 if r.zero else 0) | (4 if r.integer else 0)


def _status_messages() -> list[str]:
    from .solver import STATUS_MESSAGES

    return [STATUS_MESSAGES[i] for i in range(4)]


def quote_c(text: str) -> str:
    """A C string literal of ``text`` in UTF-8 (printable ASCII as is, other bytes as octal
    escapes).

    Parameters
    ----------
    text : str
        The text.

    Returns
    -------
    str
        The literal, with its quotes.
    """
    out = []
    for byte in text.encode("utf-8"):
        c = chr(byte)
        if c in ('"', "\\"):
            out.append("\\" + c)
        elif 32 <= byte < 127 and c != "?":  # "?": no trigraphs
            out.append(c)
        else:  # UTF-8 bytes as octal escapes: the logger gets the text as written
            out.append(f"\\{byte:03o}")
    return '"' + "".join(out) + '"'


def xml_text(text: str) -> str:
    """Text escaped for an XML attribute or element (``&``, ``<``, ``>``).

    Parameters
    ----------
    text : str
        The text.

    Returns
    -------
    str
        The escaped text.
    """
    return escape(text)


__all__ = ["Variable", "variables", "model_description", "c_tables", "parameter_info",
           "base_units", "AXIS_PARAMS"]
