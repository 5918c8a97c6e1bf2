"""Sampled (zero-order-hold) control for the reference model, integrated with scipy.

Digital servo loops run at fixed periods and hold their outputs in between (Åström &
Wittenmark, *Computer-Controlled Systems*, 3rd ed., 1997, Ch. 7: zero-order hold, PI with
forward-Euler integration and conditional anti-windup).  Each loop of
``reference.scipy_model.ReferenceModel`` whose ``controller.<loop>_period`` is > 0 is sampled;
a period of 0 leaves that loop continuous (computed in ``rhs``).

Sample instants are t_k = k·T_b, T_b the fastest loop period; the position loop acts every
n_pos instants, the velocity loop every n_vel, the current loop every n_cur (T_p = n_pos·T_b,
…).  At each instant, in this order (the engine's, ``feeddrive.model.loops``):

1. position loop (if k mod n_pos = 0): measured positions from the quantised channels —
   table x_q = q_g·⌊x_t/q_g⌋ (grating resolution q_g), angles θ_q = q_e·⌊θ/q_e⌋ with
   q_e = 2π/encoder_counts — and the held speed command ω_cmd = (k_p·(x_ref − x_q) + FF·v)/H;
2. velocity loop (if k mod n_vel = 0): with an encoder or a grating set, every channel's speed
   is the difference of its quantised readings over the loop period, (q_k − q_{k−n_vel})/T_v
   (0 at k = 0); without, the true speed.  Then, with the held (or, if the position loop is
   continuous, the instantaneous) speed command,
       e = error(ω_cmd, ω_meas);  i_raw = K_vp·e + K_vi·I_v;  I_v += T_v·r(e, i_raw, I_max);
       i_cmd = sat(i_raw, I_max)
   (r: conditional integration, 0 when i_raw is beyond the limit and e pushes further);
3. current loop (if k mod n_cur = 0): e = i_cmd − i; u_raw = K_ip·e + K_ii·I_c;
   I_c += T_c·r(e, u_raw, U_max); u = sat(u_raw, U_max), i_cmd being the held command or,
   with a continuous velocity loop, the instantaneous one.

Between instants ``ReferenceModel.rhs`` integrates the plant with the held outputs
(``scipy.integrate.solve_ivp``, restarted at every instant: the right-hand side jumps there).
Only the active axes update (the nut's with the CDFS nut locked is skipped).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from .scipy_model import Grid, Held, ReferenceModel, _integral_rate, sampling_grid


def quantise(value: float, step: float) -> float:
    """An incremental encoder or grating count: ``step``·⌊value/step⌋; step 0 = ideal."""
    return value if step <= 0.0 else step * math.floor(value / step)


def sample_update(model: ReferenceModel, k: int, t: float, y: Any, grid: Grid) -> None:
    """The sampled loops' updates at instant k (time t [s], state y) into ``model.held``."""
    held = model.held
    c = model.c
    y = [float(v) for v in y]
    ref = model.reference(t)
    axes = [(a, ax) for a, ax in enumerate(model.axes) if ax.active]
    if grid.n_pos > 0 and k % grid.n_pos == 0:
        measured = list(y)
        for name, (i_pos, _) in model.channels.items():
            measured[i_pos] = quantise(y[i_pos], model.quanta[name])
        for a, ax in axes:
            held.speed_command[a] = model.speed_command(ax, ref, measured)
    if grid.n_vel > 0 and k % grid.n_vel == 0:
        tv = grid.n_vel * grid.base
        measured = list(y)
        differences = any(model.quanta[name] > 0.0 for name in model.channels)
        for name, (i_pos, i_speed) in model.channels.items():
            q = quantise(y[i_pos], model.quanta[name])
            if differences:
                measured[i_speed] = 0.0 if k == 0 else (q - held.previous[name]) / tv
            held.previous[name] = q
        for a, ax in axes:
            w_cmd = (held.speed_command[a] if grid.n_pos > 0
                     else model.speed_command(ax, ref, y))
            e = model.velocity_error(ax, w_cmd, model.measured_speed(ax, measured))
            raw, i_cmd = model.current_command(e, held.velocity_integral[a])
            held.velocity_integral[a] += tv * _integral_rate(e, raw, c.current_limit)
            held.current_command[a] = i_cmd
    if grid.n_cur > 0 and k % grid.n_cur == 0:
        tc = grid.n_cur * grid.base
        for a, ax in axes:
            if grid.n_vel > 0:
                i_cmd = held.current_command[a]
            else:
                w_cmd = (held.speed_command[a] if grid.n_pos > 0
                         else model.speed_command(ax, ref, y))
                e_w = model.velocity_error(ax, w_cmd, model.measured_speed(ax, y))
                i_cmd = model.current_command(e_w, y[ax.velocity_integral])[1]
            e = i_cmd - y[ax.current]
            raw, u = model.voltage_command(e, held.current_integral[a])
            held.current_integral[a] += tc * _integral_rate(e, raw, c.voltage_limit)
            held.voltage[a] = u


def simulate_sampled(model: ReferenceModel, duration: float, *, output_interval: float = 1e-3,
                     y0: np.ndarray | None = None, rtol: float = 1e-10,
                     atol: np.ndarray | None = None, method: str = "DOP853",
                     ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Run ``model`` from ``y0`` (rest) over ``duration`` [s] with its sampled loops held
    between their instants.

    Returns (times [s], states, outputs): every ``output_interval`` [s] (a multiple of the
    fastest loop period) the state just after that instant's update (as the engine records
    it), and the held outputs of the sampled loops, named as the engine's signals
    (``<axis>_speed_command`` [rad/s], ``<axis>_current_command`` [A], ``<axis>_voltage``
    [V]).  The model's ``held`` values start at 0 and are left at their final values.
    """
    grid = sampling_grid(model.params, output_interval)
    model.n_pos, model.n_vel, model.n_cur = grid.n_pos, grid.n_vel, grid.n_cur
    model.held = Held.zeros(len(model.axes))
    if atol is None:
        atol = model.tolerances(position=1e-15, speed=1e-13, current=1e-11)
    y = np.zeros(model.n_state) if y0 is None else np.array(y0, dtype=float)
    loops = [(n, field) for n, field in ((grid.n_pos, "speed_command"),
                                         (grid.n_vel, "current_command"),
                                         (grid.n_cur, "voltage")) if n > 0]
    outputs: dict[str, list[float]] = {f"{ax.name}_{name}": []
                                       for ax in model.axes for _, name in loops}
    n_break = round(duration / grid.base)
    times, states = [], []
    for k in range(n_break + 1):
        t = k * grid.base
        sample_update(model, k, t, y, grid)
        if k % grid.out_every == 0:
            times.append(t)
            states.append(y.copy())
            for a, ax in enumerate(model.axes):
                for _, name in loops:
                    outputs[f"{ax.name}_{name}"].append(getattr(model.held, name)[a])
        if k == n_break:
            break
        sol = solve_ivp(model.rhs, (t, (k + 1) * grid.base), y, method=method, rtol=rtol,
                        atol=atol)
        if not sol.success:
            raise RuntimeError(f"reference integration failed at t = {t:g} s: {sol.message}")
        y = sol.y[:, -1]
    return (np.array(times), np.array(states),
            {name: np.array(v) for name, v in outputs.items()})
