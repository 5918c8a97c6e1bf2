"""Tight-tolerance references for creeping runs: scipy Radau on the plain-Python model.

Run from the repository root::

    /work/venv/bin/python reference/make_radau_reference.py            # all cases
    /work/venv/bin/python reference/make_radau_reference.py cdfs_creep_1p0
    /work/venv/bin/python reference/make_radau_reference.py deciding   # the report's trials

For every case of ``reference.cases.RADAU_CASES`` this integrates
``reference.scipy_model.ReferenceModel`` with ``solve_ivp(method="Radau", rtol=1e-10)`` and
absolute tolerances 1000× tighter than the engine's defaults (1e-13 m, 1e-11 m/s, 1e-9 A),
in two pieces split at the end of the start ramp (where the reference speed has a kink), and
writes ``tests/data/radau_<case>.npz`` with

* ``time`` [s] (1-ms grid) and ``table_speed`` [m/s] on it,
* the steady-window figures of :func:`stick_slip_figures`: ``ripple`` [m/s] (max − min),
  ``period`` [s] (stick-slip period), ``mean_speed`` [m/s], ``window`` [s],
* the settings (``rtol``, ``atol``), the run statistics and the parameters as TOML.

Recorded run (2 cores, AMD EPYC, Python 3.11, scipy 1.17.1; the Jacobian by central
differences of the model): cdfs_creep_1p0 2.4 s (111 409 RHS calls), cdfs_creep_1p5 2.0 s
(85 983), ddfs_creep_0p5 3.6 s (142 938); 8.1 s in all.  The references are converged: a rerun
at rtol = 1e-12 and absolute tolerances 100× tighter moves the table speed by at most
1e-9 m/s, the ripple by 3e-8 relative and the period by 4e-10 relative.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from feeddrive.parameters import dumps  # noqa: E402
from reference.cases import (  # noqa: E402
    DECIDING,
    DECIDING_SETTINGS,
    RADAU_CASES,
    Case,
    deciding_name,
    trial_profile,
)
from reference.scipy_model import STATE_NAMES, ReferenceModel, tolerances  # noqa: E402

DATA = ROOT / "tests" / "data"
RTOL = 1e-10
ATOL_SCALE = 1e-3  # × the engine's default absolute tolerances
OUTPUT_INTERVAL = 1e-3  # s
V_T = STATE_NAMES.index("table_speed")


def stick_slip_figures(time_s: np.ndarray, speed: np.ndarray,
                       window: tuple[float, float]) -> dict[str, float]:
    """Ripple, period and mean of a speed trace over ``window`` [s].

    ripple [m/s]: max − min of the samples.  period [s]: mean spacing of the upward crossings
    of the mid level (min + max)/2, interpolated linearly between samples; a crossing counts
    only after the speed has dropped below min + 0.25·ripple since the last one (a Schmitt
    trigger, so wiggles within a slip phase are not counted).  NaN if fewer than two cycles.
    """
    sel = (time_s >= window[0]) & (time_s <= window[1])
    t, v = time_s[sel], speed[sel]
    lo, hi = float(np.min(v)), float(np.max(v))
    ripple = hi - lo
    mid, arm = lo + 0.5 * ripple, lo + 0.25 * ripple
    crossings = []
    armed = False
    for k in range(1, v.size):
        if v[k - 1] < arm:
            armed = True
        if armed and v[k - 1] < mid <= v[k]:
            crossings.append(t[k - 1] + (mid - v[k - 1]) / (v[k] - v[k - 1]) * (t[k] - t[k - 1]))
            armed = False
    period = (float((crossings[-1] - crossings[0]) / (len(crossings) - 1))
              if len(crossings) >= 2 else float("nan"))
    mean = float(np.trapezoid(v, t) / (t[-1] - t[0]))
    return {"ripple": ripple, "period": period, "mean_speed": mean,
            "cycles": float(max(len(crossings) - 1, 0))}


def radau_states(params: Any, drive: str, profile: Any, duration: float, rtol: float,
                 atol_scale: float, **model_options: Any
                 ) -> tuple[np.ndarray, np.ndarray, dict[str, float]]:
    """(time, states [n_state × n], statistics) of ``drive`` with ``params`` following
    ``profile`` from rest on the 1-ms grid, split at the end of the start ramp (where the
    reference speed has a kink); absolute tolerances ``atol_scale`` × the former fixed
    defaults.  ``model_options`` go to :class:`ReferenceModel` (e.g. ``stribeck_exponents``);
    the states are then in ``ReferenceModel(...).state_names`` order (15, ``STATE_NAMES``,
    for the default layout)."""
    model = ReferenceModel(params, drive, 0.4, profile, **model_options)
    default = model.state_names == STATE_NAMES
    atol = (tolerances(model.H) if default else model.tolerances()) * atol_scale
    n = int(round(duration / OUTPUT_INTERVAL))
    grid = np.arange(n + 1) * OUTPUT_INTERVAL
    ramp = getattr(profile, "ramp_time", 0.0)  # a SineSpeed has no kink
    cuts = [0.0, ramp, duration] if ramp > 0 else [0.0, duration]
    y0 = np.zeros(model.n_state)
    ys, ts = [], []
    stats = {"nfev": 0.0, "njev": 0.0, "nlu": 0.0}
    started = time.perf_counter()
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        last = b == cuts[-1]
        sel = (grid >= a - 1e-12) & ((grid < b - 1e-12) | last)
        sol = solve_ivp(model, (a, b), y0, method="Radau", rtol=rtol, atol=atol,
                        jac=model.jacobian, t_eval=grid[sel], dense_output=True)
        if sol.status != 0:
            raise RuntimeError(f"Radau failed at t = {sol.t[-1]:g} s: {sol.message}")
        ts.append(sol.t)
        ys.append(sol.y)
        y0 = sol.sol(b)
        for k in stats:
            stats[k] += float(getattr(sol, k))
    stats["wall_time_s"] = time.perf_counter() - started
    return np.concatenate(ts), np.concatenate(ys, axis=1), stats


def radau_run(case: Case, rtol: float = RTOL,
              atol_scale: float = ATOL_SCALE) -> tuple[np.ndarray, np.ndarray, dict[str, float]]:
    """(time, states [15 × n], statistics) of ``case`` on the 1-ms grid."""
    try:
        return radau_states(case.parameters(), case.drive, case.profile(), case.duration,
                            rtol, atol_scale)
    except RuntimeError as err:
        raise RuntimeError(f"{case.name}: {err}") from None


def make(case: Case) -> Path:
    t, y, stats = radau_run(case)
    figures = stick_slip_figures(t, y[V_T], (case.window_start, case.duration))
    DATA.mkdir(parents=True, exist_ok=True)
    path = DATA / f"radau_{case.name}.npz"
    model = ReferenceModel(case.parameters(), case.drive, 0.4, case.profile())
    arrays: dict[str, Any] = {
        "time": t, "table_speed": y[V_T], "window": np.array([case.window_start, case.duration]),
        "rtol": RTOL, "atol": tolerances(model.H) * ATOL_SCALE,
        "parameters_toml": dumps(case.parameters()), "case": repr(case), **figures, **stats}
    np.savez_compressed(path, **arrays)
    print(f"{case.name}: {stats['wall_time_s']:.1f} s wall, nfev {stats['nfev']:.0f}, "
          f"ripple {figures['ripple'] * 1e3:.5f} mm/s, period {figures['period'] * 1e3:.4f} ms, "
          f"mean {figures['mean_speed'] * 1e3:.5f} mm/s ({figures['cycles']:.0f} cycles) "
          f"→ {path.relative_to(ROOT)}", flush=True)
    return path


DECIDING_PATH = DATA / "radau_deciding_trials.npz"


def make_deciding() -> Path:
    """The Radau references of the report's deciding trials (``reference.cases.DECIDING``) at
    ``DECIDING_SETTINGS``: one file, each trial's table speed [m/s] on its 1-ms grid under
    its :func:`~reference.cases.deciding_name`, with the settings and the parameters as TOML
    (the loader refuses a file made from other ones)."""
    import feeddrive as fd

    rtol, scale = DECIDING_SETTINGS
    params = fd.preset("wang2021")
    arrays: dict[str, Any] = {"rtol": rtol, "atol_scale": scale,
                              "parameters_toml": dumps(params)}
    for trial in DECIDING:
        drive, speed, nut, duration = trial
        _, y, stats = radau_states(params, drive, trial_profile(speed, nut), duration, rtol,
                                   scale)
        arrays[deciding_name(trial)] = y[V_T]
        print(f"{deciding_name(trial)}: {stats['wall_time_s']:.1f} s wall, nfev "
              f"{stats['nfev']:.0f}", flush=True)
    np.savez_compressed(DECIDING_PATH, **arrays)
    print(f"→ {DECIDING_PATH.relative_to(ROOT)}")
    return DECIDING_PATH


def deciding_reference(trial: tuple[str, float, float, float]) -> np.ndarray:
    """The stored Radau table speed [m/s] of a deciding trial on its 1-ms grid
    (:func:`make_deciding`); refused where the file was made at other settings or from
    other parameters than ``wang2021``'s now."""
    import feeddrive as fd

    with np.load(DECIDING_PATH) as data:
        made = (float(data["rtol"]), float(data["atol_scale"]))
        if made != DECIDING_SETTINGS or str(data["parameters_toml"]) != dumps(
                fd.preset("wang2021")):
            raise RuntimeError(f"{DECIDING_PATH.name} was made at {made} or from other "
                               "parameters; run reference/make_radau_reference.py deciding")
        return np.array(data[deciding_name(trial)])


def main(argv: list[str]) -> None:
    if argv == ["deciding"]:
        make_deciding()
        return
    chosen = [c for c in RADAU_CASES if not argv or c.name in argv]
    if not chosen:
        raise SystemExit(f"unknown case; expected one of {[c.name for c in RADAU_CASES]}")
    started = time.perf_counter()
    for case in chosen:
        make(case)
    print(f"total {time.perf_counter() - started:.1f} s")


if __name__ == "__main__":
    main(sys.argv[1:])
