"""Writers for simulation results: CSV, Parquet, NetCDF, MATLAB .mat.

CSV and Parquet are edge formats: engineering units (mm, mm/s, N/µm), the unit in brackets
in each column name, e.g. ``table_position [mm]``.  NetCDF and .mat keep SI with the units
as attributes (.mat: a ``units`` struct beside the signals).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import scipy.io
import xarray as xr

from .parameters import ParameterError
from .units import ENGINEERING

FORMATS = (".csv", ".parquet", ".nc", ".mat")


def to_engineering_frame(dataset: xr.Dataset) -> pd.DataFrame:
    """All time signals as a DataFrame in engineering units, units in the column names."""
    cols = {"time [s]": dataset["time"].values}
    for name, var in dataset.data_vars.items():
        unit = var.attrs.get("units", "")
        eng_unit, factor = ENGINEERING.get(unit, (unit, 1.0))
        cols[f"{name} [{eng_unit}]"] = var.values * factor
    return pd.DataFrame(cols)


def save_result(dataset: xr.Dataset, path: str | Path) -> Path:
    """Write ``dataset`` to ``path``; the format follows the extension."""
    p = Path(path)
    ext = p.suffix.lower()
    if ext not in FORMATS:
        raise ParameterError("output", str(p), f"unknown extension; expected one of {FORMATS}")
    p.parent.mkdir(parents=True, exist_ok=True)
    if ext == ".csv":
        to_engineering_frame(dataset).to_csv(p, index=False, float_format="%.10g")
    elif ext == ".parquet":
        to_engineering_frame(dataset).to_parquet(p, index=False)
    elif ext == ".nc":
        dataset.to_netcdf(p, engine="scipy")
    else:
        signals = {name: var.values for name, var in dataset.data_vars.items()}
        signals["time"] = dataset["time"].values
        units = {name: var.attrs.get("units", "") for name, var in dataset.data_vars.items()}
        units["time"] = "s"
        scipy.io.savemat(p, {"feeddrive": {**signals, "units": units,
                                            "attrs": {k: str(v) for k, v in
                                                      dataset.attrs.items()}}},
                         long_field_names=True, do_compression=True)
    return p
