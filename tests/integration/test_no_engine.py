"""Without a C compiler and without numba (issue 42's acceptance): a simulating command stops
with one line saying how to get either build, not a traceback and not the drivers in plain
Python.  numba is hidden (whether installed or not) by a folder first on ``PYTHONPATH`` whose
``numba`` package raises ``ImportError``; the compilers by a ``PATH`` that holds none."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

FAILED = 1  # the work could not finish (README, "Exit status")


def test_without_a_compiler_and_without_numba_one_line_says_how_to_get_either(
        tmp_path: Path) -> None:
    hide = tmp_path / "hide"
    (hide / "numba").mkdir(parents=True)
    (hide / "numba" / "__init__.py").write_text('raise ImportError("hidden by the test")\n')
    empty = tmp_path / "bin"  # no cc, gcc, clang
    empty.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("CC", "FEEDDRIVE_ENGINE")}
    env.update(PATH=str(empty), PYTHONPATH=os.pathsep.join(
        [str(hide), *filter(None, [os.environ.get("PYTHONPATH")])]))
    proc = subprocess.run(
        [sys.executable, "-m", "feeddrive", "simulate", "--drive", "cdfs", "--table-speed",
         "2", "--duration", "0.1"],
        capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300, check=False)
    assert proc.returncode == FAILED, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert "Traceback" not in proc.stderr
    line = lines[0]
    # numba is found (the folder above) but does not import: said as it is, with its error
    assert line.startswith("error: no C compiler found and numba does not import (hidden by "
                           "the test); ")
    assert "apt-get install gcc" in line and "pip install 'feeddrive[numba]'" in line
