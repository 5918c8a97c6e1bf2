"""
The drive as an FMU: ``feeddrive export fmu``, run in fmpy
==========================================================

``feeddrive export fmu`` writes a drive as a Functional Mock-up Unit (FMI 2.0 co-simulation
here) for Simulink, Modelica tools, PathSim or a HIL rig; its C is translated from the same
kernels numba compiles.  Here the CDFS at 2 mm/s runs for 2 s in fmpy, beside the same run
in ``feeddrive.simulate`` with the command held over each 1-ms communication step as the FMU
holds its inputs (docs: ``docs/fmu.md``; this needs a C compiler).
"""

import subprocess
import sys
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from fmpy import simulate_fmu

import feeddrive as fd

folder = Path(tempfile.mkdtemp())
fmu = folder / "cdfs.fmu"
done = subprocess.run([sys.executable, "-m", "feeddrive", "export", "fmu", "--drive", "cdfs",
                       "--out", str(fmu)], capture_output=True, text=True, check=True)
print(done.stdout.strip())
print(f"{fmu.name}: {fmu.stat().st_size / 1e3:.0f} kB")

t = np.arange(0.0, 2.0 + 1e-9, 1e-3)  # the communication grid [s]
speed = 2e-3 * np.minimum(t / 0.1, 1.0)  # 2 mm/s after a 0.1-s ramp [m/s]
# every input of the FMU (SI): no load; the position reference is the integral of the speed
# reference (integrate_speed_reference, the default), so its column only gives the start, 0
inputs = np.zeros(t.size, dtype=[("time", float), ("table_speed_reference", float),
                                 ("table_position_reference", float), ("load_force", float)])
inputs["time"], inputs["table_speed_reference"] = t, speed
run = simulate_fmu(fmu, stop_time=2.0, output_interval=1e-3, input=inputs,
                   output=["table_position", "table_speed"])

system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
ref = fd.simulate(system, fd.SampledSpeed(t, speed, hold=True), 2.0)
x_fmu = np.interp(ref.time, run["time"], run["table_position"])
print(f"table position at 2 s: FMU {1e3 * run['table_position'][-1]:.6f} mm, "
      f"feeddrive {1e3 * ref['table_position'][-1]:.6f} mm; largest difference "
      f"{1e9 * np.max(np.abs(x_fmu - ref['table_position'])):.3g} nm")

fig, ax = plt.subplots(figsize=(8, 3.6), layout="constrained")
ax.plot(ref.time, 1e3 * ref["table_speed"], lw=1.5, label="feeddrive.engine.simulate")
ax.plot(run["time"], 1e3 * run["table_speed"], "--", lw=1.0, label="FMU in fmpy")
ax.set_xlabel("time [s]")
ax.set_ylabel("table speed [mm/s]")
ax.legend()
plt.show()
