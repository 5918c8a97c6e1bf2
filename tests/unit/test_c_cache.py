"""The compiled-object cache (issue 42 item 2): a C source compiled once per machine, keyed by
source, compiler, flags and platform, written atomically under a lock (two real processes at
once: one compiles, both load), a read-only cache left for a private temporary folder (chmod),
a compiler failure in one line with its first error line, and, without a compiler, one line
saying how to get one, once per process."""

from __future__ import annotations

import ctypes
import os
import shutil
import stat
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from feeddrive.backends import c_cache
from feeddrive.backends.c_cache import (
    CompileError,
    CompilerNotFound,
    cache_key,
    cached_library,
    find_compiler,
)

try:
    CC = find_compiler()
except CompilerNotFound:
    CC = []

needs_cc = pytest.mark.skipif(not CC, reason="no C compiler (set CC)")

#: a source whose value tells which text was compiled
SOURCE = "double fd_value(double x) { return 2.0 * x + %s; }\n"


def _value(lib: Path, x: float = 1.5) -> float:
    fn = ctypes.CDLL(str(lib)).fd_value
    fn.argtypes, fn.restype = [ctypes.c_double], ctypes.c_double
    return float(fn(x))


@needs_cc
def test_a_source_is_compiled_once_then_loaded_from_the_cache(cache: Path) -> None:
    first = cached_library(SOURCE % "1.0")
    assert first.parent == cache and first.name.startswith(cache_key(SOURCE % "1.0", CC,
                                                                     c_cache.LIBRARY_FLAGS,
                                                                     ("-lm",)))
    assert _value(first) == 4.0
    assert cached_library(SOURCE % "1.0") == first
    assert c_cache.STATS == {"compiles": 1, "hits": 1}
    other = cached_library(SOURCE % "2.0")  # another text, another library
    assert other != first and _value(other) == 5.0
    assert sorted(p.suffix for p in cache.iterdir() if not p.name.endswith(".lock")) == [
        ".sha256", ".sha256", ".so", ".so"]  # each with its digest; no temporary file left


@needs_cc
def test_the_key_holds_source_compiler_flags_and_platform(monkeypatch: pytest.MonkeyPatch
                                                           ) -> None:
    base = cache_key("int x;", CC, ("-O2",))
    assert len(base) == 64
    assert cache_key("int x;", CC, ("-O2",)) == base
    assert cache_key("int y;", CC, ("-O2",)) != base
    assert cache_key("int x;", CC, ("-O1",)) != base
    assert cache_key("int x;", CC, ("-O2",), ("-lm",)) != base
    assert cache_key("int x;", [*CC, "-m64"], ("-O2",)) != base
    assert c_cache.compiler_identity(tuple(CC)).splitlines()[0] == os.path.realpath(
        shutil.which(CC[0]) or CC[0])
    monkeypatch.setattr(c_cache.sysconfig, "get_platform", lambda: "win-amd64")
    assert cache_key("int x;", CC, ("-O2",)) != base


@needs_cc
def test_a_compiler_failure_is_one_line_with_its_first_error(cache: Path) -> None:
    with pytest.raises(CompileError) as err:
        cached_library("double fd_value(double x) { return x + undeclared_name; }\n")
    message = str(err.value)
    assert "\n" not in message
    assert message.startswith("the C compiler failed (")
    assert "error" in message and "undeclared_name" in message
    assert "undeclared_name" in err.value.output
    assert c_cache.STATS["compiles"] == 0
    assert not [p for p in cache.iterdir() if not p.name.endswith(".lock")]


def test_without_a_compiler_one_line_says_how_to_get_one_once(
        monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv("PATH", "")
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setattr(c_cache, "_SAID", [])
    with pytest.raises(CompilerNotFound, match="no C compiler found"):
        find_compiler()
    assert c_cache.available_compiler() is None
    assert c_cache.available_compiler() is None
    err = capsys.readouterr().err
    assert err == c_cache.NO_COMPILER + "\n"
    # said while numba runs: no advice to install it (tests/unit/test_s20_c_texts.py)
    assert "apt-get install gcc" in err and "pip install" not in err


_CHILD = textwrap.dedent("""
    import ctypes, sys, time
    from pathlib import Path
    from feeddrive.backends import c_cache
    gate = Path(sys.argv[1])
    Path(sys.argv[3]).touch()  # ready
    while not gate.exists():
        time.sleep(0.001)
    lib = c_cache.cached_library(Path(sys.argv[2]).read_text())
    fn = ctypes.CDLL(str(lib)).fd_value
    fn.argtypes, fn.restype = [ctypes.c_double], ctypes.c_double
    print(c_cache.STATS["compiles"], fn(1.5), lib)
""")


@needs_cc
def test_two_processes_compiling_one_model_at_once_compile_it_once(tmp_path: Path) -> None:
    """Both start on one signal; the second waits on the lock and loads the first's library.
    Without the lock both would compile: each waits, imported, for the signal, so they start
    within milliseconds, and the compile takes longer than that."""
    cache = tmp_path / "cache"
    gate = tmp_path / "go"
    # a source that takes the compiler a while: many functions
    source = SOURCE % "3.0" + "".join(
        f"double fd_f{i}(double x) {{ return x * {i}.0 + x / {i + 1}.0; }}\n" for i in range(400))
    (tmp_path / "model.c").write_text(source)
    env = dict(os.environ, **{c_cache.CACHE_ENV: str(cache)})
    procs = [subprocess.Popen([sys.executable, "-c", _CHILD, str(gate),
                               str(tmp_path / "model.c"), str(tmp_path / f"ready{k}")],
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for k in range(2)]
    while not all((tmp_path / f"ready{k}").exists() for k in range(2)):
        if any(p.poll() is not None for p in procs):
            break
        time.sleep(0.01)
    gate.touch()
    outs = [p.communicate(timeout=300) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], [o[1] for o in outs]
    rows = [o[0].split() for o in outs]
    assert sorted(int(r[0]) for r in rows) == [0, 1]  # one compiled, one loaded
    assert [float(r[1]) for r in rows] == [6.0, 6.0]
    assert rows[0][2] == rows[1][2]
    assert len([p for p in cache.iterdir() if p.suffix == ".so"]) == 1


@needs_cc
@pytest.mark.skipif(sys.platform == "win32", reason="chmod does not make a folder read-only")
def test_a_read_only_cache_falls_back_to_a_private_temporary_folder(tmp_path: Path) -> None:
    """chmod 0555 on the cache folder; as root (who writes anyway) the child runs without the
    capability to bypass file permissions (util-linux setpriv)."""
    cache = tmp_path / "cache"
    cache.mkdir()
    cache.chmod(stat.S_IRUSR | stat.S_IXUSR | stat.S_IRGRP | stat.S_IXGRP | stat.S_IROTH
                | stat.S_IXOTH)
    prefix: list[str] = []
    if os.geteuid() == 0:
        setpriv = shutil.which("setpriv")
        if setpriv is None:
            pytest.skip("running as root without setpriv: a chmod does not stop root")
        prefix = [setpriv, "--bounding-set", "-dac_override,-dac_read_search"]
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    code = textwrap.dedent("""
        import sys
        from feeddrive.backends import c_cache
        lib = c_cache.cached_library(sys.argv[1])
        again = c_cache.cached_library(sys.argv[1])
        print(lib, again, c_cache.STATS["compiles"], c_cache.STATS["hits"])
    """)
    env = dict(os.environ, **{c_cache.CACHE_ENV: str(cache)}, TMPDIR=str(tmp))
    try:
        proc = subprocess.run([*prefix, sys.executable, "-c", code, SOURCE % "4.0"], env=env,
                              capture_output=True, text=True, timeout=300, check=False)
    finally:
        cache.chmod(stat.S_IRWXU)
    assert proc.returncode == 0, proc.stderr
    lib, again, compiles, hits = proc.stdout.split()
    assert lib == again and (compiles, hits) == ("1", "1")
    assert Path(lib).parent == tmp / f"feeddrive-c-{os.getuid()}"
    assert stat.S_IMODE(Path(lib).parent.stat().st_mode) == 0o700
    assert _value(Path(lib)) == 7.0
    assert list(cache.iterdir()) == []


def test_a_temporary_folder_of_someone_else_is_not_used(tmp_path: Path,
                                                        monkeypatch: pytest.MonkeyPatch
                                                        ) -> None:
    from feeddrive import _disk

    monkeypatch.setattr(c_cache.tempfile, "tempdir", str(tmp_path))
    _disk._own_folder.cache_clear()  # this process's own folder: made once per process
    taken = tmp_path / f"feeddrive-c-{os.getuid()}"
    taken.mkdir(mode=0o777)
    taken.chmod(0o777)  # world-writable: anyone could have put a library there
    chosen = c_cache.fallback_folder()
    assert chosen != taken and chosen.parent == tmp_path
    taken.chmod(0o700)
    assert c_cache.fallback_folder() == taken


def test_the_documentation_states_the_folder_flags_and_key(monkeypatch: pytest.MonkeyPatch,
                                                           tmp_path: Path) -> None:
    doc = (Path(__file__).resolve().parents[2] / "docs" / "c-backend.md").read_text(
        encoding="utf-8")
    section = doc.split("## The compiled-object cache", 1)[1].split("\n## ", 1)[0]
    assert f"`${c_cache.CACHE_ENV}`" in section
    assert f"`{' '.join(c_cache.LIBRARY_FLAGS)}`" in section and "`-lm`" in section
    monkeypatch.delenv(c_cache.CACHE_ENV, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert c_cache.cache_folder() == tmp_path / "feeddrive" / "c"
    assert "`$XDG_CACHE_HOME/feeddrive/c`" in section and "`~/.cache/feeddrive/c`" in section
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert c_cache.cache_folder() == Path.home() / ".cache" / "feeddrive" / "c"
    for word in ("SHA-256", "`--version`", "`sysconfig.get_platform()`", "`fcntl.flock`",
                 "`os.replace`", "feeddrive-c-<user id>", "mode 0700", "`compile_c`"):
        assert word in section, word


@needs_cc
def test_the_c_backend_and_the_fmu_report_a_failure_the_same_way(tmp_path: Path) -> None:
    """compile_shared and the FMU's compile_library run the compiler through compile_c."""
    from feeddrive.backends.c_backend import compile_shared
    from feeddrive.fmu.build import compile_library

    for build in (lambda: compile_shared("int broken = ;\n", tmp_path / "a"),
                  lambda: compile_library("int broken = ;\n", 2, tmp_path / "b", "bad")):
        with pytest.raises(CompileError) as err:
            build()
        assert "\n" not in str(err.value) and "error" in str(err.value)
        assert isinstance(err.value, RuntimeError)  # what callers caught before



def test_the_driver_library_is_compiled_with_the_documented_flags(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """docs/c-backend.md, "The driver library at -O3": the flags it states are the ones the
    engine passes when it builds the driver library; the model libraries keep the default."""
    from feeddrive.backends import c_engine

    if c_cache.available_compiler() is None:
        pytest.skip("no C compiler")
    doc = (Path(__file__).resolve().parents[2] / "docs" / "c-backend.md").read_text(
        encoding="utf-8")
    assert f"`{' '.join(c_engine.DRIVER_FLAGS)}`" in " ".join(doc.split())
    assert c_engine.DRIVER_FLAGS == tuple("-O3" if f == "-O2" else f
                                          for f in c_cache.LIBRARY_FLAGS)
    seen: list[tuple[str, ...]] = []
    real = c_engine.cached_library

    def recording(source: str, **kwargs: object) -> Path:
        seen.append(tuple(kwargs.get("flags", c_cache.LIBRARY_FLAGS)))  # type: ignore[arg-type]
        return real(source, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(c_engine, "cached_library", recording)
    c_engine.CEngine()._driver_library()
    assert seen == [c_engine.DRIVER_FLAGS]
