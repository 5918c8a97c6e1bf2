"""The report's CSV tables (``feeddrive.reproduce.studies.write_csv``): written with the
standard library's csv writer since 2026-12-06 (pandas' import cost the parent ≈ 0.2 CPU s);
the same bytes as ``pandas.DataFrame(rows).to_csv(index=False, float_format=CSV_FLOAT)``, the
writer before, on the kinds of cells the report's tables hold."""

from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np
import pandas as pd

from feeddrive.reproduce.studies import CSV_FLOAT, write_csv

ROWS = [
    {"position_mm": 200.0, "k_sa_N_per_um": 1e-6 * 220.9e6, "critical_mm_s": 1.56,
     "status": "found", "text": 'a "quoted", comma', "bands": [0.02, 3.02], "count": 3,
     "flag": True, "speed": np.float64(0.1 + 0.2)},
    {"position_mm": 300.0, "k_sa_N_per_um": 276.1250503123, "critical_mm_s": None,
     "status": "not found", "text": "plain", "bands": None, "count": 4, "flag": False,
     "speed": math.nan, "extra": 5},
]


def test_the_bytes_are_pandas_to_csv_s(tmp_path: Path) -> None:
    path = tmp_path / "t.csv"
    write_csv(ROWS, path)
    expected = io.StringIO()
    pd.DataFrame(ROWS).to_csv(expected, index=False, float_format=CSV_FLOAT)
    assert path.read_text(encoding="utf-8") == expected.getvalue()


def test_no_binary_noise_and_empty_cells_for_missing_values(tmp_path: Path) -> None:
    path = tmp_path / "t.csv"
    write_csv(ROWS, path)
    header, first, second = path.read_text(encoding="utf-8").splitlines()
    assert header.split(",")[-1] == "extra"  # a key of a later row joins the header
    assert ",220.9," in first and "0.30000000000000004" not in first
    assert second.endswith(",,5") and ",,not found," in second
