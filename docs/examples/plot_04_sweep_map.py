"""
A sweep map: the linear creep band over table position and a loop gain
======================================================================

A sweep computes one quantity at every point of a design and stores each point in a
resumable SQLite store; a map draws it.  The quantity here is the cheap ``linear-band``
(the speeds at which steady sliding is linearly unstable, no time simulation) for the CDFS
over a 2 × 3 grid of table position and the velocity-loop integral gain (relative to the
preset's).  The same from the shell::

    feeddrive sweep band.toml --output band.nc
    feeddrive map band.sqlite --x table_position \
        --y controller.velocity_integral_gain --plot band.png

The examples in ``examples/*.toml`` map the simulated critical speed instead
(docs: ``docs/sweeps.md``).
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import xarray as xr

from feeddrive import sweep

# the sweep's worker processes start by importing this script: the work runs under the
# __main__ guard only (as with any Python multiprocessing)
if __name__ == "__main__":
    folder = Path(tempfile.mkdtemp())
    (folder / "band.toml").write_text('''
name = "band"
drive = "cdfs"
store = "band.sqlite"

[quantity]
kind = "linear-band"
linear_points = 10

[axes]
table_position = [200, 600]   # [mm]
"controller.velocity_integral_gain" = { values = [0.8, 1.0, 1.2], relative = true }
''', encoding="utf-8")

    config = sweep.load_config(folder / "band.toml")
    store = sweep.SweepStore(folder / "band.sqlite")
    summary = sweep.run_sweep(config, store, workers=1)
    print(f"{summary.computed} points computed, {summary.stored_before} found in the store")

    sweep.export(store, "band", folder / "band.nc")  # NetCDF4 with CF-1.8 attributes, SI
    with xr.open_dataset(folder / "band.nc") as ds:
        print(ds.attrs["Conventions"], "-", ds.attrs["title"])
        print("upper edge of the unstable band [mm/s]:")
        print(1e3 * ds["linear_upper"].to_pandas())

    dataset = sweep.to_dataset(store, "band")
    png = sweep.plot_map(dataset, "table_position", "controller.velocity_integral_gain",
                         folder / "band.png")
    fig, ax = plt.subplots(figsize=(8, 5), layout="constrained")
    ax.imshow(plt.imread(png))
    ax.set_axis_off()
    plt.show()
