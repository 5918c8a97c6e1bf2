"""Tight references for the accuracy convergence tests with friction on (issue 35 item 2):
scipy Radau on the plain-Python model, never feeddrive's integrator.

Run from the repository root::

    .venv/bin/python reference/make_accuracy_reference.py            # all cases
    .venv/bin/python reference/make_accuracy_reference.py cdfs_2p0

Cases (the shipped ``wang2021`` set, LuGre at the three sites, table at mid-screw, from rest
with the default 0.1-s start ramp, 3 s): the CDFS at 2.0 mm/s and the DDFS at 0.5 mm/s with
the hollow motor at 16 mm/s — both smooth (Wang2021 Sect. 5.2, Fig. 8).

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


def main(argv: list[str]) -> None:
    chosen = [n for n in CASES if not argv or n in argv]
    if not chosen:
        raise SystemExit(f"unknown case; expected one of {list(CASES)}")
    for name in chosen:
        make(name)


if __name__ == "__main__":
    main(sys.argv[1:])
