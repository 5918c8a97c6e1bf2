"""The session's shared folder and a file lock: the test session's one `feeddrive reproduce`
run (conftest.py, issue 41 item 14)."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path

import pytest

#: the file, in the session's shared folder, that gets one line per `reproduce` run made
RUNS_MARKER = "reproduce-runs.log"


def session_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The folder every process of this test session shares: the base temporary folder, or
    its parent under pytest-xdist (whose workers each get ``…/pytest-N/popen-gwK``)."""
    base = tmp_path_factory.getbasetemp()
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base


@contextlib.contextmanager
def locked(path: Path) -> Iterator[None]:
    """An exclusive lock on ``path`` across processes (``fcntl.flock``; ``msvcrt`` on
    Windows), held for the ``with`` block."""
    with open(path, "a+b") as f:
        if os.name == "nt":  # pragma: no cover - the suite runs on Linux
            import msvcrt

            f.seek(0)
            while True:
                try:
                    msvcrt.locking(f.fileno(), msvcrt.LK_LOCK, 1)
                    break
                except OSError:
                    continue
            try:
                yield
            finally:
                f.seek(0)
                msvcrt.locking(f.fileno(), msvcrt.LK_UNLCK, 1)
        else:
            import fcntl

            fcntl.flock(f.fileno(), fcntl.LOCK_EX)
            try:
                yield
            finally:
                fcntl.flock(f.fileno(), fcntl.LOCK_UN)
