"""Ctrl-C while a record is read stops the command (an outside check, 2026-12-07): pandas'
C reader turned the KeyboardInterrupt raised inside its read into a ParserError, which the
column reader took for a bad cell and read on — `fit` ran on, `validate` ended with exit
status 0 and its full output.  Deterministic here: the read raises SIGINT and then what
pandas raises (measured on pandas 3.1.1: ``ParserError: Calling read(nbytes) on source
failed``)."""

from __future__ import annotations

import signal
from pathlib import Path
from typing import Any

import pandas as pd
import pytest

from feeddrive.io import measured


@pytest.fixture()
def table(tmp_path: Path) -> measured.CsvTable:
    path = tmp_path / "t.csv"
    path.write_text("time,position\n" + "".join(f"{k * 1e-3},{k}\n" for k in range(20)),
                    encoding="utf-8")
    return measured.read_csv_table(path)


@pytest.fixture()
def python_handler() -> Any:
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


def test_an_interrupt_pandas_swallowed_is_raised(table: measured.CsvTable,
                                                  monkeypatch: pytest.MonkeyPatch,
                                                  python_handler: Any) -> None:
    def read(*args: object) -> None:
        try:
            signal.raise_signal(signal.SIGINT)
        except KeyboardInterrupt:
            pass  # what pandas' C reader does with it
        raise pd.errors.ParserError("Error tokenizing data. C error: Calling read(nbytes) "
                                    "on source failed. Try engine='python'.")

    monkeypatch.setattr(measured.CsvTable, "_read_csv", lambda self, *a: read())
    with pytest.raises(KeyboardInterrupt):
        table.numbers("position")
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # put back


def test_without_an_interrupt_the_column_reads_as_before(table: measured.CsvTable,
                                                          python_handler: Any) -> None:
    assert table.numbers("position").tolist() == [float(k) for k in range(20)]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
