"""What the command line says about the engine's build (issue 42 item 2: "said once, in one
line"; an outside check, 2026-12-06): a compiler that fails, ``FEEDDRIVE_ENGINE=c`` without
one, ``$CC`` naming a program that is not there, a numba that is installed but does not import
while a compiler is there — each one line, no traceback, naming what is wrong; a pool's
workers do not each say again what their parent said; a run off a terminal writes nothing to
stderr (rich's bar wrote a blank line when it stopped)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from feeddrive import _workers
from feeddrive.backends import c_cache
from feeddrive.solvers import builds

HAVE_CC = any(shutil.which(c) for c in ("cc", "gcc", "clang"))
needs_cc = pytest.mark.skipif(not HAVE_CC, reason="no C compiler (cc, gcc, clang) on PATH")
RUN = ["simulate", "--table-speed", "0.5", "--duration", "0.02"]


def _feeddrive(args: list[str], tmp_path: Path, **env: str) -> subprocess.CompletedProcess[str]:
    """The command in a fresh process with an empty C cache of its own."""
    full = dict(os.environ, **{c_cache.CACHE_ENV: str(tmp_path / "c")}, **env)
    full.pop(builds.SAID_ENV, None)
    return subprocess.run([sys.executable, "-m", "feeddrive", *args], env=full,
                          capture_output=True, text=True, timeout=600, check=False)


def _one_line(proc: subprocess.CompletedProcess[str]) -> str:
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    return lines[0]


@pytest.mark.skipif(sys.platform == "win32", reason="a shell script as the compiler")
def test_a_compiler_that_fails_is_one_line_naming_it(tmp_path: Path) -> None:
    fake = tmp_path / "badcc"
    fake.write_text("#!/bin/sh\necho 'badcc: fatal error: no headers here' >&2\nexit 1\n",
                    encoding="utf-8")
    fake.chmod(0o755)
    proc = _feeddrive(RUN, tmp_path, CC=f"{fake} -m32", FEEDDRIVE_ENGINE="c")
    line = _one_line(proc)
    assert proc.returncode == 1
    assert line.startswith("error: the C compiler failed (badcc -m32 ")  # CC's own options too
    assert "no headers here" in line and c_cache.COMPILE_FAILED_ADVICE in line


def test_forcing_c_without_a_compiler_is_one_line(tmp_path: Path) -> None:
    empty = tmp_path / "bin"
    empty.mkdir()
    proc = _feeddrive(RUN, tmp_path, PATH=str(empty), FEEDDRIVE_ENGINE="c")
    line = _one_line(proc)
    assert proc.returncode == 1 and line.startswith("error: FEEDDRIVE_ENGINE = 'c': ")


def test_a_cc_that_is_not_there_is_named(monkeypatch: pytest.MonkeyPatch,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv("CC", "/nonexistent/cc")
    monkeypatch.delenv(builds.SAID_ENV, raising=False)
    monkeypatch.setattr(c_cache, "_SAID", [])
    assert c_cache.available_compiler() is None
    err = capsys.readouterr().err
    # in find_compiler's words (c_cache.cc_problem), as every message about $CC says it
    said = "CC = '/nonexistent/cc': '/nonexistent/cc' is not an executable file"
    assert err.count("\n") == 1 and said in err
    assert "no C compiler found" not in err
    assert said in builds.no_engine_text()


@needs_cc
def test_a_numba_that_does_not_import_beside_a_compiler_says_so(tmp_path: Path) -> None:
    """FEEDDRIVE_ENGINE=numba with a numba found but broken, a compiler present: the line said
    there was no compiler."""
    stub = tmp_path / "stub" / "numba"
    stub.mkdir(parents=True)
    (stub / "__init__.py").write_text("raise ImportError('numba is broken here')\n",
                                      encoding="utf-8")
    proc = _feeddrive(RUN, tmp_path, PYTHONPATH=str(tmp_path / "stub"),
                      FEEDDRIVE_ENGINE="numba")
    line = _one_line(proc)
    assert proc.returncode == 1 and "numba does not import (numba is broken here)" in line
    assert "unset FEEDDRIVE_ENGINE to use the C build" in line
    assert "no C compiler" not in line


def test_a_pools_workers_are_told_the_parent_said_it(monkeypatch: pytest.MonkeyPatch,
                                                     tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str]
                                                     ) -> None:
    """No compiler, numba found: the parent of a pool says the fallback once, its workers
    (started while ``single_threaded_children`` lasts) see SAID_ENV and say nothing."""
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))  # no cc, gcc, clang
    monkeypatch.delenv(builds.SAID_ENV, raising=False)
    monkeypatch.delenv("FEEDDRIVE_ENGINE", raising=False)
    monkeypatch.setattr(c_cache, "_SAID", [])
    monkeypatch.setattr(builds, "HAVE_NUMBA", True)
    engine = builds.registry.table(builds.registry.ENGINES)["c"]
    monkeypatch.setattr(engine, "_compiler", {})
    with _workers.single_threaded_children():
        assert os.environ[builds.SAID_ENV] == "1"
        said = capsys.readouterr().err
        monkeypatch.setattr(c_cache, "_SAID", [])  # a worker: a process of its own
        assert c_cache.available_compiler() is None
        assert capsys.readouterr().err == ""
    assert said == c_cache.NO_COMPILER + "\n"
    assert builds.SAID_ENV not in os.environ


@needs_cc
def test_a_run_off_a_terminal_writes_nothing_to_stderr(tmp_path: Path) -> None:
    proc = _feeddrive([*RUN[:-1], "3"], tmp_path)  # 3 s: chunked, progress reported
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
