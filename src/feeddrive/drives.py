"""CDFS and DDFS plants: the right-hand side of the closed-loop equations.

Wang2021 Eqs. (7)–(8) (DDFS) with the friction of Eqs. (9)–(11); the CDFS is the DDFS with
the hollow motor held (Sect. 2; ``nut_active = 0`` locks nut angle, speed and current).

    J_s ω̇_s = K_t i_s − H·F_sf(Hω_s, z_s) − H·F_d
    J_n ω̇_n = K_t i_n − H·F_nf(Hω_n, z_n) + H·F_d
    m_t v̇_t = F_d − F_gf(v_t, z_g)
    F_d     = K_eq(a)·[H(θ_s − θ_n) − x_t] + c_ax·[H(ω_s − ω_n) − v_t]
    L i̇     = u − R i − K_emf ω

Friction forces are Table 1's linear-equivalent forces; H·F is the shaft torque.  K_eq(a)
follows Eqs. (2)–(5) at the table's current position a = x0 + x_t (or a fixed value).
"""

from __future__ import annotations

import numpy as np

from . import layout as ix
from ._jit import kernel
from .control import (
    commands,
    integrator_rate,
    reference_kernel,
    saturate,
    velocity_error,
    voltage_command,
)
from .friction import bristle_rate_kernel


@kernel
def equivalent_stiffness_kernel(x_t: float, P: np.ndarray) -> float:
    """K_eq [N/m] at table displacement x_t [m] from the start position.  Eqs. (4)–(5)."""
    if P[ix.K_FIXED] > 0.0:
        return P[ix.K_FIXED]
    a = P[ix.X0] + x_t
    length = P[ix.LEN]
    # keep the nut strictly between the supports (Eq. 4 diverges at the supports)
    lo = 1e-3 * length
    if a < lo:
        a = lo
    elif a > length - lo:
        a = length - lo
    if P[ix.SUPPORT] < 0.5:
        c_screw = a * (length - a) / (P[ix.EA] * length)
    else:
        c_screw = a / P[ix.EA]
    return 1.0 / (P[ix.C0] + c_screw)


@kernel
def _site(v: float, z: float, p: np.ndarray) -> tuple[float, float]:
    """(friction force [N], bristle rate [m/s]) of one LuGre site."""
    dz = bristle_rate_kernel(v, z, p)
    o = 0 if v >= 0.0 else 4
    return p[8] * z + p[9] * dz + p[o + 3] * v, dz


@kernel
def rhs(t: float, y: np.ndarray, held: np.ndarray, P: np.ndarray, fr_s: np.ndarray,
        fr_n: np.ndarray, fr_g: np.ndarray, ref_table: np.ndarray, n_pos: int, n_vel: int,
        n_cur: int, dy: np.ndarray, aux: np.ndarray) -> None:
    """Closed-loop state derivative dy at (t, y); auxiliary signals into aux."""
    ref = np.empty(4)
    reference_kernel(t, P, ref_table, ref)
    aux[ix.A_X_REF] = ref[0]
    aux[ix.A_V_REF] = ref[1]
    aux[ix.A_XN_REF] = ref[2]
    aux[ix.A_VN_REF] = ref[3]
    commands(t, y, held, P, ref, n_pos, n_vel, aux)
    H = P[ix.H]
    nut = P[ix.NUT_ACTIVE] > 0.5

    # velocity-loop integrators (continuous loop only)
    if n_vel == 0 and P[ix.KVI] != 0.0:
        w_s = y[ix.W_S]
        if int(P[ix.V_FEEDBACK]) == 1:
            w_s = (y[ix.V_T] + H * y[ix.W_N]) / H
        e_s = velocity_error(aux[ix.A_W_CMD_S], w_s, P)
        raw = P[ix.KVP] * e_s + P[ix.KVI] * y[ix.IV_S]
        dy[ix.IV_S] = integrator_rate(e_s, raw, P[ix.I_MAX])
        if nut:
            e_n = velocity_error(aux[ix.A_W_CMD_N], y[ix.W_N], P)
            raw = P[ix.KVP] * e_n + P[ix.KVI] * y[ix.IV_N]
            dy[ix.IV_N] = integrator_rate(e_n, raw, P[ix.I_MAX])
        else:
            dy[ix.IV_N] = 0.0
    else:
        dy[ix.IV_S] = 0.0
        dy[ix.IV_N] = 0.0

    # current loops → armature voltage
    for m in range(2):
        if n_cur > 0:
            u = held[ix.HU_S + m]
            dy[ix.IC_S + m] = 0.0
        else:
            e = aux[ix.A_I_CMD_S + m] - y[ix.I_S + m]
            raw = voltage_command(e, y[ix.IC_S + m], P)
            u = saturate(raw, P[ix.U_MAX])
            dy[ix.IC_S + m] = integrator_rate(e, raw, P[ix.U_MAX]) if P[ix.KII] != 0.0 else 0.0
        aux[ix.A_U_S + m] = u

    # mechanics
    w_s = y[ix.W_S]
    w_n = y[ix.W_N]
    v_t = y[ix.V_T]
    f_s, dz_s = _site(H * w_s, y[ix.Z_S], fr_s)
    f_g, dz_g = _site(v_t, y[ix.Z_G], fr_g)
    k_eq = equivalent_stiffness_kernel(y[ix.X_T], P)
    f_d = (k_eq * (H * (y[ix.TH_S] - y[ix.TH_N]) - y[ix.X_T])
           + P[ix.C_AX] * (H * (w_s - w_n) - v_t))
    dy[ix.TH_S] = w_s
    dy[ix.W_S] = (P[ix.KT_S] * y[ix.I_S] - H * f_s - H * f_d) / P[ix.J_S]
    dy[ix.X_T] = v_t
    dy[ix.V_T] = (f_d - f_g) / P[ix.M_T]
    dy[ix.Z_S] = dz_s
    dy[ix.Z_G] = dz_g
    dy[ix.I_S] = (aux[ix.A_U_S] - P[ix.R_S] * y[ix.I_S] - P[ix.KE_S] * w_s) / P[ix.L_S]
    if nut:
        f_n, dz_n = _site(H * w_n, y[ix.Z_N], fr_n)
        dy[ix.TH_N] = w_n
        dy[ix.W_N] = (P[ix.KT_N] * y[ix.I_N] - H * f_n + H * f_d) / P[ix.J_N]
        dy[ix.Z_N] = dz_n
        dy[ix.I_N] = (aux[ix.A_U_N] - P[ix.R_N] * y[ix.I_N] - P[ix.KE_N] * w_n) / P[ix.L_N]
    else:
        f_n = 0.0
        dy[ix.TH_N] = 0.0
        dy[ix.W_N] = 0.0
        dy[ix.Z_N] = 0.0
        dy[ix.I_N] = 0.0
    aux[ix.A_F_S] = f_s
    aux[ix.A_F_N] = f_n
    aux[ix.A_F_G] = f_g
    aux[ix.A_F_D] = f_d
    aux[ix.A_K_EQ] = k_eq
