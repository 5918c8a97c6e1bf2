"""Records of the acceptance tests (CSV): an XY trace of a circular test, the approaches of a
positioning test.

The file rules are those of docs/measured-data.md (one header row, ``#`` comments, the
separator detected, units in brackets honoured); errors are
:class:`~feeddrive.io.measured.MeasuredDataError`, one line naming the file, the line and the
problem.  The formats are documented in docs/acceptance-tests.md.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .measured import MeasuredDataError, _need_rows, check_increasing, read_csv_table

__all__ = ["POSITIONING_COLUMNS", "X_COLUMNS", "XY_COLUMNS", "Y_COLUMNS", "PositioningRecord",
           "XYTrace", "read_positioning_record", "read_xy_trace", "write_positioning_record",
           "write_xy_trace"]

#: x columns looked for, in this order (a machine run names them ``<axis>.<signal>``)
X_COLUMNS = ("x", "x_position", "x.table_position")
#: y columns looked for, in this order
Y_COLUMNS = ("y", "y_position", "y.table_position")
#: the columns of a circular test's record, as :func:`write_xy_trace` writes them
XY_COLUMNS = ("time [s]", "x [mm]", "y [mm]")
#: the columns of a positioning record, as :func:`write_positioning_record` writes them
POSITIONING_COLUMNS = ("target [mm]", "direction", "cycle", "position [mm]")


@dataclass(frozen=True)
class XYTrace:
    """Time and the two axes' positions of a circular test, SI.

    Parameters
    ----------
    time : numpy.ndarray
        Sample times [s].
    x, y : numpy.ndarray
        Positions [m].
    source : str
        The file's name.
    columns : tuple of str
        The x and y columns read.
    """

    time: np.ndarray
    x: np.ndarray
    y: np.ndarray
    source: str
    columns: tuple[str, str]


def read_xy_trace(path: str | Path, *, time_column: str = "time", x_column: str | None = None,
                  y_column: str | None = None, time_unit: str | None = None,
                  position_unit: str | None = None, sep: str | None = None,
                  decimal: str = ".") -> XYTrace:
    """Read time, x and y of a circular test; default units s and mm.

    Parameters
    ----------
    path : str or Path
        The CSV file (at least 16 rows).
    time_column : str, default "time"
        The time column.
    x_column, y_column : str, optional
        The position columns; by default the first of ``X_COLUMNS`` (``Y_COLUMNS``) present.
    time_unit, position_unit : str, optional
        Units overriding the header's.
    sep : str, optional
        Column separator; detected from the header when omitted.
    decimal : str, default "."
        Decimal mark.

    Returns
    -------
    XYTrace
        The trace in SI.

    Raises
    ------
    MeasuredDataError
        For a missing x or y column (before any other work), too few rows, bad cells or
        non-increasing time.
    """
    table = read_csv_table(path, sep=sep, decimal=decimal)
    names = {}
    for axis, option, candidates in (("x", x_column, X_COLUMNS), ("y", y_column, Y_COLUMNS)):
        wanted = [option] if option else list(candidates)
        if not any(table.has(c) for c in wanted):
            shown = ", ".join(repr(n) for n in table.names)
            raise MeasuredDataError(
                table.source, table.header_line,
                f"no {axis} column ({' or '.join(repr(c) for c in wanted)}) in the header "
                f"(columns: {shown}); a circular test needs x and y positions "
                f"(--{axis}-column){table.header_hint()}")
        names[axis] = wanted
    _need_rows(table, 16, "circular test")
    time, tname, _ = table.quantity([time_column], "time", unit=time_unit, default_unit="s")
    check_increasing(table, time, tname)
    x, xname, _ = table.quantity(names["x"], "length", unit=position_unit, default_unit="mm")
    y, yname, _ = table.quantity(names["y"], "length", unit=position_unit, default_unit="mm")
    return XYTrace(time=time, x=x, y=y, source=table.source, columns=(xname, yname))


def write_xy_trace(path: str | Path, time: np.ndarray, x: np.ndarray, y: np.ndarray, *,
                   comment: str = "") -> Path:
    """Write a circular test's trace: time [s], x [mm], y [mm].

    Written atomically with 17 significant digits, so that :func:`read_xy_trace` gives the
    same numbers back (positions as x·1e3 [mm], read back times 1e-3).

    Parameters
    ----------
    path : str or Path
        The CSV file.
    time : numpy.ndarray
        Sample times [s].
    x, y : numpy.ndarray
        Positions [m].
    comment : str, default ""
        ``#`` lines written first (what produced the record).

    Returns
    -------
    Path
        The file written.
    """
    from .outputs import atomic_path

    rows = [f"{float(t)!r},{float(a * 1e3)!r},{float(b * 1e3)!r}"
            for t, a, b in zip(np.asarray(time, dtype=float), np.asarray(x, dtype=float),
                               np.asarray(y, dtype=float), strict=True)]
    text = "".join(f"# {line}\n" for line in comment.splitlines() if line)
    text += ",".join(XY_COLUMNS) + "\n" + "\n".join(rows) + "\n"
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return Path(path)


@dataclass(frozen=True)
class PositioningRecord:
    """The approaches of a positioning test, SI.

    Parameters
    ----------
    targets : numpy.ndarray
        The target positions P_i, increasing [m].
    deviation_up, deviation_down : numpy.ndarray
        x_ij↑, x_ij↓, shape (m, n) [m].
    source : str
        The file's name.
    """

    targets: np.ndarray
    deviation_up: np.ndarray
    deviation_down: np.ndarray
    source: str


def write_positioning_record(path: str | Path, targets: Sequence[float] | np.ndarray,
                             deviation_up: np.ndarray, deviation_down: np.ndarray, *,
                             comment: str = "") -> Path:
    """Write every approach as a row: target [mm], direction (+1 ↑, −1 ↓), cycle, position [mm].

    Written atomically with 17 significant digits, so that :func:`read_positioning_record`
    gives the same numbers back.

    Parameters
    ----------
    path : str or Path
        The CSV file.
    targets : sequence of float
        P_i [m].
    deviation_up, deviation_down : numpy.ndarray
        x_ij↑, x_ij↓, shape (m, n) [m].
    comment : str, default ""
        A ``#`` line written first (what produced the record).

    Returns
    -------
    Path
        The file written.
    """
    from .outputs import atomic_path

    p = np.asarray(targets, dtype=float)
    rows = []
    for direction, dev in ((1, deviation_up), (-1, deviation_down)):
        for i in range(p.size):
            for j in range(dev.shape[1]):
                # the target as typed (12 significant digits: a --targets 175 read as
                # 0.17500000000000002 m was written 175.00000000000003), the position as the
                # sum the reader subtracts again: x_ij = P_ij − P_i
                target = float(f"{p[i] * 1e3:.12g}")
                rows.append(f"{target!r},{direction},{j + 1},"
                            f"{target + float(dev[i, j]) * 1e3!r}")
    text = "".join(f"# {line}\n" for line in comment.splitlines() if line)
    text += ",".join(POSITIONING_COLUMNS) + "\n" + "\n".join(rows) + "\n"
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return Path(path)


def read_positioning_record(path: str | Path, *, sep: str | None = None, decimal: str = "."
                            ) -> PositioningRecord:
    """Read the approaches of a positioning test.

    Columns: ``target`` [mm], ``direction`` (+1 for an approach in the positive direction,
    −1 for the negative), and the actual ``position`` [mm] or the ``deviation`` P_ij − P_i
    [µm]; a ``cycle`` column is optional (the approaches of one target and direction are taken
    in file order).

    Parameters
    ----------
    path : str or Path
        The CSV file.
    sep : str, optional
        Column separator; detected when omitted.
    decimal : str, default "."
        Decimal mark.

    Returns
    -------
    PositioningRecord
        Targets and deviations in SI.

    Raises
    ------
    MeasuredDataError
        For missing columns, a direction other than ±1, or targets approached a different
        number of times.
    """
    table = read_csv_table(path, sep=sep, decimal=decimal)
    for needed in ("target", "direction"):
        if not table.has(needed):
            shown = ", ".join(repr(n) for n in table.names)
            raise MeasuredDataError(table.source, table.header_line,
                                    f"no column {needed!r} in the header (columns: {shown}); "
                                    "a positioning record needs target, direction and "
                                    f"position or deviation{table.header_hint()}")
    _need_rows(table, 20, "positioning record (2 targets × 5 cycles × 2 directions)")
    target, _, _ = table.quantity(["target"], "length", unit=None, default_unit="mm")
    direction = table.numbers("direction")
    bad = np.flatnonzero((direction != 1.0) & (direction != -1.0))
    if bad.size:
        k = int(bad[0])
        raise MeasuredDataError(table.source, int(table.lines[k]),
                                f"column 'direction': {direction[k]:g}; expected +1 (positive "
                                "approach) or -1 (negative)")
    if table.has("position"):
        position, _, _ = table.quantity(["position"], "length", unit=None, default_unit="mm")
        deviation = position - target
    else:
        deviation, _, _ = table.quantity(["deviation"], "length", unit=None, default_unit="um")
    targets = np.unique(target)
    counts = {}
    columns: dict[tuple[int, int], list[float]] = {}
    for i, p in enumerate(targets):
        for d in (1, -1):
            rows = np.flatnonzero((target == p) & (direction == d))
            counts[(i, d)] = rows.size
            columns[(i, d)] = list(deviation[rows])
    n = set(counts.values())
    if len(n) != 1:
        (i, d), c = min(counts.items(), key=lambda kv: kv[1])
        raise MeasuredDataError(table.source, None,
                                f"target {targets[i] * 1e3:g} mm is approached {c} times in "
                                f"the {'positive' if d > 0 else 'negative'} direction, the "
                                f"others up to {max(n)}; every target needs the same number "
                                "each way")
    up = np.array([columns[(i, 1)] for i in range(targets.size)])
    down = np.array([columns[(i, -1)] for i in range(targets.size)])
    return PositioningRecord(targets=targets, deviation_up=up, deviation_down=down,
                             source=table.source)
