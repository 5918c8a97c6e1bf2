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

from ..parameters import DriveParameters, ParameterError
from . import codegen, loops, sparsity
from .compensation import emit_compensation
from .disturbances import LoadProfile, emit_harmonics, emit_load, harmonics
from .friction import FrictionLaw, friction_law
from .mechanisms import Mechanics, Site, mechanism
from .reference import PROFILE_PARAMS, REFERENCE_INPUTS, reference_with_inputs

if TYPE_CHECKING:
    from .reference import Profile


@dataclass(frozen=True)
class Model:
    """An assembled drive model: names, packed numbers and its compiled module."""

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
    # the sample schedule: (name, index in P of its period [s]) per clock (Builder.clock)
    clocks: tuple[tuple[str, int], ...] = ()

    @property
    def n_held(self) -> int:
        return int(self.module.N_HELD)

    def periods(self, P: np.ndarray | None = None) -> dict[str, float]:
        """Sample period [s] of every clock of the schedule by name (0: continuous), read from
        the parameter vector ``P`` (default: the model's)."""
        P = self.P if P is None else P
        return {name: float(P[k]) for name, k in self.clocks}

    def continuous_ticks(self) -> np.ndarray:
        """The ``tick`` argument of ``sample_update`` with no clock due (all −1)."""
        return np.full(int(self.module.N_CLOCK), -1, dtype=np.int64)

    def index(self, name: str) -> int:
        """Position of state ``name`` in the state vector."""
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

    def tolerances(self, position: float, speed: float, current: float
                   ) -> tuple[np.ndarray, np.ndarray]:
        """(absolute tolerance, relative-tolerance mask) per state."""
        atol = np.empty(len(self.states))
        rel = np.zeros(len(self.states))
        for i, (kind, scale) in enumerate(zip(self.tolerance_kinds, self.tolerance_scales,
                                              strict=True)):
            atol[i] = {"position": position, "speed": speed, "angle": position / scale,
                       "rotary_speed": speed / scale, "current": current,
                       "current_integral": current * 1e-3,
                       "velocity_integral": position / scale, "none": position}[kind]
            rel[i] = 1.0 if kind in codegen.RELATIVE_KINDS else 0.0
        return atol, rel


def _profile(b: codegen.Builder, profile: Profile, mech: Any) -> None:
    values, table = profile.encode()
    block = np.zeros(len(PROFILE_PARAMS))
    for k, v in values.items():
        block[k] = v
    mech.check_profile(float(block[2]), table[3])
    table = np.ascontiguousarray(table, dtype=float)
    block[5] = b.table(table)
    block[6] = table.shape[1]
    o = b.params("profile", block)
    # the linearisation's reference inputs (feeddrive.analysis.linear), zero in a simulation
    oi = b.param(f"inputs.{REFERENCE_INPUTS[0]}", 0.0)
    for name in REFERENCE_INPUTS[1:]:
        b.param(f"inputs.{name}", 0.0)
    b.reference_call = f"{b.use(reference_with_inputs)}(t, P, {o}, {oi}, T)"


def _site_code(b: codegen.Builder, site: Site, law: FrictionLaw, params: Any,
               y_offset: int) -> str:
    packed = law.pack(params.scaled(site.scale) if site.scale != 1.0 else params)
    o = b.named_params(f"friction.{site.name}", law.site_slots(params), packed)
    alias = b.use_dynamic(f"_law_{law.name.replace('-', '_')}",
                          f"_friction_law({law.name!r}).compiled", law.compiled)
    b.local_kernel(alias, len(law.states(params)))
    return f"f_{site.name} = {alias}({site.speed}, y, {y_offset}, P, {o}, dy)"


def assemble(parameters: DriveParameters, drive: str, table_position: float, nut_hold: str,
             profile: Profile, load: LoadProfile | None = None) -> Model:
    """Build (or fetch from the cache) the compiled model of one drive and profile."""
    key = (parameters, drive, table_position, nut_hold, profile, load)
    try:
        return _assemble_cached(*key)
    except TypeError:  # unhashable inputs (array profiles, load records): build anew
        return _assemble(*key)


@functools.lru_cache(maxsize=64)
def _assemble_cached(parameters: DriveParameters, drive: str, table_position: float,
                     nut_hold: str, profile: Profile, load: LoadProfile | None) -> Model:
    return _assemble(parameters, drive, table_position, nut_hold, profile, load)


def _assemble(parameters: DriveParameters, drive: str, table_position: float, nut_hold: str,
              profile: Profile, load: LoadProfile | None) -> Model:
    b = codegen.Builder()
    b.imports["_friction_law"] = "feeddrive.model.friction:friction_law"
    mech = mechanism(drive)(parameters, drive, table_position, nut_hold)
    mech.declare(b)
    mech.parameters(b)
    sites = mech.sites(b)
    laws: list[tuple[Site, FrictionLaw, int]] = []
    for site in sites:
        site_params = site.parameters(parameters)
        law = friction_law(site_params.law)
        first = len(b.states)
        for state in law.states(site_params):
            b.state(f"{site.name}_{state}", law.state_unit,
                    f"{law.name} {state} state, {site.name.replace('_', '–')} friction",
                    "position")
        laws.append((site, law, first))
    mech.motors(b)
    axes, channels = mech.axes(b)
    loops.declare_states(b, axes)
    for ax in axes:
        b.tol_scale[f"{ax.name}_velocity_integral"] = b.param_values[ax.param_offset
                                                                     + loops.H_AX]
    loops.declare_signals(b, axes)
    for site, law, _ in laws:
        b.add_aux(f"{site.name}_friction", "N",
                  f"{site.name.replace('_', '–')} friction ({law.name}"
                  f"{', torque ÷ H' if site.name != 'guide' else ''})")
    b.add_aux("drive_force", "N", "force driving the table (screw–nut force F_d, or motor)")
    b.add_aux("table_position_reference", "m", "commanded table position")
    b.add_aux("table_speed_reference", "m/s", "commanded table speed")
    mech.signals(b)
    _profile(b, profile, mech)
    for ch in channels:
        b.add_held(f"prev.{ch.name}")

    dist = parameters.disturbances
    load_code = emit_load(b, dist.load_force, dist.load_start, load)
    load_aux = load_code is not None
    # the linearisation's load-force input [N] (feeddrive.analysis.linear), zero in a simulation
    o_load = b.param("inputs.load_force", 0.0)
    load_code = f"P[{o_load}]" if load_code is None else f"({load_code} + P[{o_load}])"
    ripple: dict[str, str] = {}
    ripple_lines: list[str] = []
    for key, r in (("screw", dist.screw_motor_ripple), ("nut", dist.hollow_motor_ripple)):
        field = f"{'screw' if key == 'screw' else 'hollow'}_motor_ripple"
        block = emit_harmonics(b, field, r)
        if block is None:
            continue
        if key not in mech.ripple_motors:
            raise ParameterError(f"disturbances.{field}", r.amplitudes,
                                 f"the {drive} drive has no such motor")
        b.add_aux(f"{key}_ripple_torque", "N m", f"{key} motor torque ripple")
        ripple[key] = f"rip_{key}"
        ripple_lines.append(f"rip_{key} = {b.use(harmonics)}({b.y(key + '_angle')}, P, "
                            f"{block[0]}, {block[1]})[0]")
        ripple_lines.append(f"{b.a(key + '_ripple_torque')} = rip_{key}")
    lead = emit_harmonics(b, "lead_error", dist.lead_error)
    if lead is not None and not mech.has_lead_screw:
        raise ParameterError("disturbances.lead_error", dist.lead_error.amplitudes,
                             f"the {drive} drive has no lead screw")

    # the sample schedule: the loops' clocks (the parts' own join in declare_part)
    loops.declare_clocks(b, parameters.controller)

    # ---- right-hand side
    b.emit(f"ref_x, ref_v, ref_xn, ref_vn = {b.reference_call}")
    b.emit(f"{b.a('table_position_reference')} = ref_x")
    b.emit(f"{b.a('table_speed_reference')} = ref_v")
    comp = emit_compensation(b, parameters, mech)
    if comp is not None:
        axes[0] = dataclasses.replace(axes[0], extra_current=comp)
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
            term = f"- f_{site.name}" if factor == "1.0" else f"- {factor} * f_{site.name}"
            m.forces.setdefault(body, []).append(term)
        if site.active:
            m.gated.append(code)
            m.frozen.append(f"f_{site.name} = 0.0")
            m.frozen += [f"{b.dy(f'{site.name}_{s}')} = 0.0"
                         for s in law.states(site.parameters(parameters))]
        else:
            m.always.append(code)
    mech.emit(b, m)
    for site, _, _ in laws:
        b.emit(f"{b.a(site.name + '_friction')} = f_{site.name}")
    b.emit(f"{b.a('drive_force')} = f_d")
    if load_aux:
        b.emit(f"{b.a('load_force')} = {load_code}")

    source = codegen.module_source(b, solver_sources())
    module = codegen.compile_module(source, b.dynamic_sources)
    pattern = sparsity.jacobian_pattern(codegen.rhs_source(b), len(b.states),
                                        frozenset(b.imports), b.local_kernels)
    return Model(
        state_names=tuple(s.name for s in b.states), states=tuple(b.states), aux=tuple(b.aux),
        parameter_names=tuple(b.param_names), P=b.packed_parameters(), T=b.packed_tables(),
        tolerance_kinds=tuple(s.kind for s in b.states),
        tolerance_scales=tuple(b.tol_scale.get(s.name, 1.0) for s in b.states),
        module=module, source=source, drive=drive,
        sites=tuple((site.name, law.name) for site, law, _ in laws),
        jacobian_pattern=pattern, jacobian_colours=sparsity.colour_columns(pattern),
        derived=tuple(b.derived), clocks=tuple(b.clocks))


@functools.cache
def solver_sources() -> list[str]:
    """The integrator templates placed in every generated module (DOPRI5 as in engine v1, and
    the dense-output DOPRI5 ⇄ RODAS4 driver).  numba compiles each at its first call, so a
    model only ever run with one method never compiles the other.  Cached: reading template
    sources with ``inspect`` costs ~15 ms, more than a short simulation."""
    from ..solvers import dopri5, rodas4, steps, switching

    return (steps.template_sources() + rodas4.template_sources() + dopri5.template_sources()
            + switching.template_sources())



