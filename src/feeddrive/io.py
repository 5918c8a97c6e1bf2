"""Writers for simulation results: CSV, Parquet, NetCDF, MATLAB .mat.

CSV and Parquet are edge formats: engineering units (mm, mm/s, N/µm), the unit in brackets
in each column name, e.g. ``table_position [mm]``.  NetCDF and .mat keep SI with the units
as attributes (.mat: a ``units`` struct beside the signals).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path
from typing import TYPE_CHECKING

from .parameters import ParameterError
from .units import ENGINEERING

if TYPE_CHECKING:
    import pandas as pd
    import xarray as xr

FORMATS = (".csv", ".parquet", ".nc", ".mat")

#: how to get Parquet support (pyarrow is an optional dependency: docs/outputs.md)
PARQUET_HINT = "Parquet output needs pyarrow: pip install 'feeddrive[parquet]'"


def check_format(path: str | Path) -> str:
    """The output format of ``path`` (its extension), refused before any work when unknown
    or when its writer is not installed (Parquet without pyarrow)."""
    p = Path(path)
    ext = p.suffix.lower()
    if ext not in FORMATS:
        raise ParameterError("output", str(p), f"unknown extension; expected one of {FORMATS}")
    if ext == ".parquet" and importlib.util.find_spec("pyarrow") is None:
        raise ParameterError("output", str(p), PARQUET_HINT)
    return ext


def to_engineering_frame(dataset: xr.Dataset) -> pd.DataFrame:
    """All time signals as a DataFrame in engineering units, units in the column names."""
    import pandas as pd

    cols = {"time [s]": dataset["time"].values}
    for name, var in dataset.data_vars.items():
        unit = var.attrs.get("units", "")
        eng_unit, factor = ENGINEERING.get(unit, (unit, 1.0))
        cols[f"{name} [{eng_unit}]"] = var.values * factor
    return pd.DataFrame(cols)


def save_result(dataset: xr.Dataset, path: str | Path) -> Path:
    """Write ``dataset`` to ``path``; the format follows the extension."""
    p = Path(path)
    ext = check_format(p)
    p.parent.mkdir(parents=True, exist_ok=True)
    if ext == ".csv":
        to_engineering_frame(dataset).to_csv(p, index=False, float_format="%.10g")
    elif ext == ".parquet":
        to_engineering_frame(dataset).to_parquet(p, index=False)
    elif ext == ".nc":
        dataset.to_netcdf(p, engine="scipy")
    else:
        import scipy.io

        signals = {name: var.values for name, var in dataset.data_vars.items()}
        signals["time"] = dataset["time"].values
        units = {name: var.attrs.get("units", "") for name, var in dataset.data_vars.items()}
        units["time"] = "s"
        scipy.io.savemat(p, {"feeddrive": {**signals, "units": units,
                                            "attrs": {k: str(v) for k, v in
                                                      dataset.attrs.items()}}},
                         long_field_names=True, do_compression=True)
    return p
