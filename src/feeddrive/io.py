"""Writers for simulation results: CSV, Parquet, NetCDF, MATLAB .mat.

CSV and Parquet are edge formats: engineering units (mm, mm/s, N/µm), the unit in brackets
in each column name, e.g. ``table_position [mm]``.  NetCDF and .mat keep SI with the units
as attributes (.mat: a ``units`` struct beside the signals).

Every file is written under a temporary name in its folder and renamed when complete
(:func:`feeddrive.outputs.atomic_path`): a full disk never leaves a truncated file under the
output's name.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import scipy.io
import xarray as xr

from .outputs import atomic_path
from .parameters import ParameterError
from .units import ENGINEERING

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
    with atomic_path(p) as tmp:
        _write(dataset, tmp, ext)
    return p


def _write(dataset: xr.Dataset, p: Path, ext: str) -> None:
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


class ChunkWriter:
    """Appends a run's samples to ``.parquet`` or ``.csv`` chunk by chunk (engineering units,
    the columns of :func:`to_engineering_frame`), so a long run never holds all of them.

    The samples go to a temporary name in the output's folder; :meth:`close` renames it to
    ``path`` (a run stopped by Ctrl-C keeps the samples written so far, complete rows),
    :meth:`abort` removes it (a write that failed: nothing partial under ``path``)."""

    def __init__(self, path: str | Path, model: Any, system: Any, run_type: Any) -> None:
        """``run_type``: :class:`feeddrive.result.Run` (passed in, so that this writer does not
        import the results layer that imports it)."""
        self.path = Path(path)
        ext = self.path.suffix.lower()
        if ext not in (".parquet", ".csv"):
            raise ParameterError("output", str(self.path), "a streamed run is written as "
                                 ".parquet or .csv (.nc and .mat hold the whole run)")
        self.ext, self.model, self.system, self.run_type = ext, model, system, run_type
        self._writer: Any = None
        self._atomic: Any = None
        self._first = True
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._atomic = atomic_path(self.path)
        self._tmp = self._atomic.__enter__()

    def _frame(self, t: np.ndarray, y: np.ndarray, aux: np.ndarray) -> pd.DataFrame:
        run = self.run_type(t, y, aux, self.model, self.system, None, {})
        cols = {"time [s]": t}
        for name, (unit, _) in run.meta.items():
            eng_unit, factor = ENGINEERING.get(unit, (unit, 1.0))
            cols[f"{name} [{eng_unit}]"] = run.signal(name) * factor
        return pd.DataFrame(cols)

    def write(self, t: np.ndarray, y: np.ndarray, aux: np.ndarray) -> None:
        if t.size == 0:
            return
        frame = self._frame(t, y, aux)
        if self.ext == ".csv":
            frame.to_csv(self._tmp, mode="w" if self._first else "a", header=self._first,
                         index=False, float_format="%.10g")
        else:
            import pyarrow as pa
            import pyarrow.parquet as pq

            table = pa.Table.from_pandas(frame, preserve_index=False)
            if self._writer is None:
                self._writer = pq.ParquetWriter(self._tmp, table.schema)
            self._writer.write_table(table)
        self._first = False

    def close(self) -> None:
        """Finish the file and rename it to ``path``."""
        if self._atomic is None:
            return
        try:
            if self._writer is not None:
                self._writer.close()
                self._writer = None
        except BaseException as err:
            self._end(err)
            raise
        self._end(None)

    def abort(self, err: BaseException | None = None) -> None:
        """Remove the temporary file: nothing is left under ``path``."""
        if self._atomic is None:
            return
        if self._writer is not None:
            try:
                self._writer.close()
            except Exception:  # noqa: BLE001  (the file is removed anyway)
                pass
            self._writer = None
        self._end(err or RuntimeError("aborted"))

    def _end(self, err: BaseException | None) -> None:
        atomic, self._atomic = self._atomic, None
        if err is None:
            atomic.__exit__(None, None, None)
        else:
            atomic.__exit__(type(err), err, None)
