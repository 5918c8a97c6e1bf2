"""Parts → one compiled model: ``assemble(system, profile) -> Model``.

The order is fixed and short: mechanism states, friction-site states, motor currents, loop
integrators; then the right-hand side is written as reference → controller → mechanics.
Structural choices (topology, friction laws, ball–nut split, disturbances present, motors on
or off) select code; numbers (gains, masses, friction values, CDFS vs DDFS, sample periods)
go into the parameter vector, so one compiled model serves many parameter values.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np

from .._kept import Kept
from ..parameters import DriveParameters, ParameterError
from . import codegen, loops, sparsity
from .compensation import CompensationFootprint, emit_compensation
from .disturbances import LoadProfile, TorqueRipple, emit_harmonics, emit_load, harmonics
from .friction import FrictionLaw, friction_law
from .mechanisms import Mechanics, Site, mechanism
from .reference import (
    PROFILE_PARAMS,
    REFERENCE_INPUTS,
    REFERENCE_SIGNALS,
    TABLE_COLUMNS,
    TABLE_OFFSET,
    commanded_references,
    reference_signal,
)
from .replay import Replay, declare_replay, emit_replay_rates, emit_replay_value

if TYPE_CHECKING:
    from .reference import Profile


@dataclass(frozen=True)
class Model:
    """An assembled drive model: its named slots, packed numbers and compiled module.

    Parameters
    ----------
    state_names : tuple of str
        State names, in ``y`` order.
    states : tuple of Signal
        The states with units and descriptions.
    aux : tuple of Signal
        The auxiliary outputs the right-hand side writes.
    parameter_names : tuple of str
        Parameter slot names, in ``P`` order.
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    T : numpy.ndarray
        The packed data tables (profiles, load records) [SI].
    tolerance_kinds : tuple of str
        Tolerance class of each state.
    tolerance_scales : tuple of float
        Tolerance scale of each state [m per state unit].
    module : module
        The compiled module (``rhs``, ``sample_update``, the solver drivers).
    source : str
        Its source text.
    drive : str
        The drive name it was built for.
    sites : tuple of (str, str)
        (site name, law name) of each friction site.
    jacobian_pattern : numpy.ndarray of int
        (n, n + 1) uint8: 1 where dy[i] may depend on y[j] (column n: on t).
    jacobian_colours : numpy.ndarray of int
        (n + 1,) column groups of the grouped finite-difference Jacobian.
    flows : tuple of (str, tuple of str), default ()
        The parts' declared flows: each written quantity and what it reads.
    compensation : CompensationFootprint, optional
        What the compensator reads and adds; None without compensation.
    clocks : tuple of (str, int), default ()
        The sample schedule: each clock's period slot and its index in ``P``.
    control_axes : tuple of ControlAxis, default ()
        Each controller axis' signals and parameter block, as its loops declared them
        (:class:`feeddrive.model.loops.ControlAxis`).
    derived : tuple of (Signal, str, float), default ()
        Signals a part declares as factor × a state or signal: (signal, source, factor
        [signal unit per source unit]).
    slot_units : tuple of (str, str), default ()
        The units declared with their slots (:meth:`Builder.param
        <feeddrive.model.codegen.Builder.param>`): (slot name, unit) of each slot whose name
        leads to no declaration, a machine's coupling parameters (``couplings.beam.mass``,
        ``kg``: the part's :attr:`~feeddrive.machine.couplings.Coupling.units`).
    """

    state_names: tuple[str, ...]
    states: tuple[codegen.Signal, ...]
    aux: tuple[codegen.Signal, ...]
    parameter_names: tuple[str, ...]
    P: np.ndarray
    T: np.ndarray
    tolerance_kinds: tuple[str, ...]
    tolerance_scales: tuple[float, ...]
    module: ModuleType
    source: str
    drive: str
    sites: tuple[tuple[str, str], ...]  # (site name, law name)
    jacobian_pattern: np.ndarray  # (n, n + 1) uint8: dy[i] may depend on y[j] (column n: t)
    jacobian_colours: np.ndarray  # (n + 1,) group of each column in the grouped FD Jacobian
    # signals a part declares as factor × a state or signal: (signal, source name, factor)
    derived: tuple[tuple[codegen.Signal, str, float], ...] = ()
    # what each right-hand-side quantity is computed from, as the parts' code text says it
    # (``Builder.emit``; the Jacobian pattern follows from it)
    flows: tuple[tuple[str, tuple[str, ...]], ...] = ()
    compensation: CompensationFootprint | None = None  # the compensator's reads and adds
    # the sample schedule: (name, index in P of its period [s]) per clock (Builder.clock)
    clocks: tuple[tuple[str, int], ...] = ()
    # each controller axis' signals and parameter block (loops.ControlAxis)
    control_axes: tuple[loops.ControlAxis, ...] = ()
    # (slot name, unit) declared with the slot (Builder.param's unit: coupling parameters)
    slot_units: tuple[tuple[str, str], ...] = ()

    @property
    def n_held(self) -> int:
        """Number of values the sampled controller holds between updates (at least 1)."""
        return int(self.module.N_HELD)

    def periods(self, P: np.ndarray | None = None) -> dict[str, float]:
        """Sample period [s] of every clock of the schedule by name (0: continuous), read from
        the parameter vector ``P`` (default: the model's).

        Parameters
        ----------
        P : numpy.ndarray, optional
            The parameter vector [SI, per slot].

        Returns
        -------
        dict of str to float
            Clock → period [s].
        """
        P = self.P if P is None else P
        return {name: float(P[k]) for name, k in self.clocks}

    def continuous_ticks(self) -> np.ndarray:
        """The ``tick`` argument of ``sample_update`` with no clock due (all −1).

        Returns
        -------
        numpy.ndarray of int
            −1 per clock.
        """
        return np.full(int(self.module.N_CLOCK), -1, dtype=np.int64)

    def index(self, name: str) -> int:
        """Position of a state in the state vector.

        Parameters
        ----------
        name : str
            A state name (:attr:`state_names`).

        Returns
        -------
        int
            Its index in ``y``.

        Raises
        ------
        ParameterError
            For an unknown name; the message lists the model's states.
        """
        try:
            return self.state_names.index(name)
        except ValueError:
            raise ParameterError("initial_state", name,
                                 f"unknown state; expected one of {', '.join(self.state_names)}"
                                 ) from None

    def parameter(self, name: str) -> float:
        """The value of a named parameter slot of this model.

        Parameters
        ----------
        name : str
            A slot name, e.g. ``"friction.screw.bristle_stiffness"``, ``"table.mass"``,
            ``"controller.screw.kvp"`` (:attr:`parameter_names` lists them).

        Returns
        -------
        float
            The value, in the slot's SI unit [unit of ``name``].
        """
        try:
            return float(self.P[self.parameter_names.index(name)])
        except ValueError:
            near = [n for n in self.parameter_names if n.split(".")[0] == name.split(".")[0]]
            raise ParameterError("parameter", name, "no such slot in this model; expected one "
                                 f"of {', '.join(near or self.parameter_names)}") from None

    def tolerances(self, position: float, speed: float, current: float,
                   deflection: float | None = None, *, motor_position: float | None = None,
                   motor_speed: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Absolute tolerance and relative-tolerance mask of each state, from the solver's
        resolved tolerances (:class:`feeddrive.engine.options.Tolerances`).

        Angles and rotary speeds divide the linear tolerances by their scale H; integrals follow
        the motor position or current tolerance; friction deflections are ``deflection`` × their
        own scale, or take the position tolerance when ``deflection`` is None.

        Parameters
        ----------
        position : float
            Absolute tolerance of positions [m].
        speed : float
            Absolute tolerance of speeds [m/s].
        current : float
            Absolute tolerance of currents [A].
        deflection : float or None, default None
            Fraction of each deflection state's scale [-]; None: the position tolerance.
        motor_position : float or None, default None
            Absolute tolerance of the motors' angles and the loops' velocity integrals in
            table units [m] (÷ H per state); None: ``position``.
        motor_speed : float or None, default None
            Absolute tolerance of the motors' speeds in table units [m/s] (÷ H per state);
            None: ``speed``.

        Returns
        -------
        atol : numpy.ndarray
            Absolute tolerance per state [state unit].
        relative : numpy.ndarray
            1 for the states whose error is also weighed relative to their size, else 0.
        """
        mx = position if motor_position is None else motor_position
        mv = speed if motor_speed is None else motor_speed
        atol = np.empty(len(self.states))
        rel = np.zeros(len(self.states))
        for i, (kind, scale) in enumerate(zip(self.tolerance_kinds, self.tolerance_scales,
                                              strict=True)):
            if kind == "deflection":
                atol[i] = position if deflection is None else deflection * scale
            else:
                atol[i] = {"position": position, "speed": speed, "angle": mx / scale,
                           "rotary_speed": mv / scale, "current": current,
                           "current_integral": current * 1e-3,
                           "velocity_integral": mx / scale, "none": position}[kind]
            rel[i] = 1.0 if kind in codegen.RELATIVE_KINDS else 0.0
        return atol, rel


def _profile(b: codegen.Builder, profile: Profile, mech: Any) -> None:
    values, table = profile.encode()
    block = np.zeros(len(PROFILE_PARAMS))
    for k, v in values.items():
        block[k] = v
    mech.check_profile(commanded_references(block, table))
    table = np.ascontiguousarray(table, dtype=float)
    block[TABLE_OFFSET] = b.table(table)
    block[TABLE_COLUMNS] = table.shape[1]
    o = b.params("profile", block)
    # the linearisation's reference inputs (feeddrive.analysis.linear), zero in a simulation
    oi = b.param(f"inputs.{REFERENCE_INPUTS[0]}", 0.0)
    for name in REFERENCE_INPUTS[1:]:
        b.param(f"inputs.{name}", 0.0)
    # the table's reference, and each further one the topology follows: named values
    # ``ref_x``, ``ref_v`` (the table's), ``ref_x_<signal>``, ``ref_v_<signal>``
    call = f"{b.use(reference_signal)}({{t}}, P, {o}, {oi}, T"
    b.references = [f"{{ref_x}}, {{ref_v}} = {call}, 0)"]
    for signal in mech.followed_references(mech.drive):
        b.references.append(f"{{ref_x_{signal}}}, {{ref_v_{signal}}} = {call}, "
                            f"{REFERENCE_SIGNALS.index(signal)})")


def _site_code(b: codegen.Builder, site: Site, law: FrictionLaw, params: Any,
               y_offset: int) -> codegen.Line:
    packed = law.pack(params.scaled(site.scale) if site.scale != 1.0 else params)
    o = b.named_params(f"friction.{site.name}", law.site_slots(params), packed)
    alias = b.use_dynamic(f"_law_{law.name.replace('-', '_')}",
                          f"_friction_law({law.name!r}).compiled", law.compiled)
    # the friction-law interface: the kernel reads its sliding speed and its own states
    # y[k : k + m] only, and writes dy at exactly those places — the one thing its text
    # (``y, k, …, dy``) cannot show, so the line carries it
    own = [f"{site.name}_{state}" for state in law.states(params)]
    return codegen.Line(f"{{f_{site.name}}} = {alias}({site.speed}, y, "
                        f"{codegen.index(y_offset)}, P, {codegen.index(o)}, dy)",
                        writes=tuple(f"dy:{s}" for s in own),
                        reads=tuple(f"y:{s}" for s in own))


def _ripple(b: codegen.Builder, parameters: DriveParameters, mech: Any, drive: str
            ) -> tuple[dict[str, str], list[str]]:
    """Torque ripple of the motors the mechanism declares (:attr:`Mechanism.drive_motors`):
    (ripple code per motor name, its lines)."""
    dist = parameters.disturbances
    claimed = {m.ripple: m for m in mech.drive_motors if m.ripple}
    for m in claimed.values():
        if b.q(m.angle) not in b.state_index:
            raise ValueError(f"motor {m.name!r}: its ripple needs its rotor-angle state; "
                             f"{m.angle!r} is no state of the {drive} model")
    for f in dataclasses.fields(dist):
        value = getattr(dist, f.name)
        if (isinstance(value, TorqueRipple) and f.name not in claimed
                and any(a != 0.0 for a in value.amplitudes)):
            raise ParameterError(f"disturbances.{f.name}", value.amplitudes,
                                 f"the {drive} drive has no such motor")
    ripple: dict[str, str] = {}
    lines: list[str] = []
    for motor in claimed.values():
        block = emit_harmonics(b, motor.ripple, getattr(dist, motor.ripple))
        if block is None:
            continue
        key = motor.name
        b.add_aux(f"{key}_ripple_torque", "N m", f"{key} motor torque ripple")
        ripple[key] = f"{{rip_{key}}}"
        lines.append(f"{{rip_{key}}} = {b.use(harmonics)}({{{motor.angle}}}, P, "
                     f"{block[0]}, {block[1]})[0]")
        lines.append(f"{{{key}_ripple_torque}} = {{rip_{key}}}")
    return ripple, lines


def assemble(parameters: DriveParameters, drive: str, table_position: float, nut_hold: str,
             profile: Profile, load: LoadProfile | None = None) -> Model:
    """Build the compiled model of one drive, parameter set and reference profile.

    Each part (mechanism, friction sites and their laws, controller axes, disturbances,
    compensation) declares its slots to a :class:`~feeddrive.model.codegen.Builder`; the
    generated module is compiled once and cached by its source hash.  Hashable inputs are also
    cached in memory.

    Parameters
    ----------
    parameters : DriveParameters
        The parameter set [SI].
    drive : str
        The drive name (``"cdfs"``, ``"ddfs"``, ``"linear-motor"``, ``"rack-pinion"``).
    table_position : float
        Table position at the start [m] (sets the ball screw's K_eq).
    nut_hold : str
        How the CDFS holds its nut: ``"locked"`` or ``"servo"``.
    profile : Profile
        The reference profile.
    load : LoadProfile, optional
        A table load record.

    Returns
    -------
    Model
        The assembled model.

    Raises
    ------
    ParameterError
        When a part refuses the parameters, the drive name or the profile.
    """
    key = (parameters, drive, table_position, nut_hold, profile, load)
    if not _hashable((parameters, load)):  # a load record: build anew
        return _assemble(*key)
    if not _hashable(profile):  # an array profile (a fit's record, a replay): its type's model
        return _with_profile(*key)
    return _assemble_cached(*key)


def _hashable(value: Any) -> bool:
    """Whether ``value`` can key a cache (a profile or load of arrays cannot)."""
    try:
        hash(value)
    except TypeError:
        return False
    return True


@functools.lru_cache(maxsize=64)
def _assemble_cached(parameters: DriveParameters, drive: str, table_position: float,
                     nut_hold: str, profile: Profile, load: LoadProfile | None) -> Model:
    return _with_profile(parameters, drive, table_position, nut_hold, profile, load)


#: the most bytes of ``P`` and ``T`` the kept models hold together: a record's profile (a
#: fit's, a replay's) puts its table in ``T`` (an 8-kHz, 100-s record: 26 MB), and a fit
#: builds one model per parameter point
_TEMPLATES_BYTES = 64 * 2 ** 20


def _template_bytes(entry: tuple[Model, Any, int]) -> int:
    return int(entry[0].P.nbytes + entry[0].T.nbytes)


#: models already built, by everything but the profile's numbers: (model, its mechanism,
#: offset of the profile block in P); 64 at most, within ``_TEMPLATES_BYTES``
_TEMPLATES = Kept(64, _template_bytes, _TEMPLATES_BYTES)


def _with_profile(parameters: DriveParameters, drive: str, table_position: float,
                  nut_hold: str, profile: Profile, load: LoadProfile | None) -> Model:
    """The model of ``profile``: a model already built for another profile of the same type
    (same parameters, drive, position, hold and load) with only the profile's slots of ``P``
    and its table in ``T`` rewritten — the profile's numbers go into those slots only (the
    generated source, the Jacobian pattern and every other slot do not depend on them), so
    the result equals a full :func:`_assemble` (tested field by field) at ~1/50 of the cost
    of building the model again (≈ 1.1 ms per creep trial and per linearisation)."""
    key = (parameters, drive, table_position, nut_hold, type(profile), load)
    entry = _TEMPLATES.get(key)  # under its lock: the explorer runs its jobs on threads
    if entry is None:
        model = _assemble(parameters, drive, table_position, nut_hold, profile, load)
        mech = mechanism(drive)(parameters, drive, table_position, nut_hold)
        _TEMPLATES.put(key, (model, mech, model.parameter_names.index("profile[0]")))
        return model
    model, mech, o = entry
    values, table = profile.encode()
    block = np.zeros(len(PROFILE_PARAMS))
    for k, v in values.items():
        block[k] = v
    mech.check_profile(commanded_references(block, table))
    table = np.ascontiguousarray(table, dtype=float)
    to, columns = int(model.P[o + 5]), int(model.P[o + 6])
    if table.shape != (4, columns):  # another table size: the layout of T differs
        return _assemble(parameters, drive, table_position, nut_hold, profile, load)
    block[5], block[6] = to, columns
    P = model.P.copy()
    P[o:o + block.size] = block
    T = model.T.copy()
    T[to:to + table.size] = table.ravel()
    return dataclasses.replace(model, P=P, T=T)


def _assemble(parameters: DriveParameters, drive: str, table_position: float, nut_hold: str,
              profile: Profile, load: LoadProfile | None) -> Model:
    b = codegen.Builder()
    b.imports["_friction_law"] = "feeddrive.model.friction:friction_law"
    laws, comp = declare_drive(b, parameters, drive, table_position, nut_hold, profile, load)
    return package(b, drive, laws, comp, b.control_axes)


def declare_drive(b: codegen.Builder, parameters: DriveParameters, drive: str,
                  table_position: float, nut_hold: str, profile: Profile,
                  load: LoadProfile | None, *, external_force: bool = False,
                  speed_correction: bool = False
                  ) -> tuple[list[tuple[Site, FrictionLaw, int]], CompensationFootprint | None]:
    """Declare one drive's parts to ``b`` and write their code: the whole of a single-axis
    model, or one axis of a machine inside :meth:`Builder.scope
    <feeddrive.model.codegen.Builder.scope>`.

    Parameters
    ----------
    b : Builder
        The model being assembled.
    parameters, drive, table_position, nut_hold, profile, load
        As :func:`assemble`.
    external_force : bool, default False
        Declare the input signal ``external_force`` [N], a load on the table that a
        machine's coupling part writes (added to the load force: positive opposes positive
        motion).
    speed_correction : bool, default False
        Declare the input signal ``speed_correction`` [m/s], a table speed a machine's
        synchronisation part adds to the first axis' continuous speed command.

    Returns
    -------
    laws : list of (Site, FrictionLaw, int)
        Each friction site, its law and its first state's index.
    compensation : CompensationFootprint or None
        The compensator's footprint.
    """
    mech = mechanism(drive)(parameters, drive, table_position, nut_hold)
    # an open-loop replay imposes one state: set before any part writes code that reads it
    replay = profile if isinstance(profile, Replay) else None
    replayed = declare_replay(b, replay, mech) if replay is not None else None
    mech.declare(b)
    mech.parameters(b)
    sites = mech.sites(b)
    laws: list[tuple[Site, FrictionLaw, int]] = []
    for site in sites:
        site_params = site.parameters(parameters)
        law = friction_law(site_params.law)
        first = len(b.states)
        sizes = law.deflection_scales(site_params)
        for state, size in zip(law.states(site_params), sizes, strict=True):
            b.state(f"{site.name}_{state}", law.state_unit,
                    f"{law.name} {state} state, {site.name.replace('_', '–')} friction",
                    "deflection", size)
        laws.append((site, law, first))
    mech.motors(b)
    axes, channels = mech.axes(b)
    loops.declare_states(b, axes)
    for ax in axes:
        b.tol_scale[b.q(f"{ax.name}_velocity_integral")] = b.param_values[ax.param_offset
                                                                     + loops.H_AX]
    loops.declare_signals(b, axes)
    b.control_axes += loops.control_axes(b, axes)
    for site, law, _ in laws:
        b.add_aux(f"{site.name}_friction", "N",
                  f"{site.name.replace('_', '–')} friction ({law.name}"
                  f"{', torque ÷ H' if site.rotary else ''})")
    b.add_aux("drive_force", "N", "force driving the table (screw–nut force F_d, or motor)")
    b.add_aux("table_position_reference", "m", "commanded table position")
    b.add_aux("table_speed_reference", "m/s", "commanded table speed")
    mech.signals(b)
    _profile(b, profile, mech)
    if replay is not None and replayed is not None:
        emit_replay_value(b, replay, mech, replayed[1], b.param_index[b.q("profile[0]")])
    for ch in channels:
        b.add_held(f"prev.{ch.name}")

    dist = parameters.disturbances
    load_code = emit_load(b, dist.load_force, dist.load_start, load)
    load_aux = load_code is not None
    # the linearisation's load-force input [N] (feeddrive.analysis.linear), zero in a simulation
    o_load = b.param("inputs.load_force", 0.0)
    load_code = f"P[{o_load}]" if load_code is None else f"({load_code} + P[{o_load}])"
    if external_force:
        if b.q("external_force") not in b.aux_index:  # or declared by the part writing it
            b.add_aux("external_force", "N",
                      "force on the table from the machine's coupling parts")
        load_code = f"({load_code} + {{external_force}})"
    ripple, ripple_lines = _ripple(b, parameters, mech, drive)
    lead = emit_harmonics(b, "lead_error", dist.lead_error)
    if lead is not None and not mech.has_lead_screw:
        raise ParameterError("disturbances.lead_error", dist.lead_error.amplitudes,
                             f"the {drive} drive has no lead screw")

    if parameters.controller.position_feedback == "motor" and not mech.has_lead_screw:
        raise ParameterError("controller.position_feedback", "motor",
                             f"the {drive} drive has no motor encoder referred through a lead; "
                             "expected 'table'")
    # the sample schedule: the loops' clocks (the parts' own join in declare_part)
    loops.declare_clocks(b, parameters.controller)

    # ---- right-hand side
    for line in b.references:
        b.emit(line)
    b.emit("{table_position_reference} = {ref_x}")
    b.emit("{table_speed_reference} = {ref_v}")
    if speed_correction:
        if parameters.controller.position_period > 0:
            raise ParameterError("controller.position_period",
                                 parameters.controller.position_period,
                                 "a synchronisation part corrects a continuous position "
                                 "loop; expected 0 [s]")
        if b.q("speed_correction") not in b.aux_index:
            b.add_aux("speed_correction", "m/s", "table speed added to the speed command by "
                      "the machine's synchronisation part")
        h_ax = f"P[{axes[0].param_offset + loops.H_AX}]"
        axes[0] = dataclasses.replace(
            axes[0], speed_correction=f"{{speed_correction}} / {h_ax}")
    comp = emit_compensation(b, parameters, mech, axes[0].name)
    if comp is not None:
        axes[0] = dataclasses.replace(axes[0], extra_current=comp.current)
    # parts of the model given as sections of their own (model/parts/): they declare their
    # slots and may wire into the axes before the cascade, then write their sampled updates
    parts = [s for _, s in parameters.sections if hasattr(s, "declare_part")]
    for part in parts:
        axes = part.declare_part(b, axes)
    loops.emit_cascade(b, axes, channels)
    for part in parts:
        part.emit_part(b)
    for ln in ripple_lines:
        b.emit(ln)
    m = Mechanics(forces={}, always=[], gated=[], frozen=[], ripple=ripple, lead=lead,
                  load=load_code, torque_off=parameters.controller.mode == "torque_off")
    for site, law, first in laws:
        code = _site_code(b, site, law, site.parameters(parameters), first)
        for body, factor in site.bodies:
            term = (f"- {{f_{site.name}}}" if factor == "1.0"
                    else f"- {factor} * {{f_{site.name}}}")
            m.forces.setdefault(body, []).append(term)
        if site.active:
            m.gated.append(code)
            m.frozen.append(f"{{f_{site.name}}} = 0.0")
            m.frozen += [f"{{der({site.name}_{s})}} = 0.0"
                         for s in law.states(site.parameters(parameters))]
        else:
            m.always.append(code)
    mech.emit(b, m)
    if replayed is not None:
        emit_replay_rates(b, *replayed)
    for site, _, _ in laws:
        b.emit(f"{{{site.name}_friction}} = {{f_{site.name}}}")
    b.emit("{drive_force} = {f_d}")
    if load_aux:
        b.emit(f"{{load_force}} = {load_code}")
    return laws, comp


def package(b: codegen.Builder, drive: str, laws: list[tuple[Site, FrictionLaw, int]],
            comp: CompensationFootprint | None,
            control: tuple[loops.ControlAxis, ...] = ()) -> Model:
    """Compile what every part declared to ``b`` into a :class:`Model`.

    Parameters
    ----------
    b : Builder
        The builder every part has declared to.
    drive : str
        The drive (or machine) name the model is built for.
    laws : list of (Site, FrictionLaw, int)
        Each friction site (its model-wide name), its law and first state's index.
    comp : CompensationFootprint or None
        The compensator's footprint.
    control : tuple of ControlAxis, default ()
        Each controller axis' declarations.

    Returns
    -------
    Model
        The assembled model.
    """
    source = codegen.module_source(b)
    module = codegen.compile_module(source, b.dynamic_sources)
    pattern = sparsity.declared_pattern([s.name for s in b.states], [a.name for a in b.aux],
                                        b.flows)
    return Model(
        state_names=tuple(s.name for s in b.states), states=tuple(b.states), aux=tuple(b.aux),
        parameter_names=tuple(b.param_names), P=b.packed_parameters(), T=b.packed_tables(),
        tolerance_kinds=tuple(s.kind for s in b.states),
        tolerance_scales=tuple(b.tol_scale.get(s.name, 1.0) for s in b.states),
        module=module, source=source, drive=drive,
        sites=tuple((site.name, law.name) for site, law, _ in laws),
        jacobian_pattern=pattern, jacobian_colours=sparsity.colour_columns(pattern),
        derived=tuple(b.derived), clocks=tuple(b.clocks),
        flows=tuple((w, tuple(sorted(r))) for w, r in b.flows.items()), compensation=comp,
        control_axes=tuple(control), slot_units=tuple(b.param_units.items()))


def __getattr__(name: str) -> Any:
    """Names that moved from here before 0.2.0: importable until 0.3.0, with a
    DeprecationWarning naming their new place (:mod:`feeddrive._compat`)."""
    from .. import _compat

    return _compat.moved(__name__, name)
