"""Truths for the open-loop replay (``feeddrive.model.replay``), made by the plain-Python model
(:mod:`reference.scipy_model`) and scipy's Radau — an integrator other than feeddrive's.

* :func:`force_driven` — a drive with its motor torque off (``controller.mode =
  "torque_off"``) pushed by a force record applied to the table as a negative load: for the
  linear motor that is its forcer's force K_f·i, so the record is what ``ForceReplay``
  (or ``CurrentReplay`` of F/K_f) drives feeddrive's model with;
* :func:`speed_driven` — the rack and pinion with its motor speed imposed: the model's motor
  speed state is overwritten by the record before each evaluation and its rate by 0, the
  angle integrates the record; the mesh, the table and the guide friction are the
  reference model's own equations.

Both records are interpolated linearly between their samples (``numpy.interp``), as the
replay's table is, and each sample interval is a separate Radau integration, so no step
crosses a kink of the input.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.scipy_model import Load, ReferenceModel  # noqa: E402

RTOL = 1e-9
ATOL_SCALE = 1e-2


def _piecewise(model: Any, f: Any, time: np.ndarray, y0: np.ndarray, rtol: float,
               atol: np.ndarray) -> np.ndarray:
    """States at every sample instant, one Radau integration per sample interval."""
    ys = [y0]
    y = y0
    for a, b in zip(time[:-1], time[1:], strict=True):
        sol = solve_ivp(f, (a, b), y, method="Radau", rtol=rtol, atol=atol)
        if sol.status != 0:
            raise RuntimeError(f"Radau failed at t = {sol.t[-1]:g} s: {sol.message}")
        y = sol.y[:, -1]
        ys.append(y)
    return np.array(ys).T


def force_driven(truth: Any, time: np.ndarray, force: np.ndarray, *, drive: str = "linear-motor",
                 rtol: float = RTOL, atol_scale: float = ATOL_SCALE
                 ) -> tuple[dict[str, np.ndarray], tuple[str, ...]]:
    """The table of ``drive`` pushed from rest by ``force`` [N] on ``time`` [s] (module).

    Returns
    -------
    states : dict
        State name → values at ``time`` [SI].
    names : tuple of str
        The reference model's state names.
    """
    p = truth.replace_path("controller.mode", "torque_off")
    record = type("Record", (), {"time": np.asarray(time, float),
                                 "force": -np.asarray(force, float)})
    model = ReferenceModel(p, drive, 0.0, None, load=record)
    assert isinstance(model.load, Load)
    y = _piecewise(model, model.rhs, np.asarray(time, float), np.zeros(model.n_state), rtol,
                   model.tolerances() * atol_scale)
    return {n: y[k] for k, n in enumerate(model.state_names)}, model.state_names


def speed_driven(truth: Any, time: np.ndarray, motor_speed: np.ndarray, *,
                 rtol: float = RTOL, atol_scale: float = ATOL_SCALE
                 ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The rack and pinion from rest with its motor speed [rad/s] imposed (module).

    Returns
    -------
    states : dict
        State name → values at ``time`` [SI] (``motor_speed``: the record).
    signals : dict
        ``drive_force``: the mesh force on the table [N] at ``time``.
    """
    t = np.asarray(time, float)
    w = np.asarray(motor_speed, float)
    model = ReferenceModel(truth.replace_path("controller.mode", "torque_off"), "rack-pinion",
                           0.0, None)
    iw = model.state_names.index("motor_speed")

    def f(tt: float, y: np.ndarray) -> np.ndarray:
        y = np.array(y, dtype=float)
        y[iw] = np.interp(tt, t, w)
        dy = model.rhs(tt, y)
        dy[iw] = 0.0
        return dy

    y = _piecewise(model, f, t, np.zeros(model.n_state), rtol, model.tolerances() * atol_scale)
    states = {n: y[k] for k, n in enumerate(model.state_names)}
    states["motor_speed"] = w
    rp = model.rack_section
    H = model.H
    mesh = rp.mesh_stiffness * (H * states["motor_angle"] - states["table_position"]) \
        + rp.mesh_damping * (H * w - states["table_speed"])
    return states, {"drive_force": mesh}
