"""One entry point: ``simulate(system, profile, duration, *, options) -> Result``."""

from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass, field

import numpy as np

from . import budget
from . import layout as ix
from .control import ConstantSpeed, Profile, SampledSpeed, SineSpeed
from .parameters import DriveParameters, ParameterError
from .result import Result, build_dataset
from .solvers import dopri5
from .stiffness import axial_stiffness, equivalent_stiffness, torsional_stiffness

DRIVES = ("cdfs", "ddfs")


@dataclass(frozen=True)
class DriveSystem:
    """A drive to simulate: parameters, CDFS or DDFS, and where the table starts.

    ``table_position`` [m] is the distance a of the nut from the motor-side screw support
    (Wang2021 Table 3: 0.2 … 0.6 m; mid-screw 0.4 m).  For the CDFS the hollow motor is held:
    ``nut_hold = "locked"`` removes the nut's degrees of freedom (the default), ``"servo"``
    keeps the hollow motor's position loop active at zero command.
    """

    parameters: DriveParameters
    drive: str = "ddfs"
    table_position: float = 0.4
    nut_hold: str = "locked"

    def __post_init__(self) -> None:
        if self.drive not in DRIVES:
            raise ParameterError("drive", self.drive, "expected cdfs or ddfs")
        if self.nut_hold not in ("locked", "servo"):
            raise ParameterError("nut_hold", self.nut_hold, "expected locked or servo")
        length = self.parameters.screw.length
        a = self.table_position
        if not (math.isfinite(a) and 0.0 < a < length):
            raise ParameterError("table_position", a,
                                 f"expected 0 < a < {length:g} [m] (between the supports)")


@dataclass(frozen=True)
class SolverOptions:
    """Integrator settings, echoed in the result.

    ``method``: ``"dopri5"`` (adaptive) or ``"dopri5-fixed"`` (fixed step ``fixed_step``).
    ``output_interval`` [s] is the spacing of the recorded samples; it is also the breakpoint
    spacing for continuous control.  ``position_tolerance`` [m] and ``speed_tolerance`` [m/s]
    are absolute error targets (angles scaled by H), combined with ``rtol`` on speeds.
    """

    method: str = "dopri5"
    rtol: float = 1e-6
    position_tolerance: float = 1e-10
    speed_tolerance: float = 1e-8
    current_tolerance: float = 1e-6
    output_interval: float = 1e-3
    max_step: float = 1e-3
    fixed_step: float = 1e-5
    max_steps: int = 50_000_000

    def __post_init__(self) -> None:
        if self.method not in ("dopri5", "dopri5-fixed"):
            raise ParameterError("options.method", self.method, "expected dopri5 or dopri5-fixed")
        for name in ("rtol", "position_tolerance", "speed_tolerance", "current_tolerance",
                     "output_interval", "max_step", "fixed_step"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ParameterError(f"options.{name}", v, "expected a finite value > 0")


class SimulationError(RuntimeError):
    """The integrator could not finish; the message says why and where."""


@dataclass
class _Packed:
    P: np.ndarray
    fr_s: np.ndarray
    fr_n: np.ndarray
    fr_g: np.ndarray
    ref_table: np.ndarray
    base: float
    n_pos: int
    n_vel: int
    n_cur: int
    out_every: int
    meta: dict[str, float] = field(default_factory=dict)


def _periods(params: DriveParameters, output_interval: float) -> tuple[float, int, int, int, int]:
    c = params.controller
    periods = [c.position_period, c.velocity_period, c.current_period]
    nonzero = [p for p in periods if p > 0]
    if (c.encoder_counts > 0 or c.grating_resolution > 0) and not (
            c.position_period > 0 and c.velocity_period > 0):
        raise ParameterError("controller.encoder_counts", c.encoder_counts,
                             "quantisation needs sampled position and velocity loops "
                             "(set controller.position_period and velocity_period > 0 [s])")
    base = min(nonzero) if nonzero else output_interval
    n = [int(round(p / base)) if p > 0 else 0 for p in periods]
    out_every = max(1, int(round(output_interval / base)))
    if abs(out_every * base - output_interval) > 1e-9 * output_interval:
        raise ParameterError("options.output_interval", output_interval,
                             f"must be a multiple of the fastest controller period {base:g} [s]")
    return base, n[0], n[1], n[2], out_every


def pack(system: DriveSystem, profile: Profile, options: SolverOptions) -> _Packed:
    """Flatten parameters, profile and options into the solver's arrays."""
    p = system.parameters
    s, c, m = p.screw, p.controller, p.stiffness
    H = s.transmission_ratio
    P = np.zeros(ix.N_PARAM)
    P[ix.H] = H
    P[ix.J_S] = p.screw_motor.inertia + s.shaft_inertia
    P[ix.J_N] = p.hollow_motor.inertia + s.nut_inertia
    P[ix.M_T] = p.table.mass
    P[ix.C_AX] = m.axial_damping
    k_t1 = torsional_stiffness(p.coupling, s)
    # all compliances of Eqs. (3) and (5) except the screw's own (which moves with the table)
    c0 = float(1.0 / axial_stiffness(np.inf, s, m.support_bearing_count))
    if m.include_torsion:
        c0 += H**2 / s.efficiency / k_t1
    P[ix.C0] = c0
    P[ix.EA] = math.pi * s.diameter**2 / 4.0 * s.youngs_modulus
    P[ix.LEN] = s.length
    P[ix.SUPPORT] = 0.0 if m.screw_support == "fixed-fixed" else 1.0
    P[ix.X0] = system.table_position
    if m.equivalent_stiffness > 0:
        P[ix.K_FIXED] = m.equivalent_stiffness
    elif not m.position_dependent:
        P[ix.K_FIXED] = equivalent_stiffness(p, system.table_position)
    for motor, (kt, ke, ll, rr) in ((p.screw_motor, (ix.KT_S, ix.KE_S, ix.L_S, ix.R_S)),
                                    (p.hollow_motor, (ix.KT_N, ix.KE_N, ix.L_N, ix.R_N))):
        P[kt] = motor.torque_constant
        P[ke] = motor.back_emf_constant
        P[ll] = motor.inductance
        P[rr] = motor.resistance
    P[ix.KPP] = c.position_gain
    P[ix.KVP] = c.velocity_gain
    P[ix.KVI] = c.velocity_integral_gain
    P[ix.KIP] = c.current_gain
    P[ix.KII] = c.current_integral_gain
    P[ix.KV] = c.velocity_command_gain
    P[ix.KV_PLACE] = ("none", "position_output", "velocity_error").index(c.kv_placement)
    P[ix.V_BASIS] = ("motor", "table").index(c.velocity_gain_basis)
    P[ix.V_FEEDBACK] = ("motor", "table").index(c.velocity_feedback)
    P[ix.FF] = 1.0 if c.velocity_feedforward else 0.0
    P[ix.NUT_SPEED_MODE] = 1.0 if c.nut_loop == "speed" else 0.0
    P[ix.I_MAX] = c.current_limit
    P[ix.U_MAX] = c.voltage_limit
    P[ix.T_POS] = c.position_period
    P[ix.T_VEL] = c.velocity_period
    P[ix.T_CUR] = c.current_period
    P[ix.ENC_Q] = 2.0 * math.pi / c.encoder_counts if c.encoder_counts > 0 else 0.0
    P[ix.GRAT_Q] = c.grating_resolution
    nut_active = system.drive == "ddfs" or system.nut_hold == "servo"
    P[ix.NUT_ACTIVE] = 1.0 if nut_active else 0.0
    values, table = profile.encode()
    for k, v in values.items():
        P[k] = v
    if system.drive == "cdfs" and (P[ix.REF_VN] != 0.0 or np.any(table[3] != 0.0)):
        raise ParameterError("nut_speed", float(P[ix.REF_VN]),
                             "the CDFS holds the hollow motor; expected 0 [m/s]")
    base, n_pos, n_vel, n_cur, out_every = _periods(p, options.output_interval)
    return _Packed(P=P, fr_s=p.friction.screw.as_array(), fr_n=p.friction.nut.as_array(),
                   fr_g=p.friction.guide.as_array(), ref_table=np.ascontiguousarray(table),
                   base=base, n_pos=n_pos, n_vel=n_vel, n_cur=n_cur, out_every=out_every)


def tolerances(H: float, options: SolverOptions) -> tuple[np.ndarray, np.ndarray]:
    """(absolute tolerance, relative-tolerance mask) per state."""
    pos, spd, cur = options.position_tolerance, options.speed_tolerance, options.current_tolerance
    atol = np.empty(ix.N_STATE)
    rel = np.zeros(ix.N_STATE)
    atol[[ix.TH_S, ix.TH_N]] = pos / H
    atol[[ix.W_S, ix.W_N]] = spd / H
    atol[ix.X_T] = pos
    atol[ix.V_T] = spd
    atol[[ix.Z_S, ix.Z_N, ix.Z_G]] = pos
    atol[[ix.I_S, ix.I_N]] = cur
    atol[[ix.IV_S, ix.IV_N]] = pos / H
    atol[[ix.IC_S, ix.IC_N]] = cur * 1e-3
    rel[[ix.W_S, ix.W_N, ix.V_T, ix.I_S, ix.I_N]] = 1.0
    return atol, rel


def _check_budget(system: DriveSystem, packed: _Packed, options: SolverOptions, t_end: float,
                  n_break: int, adaptive: int, atol: np.ndarray, rel: np.ndarray,
                  h_init: float, h_max: float) -> None:
    """Refuse, before integrating, a run whose output would not fit in memory or whose
    steps (projected from a short probe) exceed ``max_steps`` (feeddrive.budget)."""
    budget.check_output_memory(t_end, options.output_interval, n_break, options.max_steps)
    t_probe = budget.probe_time(t_end, packed.base) if adaptive else 0.0
    if not t_probe:
        return
    allowed = int(options.max_steps * t_probe / t_end) + 1000
    _, _, _, stats, _ = dopri5.integrate(
        np.zeros(ix.N_STATE), t_probe, packed.out_every, packed.base, packed.n_pos,
        packed.n_vel, packed.n_cur, packed.P, packed.fr_s, packed.fr_n, packed.fr_g,
        packed.ref_table, options.rtol, atol, rel, h_init, h_max, adaptive, allowed)
    if int(stats[0]) in (dopri5.STATUS_OK, dopri5.STATUS_MAX_STEPS) and stats[4] > 0:
        speed = float(packed.P[ix.REF_VT]) or float(np.max(np.abs(packed.ref_table[1]),
                                                           initial=1e-3))
        budget.check_step_rate(steps=int(stats[1]), probe_time=float(stats[4]),
                               duration=t_end, max_steps=options.max_steps,
                               params=system.parameters, drive=system.drive, speed=speed)


def simulate(system: DriveSystem, profile: Profile, duration: float, *,
             options: SolverOptions | None = None) -> Result:
    """Simulate ``system`` following ``profile`` for ``duration`` [s] from rest.

    Returns a :class:`Result` (xarray Dataset with named signals and units).  Raises
    :class:`SimulationError` if the integrator fails (never returns NaN silently).
    """
    options = options or SolverOptions()
    if not (isinstance(duration, int | float) and math.isfinite(duration) and duration > 0):
        raise ParameterError("duration", duration, "expected a finite time > 0 [s]")
    if not isinstance(profile, ConstantSpeed | SineSpeed | SampledSpeed):
        raise ParameterError("profile", type(profile).__name__,
                             "expected ConstantSpeed, SineSpeed or SampledSpeed")
    packed = pack(system, profile, options)
    n_break = int(round(duration / packed.base))
    t_end = n_break * packed.base
    H = packed.P[ix.H]
    atol, rel = tolerances(H, options)
    adaptive = 1 if options.method == "dopri5" else 0
    h_init = 1e-6 if adaptive else options.fixed_step
    h_max = min(options.max_step, packed.base) if adaptive else options.fixed_step
    y0 = np.zeros(ix.N_STATE)
    _check_budget(system, packed, options, t_end, n_break, adaptive, atol, rel, h_init, h_max)
    started = _time.perf_counter()
    t, y, aux, stats, _ = dopri5.integrate(
        y0, t_end, packed.out_every, packed.base, packed.n_pos, packed.n_vel, packed.n_cur,
        packed.P, packed.fr_s, packed.fr_n, packed.fr_g, packed.ref_table, options.rtol, atol,
        rel, h_init, h_max, adaptive, options.max_steps)
    wall = _time.perf_counter() - started
    status = int(stats[0])
    if status != dopri5.STATUS_OK:
        raise SimulationError(
            f"integration stopped at t = {stats[4]:.6g} s of {t_end:g} s: "
            f"{dopri5.STATUS_MESSAGES[status]} (steps {int(stats[1])}, rejected "
            f"{int(stats[2])}); raise max_steps (--max-steps) or check the parameters")
    solver_stats = {
        "method": options.method, "rtol": options.rtol,
        "position_tolerance": options.position_tolerance,
        "speed_tolerance": options.speed_tolerance,
        "steps": int(stats[1]), "rejected_steps": int(stats[2]),
        "rhs_evaluations": int(stats[3]), "wall_time_s": wall,
        "breakpoint_interval_s": packed.base,
    }
    dataset = build_dataset(t, y, aux, system, profile, solver_stats)
    return Result(dataset)
