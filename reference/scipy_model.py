"""Reference right-hand side of the closed-loop feed drives, in plain Python (no numba).

An independent implementation of the model the compiled engine integrates, written from the
equations (Wang2021 Eqs. (2)–(11), Tables 1–2), the cited friction laws and the documented
parts of ``feeddrive.model`` (mechanisms, friction laws, loops, disturbances).  It shares no
code with the engine's kernels: only the parameter dataclasses (``feeddrive.parameters``) are
read.  It serves as

* the baseline of ``benchmarks/bench_engine.py`` (``scipy.integrate.solve_ivp`` with this RHS),
* the model of the tight-tolerance Radau references (``reference/make_radau_reference.py``),
* the other side of the RHS cross-checks in ``tests/validation/test_engine_accuracy.py`` and
  ``tests/validation/test_reference_parts.py``,
* with ``reference/sampled.py``, the zero-order-hold reference for sampled control
  (``tests/validation/test_reference_sampled.py``).

Scope: now covers

* the topologies: CDFS and DDFS (ball screw; CDFS nut ``locked`` or on its ``servo``),
  the linear-motor direct drive and the rack and pinion (continuous loops);
* per friction site the laws ``lugre``, ``stribeck`` (smoothed static), ``dahl``,
  ``gms`` (generalized Maxwell slip, Al-Bender, Lampaert & Swevers 2005) and ``none``; the
  ball–nut share f of the screw-shaft friction; and, for truths the fit's model lacks, a
  LuGre site whose Stribeck curve has another exponent (``stribeck_exponents``);
* disturbances: the table load force (constant from a start time, plus a sampled record),
  motor torque ripple of both ball-screw motors, screw lead error;
* ``controller.mode`` ``cascade`` and ``torque_off``;
* continuous loops in :meth:`ReferenceModel.rhs`, and sampled (zero-order-hold) position,
  velocity and current loops with encoder/grating quantisation, where ``rhs`` holds the
  sampled outputs of :class:`Held` and ``reference.sampled`` updates them;
* ``ConstantSpeed`` (with start ramp) and ``SineSpeed`` profiles.

SI units throughout.

The model
---------
States, in the engine's order (``model.state_names``): the mechanism's (θ_s, ω_s, θ_n, ω_n
[rad, rad/s], x_t, v_t [m, m/s] for the ball screw; x_t, v_t for the linear motor); the
friction laws' states site by site (screw, nut, guide, ball_nut; one bristle/pre-sliding
deflection [m] for LuGre and Dahl, none for the static laws; the screw site is absent at
f = 1, the ball–nut site at f = 0); the motor currents [A]; the velocity-loop integrals of
every motor; the current-loop integrals.  ``STATE_NAMES`` is the default ball-screw layout
(LuGre everywhere, f = 0).

Ball screw (Wang2021 Eqs. (7)–(8); the CDFS is the DDFS with the nut held, Sect. 2)::

    θ_r     = θ_s − θ_n,   δ(θ_r) = Σ a_k sin(n_k θ_r + φ_k)            (lead error)
    F_d     = K_eq(a)·[H θ_r + δ − x_t] + c_ax·[(H + δ')(ω_s − ω_n) − v_t]
    J_s ω̇_s = K_t i_s + T_rs(θ_s) − H·(1 − f)·F_screw(Hω_s) − H·f·F_bn(H(ω_s − ω_n)) − (H + δ')·F_d
    J_n ω̇_n = K_t i_n + T_rn(θ_n) − H·F_nut(Hω_n) + H·f·F_bn + (H + δ')·F_d
    m_t v̇_t = F_d − F_guide(v_t) − F_load(t)
    L i̇     = u − R i − K_e ω

with J_s = screw-motor + screw-shaft inertia, J_n = hollow-motor + nut inertia, H = p_h/2π,
T_r(θ) = Σ A_k sin(n_k θ + φ_k) the torque ripple of a motor at its shaft angle.  With the nut
held (CDFS ``locked``) every nut state is frozen (the ball–nut contact still slides at Hω_s).
``torque_off``: the motor torque K_t i is not applied and the currents are frozen; the
controller still runs (its integrals evolve) but drives nothing.

Linear motor (a direct-drive table, forcer on the table)::

    (m_t + m_f) v̇_t = K_f i − F_guide(v_t) − F_load(t),     L i̇ = u − R i − K_e v_t

Friction laws, per site, in Table 1's linear ÷H form (branch by the sign of v, + for v ≥ 0),
with G(v) = F_c + (F_s − F_c)·exp(−(v/v_s)²)::

    LuGre  (Canudas de Wit et al., IEEE TAC 40 (1995) 419; Eqs. (9)–(11)):
        ż = v − σ0·|v|·z / G(v),   F = σ0 z + σ1 ż + σ2 v
    Dahl   (Dahl 1968; Olsson et al., Eur. J. Control 4 (1998) 176, Eq. (9), i = 1):
        ż = v − σ0·|v|·z / F_c,    F = σ0 z + σ2 v
    static (Armstrong-Hélouvry et al., Automatica 30 (1994) 1083; tanh-smoothed sign):
        F = tanh(v/v_ε)·G(v) + σ2 v
    none:  F = 0

The ball–nut share f multiplies a site's force (the screw site by 1 − f, the ball–nut site by
f); its internal dynamics are those of the unscaled site.

K_eq (Eqs. (2)–(5)) at a = x0 + x_t, the nut's distance from the motor-side support::

    1/K_eq = n_b/K_ba + 1/K_sa(a) + 1/K_na + 1/K_nba + H²/(η·K_t1),   1/K_t1 = 1/K_c + 1/K_sθ
    K_sa   = πd²E·l/(4a(l − a))  (fixed–fixed)  or  πd²E/(4a)  (fixed–free)

(a kept within 0.1 % of the length from either support; the torsion term only if
``stiffness.include_torsion``; a positive ``stiffness.equivalent_stiffness`` overrides the chain;
``position_dependent = False`` freezes it at the start position).

Cascade, per motor (Wang2021 Sect. 2.1, Fig. 2; the choices are the engine's options)::

    screw:  Δx = x_ref − x_t                (table position, grating ruler)
            ω_cmd = (k_p·Δx + FF·(v_ref + v_n,ref)) / H
    nut:    Δx = x_n,ref − H θ_n            (hollow-motor encoder); with
            controller.nut_loop = "speed" there is no nut position loop: ω_cmd = v_n,ref/H
            ω_cmd = (k_p·Δx + FF·v_n,ref) / H
    linear motor: as the screw with H = 1, Δx = x_ref − x_t, feed-forward v_ref, v_meas = v_t
            k_p = K_pp, or K_v·K_pp with kv_placement = "position_output"
    e_ω   = (ω_cmd − ω_meas) · [H if velocity_gain_basis = "table"] / [K_v if kv_placement =
            "velocity_error"];  ω_meas = ω_s, or (v_t + Hω_n)/H for the screw with
            velocity_feedback = "table"
    i_cmd = sat(K_vp e_ω + K_vi ∫e_ω, I_max)
    u     = sat(K_ip (i_cmd − i) + K_ii ∫(i_cmd − i), U_max)

Integrals stop integrating into a saturated output (conditional anti-windup): the rate is 0
when the unsaturated output exceeds the limit and the error would push it further.  An
integral whose gain is 0 is frozen.

Sampled loops (a period > 0) hold their output between sample instants; see
``reference/sampled.py`` for the update (position → velocity → current at each instant, the
velocity loop measuring speed as the quantised position difference over its period when an
encoder or grating is set).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from feeddrive.model.friction.lugre_parameters import LuGreParameters
from feeddrive.parameters import DriveParameters

STATE_NAMES = (
    "screw_angle", "screw_speed", "nut_angle", "nut_speed", "table_position", "table_speed",
    "screw_bristle", "nut_bristle", "guide_bristle", "screw_current", "nut_current",
    "screw_velocity_integral", "nut_velocity_integral", "screw_current_integral",
    "nut_current_integral",
)
N_STATE = len(STATE_NAMES)

DRIVES = ("cdfs", "ddfs", "linear-motor", "rack-pinion")


# ---------------------------------------------------------------- friction laws


def _stribeck_curve(fc: float, fs: float, vs: float, v: float) -> float:
    """G(v) = F_c + (F_s − F_c)·exp(−(v/v_s)²) [N]."""
    return fc + (fs - fc) * math.exp(-(v / vs) ** 2)


@dataclass(frozen=True)
class _Branches:
    """A site's Table-1 numbers per direction (index 0: v ≥ 0, 1: v < 0)."""

    coulomb: tuple[float, float]  # F_c (magnitudes) [N]
    static: tuple[float, float]  # F_s [N]
    stribeck: tuple[float, float]  # v_s [m/s]
    viscous: tuple[float, float]  # σ2 [N s/m]
    sigma0: float  # [N/m]
    sigma1: float  # [N s/m]

    @classmethod
    def of(cls, p: LuGreParameters) -> _Branches:
        pos, neg = p.positive, p.negative
        return cls(coulomb=(pos.coulomb_force, neg.coulomb_force),
                   static=(pos.static_force, neg.static_force),
                   stribeck=(pos.stribeck_velocity, neg.stribeck_velocity),
                   viscous=(pos.viscous_coefficient, neg.viscous_coefficient),
                   sigma0=p.bristle_stiffness, sigma1=p.bristle_damping)


@dataclass(frozen=True)
class LuGre(_Branches):
    """LuGre: forces [N], speeds [m/s], bristle deflection [m]."""

    states = ("bristle",)

    @classmethod
    def from_parameters(cls, p: LuGreParameters) -> LuGre:
        b = _Branches.of(p)
        return cls(b.coulomb, b.static, b.stribeck, b.viscous, b.sigma0, b.sigma1)

    def force_and_rate(self, v: float, z: float) -> tuple[float, float]:
        """(friction force F [N], bristle rate ż [m/s]) at sliding speed v and deflection z."""
        b = 0 if v >= 0.0 else 1
        G = _stribeck_curve(self.coulomb[b], self.static[b], self.stribeck[b], v)
        zdot = v - self.sigma0 * abs(v) * z / G
        return self.sigma0 * z + self.sigma1 * zdot + self.viscous[b] * v, zdot


@dataclass(frozen=True)
class Dahl(_Branches):
    """Dahl: Coulomb level F_c per direction, pre-sliding stiffness σ0, viscous σ2."""

    states = ("bristle",)

    @classmethod
    def from_parameters(cls, p: LuGreParameters) -> Dahl:
        b = _Branches.of(p)
        return cls(b.coulomb, b.static, b.stribeck, b.viscous, b.sigma0, b.sigma1)

    def force_and_rate(self, v: float, z: float) -> tuple[float, float]:
        b = 0 if v >= 0.0 else 1
        zdot = v - self.sigma0 * abs(v) * z / self.coulomb[b]
        return self.sigma0 * z + self.viscous[b] * v, zdot


@dataclass(frozen=True)
class StaticStribeck(_Branches):
    """Stribeck + Coulomb + viscous steady curve, sign smoothed by tanh(v/v_ε); no state."""

    smoothing: float = 1e-6  # v_ε [m/s]
    states = ()

    @classmethod
    def from_parameters(cls, p: LuGreParameters) -> StaticStribeck:
        b = _Branches.of(p)
        return cls(b.coulomb, b.static, b.stribeck, b.viscous, b.sigma0, b.sigma1,
                   smoothing=p.smoothing_velocity)

    def force(self, v: float) -> float:
        b = 0 if v >= 0.0 else 1
        return (math.tanh(v / self.smoothing)
                * _stribeck_curve(self.coulomb[b], self.static[b], self.stribeck[b], v)
                + self.viscous[b] * v)


@dataclass(frozen=True)
class NoFriction:
    states = ()

    @classmethod
    def from_parameters(cls, p: LuGreParameters) -> NoFriction:
        return cls()

    def force(self, v: float) -> float:
        return 0.0


@dataclass(frozen=True)
class GMS:
    """Generalized Maxwell slip (Al-Bender, Lampaert & Swevers, IEEE TAC 50 (2005)
    1883–1887), written from the paper: N elements with stiffness k_i [N/m], weight α_i and
    deflection δ_i [m]; an element sticks (dδ_i/dt = v) until its force k_i·δ_i in the
    direction of motion reaches (1 − margin)·α_i·|s(v)|, then slips,
    dF_i/dt = sgn(v)·C·(α_i − F_i/s(v)) with s(v) = sgn(v)·G(v), G the Stribeck curve;
    F = Σ F_i + σ2·v.  The slip margin is ``GMSParameters.slip_margin``."""

    branches: _Branches
    attraction: float  # C [N/s]
    stiffness: tuple[float, ...]  # k_i [N/m]
    weight: tuple[float, ...]  # α_i [-]
    margin: float  # [-]

    @classmethod
    def from_parameters(cls, p: Any) -> GMS:
        pos, neg = p.positive, p.negative
        b = _Branches(coulomb=(pos.coulomb_force, neg.coulomb_force),
                      static=(pos.static_force, neg.static_force),
                      stribeck=(pos.stribeck_velocity, neg.stribeck_velocity),
                      viscous=(pos.viscous_coefficient, neg.viscous_coefficient),
                      sigma0=0.0, sigma1=0.0)
        return cls(b, p.attraction, tuple(p.element_stiffness), tuple(p.element_weight),
                   p.slip_margin)

    @property
    def states(self) -> tuple[str, ...]:
        # the engine's names; a deflection's tolerance and typical size (``_kind``)
        return tuple(f"element{i}" for i in range(len(self.stiffness)))

    def force_and_rates(self, v: float, z: np.ndarray) -> tuple[float, np.ndarray]:
        """(friction force F [N], element rates dδ_i/dt [m/s]) at speed v, deflections z."""
        b = 0 if v >= 0.0 else 1
        br = self.branches
        g = _stribeck_curve(br.coulomb[b], br.static[b], br.stribeck[b], v)
        sgn = 1.0 if v >= 0.0 else -1.0
        rates = np.empty(len(self.stiffness))
        force = 0.0
        for i, (k, a) in enumerate(zip(self.stiffness, self.weight, strict=True)):
            f = k * z[i]
            if v != 0.0 and f * sgn >= (1.0 - self.margin) * a * g:
                rates[i] = sgn * self.attraction * (a - f * sgn / g) / k
            else:
                rates[i] = v
            force += f
        return force + br.viscous[b] * v, rates


@dataclass(frozen=True)
class ShapedLuGre(LuGre):
    """LuGre whose Stribeck curve is G(v) = F_c + (F_s − F_c)·exp(−|v/v_s|^δ) with an
    exponent δ other than LuGre's 2 (Armstrong-Hélouvry, Dupont & Canudas de Wit,
    Automatica 30 (1994) 1083–1138, review the exponents 0.5–2 measured on machines): a truth
    the fitted model lacks (``ReferenceModel(..., stribeck_exponents={site: δ})``)."""

    exponent: float = 2.0

    def force_and_rate(self, v: float, z: float) -> tuple[float, float]:
        b = 0 if v >= 0.0 else 1
        fc, fs, vs = self.coulomb[b], self.static[b], self.stribeck[b]
        G = fc + (fs - fc) * math.exp(-abs(v / vs) ** self.exponent)
        zdot = v - self.sigma0 * abs(v) * z / G
        return self.sigma0 * z + self.sigma1 * zdot + self.viscous[b] * v, zdot


LAWS: dict[str, Any] = {"lugre": LuGre, "dahl": Dahl, "stribeck": StaticStribeck,
                        "gms": GMS, "none": NoFriction}


def friction_law(p: LuGreParameters) -> Any:
    """The reference's implementation of a site's ``law``."""
    if p.law not in LAWS:
        raise ValueError(f"friction law {p.law!r}: the reference model knows "
                         f"{', '.join(LAWS)}")
    return LAWS[p.law].from_parameters(p)


@dataclass(frozen=True)
class _Site:
    name: str
    law: Any
    scale: float  # share of the site's force (ball–nut split)
    index: int  # of its state in y, −1 when the law has none


def _site_force(site: _Site, v: float, y: Any, dy: np.ndarray) -> float:
    if site.index < 0:
        return site.scale * site.law.force(v)
    if isinstance(site.law, GMS):
        n = len(site.law.states)
        F, rates = site.law.force_and_rates(v, y[site.index:site.index + n])
        dy[site.index:site.index + n] = rates
        return site.scale * F
    F, zdot = site.law.force_and_rate(v, y[site.index])
    dy[site.index] = zdot
    return site.scale * F


# ---------------------------------------------------------------- disturbances


@dataclass(frozen=True)
class Harmonics:
    """s(θ) = Σ_k A_k sin(n_k θ + φ_k) and ds/dθ (torque ripple [N m], lead error [m])."""

    orders: tuple[float, ...]
    amplitudes: tuple[float, ...]
    phases: tuple[float, ...]

    @classmethod
    def of(cls, series: Any) -> Harmonics | None:
        if not any(a != 0.0 for a in series.amplitudes):
            return None
        return cls(tuple(series.orders), tuple(series.amplitudes), tuple(series.phases))

    def value_and_slope(self, theta: float) -> tuple[float, float]:
        s = ds = 0.0
        for n, a, phi in zip(self.orders, self.amplitudes, self.phases, strict=True):
            s += a * math.sin(n * theta + phi)
            ds += a * n * math.cos(n * theta + phi)
        return s, ds


@dataclass(frozen=True)
class Load:
    """Table load force [N] against positive motion: ``force`` from ``start`` [s] on, plus a
    record (any object with uniform ``time`` from 0 and ``force`` arrays, e.g.
    ``feeddrive.LoadProfile``) interpolated linearly, its last value held after its end."""

    force: float
    start: float
    record_time: np.ndarray | None = None
    record_force: np.ndarray | None = None

    def __call__(self, t: float) -> float:
        f = self.force if t >= self.start else 0.0
        if self.record_time is not None and self.record_force is not None:
            f += float(np.interp(t, self.record_time, self.record_force))
        return f


# ---------------------------------------------------------------- reference profiles


def _profile_kind(profile: Any) -> str:
    if profile is None:
        return "rest"
    if all(hasattr(profile, a) for a in ("table_speed", "nut_speed", "ramp_time")):
        return "constant"
    if all(hasattr(profile, a) for a in ("table_amplitude", "nut_amplitude", "frequency")):
        return "sine"
    if callable(getattr(profile, "signals", None)):
        return "custom"
    raise ValueError(f"profile {type(profile).__name__}: the reference model handles "
                     "ConstantSpeed, SineSpeed and profiles with signals(t) only")


def reference_signals(profile: Any, t: float) -> tuple[float, float, float, float]:
    """(x_ref, v_ref, x_n,ref, v_n,ref) [m, m/s] of a ConstantSpeed or SineSpeed profile, or
    of any profile with a ``signals(t)`` method that returns them.

    Constant speed: the speed rises linearly over ``ramp_time`` then stays; positions are
    its integral.  Sine: v = A·sin(2πft), x = A·(1 − cos 2πft)/(2πf).  ``None``: at rest.
    """
    kind = _profile_kind(profile)
    if kind == "rest":
        return 0.0, 0.0, 0.0, 0.0
    if kind == "custom":  # e.g. reference.emps_record.MinimumJerk
        return tuple(profile.signals(t))  # type: ignore[return-value]
    if kind == "constant":
        vt, vn, tr = profile.table_speed, profile.nut_speed, profile.ramp_time
        if tr > 0.0 and t < tr:
            s = t / tr
            return 0.5 * vt * t * s, vt * s, 0.5 * vn * t * s, vn * s
        return vt * (t - 0.5 * tr), vt, vn * (t - 0.5 * tr), vn
    w = 2.0 * math.pi * profile.frequency
    s, c = math.sin(w * t), math.cos(w * t)
    return (profile.table_amplitude * (1.0 - c) / w, profile.table_amplitude * s,
            profile.nut_amplitude * (1.0 - c) / w, profile.nut_amplitude * s)


# ---------------------------------------------------------------- the loops


def _saturate(x: float, limit: float) -> float:
    return limit if x > limit else (-limit if x < -limit else x)


def _integral_rate(error: float, unsaturated: float, limit: float) -> float:
    """Conditional integration: hold the integral while the output is pushed into its limit."""
    if (unsaturated > limit and error > 0.0) or (unsaturated < -limit and error < 0.0):
        return 0.0
    return error


@dataclass
class Axis:
    """One motor's cascade: its transmission H [m/rad] (1 for a linear motor), what it
    measures (as linear maps of the state, so that sampled loops apply the same maps to
    quantised readings), and the indices of its current and loop integrals in y."""

    name: str
    H: float
    speed_only: bool  # no position loop (the hollow motor with nut_loop = "speed")
    position: tuple[int, float]  # measured position [m] = factor · y[index]
    reference: int  # index of its commanded position in (x_ref, v_ref, x_n,ref, v_n,ref)
    feedforward: tuple[float, float]  # speed feed-forward [m/s] = a·v_ref + b·v_n,ref
    speed: tuple[tuple[int, float], ...]  # measured speed = Σ factor · y[index]
    current: int
    velocity_integral: int
    current_integral: int
    active: bool = True


@dataclass
class Held:
    """Outputs and integrals of the sampled loops, per axis, held between sample instants
    (zero-order hold), and the last quantised channel readings of the velocity loop."""

    speed_command: list[float]
    current_command: list[float]
    voltage: list[float]
    velocity_integral: list[float]
    current_integral: list[float]
    previous: dict[str, float] = field(default_factory=dict)

    @classmethod
    def zeros(cls, n_axes: int) -> Held:
        return cls([0.0] * n_axes, [0.0] * n_axes, [0.0] * n_axes, [0.0] * n_axes,
                   [0.0] * n_axes)


@dataclass(frozen=True)
class Grid:
    """Sample instants: the fastest loop period ``base`` [s]; loop periods in units of it
    (0 = continuous); output every ``out_every`` instants."""

    base: float
    n_pos: int
    n_vel: int
    n_cur: int
    out_every: int


def sampling_grid(params: DriveParameters, output_interval: float) -> Grid:
    c = params.controller
    periods = (c.position_period, c.velocity_period, c.current_period)
    fastest = min((p for p in periods if p > 0.0), default=0.0)
    base = fastest if fastest > 0.0 else output_interval
    n = [round(p / base) if p > 0.0 else 0 for p in periods]
    out_every = max(1, round(output_interval / base))
    if abs(out_every * base - output_interval) > 1e-9 * output_interval:
        raise ValueError(f"output_interval {output_interval:g} s: not a multiple of the "
                         f"fastest loop period {base:g} s")
    return Grid(base, n[0], n[1], n[2], out_every)


# ---------------------------------------------------------------- the closed loop


class ReferenceModel:
    """Closed-loop drive as a plain function ``f(t, y) -> dy/dt`` for ``scipy.integrate``.

    Parameters
    ----------
    params:
        The drive's parameters (``feeddrive.preset(...)``).
    drive:
        ``"cdfs"``, ``"ddfs"`` or ``"linear-motor"``.
    table_position:
        Start position a [m] of the nut from the motor-side screw support (ball screw).
    profile:
        A ``ConstantSpeed`` or ``SineSpeed`` (any object with their fields); ``None``: the
        references stay at 0.
    nut_hold:
        CDFS only: ``"locked"`` freezes the nut; ``"servo"`` keeps its loop at zero command.
    load:
        Optional load-force record (``time``, ``force``), added to ``disturbances.load_force``.
    stribeck_exponents:
        Per friction site name (``"screw"``, ``"guide"``, …), an exponent δ of the Stribeck
        curve exp(−|v/v_s|^δ) other than LuGre's 2, for that site's LuGre law
        (:class:`ShapedLuGre`): a truth the fitted model lacks.

    Sampled loops (``controller.*_period > 0``; ``n_pos``, ``n_vel``, ``n_cur`` > 0 in base
    periods) take their outputs from ``self.held`` in ``rhs`` (zero until updated), as the
    engine's ``rhs`` takes its held vector; ``reference.sampled.simulate_sampled`` performs
    the sample updates and the integration between them.
    """

    def __init__(self, params: DriveParameters, drive: str, table_position: float,
                 profile: Any = None, nut_hold: str = "locked", load: Any = None,
                 stribeck_exponents: dict[str, float] | None = None) -> None:
        if drive not in DRIVES:
            raise ValueError(f"drive = {drive!r}: expected one of {', '.join(DRIVES)}")
        if nut_hold not in ("locked", "servo"):
            raise ValueError(f"nut_hold = {nut_hold!r}: expected 'locked' or 'servo'")
        self.params = params
        self.profile = profile
        self.drive = drive
        # per LuGre site name, a Stribeck exponent other than 2 (a truth the fit lacks)
        self.stribeck_exponents = dict(stribeck_exponents or {})
        self.linear = drive == "linear-motor"
        self.rack = drive == "rack-pinion"
        self.nut_active = drive == "ddfs" or nut_hold == "servo"
        c = params.controller
        self.c = c
        self.torque_off = c.mode == "torque_off"
        self.x0 = table_position
        dist = params.disturbances
        record = (None, None) if load is None else (np.asarray(load.time, dtype=float),
                                                    np.asarray(load.force, dtype=float))
        self.load = (Load(dist.load_force, dist.load_start, *record)
                     if dist.load_force != 0.0 or load is not None else None)
        self.screw_ripple = Harmonics.of(dist.screw_motor_ripple)
        self.nut_ripple = Harmonics.of(dist.hollow_motor_ripple)
        self.lead_error = Harmonics.of(dist.lead_error)

        names: list[str] = []
        if self.linear:
            self._linear_motor(params, names)
        elif self.rack:
            self._rack_pinion(params, names)
        else:
            self._ball_screw(params, names)
        self.state_names = tuple(names)
        self.n_state = len(names)
        self.index = {n: k for k, n in enumerate(names)}

        self.k_position = c.position_gain * (
            c.velocity_command_gain if c.kv_placement == "position_output" else 1.0)
        self.velocity_divisor = (c.velocity_command_gain if c.kv_placement == "velocity_error"
                                 else 1.0)
        self.table_basis = c.velocity_gain_basis == "table"
        self.feedforward = 1.0 if c.velocity_feedforward else 0.0
        encoder = 2.0 * math.pi / c.encoder_counts if c.encoder_counts > 0 else 0.0
        self.quanta = {"screw_angle": encoder, "nut_angle": encoder,
                       "table": c.grating_resolution}
        self._kind = _profile_kind(profile)
        # which loops are sampled (their period in base periods; 0 = continuous): rhs takes
        # their outputs from self.held, which reference.sampled updates
        fastest = min((p for p in (c.position_period, c.velocity_period, c.current_period)
                       if p > 0.0), default=0.0)
        grid = sampling_grid(params, fastest) if fastest > 0.0 else Grid(0.0, 0, 0, 0, 1)
        self.n_pos, self.n_vel, self.n_cur = grid.n_pos, grid.n_vel, grid.n_cur
        self.held = Held.zeros(len(self.axes))

    # ------------------------------------------------------------ topologies

    def _friction_sites(self, params: DriveParameters, names: list[str],
                        placements: list[tuple[str, LuGreParameters, float]]) -> list[_Site]:
        sites = []
        for name, p, scale in placements:
            law = friction_law(p)
            if name in self.stribeck_exponents and type(law) is LuGre:
                law = ShapedLuGre(*(getattr(law, f) for f in
                                    ("coulomb", "static", "stribeck", "viscous", "sigma0",
                                     "sigma1")), exponent=self.stribeck_exponents[name])
            index = len(names) if law.states else -1
            names += [f"{name}_{s}" for s in law.states]
            sites.append(_Site(name, law, scale, index))
        return sites

    def _ball_screw(self, params: DriveParameters, names: list[str]) -> None:
        s = params.screw
        self.H = s.lead / (2.0 * math.pi)
        self.J_s = params.screw_motor.inertia + s.shaft_inertia
        self.J_n = params.hollow_motor.inertia + s.nut_inertia
        self.m_t = params.table.mass
        self.c_ax = params.stiffness.axial_damping
        self.motors = [params.screw_motor, params.hollow_motor]

        # stiffness chain, Wang2021 Eqs. (2)–(5)
        st = params.stiffness
        self.length = s.length
        self.EA = math.pi * s.diameter ** 2 / 4.0 * s.youngs_modulus
        self.fixed_fixed = st.screw_support == "fixed-fixed"
        k_t1 = 1.0 / (1.0 / params.coupling.torsional_stiffness + 1.0 / s.torsional_stiffness)
        self.compliance_rest = (st.support_bearing_count / s.support_bearing_axial_stiffness
                                + 1.0 / s.nut_axial_stiffness
                                + 1.0 / s.nut_bearing_axial_stiffness)
        if st.include_torsion:
            self.compliance_rest += self.H ** 2 / s.efficiency / k_t1
        self.K_fixed = 0.0
        if st.equivalent_stiffness > 0.0:
            self.K_fixed = st.equivalent_stiffness
        elif not st.position_dependent:
            self.K_fixed = self._chain(self.x0)

        names += ["screw_angle", "screw_speed", "nut_angle", "nut_speed", "table_position",
                  "table_speed"]
        fr = params.friction
        f = fr.ball_nut_share
        placements = []
        if f < 1.0:
            placements.append(("screw", fr.screw, 1.0 - f))
        placements += [("nut", fr.nut, 1.0), ("guide", fr.guide, 1.0)]
        if f > 0.0:
            placements.append(("ball_nut", fr.screw, f))
        sites = {site.name: site for site in self._friction_sites(params, names, placements)}
        self.screw_site = sites.get("screw")
        self.nut_site = sites["nut"]
        self.guide_site = sites["guide"]
        self.ball_nut_site = sites.get("ball_nut")
        n = len(names)
        names += ["screw_current", "nut_current", "screw_velocity_integral",
                  "nut_velocity_integral", "screw_current_integral", "nut_current_integral"]
        c = params.controller
        # screw motor: grating position, speed from its encoder or (velocity_feedback =
        # "table") the table's speed plus the nut's, (v_t + H ω_n)/H
        screw_speed = (((5, 1.0 / self.H), (3, 1.0)) if c.velocity_feedback == "table"
                       else ((1, 1.0),))
        self.axes = [Axis("screw", self.H, False, (4, 1.0), 0, (1.0, 1.0), screw_speed,
                          n, n + 2, n + 4),
                     Axis("nut", self.H, c.nut_loop == "speed", (2, self.H), 2, (0.0, 1.0),
                          ((3, 1.0),), n + 1, n + 3, n + 5, active=self.nut_active)]
        # sampled channels: (position index, speed index) in y
        self.channels = {"screw_angle": (0, 1), "nut_angle": (2, 3), "table": (4, 5)}

    def _linear_motor(self, params: DriveParameters, names: list[str]) -> None:
        lm = params.linear_motor
        if lm is None:
            raise ValueError("the linear-motor drive needs params.linear_motor")
        for label, series in (("screw_motor_ripple", self.screw_ripple),
                              ("hollow_motor_ripple", self.nut_ripple),
                              ("lead_error", self.lead_error)):
            if series is not None:
                raise ValueError(f"disturbances.{label}: the linear-motor drive has none")
        self.H = 1.0
        self.m_t = params.table.mass + lm.forcer_mass
        self.linear_motor = lm
        names += ["table_position", "table_speed"]
        (self.guide_site,) = self._friction_sites(params, names,
                                                  [("guide", params.friction.guide, 1.0)])
        n = len(names)
        names += ["motor_current", "motor_velocity_integral", "motor_current_integral"]
        self.axes = [Axis("motor", 1.0, False, (0, 1.0), 0, (1.0, 0.0), ((1, 1.0),),
                          n, n + 1, n + 2)]
        self.channels = {"table": (0, 1)}

    def _rack_pinion(self, params: DriveParameters, names: list[str]) -> None:
        """Motor → gearbox → pinion → rack on the table, from the equations of
        ``feeddrive.model.mechanisms.rack_pinion``'s docstring: a tooth-mesh spring
        k_m·(H·θ_m − x_t) + c_m·(H·ω_m − v_t) between the pinion's pitch line and the table,
        H = r_p/G; the gearbox friction a site at the motor shaft evaluated at H·ω_m and
        acting as torque H·F; one axis (position from the table, speed from the motor or,
        ``velocity_feedback = "table"``, v_t/H); continuous loops only."""
        rp = params.section("rack_pinion")
        if rp is None:
            raise ValueError("the rack-pinion drive needs a [rack_pinion] section")
        for label, series in (("screw_motor_ripple", self.screw_ripple),
                              ("hollow_motor_ripple", self.nut_ripple),
                              ("lead_error", self.lead_error)):
            if series is not None:
                raise ValueError(f"disturbances.{label}: the rack-pinion drive has none")
        c = params.controller
        if max(c.position_period, c.velocity_period, c.current_period) > 0.0:
            raise ValueError("the reference's rack and pinion has continuous loops only")
        self.H = rp.pinion_radius / rp.gear_ratio
        self.J_m = rp.motor.inertia + rp.gearbox_inertia + rp.pinion_inertia / rp.gear_ratio ** 2
        self.m_t = params.table.mass
        self.rack_section = rp
        names += ["motor_angle", "motor_speed", "table_position", "table_speed"]
        self.gearbox_site, self.guide_site = self._friction_sites(
            params, names, [("gearbox", rp.gearbox_friction, 1.0),
                            ("guide", params.friction.guide, 1.0)])
        n = len(names)
        names += ["motor_current", "motor_velocity_integral", "motor_current_integral"]
        speed = ((3, 1.0 / self.H),) if c.velocity_feedback == "table" else ((1, 1.0),)
        self.axes = [Axis("motor", self.H, False, (2, 1.0), 0, (1.0, 0.0), speed,
                          n, n + 1, n + 2)]
        self.channels = {"motor_angle": (0, 1), "table": (2, 3)}

    # ------------------------------------------------------------ pieces

    def _chain(self, a: float) -> float:
        lo = 1e-3 * self.length
        a = min(max(a, lo), self.length - lo)
        if self.fixed_fixed:
            c_screw = a * (self.length - a) / (self.EA * self.length)
        else:
            c_screw = a / self.EA
        return 1.0 / (self.compliance_rest + c_screw)

    def equivalent_stiffness(self, x_t: float) -> float:
        """K_eq [N/m] with the table displaced x_t [m] from its start."""
        return self.K_fixed if self.K_fixed > 0.0 else self._chain(self.x0 + x_t)

    def reference(self, t: float) -> tuple[float, float, float, float]:
        if self._kind == "constant":  # the common case inline (the benchmark's hot path)
            p = self.profile
            vt, vn, tr = p.table_speed, p.nut_speed, p.ramp_time
            if tr > 0.0 and t < tr:
                s = t / tr
                return 0.5 * vt * t * s, vt * s, 0.5 * vn * t * s, vn * s
            return vt * (t - 0.5 * tr), vt, vn * (t - 0.5 * tr), vn
        return reference_signals(self.profile, t)

    def speed_command(self, ax: Axis, ref: tuple[float, float, float, float],
                      y: Any) -> float:
        """Position loop (P + feed-forward) output [rad/s, m/s for a linear motor] from the
        references ``ref`` = (x_ref, v_ref, x_n,ref, v_n,ref) and the measurements in ``y``."""
        if ax.speed_only:
            return ref[3] / ax.H
        k, factor = ax.position
        a, b = ax.feedforward
        return (self.k_position * (ref[ax.reference] - factor * y[k])
                + self.feedforward * (a * ref[1] + b * ref[3])) / ax.H

    @staticmethod
    def measured_speed(ax: Axis, y: Any) -> float:
        """Axis speed feedback [rad/s, or m/s for a linear motor] from the speeds in ``y``."""
        total = 0.0
        for k, factor in ax.speed:
            total += factor * y[k]
        return total

    def velocity_error(self, ax: Axis, w_cmd: float, w_meas: float) -> float:
        """Velocity-loop error in the units its gains act on."""
        e = w_cmd - w_meas
        if self.table_basis:
            e *= ax.H
        return e / self.velocity_divisor

    def current_command(self, e_w: float, integral: float) -> tuple[float, float]:
        """(unsaturated, saturated) current command [A]."""
        raw = self.c.velocity_gain * e_w + self.c.velocity_integral_gain * integral
        return raw, _saturate(raw, self.c.current_limit)

    def voltage_command(self, e_i: float, integral: float) -> tuple[float, float]:
        raw = self.c.current_gain * e_i + self.c.current_integral_gain * integral
        return raw, _saturate(raw, self.c.voltage_limit)

    def _controller(self, t: float, y: list[float], dy: np.ndarray) -> list[float]:
        """Armature voltage of every axis; writes the continuous integrals' rates.  (The
        loop laws of :meth:`current_command` and :meth:`voltage_command`, written out: this
        is the benchmark's hot path.)"""
        c = self.c
        held = self.held
        ref = self.reference(t)
        voltages = []
        for a, ax in enumerate(self.axes):
            if not ax.active:
                voltages.append(0.0)
                continue
            if self.n_vel > 0:
                i_cmd = held.current_command[a]
            else:
                w_cmd = (held.speed_command[a] if self.n_pos > 0
                         else self.speed_command(ax, ref, y))
                w_meas = 0.0
                for k, factor in ax.speed:
                    w_meas += factor * y[k]
                e_w = w_cmd - w_meas
                if self.table_basis:
                    e_w *= ax.H
                e_w /= self.velocity_divisor
                raw = c.velocity_gain * e_w + c.velocity_integral_gain * y[ax.velocity_integral]
                i_cmd = _saturate(raw, c.current_limit)
                if c.velocity_integral_gain != 0.0:
                    dy[ax.velocity_integral] = _integral_rate(e_w, raw, c.current_limit)
            if self.n_cur > 0:
                u = held.voltage[a]
            else:
                e_i = i_cmd - y[ax.current]
                raw = c.current_gain * e_i + c.current_integral_gain * y[ax.current_integral]
                u = _saturate(raw, c.voltage_limit)
                if c.current_integral_gain != 0.0:
                    dy[ax.current_integral] = _integral_rate(e_i, raw, c.voltage_limit)
            voltages.append(u)
        return voltages

    # ------------------------------------------------------------ the right-hand side

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        """dy/dt [SI] of the closed loop at time t [s] and state y (order ``state_names``)."""
        dy = np.zeros(self.n_state)
        values: list[float] = y.tolist() if isinstance(y, np.ndarray) else list(y)
        u = self._controller(t, values, dy)
        if self.linear:
            self._linear_motor_rhs(t, values, u, dy)
        elif self.rack:
            self._rack_pinion_rhs(t, values, u, dy)
        else:
            self._ball_screw_rhs(t, values, u, dy)
        return dy

    __call__ = rhs

    def _ball_screw_rhs(self, t: float, y: Any, u: list[float], dy: np.ndarray) -> None:
        th_s, w_s, th_n, w_n, x_t, v_t = y[:6]
        H = self.H
        screw, nut = self.axes
        i_s, i_n = y[screw.current], y[nut.current]
        F_s = 0.0 if self.screw_site is None else _site_force(self.screw_site, H * w_s, y, dy)
        F_g = _site_force(self.guide_site, v_t, y, dy)
        F_bn = (0.0 if self.ball_nut_site is None
                else _site_force(self.ball_nut_site, H * (w_s - w_n), y, dy))
        th_r = th_s - th_n
        if self.lead_error is None:
            lever, stretch = H, H * th_r - x_t
        else:
            dev, slope = self.lead_error.value_and_slope(th_r)
            lever, stretch = H + slope, H * th_r + dev - x_t
        F_d = (self.equivalent_stiffness(x_t) * stretch
               + self.c_ax * (lever * (w_s - w_n) - v_t))
        ms, mn = self.motors
        T_s = 0.0 if self.torque_off else ms.torque_constant * i_s
        if self.screw_ripple is not None:
            T_s += self.screw_ripple.value_and_slope(th_s)[0]

        dy[0] = w_s
        dy[1] = (T_s - H * F_s - H * F_bn - lever * F_d) / self.J_s
        dy[4] = v_t
        F_load = 0.0 if self.load is None else self.load(t)
        dy[5] = (F_d - F_g - F_load) / self.m_t
        if not self.torque_off:
            dy[screw.current] = (u[0] - ms.resistance * i_s
                                 - ms.back_emf_constant * w_s) / ms.inductance

        if self.nut_active:
            F_n = _site_force(self.nut_site, H * w_n, y, dy)
            T_n = 0.0 if self.torque_off else mn.torque_constant * i_n
            if self.nut_ripple is not None:
                T_n += self.nut_ripple.value_and_slope(th_n)[0]
            dy[2] = w_n
            dy[3] = (T_n - H * F_n + H * F_bn + lever * F_d) / self.J_n
            if not self.torque_off:
                dy[nut.current] = (u[1] - mn.resistance * i_n
                                   - mn.back_emf_constant * w_n) / mn.inductance

    def _linear_motor_rhs(self, t: float, y: Any, u: list[float], dy: np.ndarray) -> None:
        lm = self.linear_motor
        ix = self.index
        v_t = y[ix["table_speed"]]
        k = self.axes[0].current
        i = y[k]
        F_g = _site_force(self.guide_site, v_t, y, dy)
        F_m = 0.0 if self.torque_off else lm.force_constant * i
        F_load = 0.0 if self.load is None else self.load(t)
        dy[ix["table_position"]] = v_t
        dy[ix["table_speed"]] = (F_m - F_g - F_load) / self.m_t
        if not self.torque_off:
            dy[k] = (u[0] - lm.resistance * i - lm.back_emf_constant * v_t) / lm.inductance

    def _rack_pinion_rhs(self, t: float, y: Any, u: list[float], dy: np.ndarray) -> None:
        rp = self.rack_section
        H = self.H
        th_m, w_m, x_t, v_t = y[:4]
        k = self.axes[0].current
        i = y[k]
        F_gb = _site_force(self.gearbox_site, H * w_m, y, dy)
        F_g = _site_force(self.guide_site, v_t, y, dy)
        F_mesh = rp.mesh_stiffness * (H * th_m - x_t) + rp.mesh_damping * (H * w_m - v_t)
        T_m = 0.0 if self.torque_off else rp.motor.torque_constant * i
        F_load = 0.0 if self.load is None else self.load(t)
        dy[0] = w_m
        dy[1] = (T_m - H * F_gb - H * F_mesh) / self.J_m
        dy[2] = v_t
        dy[3] = (F_mesh - F_g - F_load) / self.m_t
        if not self.torque_off:
            dy[k] = (u[0] - rp.motor.resistance * i - rp.motor.back_emf_constant * w_m) \
                / rp.motor.inductance

    # ------------------------------------------------------------ for solvers

    def typical_sizes(self) -> np.ndarray:
        """A typical magnitude of each state: 1 mm, 1 mm/s, 1 µm of bristle, 1 A, …"""
        H = self.H
        size = {"angle": 1e-3 / H, "speed": 1e-3 / H, "table_position": 1e-3,
                "table_speed": 1e-3, "bristle": 1e-6, "current": 1.0,
                "velocity_integral": 1e-3 / H, "current_integral": 1e-3}
        out = np.empty(self.n_state)
        for k, name in enumerate(self.state_names):
            key = next(s for s in ("table_position", "table_speed", "velocity_integral",
                                   "current_integral", "current", "bristle", "angle", "speed")
                       if _kind(name).endswith(s))
            out[k] = size[key]
        return out

    def tolerances(self, position: float = 1e-10, speed: float = 1e-8,
                   current: float = 1e-6) -> np.ndarray:
        """Absolute tolerance per state from position [m], speed [m/s] and current [A]
        targets (angles scaled by 1/H, as the engine's error weights)."""
        H = self.H
        per = {"table_position": position, "table_speed": speed,
               "velocity_integral": position / H, "current_integral": current * 1e-3,
               "current": current, "bristle": position, "angle": position / H,
               "speed": speed / H}
        return np.array([next(v for k, v in per.items() if _kind(name).endswith(k))
                         for name in self.state_names])

    def jacobian(self, t: float, y: np.ndarray) -> np.ndarray:
        """∂f/∂y by central differences, for implicit solvers.

        Steps are 1e-7 of each state's typical size (:meth:`typical_sizes`), or of the state
        itself when larger.  scipy's own difference Jacobian fails here: its step factor
        overflows on states with no influence (the held nut of the CDFS).
        """
        steps = 1e-7 * np.maximum(np.abs(y), self.typical_sizes())
        n = self.n_state
        jac = np.empty((n, n))
        for j in range(n):
            yp = np.array(y, dtype=float)
            ym = yp.copy()
            yp[j] += steps[j]
            ym[j] -= steps[j]
            jac[:, j] = (self.rhs(t, yp) - self.rhs(t, ym)) / (2.0 * steps[j])
        return jac


def _kind(name: str) -> str:
    """A state's name for the tolerance and size tables: a GMS element's deflection
    (``guide_element3``) is a deflection like a bristle's."""
    site, _, rest = name.rpartition("_element")
    return f"{site}_bristle" if site and rest.isdigit() else name


def tolerances(H: float, position: float = 1e-10, speed: float = 1e-8,
               current: float = 1e-6) -> np.ndarray:
    """Absolute tolerance per state of the default layout (``STATE_NAMES``) for ``solve_ivp``
    from position [m], speed [m/s] and current [A] targets (angles scaled by 1/H, as the
    engine's error weights)."""
    atol = np.empty(N_STATE)
    atol[[0, 2]] = position / H
    atol[[1, 3]] = speed / H
    atol[4] = position
    atol[5] = speed
    atol[[6, 7, 8]] = position
    atol[[9, 10]] = current
    atol[[11, 12]] = position / H
    atol[[13, 14]] = current * 1e-3
    return atol
