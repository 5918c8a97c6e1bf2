"""Shared fixtures of the validation tests."""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Any

import pytest
from reproduce_session import RUNS_MARKER, locked, session_folder


@pytest.fixture(scope="session")
def full_reproduction(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    """`feeddrive reproduce --out DIR --workers 2`, run once for the whole test session
    whatever ``-n`` (the suite's costliest job; issue 41 item 14: with ``pytest -n 2`` each
    xdist worker made its own), and its results as :func:`feeddrive.reproduce.run` returns
    them.

    The first process to get here runs the CLI into the session's shared folder under a file
    lock, appending a line to :data:`RUNS_MARKER`, and keeps what it printed
    (``reproduce-output.txt``); every process then copies the stored studies into a folder of
    its own and runs :func:`~feeddrive.reproduce.run` there, which finds every study stored
    and only redraws the figures and the report (issue 24 item 15)."""
    from typer.testing import CliRunner

    from feeddrive.cli import app
    from feeddrive.parameters import preset
    from feeddrive.reproduce import run

    shared = session_folder(tmp_path_factory)
    made = shared / "reproduce-shared"
    with locked(shared / "reproduce.lock"):
        if not (made / "data").is_dir():
            res = CliRunner().invoke(app, ["reproduce", "--out", str(made), "--workers", "2"])
            assert res.exit_code == 0, res.output
            (shared / "reproduce-output.txt").write_text(res.stdout, encoding="utf-8")
            with open(shared / RUNS_MARKER, "a", encoding="utf-8") as log:
                log.write(f"reproduce run by pid {os.getpid()} "
                          f"({os.environ.get('PYTEST_XDIST_WORKER', 'no xdist')})\n")
    out = tmp_path_factory.mktemp("reproduce")
    shutil.copytree(made / "data", out / "data")
    results = run(preset("wang2021"), out, workers=2)
    assert results["studies_reused"] == results["studies_total"]  # nothing computed twice
    return out, results


@pytest.fixture(scope="session")
def reproduce_output(full_reproduction: tuple[Path, dict[str, Any]],
                     tmp_path_factory: pytest.TempPathFactory) -> str:
    """What the session's one `feeddrive reproduce` printed (its output is not a terminal)."""
    return (session_folder(tmp_path_factory) / "reproduce-output.txt").read_text("utf-8")


@pytest.fixture(scope="session")
def shared_fmus(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    """The FMUs of the session, each exported once for every test (and every pytest-xdist
    worker) that reads it (:class:`fmu_helpers.SharedExports`)."""
    from fmu_helpers import SharedExports

    return SharedExports(session_folder(tmp_path_factory) / "shared-fmus")
