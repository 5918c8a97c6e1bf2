"""Index layout of the packed vectors shared by the compiled plant, controller and solver.

numba kernels take flat float64 arrays; these module-level integers are compile-time
constants there.  Keep every index in this one place.
"""

from __future__ import annotations

# ---- state vector y
TH_S, W_S, TH_N, W_N, X_T, V_T, Z_S, Z_N, Z_G, I_S, I_N, IV_S, IV_N, IC_S, IC_N = range(15)
N_STATE = 15
STATE_NAMES = (
    "screw_angle", "screw_speed", "nut_angle", "nut_speed", "table_position", "table_speed",
    "screw_bristle", "nut_bristle", "guide_bristle", "screw_current", "nut_current",
    "screw_velocity_integral", "nut_velocity_integral", "screw_current_integral",
    "nut_current_integral",
)

# ---- packed parameter vector P
(
    H, J_S, J_N, M_T, C_AX,
    K_FIXED, C0, EA, LEN, SUPPORT, X0,
    KT_S, KE_S, L_S, R_S, KT_N, KE_N, L_N, R_N,
    KPP, KVP, KVI, KIP, KII, KV, KV_PLACE, V_BASIS, V_FEEDBACK, FF, I_MAX, U_MAX,
    T_POS, T_VEL, T_CUR, ENC_Q, GRAT_Q,
    NUT_ACTIVE,
    REF_KIND, REF_VT, REF_VN, REF_TRAMP, REF_FREQ,
    NUT_SPEED_MODE,
) = range(43)
N_PARAM = 43

# ---- held (sampled-controller) vector
(
    HW_CMD_S, HW_CMD_N, HI_CMD_S, HI_CMD_N, HU_S, HU_N,
    HIV_S, HIV_N, HIC_S, HIC_N, HQ_PREV_S, HQ_PREV_N, HQ_PREV_T,
) = range(13)
N_HELD = 13

# ---- auxiliary outputs written by the right-hand side
(
    A_W_CMD_S, A_W_CMD_N, A_I_CMD_S, A_I_CMD_N, A_U_S, A_U_N,
    A_F_S, A_F_N, A_F_G, A_F_D, A_K_EQ, A_X_REF, A_V_REF, A_XN_REF, A_VN_REF,
) = range(15)
N_AUX = 15
AUX_NAMES = (
    "screw_speed_command", "nut_speed_command", "screw_current_command",
    "nut_current_command", "screw_voltage", "nut_voltage", "screw_friction", "nut_friction",
    "guide_friction", "drive_force", "equivalent_stiffness", "table_position_reference",
    "table_speed_reference", "nut_position_reference", "nut_speed_reference",
)

# ---- profile kinds
REF_CONSTANT, REF_SINE, REF_SAMPLED = 0, 1, 2
