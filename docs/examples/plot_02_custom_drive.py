"""
A drive from parts: another friction law at the screw
=====================================================

The model is assembled from parts chosen in the parameter file: topology, a friction law per
site, the loops, disturbances.  This file extends the ``wang2021`` preset and replaces the
screw-shaft LuGre law by the Dahl law (no Stribeck effect), then compares the CDFS at
1.0 mm/s with both.  The Dahl law has no falling (Stribeck) branch of friction against speed,
which is what makes the LuGre reading creep below its critical speed; the verdicts printed
below say what each run did (how to add a law of one's own: ``docs/extending.md``).
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

import feeddrive as fd

folder = Path(tempfile.mkdtemp())
(folder / "dahl_screw.toml").write_text(
    'extends = "wang2021"\n'
    "\n"
    "[friction.screw]\n"
    'law = "dahl"\n',
    encoding="utf-8",
)
drives = {"LuGre (wang2021)": fd.preset("wang2021"),
          "Dahl at the screw": fd.load(folder / "dahl_screw.toml")}

fig, ax = plt.subplots(figsize=(8, 3.6), layout="constrained")
for label, params in drives.items():
    system = fd.DriveSystem(params, "cdfs", 0.4)
    result = fd.simulate(system, fd.ConstantSpeed(1.0e-3), duration=6.0)
    print(f"{label}: friction laws {result.attrs['friction_laws']}, "
          f"verdict {result.summary()['verdict']}")
    ax.plot(result.time, 1e3 * result["table_speed"], lw=0.8, label=label)
ax.axhline(1.0, color="k", ls="--", lw=0.8, label="command")
ax.set_xlabel("time [s]")
ax.set_ylabel("table speed [mm/s]")
ax.legend()
plt.show()
