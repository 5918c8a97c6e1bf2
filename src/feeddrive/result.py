"""Simulation results: an xarray Dataset with named signals, SI units in attrs."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from . import layout as ix
from .parameters import dumps

if TYPE_CHECKING:
    from .analysis.metrics import CreepMetrics, CreepThresholds
    from .control import Profile
    from .simulate import DriveSystem

# name: (source, unit, description)
_SIGNALS: dict[str, tuple[str, str, str]] = {
    "table_position": ("y:table_position", "m", "table displacement from its start x_t"),
    "table_speed": ("y:table_speed", "m/s", "table speed"),
    "screw_angle": ("y:screw_angle", "rad", "screw motor / shaft angle θ_s"),
    "nut_angle": ("y:nut_angle", "rad", "hollow motor / nut angle θ_n"),
    "screw_speed": ("y:screw_speed", "rad/s", "screw motor speed"),
    "nut_speed": ("y:nut_speed", "rad/s", "hollow motor speed"),
    "screw_current": ("y:screw_current", "A", "screw motor current"),
    "nut_current": ("y:nut_current", "A", "hollow motor current"),
    "screw_bristle": ("y:screw_bristle", "m", "LuGre bristle state, screw shaft (÷H form)"),
    "nut_bristle": ("y:nut_bristle", "m", "LuGre bristle state, hollow shaft (÷H form)"),
    "guide_bristle": ("y:guide_bristle", "m", "LuGre bristle state, linear guide"),
    "screw_voltage": ("a:screw_voltage", "V", "screw motor armature voltage"),
    "nut_voltage": ("a:nut_voltage", "V", "hollow motor armature voltage"),
    "screw_current_command": ("a:screw_current_command", "A", "screw current command"),
    "nut_current_command": ("a:nut_current_command", "A", "hollow current command"),
    "screw_speed_command": ("a:screw_speed_command", "rad/s", "screw speed command"),
    "nut_speed_command": ("a:nut_speed_command", "rad/s", "hollow speed command"),
    "screw_friction": ("a:screw_friction", "N", "screw-shaft friction (torque ÷ H)"),
    "nut_friction": ("a:nut_friction", "N", "hollow-shaft friction (torque ÷ H)"),
    "guide_friction": ("a:guide_friction", "N", "linear-guide friction"),
    "drive_force": ("a:drive_force", "N", "screw–nut force on the table F_d"),
    "equivalent_stiffness": ("a:equivalent_stiffness", "N/m", "K_eq at the table position"),
    "table_position_reference": ("a:table_position_reference", "m", "commanded table position"),
    "table_speed_reference": ("a:table_speed_reference", "m/s", "commanded table speed"),
    "nut_speed_reference": ("a:nut_speed_reference", "m/s", "commanded nut speed (linear)"),
}

# SI → engineering units at the edges (CSV, Parquet, CLI)
ENGINEERING = {"m": ("mm", 1e3), "m/s": ("mm/s", 1e3), "N/m": ("N/µm", 1e-6)}


def build_dataset(t: np.ndarray, y: np.ndarray, aux: np.ndarray, system: DriveSystem,
                  profile: Profile, solver_stats: dict[str, Any]) -> xr.Dataset:
    H = system.parameters.screw.transmission_ratio
    data_vars: dict[str, Any] = {}
    for name, (src, unit, desc) in _SIGNALS.items():
        kind, key = src.split(":")
        values = (y[:, ix.STATE_NAMES.index(key)] if kind == "y"
                  else aux[:, ix.AUX_NAMES.index(key)])
        data_vars[name] = ("time", np.array(values), {"units": unit, "long_name": desc})
    data_vars["screw_linear_speed"] = ("time", H * y[:, ix.W_S],
                                       {"units": "m/s", "long_name": "screw speed × H"})
    data_vars["nut_linear_speed"] = ("time", H * y[:, ix.W_N],
                                     {"units": "m/s", "long_name": "nut speed × H"})
    data_vars["following_error"] = ("time", aux[:, ix.A_X_REF] - y[:, ix.X_T],
                                    {"units": "m", "long_name": "commanded − table position"})
    attrs: dict[str, Any] = {
        "drive": system.drive,
        "table_start_position_m": system.table_position,
        "nut_hold": system.nut_hold,
        "profile": repr(profile) if not hasattr(profile, "time") else type(profile).__name__,
        "parameters_toml": dumps(system.parameters),
        "parameter_set": system.parameters.name,
        "solver": json.dumps(solver_stats),
        "conventions": "SI units; friction at the shafts as torque ÷ H (Wang2021 Table 1)",
    }
    return xr.Dataset(data_vars, coords={"time": ("time", t, {"units": "s"})}, attrs=attrs)


class Result:
    """A simulation's signals (``.dataset``), its solver statistics and summaries."""

    def __init__(self, dataset: xr.Dataset) -> None:
        self.dataset = dataset

    def __getitem__(self, name: str) -> np.ndarray:
        return np.asarray(self.dataset[name].values)

    @property
    def time(self) -> np.ndarray:
        return np.asarray(self.dataset["time"].values)

    @property
    def solver_stats(self) -> dict[str, Any]:
        stats: dict[str, Any] = json.loads(self.dataset.attrs["solver"])
        return stats

    @property
    def command_speed(self) -> float:
        """The steady commanded table speed [m/s] (largest magnitude of the reference)."""
        ref = self["table_speed_reference"]
        return float(ref[np.argmax(np.abs(ref))])

    def creep_metrics(self, *, thresholds: CreepThresholds | None = None,
                      window: tuple[float, float] | None = None) -> CreepMetrics:
        """Creep metrics of the table speed against the commanded speed."""
        from .analysis.metrics import creep_metrics
        return creep_metrics(self.time, self["table_speed"], self.command_speed,
                             thresholds=thresholds, window=window)

    def summary(self) -> dict[str, Any]:
        """Mean and ripple of table speed after the transient, stick fraction, motor speeds —
        in engineering units (mm/s), for printing."""
        import tomllib

        from .analysis.metrics import travel_warning

        m = self.creep_metrics()
        sel = (self.time >= m.window_start) & (self.time <= m.window_end)
        warnings = []
        if m.unstable:
            warnings.append(f"unstable: the loop diverges (table speed peaks at "
                            f"{max(abs(m.max_ratio), abs(m.min_ratio)):.3g}× the command, limit "
                            f"{m.thresholds.max_speed_ratio:g}×)")
        length = tomllib.loads(self.dataset.attrs["parameters_toml"])["screw"]["length"]
        travel = travel_warning(self.dataset.attrs["table_start_position_m"],
                                self["table_position"], length)
        if travel:
            warnings.append(travel)
        return {
            "drive": self.dataset.attrs["drive"],
            "command_speed_mm_s": 1e3 * self.command_speed,
            "mean_table_speed_mm_s": 1e3 * m.mean_speed,
            "ripple_ratio": m.ripple_ratio,
            "min_ratio": m.min_ratio,
            "stick_fraction": m.stick_fraction,
            "stick_slip_frequency_hz": m.stick_slip_frequency,
            "verdict": m.verdict,
            "window_s": [m.window_start, m.window_end],
            "mean_screw_speed_mm_s": 1e3 * float(np.mean(self["screw_linear_speed"][sel])),
            "mean_nut_speed_mm_s": 1e3 * float(np.mean(self["nut_linear_speed"][sel])),
            "solver": self.solver_stats,
            "warnings": warnings,
        }

    def save(self, path: str | Path) -> Path:
        from .io import save_result
        return save_result(self.dataset, path)
