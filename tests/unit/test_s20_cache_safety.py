"""``feeddrive cache`` and the caches' disk helpers, against an outside check (2026-12-06):
prune touched files that are not feeddrive's, a file system without ``flock`` stopped the
first run, a cache folder that could be written but not read was written into and then not
reported, a ``.lock`` left by a failed compilation counted as a library, ``--older-than inf``
was refused with the wrong words, and ``NUMBA_CACHE_DIR`` was not documented."""

from __future__ import annotations

import errno
import json
import os
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from feeddrive import _disk, _jit, caches
from feeddrive.backends import c_cache, c_engine
from feeddrive.cli import app
from feeddrive.io.outputs import atomic_path

DAY = 86400.0
SUFFIX = c_cache.library_suffix()
UID = os.getuid() if hasattr(os, "getuid") else 0


def _aged(path: Path, days: float) -> Path:
    """Set the modification time of ``path`` and everything under it ``days`` back."""
    when = time.time() - days * DAY
    for p in [path, *(path.rglob("*") if path.is_dir() else [])]:
        os.utime(p, (when, when))
    return path


def _file(path: Path, text: str = "x") -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


@pytest.fixture
def folders(cache: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> dict[str, Path]:
    """The C cache (the shared ``cache`` fixture), numba's folder and the system's temporary
    folder, all the test's own."""
    numba = tmp_path / "numba"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(numba))
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    for name in ("_MADE", "_NOTED", "_NOT_WRITABLE"):  # what c_cache keeps per process
        if hasattr(c_cache, name):
            monkeypatch.setattr(c_cache, name, type(getattr(c_cache, name))())
    return {"c": cache, "numba": numba, "tmp": tmp}


def _fake_compile(files: dict[str, str], folder: Any, output: str, *args: Any,
                  **kwargs: Any) -> Path:
    """``compile_c`` without a compiler: the source's bytes as the library."""
    out = Path(folder) / output
    out.write_text(next(iter(files.values())), encoding="utf-8")
    return out


# -- 1. only feeddrive's names are listed and pruned ------------------------------------------

#: names feeddrive never writes in its cache folders; each must be left alone
FOREIGN_FILES = ("thesis.tex", "random.so", "random.dylib", "abc.sha256", "abc.lock",
                 "notes.json", f"{'0' * 64}.txt", f"{'A' * 64}{SUFFIX}", f"{'0' * 63}{SUFFIX}",
                 f"x{'0' * 64}.lock", "model-abc.c", f"model-{'0' * 24}.h",
                 f"driver-{'0' * 20}.json", f"driver-integrate-{'0' * 19}.json",
                 ".thesis.0123abcd.partial.tex", ".model-abc.0123abcd.partial.c",
                 f".model-{'0' * 24}.0123abcd.partial", ".probe", ".bashrc", "numba-notes")
FOREIGN_FOLDERS = (".ssh", ".git", ".config", ".0123456789abcdef", ".0123456789abcde-abcdefgh",
                   f".{'0' * 16}-abc", "numba-notes.d", "numba-0123456789abcdeg", "src")


def _foreign(folder: Path, days: float = 40) -> list[Path]:
    """Files and folders that are not feeddrive's, in ``folder``, ``days`` old."""
    made = [_file(folder / name) for name in FOREIGN_FILES]
    made += [_file(folder / name / "inside").parent for name in FOREIGN_FOLDERS]
    for p in made:
        _aged(p, days)
    return made


@pytest.mark.parametrize("name", FOREIGN_FILES + FOREIGN_FOLDERS)
def test_names_feeddrive_never_writes_are_not_its_own(name: str) -> None:
    assert caches._c_kind(name) is None
    assert not caches._numba_folder(name)


def test_the_names_the_c_build_writes_are_its_own(folders: dict[str, Path],
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    """Each name made by the code that writes it (not a copy of its pattern) is recognised as
    the kind it is."""
    c = folders["c"]
    seen: list[str] = []

    def failing(files: dict[str, str], folder: Any, *args: Any, **kwargs: Any) -> Path:
        # the compilation's temporary folder, and what is beside it while it runs (its lock)
        seen.extend([Path(folder).name, *os.listdir(Path(folder).parent)])
        raise c_cache.CompileError("the C compiler failed", "")

    monkeypatch.setattr(c_cache, "compile_c", failing)
    with pytest.raises(c_cache.CompileError):
        c_cache.cached_library("int failing;\n", cc=[sys.executable])
    key = c_cache.cache_key("int failing;\n", [sys.executable], c_cache.LIBRARY_FLAGS, ("-lm",))
    assert caches._c_kind(seen[0]) == "compiling"
    assert {name: caches._c_kind(name) for name in seen[1:]} == {seen[0]: "compiling",
                                                                 f"{key}.lock": "lock"}
    assert all(caches._c_kind(name) for name in os.listdir(c))  # what a failure leaves
    monkeypatch.setattr(c_cache, "compile_c", _fake_compile)
    lib = c_cache.cached_library("int fine;\n", cc=[sys.executable])
    key = lib.name.removesuffix(SUFFIX)
    assert {p.name: caches._c_kind(p.name) for p in c.iterdir() if key in p.name} == {
        lib.name: "library", f"{key}{c_cache.DIGEST_SUFFIX}": "digest", f"{key}.lock": "lock"}

    # the translated texts, as c_engine names and writes them (the translation itself skipped)
    monkeypatch.setattr(c_engine, "_translated",
                        lambda use: {"c": "", "n_stats": 0, "params": []})
    monkeypatch.setattr(c_engine, "model_source", lambda model: "int model;\n")
    for use in (*c_engine.USES, "functions"):
        c_engine.driver_unit.__wrapped__(use)
    module = SimpleNamespace(__name__="feeddrive_model_0123", N_HELD=0, N_CLOCK=0)
    model = SimpleNamespace(module=module, drive="cdfs", states=(), aux=(), P=np.zeros(3),
                            T=np.zeros(0))
    c_engine._model_text(model)  # type: ignore[arg-type]
    texts = sorted(p.name for p in c.iterdir() if p.suffix in (".c", ".json"))
    assert len(texts) == len(c_engine.USES) + 2
    assert all(caches._c_kind(name) == "text" for name in texts), texts
    assert all(caches._c_kind(p.name) for p in c.iterdir()), sorted(os.listdir(c))
    # a text is one entry with its digest, where it has one (c_cache.keep_text)
    part = next(p for p in caches.usage() if p.name == "C libraries and texts")
    assert part.entries == 1 + len(texts) and part.foreign == 0

    # the partial files of those writes cut short, and the probe of a writable test
    for name in [*texts, *(f"{name}{c_cache.DIGEST_SUFFIX}" for name in texts)]:
        with atomic_path(c / name) as tmp:
            assert caches._c_kind(tmp.name) == "partial", tmp.name
    unlink = os.unlink
    with monkeypatch.context() as m:
        m.setattr(os, "unlink", lambda path: None)  # a process killed after its probe
        assert _disk.writable(c)
    probes = [p for p in c.iterdir() if p.name.startswith(_disk.PROBE_PREFIX)]
    assert len(probes) == 1 and caches._c_kind(probes[0].name) == "partial"
    unlink(probes[0])
    # numba's folder of this version
    assert caches._numba_folder(Path(_jit.CACHE_DIR).name)


def test_prune_leaves_a_home_folder_alone(folders: dict[str, Path], tmp_path: Path,
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """Defect: with FEEDDRIVE_C_CACHE='~', --prune --dry-run listed ~/.ssh (any dot-folder
    older than an hour was an unfinished compilation) and, with --older-than 0, every other
    file (a "text"): a prune removed them."""
    home = tmp_path / "home"
    foreign = _foreign(home, days=2 / 24)
    ours = {"library": _aged(_file(home / f"{'a' * 64}{SUFFIX}"), 40),
            "digest": _aged(_file(home / f"{'a' * 64}.sha256"), 40),
            "text": _aged(_file(home / f"model-{'c' * 24}.c"), 40),
            "killed": _aged(_file(home / f".{'b' * 16}-abc_1234" / "model.c").parent, 2 / 24)}
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.setenv(c_cache.CACHE_ENV, "~")
    runner = CliRunner()
    listed = runner.invoke(app, ["cache", "--prune", "--dry-run", "--older-than", "0"])
    assert listed.exit_code == 0, listed.output
    assert not any(str(p) in listed.output for p in foreign), listed.output
    assert "would remove 3 entries" in listed.output
    part = next(p for p in caches.usage() if p.name == "C libraries and texts")
    assert (part.folder, part.entries, part.foreign) == (home, 2, len(foreign))
    assert f"({len(foreign)} other files not feeddrive's, left alone)" in listed.output
    data = json.loads(runner.invoke(app, ["cache", "--json"]).output)["parts"]
    assert [p["foreign"] for p in data] == [0, 0, len(foreign), 0]
    report = caches.prune(0.0)
    assert set(report.removed) == set(ours.values()) and report.entries == 3
    assert all(p.exists() for p in foreign)
    assert not any(p.exists() for p in ours.values())


def test_prune_leaves_foreign_files_in_numba_and_the_fallback_folders(
        folders: dict[str, Path]) -> None:
    """The same for numba's folder (``NUMBA_CACHE_DIR``) and both fallback folders: only
    ``numba-<hash>`` folders, and the C build's names, are entries."""
    old = _aged(_file(folders["numba"] / "numba-0123456789abcdef" / "k.nbc").parent, 40)
    py = folders["tmp"] / f"feeddrive-py-{UID}"
    c = folders["tmp"] / f"feeddrive-c-{UID}"
    py_old = _aged(_file(py / "numba-fedcba9876543210" / "k.nbc").parent, 40)
    c_old = _aged(_file(c / f"{'d' * 64}.sha256"), 40)
    foreign = [*_foreign(folders["numba"]), *_foreign(py), *_foreign(c)]
    py.chmod(0o700)
    c.chmod(0o700)
    report = caches.prune(0.0, dry_run=True)
    assert set(report.removed) == {old, py_old, c_old}
    shown = {p.name: p.foreign for p in caches.usage() if p.foreign}
    each = len(FOREIGN_FILES) + len(FOREIGN_FOLDERS)
    assert shown == {"numba, this version": each,
                     "numba, this version (fallback folder, used when the cache cannot be "
                     "written)": each,
                     "C libraries and texts (fallback folder, used when the cache cannot be "
                     "written)": each}
    report = caches.prune(0.0)
    assert set(report.removed) == {old, py_old, c_old}
    assert all(p.exists() for p in foreign)


def test_the_c_folder_inside_numbas_folder_is_not_foreign(tmp_path: Path,
                                                          monkeypatch: pytest.MonkeyPatch
                                                          ) -> None:
    """The default layout: ``~/.cache/feeddrive`` holds numba's folders and the C folder
    ``c``, which is a part of its own, not a stranger in numba's."""
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.delenv(c_cache.CACHE_ENV, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    _file(tmp_path / "xdg" / "feeddrive" / "c" / f"model-{'c' * 24}.c")
    _file(tmp_path / "xdg" / "feeddrive" / "numba-0123456789abcdef" / "k.nbc")
    assert [(p.entries, p.foreign) for p in caches.usage()] == [(0, 0), (1, 0), (1, 0), (0, 0)]


# -- 2. a file system without flock ------------------------------------------------------------


@pytest.mark.parametrize("code", [errno.ENOLCK, errno.EOPNOTSUPP, errno.ENOSYS])
def test_a_file_system_that_does_not_lock_runs_unlocked(code: int, folders: dict[str, Path],
                                                        monkeypatch: pytest.MonkeyPatch
                                                        ) -> None:
    """Defect: ``flock`` failing with ENOLCK (an NFS or FUSE mount) stopped the first run,
    ``error: output: No locks available``, where the callers are correct unlocked."""
    if _disk._fcntl is None:
        pytest.skip("no fcntl: nothing is locked here anyway")

    def flock(fd: Any, operation: int) -> None:
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(_disk._fcntl, "flock", flock)
    with _disk.file_lock(folders["c"].parent / "x.lock") as held:
        assert held is False
    with pytest.raises(KeyError) as err, _disk.file_lock(folders["c"].parent / "y.lock"):
        raise KeyError("the block's own")
    assert err.value.__context__ is None  # not raised "during handling of" the lock's error
    monkeypatch.setattr(c_cache, "compile_c", _fake_compile)
    lib = c_cache.cached_library("int x;\n", cc=[sys.executable])
    assert lib.read_text(encoding="utf-8") == "int x;\n" and c_cache.STATS["compiles"] == 1


def test_a_failing_unlock_is_not_an_error(tmp_path: Path, monkeypatch: pytest.MonkeyPatch
                                          ) -> None:
    if _disk._fcntl is None:
        pytest.skip("no fcntl")
    real = _disk._fcntl.flock

    def flock(fd: Any, operation: int) -> None:
        if operation == _disk._fcntl.LOCK_UN:
            raise OSError(errno.EIO, os.strerror(errno.EIO))
        real(fd, operation)

    monkeypatch.setattr(_disk._fcntl, "flock", flock)
    with _disk.file_lock(tmp_path / "x.lock") as held:
        assert held is True


# -- 3. a folder that can be written but not read ---------------------------------------------


@pytest.fixture
def unlistable(folders: dict[str, Path], monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """The C cache folder, made, as one of mode 0333 is to a user who is not root: files can
    be made in it, it cannot be listed (``os.scandir``, ``Path.iterdir``)."""
    folder = folders["c"]
    folder.mkdir()
    refused = PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(folder))
    scandir, iterdir = os.scandir, Path.iterdir

    def scan(path: Any = ".") -> Any:
        if Path(path) == folder:
            raise refused
        return scandir(path)

    def listing(self: Path) -> Iterator[Path]:
        if self == folder:
            raise refused
        return iterdir(self)

    with monkeypatch.context() as m:
        m.setattr(os, "scandir", scan)
        m.setattr(Path, "iterdir", listing)
        yield folder


def test_a_folder_that_cannot_be_read_is_not_written(unlistable: Path,
                                                     folders: dict[str, Path]) -> None:
    """Defect: ``writable`` only tried to make a file, so a folder of mode 0333 took the
    libraries, which no listing (nor prune) could see afterwards."""
    assert not _disk.writable(unlistable)
    assert c_cache.store_folder() == folders["tmp"] / f"feeddrive-c-{UID}"
    assert [n for n in os.listdir(unlistable) if n.startswith(_disk.PROBE_PREFIX)] == []


def test_prune_says_it_could_not_read_a_folder(unlistable: Path) -> None:
    """Defect: --prune on a folder it could not list removed nothing there and said nothing,
    exit status 0."""
    runner = CliRunner()
    done = runner.invoke(app, ["cache", "--prune"])
    assert done.exit_code == 1, done.output
    assert caches.prune(0.0).unread == ((unlistable, os.strerror(errno.EACCES)),)
    assert (f"error: could not read {unlistable}: {os.strerror(errno.EACCES)}; nothing there "
            "was pruned") in done.stderr
    assert "(cannot be read: Permission denied)" in done.stdout  # the listing still comes
    data = runner.invoke(app, ["cache", "--prune", "--json"])
    assert data.exit_code == 1
    assert json.loads(data.stdout)["pruned"]["unread"] == [
        {"path": str(unlistable), "reason": os.strerror(errno.EACCES)}]
    assert runner.invoke(app, ["cache"]).exit_code == 0  # listing alone is no failure


def test_a_folder_that_can_be_listed_but_not_searched_cannot_be_read(
        folders: dict[str, Path], monkeypatch: pytest.MonkeyPatch) -> None:
    """Mode 0644 on a folder: its names can be listed, nothing in it looked at (``lstat``
    refused); said as a folder that cannot be read, not a crash."""
    folder = folders["c"]
    inside = _file(folder / f"model-{'c' * 24}.c")
    lstat = Path.lstat

    def refused(self: Path) -> os.stat_result:
        if self.parent == folder:
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(self))
        return lstat(self)

    monkeypatch.setattr(Path, "lstat", refused)
    report = caches.prune(0.0)
    assert report.unread == ((folder, os.strerror(errno.EACCES)),) and report.removed == ()
    assert inside.exists()


# -- 4. a lock without its library; --older-than inf; NUMBA_CACHE_DIR documented -------------


def test_the_lock_of_a_failed_compilation_is_junk_not_a_library(
        folders: dict[str, Path], monkeypatch: pytest.MonkeyPatch) -> None:
    """Defect: the ``<key>.lock`` a failed or killed compilation leaves counted as an entry
    among the libraries and went only after --older-than days."""
    locks: list[Path] = []

    def killed(files: dict[str, str], folder: Any, *args: Any, **kwargs: Any) -> Path:
        locks.extend(Path(folder).parent.glob("*.lock"))  # held while it compiles
        raise c_cache.CompileError("the C compiler failed", "")

    monkeypatch.setattr(c_cache, "compile_c", killed)
    with pytest.raises(c_cache.CompileError):
        c_cache.cached_library("int failing;\n", cc=[sys.executable])
    (lock,) = locks
    lock.touch()  # left, as by a process killed while compiling (or an older version)
    assert sorted(folders["c"].iterdir()) == [lock]
    parts = {p.name: p.entries for p in caches.usage()}
    assert (parts["C libraries and texts"], parts["unfinished compilations"]) == (0, 1)
    assert caches.prune(30.0).removed == ()  # a compilation may be under way
    _aged(lock, 2 / 24)
    report = caches.prune(30.0)  # an hour old is enough, whatever --older-than says
    assert report.removed == (lock,) and report.entries == 1 and not lock.exists()


def test_an_infinite_age_is_refused_as_not_finite(folders: dict[str, Path]) -> None:
    """Defect: ``--older-than inf`` was refused as "expected a number of days ≥ 0"."""
    r = CliRunner().invoke(app, ["cache", "--prune", "--older-than", "inf"])
    assert r.exit_code == 2
    assert "--older-than = inf: expected a finite number of days ≥ 0" in r.output


def test_the_documentation_names_numba_cache_dir() -> None:
    """Defect: ``NUMBA_CACHE_DIR`` is where the package's numba cache goes (and what
    ``feeddrive cache`` lists) when set, and docs/c-backend.md never said so."""
    doc = (Path(__file__).resolve().parents[2] / "docs" / "c-backend.md").read_text(
        encoding="utf-8")
    section = doc.split("## The compiled-object cache", 1)[1].split("\n## ", 1)[0]
    where = " ".join(section.split("- **Where.**", 1)[1].split("\n- **", 1)[0].split())
    assert "`$NUMBA_CACHE_DIR/numba-<hash>`" in where
    clearing = " ".join(section.split("- **Clearing it.**", 1)[1].split("\n- **", 1)[0].split())
    for words in ("other files not feeddrive's, left alone", "`foreign` in `--json`",
                  "`unread` in `--json`", "a `<key>.lock` whose library is not there"):
        assert words in clearing, words
