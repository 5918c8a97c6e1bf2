"""docs/model.md states the verdict corpus's agreement as the recorded benchmark has it
(benchmarks/results/bench_verdicts.json, written by benchmarks/bench_verdicts.py)."""

from __future__ import annotations

import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_stated_agreement_is_the_recorded_one() -> None:
    recorded = json.loads((ROOT / "benchmarks" / "results" / "bench_verdicts.json").read_text())
    default = recorded["default_method"]
    summary = recorded["summary"][default]
    text = (ROOT / "docs" / "model.md").read_text(encoding="utf-8")
    stated = re.search(r"Verdict corpus \(`benchmarks/bench_verdicts.py`[^)]*\): (\d+) creep "
                       r"trials.*?\*\*all (\d+) agree\*\*", text, re.S)
    assert stated is not None, "docs/model.md no longer states the corpus as tested here"
    trials, agree = int(stated[1]), int(stated[2])
    assert trials == len(recorded["rows"])
    assert agree == summary["agree"] == summary["of"] and not summary["disagree"]
