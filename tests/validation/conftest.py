"""Shared fixtures of the validation tests."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest


@pytest.fixture(scope="session")
def full_reproduction(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    """`feeddrive reproduce --out DIR --workers 2` run once for the whole session (the
    suite's costliest job), and its results as :func:`feeddrive.reproduce.run` returns them:
    a second run into the same folder finds every study stored and only redraws the figures
    and the report (issue 24 item 15: test_report_new_user ran a reproduction of its own)."""
    from typer.testing import CliRunner

    from feeddrive.cli import app
    from feeddrive.parameters import preset
    from feeddrive.reproduce import run

    out = tmp_path_factory.mktemp("reproduce")
    res = CliRunner().invoke(app, ["reproduce", "--out", str(out), "--workers", "2"])
    assert res.exit_code == 0, res.output
    results = run(preset("wang2021"), out, workers=2)
    assert results["studies_reused"] == results["studies_total"]  # nothing computed twice
    return out, results
