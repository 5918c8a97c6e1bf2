"""Reference right-hand side of the closed-loop CDFS/DDFS, in plain Python (no numba).

An independent implementation of the model the compiled engine integrates, written from the
equations (Wang2021 Eqs. (2)–(11), Tables 1–2) and the cascade described in the docstrings of
``feeddrive.drives`` and ``feeddrive.control``.  It shares no code with the engine's kernels:
only the parameter dataclasses (``feeddrive.parameters``) are read.  It serves as

* the baseline of ``benchmarks/bench_engine.py`` (``scipy.integrate.solve_ivp`` with this RHS),
* the model of the tight-tolerance Radau references (``reference/make_radau_reference.py``),
* the other side of the RHS cross-check in ``tests/validation/test_engine_accuracy.py``.

Scope: continuous control only (every loop period 0), constant-speed (with start ramp) and
sinusoidal profiles.  SI units throughout.

The model
---------
State (same order as ``feeddrive.layout.STATE_NAMES``, see ``STATE_NAMES`` below):
θ_s, ω_s, θ_n, ω_n [rad, rad/s]; x_t, v_t [m, m/s]; z_s, z_n, z_g [m] (LuGre bristles);
i_s, i_n [A]; the velocity-loop integrals of both motors; the current-loop integrals.

Mechanics (Wang2021 Eqs. (7)–(8); the CDFS is the DDFS with the nut held, Sect. 2)::

    F_d     = K_eq(a)·[H(θ_s − θ_n) − x_t] + c_ax·[H(ω_s − ω_n) − v_t]
    J_s ω̇_s = K_t i_s − H·F_sf(Hω_s, z_s) − H·F_d
    J_n ω̇_n = K_t i_n − H·F_nf(Hω_n, z_n) + H·F_d
    m_t v̇_t = F_d − F_gf(v_t, z_g)
    L i̇     = u − R i − K_e ω

with J_s = screw-motor + screw-shaft inertia, J_n = hollow-motor + nut inertia, H = p_h/2π.

LuGre at each site (Eqs. (9)–(11), Table 1 in its linear, ÷H form; branch by sign of v)::

    G(v) = F_c + (F_s − F_c)·exp(−(v/v_s)²)          (= σ0·g(v), a force)
    ż    = v − σ0·|v|·z / G(v)
    F    = σ0 z + σ1 ż + σ2 v

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
            k_p = K_pp, or K_v·K_pp with kv_placement = "position_output"
    e_ω   = (ω_cmd − ω_meas) · [H if velocity_gain_basis = "table"] / [K_v if kv_placement =
            "velocity_error"];  ω_meas = ω_s, or (v_t + Hω_n)/H for the screw with
            velocity_feedback = "table"
    i_cmd = sat(K_vp e_ω + K_vi ∫e_ω, I_max)
    u     = sat(K_ip (i_cmd − i) + K_ii ∫(i_cmd − i), U_max)

Integrals stop integrating into a saturated output (conditional anti-windup): the rate is 0
when the unsaturated output exceeds the limit and the error would push it further.  An
integral whose gain is 0 is frozen.  With the nut held (CDFS, ``nut_hold = "locked"``) every
nut state is frozen.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from feeddrive.parameters import DriveParameters, LuGreParameters

STATE_NAMES = (
    "screw_angle", "screw_speed", "nut_angle", "nut_speed", "table_position", "table_speed",
    "screw_bristle", "nut_bristle", "guide_bristle", "screw_current", "nut_current",
    "screw_velocity_integral", "nut_velocity_integral", "screw_current_integral",
    "nut_current_integral",
)
N_STATE = len(STATE_NAMES)


# ---------------------------------------------------------------- friction


@dataclass(frozen=True)
class LuGre:
    """One LuGre site in linear form: forces [N], speeds [m/s], bristle deflection [m]."""

    coulomb: tuple[float, float]  # F_c for v ≥ 0, v < 0 (magnitudes)
    static: tuple[float, float]  # F_s
    stribeck: tuple[float, float]  # v_s
    viscous: tuple[float, float]  # σ2
    sigma0: float
    sigma1: float

    @classmethod
    def from_parameters(cls, p: LuGreParameters) -> LuGre:
        pos, neg = p.positive, p.negative
        return cls(coulomb=(pos.coulomb_force, neg.coulomb_force),
                   static=(pos.static_force, neg.static_force),
                   stribeck=(pos.stribeck_velocity, neg.stribeck_velocity),
                   viscous=(pos.viscous_coefficient, neg.viscous_coefficient),
                   sigma0=p.bristle_stiffness, sigma1=p.bristle_damping)

    def force_and_rate(self, v: float, z: float) -> tuple[float, float]:
        """(friction force F [N], bristle rate ż [m/s]) at sliding speed v and deflection z."""
        b = 0 if v >= 0.0 else 1
        fc = self.coulomb[b]
        G = fc + (self.static[b] - fc) * math.exp(-(v / self.stribeck[b]) ** 2)
        zdot = v - self.sigma0 * abs(v) * z / G
        return self.sigma0 * z + self.sigma1 * zdot + self.viscous[b] * v, zdot


# ---------------------------------------------------------------- reference profiles


def _profile_kind(profile: Any) -> str:
    if all(hasattr(profile, a) for a in ("table_speed", "nut_speed", "ramp_time")):
        return "constant"
    if all(hasattr(profile, a) for a in ("table_amplitude", "nut_amplitude", "frequency")):
        return "sine"
    raise ValueError(f"profile {type(profile).__name__}: the reference model handles "
                     "ConstantSpeed and SineSpeed only")


def reference_signals(profile: Any, t: float) -> tuple[float, float, float, float]:
    """(x_ref, v_ref, x_n,ref, v_n,ref) [m, m/s] of a ConstantSpeed or SineSpeed profile.

    Constant speed: the speed rises linearly over ``ramp_time`` then stays; positions are
    its integral.  Sine: v = A·sin(2πft), x = A·(1 − cos 2πft)/(2πf).
    """
    if _profile_kind(profile) == "constant":
        vt, vn, tr = profile.table_speed, profile.nut_speed, profile.ramp_time
        if tr > 0.0 and t < tr:
            s = t / tr
            return 0.5 * vt * t * s, vt * s, 0.5 * vn * t * s, vn * s
        return vt * (t - 0.5 * tr), vt, vn * (t - 0.5 * tr), vn
    w = 2.0 * math.pi * profile.frequency
    s, c = math.sin(w * t), math.cos(w * t)
    return (profile.table_amplitude * (1.0 - c) / w, profile.table_amplitude * s,
            profile.nut_amplitude * (1.0 - c) / w, profile.nut_amplitude * s)


# ---------------------------------------------------------------- the closed loop


def _saturate(x: float, limit: float) -> float:
    return limit if x > limit else (-limit if x < -limit else x)


def _integral_rate(error: float, unsaturated: float, limit: float) -> float:
    """Conditional integration: hold the integral while the output is pushed into its limit."""
    if (unsaturated > limit and error > 0.0) or (unsaturated < -limit and error < 0.0):
        return 0.0
    return error


class ReferenceModel:
    """Closed-loop drive as a plain function ``f(t, y) -> dy/dt`` for ``scipy.integrate``.

    Parameters
    ----------
    params:
        The drive's parameters (``feeddrive.preset(...)``).
    drive:
        ``"cdfs"`` or ``"ddfs"``.
    table_position:
        Start position a [m] of the nut from the motor-side screw support.
    profile:
        A ``ConstantSpeed`` or ``SineSpeed`` (any object with their fields).
    nut_hold:
        CDFS only: ``"locked"`` freezes the nut; ``"servo"`` keeps its loop at zero command.
    """

    def __init__(self, params: DriveParameters, drive: str, table_position: float,
                 profile: Any, nut_hold: str = "locked") -> None:
        if drive not in ("cdfs", "ddfs"):
            raise ValueError(f"drive = {drive!r}: expected 'cdfs' or 'ddfs'")
        if nut_hold not in ("locked", "servo"):
            raise ValueError(f"nut_hold = {nut_hold!r}: expected 'locked' or 'servo'")
        c = params.controller
        if c.position_period or c.velocity_period or c.current_period:
            raise ValueError("the reference model covers continuous control only "
                             "(controller.*_period = 0)")
        _profile_kind(profile)
        self.params = params
        self.profile = profile
        self.drive = drive
        self.nut_active = drive == "ddfs" or nut_hold == "servo"

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
        self.x0 = table_position
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
            self.K_fixed = self._chain(table_position)

        fr = params.friction
        self.screw_friction = LuGre.from_parameters(fr.screw)
        self.nut_friction = LuGre.from_parameters(fr.nut)
        self.guide_friction = LuGre.from_parameters(fr.guide)

        self.c = c
        self.k_position = c.position_gain * (
            c.velocity_command_gain if c.kv_placement == "position_output" else 1.0)
        self.error_scale = ((self.H if c.velocity_gain_basis == "table" else 1.0)
                            / (c.velocity_command_gain if c.kv_placement == "velocity_error"
                               else 1.0))
        self.feedforward = 1.0 if c.velocity_feedforward else 0.0

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
        return reference_signals(self.profile, t)

    def _motor(self, w_cmd: float, w_meas: float, i: float, iv: float,
               ic: float) -> tuple[float, float, float]:
        """(armature voltage, velocity-integral rate, current-integral rate) of one motor."""
        c = self.c
        e_w = (w_cmd - w_meas) * self.error_scale
        raw_i = c.velocity_gain * e_w + c.velocity_integral_gain * iv
        i_cmd = _saturate(raw_i, c.current_limit)
        div = (_integral_rate(e_w, raw_i, c.current_limit)
               if c.velocity_integral_gain != 0.0 else 0.0)
        e_i = i_cmd - i
        raw_u = c.current_gain * e_i + c.current_integral_gain * ic
        u = _saturate(raw_u, c.voltage_limit)
        dic = (_integral_rate(e_i, raw_u, c.voltage_limit)
               if c.current_integral_gain != 0.0 else 0.0)
        return u, div, dic

    # ------------------------------------------------------------ the right-hand side

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        """dy/dt [SI] of the closed loop at time t [s] and state y (order ``STATE_NAMES``)."""
        (th_s, w_s, th_n, w_n, x_t, v_t, z_s, z_n, z_g, i_s, i_n,
         iv_s, iv_n, ic_s, ic_n) = (float(v) for v in y)
        H = self.H
        x_ref, v_ref, xn_ref, vn_ref = self.reference(t)
        ff = self.feedforward

        # screw motor: position loop on the table (grating), speed feed-forward v_s = v_t + v_n
        w_cmd_s = (self.k_position * (x_ref - x_t) + ff * (v_ref + vn_ref)) / H
        w_meas_s = (v_t + H * w_n) / H if self.c.velocity_feedback == "table" else w_s
        u_s, div_s, dic_s = self._motor(w_cmd_s, w_meas_s, i_s, iv_s, ic_s)

        # mechanics
        F_s, dz_s = self.screw_friction.force_and_rate(H * w_s, z_s)
        F_g, dz_g = self.guide_friction.force_and_rate(v_t, z_g)
        F_d = (self.equivalent_stiffness(x_t) * (H * (th_s - th_n) - x_t)
               + self.c_ax * (H * (w_s - w_n) - v_t))
        ms = self.motors[0]

        dy = np.zeros(N_STATE)
        dy[0] = w_s
        dy[1] = (ms.torque_constant * i_s - H * F_s - H * F_d) / self.J_s
        dy[4] = v_t
        dy[5] = (F_d - F_g) / self.m_t
        dy[6] = dz_s
        dy[8] = dz_g
        dy[9] = (u_s - ms.resistance * i_s - ms.back_emf_constant * w_s) / ms.inductance
        dy[11] = div_s
        dy[13] = dic_s

        if self.nut_active:
            # hollow motor: its own position loop on its encoder
            if self.params.controller.nut_loop == "speed":
                w_cmd_n = vn_ref / H  # speed loop only: no position feedback on the nut
            else:
                w_cmd_n = (self.k_position * (xn_ref - H * th_n) + ff * vn_ref) / H
            u_n, div_n, dic_n = self._motor(w_cmd_n, w_n, i_n, iv_n, ic_n)
            F_n, dz_n = self.nut_friction.force_and_rate(H * w_n, z_n)
            mn = self.motors[1]
            dy[2] = w_n
            dy[3] = (mn.torque_constant * i_n - H * F_n + H * F_d) / self.J_n
            dy[7] = dz_n
            dy[10] = (u_n - mn.resistance * i_n - mn.back_emf_constant * w_n) / mn.inductance
            dy[12] = div_n
            dy[14] = dic_n
        return dy

    __call__ = rhs

    def jacobian(self, t: float, y: np.ndarray) -> np.ndarray:
        """∂f/∂y by central differences, for implicit solvers.

        Steps are 1e-7 of each state's typical size (1 mm, 1 mm/s, 1 µm of bristle, 1 A, …),
        or of the state itself when larger.  scipy's own difference Jacobian fails here: its
        step factor overflows on states with no influence (the held nut of the CDFS).
        """
        H = self.H
        typical = np.array([1e-3 / H, 1e-3 / H, 1e-3 / H, 1e-3 / H, 1e-3, 1e-3, 1e-6, 1e-6,
                            1e-6, 1.0, 1.0, 1e-3 / H, 1e-3 / H, 1e-3, 1e-3])
        steps = 1e-7 * np.maximum(np.abs(y), typical)
        jac = np.empty((N_STATE, N_STATE))
        for j in range(N_STATE):
            yp = np.array(y, dtype=float)
            ym = yp.copy()
            yp[j] += steps[j]
            ym[j] -= steps[j]
            jac[:, j] = (self.rhs(t, yp) - self.rhs(t, ym)) / (2.0 * steps[j])
        return jac


def tolerances(H: float, position: float = 1e-10, speed: float = 1e-8,
               current: float = 1e-6) -> np.ndarray:
    """Absolute tolerance per state for ``solve_ivp`` from position [m], speed [m/s] and
    current [A] targets (angles scaled by 1/H, as the engine's error weights)."""
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
