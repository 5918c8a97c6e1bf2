"""Cascade servo control and reference profiles.  Wang2021 Sect. 2.1 (Fig. 2).

Structure (an explicit choice; Fig. 5 of the paper is an image, see docs/model.md):

* screw motor: position loop on the *table* position x' from the grating ruler,
  Δx = x − x', x = x_s − x_n, with velocity feed-forward of the screw's ideal speed;
* hollow motor: its own position loop on its encoder at the commanded nut motion, or
  (``nut_loop = "speed"``) a speed loop at the commanded nut speed with no position loop;
* each motor: position (P, K_pp) → velocity (P or PI, K_vp, K_vi) → current (P or PI,
  K_ip, K_ii) → R-L armature with back-EMF, torque K_t·i;
* K_v (Table 2's "velocity-adjusting gain") enters where ``kv_placement`` says:
  ``none``; ``position_output`` (ω_cmd = K_v·K_pp·Δx/H, K_pp read as V per rad);
  ``velocity_error`` (velocity error read as a voltage ω/K_v, i.e. K_vp/K_v);
* ``velocity_gain_basis = table``: velocity gains act on m/s of table-equivalent motion
  (error·H) instead of rad/s;
* every loop is continuous (period 0) or sampled with zero-order hold at its own period;
  sampled loops may quantise the motor encoder (counts/rev) and the grating (m).

The kernels are numba-compiled and called by the solver; ``Profile`` classes build the
reference arrays.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import layout as ix
from ._jit import kernel

# ---------------------------------------------------------------- reference profiles


@kernel
def reference_kernel(t: float, P: np.ndarray, table: np.ndarray, out: np.ndarray) -> None:
    """Commanded table position/speed and nut position/speed at time t [s] → out[0:4]."""
    kind = int(P[ix.REF_KIND])
    if kind == ix.REF_CONSTANT:
        tr = P[ix.REF_TRAMP]
        vt = P[ix.REF_VT]
        vn = P[ix.REF_VN]
        if tr > 0.0 and t < tr:
            f = t / tr
            out[0] = vt * t * f / 2.0
            out[1] = vt * f
            out[2] = vn * t * f / 2.0
            out[3] = vn * f
        else:
            shift = tr / 2.0 if tr > 0.0 else 0.0
            out[0] = vt * (t - shift)
            out[1] = vt
            out[2] = vn * (t - shift)
            out[3] = vn
    elif kind == ix.REF_SINE:
        w = 2.0 * math.pi * P[ix.REF_FREQ]
        s = math.sin(w * t)
        c = math.cos(w * t)
        out[0] = P[ix.REF_VT] * (1.0 - c) / w
        out[1] = P[ix.REF_VT] * s
        out[2] = P[ix.REF_VN] * (1.0 - c) / w
        out[3] = P[ix.REF_VN] * s
    else:
        dt = P[ix.REF_FREQ]
        n = table.shape[1]
        u = t / dt
        k = int(math.floor(u))
        if k >= n - 1:
            k = n - 2
            u = float(n - 1)
        if k < 0:
            k = 0
            u = 0.0
        f = u - k
        tau = f * dt
        for j in range(2):
            v0 = table[2 * j + 1, k]
            v1 = table[2 * j + 1, k + 1]
            slope = (v1 - v0) / dt
            out[2 * j] = table[2 * j, k] + v0 * tau + 0.5 * slope * tau * tau
            out[2 * j + 1] = v0 + slope * tau


@dataclass(frozen=True)
class ConstantSpeed:
    """Constant table speed [m/s] (and nut speed for the DDFS) after a linear start ramp."""

    table_speed: float
    nut_speed: float = 0.0
    ramp_time: float = 0.1  # [s]

    def encode(self) -> tuple[dict[int, float], np.ndarray]:
        _finite("table_speed", self.table_speed, "m/s")
        _finite("nut_speed", self.nut_speed, "m/s")
        if not (self.ramp_time >= 0.0 and math.isfinite(self.ramp_time)):
            raise ValueError(f"profile.ramp_time = {self.ramp_time!r}: expected ≥ 0 [s]")
        return ({ix.REF_KIND: ix.REF_CONSTANT, ix.REF_VT: self.table_speed,
                 ix.REF_VN: self.nut_speed, ix.REF_TRAMP: self.ramp_time}, _EMPTY_TABLE)


@dataclass(frozen=True)
class SineSpeed:
    """Sinusoidal speeds v(t) = A·sin(2πft): table amplitude [m/s], nut amplitude [m/s].

    The screw's amplitude is their sum (Wang2021 Figs. 9–10: v_sp = v_tp + v_np).  The paper
    does not state the frequency; 0.2 Hz is our default (see docs/model.md).
    """

    table_amplitude: float
    nut_amplitude: float = 0.0
    frequency: float = 0.2  # [Hz]

    def encode(self) -> tuple[dict[int, float], np.ndarray]:
        _finite("table_amplitude", self.table_amplitude, "m/s")
        _finite("nut_amplitude", self.nut_amplitude, "m/s")
        if not (self.frequency > 0.0 and math.isfinite(self.frequency)):
            raise ValueError(f"profile.frequency = {self.frequency!r}: expected > 0 [Hz]")
        return ({ix.REF_KIND: ix.REF_SINE, ix.REF_VT: self.table_amplitude,
                 ix.REF_VN: self.nut_amplitude, ix.REF_FREQ: self.frequency}, _EMPTY_TABLE)


@dataclass(frozen=True)
class SampledSpeed:
    """Table and nut speeds [m/s] sampled on a uniform time grid starting at 0 [s].

    Speeds are interpolated linearly; positions are their exact integrals.
    """

    time: np.ndarray
    table_speed: np.ndarray
    nut_speed: np.ndarray | None = None

    def encode(self) -> tuple[dict[int, float], np.ndarray]:
        t = np.asarray(self.time, dtype=float)
        vt = np.asarray(self.table_speed, dtype=float)
        vn = np.zeros_like(vt) if self.nut_speed is None else np.asarray(self.nut_speed, float)
        if t.ndim != 1 or t.size < 2 or vt.shape != t.shape or vn.shape != t.shape:
            raise ValueError("profile.time/table_speed/nut_speed: expected 1-D arrays of one "
                             "length ≥ 2")
        for name, arr in (("time", t), ("table_speed", vt), ("nut_speed", vn)):
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"profile.{name}: contains non-finite values")
        dt = np.diff(t)
        if abs(t[0]) > 1e-12 or np.any(dt <= 0) or np.ptp(dt) > 1e-9 * max(dt.mean(), 1e-300):
            raise ValueError("profile.time: expected a uniform, increasing grid starting at 0 [s]")
        table = np.empty((4, t.size))
        for j, v in enumerate((vt, vn)):
            table[2 * j + 1] = v
            table[2 * j, 0] = 0.0
            table[2 * j, 1:] = np.cumsum(0.5 * (v[1:] + v[:-1]) * dt)
        return ({ix.REF_KIND: ix.REF_SAMPLED, ix.REF_FREQ: float(dt.mean())}, table)

    @classmethod
    def from_function(cls, table_speed: Callable[[np.ndarray], np.ndarray], duration: float,
                      nut_speed: Callable[[np.ndarray], np.ndarray] | None = None,
                      interval: float = 1e-4) -> SampledSpeed:
        """Sample user functions of time [s] → speed [m/s] on a grid of ``interval`` [s]."""
        n = int(math.ceil(duration / interval)) + 2
        t = np.arange(n) * interval
        vt = np.asarray(table_speed(t), dtype=float) * np.ones_like(t)
        vn = None if nut_speed is None else np.asarray(nut_speed(t), dtype=float) * np.ones_like(t)
        return cls(time=t, table_speed=vt, nut_speed=vn)


Profile = ConstantSpeed | SineSpeed | SampledSpeed
_EMPTY_TABLE = np.zeros((4, 2))


def _finite(name: str, value: float, unit: str) -> None:
    if not math.isfinite(value):
        raise ValueError(f"profile.{name} = {value!r}: expected a finite speed [{unit}]")


# ---------------------------------------------------------------- controller laws


@kernel
def quantise(value: float, step: float) -> float:
    """Floor quantisation to ``step`` (an incremental encoder or grating count); 0 = ideal."""
    if step <= 0.0:
        return value
    return step * math.floor(value / step)


@kernel
def position_law(error: float, speed_ff: float, P: np.ndarray) -> float:
    """Speed command [rad/s] from position error [m] and feed-forward speed [m/s]."""
    k = P[ix.KPP]
    if int(P[ix.KV_PLACE]) == 1:
        k *= P[ix.KV]
    return (k * error + P[ix.FF] * speed_ff) / P[ix.H]


@kernel
def nut_speed_command(error: float, speed_ref: float, P: np.ndarray) -> float:
    """Hollow-motor speed command [rad/s]: its position loop, or (``nut_loop = "speed"``)
    the commanded nut speed itself, with no position feedback."""
    if P[ix.NUT_SPEED_MODE] > 0.5:
        return speed_ref / P[ix.H]
    return position_law(error, speed_ref, P)


@kernel
def velocity_error(speed_cmd: float, speed_meas: float, P: np.ndarray) -> float:
    """Velocity-loop error in the units the gains act on (see module docstring)."""
    e = speed_cmd - speed_meas
    if int(P[ix.V_BASIS]) == 1:
        e *= P[ix.H]
    if int(P[ix.KV_PLACE]) == 2:
        e /= P[ix.KV]
    return e


@kernel
def saturate(value: float, limit: float) -> float:
    if value > limit:
        return limit
    if value < -limit:
        return -limit
    return value


@kernel
def integrator_rate(error: float, unsaturated: float, limit: float) -> float:
    """Conditional integration (anti-windup): stop integrating into a saturated output."""
    if (unsaturated > limit and error > 0.0) or (unsaturated < -limit and error < 0.0):
        return 0.0
    return error


@kernel
def current_command(error: float, integral: float, P: np.ndarray) -> float:
    return P[ix.KVP] * error + P[ix.KVI] * integral


@kernel
def voltage_command(error: float, integral: float, P: np.ndarray) -> float:
    return P[ix.KIP] * error + P[ix.KII] * integral


@kernel
def sample_update(k: int, t: float, y: np.ndarray, held: np.ndarray, P: np.ndarray,
                  ref_table: np.ndarray, n_pos: int, n_vel: int, n_cur: int,
                  base: float) -> None:
    """Discrete controller update at sample instant k (time t): position → velocity → current.

    Loops with a zero period are continuous and evaluated in the right-hand side instead.
    ``n_*`` are the loop periods in units of the base period ``base`` (0 = continuous).
    """
    ref = np.empty(4)
    reference_kernel(t, P, ref_table, ref)
    H = P[ix.H]
    active_nut = P[ix.NUT_ACTIVE] > 0.5
    if n_pos > 0 and k % n_pos == 0:
        x_meas = quantise(y[ix.X_T], P[ix.GRAT_Q])
        held[ix.HW_CMD_S] = position_law(ref[0] - x_meas, ref[1] + ref[3], P)
        if active_nut:
            th_n = quantise(y[ix.TH_N], P[ix.ENC_Q])
            held[ix.HW_CMD_N] = nut_speed_command(ref[2] - H * th_n, ref[3], P)
    if n_vel > 0 and k % n_vel == 0:
        tv = n_vel * base
        w_cmd_s = held[ix.HW_CMD_S] if n_pos > 0 else position_law(
            ref[0] - y[ix.X_T], ref[1] + ref[3], P)
        w_cmd_n = held[ix.HW_CMD_N] if n_pos > 0 else nut_speed_command(
            ref[2] - H * y[ix.TH_N], ref[3], P)
        # speed measurement: difference of quantised positions over the period
        th_s_q = quantise(y[ix.TH_S], P[ix.ENC_Q])
        th_n_q = quantise(y[ix.TH_N], P[ix.ENC_Q])
        x_q = quantise(y[ix.X_T], P[ix.GRAT_Q])
        if P[ix.ENC_Q] > 0.0 or P[ix.GRAT_Q] > 0.0:
            if k == 0:
                w_s_meas = 0.0
                w_n_meas = 0.0
                v_t_meas = 0.0
            else:
                w_s_meas = (th_s_q - held[ix.HQ_PREV_S]) / tv
                w_n_meas = (th_n_q - held[ix.HQ_PREV_N]) / tv
                v_t_meas = (x_q - held[ix.HQ_PREV_T]) / tv
        else:
            w_s_meas = y[ix.W_S]
            w_n_meas = y[ix.W_N]
            v_t_meas = y[ix.V_T]
        held[ix.HQ_PREV_S] = th_s_q
        held[ix.HQ_PREV_N] = th_n_q
        held[ix.HQ_PREV_T] = x_q
        if int(P[ix.V_FEEDBACK]) == 1:
            w_s_meas = (v_t_meas + H * w_n_meas) / H
        e_s = velocity_error(w_cmd_s, w_s_meas, P)
        i_raw = current_command(e_s, held[ix.HIV_S], P)
        held[ix.HIV_S] += tv * integrator_rate(e_s, i_raw, P[ix.I_MAX])
        held[ix.HI_CMD_S] = saturate(i_raw, P[ix.I_MAX])
        if active_nut:
            e_n = velocity_error(w_cmd_n, w_n_meas, P)
            i_raw = current_command(e_n, held[ix.HIV_N], P)
            held[ix.HIV_N] += tv * integrator_rate(e_n, i_raw, P[ix.I_MAX])
            held[ix.HI_CMD_N] = saturate(i_raw, P[ix.I_MAX])
    if n_cur > 0 and k % n_cur == 0:
        tc = n_cur * base
        aux = np.empty(ix.N_AUX)
        commands(t, y, held, P, ref, n_pos, n_vel, aux)
        for m in range(2):
            if m == 1 and not active_nut:
                break
            i_cmd = aux[ix.A_I_CMD_S + m]
            e = i_cmd - y[ix.I_S + m]
            u_raw = voltage_command(e, held[ix.HIC_S + m], P)
            held[ix.HIC_S + m] += tc * integrator_rate(e, u_raw, P[ix.U_MAX])
            held[ix.HU_S + m] = saturate(u_raw, P[ix.U_MAX])


@kernel
def commands(t: float, y: np.ndarray, held: np.ndarray, P: np.ndarray, ref: np.ndarray,
             n_pos: int, n_vel: int, aux: np.ndarray) -> None:
    """Speed and current commands of both motors (continuous loops evaluated here)."""
    H = P[ix.H]
    if n_pos > 0:
        aux[ix.A_W_CMD_S] = held[ix.HW_CMD_S]
        aux[ix.A_W_CMD_N] = held[ix.HW_CMD_N]
    else:
        aux[ix.A_W_CMD_S] = position_law(ref[0] - y[ix.X_T], ref[1] + ref[3], P)
        aux[ix.A_W_CMD_N] = nut_speed_command(ref[2] - H * y[ix.TH_N], ref[3], P)
    if n_vel > 0:
        aux[ix.A_I_CMD_S] = held[ix.HI_CMD_S]
        aux[ix.A_I_CMD_N] = held[ix.HI_CMD_N]
    else:
        w_s = y[ix.W_S]
        if int(P[ix.V_FEEDBACK]) == 1:
            w_s = (y[ix.V_T] + H * y[ix.W_N]) / H
        e_s = velocity_error(aux[ix.A_W_CMD_S], w_s, P)
        e_n = velocity_error(aux[ix.A_W_CMD_N], y[ix.W_N], P)
        aux[ix.A_I_CMD_S] = saturate(current_command(e_s, y[ix.IV_S], P), P[ix.I_MAX])
        aux[ix.A_I_CMD_N] = saturate(current_command(e_n, y[ix.IV_N], P), P[ix.I_MAX])
