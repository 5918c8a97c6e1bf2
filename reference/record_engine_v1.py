"""Record the v1 (hard-wired) engine's trajectories, before the composable core replaced it.

The composable core (``feeddrive.model``) must reproduce these runs bit-for-bit or within
1e-9 with the ball–nut share at 0 (issue "Engine core v2").  Run once with the v1 engine;
the output ``tests/data/engine_v1_regression.npz`` is what
``tests/validation/test_engine_v1_regression.py`` compares against.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import feeddrive as fd
from feeddrive.model.reference import ConstantSpeed, SampledSpeed, SineSpeed

OUT = Path(__file__).resolve().parents[1] / "tests" / "data" / "engine_v1_regression.npz"


def cases() -> dict[str, tuple[fd.DriveSystem, object, float]]:
    # the shipped reading as recorded (commit 1f1fc75): its fitted velocity integral was
    # 3872.12 then (re-fitted to 3925.28 under issue 15's creep verdict)
    w = fd.preset("wang2021").replace_path("controller.velocity_integral_gain", 3872.12)
    lit = fd.preset("wang2021-literal").replace_path("stiffness.axial_damping", 2000.0)
    sampled = (w.replace_path("controller.position_period", 1e-3)
               .replace_path("controller.velocity_period", 5e-4)
               .replace_path("controller.current_period", 1.25e-4)
               .replace_path("controller.encoder_counts", 10000.0)
               .replace_path("controller.grating_resolution", 1e-7))
    t = np.arange(0, 2.01, 0.01)
    return {
        "cdfs_1p2": (fd.DriveSystem(w, "cdfs", 0.4), ConstantSpeed(1.2e-3), 3.0),
        "cdfs_2p0": (fd.DriveSystem(w, "cdfs", 0.3), ConstantSpeed(2.0e-3), 2.0),
        "ddfs_0p5": (fd.DriveSystem(w, "ddfs", 0.4), ConstantSpeed(0.5e-3, 16e-3), 2.0),
        "ddfs_sine": (fd.DriveSystem(w, "ddfs", 0.4), SineSpeed(2e-3, 5e-3, 0.5), 2.0),
        "cdfs_servo_hold": (fd.DriveSystem(w, "cdfs", 0.5, nut_hold="servo"),
                            ConstantSpeed(1.5e-3), 1.0),
        "literal_ddfs": (fd.DriveSystem(lit, "ddfs", 0.4), ConstantSpeed(1.5e-3, 2e-3), 1.0),
        "sampled_cdfs": (fd.DriveSystem(sampled, "cdfs", 0.4), ConstantSpeed(1.5e-3), 1.0),
        "sampled_ddfs": (fd.DriveSystem(sampled, "ddfs", 0.4),
                         SampledSpeed(t, 1e-3 * np.sin(3 * t), 1e-2 * np.ones_like(t)), 1.5),
    }


def main() -> None:
    data: dict[str, np.ndarray] = {}
    for name, (system, profile, duration) in cases().items():
        r = fd.simulate(system, profile, duration)  # type: ignore[arg-type]
        ds = r.dataset
        for var in ds.data_vars:
            data[f"{name}/{var}"] = np.asarray(ds[var].values)
        data[f"{name}/time"] = r.time
    np.savez_compressed(OUT, **data)
    print(f"wrote {OUT} ({OUT.stat().st_size / 1e6:.1f} MB)")


if __name__ == "__main__":
    main()
