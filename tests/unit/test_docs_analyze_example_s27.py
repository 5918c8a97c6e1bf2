"""docs/measured-data.md's `feeddrive analyze stepdown.csv` example is the command's output.

The example's record is the synthetic step-down run of tests/unit/test_trace.py (Wang2021
Sect. 6's protocol: 0.01-mm/s steps, the last two creeping as a 2-Hz sawtooth), written as
the CSV a user would give (`time [s]`, `position [mm]`).  The block had drifted from the
code (it still said "stick-slip none" where the command prints "oscillation none", and
lacked the run-up and filter notes); it is now compared line for line.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from test_trace import CREEPS, STEPS, position_of, speed_profile
from typer.testing import CliRunner

from feeddrive.cli import app

DOC = Path(__file__).parents[2] / "docs" / "measured-data.md"
COMMAND = "$ feeddrive analyze stepdown.csv"


def documented_lines() -> list[str]:
    text = DOC.read_text(encoding="utf-8")
    block = re.search(r"```\n(\$ feeddrive analyze stepdown\.csv[^\n]*)\n(.*?)```", text,
                      re.S)
    assert block is not None, "the analyze example is gone from docs/measured-data.md"
    return block.group(2).rstrip("\n").splitlines()


def test_analyze_example_is_the_commands_output(tmp_path: Path, monkeypatch) -> None:
    t, v = speed_profile(STEPS, CREEPS)
    x = position_of(t, v)
    np.savetxt(tmp_path / "stepdown.csv", np.c_[t, x * 1e3], delimiter=",",
               header="time [s],position [mm]", comments="", fmt="%.9g")
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(app, ["analyze", "stepdown.csv"])
    assert result.exit_code == 0, result.output
    assert result.output.rstrip("\n").splitlines() == documented_lines()
