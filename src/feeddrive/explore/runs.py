"""The explorer's finished runs, kept for the page: every signal of a run's Dataset on demand
(the signal picker, the A/B overlay), the run's data as CSV or MATLAB .mat (the writers of
``feeddrive simulate --output``), and a measured trace read as ``feeddrive analyze`` reads it.

Signals are sent in the engineering units of the exports (mm, mm/s, N/µm; :mod:`..units`),
with the unit and description the model's parts give them, at most
:data:`.compute.MAX_POINTS` samples (min/max per bucket).
"""

from __future__ import annotations

import os
import tempfile
import threading
from collections import OrderedDict
from pathlib import Path
from typing import Any

import numpy as np

from ..units import ENGINEERING
from .compute import MAX_POINTS, _list, decimate

#: finished runs kept (each holds its full-resolution Result)
KEEP_RUNS = 12
#: largest measured trace accepted [bytes of CSV text]
MAX_MEASURED = 8 * 1024 * 1024


class Runs:
    """Finished simulations by job id, the oldest dropped beyond :data:`KEEP_RUNS`.

    Parameters
    ----------
    keep : int, default 12
        How many runs are kept.
    """

    def __init__(self, keep: int = KEEP_RUNS) -> None:
        self._items: OrderedDict[str, tuple[Any, dict[str, str]]] = OrderedDict()
        self._lock = threading.Lock()
        self._keep = keep

    def put(self, run_id: str, result: Any, settings: dict[str, str]) -> None:
        """Keep a finished run, dropping the oldest beyond the limit.

        Parameters
        ----------
        run_id : str
            The job id of the run.
        result : Result
            The run.
        settings : dict of str to str
            The page settings it was run with.
        """
        with self._lock:
            self._items[run_id] = (result, dict(settings))
            while len(self._items) > self._keep:
                self._items.popitem(last=False)

    def get(self, run_id: str) -> tuple[Any, dict[str, str]] | None:
        """A kept run by id.

        Parameters
        ----------
        run_id : str
            The job id of the run.

        Returns
        -------
        tuple of (Result, dict) or None
            The run and its settings; None when unknown or dropped.
        """
        with self._lock:
            return self._items.get(run_id)


def _engineering(unit: str) -> tuple[str, float]:
    return ENGINEERING.get(unit, (unit, 1.0))


def signal_list(result: Any) -> list[dict[str, str]]:
    """Every signal of the run's Dataset: name, unit (engineering) and description.

    Parameters
    ----------
    result : Result
        The run.

    Returns
    -------
    list of dict of str to str
        ``name``, ``unit`` and ``description`` of each signal.
    """
    ds = result.dataset
    out = []
    for name, var in ds.data_vars.items():
        unit, _ = _engineering(str(var.attrs.get("units", "")))
        out.append({"name": str(name), "unit": unit,
                    "label": str(var.attrs.get("long_name", name))})
    return out


def signal(result: Any, name: str, max_points: int = MAX_POINTS) -> dict[str, Any]:
    """One signal, decimated keeping its peaks; KeyError when the run has no such signal.

    Parameters
    ----------
    result : Result
        The run.
    name : str
        The signal.
    max_points : int, default 4000
        Most samples returned.

    Returns
    -------
    dict
        Name, unit, label, time [s] and values [engineering unit of the signal], and the
        sample counts (recorded, sent).

    Raises
    ------
    KeyError
        When the run has no such signal.
    """
    ds = result.dataset
    if name not in ds.data_vars:
        raise KeyError(name)
    var = ds[name]
    unit, factor = _engineering(str(var.attrs.get("units", "")))
    values = np.asarray(var.values, dtype=float)
    t = np.asarray(ds["time"].values, dtype=float)
    idx = decimate(t.size, values, max_points)
    return {"name": name, "unit": unit, "label": str(var.attrs.get("long_name", name)),
            "time_s": _list(t[idx]), "values": _list(values[idx], factor),
            "samples": int(t.size), "samples_sent": int(idx.size)}


def export(result: Any, fmt: str) -> bytes:
    """The run's every sample as ``fmt`` ("csv": engineering units in the column names, as
    ``feeddrive simulate --output run.csv`` writes; "mat": SI with a ``units`` struct).

    Parameters
    ----------
    result : Result
        The run.
    fmt : str
        ``"csv"`` or ``"mat"``.

    Returns
    -------
    bytes
        The file's contents.
    """
    from ..io.results import save_result

    if fmt not in ("csv", "mat"):
        raise ValueError(f"format = {fmt!r}: expected csv or mat")
    with tempfile.TemporaryDirectory(prefix="feeddrive-explore-") as folder:
        path = Path(folder) / f"run.{fmt}"
        save_result(result.dataset, path)
        return path.read_bytes()


def measured_trace(text: str, name: str = "measured.csv") -> dict[str, Any]:
    """A table position trace (CSV as ``feeddrive analyze`` reads it: ``time`` [s] and
    ``position`` or ``table_position`` [mm] by default, units in brackets honoured) as the
    page overlays it: time [s], position [mm], speed [mm/s] (its own speed column when the
    file has ``table_speed``, else the position differentiated).  A refused file raises
    ValueError with the file's line named.

    Parameters
    ----------
    text : str
        The CSV text.
    name : str, default "measured.csv"
        The file's name as the page sent it: shown in messages and the answer (its last
        part, control characters escaped, cut), never used in a path.

    Returns
    -------
    dict
        Name, sample count, decimated ``time_s`` [s], ``position_mm`` [mm] and ``speed_mm_s``
        [mm/s], and where the speed came from.

    Raises
    ------
    MeasuredDataError
        For a file ``feeddrive analyze`` would refuse.
    ValueError
        For a file larger than the page accepts.
    """
    from ..io import measured
    from ..io.outputs import shown

    # the page's name is only ever shown: never part of a path (".." was a folder, issue 39)
    label = shown(name.rsplit("/", 1)[-1].strip() or "measured.csv")
    if len(text.encode("utf-8")) > MAX_MEASURED:
        raise ValueError(f"{label}: larger than {MAX_MEASURED // 1024 // 1024} MB")
    with tempfile.TemporaryDirectory(prefix="feeddrive-measured-") as folder:
        path = Path(folder) / "measured.csv"
        path.write_text(text, encoding="utf-8")
        try:
            has_speed = _has_column(text, "table_speed")
            trace = measured.read_position_trace(
                path, speed_column="table_speed" if has_speed else None, source=label)
        finally:
            os.unlink(path)
    t = trace.time
    speed = trace.speed if trace.speed is not None else np.gradient(trace.position, t)
    idx = decimate(t.size, speed)
    return {"name": label, "samples": int(t.size), "time_s": _list(t[idx]),
            "position_mm": _list(trace.position[idx], 1e3),
            "speed_mm_s": _list(speed[idx], 1e3),
            "speed_from": "table_speed column" if trace.speed is not None
            else "the position differentiated"}


def _has_column(text: str, column: str) -> bool:
    for line in text.splitlines():
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        header = [h.split("[")[0].strip().lower() for h in
                  stripped.replace(";", ",").replace("\t", ",").split(",")]
        return column in header
    return False
