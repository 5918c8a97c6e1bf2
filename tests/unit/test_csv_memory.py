"""Measured-data CSVs are parsed in bulk by pandas with bounded memory: issue 13, item 10.

Guard: 10 M rows peaked at 3.9 GB RSS in the hand parser (measured on the development
machine: 4.2 GB and 39 s for a 2-column 10 M-row trace; now 0.65 GB and 8–11 s).  Here 1 M
rows in a subprocess: the reader may add at most 160 bytes per row to the peak resident size
(the former parser added about 400).  Line-numbered errors are kept
(tests/unit/test_measured_io.py).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd

ROWS = 1_000_000

_MEASURE = """
import resource, sys
import numpy, pandas
from feeddrive.io.measured import read_position_trace
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
trace = read_position_trace(sys.argv[1])
after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(trace.time.size, trace.lines[-1], (after - before) * 1024)
"""


def test_million_row_trace_memory(tmp_path: Path) -> None:
    t = np.arange(ROWS) * 1e-4
    path = tmp_path / "trace.csv"
    with open(path, "w", encoding="utf-8") as f:
        f.write("# interferometer export\n\n")
        pd.DataFrame({"time [s]": t, "position [mm]": 1.5 * t}).to_csv(f, index=False)
    r = subprocess.run([sys.executable, "-c", _MEASURE, str(path)], capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    rows, last_line, grown = r.stdout.split()
    assert int(rows) == ROWS
    assert int(last_line) == ROWS + 3  # comment, blank line, header
    assert int(grown) < 160 * ROWS, f"{int(grown) / ROWS:.0f} bytes per row"
