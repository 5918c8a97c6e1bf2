"""Issue 41 items 14 and 6 on the session's one `feeddrive reproduce` run (conftest.py)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
from reproduce_session import RUNS_MARKER, session_folder


@pytest.mark.slow
def test_reproduce_runs_once_per_test_session_whatever_n(
        full_reproduction: tuple[Path, dict[str, Any]],
        tmp_path_factory: pytest.TempPathFactory) -> None:
    """Item 14: with ``pytest -n 2`` both xdist workers built their own reproduction (883 CPU s
    for the README's test command); the file lock lets the first build it and the others wait
    and reuse it.  The marker gets one line per `reproduce` run made."""
    runs = (session_folder(tmp_path_factory) / RUNS_MARKER).read_text("utf-8").splitlines()
    assert len(runs) == 1, runs
    out, results = full_reproduction
    assert results["studies_reused"] == results["studies_total"] > 0
    assert (out / "report.html").is_file()


@pytest.mark.slow
def test_reproduce_piped_prints_a_progress_line_at_least_every_10_s(
        reproduce_output: str) -> None:
    """Item 6: `reproduce` printed nothing for minutes when its output was not a terminal."""
    lines = reproduce_output.splitlines()
    stamps = [float(m.group(1)) for line in lines
              if (m := re.fullmatch(r"reproduce: .* \((\d+) s\)", line))]
    total = float(re.search(r"\((\d+) s\)$", lines[-1]).group(1))  # "wrote …, (N s)"
    assert lines[-1].startswith("wrote ") and len(stamps) >= 3
    gaps = [b - a for a, b in zip([0.0, *stamps], [*stamps, total], strict=True)]
    # the lines state whole seconds: a gap of 10 s reads at most 11
    assert max(gaps) <= 11, gaps
