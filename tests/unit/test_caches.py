"""``feeddrive cache`` (:mod:`feeddrive.caches`): what the compile caches hold, and pruning
what has not been used — on a cache tree made here, with file times set by the test."""

from __future__ import annotations

import errno
import json
import os
import tempfile
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from feeddrive import caches
from feeddrive._jit import SOURCE_DIGEST
from feeddrive.backends import c_cache
from feeddrive.cli import app
from feeddrive.io.outputs import atomic_path
from feeddrive.parameters import ParameterError

DAY = 86400.0


def _k(digit: str) -> str:
    """A cache key, as the C build names a library (64 hexadecimal digits): ``digit`` 64 times."""
    return digit * 64


def _model(digit: str) -> str:
    """A model's kept text, named as the C build names it: ``model-<24 digits>.c``."""
    return f"model-{digit * 24}.c"


def _compiling(digit: str, tail: str) -> str:
    """A compilation's temporary folder, named as the C build names it:
    ``.<16 digits of the key>-<8 random characters>``."""
    return f".{digit * 16}-{tail:_<8}"


def _aged(path: Path, days: float) -> Path:
    """Set the modification time of ``path`` and everything under it ``days`` back."""
    when = time.time() - days * DAY
    for p in [path, *(path.rglob("*") if path.is_dir() else [])]:
        os.utime(p, (when, when))
    return path


def _file(path: Path, size: int) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"x" * size)
    return path


def _temporary_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The system's temporary folder, for this test: where the C build's fallback folder is."""
    folder = tmp_path / "tmp"
    folder.mkdir(exist_ok=True)
    monkeypatch.setattr(tempfile, "tempdir", str(folder))
    return folder


@pytest.fixture
def tree(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> dict[str, Path]:
    root = tmp_path / "cache"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(root))
    monkeypatch.setenv(c_cache.CACHE_ENV, str(root / "c"))
    _temporary_folder(tmp_path, monkeypatch)  # no fallback folder but the test's own
    made = {
        "current": _file(root / f"numba-{SOURCE_DIGEST}" / "k.nbi", 100).parent,
        "old_version": _file(root / "numba-0123456789abcdef" / "k.nbc", 1000).parent,
        "recent_version": _file(root / "numba-fedcba9876543210" / "k.nbc", 10).parent,
        "old_library": _file(root / "c" / f"{_k('a')}{c_cache.library_suffix()}", 300),
        "new_library": _file(root / "c" / f"{_k('b')}{c_cache.library_suffix()}", 30),
        "old_text": _file(root / "c" / _model("c"), 7),
        "killed": _file(root / "c" / _compiling("a", "x1") / "model.c", 5).parent,
        "compiling": _file(root / "c" / _compiling("b", "x2") / "model.c", 5).parent,
    }
    for name in ("current", "old_version", "old_library", "old_text"):
        _aged(made[name], 40)
    _aged(made["killed"], 0.5)  # twelve hours: an unfinished compilation, not a running one
    return made


def test_usage_counts_each_part(tree: dict[str, Path]) -> None:
    parts = {p.name: p for p in caches.usage()}
    assert [p.name for p in caches.usage()] == ["numba, this version", "numba, other versions",
                                                "C libraries and texts",
                                                "unfinished compilations"]
    assert (parts["numba, this version"].entries, parts["numba, this version"].size) == (1, 100)
    assert (parts["numba, other versions"].entries,
            parts["numba, other versions"].size) == (2, 1010)
    assert (parts["C libraries and texts"].entries,
            parts["C libraries and texts"].size) == (3, 337)
    assert (parts["unfinished compilations"].entries,
            parts["unfinished compilations"].size) == (2, 10)


def test_prune_removes_the_unused_and_keeps_this_versions_numba(tree: dict[str, Path]
                                                                 ) -> None:
    would = caches.prune(30.0, dry_run=True)
    expected = {tree["old_version"], tree["old_library"], tree["old_text"], tree["killed"]}
    assert set(would.removed) == expected and would.freed == 1000 + 300 + 7 + 5
    assert all(p.exists() for p in tree.values())  # a dry run removes nothing
    done = caches.prune(30.0)
    assert set(done.removed) == expected and done.freed == would.freed
    assert {name for name, p in tree.items() if p.exists()} == {
        "current", "recent_version", "new_library", "compiling"}
    # 0 days: everything it may prune, but never the running version's numba folder nor a
    # compilation younger than an hour
    caches.prune(0.0)
    assert {name for name, p in tree.items() if p.exists()} == {"current", "compiling"}


@pytest.mark.parametrize("bad", [-1.0, float("nan"), float("inf"), "30"])
def test_prune_refuses_an_age_that_is_not_a_number_of_days(bad: object) -> None:
    with pytest.raises(ParameterError,
                       match="older_than = .*expected a finite number of days ≥ 0"):
        caches.prune(bad)  # type: ignore[arg-type]


def test_a_library_loaded_from_the_cache_is_marked_used(tmp_path: Path,
                                                        monkeypatch: pytest.MonkeyPatch
                                                        ) -> None:
    if c_cache.available_compiler() is None:
        pytest.skip("no C compiler")
    monkeypatch.setenv(c_cache.CACHE_ENV, str(tmp_path / "c"))
    source = "double feeddrive_test_cache(double x) { return 2.0 * x; }\n"
    lib = c_cache.cached_library(source)
    _aged(lib, 3)
    assert time.time() - lib.stat().st_mtime > 2 * DAY
    assert c_cache.cached_library(source) == lib  # a hit: not compiled again ...
    assert time.time() - lib.stat().st_mtime < DAY  # ... and its time is now
    # within a day of its last mark it is not written again
    _aged(lib, 0.5)
    before = lib.stat().st_mtime
    c_cache.mark_used(lib)
    assert lib.stat().st_mtime == before


def test_the_command_shows_prunes_and_refuses(tree: dict[str, Path]) -> None:
    runner = CliRunner()
    shown = runner.invoke(app, ["cache", "--json"])
    assert shown.exit_code == 0, shown.output
    parts = json.loads(shown.output)["parts"]
    assert [p["entries"] for p in parts] == [1, 2, 3, 2]
    listed = runner.invoke(app, ["cache", "--prune", "--dry-run"])
    assert listed.exit_code == 0, listed.output
    assert str(tree["old_library"]) in listed.output
    assert "would remove 4 entries not used for 30 days" in listed.output
    assert tree["old_library"].exists()
    pruned = runner.invoke(app, ["cache", "--prune", "--json"])
    data = json.loads(pruned.output)["pruned"]
    assert data["dry_run"] is False and len(data["removed"]) == 4
    assert not tree["old_library"].exists() and tree["current"].exists()
    for args, message in ((["--prune", "--older-than", "-1"],
                           "--older-than = -1.0: expected a finite number of days ≥ 0"),
                          (["--dry-run"], "--dry-run: give it with --prune"),
                          (["--older-than", "5"], "--older-than: give it with --prune")):
        r = runner.invoke(app, ["cache", *args])
        assert r.exit_code == 2
        assert message in r.output and len(r.output.strip().splitlines()) == 1


def test_the_commands_default_age_is_the_modules() -> None:
    from feeddrive.cli import cache_cmd

    assert cache_cmd.DEFAULT_AGE == caches.DEFAULT_AGE
    assert caches.prune.__defaults__ == (caches.DEFAULT_AGE,)
    text = " ".join(CliRunner().invoke(app, ["cache", "--help"]).output.split())
    assert f"Age for --prune [days], {caches.DEFAULT_AGE:g} if not given" in text


# -- a library is one entry; the fallback folder; partial files; what cannot be removed --

SUFFIX = c_cache.library_suffix()
FALLBACK_C = "C libraries and texts (fallback folder, used when the cache cannot be written)"
FALLBACK_UNFINISHED = "unfinished compilations (fallback folder)"


def _library(folder: Path, key: str, size: int, days: float, *, lock_days: float | None = None,
             digest_days: float | None = None) -> dict[str, Path]:
    """A cached library as the C build leaves it: ``<key>.so``, its ``.sha256`` and empty
    ``.lock``, the library last used ``days`` ago, the others written when it was compiled."""
    files = {"library": _file(folder / f"{key}{SUFFIX}", size),
             "digest": _file(folder / f"{key}.sha256", 65),
             "lock": _file(folder / f"{key}.lock", 0)}
    _aged(files["library"], days)
    _aged(files["digest"], days if digest_days is None else digest_days)
    _aged(files["lock"], days if lock_days is None else lock_days)
    return files


@pytest.fixture
def c_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty C cache folder (and no numba cache, no fallback folder)."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))
    monkeypatch.setenv(c_cache.CACHE_ENV, str(tmp_path / "c"))
    _temporary_folder(tmp_path, monkeypatch)
    (tmp_path / "c").mkdir()
    return tmp_path / "c"


def _part(name: str) -> caches.CachePart:
    return next(p for p in caches.usage() if p.name == name)


def test_a_library_is_one_entry_with_its_digest_and_lock(c_folder: Path) -> None:
    """Defect: each empty .lock (and .sha256) counted as an entry of its own, so a cache of
    1076 libraries showed 2152 entries for them.  A .lock without its library is no library:
    an unfinished compilation (defect: it was counted among the libraries)."""
    for key in ("a", "b"):
        _library(c_folder, _k(key), 300, 1)
    _file(c_folder / _model("c"), 7)
    _file(c_folder / f"driver-integrate_dense-{'d' * 20}.json", 11)
    _aged(_file(c_folder / f"{_k('e')}.lock", 0), 40)  # the lock of a library pruned since
    part = _part("C libraries and texts")
    assert (part.entries, part.size) == (2 + 2, 2 * (300 + 65) + 7 + 11)
    assert _part("unfinished compilations").entries == 1
    text = CliRunner().invoke(app, ["cache"]).output
    assert "C libraries and texts: 4 entries" in text


def test_a_library_in_use_is_pruned_whole_or_not_at_all(c_folder: Path) -> None:
    """Defect: --prune removed the old .lock (and would remove the .sha256) of a library that
    is used every day (``mark_used`` touches only the library file), on their own; an orphan
    .sha256 goes by its own age, an orphan .lock as an unfinished compilation (older than an
    hour, whatever --older-than)."""
    used = _library(c_folder, _k("a"), 300, 0.5, lock_days=400, digest_days=400)
    unused = _library(c_folder, _k("b"), 200, 40)
    old_lock = _aged(_file(c_folder / f"{_k('c')}.lock", 0), 40)
    old_digest = _aged(_file(c_folder / f"{_k('d')}.sha256", 65), 40)
    day_old_lock = _aged(_file(c_folder / f"{_k('e')}.lock", 0), 1)
    new_lock = _aged(_file(c_folder / f"{_k('f')}.lock", 0), 10 / 1440)  # compiling now
    report = caches.prune(30.0)
    assert all(p.exists() for p in used.values())  # nothing of a library in use goes
    assert not any(p.exists() for p in unused.values())  # an unused one goes whole
    assert not old_lock.exists() and not old_digest.exists() and not day_old_lock.exists()
    assert new_lock.exists()
    assert set(report.removed) == {*unused.values(), old_lock, old_digest, day_old_lock}
    assert report.entries == 4 and report.freed == 200 + 65 + 65 and report.failed == ()
    assert _part("C libraries and texts").entries == 1  # aaaa
    assert _part("unfinished compilations").entries == 1  # the new lock


def test_partial_files_of_interrupted_writes_are_unfinished_compilations(c_folder: Path
                                                                         ) -> None:
    """Defect: the temporary files of atomic writes cut short (``.model-abc.1234abcd.partial.c``)
    were neither counted nor pruned."""
    with atomic_path(c_folder / _model("f")) as tmp:  # the names atomic_path writes under
        tmp.write_text("int x;\n", encoding="utf-8")
        assert (_part("unfinished compilations").entries, _part("C libraries and texts")
                .entries) == (1, 0)
    killed = _aged(_file(c_folder / f".{_model('a')[:-2]}.1234abcd.partial.c", 40), 2 / 24)
    writing = _file(c_folder / f".driver-integrate-{'a' * 20}.5678ef90.partial.json", 3)
    part = _part("unfinished compilations")
    assert (part.entries, part.size) == (2, 43)
    report = caches.prune(30.0)  # an hour old is enough, whatever --older-than says
    assert report.removed == (killed,) and report.freed == 40
    assert writing.exists() and (c_folder / _model("f")).exists()


def test_the_fallback_folder_is_listed_and_pruned(tmp_path: Path, c_folder: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    """Defect: the folder the C build uses when its cache cannot be written,
    ``<temporary folder>/feeddrive-c-<user id>``, was never listed nor pruned."""
    assert [p.name for p in caches.usage()][-1] == "unfinished compilations"  # none yet
    uid = os.getuid() if hasattr(os, "getuid") else 0
    fallback = tmp_path / "tmp" / f"feeddrive-c-{uid}"
    old = _library(fallback, _k("a"), 300, 40)
    new = _library(fallback, _k("b"), 30, 1)
    killed = _aged(_file(fallback / _compiling("a", "x1") / "model.c", 5).parent, 0.5)
    parts = {p.name: p for p in caches.usage()}
    assert list(parts)[-2:] == [FALLBACK_C, FALLBACK_UNFINISHED]
    assert (parts[FALLBACK_C].folder, parts[FALLBACK_C].entries,
            parts[FALLBACK_C].size) == (fallback, 2, 300 + 65 + 30 + 65)
    assert (parts[FALLBACK_UNFINISHED].entries, parts[FALLBACK_UNFINISHED].size) == (1, 5)
    shown = json.loads(CliRunner().invoke(app, ["cache", "--json"]).output)["parts"]
    assert [p["entries"] for p in shown] == [0, 0, 0, 0, 2, 1]
    report = caches.prune(30.0)
    assert set(report.removed) == {*old.values(), killed} and report.entries == 2
    assert all(p.exists() for p in new.values())
    # the configured folder being the fallback folder, it is listed once
    monkeypatch.setenv(c_cache.CACHE_ENV, str(fallback))
    assert [p.name for p in caches.usage()][-1] == "unfinished compilations"


def test_the_generated_modules_fallback_folder_is_listed_and_pruned(tmp_path: Path,
                                                                     c_folder: Path) -> None:
    """numba's cache and the generated modules move to ``<temporary folder>/feeddrive-py-<user
    id>`` when the user's cache cannot be written (``feeddrive._jit.cache_dir``); its numba
    folders are listed as two parts, the other versions' pruned, this version's kept."""
    uid = os.getuid() if hasattr(os, "getuid") else 0
    py = tmp_path / "tmp" / f"feeddrive-py-{uid}"
    this = _aged(_file(py / f"numba-{SOURCE_DIGEST}" / "models" / "m.py", 11).parent.parent, 40)
    other = _aged(_file(py / "numba-0123456789abcdef" / "k.nbc", 13).parent, 40)
    parts = {p.name: p for p in caches.usage()}
    this_name = "numba, this version (fallback folder, used when the cache cannot be written)"
    assert (parts[this_name].folder, parts[this_name].entries, parts[this_name].size) == (
        py, 1, 11)
    assert (parts["numba, other versions (fallback folder)"].entries,
            parts["numba, other versions (fallback folder)"].size) == (1, 13)
    report = caches.prune(30.0)
    assert other in report.removed and this not in report.removed and this.exists()


def test_a_configured_folder_that_is_not_a_folder_is_said(tmp_path: Path, c_folder: Path,
                                                         monkeypatch: pytest.MonkeyPatch
                                                         ) -> None:
    """Defect: with FEEDDRIVE_C_CACHE naming a file, the listing showed 0 entries there and
    did not say that nothing can be cached there."""
    not_a_folder = _file(tmp_path / "a-file", 3)
    monkeypatch.setenv(c_cache.CACHE_ENV, str(not_a_folder))
    part = _part("C libraries and texts")
    assert part.note is not None and "not a folder" in part.note
    assert _part("numba, this version").note is None
    runner = CliRunner()
    text = runner.invoke(app, ["cache"])
    assert text.exit_code == 0
    assert f"C libraries and texts: 0 entries, 0.0 MB in {not_a_folder} (is not a folder" \
        in text.output
    data = json.loads(runner.invoke(app, ["cache", "--json"]).output)["parts"]
    assert "not a folder" in data[2]["note"] and data[0]["note"] is None


def _denied(monkeypatch: pytest.MonkeyPatch, *denied: Path) -> None:
    """Make ``Path.unlink`` refuse ``denied`` as a read-only folder would (as root too)."""
    real = Path.unlink

    def unlink(self: Path, missing_ok: bool = False) -> None:
        if self in denied:
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(self))
        real(self, missing_ok=missing_ok)

    monkeypatch.setattr(Path, "unlink", unlink)


def test_prune_carries_on_past_what_it_cannot_remove(c_folder: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """Defect: the first file that could not be removed stopped the prune with
    ``error: ...: Permission denied``, after other files were removed, unreported."""
    stuck = _library(c_folder, _k("a"), 300, 40)
    going = _library(c_folder, _k("b"), 200, 40)
    text = _aged(_file(c_folder / _model("c"), 7), 40)
    killed = _aged(_file(c_folder / _compiling("a", "x1") / "model.c", 5).parent, 0.5)
    _file(killed / "model.o", 11)
    _aged(killed, 0.5)
    _denied(monkeypatch, stuck["library"], killed / "model.c")
    why = os.strerror(errno.EACCES)
    report = caches.prune(30.0)
    assert set(report.failed) == {(stuck["library"], why), (killed / "model.c", why)}
    assert set(report.removed) == {*going.values(), text}
    assert report.entries == 2 and report.freed == 200 + 65 + 7 + 11
    # the library that stays keeps its .sha256 and .lock; the folder keeps what it could not
    assert all(p.exists() for p in stuck.values())
    assert killed.is_dir() and [p.name for p in killed.iterdir()] == ["model.c"]


def test_the_command_reports_what_it_removed_and_what_it_could_not(
        c_folder: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    stuck = _library(c_folder, _k("a"), 300, 40)
    going = _library(c_folder, _k("b"), 200, 40)
    _denied(monkeypatch, stuck["library"])
    runner = CliRunner()
    done = runner.invoke(app, ["cache", "--prune"])
    assert done.exit_code == 1, done.output
    assert "removed 1 entry not used for 30 days" in done.stdout
    assert f"error: could not remove {stuck['library']}: Permission denied" in done.stderr
    assert "C libraries and texts: 1 entry" in done.stdout  # the listing is still printed
    for p in going.values():
        _file(p, 1)
        _aged(p, 40)
    data = runner.invoke(app, ["cache", "--prune", "--json"])
    assert data.exit_code == 1
    pruned = json.loads(data.stdout)["pruned"]
    assert pruned["failed"] == [{"path": str(stuck["library"]), "reason": "Permission denied"}]
    assert set(pruned["removed"]) == {str(p) for p in going.values()}
    assert pruned["entries"] == 1 and pruned["freed_mb"] == 3 / 1e6


def test_the_documentation_says_what_the_command_does() -> None:
    """docs/c-backend.md, "The compiled-object cache", "Clearing it": its ages, parts and
    report are the code's."""
    from feeddrive.cli._common import EXIT_FAILED

    doc = (Path(__file__).resolve().parents[2] / "docs" / "c-backend.md").read_text(
        encoding="utf-8")
    section = doc.split("## The compiled-object cache", 1)[1].split("\n## ", 1)[0]
    text = " ".join(section.split("- **Clearing it.**", 1)[1].split("\n- **", 1)[0].split())
    assert f"({caches.DEFAULT_AGE:g} by default;" in text
    assert caches.UNFINISHED_AGE == 3600.0 and "unfinished compilations older than an hour" \
        in text
    assert f"the exit status is then {EXIT_FAILED}" in text
    for word in ("`<temporary folder>/feeddrive-c-<user id>`", "`<key>.sha256`", "`<key>.lock`",
                 "`.NAME.XXXXXXXX.partial.EXT`", "`note` in `--json`", "`failed` in `--json`",
                 "15–100 kB"):
        assert word in text, word
    assert "15–100 kB" in (caches.__doc__ or "")
