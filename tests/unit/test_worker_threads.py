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
    real = multiprocessing.get_context

    def context(method: str | None = None) -> Any:
        ctx = real(method)

        class Recorder:
            def Pool(self, processes: int, **_: Any) -> Any:  # noqa: N802 - as multiprocessing
                made.append((ctx.get_start_method(), _environment(VARIABLES), processes))
                raise _Started

        return Recorder()

    monkeypatch.setattr(runner.multiprocessing, "get_context", context)
    with pytest.raises(_Started):
        runner.run(fd.preset("wang2021"), tmp_path / "out", workers=2, study=False)
    assert made == [("spawn", ["1"] * len(VARIABLES), 2)]
