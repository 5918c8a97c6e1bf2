"""``feeddrive cache`` (:mod:`feeddrive.caches`): what the compile caches hold, and pruning
what has not been used — on a cache tree made here, with file times set by the test."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from feeddrive import caches
from feeddrive._jit import SOURCE_DIGEST
from feeddrive.backends import c_cache
from feeddrive.cli import app
from feeddrive.parameters import ParameterError

DAY = 86400.0


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


@pytest.fixture
def tree(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> dict[str, Path]:
    root = tmp_path / "cache"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(root))
    monkeypatch.setenv(c_cache.CACHE_ENV, str(root / "c"))
    made = {
        "current": _file(root / f"numba-{SOURCE_DIGEST}" / "k.nbi", 100).parent,
        "old_version": _file(root / "numba-0123456789abcdef" / "k.nbc", 1000).parent,
        "recent_version": _file(root / "numba-fedcba9876543210" / "k.nbc", 10).parent,
        "old_library": _file(root / "c" / f"aaaa{c_cache.library_suffix()}", 300),
        "new_library": _file(root / "c" / f"bbbb{c_cache.library_suffix()}", 30),
        "old_text": _file(root / "c" / "model-cccc.c", 7),
        "killed": _file(root / "c" / ".aaaa-x1" / "model.c", 5).parent,
        "compiling": _file(root / "c" / ".bbbb-x2" / "model.c", 5).parent,
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
    with pytest.raises(ParameterError, match="older_than = .*expected a number of days ≥ 0"):
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
                           "--older-than = -1.0: expected a number of days ≥ 0"),
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
