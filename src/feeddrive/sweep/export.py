"""A stored sweep as a table or an xarray Dataset, and its exports.

* :func:`to_dataset`: SI, units in the attributes; a grid's swept axes are dimensions (the
  drive a dimension of names), a random or Latin-hypercube design has one dimension
  ``sample`` with the axes as coordinates.  Points not computed yet are NaN.
* :func:`to_frame`: one row per design point, engineering units in the column names
  (``table_position [mm]``, ``critical_speed [mm/s]``), as every CSV/Parquet of feeddrive.
* :func:`export`: ``.csv``, ``.parquet`` (the frame) or ``.nc`` (the Dataset, NetCDF via
  scipy, SI).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from .. import units
from ..outputs import atomic_path
from .design import SPECIAL_AXES
from .quantities import UNITS
from .store import SweepStore

__all__ = ["EXPORT_FORMATS", "export", "to_dataset", "to_frame"]

EXPORT_FORMATS = (".csv", ".parquet", ".nc")


def _axis_si(name: str, unit: str, value: Any) -> Any:
    factor = SPECIAL_AXES.get(name, ("", 1.0))[1]
    if isinstance(value, int | float) and not isinstance(value, bool):
        return float(value) * factor
    return value


def _si_unit(name: str, axis: dict[str, Any]) -> str:
    if axis["relative"]:
        return "1"
    return {"mm": "m", "mm/s": "m/s"}.get(axis["unit"], axis["unit"])


def _value(v: Any) -> Any:
    return math.nan if v is None else v


def _records(store: SweepStore, sweep: str) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    desc = store.description(sweep)
    out = []
    for idx, key, coords, result in store.rows(sweep):
        rec: dict[str, Any] = {"index": idx}
        for axis in desc["axes"]:
            rec[axis["name"]] = _axis_si(axis["name"], axis["unit"], coords[axis["name"]])
        if result is None:
            rec["done"] = 0
        elif "error" in result:
            rec["done"] = 1
            rec["error"] = result["error"]
        else:
            rec["done"] = 1
            rec.update({k: _value(v) for k, v in result["values"].items()})
            rec["seconds"] = result.get("seconds", math.nan)
        rec["key"] = key
        out.append(rec)
    return desc, out


def _value_columns(records: list[dict[str, Any]], axes: list[str]) -> list[str]:
    cols: list[str] = []
    for rec in records:
        for k in rec:
            if k not in axes and k not in ("index", "key") and k not in cols:
                cols.append(k)
    return cols


def to_dataset(store: SweepStore, sweep: str) -> xr.Dataset:
    """The sweep as an xarray Dataset (see the module)."""
    desc, records = _records(store, sweep)
    axes = [a["name"] for a in desc["axes"]]
    values = _value_columns(records, axes)
    frame = pd.DataFrame.from_records(records)
    for col in values:
        if col not in frame:
            frame[col] = math.nan
    if desc["design"] == "grid" and axes:
        frame = frame.set_index(axes)
        ds = xr.Dataset.from_dataframe(frame[values])
        for a in desc["axes"]:  # keep the design's order of each axis
            grid = [_axis_si(a["name"], a["unit"], v) for v in a["values"]]
            ds = ds.reindex({a["name"]: grid})
    else:
        frame = frame.set_index("index").rename_axis("sample")
        ds = xr.Dataset({c: ("sample", frame[c].to_numpy()) for c in values},
                        coords={"sample": frame.index.to_numpy(),
                                **{a: ("sample", frame[a].to_numpy()) for a in axes}})
    for a in desc["axes"]:
        ds[a["name"]].attrs["units"] = _si_unit(a["name"], a)
        if a["relative"]:
            ds[a["name"]].attrs["long_name"] = f"factor on the base value of {a['name']}"
    for name in values:
        if name in UNITS:
            ds[name].attrs["units"] = UNITS[name]
        if ds[name].dtype == object:
            ds[name] = ds[name].fillna("").astype(str)
    ds.attrs.update({"sweep": sweep, "design": desc["design"],
                     "quantity": str(desc["quantity"]["kind"]),
                     "source": str(desc["source"])})
    return ds


def to_frame(store: SweepStore, sweep: str) -> pd.DataFrame:
    """One row per design point in engineering units (see the module)."""
    desc, records = _records(store, sweep)
    axes = {a["name"]: a for a in desc["axes"]}
    frame = pd.DataFrame.from_records(records).set_index("index")
    renamed = {}
    for col in frame.columns:
        unit = _si_unit(col, axes[col]) if col in axes else UNITS.get(col, "")
        eng, factor = units.ENGINEERING.get(unit, (unit, 1.0))
        if factor != 1.0 and pd.api.types.is_numeric_dtype(frame[col]):
            frame[col] = frame[col] * factor
        if col in axes and axes[col]["relative"]:
            renamed[col] = f"{col} [factor]"
        elif eng not in ("", "1"):
            renamed[col] = f"{col} [{eng}]"
    return frame.rename(columns=renamed)


def export(store: SweepStore, sweep: str, path: str | Path) -> Path:
    p = Path(path)
    ext = p.suffix.lower()
    if ext not in (".nc", ".parquet", ".csv"):
        raise ValueError(f"{p}: unknown extension; expected one of {EXPORT_FORMATS}")
    with atomic_path(p) as tmp:
        if ext == ".nc":
            ds = to_dataset(store, sweep)
            for name in ds.data_vars:
                if ds[name].dtype == np.int64:
                    ds[name] = ds[name].astype(np.int32)  # NetCDF3 has no 64-bit integers
            ds.to_netcdf(tmp, engine="scipy")
        elif ext == ".parquet":
            to_frame(store, sweep).to_parquet(tmp)
        else:
            to_frame(store, sweep).to_csv(tmp, float_format="%.10g")
    return p
