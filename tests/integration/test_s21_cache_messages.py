"""What the caches say when they cannot be written (an outside check, 2026-12-06, run as root
with read-only bind mounts and a small tmpfs; docs/c-backend.md, "A read-only cache"):

1. the generated Python modules' fallback (``<tmp>/feeddrive-py-<uid>``) that could not be
   written either ended the run with ``error: No space left on device``, naming no folder; and
   without a usable temporary folder every command, ``feeddrive cache`` too, ended with
   ``error: [Errno 2] No usable temporary directory found in […]`` (exit status 2);
2. a cache found not writable before any write (a read-only mount, ``FEEDDRIVE_C_CACHE``
   naming a file) was left for the fallback folder without a word, while a full disk was said.

Simulated here without root: a file where the cache folder should be (its ``mkdir`` fails as
on any system), ``mkstemp`` refused with ``EROFS`` in the cache (what a read-only mount gives),
``ENOSPC`` raised at the fallback's write, ``tempfile.gettempdir`` failing as it does when no
candidate folder takes a file (its own message, ``No usable temporary directory found in``)."""

from __future__ import annotations

import errno
import json
import os
import sys
import tempfile
import uuid
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import typer
from typer.testing import CliRunner

from feeddrive import _jit
from feeddrive.backends import c_cache
from feeddrive.cli import app
from feeddrive.cli._common import user_errors

UID = os.getuid() if hasattr(os, "getuid") else 0
FULL = os.strerror(errno.ENOSPC)
READ_ONLY = os.strerror(errno.EROFS)
#: what ``tempfile.gettempdir`` raises when no candidate folder takes a file (CPython's
#: ``tempfile._get_default_tempdir``, its words)
NO_TMP = "No usable temporary directory found in ['/nowhere']"
PY = "the generated Python modules' cache"


@pytest.fixture
def tmp(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The system's temporary folder, the test's own; what c_cache and _jit keep per process
    fresh (restored after)."""
    folder = tmp_path / "tmp"
    folder.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(folder))
    for name in ("_MADE", "_NOTED", "_NOT_WRITABLE"):
        monkeypatch.setattr(c_cache, name, type(getattr(c_cache, name))())
    monkeypatch.setattr(_jit, "_LOADED", {})
    for name in ("_LEFT", "_LEFT_SAID"):  # raising=False: the check runs on the old code too
        monkeypatch.setattr(_jit, name, [], raising=False)
    for name in ("CACHE_DIR", "_CACHE_DIR"):
        monkeypatch.setattr(_jit, name, getattr(_jit, name))
    return folder


@pytest.fixture
def not_a_folder(tmp_path: Path) -> Path:
    """A file where a cache folder should be: its ``mkdir`` fails, whoever runs the test."""
    path = tmp_path / "a-file"
    path.write_text("not a folder\n", encoding="utf-8")
    return path


def _read_only(monkeypatch: pytest.MonkeyPatch, folder: Path) -> None:
    """Files cannot be made in ``folder``, as on a read-only mount (``EROFS``, root too)."""
    real = tempfile.mkstemp

    def mkstemp(*args: Any, **kwargs: Any) -> Any:
        if kwargs.get("dir") is not None and Path(kwargs["dir"]) == folder:
            raise OSError(errno.EROFS, READ_ONLY, str(folder))
        return real(*args, **kwargs)

    monkeypatch.setattr(tempfile, "mkstemp", mkstemp)


def _no_temporary_folder(monkeypatch: pytest.MonkeyPatch) -> None:
    def gettempdir() -> str:
        raise FileNotFoundError(errno.ENOENT, NO_TMP)

    monkeypatch.setattr(tempfile, "tempdir", None)
    monkeypatch.setattr(tempfile, "gettempdir", gettempdir)


def _stem() -> str:
    return f"s21_{uuid.uuid4().hex[:16]}"


def _cli_error(call: Callable[[], object], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    """What a command that runs ``call`` ends with: its exit status and its standard error."""

    @user_errors
    def command(table_speed: float) -> None:
        call()

    with pytest.raises(typer.Exit) as stopped:
        command(table_speed=2.0)
    return stopped.value.exit_code, capsys.readouterr().err


# -- 2. a C cache that cannot be written is said ------------------------------------------------


@pytest.mark.parametrize("how", ["not a folder", "read-only"])
def test_a_c_cache_found_not_writable_is_said_once_naming_why_and_the_fallback(
        tmp: Path, tmp_path: Path, not_a_folder: Path, how: str,
        monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    """Defect 2: written to ``<tmp>/feeddrive-c-<uid>`` with nothing on stderr."""
    writable = tmp_path / "c"
    monkeypatch.setenv(c_cache.CACHE_ENV, str(writable))
    c_cache.keep_text("model-first.c", "first\n")
    assert (writable / "model-first.c").is_file()
    assert capsys.readouterr().err == ""  # a cache that can be written: nothing said
    if how == "read-only":
        cache, why = tmp_path / "ro", READ_ONLY
        cache.mkdir()
        _read_only(monkeypatch, cache)
    else:
        cache, why = not_a_folder, "not a folder"
    monkeypatch.setenv(c_cache.CACHE_ENV, str(cache))
    c_cache.keep_text("model-second.c", "second\n")
    fallback = tmp / f"feeddrive-c-{UID}"
    assert (fallback / "model-second.c").read_text(encoding="utf-8") == "second\n"
    assert capsys.readouterr().err == (f"feeddrive: the C cache {cache} cannot be written "
                                       f"({why}), so {fallback} is used\n")
    c_cache.keep_text("model-third.c", "third\n")  # once per process
    assert c_cache.kept_text("model-second.c") == "second\n"  # read back: nothing said
    assert capsys.readouterr().err == ""


def test_a_c_cache_and_its_fallback_unwritable_are_one_error_with_both_reasons(
        tmp: Path, not_a_folder: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """Defect 1's C side: the cache found not writable before the write, the error said
    ``the C cache cannot be written, nor …`` without why; no notice precedes the error."""
    monkeypatch.setenv(c_cache.CACHE_ENV, str(not_a_folder))
    fallback = tmp / f"feeddrive-c-{UID}"

    def write(folder: Path) -> None:
        raise OSError(errno.ENOSPC, FULL)  # nothing fits anywhere

    status, err = _cli_error(lambda: c_cache.in_store(write), capsys)
    assert (status, err) == (1, f"error: {not_a_folder}: the C cache cannot be written (not a "
                                f"folder), nor its fallback folder {fallback} ({FULL})\n")


# -- 1. the generated modules' cache -------------------------------------------------------------


def test_the_generated_modules_fallback_is_said_once(
        tmp: Path, not_a_folder: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """Defect 2's other cache: ``_jit.import_generated`` moved to ``feeddrive-py-<uid>``
    without a word."""
    cache = not_a_folder / f"numba-{_jit.SOURCE_DIGEST}"
    monkeypatch.setattr(_jit, "_CACHE_DIR", str(cache))
    first, second = _stem(), _stem()
    try:
        assert _jit.import_generated("s21", first, "X = 1\n").X == 1
        fallback = tmp / f"feeddrive-py-{UID}" / f"numba-{_jit.SOURCE_DIGEST}"
        assert (fallback / "s21" / f"{first}.py").is_file()
        assert capsys.readouterr().err == (f"feeddrive: {PY} {cache} cannot be written (not a "
                                           f"folder), so {fallback} is used\n")
        assert _jit.import_generated("s21", second, "X = 2\n").X == 2
        assert capsys.readouterr().err == ""  # once per process
    finally:
        for stem in (first, second):
            sys.modules.pop(f"feeddrive_{stem}", None)


def test_the_generated_modules_double_failure_is_one_error_naming_the_folders(
        tmp: Path, not_a_folder: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """Defect 1: ``error: No space left on device`` (exit status 1), no folder named; and the
    write cut short left its ``.tmp`` file in the fallback folder."""
    cache = not_a_folder / f"numba-{_jit.SOURCE_DIGEST}"
    monkeypatch.setattr(_jit, "_CACHE_DIR", str(cache))
    fallback = tmp / f"feeddrive-py-{UID}" / f"numba-{_jit.SOURCE_DIGEST}"
    real = Path.write_text

    def full(path: Path, text: str, *args: Any, **kwargs: Any) -> int:
        """A write of a partial file (the atomic writer's) finds the disk full."""
        if ".partial" in path.name:
            raise OSError(errno.ENOSPC, FULL)
        return real(path, text, *args, **kwargs)

    monkeypatch.setattr(Path, "write_text", full)
    stem = _stem()
    status, err = _cli_error(lambda: _jit.import_generated("s21", stem, "X = 1\n"), capsys)
    assert (status, err) == (1, f"error: {cache}: {PY} cannot be written (not a folder), nor "
                                f"its fallback folder {fallback} ({FULL})\n")
    assert list((fallback / "s21").iterdir()) == []  # no partial file left
    assert f"feeddrive_{stem}" not in sys.modules


# -- 1. no usable temporary folder ---------------------------------------------------------------


def test_without_a_temporary_folder_the_listing_says_the_fallback_is_unavailable(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Defect 1: ``feeddrive cache`` ended with ``error: [Errno 2] No usable temporary
    directory found in […]``, exit status 2, listing nothing."""
    monkeypatch.setenv(c_cache.CACHE_ENV, str(tmp_path / "c"))
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))
    _no_temporary_folder(monkeypatch)
    runner = CliRunner()
    shown = runner.invoke(app, ["cache"])
    assert shown.exit_code == 0, shown.output
    lines = shown.stdout.splitlines()
    assert lines[2] == f"C libraries and texts: 0 entries, 0.0 MB in {tmp_path / 'c'}"
    assert lines[-1] == ("fallback folders (used when the cache cannot be written): "
                         f"unavailable, no temporary folder is usable ({NO_TMP})")
    data = json.loads(runner.invoke(app, ["cache", "--json"]).stdout)
    assert data["fallback_unavailable"] == f"no temporary folder is usable ({NO_TMP})"
    assert len(data["parts"]) == 4  # the cache's own parts, listed
    assert runner.invoke(app, ["cache", "--prune", "--dry-run"]).exit_code == 0


def test_without_a_temporary_folder_a_run_that_needs_a_fallback_names_its_cache(
        tmp_path: Path, not_a_folder: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """Defect 1: exit status 2 (refused input) and tempfile's words alone; now the cache, why
    it was left and that no temporary folder is usable, exit status 1.  A cache that can be
    written needs no temporary folder (its lookups do not fail)."""
    for name in ("_MADE", "_NOTED", "_NOT_WRITABLE"):
        monkeypatch.setattr(c_cache, name, type(getattr(c_cache, name))())
    monkeypatch.setattr(_jit, "_LOADED", {})
    for name in ("_LEFT", "_LEFT_SAID"):
        monkeypatch.setattr(_jit, name, [], raising=False)
    monkeypatch.setattr(_jit, "CACHE_DIR", _jit.CACHE_DIR)
    _no_temporary_folder(monkeypatch)
    writable = tmp_path / "c"
    monkeypatch.setenv(c_cache.CACHE_ENV, str(writable))
    c_cache.keep_text("model-here.c", "here\n")
    assert c_cache.kept_text("model-here.c") == "here\n"
    monkeypatch.setenv(c_cache.CACHE_ENV, str(not_a_folder))
    status, err = _cli_error(lambda: c_cache.in_store(lambda folder: None), capsys)
    assert (status, err) == (1, f"error: {not_a_folder}: the C cache cannot be written (not a "
                                "folder), and no temporary folder is usable for its fallback "
                                f"({NO_TMP})\n")
    cache = not_a_folder / f"numba-{_jit.SOURCE_DIGEST}"
    monkeypatch.setattr(_jit, "_CACHE_DIR", str(cache))
    status, err = _cli_error(lambda: _jit.import_generated("s21", _stem(), "X = 1\n"), capsys)
    assert (status, err) == (1, f"error: {cache}: {PY} cannot be written (not a folder), and "
                                f"no temporary folder is usable for its fallback ({NO_TMP})\n")


@pytest.mark.skipif(sys.platform == "win32", reason="a shell script as the compiler")
def test_the_compiler_keeps_its_temporary_files_in_the_compilation_folder(
        tmp_path: Path) -> None:
    """gcc writes its intermediate files to ``$TMPDIR``, else ``/tmp``, else ``./``: with those
    read-only (the outside check) a cache that could be written failed to compile ("Cannot
    create temporary file in ./: Read-only file system") and was blamed.  A fake compiler
    writes the ``$TMPDIR`` it was given as its output."""
    fake = tmp_path / "cc-tmpdir"
    fake.write_text('#!/bin/sh\nwhile [ "$1" != "-o" ]; do shift; done\n'
                    'printf %s "$TMPDIR" > "$2"\n', encoding="utf-8")
    fake.chmod(0o755)
    folder = tmp_path / "build"
    out = c_cache.compile_c({"x.c": "int x;\n"}, folder, "x.so", [str(fake)], ["-c"])
    assert out.read_text(encoding="utf-8") == str(folder)
