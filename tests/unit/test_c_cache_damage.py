"""A damaged or unwritable compile cache (issue 42 item 2; an outside check, 2026-12-06): a
truncated or altered library is compiled again, never loaded (loading a truncated one killed
the process with a bus error); a cache folder that cannot be written or read leaves the
libraries *and* the translated texts *and* the generated Python modules for this user's
temporary folder, one per process that is reused, not one per library; ``~`` in
``$FEEDDRIVE_C_CACHE`` is the home folder; a damaged kept model text is translated again."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from test_c_cache import _value, needs_cc

from feeddrive.backends import c_cache, c_engine
from feeddrive.backends.c_cache import cached_library

SOURCE = "double fd_value(double x) { return 3.0 * x + %s; }\n"


@needs_cc
@pytest.mark.parametrize("damage", ["truncated", "altered", "digest gone"])
def test_a_damaged_library_is_compiled_again_not_loaded(cache: Path, damage: str) -> None:
    text = SOURCE % {"truncated": "1.0", "altered": "2.0", "digest gone": "3.0"}[damage]
    lib = cached_library(text)  # compiled, not loaded by this process
    digest = lib.with_suffix(c_cache.DIGEST_SUFFIX)
    assert digest.read_text(encoding="ascii").split() and c_cache.STATS["compiles"] == 1
    if damage == "truncated":
        os.truncate(lib, 1000)
    elif damage == "altered":
        data = bytearray(lib.read_bytes())
        data[len(data) // 2] ^= 0xFF
        lib.write_bytes(bytes(data))
    else:
        digest.unlink()
    again = cached_library(text)
    assert again == lib and c_cache.STATS == {"compiles": 2, "hits": 0}
    assert _value(again, 2.0) == 6.0 + float(text.split("+ ")[1].split(";")[0])
    assert cached_library(text) == lib and c_cache.STATS["hits"] == 1  # whole now


@needs_cc
def test_an_unusable_cache_folder_leaves_everything_for_one_private_folder(
        tmp_path: Path) -> None:
    """The cache paths under a regular file (no folder can be made there, whoever runs):
    a run completes, its libraries, texts and generated modules in this user's temporary
    folders; a second run finds them there (no compilation)."""
    blocked = tmp_path / "a-file"
    blocked.write_text("not a folder", encoding="utf-8")
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = dict(os.environ, **{c_cache.CACHE_ENV: str(blocked / "c")},
               NUMBA_CACHE_DIR=str(blocked / "numba"), XDG_CACHE_HOME=str(blocked / "xdg"),
               TMPDIR=str(tmp), FEEDDRIVE_ENGINE="c")
    code = textwrap.dedent("""
        import feeddrive as fd
        from feeddrive.backends import c_cache, c_engine
        from feeddrive.model.reference import ConstantSpeed
        r = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4), ConstantSpeed(2e-3),
                        0.01)
        print(r.solver_stats["engine"], c_cache.STATS["compiles"], c_cache.STATS["hits"])
    """)
    runs = [subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                           text=True, timeout=600, check=False) for _ in range(2)]
    assert [r.returncode for r in runs] == [0, 0], runs[0].stderr + runs[1].stderr
    assert runs[0].stdout.split()[:2] == ["c", "2"]  # the driver library and the model's
    assert runs[1].stdout.split() == ["c", "0", "2"]
    uid = os.getuid() if hasattr(os, "getuid") else 0
    c_folder, py_folder = tmp / f"feeddrive-c-{uid}", tmp / f"feeddrive-py-{uid}"
    assert sorted(p.name for p in tmp.iterdir()) == sorted([c_folder.name, py_folder.name])
    names = [p.name for p in c_folder.iterdir()]
    assert sum(n.endswith(c_cache.library_suffix()) for n in names) == 2
    assert any(n.startswith("model-") and n.endswith(".c") for n in names)
    assert any(n.startswith("driver-") and n.endswith(".json") for n in names)
    assert list(py_folder.glob("numba-*/models/*.py"))
    assert "Permission" not in runs[0].stderr + runs[1].stderr


def test_a_fresh_fallback_folder_is_made_once_per_process(tmp_path: Path,
                                                          monkeypatch: pytest.MonkeyPatch
                                                          ) -> None:
    """The shared name taken by a folder anyone can write: a folder of this process, the same
    for every library it compiles (it made one per library, never removed)."""
    from feeddrive import _disk

    monkeypatch.setattr(c_cache.tempfile, "tempdir", str(tmp_path))
    taken = tmp_path / f"feeddrive-c-{os.getuid() if hasattr(os, 'getuid') else 0}"
    taken.mkdir(mode=0o777)
    taken.chmod(0o777)
    _disk._own_folder.cache_clear()
    first, second = c_cache.fallback_folder(), c_cache.fallback_folder()
    assert first == second != taken and first.parent == tmp_path


def test_a_tilde_in_the_cache_variable_is_the_home_folder(monkeypatch: pytest.MonkeyPatch
                                                          ) -> None:
    monkeypatch.setenv(c_cache.CACHE_ENV, "~/fdcache")
    assert c_cache.cache_folder() == Path.home() / "fdcache"


@needs_cc
def test_a_damaged_model_text_is_translated_again(tmp_path: Path, filled_c_cache: Path) -> None:
    """A kept ``model-*.c`` cut short (it failed to compile, every run after): the model is
    translated again, and the run completes.

    The cache is a copy of the session's filled one (the model's kept text, the drivers'
    library); only the model's library is removed, which makes a run compile the model's
    text again: the drivers' library plays no part in it (their kept texts and their
    compilation are test_s20_c_texts.py's)."""
    shutil.copytree(filled_c_cache, tmp_path / "c")
    env = dict(os.environ, **{c_cache.CACHE_ENV: str(tmp_path / "c")}, FEEDDRIVE_ENGINE="c")
    code = textwrap.dedent("""
        import feeddrive as fd
        from feeddrive.model.reference import ConstantSpeed
        r = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4), ConstantSpeed(2e-3),
                        0.01)
        print(r.solver_stats["engine"], float(r["table_speed"][-1]))
    """)

    def run() -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                              text=True, timeout=600, check=False)

    first = run()
    assert first.returncode == 0, first.stderr
    texts = list((tmp_path / "c").glob("model-*.c"))
    assert len(texts) == 1
    whole = texts[0].read_text(encoding="utf-8")
    texts[0].write_text(whole[: len(whole) // 2], encoding="utf-8")
    (model_lib,) = [lib for lib in (tmp_path / "c").glob(f"*{c_cache.library_suffix()}")
                    if c_engine.TABLE.encode() in lib.read_bytes()]
    model_lib.unlink()  # so that the text is compiled again
    second = run()
    assert second.returncode == 0, second.stderr
    assert second.stdout == first.stdout
    assert texts[0].read_text(encoding="utf-8") == whole
