"""Tight references for the accuracy convergence tests with friction on (issue 35 item 2):
scipy Radau on the plain-Python model, never feeddrive's integrator.

Run from the repository root::

    .venv/bin/python reference/make_accuracy_reference.py            # all cases
    .venv/bin/python reference/make_accuracy_reference.py cdfs_2p0

Cases (the shipped ``wang2021`` set, LuGre at the three sites, table at mid-screw, from rest
with the default 0.1-s start ramp, 3 s): the CDFS at 2.0 mm/s and the DDFS at 0.5 mm/s with
the hollow motor at 16 mm/s — both smooth (Wang2021 Sect. 5.2, Fig. 8).

``--check-reversals``: the DDFS's table reverses eight times in its start (its guide's
LuGre law has a kink at v = 0); the case is integrated again with Radau split exactly at
each reversal (``solve_ivp`` events, the guide's direction branch held on each side) at the
reference's and two tighter settings, and the largest differences to the stored reference
are printed — the check that the reference is not what kept the engine's error from
converging (docs/model.md, "Friction reversals are events": ≤ 1.3e-14 m).

Each is integrated twice with ``solve_ivp(method="Radau")`` on
``reference.scipy_model.ReferenceModel``, split at the end of the start ramp: at rtol 1e-11
with absolute tolerances 1e-4 × the engine's former fixed defaults (1e-14 m, 1e-12 m/s,
1e-10 A), and again at rtol 1e-12 with 1e-5 × (the *check*).  The file keeps the first on
the 1-ms grid (``time``, ``table_position``, ``table_speed``) and, as ``reference_error_*``,
the largest difference between the two: what a comparison against the reference can resolve.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import feeddrive  # noqa: E402
from feeddrive.model.reference import ConstantSpeed  # noqa: E402
from feeddrive.parameters import dumps  # noqa: E402
from reference.make_radau_reference import radau_states  # noqa: E402
from reference.scipy_model import STATE_NAMES  # noqa: E402

DATA = ROOT / "tests" / "data"
SETTINGS = {"reference": (1e-11, 1e-4), "check": (1e-12, 1e-5)}  # (rtol, × former atol)
OUTPUT_INTERVAL = 1e-3  # [s]
DURATION = 3.0  # [s]
X_T, V_T = STATE_NAMES.index("table_position"), STATE_NAMES.index("table_speed")
#: name -> (drive, table speed [m/s], nut speed [m/s])
CASES = {"cdfs_2p0": ("cdfs", 2.0e-3, 0.0), "ddfs_0p5_vn16": ("ddfs", 0.5e-3, 16e-3)}


def radau(drive: str, table_speed: float, nut_speed: float, rtol: float,
          atol_scale: float, *, params: Any = None,
          duration: float = DURATION) -> tuple[np.ndarray, np.ndarray, dict[str, float]]:
    """(time, states [15 × n], statistics) on the 1-ms grid (``params``: default the shipped
    ``wang2021`` set), by :func:`reference.make_radau_reference.radau_states`."""
    params = params if params is not None else feeddrive.preset("wang2021")
    profile = ConstantSpeed(table_speed=table_speed, nut_speed=nut_speed)
    return radau_states(params, drive, profile, duration, rtol, atol_scale)


def make(name: str) -> Path:
    drive, v_t, v_n = CASES[name]
    runs = {key: radau(drive, v_t, v_n, rtol, scale) for key, (rtol, scale) in SETTINGS.items()}
    (t, y, stats), (_, y_check, _) = runs["reference"], runs["check"]
    path = DATA / f"accuracy_{name}.npz"
    arrays: dict[str, Any] = {
        "time": t, "table_position": y[X_T], "table_speed": y[V_T],
        "reference_error_table_position": float(np.max(np.abs(y[X_T] - y_check[X_T]))),
        "reference_error_table_speed": float(np.max(np.abs(y[V_T] - y_check[V_T]))),
        "rtol": SETTINGS["reference"][0], "atol_scale": SETTINGS["reference"][1],
        "drive": drive, "table_speed_command": v_t, "nut_speed_command": v_n,
        "parameters_toml": dumps(feeddrive.preset("wang2021")), **stats}
    np.savez_compressed(path, **arrays)
    print(f"{name}: {stats['wall_time_s']:.1f} s wall, nfev {stats['nfev']:.0f}; reference vs "
          f"check: x_t {arrays['reference_error_table_position']:.2e} m, v_t "
          f"{arrays['reference_error_table_speed']:.2e} m/s → {path.relative_to(ROOT)}",
          flush=True)
    return path


class _HeldBranch:
    """A LuGre site with its direction branch held (``sign``): smooth on either side of a
    reversal, so that Radau, split at the reversals, never steps across the kink."""

    states = ("bristle",)

    def __init__(self, law: Any) -> None:
        self.law, self.sign = law, 1.0

    def force_and_rate(self, v: float, z: float) -> tuple[float, float]:
        law, b = self.law, 0 if self.sign > 0 else 1
        G = law.coulomb[b] + (law.static[b] - law.coulomb[b]) * np.exp(-(v / law.stribeck[b]) ** 2)
        zdot = v - law.sigma0 * self.sign * v * z / G
        return law.sigma0 * z + law.sigma1 * zdot + law.viscous[b] * v, zdot


def radau_split_at_reversals(name: str, rtol: float,
                             atol_scale: float) -> tuple[np.ndarray, np.ndarray, list[float]]:
    """(time, states, reversal instants) of case ``name`` by Radau with an event at every
    zero crossing of the table speed and the guide's branch switched there."""
    from scipy.integrate import solve_ivp

    from reference.scipy_model import ReferenceModel, _Site

    drive, v_t, v_n = CASES[name]
    profile = ConstantSpeed(table_speed=v_t, nut_speed=v_n)
    model = ReferenceModel(feeddrive.preset("wang2021"), drive, 0.4, profile)
    g = model.guide_site
    held = _HeldBranch(g.law)
    model.guide_site = _Site(g.name, held, g.scale, g.index)
    atol = model.tolerances() * atol_scale
    grid = np.arange(int(round(DURATION / OUTPUT_INTERVAL)) + 1) * OUTPUT_INTERVAL
    y0 = np.zeros(model.n_state)
    ts, ys, reversals = [], [], []
    for a, b in ((0.0, profile.ramp_time), (profile.ramp_time, DURATION)):
        t0 = a
        while True:
            sel = (grid >= t0 - 1e-12) & ((grid < b - 1e-12) | (b == DURATION))

            def crossing(t: float, y: np.ndarray) -> float:
                return float(y[V_T])

            crossing.terminal = True  # type: ignore[attr-defined]
            crossing.direction = -held.sign  # type: ignore[attr-defined]
            sol = solve_ivp(model, (t0, b), y0, method="Radau", rtol=rtol, atol=atol,
                            jac=model.jacobian, t_eval=grid[sel], dense_output=True,
                            events=[crossing])
            if sol.status < 0:
                raise RuntimeError(f"Radau failed at t = {sol.t[-1]:g} s: {sol.message}")
            ts.append(sol.t)
            ys.append(sol.y)
            if sol.status == 1:
                t0 = float(sol.t_events[0][0])
                y0 = sol.y_events[0][0].copy()
                y0[V_T] = 0.0
                reversals.append(t0)
                held.sign = -held.sign
                continue
            y0 = sol.sol(b)
            break
    return np.concatenate(ts), np.concatenate(ys, axis=1), reversals


def check_reversals(name: str = "ddfs_0p5_vn16") -> None:
    with np.load(DATA / f"accuracy_{name}.npz") as f:
        x_ref, v_ref = f["table_position"], f["table_speed"]
    for rtol, scale in ((1e-11, 1e-4), (1e-12, 1e-5), (1e-13, 1e-6)):
        _, y, reversals = radau_split_at_reversals(name, rtol, scale)
        print(f"{name} split at {len(reversals)} reversals, rtol {rtol:g}: x_t "
              f"{np.max(np.abs(y[X_T] - x_ref)):.2e} m, v_t {np.max(np.abs(y[V_T] - v_ref)):.2e}"
              f" m/s from the stored reference", flush=True)


def main(argv: list[str]) -> None:
    if "--check-reversals" in argv:
        check_reversals()
        return
    chosen = [n for n in CASES if not argv or n in argv]
    if not chosen:
        raise SystemExit(f"unknown case; expected one of {list(CASES)}")
    for name in chosen:
        make(name)


if __name__ == "__main__":
    main(sys.argv[1:])
