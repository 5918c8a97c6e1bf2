"""
Fitting friction from a measured file: ``feeddrive identify static``
====================================================================

A static friction measurement is a file of steady sliding speeds and the friction force at
each.  Here the "measurement" is made from Wang2021 Table 1's screw-shaft Stribeck curve with
2 % noise, written as the CSV a test rig would give (columns ``speed [mm/s]``,
``force [N]``), and fitted by the command a user runs on such a file.  The fit's result is a
TOML fragment that a parameter file can ``extends`` (docs: ``docs/measured-data.md``).
"""

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import feeddrive as fd
from feeddrive.analysis.fragments import merge_fragment
from feeddrive.model.friction.stribeck import steady_friction

screw = fd.preset("wang2021").friction.screw
speed = np.repeat(np.geomspace(0.05, 50.0, 30), 3)  # [mm/s], both directions
speed = np.concatenate([speed, -speed])
rng = np.random.default_rng(0)
force = steady_friction(speed * 1e-3, screw) * (1 + 0.02 * rng.standard_normal(speed.size))

folder = Path(tempfile.mkdtemp())
measured = folder / "static.csv"
rows = "\n".join(f"{v:.6g},{f:.6g}" for v, f in zip(speed, force, strict=True))
measured.write_text("speed [mm/s],force [N]\n" + rows + "\n", encoding="utf-8")

# the command, as a user types it: feeddrive identify static static.csv --out ... --json
done = subprocess.run([sys.executable, "-m", "feeddrive", "identify", "static", str(measured),
                       "--out", str(folder / "screw_static.toml"), "--json"],
                      capture_output=True, text=True, check=True)
fit = json.loads(done.stdout)
for name in ("static_force", "coulomb_force", "stribeck_velocity"):
    est = fit["positive"][name]
    print(f"{name}: {est['value']:.4g} {est['unit']} "
          f"(95 % CI {est['ci_low']:.4g} … {est['ci_high']:.4g})")
print("Table 1 (+ branch):", screw.positive)
print((folder / "screw_static.toml").read_text(encoding="utf-8"))

# the fragment merged into the preset: a parameter set with the fitted screw friction
fitted = merge_fragment(fd.preset("wang2021"), folder / "screw_static.toml")

v = np.geomspace(0.05, 50.0, 200)  # [mm/s]
fig, ax = plt.subplots(figsize=(7, 3.8), layout="constrained")
ax.semilogx(speed[speed > 0], force[speed > 0], ".", ms=3, label="measured (+)")
ax.semilogx(v, steady_friction(v * 1e-3, fitted.friction.screw), lw=1.2, label="fitted")
ax.semilogx(v, steady_friction(v * 1e-3, screw), "k--", lw=0.8, label="Table 1")
ax.set_xlabel("sliding speed [mm/s]")
ax.set_ylabel("friction force [N]")
ax.legend()
plt.show()
