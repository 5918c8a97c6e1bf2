"""docs/model.md states the verdict corpus's agreement as the recorded benchmark has it
(benchmarks/results/bench_verdicts.json, written by benchmarks/bench_verdicts.py)."""

from __future__ import annotations

import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_stated_agreement_is_the_recorded_one() -> None:
    recorded = json.loads((ROOT / "benchmarks" / "results" / "bench_verdicts.json").read_text())
    summary = recorded["summary"][recorded["default_method"]]
    text = (ROOT / "docs" / "model.md").read_text(encoding="utf-8")
    stated = re.search(r"Verdict corpus \(`benchmarks/bench_verdicts.py`[^)]*\): (\d+) creep "
                       r"trials.*?\*\*(\d+) of (\d+) agree\*\*(.*?)\n\n", text, re.S)
    assert stated is not None, "docs/model.md no longer states the corpus as tested here"
    assert int(stated[1]) == len(recorded["rows"])
    assert (int(stated[2]), int(stated[3])) == (summary["agree"], summary["of"])
    # every disagreeing trial is named where the agreement is stated
    for case in summary["disagree"]:
        assert f"`{case}`" in stated[4], case
    assert len(summary["disagree"]) == summary["of"] - summary["agree"]
    assert recorded["summary"]["reference"]["older"] == []  # every reference of the current rule
