"""The closed loop without friction as a linear system, and its exact response.

With the friction of all three sites switched off (σ0 = σ1 = σ2 = 0, so F = 0 and ż = v), a
fixed K_eq, continuous P velocity and current loops, no saturation and a constant-speed
profile without start ramp, the closed loop is linear time-invariant with an affine input:

    ẏ = A y + b0 + b1·t         (the references x_ref = v_t·t, x_n,ref = v_n·t)

Augmenting the state with τ (τ̇ = 1) and a constant 1 makes it homogeneous, ẏ_a = A_a y_a,
so y(t) = expm(A_a t)·[y(0); 0; 1] exactly.  ``augmented_matrix`` builds A_a row by row from
the equations (Wang2021 Eqs. (7)–(8) and the cascade of ``reference/scipy_model.py``), written
out here once more by hand for the convergence and cross-path tests of the engine.
"""

from __future__ import annotations

import hashlib
import math
from collections import OrderedDict

import numpy as np
from scipy.linalg import expm

from feeddrive.model.mechanisms.shared import Motor
from feeddrive.parameters import DriveParameters

N_STATE = 15
TAU, ONE = 15, 16  # augmented states: time and the constant 1
N_AUG = 17
# state order: θs ωs θn ωn x v zs zn zg is in ivs ivn ics icn
TH_S, W_S, TH_N, W_N, X, V, Z_S, Z_N, Z_G, I_S, I_N = range(11)


def _unit(i: int, w: float = 1.0) -> np.ndarray:
    r = np.zeros(N_AUG)
    r[i] = w
    return r


def augmented_matrix(params: DriveParameters, drive: str, table_speed: float,
                     nut_speed: float, stiffness: float) -> np.ndarray:
    """A_a (17 × 17) of the frictionless closed loop with K_eq = ``stiffness`` [N/m].

    ``drive = "cdfs"`` holds the nut (its rows stay zero).  Raises if the controller has
    integral action (the integrals would be extra states with their own rows).
    """
    c = params.controller
    if c.velocity_integral_gain != 0.0 or c.current_integral_gain != 0.0:
        raise ValueError("augmented_matrix: P loops only")
    s = params.screw
    H = s.lead / (2.0 * math.pi)
    J_s = params.screw_motor.inertia + s.shaft_inertia
    J_n = params.hollow_motor.inertia + s.nut_inertia
    m_t = params.table.mass
    c_ax = params.stiffness.axial_damping
    k_p = c.position_gain * (c.velocity_command_gain if c.kv_placement == "position_output"
                             else 1.0)
    e_scale = ((H if c.velocity_gain_basis == "table" else 1.0)
               / (c.velocity_command_gain if c.kv_placement == "velocity_error" else 1.0))
    ff = 1.0 if c.velocity_feedforward else 0.0
    e = _unit

    F_d = stiffness * (H * e(TH_S) - H * e(TH_N) - e(X)) + c_ax * (
        H * e(W_S) - H * e(W_N) - e(V))

    def armature(w_cmd: np.ndarray, w_meas: np.ndarray, current: int,
                 speed: int, motor: Motor) -> np.ndarray:
        i_cmd = c.velocity_gain * e_scale * (w_cmd - w_meas)
        u = c.current_gain * (i_cmd - e(current))
        return (u - motor.resistance * e(current)
                - motor.back_emf_constant * e(speed)) / motor.inductance

    A = np.zeros((N_AUG, N_AUG))
    # screw motor: table position loop with feed-forward of v_t + v_n
    w_cmd_s = (k_p * (table_speed * e(TAU) - e(X)) + ff * (table_speed + nut_speed) * e(ONE)) / H
    w_meas_s = (e(V) + H * e(W_N)) / H if c.velocity_feedback == "table" else e(W_S)
    A[TH_S] = e(W_S)
    A[W_S] = (params.screw_motor.torque_constant * e(I_S) - H * F_d) / J_s
    A[X] = e(V)
    A[V] = F_d / m_t
    A[Z_S] = H * e(W_S)  # ż = v with σ0 = 0
    A[Z_G] = e(V)
    A[I_S] = armature(w_cmd_s, w_meas_s, I_S, W_S, params.screw_motor)
    if drive == "ddfs":
        w_cmd_n = (k_p * (nut_speed * e(TAU) - H * e(TH_N)) + ff * nut_speed * e(ONE)) / H
        A[TH_N] = e(W_N)
        A[W_N] = (params.hollow_motor.torque_constant * e(I_N) + H * F_d) / J_n
        A[Z_N] = H * e(W_N)
        A[I_N] = armature(w_cmd_n, e(W_N), I_N, W_N, params.hollow_motor)
    A[TAU] = e(ONE)
    return A


#: the last responses computed, by the digest of (A_a, times): a test compares several methods
#: and accuracies on one output grid, whose reference is the same matrix exponentials each time
#: (each an ``expm`` per instant, ≈ 0.4 ms; 1 001 instants ≈ 0.4 s, against ≈ 2 ms for the
#: engine's run it checks)
_RESPONSES: OrderedDict[bytes, np.ndarray] = OrderedDict()
_KEEP = 32


def exact_response(A: np.ndarray, times: np.ndarray) -> np.ndarray:
    """States (len(times) × 15) from rest: expm(A_a t)·[0, …, 0, τ = 0, 1].

    Computed once per (A_a, times) in a process and kept (the last 32); a fresh copy is
    returned each call."""
    A = np.ascontiguousarray(A, dtype=float)
    times = np.ascontiguousarray(times, dtype=float)
    key = hashlib.sha256(repr((A.shape, times.shape)).encode() + A.tobytes()
                         + times.tobytes()).digest()
    out = _RESPONSES.get(key)
    if out is None:
        y0 = np.zeros(N_AUG)
        y0[ONE] = 1.0
        out = np.array([(expm(A * t) @ y0)[:N_STATE] for t in times]).reshape(-1, N_STATE)
        _RESPONSES[key] = out
        while len(_RESPONSES) > _KEEP:
            _RESPONSES.popitem(last=False)
    else:
        _RESPONSES.move_to_end(key)
    return out.copy()


def frictionless() -> np.ndarray:
    """Packed LuGre array (layout of ``LuGreParameters.as_array``) with zero force:
    σ0 = σ1 = σ2 = 0 and F_c = F_s = 1 N (so the bristle rate is finite and equals v)."""
    p = np.zeros(10)
    p[[0, 1, 4, 5]] = 1.0
    p[[2, 6]] = 1e-3
    return p
