"""Writers for simulation results: CSV, Parquet, NetCDF, MATLAB .mat (docs/outputs.md).

* CSV: engineering units (mm, mm/s, N/µm), the unit in brackets in each column name, e.g.
  ``table_position [mm]`` — a human reads it; a first ``#`` line says what wrote it
  (:func:`provenance_line`), a last one holds the run's solver record as JSON
  (:func:`solver_line`: settings, statistics, the error estimate when asked; SI, as NetCDF's
  ``solver`` attribute); feeddrive's readers skip ``#`` lines, pandas with ``comment="#"``.
* Parquet: the same numbers and units as CSV, plain column names (``table_position``) and
  each field's unit in the Arrow schema's field metadata (``unit``, ``long_name``); the units
  and the run's :func:`provenance` (the solver record among it) and parameter sets
  (:func:`parameter_texts`) also as pandas' ``df.attrs`` (``pandas.read_parquet``).
* NetCDF: NetCDF4 (HDF5, h5netcdf engine), SI, with the CF-1.8 global attributes
  (``Conventions``, ``title``, ``source``, ``history``, ``references``) and each variable's
  ``units`` (UDUNITS spelling) and ``long_name``; plain variable names (:func:`plain_names`:
  a machine's ``x.table_position`` is ``x_table_position``, the name kept in its attribute
  ``signal``).
* .mat: SI, each signal an N×1 column vector, a ``units`` struct beside the signals; the
  whole run is one variable, the struct ``feeddrive``, below the MATLAB 5 format's
  :data:`MAT5_LIMIT` (:func:`check_mat_output` refuses a run that cannot fit before it runs).

Every file is written under a temporary name in its folder and renamed when complete
(:func:`feeddrive.io.outputs.atomic_path`): a full disk never leaves a truncated file under the
output's name.  A streamed run (:class:`ChunkWriter`) is written before its solver record
exists; :func:`add_solver_record` adds it once the run (and its error estimate) is done.
"""

from __future__ import annotations

import importlib.util
import io
import json
import os
from collections.abc import Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import __version__
from ..parameters import ParameterError
from ..units import ENGINEERING
from .outputs import PARQUET_HINT, RESULT_FORMATS, atomic_path, shown, write_bytes

if TYPE_CHECKING:  # pandas, xarray and scipy.io are imported by the writers that use them
    import pandas as pd
    import xarray as xr

FORMATS = RESULT_FORMATS

#: the CF version the NetCDF exports follow (global attribute ``Conventions``)
CF_CONVENTIONS = "CF-1.8"
#: xarray's engine for NetCDF4 files (scipy writes NetCDF3 only)
NETCDF_ENGINE = "h5netcdf"
#: the global attribute ``references`` of every NetCDF export
REFERENCES = ("Wang2021: Z. Wang, X. Feng, H. Yang, H. Jin, Research on low-speed "
              "characteristics of differential double-drive feed system, Mechanical Sciences "
              "12, 791-800 (2021), doi:10.5194/ms-12-791-2021")
#: the long name of the time coordinate: simulated seconds from the start of the run (not a
#: calendar time, so no ``axis = "T"``: CF 4.4 asks a time axis for "seconds since <date>")
TIME_LONG_NAME = "time since the start of the run"

# UDUNITS spellings of the units that differ from the package's (µ is not UDUNITS)
_UDUNITS = {"": "1", "N/µm": "N/um", "µm": "um", "µs": "us"}



def check_format(path: str | Path) -> str:
    """The output format of a path, checked before any work starts.

    Parameters
    ----------
    path : str or Path
        The output file; its extension chooses the format (``FORMATS``).

    Returns
    -------
    str
        The lower-case extension, e.g. ``".nc"``.

    Raises
    ------
    ParameterError
        For an unknown extension, or ``.parquet`` without pyarrow installed.
    """
    p = Path(path)
    ext = p.suffix.lower()
    if ext not in FORMATS:
        raise ParameterError("output", str(p), "unknown extension; expected one of "
                             + ", ".join(FORMATS))
    if ext == ".parquet" and importlib.util.find_spec("pyarrow") is None:
        raise ParameterError("output", str(p), PARQUET_HINT)
    return ext


def udunits(unit: str) -> str:
    """A unit in UDUNITS-2 spelling, as the CF ``units`` attribute wants it.

    Parameters
    ----------
    unit : str
        The package's spelling (``"N s/m"``, ``"kg m^2"``, ``""``).

    Returns
    -------
    str
        The UDUNITS spelling; ``""`` becomes ``"1"``.
    """
    return _UDUNITS.get(unit, unit)


def netcdf_name(name: str) -> str:
    """A CF variable name (letters, digits, underscores; CF 1.8 section 2.3): the dots of a
    dotted name become underscores (a sweep's parameter path ``friction.screw`` →
    ``friction_screw``, a machine's signal ``x.table_position`` → ``x_table_position``).

    Parameters
    ----------
    name : str
        The package's name of a variable.

    Returns
    -------
    str
        The name in a NetCDF file.
    """
    return name.replace(".", "_")


def plain_names(dataset: xr.Dataset, attribute: str) -> xr.Dataset:
    """A shallow copy of a dataset whose dotted variable names are plain (:func:`netcdf_name`),
    each such variable keeping its own name in the attribute ``attribute`` (docs/outputs.md:
    ``parameter`` for a sweep's parameter path, ``signal`` for a machine's signal).

    Parameters
    ----------
    dataset : xarray.Dataset
        The dataset; not changed.
    attribute : str
        The variable attribute the dotted name is kept in.

    Returns
    -------
    xarray.Dataset
        The dataset with plain names (the data shared, not copied); ``dataset`` itself when
        no name has a dot.

    Raises
    ------
    ParameterError
        When two variables would share one plain name (``x.a_b`` and ``x_a.b``).
    """
    names = [str(n) for n in [*dataset.coords, *dataset.data_vars]]
    dotted = [n for n in names if "." in n]
    if not dotted:
        return dataset
    plain = [netcdf_name(n) for n in names]
    twice = sorted({n for n in plain if plain.count(n) > 1})
    if twice:
        raise ParameterError("output", twice[0], "two variables would share this NetCDF name "
                             "(dots become underscores); expected names that differ there")
    ds = dataset.copy(deep=False)
    for name in dotted:
        ds[name].attrs = {**ds[name].attrs, attribute: name}
    return ds.rename({name: netcdf_name(name) for name in dotted})


#: the MATLAB 5 format's limit, as scipy.io.savemat enforces it: one variable (a .mat export's
#: struct ``feeddrive``, which holds the whole run) below 2**32 bytes [bytes]
MAT5_LIMIT = 2**32
#: the bytes scipy writes before each N×1 double field of a struct besides its samples: the
#: field's tag (8), array flags (16), dimensions (16), empty name (8) and data tag (8) [bytes]
MAT5_FIELD_HEADER = 56


def mat_bytes(samples: int, signals: int) -> int:
    """The bytes of a run's signals in a .mat export's struct ``feeddrive``: its time and
    ``signals`` columns of ``samples`` doubles, each with its header; the ``units`` and
    ``attrs`` (text, kilobytes) come on top.

    Parameters
    ----------
    samples : int
        Output samples of the run [-].
    signals : int
        Signals recorded beside ``time`` (the run's Dataset's variables) [-].

    Returns
    -------
    int
        Bytes [bytes].
    """
    return (int(signals) + 1) * (8 * int(samples) + MAT5_FIELD_HEADER)


def check_mat_output(path: str | Path, *, duration: float, output_interval: float,
                     signals: int) -> None:
    """Refuse a ``.mat`` output whose run cannot fit in the MATLAB 5 format, before the run.

    scipy's writer fails once a variable reaches :data:`MAT5_LIMIT` (``MatWriteError: Matrix
    too large to save with Matlab 5 format``), after the whole file is written; the run is one
    struct, so its signals' bytes (:func:`mat_bytes`) decide.  A CDFS run (33 signals) at a 1-ms
    output interval fits up to ≈ 15 800 s.  Any other format takes a path.

    Parameters
    ----------
    path : str or Path
        The output; checked when its extension is ``.mat``.
    duration : float
        Simulated time [s].
    output_interval : float
        Interval of the recorded output [s].
    signals : int
        Signals the run records beside ``time`` [-].

    Raises
    ------
    ParameterError
        ``--duration``, naming the output, the bytes, the limit and the longest duration that
        fits [s].
    """
    p = Path(path)
    if p.suffix.lower() != ".mat":
        return
    samples = int(duration / output_interval) + 1
    need = mat_bytes(samples, signals)
    if need < MAT5_LIMIT:
        return
    fits = (MAT5_LIMIT - 1) // (signals + 1) - MAT5_FIELD_HEADER
    longest = (fits // 8 - 1) * output_interval
    raise ParameterError(
        "--duration", duration,
        f"a .mat --output ({shown(p)}) would hold {samples:.4g} samples of {signals + 1} "
        f"columns, {need / 2**30:.3g} GiB in the one struct 'feeddrive', past the MATLAB 5 "
        f"format's {MAT5_LIMIT / 2**30:g} GiB per variable (scipy.io.savemat); expected ≤ "
        f"{longest:.6g} [s] at the output interval {output_interval:g} s, or a .nc, .parquet "
        f"or .csv --output")


def cf_attributes(dataset: xr.Dataset, *, title: str, action: str) -> xr.Dataset:
    """A shallow copy of a dataset with the CF-1.8 attributes of a NetCDF export.

    Globals: ``Conventions``, ``title``, ``source`` (feeddrive and its version, then any former
    ``source``), ``history`` (one line per writing, newest first, ISO 8601 UTC), ``references``
    (the Wang2021 citation); a former free-text ``conventions`` becomes ``comment``.  Variables
    and coordinates: ``units`` in UDUNITS spelling, ``long_name`` (the variable's name if it had
    none).  No variable has a CF standard name (the table has none for a machine's positions,
    speeds or currents).

    Parameters
    ----------
    dataset : xarray.Dataset
        A run's dataset (``Result.dataset``), signals in SI with their units.
    title : str
        The file's ``title``.
    action : str
        What wrote it, for the ``history`` line (``"simulate --drive ddfs"``).

    Returns
    -------
    xarray.Dataset
        The dataset with the attributes; the data are shared, not copied.

    References
    ----------
    .. [1] CF Conventions 1.8, https://cfconventions.org/.
    .. [2] Wang2021, the ``references`` attribute.
    """
    ds = dataset.copy(deep=False)
    attrs = dict(ds.attrs)
    comment = attrs.pop("conventions", None)
    stamp = datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    entry = f"{stamp} feeddrive {__version__}: {action}"
    history = f"{entry}\n{attrs['history']}" if attrs.get("history") else entry
    source = f"feeddrive {__version__}"
    if attrs.get("source"):  # a sweep's configuration file: kept after the program
        source = f"{source}; {attrs['source']}"
    attrs.update({"Conventions": CF_CONVENTIONS, "title": title, "source": source,
                  "history": history, "references": REFERENCES})
    if comment is not None:
        attrs["comment"] = f"{attrs['comment']}; {comment}" if attrs.get("comment") \
            else comment
    # NetCDF has no boolean attribute type
    ds.attrs = {k: (int(v) if isinstance(v, bool | np.bool_) else v) for k, v in attrs.items()}
    for name in [*ds.coords, *ds.data_vars]:
        var = ds[name]
        new = dict(var.attrs)
        if "units" in new or name == "time":
            new["units"] = udunits(str(new.get("units", "s")))
        new.setdefault("long_name", str(name).replace("_", " "))
        if name == "time":
            new["long_name"] = TIME_LONG_NAME
        ds[name].attrs = new
    return ds


def write_netcdf(dataset: xr.Dataset, path: str | Path) -> None:
    """Write a dataset as a NetCDF4 file (h5netcdf engine).

    The file is built in memory, then written with plain file I/O
    (:func:`~feeddrive.io.outputs.write_bytes`): when HDF5 writes a file itself and a write
    fails (a full disk), its close fails too and h5py crashes the process (SIGSEGV, h5py
    3.16 / HDF5 1.14, issue 39 item 1); now a full disk is an ordinary ``OSError``.  The
    memory this takes (one copy of the file) is within the output budget
    (``feeddrive.engine.budget.check_output_memory`` counts two copies of the record).

    Parameters
    ----------
    dataset : xarray.Dataset
        The dataset, already with :func:`cf_attributes`.
    path : str or Path
        The file to write.
    """
    write_bytes(path, _netcdf_bytes(dataset))


class _KeptBuffer(io.BytesIO):
    """An in-memory file whose contents outlive its close (xarray < 2024.3 closes the
    file object it writes a NetCDF4 file into, and refuses to return bytes for h5netcdf)."""

    kept = b""

    def close(self) -> None:
        if not self.closed:
            self.kept = self.getvalue()
        super().close()


def _netcdf_bytes(dataset: Any) -> bytes:
    """The NetCDF4 (h5netcdf) file of ``dataset`` as bytes, built in memory."""
    buffer = _KeptBuffer()
    dataset.to_netcdf(buffer, engine="h5netcdf")
    return buffer.kept if buffer.closed else buffer.getvalue()


#: the run attributes that say where its numbers come from (:func:`provenance`)
PROVENANCE_KEYS = ("machine", "drive", "table_start_position_m", "parameter_set", "profile")


def provenance(attrs: Mapping[str, Any]) -> dict[str, Any]:
    """Where a run's numbers come from, as plain JSON values: feeddrive's version, the machine
    (a machine's run), the drive, its start position [m], the parameter set, the profile, a
    machine's axes (each one's drive, parameter set, start position [m]), the friction laws,
    the solver's statistics and the parameter sets as TOML (:func:`parameter_texts`) (those
    of ``attrs`` that are there).

    The one definition of a run's provenance in pandas' ``df.attrs``: a Parquet file's, whole
    or streamed, and ``Result.to_pandas()``'s (a streamed Parquet file and ``to_pandas``
    lacked the parameter sets: session 27).

    Parameters
    ----------
    attrs : mapping
        A run's attributes (``Result.attrs``; ``friction_laws`` and ``solver`` as JSON text).

    Returns
    -------
    dict
        ``feeddrive_version`` and the keys found.
    """
    out: dict[str, Any] = {"feeddrive_version": __version__}
    for key in PROVENANCE_KEYS:
        if key in attrs:
            value = attrs[key]
            out[key] = value.item() if isinstance(value, np.generic) else value
    for key in ("axes", "friction_laws", "solver"):
        if key in attrs:
            value = attrs[key]
            out[key] = json.loads(value) if isinstance(value, str) else value
    out.update(parameter_texts(attrs))
    return out


def provenance_line(attrs: Mapping[str, Any]) -> str:
    """The first line of a CSV export: a ``#`` comment saying what wrote the file.

    Parameters
    ----------
    attrs : mapping
        A run's attributes (:func:`provenance`).

    Returns
    -------
    str
        One line without its newline, e.g. ``# feeddrive 0.2.0: drive cdfs, table start
        position 0.4 m, parameter set wang2021, …; units in the column names``.
    """
    p = provenance(attrs)
    labels = {"machine": "machine {}", "drive": "drive {}",
              "table_start_position_m": "table start position {} m",
              "parameter_set": "parameter set {}", "profile": "profile {}"}
    axes = p.get("axes")
    if "machine" in p and isinstance(axes, dict):
        # a machine's run: each axis' own drive, start and set (the first axis' start alone,
        # the machine's name as drive and set: an outside check, 2026-12-07)
        words = [labels["machine"].format(p["machine"])]
        for name, axis in axes.items():
            own = [labels[key].format(axis[key]) for key in PROVENANCE_KEYS
                   if isinstance(axis, dict) and key in axis]
            words.append(f"axis {name} ({', '.join(own)})")
        if "profile" in p:
            words.append(labels["profile"].format(p["profile"]))
    else:
        words = [labels[key].format(p[key]) for key in PROVENANCE_KEYS if key in p]
    if isinstance(p.get("solver"), dict) and "method" in p["solver"]:
        words.append(f"solver {p['solver']['method']}")
    text = ", ".join(words).replace("\n", " ")
    return f"# feeddrive {__version__}: {text}; units in the column names"


#: how the solver record's line of a CSV export starts (:func:`solver_line`)
SOLVER_LINE = "# solver: "


def solver_line(attrs: Mapping[str, Any]) -> str | None:
    """The last line of a CSV export: a ``#`` comment holding the run's solver record as JSON,
    the record NetCDF's ``solver`` attribute holds (``Result.solver_stats``: the settings, the
    statistics, the error estimate when asked; SI).

    Parameters
    ----------
    attrs : mapping
        A run's attributes (``solver`` as JSON text or a dict).

    Returns
    -------
    str or None
        ``# solver: {...}`` without its newline; None when ``attrs`` has no solver record (a
        streamed run's first chunk).
    """
    value = attrs.get("solver")
    if value is None:
        return None
    record = json.loads(value) if isinstance(value, str) else value
    return SOLVER_LINE + json.dumps(record, ensure_ascii=False)


def add_solver_record(path: str | Path, solver_stats: Mapping[str, Any]) -> Path:
    """Add a finished run's solver record to its streamed ``.csv`` or ``.parquet`` output.

    :class:`ChunkWriter` writes the samples while the run goes, before its statistics (and an
    error estimate, made after the run) exist; the command line calls this when the run is
    done, a Python caller of ``simulate(..., output=)`` may.  A CSV gets the last line
    :func:`solver_line` (appended; on a failed write the file is cut back to what it held).  A
    Parquet file's pandas ``df.attrs`` get ``solver``: the file is written again, one row group
    at a time (memory: one chunk), under a temporary name renamed over it when complete.

    Parameters
    ----------
    path : str or Path
        The streamed output.
    solver_stats : mapping
        The run's ``Result.solver_stats`` [SI].

    Returns
    -------
    Path
        The file.

    Raises
    ------
    ParameterError
        For another extension (``.nc`` and ``.mat`` are written whole, with the record).
    """
    p = Path(path)
    ext = p.suffix.lower()
    if ext == ".csv":
        data = memoryview(f"{solver_line({'solver': dict(solver_stats)})}\n".encode())
        with open(p, "r+b", buffering=0) as f:  # unbuffered: nothing left to write at close
            size = f.seek(0, io.SEEK_END)
            try:
                while data:
                    data = data[f.write(data) or 0:]
                os.fsync(f.fileno())
            except BaseException:
                os.ftruncate(f.fileno(), size)
                raise
        return p
    if ext != ".parquet":
        raise ParameterError("output", str(p), "a solver record is added to a streamed "
                             ".parquet or .csv (.nc and .mat are written with it)")
    import pyarrow.parquet as pq

    with pq.ParquetFile(p) as source:
        schema = source.schema_arrow
        meta = dict(schema.metadata or {})
        attrs = json.loads(meta.get(b"PANDAS_ATTRS", b"{}"))
        attrs["solver"] = json.loads(json.dumps(dict(solver_stats)))
        meta[b"PANDAS_ATTRS"] = json.dumps(attrs).encode()
        with atomic_path(p) as tmp, pq.ParquetWriter(tmp, schema.with_metadata(meta)) as out:
            for i in range(source.num_row_groups):
                out.write_table(source.read_row_group(i))
    return p


def arrow_table(columns: Mapping[str, tuple[np.ndarray, str, str]],
                metadata: Mapping[str, str] | None = None,
                attrs: Mapping[str, Any] | None = None) -> Any:
    """A pyarrow Table from named columns with their units and descriptions.

    Plain field names; each field's ``unit`` and ``long_name`` in its metadata, the package
    version and unit convention in the schema's; the units, descriptions and ``attrs`` again
    as pandas' ``df.attrs`` (schema key ``PANDAS_ATTRS``, which ``pandas.read_parquet`` reads).

    Parameters
    ----------
    columns : mapping of str to (numpy.ndarray, str, str)
        ``{name: (values, unit, long_name)}``, values in the stated unit [unit].
    metadata : mapping of str to str, optional
        Further schema metadata.
    attrs : mapping, optional
        Further entries of pandas' ``df.attrs`` (JSON values; the run's :func:`provenance`).

    Returns
    -------
    pyarrow.Table
        The table.
    """
    import pyarrow as pa

    fields, arrays = [], []
    for name, (values, unit, long_name) in columns.items():
        array = pa.array(values)
        arrays.append(array)
        fields.append(pa.field(name, array.type, metadata={"unit": unit,
                                                             "long_name": long_name}))
    pandas_attrs = {"units": {name: unit for name, (_, unit, _) in columns.items()},
                    "long_names": {name: text for name, (_, _, text) in columns.items()},
                    "feeddrive_version": __version__, **(attrs or {})}
    meta = {"feeddrive_version": __version__,
            "units": "as feeddrive's CSV: mm, mm/s, N/µm, otherwise SI; each field's unit "
                     "in its metadata", **(metadata or {}),
            "PANDAS_ATTRS": json.dumps(pandas_attrs)}
    return pa.Table.from_arrays(arrays, schema=pa.schema(fields, metadata=meta))


def _engineering_columns(dataset: xr.Dataset) -> dict[str, tuple[np.ndarray, str, str]]:
    cols = {"time": (dataset["time"].values, "s", TIME_LONG_NAME)}
    for name, var in dataset.data_vars.items():
        unit = var.attrs.get("units", "")
        eng_unit, factor = ENGINEERING.get(unit, (unit, 1.0))
        cols[str(name)] = (var.values * factor, eng_unit, str(var.attrs.get("long_name", "")))
    return cols


def to_engineering_frame(dataset: xr.Dataset) -> pd.DataFrame:
    """A run's time signals as a DataFrame in engineering units, the units in the column names.

    The CSV export's columns: ``time [s]``, ``table_position [mm]``, ``table_speed [mm/s]``, …

    Parameters
    ----------
    dataset : xarray.Dataset
        A run's dataset (``Result.dataset``), signals in SI with their units.

    Returns
    -------
    pandas.DataFrame
        One column per signal, in mm, mm/s, N/µm, otherwise SI.
    """
    import pandas as pd

    return pd.DataFrame({f"{name} [{unit}]": values
                         for name, (values, unit, _) in _engineering_columns(dataset).items()})


def to_arrow_table(dataset: xr.Dataset) -> Any:
    """A run's time signals as a pyarrow Table in engineering units (the Parquet export).

    Parameters
    ----------
    dataset : xarray.Dataset
        A run's dataset (``Result.dataset``), signals in SI with their units.

    Returns
    -------
    pyarrow.Table
        Plain field names, each field's unit in its metadata; the run's provenance and
        parameter sets (:func:`parameter_texts`) as pandas' ``df.attrs``.
    """
    return arrow_table(_engineering_columns(dataset), attrs=provenance(dataset.attrs))


def parameter_texts(attrs: Mapping[str, Any]) -> dict[str, str]:
    """The parameter sets a run's attributes hold, as TOML under their attribute names: one
    drive's ``parameters_toml``, a machine's ``<axis>_parameters_toml`` for each axis (a
    Parquet file held none: session 27).

    Parameters
    ----------
    attrs : mapping
        A run's attributes (``Result.dataset.attrs``).

    Returns
    -------
    dict of str to str
        Attribute name → TOML text.
    """
    return {str(k): str(v) for k, v in attrs.items()
            if k == "parameters_toml" or str(k).endswith("_parameters_toml")}


def save_result(dataset: xr.Dataset, path: str | Path) -> Path:
    """Write a run's dataset to a file, the format following the extension.

    Written atomically: to a temporary name in the same folder, then renamed.

    Parameters
    ----------
    dataset : xarray.Dataset
        A run's dataset (``Result.dataset``), signals in SI with their units.
    path : str or Path
        The output file (``.nc``, ``.csv``, ``.parquet``, ``.mat``); its folder must exist.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    ParameterError
        For an unknown extension or a missing writer (:func:`check_format`), a ``.mat`` past
        the MATLAB 5 format's :data:`MAT5_LIMIT` (:func:`check_mat_output` refuses it before
        a run), two NetCDF names made one (:func:`plain_names`); nothing is left under
        ``path``.
    """
    if not isinstance(path, str | os.PathLike):  # os.fspath's TypeError (session 29)
        raise ParameterError("path", path, "expected a file name (str or pathlib.Path) "
                             f"ending in {', '.join(FORMATS)}")
    p = Path(path)
    ext = check_format(p)
    with atomic_path(p) as tmp:  # its folder must exist (docs/outputs.md)
        _write(dataset, tmp, ext, path)
    return p


def _write(dataset: xr.Dataset, p: Path, ext: str, path: str | Path) -> None:
    """Write ``dataset`` to ``p`` (the temporary name of ``path``, named in messages)."""
    if ext == ".csv":
        with open(p, "w", encoding="utf-8", newline="") as f:
            f.write(provenance_line(dataset.attrs) + "\n")
            to_engineering_frame(dataset).to_csv(f, index=False, float_format="%.10g")
            last = solver_line(dataset.attrs)
            if last is not None:
                f.write(last + "\n")
    elif ext == ".parquet":
        import pyarrow.parquet as pq

        pq.write_table(to_arrow_table(dataset), p)
    elif ext == ".nc":
        attrs = dataset.attrs
        if attrs.get("machine"):  # a machine's run: its name, then its axes' drives and sets
            title = (f"feeddrive simulation: machine {attrs['machine']}, "
                     f"{attrs.get('drive', '')} drive")
        else:
            title = f"feeddrive simulation: {attrs.get('drive', '')} drive"
        if attrs.get("parameter_set"):
            title += f", parameter set {attrs['parameter_set']}"
        # CF names (section 2.3): a machine's x.table_position is x_table_position, its own
        # name kept in the attribute "signal" (66 cfchecks warnings: an outside check,
        # 2026-12-07)
        write_netcdf(cf_attributes(plain_names(dataset, "signal"), title=title,
                                   action="simulate"), p)
    else:
        signals: dict[str, Any] = {}
        units: dict[str, Any] = {}
        for name, var in dataset.data_vars.items():
            # a machine's <axis>.<signal>: a struct per axis (MATLAB reads s.x.table_position)
            _nest(signals, str(name), var.values)
            _nest(units, str(name), var.attrs.get("units", ""))
        signals["time"] = dataset["time"].values
        units["time"] = "s"
        import scipy.io

        # oned_as="column": each signal an N×1 column vector, as MATLAB users index them;
        # uncompressed: zlib halved a 100-s run's file (27 → 13 MB) at 90× the time (0.01 →
        # 0.9 s), and a 1000-s run's 9 s of compression held off Ctrl-C with no progress
        # shown (an outside check, 2026-12-07)
        from scipy.io.matlab import MatWriteError

        try:
            # the version as the other formats carry it (NetCDF's source, Parquet's and the
            # CSV's feeddrive_version; a .mat lacked it: session 27)
            text = {**{str(k): str(v) for k, v in dataset.attrs.items()},
                    "feeddrive_version": __version__}
            scipy.io.savemat(p, {"feeddrive": {**signals, "units": units, "attrs": text}},
                             long_field_names=True, do_compression=False, oned_as="column")
        except MatWriteError:  # the struct reached the format's limit (scipy's traceback)
            need = mat_bytes(dataset.sizes["time"], len(dataset.data_vars))
            raise ParameterError(
                "output", shown(path), f"the run's {dataset.sizes['time']} samples of "
                f"{len(dataset.data_vars) + 1} columns ({need / 2**30:.3g} GiB with the text "
                f"attributes on top) are past the MATLAB 5 format's {MAT5_LIMIT / 2**30:g} GiB "
                "per variable (scipy.io.savemat); expected a shorter run [s] or a .nc, .parquet "
                "or .csv output") from None


def _nest(tree: dict[str, Any], name: str, value: Any) -> None:
    """``tree[a][b] = value`` for the dotted name ``a.b`` (a .mat struct of structs)."""
    *path, leaf = name.split(".")
    for key in path:
        tree = tree.setdefault(key, {})
    tree[leaf] = value


class ChunkWriter:
    """Appends a run's samples to ``.parquet`` or ``.csv`` chunk by chunk, so a long run never
    holds all of them.

    Engineering units, the columns of :func:`to_engineering_frame` or :func:`to_arrow_table`.
    The samples go to a temporary name in the output's folder; :meth:`close` renames it to
    ``path`` (a run stopped by Ctrl-C keeps the samples written so far, complete rows),
    :meth:`abort` removes it (a write that failed: nothing partial under ``path``).  The
    solver record is not known while the samples are written: :func:`add_solver_record` adds
    it after the run.  The rest of the run's provenance is the whole run's: the CSV's first
    line as :func:`provenance_line` writes it for ``Result.save`` (its solver named by
    ``method``), the Parquet file's ``df.attrs`` as :func:`provenance` (the parameter sets
    among them; a streamed file lacked them and its CSV line the solver: session 27).

    Parameters
    ----------
    path : str or Path
        The output file, ``.parquet`` or ``.csv``.
    model : Model
        The assembled model (signal names and units).
    system : DriveSystem
        The drive the run simulates.
    run_type : type
        ``feeddrive.engine.result.Run``, passed in so that this writer does not import the
        results layer that imports it.
    profile : Profile, optional
        The run's profile, named in the CSV's first line (:func:`provenance_line`) and the
        Parquet file's :func:`provenance`.
    method : str, optional
        The run's integration method (``SolverOptions.method``), named in the CSV's first
        line as the whole run's is.

    Raises
    ------
    ParameterError
        For another extension (``.nc`` and ``.mat`` hold the whole run).
    """

    def __init__(self, path: str | Path, model: Any, system: Any, run_type: Any,
                 profile: Any = None, *, method: str | None = None) -> None:
        self.path = Path(path)
        ext = self.path.suffix.lower()
        if ext not in (".parquet", ".csv"):
            raise ParameterError("output", str(self.path), "a streamed run is written as "
                                 ".parquet or .csv (.nc and .mat hold the whole run)")
        self.ext, self.model, self.system, self.run_type = ext, model, system, run_type
        self.profile, self.method = profile, method
        self._provenance: dict[str, Any] | None = None
        self._writer: Any = None
        self._atomic: Any = None
        self._first = True
        self._atomic = atomic_path(self.path)  # its folder must exist (docs/outputs.md)
        self._tmp = self._atomic.__enter__()

    def _columns(self, t: np.ndarray, y: np.ndarray,
                 aux: np.ndarray) -> dict[str, tuple[np.ndarray, str, str]]:
        run = self.run_type(t, y, aux, self.model, self.system, self.profile, {})
        cols = {"time": (t, "s", TIME_LONG_NAME)}
        for name, (unit, description) in run.meta.items():
            eng_unit, factor = ENGINEERING.get(unit, (unit, 1.0))
            cols[name] = (run.signal(name) * factor, eng_unit, description)
        return cols

    def _attrs(self, t: np.ndarray, y: np.ndarray, aux: np.ndarray) -> dict[str, Any]:
        """The run's attributes as its whole record has them (the parameter sets among them),
        less the solver record; made once (the parameter TOML and slot table take ms)."""
        if self._provenance is None:
            attrs: dict[str, Any] = self.run_type(t, y, aux, self.model, self.system,
                                                  self.profile, {}).attrs(full=True)
            attrs.pop("solver", None)  # the statistics of a streamed run are not known yet
            if self.profile is None:
                attrs.pop("profile", None)
            self._provenance = attrs
        return self._provenance

    def write(self, t: np.ndarray, y: np.ndarray, aux: np.ndarray) -> None:
        """Append one chunk of samples.

        Parameters
        ----------
        t : numpy.ndarray
            Sample times [s].
        y : numpy.ndarray
            States at those times, (samples, states) [SI, per state].
        aux : numpy.ndarray
            Auxiliary outputs at those times, (samples, outputs) [SI, per output].
        """
        if t.size == 0:
            return
        cols = self._columns(t, y, aux)
        if self.ext == ".csv":
            import pandas as pd

            frame = pd.DataFrame({f"{name} [{unit}]": values
                                  for name, (values, unit, _) in cols.items()})
            with open(self._tmp, "w" if self._first else "a", encoding="utf-8",
                      newline="") as f:
                if self._first:
                    named = {"solver": {"method": self.method}} if self.method else {}
                    f.write(provenance_line({**self._attrs(t, y, aux), **named}) + "\n")
                frame.to_csv(f, header=self._first, index=False, float_format="%.10g")
        else:
            import pyarrow.parquet as pq

            table = arrow_table(cols, attrs=provenance(self._attrs(t, y, aux)))
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
        """Remove the temporary file: nothing is left under ``path``.

        Parameters
        ----------
        err : BaseException, optional
            The error that stopped the write (passed to the atomic writer's exit).
        """
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
