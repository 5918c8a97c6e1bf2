"""A stored sweep as a table or an xarray Dataset, and its exports.

* :func:`to_dataset`: SI, units in the attributes; a grid's swept axes are dimensions (the
  drive a dimension of names), a random or Latin-hypercube design has one dimension
  ``sample`` with the axes as coordinates.  A value is NaN where its point is not computed
  yet (``done`` 0) or the value does not exist at it (no gain crossover, no critical speed);
  a loop without a gain margin (no phase crossover) has +inf
  (:func:`~feeddrive.sweep.quantities.absent_value`).  A parameter axis has the unit of the
  parameter's declaration (:func:`~feeddrive.sweep.design.parameter_unit`).
* :func:`to_frame`: one row per design point, engineering units in the column names
  (``table_position [mm]``, ``critical_speed [mm/s]``, a parameter axis in m/s or N/m as
  ``[mm/s]``, ``[N/µm]``), as every CSV of feeddrive; +inf is written ``inf``, NaN empty.
* :func:`to_table`: the same rows and numbers as a pyarrow Table with plain names, each
  field's unit in its metadata, as every Parquet of feeddrive.
* :func:`export`: ``.csv`` (the frame), ``.parquet`` (the table) or ``.nc`` (the Dataset,
  NetCDF4 with CF-1.8 attributes, SI) — docs/outputs.md.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import units
from ..io.outputs import SWEEP_EXPORT_FORMATS, atomic_path
from ..io.results import arrow_table, cf_attributes, plain_names, write_netcdf
from .design import SPECIAL_AXES
from .quantities import UNITS, stored_value
from .store import SweepStore

if TYPE_CHECKING:  # pandas and xarray are imported where a sweep is exported (a pool worker
    import pandas as pd  # imports this package without exporting: ≈ 0.5 s each time)
    import xarray as xr

__all__ = ["EXPORT_FORMATS", "export", "to_dataset", "to_frame", "to_table"]

EXPORT_FORMATS = SWEEP_EXPORT_FORMATS


def _axis_si(name: str, unit: str, value: Any) -> Any:
    factor = SPECIAL_AXES.get(name, ("", 1.0))[1]
    if isinstance(value, int | float) and not isinstance(value, bool):
        return float(value) * factor
    return value


def _si_unit(name: str, axis: dict[str, Any]) -> str:
    if axis["relative"]:
        return "1"
    return {"mm": "m", "mm/s": "m/s"}.get(axis["unit"], axis["unit"])


# units of the per-loop values of loop-margins, named by their suffix (…_crossover_hz); dB is
# no UDUNITS unit: a gain margin in dB is written with unit "1" and says dB in its long name
_SUFFIX_UNITS = {"_hz": ("Hz", ""), "_deg": ("degree", ""), "_db": ("1", "in dB")}


def _unit(name: str) -> tuple[str, str]:
    """(SI unit, a note for the long name) of a stored value."""
    if name in UNITS:
        return UNITS[name], ""
    for suffix, (unit, note) in _SUFFIX_UNITS.items():
        if name.endswith(suffix):
            return unit, note
    return ("1", "1 once the point is computed") if name == "done" else ("", "")


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
            rec.update({k: stored_value(k, v) for k, v in result["values"].items()})
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
    """The sweep as an xarray Dataset (see the module).

    A grid design is indexed by its axes (each in design order), other designs by ``sample``.

    Parameters
    ----------
    store : SweepStore
        The store.
    sweep : str
        The sweep's name.

    Returns
    -------
    xarray.Dataset
        The quantity's values per point, in SI.
    """
    import pandas as pd
    import xarray as xr

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
        unit, note = _unit(name)
        if unit:
            ds[name].attrs["units"] = unit
        if note:
            ds[name].attrs["long_name"] = f"{name.replace('_', ' ')} ({note})"
        if ds[name].dtype == object:
            ds[name] = ds[name].fillna("").astype(str)
    ds.attrs.update({"sweep": sweep, "design": desc["design"],
                     "quantity": str(desc["quantity"]["kind"]),
                     "source": str(desc["source"])})
    return ds


def _engineering(store: SweepStore, sweep: str
                 ) -> tuple[pd.DataFrame, dict[str, tuple[str, str]]]:
    """The rows in engineering units, plain names; each column's (unit, description)."""
    import pandas as pd

    desc, records = _records(store, sweep)
    axes = {a["name"]: a for a in desc["axes"]}
    frame = pd.DataFrame.from_records(records).set_index("index")
    meta: dict[str, tuple[str, str]] = {}
    for col in frame.columns:
        unit = _si_unit(col, axes[col]) if col in axes else _unit(col)[0]
        eng, factor = units.ENGINEERING.get(unit, (unit, 1.0))
        if factor != 1.0 and pd.api.types.is_numeric_dtype(frame[col]):
            frame[col] = frame[col] * factor
        elif factor != 1.0:  # a list per value (harmonic amplitudes): kept in SI, said so
            eng = unit
        if col in axes and axes[col]["relative"]:
            meta[col] = ("factor", f"factor on the base value of {col}")
        else:
            meta[col] = (eng, "")
    return frame, meta


def to_frame(store: SweepStore, sweep: str) -> pd.DataFrame:
    """One row per design point in engineering units (see the module).

    Parameters
    ----------
    store : SweepStore
        The store.
    sweep : str
        The sweep's name.

    Returns
    -------
    pandas.DataFrame
        Columns named ``name [unit]`` (mm, mm/s, N/µm, otherwise SI).
    """
    frame, meta = _engineering(store, sweep)
    renamed = {col: f"{col} [{unit}]" for col, (unit, _) in meta.items()
               if unit not in ("", "1")}
    return frame.rename(columns=renamed)


def to_table(store: SweepStore, sweep: str) -> Any:
    """One row per design point as a pyarrow Table: the numbers of :func:`to_frame`, plain
    names, each field's unit in its metadata (a relative axis: unit ``1``, long name 'factor
    on the base value of …').

    Parameters
    ----------
    store : SweepStore
        The store.
    sweep : str
        The sweep's name.

    Returns
    -------
    pyarrow.Table
        One row per point, units in the field metadata.
    """
    frame, meta = _engineering(store, sweep)
    columns = {"index": (frame.index.to_numpy(), "1", "design point number")}
    for col, (unit, description) in meta.items():
        unit = "1" if unit in ("", "factor") else unit
        columns[str(col)] = (frame[col].to_numpy(), unit, description)
    return arrow_table(columns, {"sweep": sweep})


def export(store: SweepStore, sweep: str, path: str | Path) -> Path:
    """Write the sweep to ``path``; the format follows the extension (see the module).

    Written atomically (nothing partial under the name).

    Parameters
    ----------
    store : SweepStore
        The store.
    sweep : str
        The sweep's name.
    path : str or Path
        ``.nc`` (CF-1.8, SI), ``.parquet`` or ``.csv`` (engineering units).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    ValueError
        For another extension.
    """
    p = Path(path)
    ext = p.suffix.lower()
    if ext not in (".nc", ".parquet", ".csv"):
        raise ValueError(f"{p}: unknown extension; expected one of {', '.join(EXPORT_FORMATS)}")
    with atomic_path(p) as tmp:  # nothing partial under the name (a full disk)
        if ext == ".nc":
            ds = plain_names(to_dataset(store, sweep), "parameter")
            write_netcdf(cf_attributes(ds, title=f"feeddrive sweep {sweep}: "
                                       f"{ds.attrs['design']} design, {ds.attrs['quantity']}",
                                       action=f"sweep export of {sweep}"), tmp)
        elif ext == ".parquet":
            import pyarrow.parquet as pq

            pq.write_table(to_table(store, sweep), tmp)
        else:
            to_frame(store, sweep).to_csv(tmp, float_format="%.10g")
    return p
