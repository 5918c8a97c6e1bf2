"""Worker processes get one thread per numerical library (issue 42): forked `reproduce`
workers inherited the parent's OpenBLAS threads, which busy-waited beside them (workers' CPU
60.7 against 52.5 s spawned single-threaded, benchmarks/README.md)."""

from __future__ import annotations

import multiprocessing
import os
from pathlib import Path
from typing import Any

import pytest

import feeddrive as fd
from feeddrive.reproduce import runner
from feeddrive.sweep import executors

VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")


def _environment(names: tuple[str, ...]) -> list[str | None]:
    return [os.environ.get(n) for n in names]


def test_processes_started_inside_are_single_threaded_and_the_parent_is_restored(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "7")
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    with executors.single_threaded_children():
        with multiprocessing.get_context("spawn").Pool(1) as pool:
            seen = pool.apply(_environment, (VARIABLES,))
    assert seen == ["1"] * len(VARIABLES)
    assert os.environ["OPENBLAS_NUM_THREADS"] == "7"
    assert "OMP_NUM_THREADS" not in os.environ


class _Started(Exception):
    pass


def test_reproduce_starts_its_pool_by_spawn_single_threaded(monkeypatch: pytest.MonkeyPatch,
                                                            tmp_path: Path) -> None:
    """The pool is made by a ``spawn`` context while the variables are set (a forked worker
    cannot drop the BLAS threads its parent started)."""
    made: list[tuple[str, list[str | None], int]] = []

    def recorder(processes: int, *, mp_context: Any, **_: Any) -> Any:
        made.append((mp_context.get_start_method(), _environment(VARIABLES), processes))
        raise _Started

    monkeypatch.setattr(runner.cf, "ProcessPoolExecutor", recorder)
    with pytest.raises(_Started):
        runner.run(fd.preset("wang2021"), tmp_path / "out", workers=2, study=False)
    assert made == [("spawn", ["1"] * len(VARIABLES), 2)]


def _die(*_: Any) -> None:
    """A study whose worker process ends at once (as a crash in compiled code would)."""
    os._exit(3)


def test_a_worker_that_dies_ends_the_run_with_a_clear_error(monkeypatch: pytest.MonkeyPatch,
                                                            tmp_path: Path) -> None:
    """multiprocessing.Pool replaced a dead worker and waited for its task for ever (seen
    2026-12-05: the benchmark's wrapper unknown to a spawned worker); the run now stops with
    WorkerLost, and the CLI says it in one line with exit status 1."""
    from typer.testing import CliRunner

    from feeddrive.cli import app

    monkeypatch.setattr(runner, "_timed", _die)  # pickled by name: the workers import it
    with pytest.raises(runner.WorkerLost, match="ended unexpectedly while computing"):
        runner.run(fd.preset("wang2021"), tmp_path / "out", workers=1, study=False)
    result = CliRunner().invoke(app, ["reproduce", "--out", str(tmp_path / "cli"),
                                      "--no-study", "--workers", "1"])
    assert result.exit_code == 1, result.output
    assert "error: a worker process ended unexpectedly" in result.stderr
    assert f"kept in {tmp_path / 'cli' / 'data'}" in result.stderr.replace("\n", "")
    assert "Traceback" not in result.output
