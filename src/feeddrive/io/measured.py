"""Readers for measured data: friction tests and interferometer position traces (CSV).

The file formats are documented in docs/measured-data.md.  In short: a delimited text file
with one header row; ``#`` lines and blank lines are ignored anywhere; a header may carry its
unit in brackets (``time [s]``, ``table_position [mm]``), which is honoured.  Column names
are matched case-insensitively without their unit.  Every value is converted to SI on
reading; every row keeps its file line number so that errors can name it.

Errors are :class:`MeasuredDataError` (a ``ValueError``) whose message names the file, the
line and the problem, e.g. ``static.csv, line 7: column 'force': 'abc' is not a number``.
"""

from __future__ import annotations

import contextlib
import math
import re
import signal
import threading
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..parameters import ParameterError
from ..units import LARGEST_SPEED

__all__ = [
    "COMMAND_COLUMNS",
    "CURRENT_UNITS",
    "FORCE_UNITS",
    "LENGTH_UNITS",
    "SPEED_UNITS",
    "TIME_UNITS",
    "CsvTable",
    "MeasuredDataError",
    "PositionTrace",
    "PreslidingTest",
    "StaticTest",
    "check_text_file",
    "encoding_hint",
    "first_beyond_largest",
    "read_csv_table",
    "read_position_trace",
    "read_presliding_test",
    "read_static_test",
    "split_unit",
]

# SI factor of every accepted unit spelling, per dimension (µ: micro sign or Greek mu, or u)
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "μm": 1e-6, "nm": 1e-9}
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "μs": 1e-6}
SPEED_UNITS = {"m/s": 1.0, "mm/s": 1e-3, "um/s": 1e-6, "µm/s": 1e-6, "μm/s": 1e-6,
               "mm/min": 1e-3 / 60.0, "m/min": 1.0 / 60.0}
FORCE_UNITS = {"N": 1.0, "kN": 1e3}
CURRENT_UNITS = {"A": 1.0, "mA": 1e-3}

_DIMENSIONS = {
    "length": LENGTH_UNITS,
    "time": TIME_UNITS,
    "speed": SPEED_UNITS,
    "force": FORCE_UNITS,
    "current": CURRENT_UNITS,
}

#: the largest magnitude a measured value of each dimension may have [SI]: far beyond any
#: feed drive (speed and force as ``static_fit``'s test limits), so that a larger one is a
#: wrong unit or a damaged file, refused naming its line; a 1e308 cell overflowed the fit's
#: sums to inf and NaN (issue 39 item 5).  Time allows absolute clocks (Unix seconds).
LARGEST_MAGNITUDE = {"length": 1e3, "time": 1e15, "speed": LARGEST_SPEED, "force": 1e7,
                     "current": 1e5, "torque": 1e6}

#: command-speed columns looked for in a position trace, in this order
COMMAND_COLUMNS = ("command_speed", "table_speed_reference")

_UNIT_RE = re.compile(r"^(?P<name>.*?)\s*\[(?P<unit>[^\]]*)\]\s*$")


class MeasuredDataError(ValueError):
    """A measured-data file was refused; the message names the file, the line and the problem.

    Parameters
    ----------
    source : str
        The file's name as shown.
    line : int or None
        The 1-based file line of the problem; None when it concerns the whole file.
    message : str
        What is wrong.
    """

    def __init__(self, source: str, line: int | None, message: str) -> None:
        self.source = source
        self.line = line
        where = f"{source}, line {line}" if line is not None else source
        super().__init__(f"{where}: {message}")


def split_unit(header: str) -> tuple[str, str | None]:
    """Split a header cell into its name and its bracketed unit.

    Parameters
    ----------
    header : str
        The cell, e.g. ``"time [s]"`` (quotes and spaces stripped).

    Returns
    -------
    name : str
        ``"time"``.
    unit : str or None
        ``"s"``; None when the cell gives no unit.
    """
    text = header.strip().strip('"').strip()
    m = _UNIT_RE.match(text)
    if m:
        return m.group("name").strip(), m.group("unit").strip()
    return text, None


def unit_factor(unit: str, dimension: str, *, what: str) -> float:
    """The factor that converts a value in ``unit`` to SI, for one dimension.

    Parameters
    ----------
    unit : str
        The unit as written (``"mm/s"``, ``"um"``, ``"kN"``); case-insensitive as a fallback.
    dimension : str
        ``"length"``, ``"time"``, ``"speed"``, ``"force"`` or ``"current"``.
    what : str
        What is being read, for the message.

    Returns
    -------
    float
        SI value of one ``unit`` [SI unit of the dimension].

    Raises
    ------
    ValueError
        When ``unit`` is not a unit of ``dimension``; the message lists the known ones.
    """
    table = _DIMENSIONS[dimension]
    if unit in table:
        return table[unit]
    lowered = {k.lower(): v for k, v in table.items()}
    if unit.lower() in lowered:
        return lowered[unit.lower()]
    raise ValueError(f"{what}: unit {unit!r} is not a {dimension} unit; expected one of "
                     f"{', '.join(table)}{encoding_hint(unit)}")


def encoding_hint(text: str, *, unit: bool = True) -> str:
    """``"; the file is not UTF-8 …"`` when ``text`` holds the replacement character that
    a byte which is not UTF-8 was read as (a ``µ`` saved as Windows-1252 / Latin-1 read as
    ``'\ufffdm'``), else ``""``: the end of a message about a header's unit, or with
    ``unit=False`` about its names (``posición`` saved as Latin-1: ``'posici\ufffdn'``).

    Parameters
    ----------
    text : str
        A header's unit as read, or (``unit=False``) its names.
    unit : bool, default True
        Whether ``text`` is a unit (the hint then asks after a µ).

    Returns
    -------
    str
        The hint, or an empty string.
    """
    if "\ufffd" not in text:
        return ""
    if not unit:
        return ("; the file is not UTF-8 text (saved as Windows-1252 or Latin-1?): save it as "
                "UTF-8 (docs/measured-data.md)")
    return ("; the file is not UTF-8 text (a µ saved as Windows-1252 or Latin-1?): save it "
            "as UTF-8 (docs/measured-data.md)")


@dataclass(frozen=True)
class CsvTable:
    """A scanned delimited text file; its columns are parsed on demand by pandas.

    Parameters
    ----------
    source : str
        The file's name as shown in messages.
    names : tuple of str
        Header names, units stripped.
    units : tuple of (str or None)
        Each column's bracketed unit, None when the header gives none.
    lines : numpy.ndarray of int
        The 1-based file line of every data row.
    header_line : int
        The header's file line.
    path : Path
        The file.
    sep : str or None
        The column separator; None for whitespace.
    skip : numpy.ndarray of int
        0-based file lines that are not data rows (preamble, header, comments).
    decimal : str, default "."
        The decimal mark.
    _parsed : dict
        Cache of the columns parsed so far (internal; not compared or shown).
    """

    source: str
    names: tuple[str, ...]
    units: tuple[str | None, ...]
    lines: np.ndarray  # file line number (1-based) of every data row
    header_line: int
    path: Path
    sep: str | None  # None: whitespace
    skip: np.ndarray  # 0-based file lines that are not data rows (preamble, header, comments)
    decimal: str = "."
    _parsed: dict[int, np.ndarray] = field(default_factory=dict, repr=False, compare=False)

    def __len__(self) -> int:
        return int(self.lines.size)

    def find(self, name: str) -> int | None:
        """Index of a column by name, case-insensitive, unit ignored.

        Parameters
        ----------
        name : str
            The column name.

        Returns
        -------
        int or None
            Its index; None when the file has no such column.
        """
        key = name.strip().lower()
        for i, n in enumerate(self.names):
            if n.lower() == key:
                return i
        return None

    def has(self, name: str) -> bool:
        """Whether the file has a column of this name (case-insensitive, unit ignored).

        Parameters
        ----------
        name : str
            The column name.

        Returns
        -------
        bool
            True when :meth:`find` finds it.
        """
        return self.find(name) is not None

    def header_hint(self) -> str:
        """:func:`encoding_hint` of the header (its names and units): the end of a "no
        column" message when the header did not decode as UTF-8 (a ``posición`` saved as
        Latin-1 is shown ``'posici\ufffdn'``), else ``""``.

        Returns
        -------
        str
            The hint, or an empty string.
        """
        return encoding_hint("".join(self.names) + "".join(u or "" for u in self.units),
                             unit=False)

    def _missing(self, names: Sequence[str]) -> MeasuredDataError:
        shown = ", ".join(repr(n) for n in self.names)
        wanted = " or ".join(repr(n) for n in names)
        return MeasuredDataError(self.source, self.header_line,
                                 f"no column {wanted} in the header (columns: {shown})"
                                 f"{self.header_hint()}")

    def _read(self, i: int, dtype: Any) -> Any:
        import pandas as pd

        _pandas_precision()
        with _interrupt_kept():
            frame = self._read_csv(pd, i, dtype)
        return frame[i].to_numpy()

    def _read_csv(self, pd: Any, i: int, dtype: Any) -> Any:
        return pd.read_csv(
            self.path, sep=r"\s+" if self.sep is None else self.sep, header=None,
            names=list(range(len(self.names))), usecols=[i], index_col=False,
            skiprows=self.skip.tolist(), skip_blank_lines=False, dtype={i: dtype},
            decimal=self.decimal, keep_default_na=False, na_values=[""],
            na_filter=dtype is not str,
            skipinitialspace=True, encoding="utf-8-sig", encoding_errors="replace",
            engine="c", quoting=3, **_PRECISION)

    def cell(self, i: int, k: int) -> str:
        """The text of one cell, for messages.

        Parameters
        ----------
        i : int
            Column index.
        k : int
            Data-row index (0-based, not the file line).

        Returns
        -------
        str
            The cell's text, stripped.
        """
        return str(self._read(i, str)[k]).strip()

    def numbers(self, name: str) -> np.ndarray:
        """A column as float64, refusing empty, non-numeric and non-finite cells.

        Parameters
        ----------
        name : str
            The column name.

        Returns
        -------
        numpy.ndarray
            The values, in the file's unit [unit of the column].

        Raises
        ------
        MeasuredDataError
            For a missing column, or a bad cell (named with its file line).
        """
        i = self.find(name)
        if i is None:
            raise self._missing([name])
        if i in self._parsed:
            return self._parsed[i]
        try:
            values = np.asarray(self._read(i, np.float64), dtype=float)
        except (ValueError, TypeError):
            values = None
        if values is None or values.size != len(self):
            # pandas refused a cell: find it, and its line, cell by cell
            raw = self._read(i, str)
            values = np.empty(len(raw))
            for k, cell in enumerate(raw):
                text = "" if cell is None or (isinstance(cell, float) and cell != cell) \
                    else str(cell).strip()
                try:
                    values[k] = float(text.replace(self.decimal, ".") if self.decimal != "."
                                      else text)
                except ValueError:
                    problem = "empty cell" if not text else f"{text!r} is not a number"
                    if text and self.decimal == "." and _is_decimal_comma(text):
                        problem += ("; a decimal comma: read the file with --decimal , "
                                    "(in Python decimal=',')")
                    raise MeasuredDataError(self.source, int(self.lines[k]),
                                            f"column {self.names[i]!r}: {problem}") from None
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            k = int(bad[0])
            text = self.cell(i, k)
            problem = "empty cell" if not text else f"{text!r} is not a finite number"
            raise MeasuredDataError(self.source, int(self.lines[k]),
                                    f"column {self.names[i]!r}: {problem}")
        self._parsed[i] = values
        return values

    def quantity(self, names: Sequence[str], dimension: str, *, unit: str | None,
                 default_unit: str) -> tuple[np.ndarray, str, str]:
        """The first present column of ``names``, converted to SI.

        The unit is ``unit`` if given (an option), else the header's bracketed unit, else
        ``default_unit``; an option that contradicts the header's unit is refused.

        Parameters
        ----------
        names : sequence of str
            Candidate column names, in order of preference.
        dimension : str
            The quantity's dimension (see ``unit_factor``).
        unit : str or None
            The unit an option gives, or None.
        default_unit : str
            The unit when neither the option nor the header gives one.

        Returns
        -------
        values : numpy.ndarray
            The column in SI [SI unit of the dimension].
        name : str
            The column used.
        unit : str
            The unit it was read in.

        Raises
        ------
        MeasuredDataError
            When no candidate is present, a cell is bad, or option and header disagree.
        """
        for name in names:
            i = self.find(name)
            if i is None:
                continue
            header_unit = self.units[i]
            what = f"{self.source}: column {self.names[i]!r}"
            if unit is not None and header_unit is not None:
                given = unit_factor(unit, dimension, what=what)
                if not math.isclose(given, unit_factor(header_unit, dimension, what=what)):
                    raise MeasuredDataError(
                        self.source, self.header_line,
                        f"column {self.names[i]!r} is in [{header_unit}] by its header but the "
                        f"unit option says {unit!r}; drop one of them")
            used = unit if unit is not None else header_unit or default_unit
            factor = unit_factor(used, dimension, what=what)
            values = self.numbers(name) * factor
            self.check_magnitude(i, values, dimension, used, factor)
            return values, self.names[i], used
        raise self._missing(names)

    def check_magnitude(self, i: int, values: np.ndarray, dimension: str,
                        unit: str, factor: float) -> None:
        """Refuse a value beyond ``LARGEST_MAGNITUDE`` of its dimension, naming its line.

        Parameters
        ----------
        i : int
            The column index.
        values : numpy.ndarray
            The column in SI [SI unit of the dimension].
        dimension : str
            A key of ``LARGEST_MAGNITUDE``.
        unit : str
            The unit the file gives, for the message.
        factor : float
            SI value of one ``unit`` [SI unit of the dimension].

        Raises
        ------
        MeasuredDataError
            At the first value too large.
        """
        limit = LARGEST_MAGNITUDE[dimension]
        k = first_beyond_largest(values, dimension)
        if k is not None:
            raise MeasuredDataError(
                self.source, int(self.lines[k]),
                f"column {self.names[i]!r}: {self.cell(i, k)} [{unit}] is beyond any feed "
                f"drive (|{dimension}| ≤ {limit / factor:g} {unit}); check the file's unit")


def first_beyond_largest(values: np.ndarray, dimension: str) -> int | None:
    """The index of the first value beyond ``LARGEST_MAGNITUDE`` of its dimension (a
    wrong unit or a damaged file), or None: the one bound every measured value is held to,
    a CSV column's (:meth:`CsvTable.check_magnitude`) and a ``.mat`` record's
    (feeddrive.analysis.rig_record).

    Parameters
    ----------
    values : numpy.ndarray
        The values in SI [SI unit of the dimension].
    dimension : str
        A key of ``LARGEST_MAGNITUDE``.

    Returns
    -------
    int or None
        The index, or None when every value is within.
    """
    big = np.flatnonzero(np.abs(values) > LARGEST_MAGNITUDE[dimension])
    return int(big[0]) if big.size else None


def _is_decimal_comma(text: str) -> bool:
    """Whether a cell that is not a number with ``.`` decimals is one with ``,``."""
    try:
        float(text.replace(",", "."))
    except ValueError:
        return False
    return "," in text


#: the first line Excel writes to name a CSV file's separator (``sep=;``)
_EXCEL_SEP_RE = re.compile(r'^\s*"?sep=(?P<sep>[^"\r\n])"?[\r\n]*$')


def _detect_separator(header: str) -> str | None:
    for sep in (",", ";", "\t"):
        if sep in header:
            return sep
    return None  # whitespace


def _split(line: str, sep: str | None) -> list[str]:
    return line.split() if sep is None else [c.strip() for c in line.split(sep)]


# leading bytes of binary formats a user may hand over instead of CSV text
_BINARY_SIGNATURES = ((b"PAR1", "a Parquet file"), (b"\x89HDF", "an HDF5/NetCDF-4 file"),
                      (b"CDF\x01", "a NetCDF file"), (b"CDF\x02", "a NetCDF file"),
                      (b"MATLAB", "a MATLAB .mat file"), (b"PK\x03\x04", "a zip archive "
                      "(an .xlsx workbook?)"), (b"\x89PNG", "a PNG image"))


def check_text_file(path: str | Path) -> None:
    """Refuse, saying what it is, a path that is not a text file.

    A directory, a Parquet, NetCDF, .mat or other binary file is named as such (issue 12 item
    14: they were reported as "line 2: 1 cells, but the header has 4 columns").

    Parameters
    ----------
    path : str or Path
        The file to read.

    Raises
    ------
    MeasuredDataError
        For a directory or a binary file.
    FileNotFoundError
        When nothing is at ``path``.
    """
    p = Path(path)
    if p.is_dir():
        raise MeasuredDataError(p.name, None, "is a directory; expected a CSV file")
    if not p.is_file():
        if p.exists():  # a device, a pipe, a socket: nothing a CSV reader may wait on
            raise MeasuredDataError(p.name, None, "is not a regular file; expected a CSV file")
        raise FileNotFoundError(f"{path}: no such file")
    with p.open("rb") as stream:
        head = stream.read(4096)
    for signature, what in _BINARY_SIGNATURES:
        if head.startswith(signature):
            raise MeasuredDataError(p.name, None, f"is {what}, not CSV text; export it as "
                                    "CSV (docs/measured-data.md)")
    if _looks_utf16(head):
        raise MeasuredDataError(p.name, None, "looks like UTF-16 text (a byte-order mark or a "
                                "NUL byte beside every character), not UTF-8; save it as "
                                "UTF-8 (Excel: 'CSV UTF-8'; docs/measured-data.md)")
    if b"\x00" in head:
        raise MeasuredDataError(p.name, None, "is a binary file (it holds NUL bytes), not CSV "
                                "text; export it as CSV (docs/measured-data.md)")


def _looks_utf16(head: bytes) -> bool:
    """Whether a file's first bytes are UTF-16 text: a byte-order mark (FF FE or FE FF), or
    every other byte NUL and none of the others (ASCII text, little or big endian)."""
    if head.startswith((b"\xff\xfe", b"\xfe\xff")):
        return True
    sample = head[:256]
    sample = sample[:len(sample) - len(sample) % 2]
    if len(sample) < 4:
        return False
    even, odd = sample[0::2], sample[1::2]
    return (odd.count(0) == len(odd) and even.count(0) == 0) or \
        (even.count(0) == len(even) and odd.count(0) == 0)


_CHUNK = 1 << 22  # bytes scanned at a time (index arrays: 8 bytes per byte scanned)
# exact (round-trip) float parsing: the default from pandas 3, an option before
_PRECISION: dict[str, Any] = {}


def _pandas_precision() -> None:
    import pandas as pd

    if int(pd.__version__.split(".")[0]) < 3:
        _PRECISION["float_precision"] = "round_trip"


_SPACE = np.zeros(256, dtype=bool)
_SPACE[[9, 10, 11, 12, 13, 32]] = True


def _scan_lines(data: np.ndarray, first_line: int, sep: str | None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For the complete lines in ``data`` (bytes, ending in a newline): (line numbers,
    is-data-row mask, cell counts).  A data row is a line that is not blank and whose
    first non-blank character is not ``#``."""
    ends = np.flatnonzero(data == 10)
    starts = np.r_[0, ends[:-1] + 1]
    numbers = first_line + np.arange(ends.size)
    space = _SPACE[data]
    # first non-blank byte of each line: the next non-space at or after the start
    nonspace = np.flatnonzero(~space)
    k = np.searchsorted(nonspace, starts)
    has = k < nonspace.size
    first = np.where(has, nonspace[np.minimum(k, max(nonspace.size - 1, 0))], -1) \
        if nonspace.size else np.full(starts.size, -1)
    blank = ~has | (first >= ends)
    comment = ~blank & (data[np.maximum(first, 0)] == ord("#"))
    is_data = ~blank & ~comment
    if sep is None:
        # a cell starts at a non-space byte that follows a space (or the line start)
        prev_space = np.r_[True, space[:-1]]
        cell_starts = np.flatnonzero(~space & prev_space)
    else:
        cell_starts = np.flatnonzero(data == ord(sep))
    counts = np.searchsorted(cell_starts, ends) - np.searchsorted(cell_starts, starts)
    if sep is not None:
        counts = counts + 1
    return numbers, is_data, counts


@contextlib.contextmanager
def _interrupt_kept() -> Iterator[list[bool]]:
    """Ctrl-C while pandas reads a file, kept: pandas' C reader turns the KeyboardInterrupt
    raised inside its read into a ``ParserError`` ("Calling read(nbytes) on source failed"),
    which the column reader took for a bad cell and read on — `fit` ran on, `validate` ended
    with exit status 0 (an outside check, 2026-12-07).  On the main thread with Python's
    handler in place, SIGINT is noted (the list becomes true) and raised as before, and once
    pandas returns or raises, KeyboardInterrupt is raised in its place."""
    hit: list[bool] = []
    previous = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is not threading.main_thread() or not callable(previous):
        yield hit
        return

    def noted(signum: int, frame: Any) -> None:
        hit.append(True)
        previous(signum, frame)

    signal.signal(signal.SIGINT, noted)
    try:
        yield hit
    except Exception:
        if hit:  # pandas' C reader made the interrupt a ParserError
            raise KeyboardInterrupt from None
        raise
    finally:
        signal.signal(signal.SIGINT, previous)
    if hit:
        raise KeyboardInterrupt


def read_csv_table(path: str | Path, *, sep: str | None = None,
                   decimal: str = ".", source: str | None = None) -> CsvTable:
    """Scan a delimited text file with one header row.

    The file is scanned in chunks (line numbers of the data rows, cells per row) with numpy;
    the columns a reader uses are then parsed by pandas' C reader, so a file of 10⁷ rows needs
    about 16 bytes per row and used column, not Python strings for every cell.

    Parameters
    ----------
    path : str or Path
        The file (``#`` comment lines allowed, see docs/measured-data.md).
    sep : str, optional
        Column separator, or ``tab``/``space``; detected from the header (comma, semicolon,
        tab, else whitespace) when omitted.
    decimal : str, default "."
        Decimal mark (``","`` for a European locale; the separator must then not be a
        comma).
    source : str, optional
        The file's name in messages; the path's last part by default (the explorer reads an
        upload from a file of its own name and names it as the page sent it).

    Returns
    -------
    CsvTable
        The scanned table.

    Raises
    ------
    MeasuredDataError
        For a binary file, a missing header or a row with the wrong number of cells.
    ValueError
        For an unknown ``sep`` or ``decimal``.
    """
    p = Path(path)
    source = p.name if source is None else source
    check_text_file(p)
    if decimal not in (".", ","):
        raise ValueError(f"decimal = {decimal!r}: expected '.' or ','")
    if sep is not None:
        sep = {"\\t": "\t", "tab": "\t", "space": None, "whitespace": None}.get(sep, sep)
        if sep is not None and len(sep.encode("utf-8")) != 1:
            raise ValueError(f"sep = {sep!r}: expected one character, tab or space")
    header: list[str] | None = None
    header_line = 0
    lines: list[np.ndarray] = []
    skip: list[np.ndarray] = []
    line_no = 1
    with open(p, "rb") as f:
        # the header: the first line that is neither blank nor a comment
        while header is None:
            raw = f.readline()
            if not raw:
                break
            text = raw.decode("utf-8", errors="replace").lstrip("\ufeff")
            line = text.strip()
            skip.append(np.array([line_no - 1]))
            excel = _EXCEL_SEP_RE.match(text)
            if excel:  # Excel's first line naming the separator: honoured, not a header
                named = excel.group("sep")
                if sep is not None and sep != named:
                    raise MeasuredDataError(source, line_no, f"the file names its separator "
                                            f"(Excel's {line!r}) and the separator option "
                                            f"gives {sep!r}; drop the option")
                sep = named
            elif line and not line.startswith("#"):
                if sep is None:
                    sep = _detect_separator(line)
                if sep == decimal:
                    raise MeasuredDataError(source, line_no, f"separator and decimal mark "
                                            f"are both {decimal!r}")
                header = _split(line, sep)
                header_line = line_no
            line_no += 1
        if header is None:
            raise MeasuredDataError(source, None, "no header row (the file is empty)")
        tail = b""
        while True:
            chunk = f.read(_CHUNK)
            data = tail + chunk
            if not chunk:
                if data and not data.endswith(b"\n"):
                    data += b"\n"
                tail = b""
            else:
                cut = data.rfind(b"\n") + 1
                data, tail = data[:cut], data[cut:]
            if data:
                numbers, is_data, counts = _scan_lines(np.frombuffer(data, dtype=np.uint8),
                                                       line_no, sep)
                wrong = np.flatnonzero(is_data & (counts != len(header)))
                if wrong.size:
                    k = int(wrong[0])
                    raise MeasuredDataError(source, int(numbers[k]), f"{int(counts[k])} cells, "
                                            f"but the header (line {header_line}) has "
                                            f"{len(header)} columns")
                lines.append(numbers[is_data])
                skip.append(numbers[~is_data] - 1)
                line_no += numbers.size
            if not chunk:
                break
    parsed = [split_unit(h) for h in header]
    names = tuple(n for n, _ in parsed)
    seen: set[str] = set()
    for n in names:
        if not n:
            raise MeasuredDataError(source, header_line, "a column has no name")
        if n.lower() in seen:
            raise MeasuredDataError(source, header_line, f"column {n!r} appears twice")
        seen.add(n.lower())
    return CsvTable(source=source, names=names, units=tuple(u for _, u in parsed),
                    lines=np.concatenate(lines) if lines else np.zeros(0, dtype=np.int64),
                    header_line=header_line, path=p, sep=sep,
                    skip=np.concatenate(skip).astype(np.int64), decimal=decimal)


def _need_rows(table: CsvTable, minimum: int, what: str) -> None:
    if len(table) == 0:
        raise MeasuredDataError(table.source, None, f"empty: a header (line "
                                f"{table.header_line}) and no data rows; a {what} needs at "
                                f"least {minimum}")
    if len(table) < minimum:
        raise MeasuredDataError(table.source, None, f"{len(table)} data rows; a {what} needs at "
                                f"least {minimum}")


def check_increasing(table: CsvTable, time: np.ndarray, column: str) -> None:
    """Refuse a time column that does not strictly increase, naming the line.

    Parameters
    ----------
    table : CsvTable
        The scanned file.
    time : numpy.ndarray
        The column's values [s].
    column : str
        The column's name, for the message.

    Raises
    ------
    MeasuredDataError
        At the first row whose time does not exceed the one before.
    """
    bad = np.flatnonzero(np.diff(time) <= 0.0)
    if bad.size:
        k = int(bad[0]) + 1
        i = table.find(column) or 0
        raise MeasuredDataError(
            table.source, int(table.lines[k]),
            f"column {column!r} does not increase ({table.cell(i, k - 1)} on line "
            f"{int(table.lines[k - 1])}, then {table.cell(i, k)})")


# ---------------------------------------------------------------- static friction tests


@dataclass(frozen=True)
class StaticTest:
    """Constant-speed friction tests, one row per test, in SI.

    Parameters
    ----------
    speed : numpy.ndarray
        Signed sliding speed of each test [m/s].
    force : numpy.ndarray
        Friction force, signed or as magnitudes [N].
    lines : numpy.ndarray of int
        The file line of every row.
    source : str
        The file's name.
    force_from : str
        ``"force"``, or ``"current × K_t / H"`` when converted from motor current.
    """

    speed: np.ndarray  # [m/s], signed
    force: np.ndarray  # [N], friction force (signed or magnitudes)
    lines: np.ndarray  # file line of every row
    source: str
    force_from: str  # "force" or "current × K_t / H"


def read_static_test(
    path: str | Path,
    *,
    speed_column: str = "speed",
    force_column: str = "force",
    current_column: str = "current",
    speed_unit: str | None = None,
    force_unit: str | None = None,
    current_unit: str | None = None,
    torque_constant: float | None = None,
    lead: float | None = None,
    sep: str | None = None,
    decimal: str = ".",
) -> StaticTest:
    """Read constant-speed friction tests: speed and friction force per row.

    Default columns ``speed`` [mm/s] and ``force`` [N].  Without a force column, a ``current``
    column [A] is converted as F = K_t·i/H with H = ``lead``/2π (Wang2021 Eq. (8) and Table 1's
    force convention); ``torque_constant`` and ``lead`` are then required.

    Parameters
    ----------
    path : str or Path
        The CSV file.
    speed_column, force_column, current_column : str
        Column names.
    speed_unit, force_unit, current_unit : str, optional
        Units overriding the header's (refused when they contradict it).
    torque_constant : float, optional
        Motor torque constant K_t, for a current column [N m/A].
    lead : float, optional
        Screw lead p_h, for a current column [m].
    sep : str, optional
        Column separator; detected from the header when omitted.
    decimal : str, default "."
        Decimal mark.

    Returns
    -------
    StaticTest
        The tests in SI.

    Raises
    ------
    MeasuredDataError
        For a missing column or constant, or a bad cell.

    References
    ----------
    .. [1] Wang2021 Eq. (8), Table 1.
    """
    table = read_csv_table(path, sep=sep, decimal=decimal)
    _need_rows(table, 1, "static friction test")
    if not table.has(speed_column) and table.has("time"):
        # a record over time given where one row per constant-speed test is expected
        raise MeasuredDataError(table.source, table.header_line,
                                f"no column {speed_column!r}, and a 'time' column: this looks "
                                "like a time trace; a static friction test has one row per "
                                "constant-speed test, columns speed [mm/s] and force [N] (or "
                                "current [A]); for a trace of the table over time use "
                                "`feeddrive analyze FILE` (creep) or `feeddrive identify "
                                f"dynamic` (pre-sliding){table.header_hint()}")
    speed, _, _ = table.quantity([speed_column], "speed", unit=speed_unit, default_unit="mm/s")
    if table.has(force_column) or not table.has(current_column):
        if not table.has(force_column):
            raise table._missing([force_column, current_column])
        force, _, _ = table.quantity([force_column], "force", unit=force_unit, default_unit="N")
        origin = "force"
    else:
        if torque_constant is None or lead is None:
            raise MeasuredDataError(table.source, table.header_line,
                                    f"column {current_column!r} needs the motor torque constant "
                                    "and the screw lead (from a parameter set or options) to "
                                    "become a force")
        for name, value, unit in (("torque_constant", torque_constant, "N m/A"),
                                  ("lead", lead, "m")):
            if not (math.isfinite(value) and value > 0):
                raise ParameterError(name, value, f"expected a finite value > 0 [{unit}]")
        current, _, _ = table.quantity([current_column], "current", unit=current_unit,
                                       default_unit="A")
        force = current * torque_constant / (lead / (2.0 * math.pi))
        origin = "current × K_t / H"
    return StaticTest(speed=speed, force=force, lines=table.lines, source=table.source,
                      force_from=origin)


# ---------------------------------------------------------------- pre-sliding tests


@dataclass(frozen=True)
class PreslidingTest:
    """A pre-sliding test (below breakaway): applied force and displacement, in SI.

    Parameters
    ----------
    time : numpy.ndarray
        Sample times [s].
    force : numpy.ndarray
        Applied force [N].
    position : numpy.ndarray
        Displacement [m].
    lines : numpy.ndarray of int
        The file line of every row.
    source : str
        The file's name.
    """

    time: np.ndarray  # [s]
    force: np.ndarray  # [N]
    position: np.ndarray  # [m]
    lines: np.ndarray
    source: str


def read_presliding_test(
    path: str | Path,
    *,
    time_column: str = "time",
    force_column: str = "force",
    position_column: str = "position",
    time_unit: str | None = None,
    force_unit: str | None = None,
    position_unit: str | None = None,
    sep: str | None = None,
    decimal: str = ".",
) -> PreslidingTest:
    """Read a pre-sliding test: columns ``time`` [s], ``force`` [N], ``position`` [µm] by default.

    Parameters
    ----------
    path : str or Path
        The CSV file (at least 20 rows).
    time_column, force_column, position_column : str
        Column names.
    time_unit, force_unit, position_unit : str, optional
        Units overriding the header's.
    sep : str, optional
        Column separator; detected from the header when omitted.
    decimal : str, default "."
        Decimal mark (``","`` for a European locale).

    Returns
    -------
    PreslidingTest
        The test in SI.

    Raises
    ------
    MeasuredDataError
        For missing columns, too few rows, bad cells or non-increasing time.
    """
    table = read_csv_table(path, sep=sep, decimal=decimal)
    _need_rows(table, 20, "pre-sliding test")
    time, tname, _ = table.quantity([time_column], "time", unit=time_unit, default_unit="s")
    check_increasing(table, time, tname)
    force, _, _ = table.quantity([force_column], "force", unit=force_unit, default_unit="N")
    position, _, _ = table.quantity([position_column], "length", unit=position_unit,
                                    default_unit="um")
    return PreslidingTest(time=time, force=force, position=position, lines=table.lines,
                          source=table.source)


# ---------------------------------------------------------------- position traces


@dataclass(frozen=True)
class PositionTrace:
    """A table position trace (interferometer export or the simulator's CSV), in SI.

    Parameters
    ----------
    time : numpy.ndarray
        Sample times [s].
    position : numpy.ndarray
        Table position [m].
    lines : numpy.ndarray of int
        The file line of every row.
    source : str
        The file's name.
    position_column : str
        The column the position was read from.
    command_speed : numpy.ndarray, optional
        Commanded speed, when the file has a command column [m/s].
    speed : numpy.ndarray, optional
        Measured speed, when a speed column was asked for [m/s].
    command_column : str, optional
        The column the command speed was read from.
    """

    time: np.ndarray  # [s]
    position: np.ndarray  # [m]
    lines: np.ndarray
    source: str
    position_column: str
    command_speed: np.ndarray | None = None  # [m/s], when the file has a command column
    speed: np.ndarray | None = None  # [m/s], when a speed column was asked for
    command_column: str | None = None


def read_position_trace(
    path: str | Path,
    *,
    time_column: str = "time",
    position_column: str | None = None,
    command_column: str | None = None,
    speed_column: str | None = None,
    time_unit: str | None = None,
    position_unit: str | None = None,
    speed_unit: str | None = None,
    sep: str | None = None,
    decimal: str = ".",
    source: str | None = None,
) -> PositionTrace:
    """Read time and table position; default columns ``time`` [s] and ``position`` [mm].

    Without ``position_column``, a ``position`` column is used, else ``table_position`` (the
    simulator's export).  The command speed [mm/s] is read from ``command_column``, or without
    it from a ``command_speed`` or ``table_speed_reference`` column when present; it marks the
    segments of a step-down run.

    Parameters
    ----------
    path : str or Path
        The CSV file (at least 16 rows).
    time_column : str, default "time"
        The time column.
    position_column : str, optional
        The position column.
    command_column : str, optional
        The command-speed column.
    speed_column : str, optional
        A speed column [mm/s] to use instead of differentiating the position.
    time_unit, position_unit, speed_unit : str, optional
        Units overriding the header's.
    sep : str, optional
        Column separator; detected from the header when omitted.
    decimal : str, default "."
        Decimal mark (``","`` for a European locale).
    source : str, optional
        The file's name in messages (:func:`read_csv_table`).

    Returns
    -------
    PositionTrace
        The trace in SI.

    Raises
    ------
    MeasuredDataError
        For missing columns, too few rows, bad cells or non-increasing time.

    Examples
    --------
    A file with a comment line, time in seconds and position in millimetres:

    >>> import pathlib, tempfile
    >>> from feeddrive.io.measured import read_position_trace
    >>> rows = "\\n".join(f"{0.01 * k:.2f},{0.015 * k:.3f}" for k in range(100))
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = pathlib.Path(folder) / "trace.csv"
    ...     _ = path.write_text(f"# rig 3, axis X\\ntime [s],position [mm]\\n{rows}\\n")
    ...     trace = read_position_trace(path)
    >>> print(f"{trace.time.size} samples, {1e3 * trace.position[-1]:.3f} mm")
    100 samples, 1.485 mm
    """
    table = read_csv_table(path, sep=sep, decimal=decimal, source=source)
    _need_rows(table, 16, "position trace")
    time, tname, _ = table.quantity([time_column], "time", unit=time_unit, default_unit="s")
    check_increasing(table, time, tname)
    names = [position_column] if position_column else ["position", "table_position"]
    position, pname, _ = table.quantity(names, "length", unit=position_unit, default_unit="mm")
    command, cname = None, None
    candidates = [command_column] if command_column else list(COMMAND_COLUMNS)
    if any(table.has(c) for c in candidates) or command_column:
        command, cname, _ = table.quantity(candidates, "speed", unit=None,
                                           default_unit="mm/s")
    speed = None
    if speed_column is not None:
        speed, _, _ = table.quantity([speed_column], "speed", unit=speed_unit,
                                     default_unit="mm/s")
    return PositionTrace(time=time, position=position, lines=table.lines, source=table.source,
                         position_column=pname, command_speed=command, speed=speed,
                         command_column=cname)
