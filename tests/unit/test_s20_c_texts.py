"""The C build's kept texts, damaged libraries and cache writes, against an outside check
(2026-12-06).  Each test names the defect it guards:

1. a kept model text was used as it was: emptied or cut before ``fd_model_table`` it stopped
   every run (``undefined symbol: fd_model_table``, exit status 2), edited it changed the
   results silently — kept texts now have a digest (``<name>.sha256``);
2. a kept driver text cut short stopped every run, blaming the compiler "on model.c" at a
   temporary path since deleted, and left an orphan ``<key>.lock``;
3. a full disk ended a run with ``error: output: No space left on device``, no fallback;
4. ``CC="gcc '-O2"`` ended with ``error: No closing quotation``, exit status 2;
5. ``CC=/nonexistent`` was "not an executable on PATH"; the no-compiler line told a numba run
   to install numba; an empty fallback folder was made by runs that wrote nothing; a damaged
   library was compiled again without a word.
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path
from typing import Any

import pytest
import typer
from typer.testing import CliRunner

from feeddrive._jit import HAVE_NUMBA
from feeddrive.backends import c_cache, c_engine
from feeddrive.backends.c_cache import CompileError, CompilerNotFound, cached_library
from feeddrive.cli import app
from feeddrive.cli._common import user_errors
from feeddrive.io import outputs
from feeddrive.solvers import builds

try:
    CC = c_cache.find_compiler()
except CompilerNotFound:
    CC = []
needs_cc = pytest.mark.skipif(not CC, reason="no C compiler (set CC)")
posix_only = pytest.mark.skipif(sys.platform == "win32", reason="a shell script as compiler")
SUFFIX = c_cache.library_suffix()
UID = os.getuid() if hasattr(os, "getuid") else 0
FULL = os.strerror(errno.ENOSPC)
#: a source whose value tells which text was compiled
SOURCE = "double fd_value(double x) { return 2.0 * x + %s; }\n"
#: a source the compiler refuses
BAD = "double fd_value(double x) { return x + undeclared_name; }\n"
#: a run of the C build whose output is its results, bit for bit
RUN = textwrap.dedent("""
    import feeddrive as fd
    from feeddrive.model.reference import ConstantSpeed
    r = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4), ConstantSpeed(2e-3),
                    0.01)
    print(r.solver_stats["engine"], repr(float(r["table_speed"][-1])),
          repr(float(r["table_position"][-1])), r.solver_stats["rhs_evaluations"])
""")


@pytest.fixture
def folders(cache: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> dict[str, Path]:
    """The C cache (the shared ``cache`` fixture) and the system's temporary folder, the
    test's own, with what c_cache keeps per process fresh."""
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    for name in ("_MADE", "_NOTED", "_NOT_WRITABLE"):
        if hasattr(c_cache, name):
            monkeypatch.setattr(c_cache, name, type(getattr(c_cache, name))())
    return {"c": cache, "tmp": tmp, "fallback": tmp / f"feeddrive-c-{UID}"}


def _value(lib: Path, x: float = 1.5) -> float:
    import ctypes

    fn = ctypes.CDLL(str(lib)).fd_value
    fn.argtypes, fn.restype = [ctypes.c_double], ctypes.c_double
    return float(fn(x))


def _run(cache: Path, tmp: Path, **env: str) -> subprocess.CompletedProcess[str]:
    """:data:`RUN` in a fresh process on the C cache ``cache``."""
    tmp.mkdir(exist_ok=True)
    full = dict(os.environ, **{c_cache.CACHE_ENV: str(cache)}, TMPDIR=str(tmp),
                FEEDDRIVE_ENGINE="c", **env)
    full.pop(builds.SAID_ENV, None)
    return subprocess.run([sys.executable, "-c", RUN], env=full, capture_output=True,
                          text=True, timeout=600, check=False)


@pytest.fixture(scope="module")
def warm(tmp_path_factory: pytest.TempPathFactory, filled_c_cache: Path) -> tuple[Path, str]:
    """A C cache one run filled, and this file's run's output on it.  The cache is a copy of
    the session's ``filled_c_cache`` (one fresh process filled it from empty: the drivers'
    and the model's texts, libraries and digests, as :data:`RUN` leaves them; its compile of
    the drivers is ≈ 4 CPU s), and :data:`RUN` ran on the copy, wholly from it (no
    compilation, nothing said), so its output is the model's own results, bit for bit."""
    if not CC:
        pytest.skip("no C compiler")
    root = tmp_path_factory.mktemp("warm")
    cache = Path(shutil.copytree(filled_c_cache, root / "c"))
    first = _run(cache, root / "tmp")
    assert first.returncode == 0 and first.stderr == "", first.stderr
    assert first.stdout.split()[0] == "c"
    return cache, first.stdout


def _copy(warm: tuple[Path, str], tmp_path: Path) -> Path:
    return Path(shutil.copytree(warm[0], tmp_path / "c"))


def _one(pattern: str, folder: Path) -> Path:
    found = sorted(folder.glob(pattern))
    assert len(found) == 1, found
    return found[0]


# -- 1. a kept model text -----------------------------------------------------------------------


@needs_cc
@pytest.mark.parametrize("damage", ["emptied", "cut before the table", "edited"])
def test_a_damaged_or_edited_model_text_is_never_used(warm: tuple[Path, str], tmp_path: Path,
                                                      damage: str) -> None:
    """Defect 1: ``: > model-….c`` and a text cut before its ``fd_model_table`` line stopped
    every run (``undefined symbol: fd_model_table``, exit status 2, "refused before any work");
    ``dy[k] = dz;`` edited to ``dy[k] = 1.5*dz;`` changed the results silently."""
    cache = _copy(warm, tmp_path)
    path = _one("model-*.c", cache)
    whole = path.read_text(encoding="utf-8")
    if damage == "emptied":
        path.write_text("", encoding="utf-8")
    elif damage == "cut before the table":
        path.write_text(whole[:whole.index(f"const fd_model {c_engine.TABLE}")],
                        encoding="utf-8")
    else:
        assert whole.count("dy[k] = dz;") == 1
        path.write_text(whole.replace("dy[k] = dz;", "dy[k] = 1.5*dz;"), encoding="utf-8")
    again = _run(cache, tmp_path / "tmp")
    assert again.returncode == 0, again.stderr
    assert again.stdout == warm[1]  # the model's own results, not the edited text's
    assert again.stderr == (f"feeddrive: {path} does not match {path.name}"
                            f"{c_cache.DIGEST_SUFFIX} (damaged or edited), so it is translated "
                            "again\n")
    assert path.read_text(encoding="utf-8") == whole  # kept whole again
    assert _run(cache, tmp_path / "tmp").stderr == ""  # and used from then on


@needs_cc
def test_a_model_library_without_its_table_is_compiled_again(warm: tuple[Path, str],
                                                             tmp_path: Path) -> None:
    """Defect 1: a library lacking ``fd_model_table`` (its digest matching) stopped every run
    with exit status 2; it is damaged: compiled again, once, said in one line."""
    cache = _copy(warm, tmp_path)
    model_lib = next(p for p in cache.glob(f"*{SUFFIX}")
                     if c_engine.TABLE.encode() in p.read_bytes())
    other = c_cache.compile_c({"other.c": "int fd_other = 1;\n"}, tmp_path / "other",
                              "other" + SUFFIX, CC, c_cache.LIBRARY_FLAGS)
    shutil.copyfile(other, model_lib)
    model_lib.with_suffix(c_cache.DIGEST_SUFFIX).write_text(
        hashlib.sha256(other.read_bytes()).hexdigest() + "\n", encoding="ascii")
    again = _run(cache, tmp_path / "tmp")
    assert again.returncode == 0, again.stderr
    assert again.stdout == warm[1]
    assert again.stderr == (f"feeddrive: {model_lib} lacks {c_engine.TABLE} (damaged), so it "
                            "is compiled again\n")
    assert c_engine.TABLE.encode() in model_lib.read_bytes()
    assert _run(cache, tmp_path / "tmp").stderr == ""


# -- 2. a kept driver text ----------------------------------------------------------------------


@needs_cc
@pytest.mark.parametrize("digest", ["its digest", "a digest made to match"])
def test_a_driver_text_cut_short_is_translated_again(warm: tuple[Path, str], tmp_path: Path,
                                                     digest: str) -> None:
    """Defect 2: valid JSON whose ``"c"`` was cut in half stopped every run, ``error: the C
    compiler failed (… on model.c): /…/.e4e0…-mbor8buh/model.c:509:155: …`` (a driver, at a
    temporary path since deleted), and left an orphan ``<key>.lock``.  With a digest that
    matches the damage, the failed compilation is retried on a fresh translation."""
    cache = _copy(warm, tmp_path)
    path = _one("driver-integrate-*.json", cache)
    whole = path.read_bytes()
    unit = json.loads(whole)
    unit["c"] = unit["c"][: len(unit["c"]) // 2]
    path.write_text(json.dumps(unit), encoding="utf-8")
    sidecar = cache / f"{path.name}{c_cache.DIGEST_SUFFIX}"
    if digest != "its digest":
        sidecar.write_text(hashlib.sha256(path.read_bytes()).hexdigest() + "\n",
                           encoding="ascii")
    for lib in cache.glob(f"*{SUFFIX}"):  # so that the drivers are compiled again
        lib.unlink()
    again = _run(cache, tmp_path / "tmp")
    assert again.returncode == 0, again.stderr
    assert again.stdout == warm[1]
    said = (f"feeddrive: {path} does not match {sidecar.name} (damaged or edited), so it is "
            "translated again\n" if digest == "its digest" else
            f"feeddrive: the kept driver texts ({path.name.replace('integrate', '*')}) did not "
            "compile: translated again\n")
    assert again.stderr == said
    assert path.read_bytes() == whole
    locks = {p.stem for p in cache.glob("*.lock")}
    assert locks == {p.stem for p in cache.glob(f"*{SUFFIX}")}  # no lock without its library


@posix_only
@needs_cc
def test_a_compiler_failure_names_the_text_not_a_deleted_folder(folders: dict[str, Path]
                                                                ) -> None:
    """Defect 2: the message said "on model.c" for the drivers too and quoted the temporary
    folder's path (deleted when it is read)."""
    cache = folders["c"]
    with pytest.raises(CompileError) as err:
        cached_library(BAD, name="driver.c")
    message = str(err.value)
    assert "on driver.c): driver.c:1:" in message, message
    assert str(cache) not in message and str(cache) not in err.value.output
    kept_copy = str(cache / "model-0123.c")
    with pytest.raises(CompileError) as err:
        cached_library(BAD, shown=kept_copy)
    assert f"on {kept_copy}): {kept_copy}:1:" in str(err.value)


@needs_cc
def test_a_failed_compilation_leaves_no_lock(folders: dict[str, Path]) -> None:
    """Defect 5: a failed compilation left ``<key>.lock``, with no library, behind."""
    with pytest.raises(CompileError):
        cached_library(BAD)
    assert list(folders["c"].iterdir()) == []


@posix_only
@needs_cc
def test_a_model_that_does_not_compile_is_named_by_its_kept_text(warm: tuple[Path, str],
                                                                 tmp_path: Path) -> None:
    """Defect 2, the model's side: the compiler's line points into the kept text, by its
    path (its lines are the ones compiled)."""
    cache = _copy(warm, tmp_path)
    text = _one("model-*.c", cache)
    fake = tmp_path / "cc"
    fake.write_text(textwrap.dedent(f"""\
        #!/bin/sh
        for a; do case "$a" in *.c) src=$a;; esac; done
        case "$src" in */model.c) echo "$src:3:1: error: boom" >&2; exit 1;; esac
        exec {CC[0]} "$@"
        """), encoding="utf-8")
    fake.chmod(0o755)
    env = dict(os.environ, **{c_cache.CACHE_ENV: str(cache)}, TMPDIR=str(tmp_path),
               FEEDDRIVE_ENGINE="c", CC=str(fake))
    env.pop(builds.SAID_ENV, None)
    proc = subprocess.run([sys.executable, "-m", "feeddrive", "simulate", "--table-speed",
                           "0.5", "--duration", "0.02"], env=env, capture_output=True,
                          text=True, timeout=600, check=False)
    assert proc.returncode == 1 and proc.stderr.count("\n") == 1, proc.stderr
    flags = " ".join(c_engine.LIBRARY_FLAGS)
    assert proc.stderr.startswith(f"error: the C compiler failed (cc {flags} on {text}): "
                                  f"{text}:3:1: error: boom;")
    assert f"{cache}{os.sep}." not in proc.stderr  # no temporary folder
    assert {p.stem for p in cache.glob("*.lock")} <= {p.stem for p in cache.glob(f"*{SUFFIX}")}


# -- 3. a full disk -----------------------------------------------------------------------------


def _full_in(folder: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Writes of compile_c under ``folder`` fail as on a full disk (``write_text``: ENOSPC
    and no file name)."""
    real = c_cache.compile_c

    def compile_c(files: Any, where: Any, *args: Any, **kwargs: Any) -> Path:
        if Path(where).is_relative_to(folder):
            raise OSError(errno.ENOSPC, FULL)
        return real(files, where, *args, **kwargs)

    monkeypatch.setattr(c_cache, "compile_c", compile_c)


@needs_cc
def test_a_full_cache_falls_back_to_the_private_folder_said_once(
        folders: dict[str, Path], monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """Defect 3: ``error: output: No space left on device``, no fallback."""
    cache, fallback = folders["c"], folders["fallback"]
    _full_in(cache, monkeypatch)
    lib = cached_library(SOURCE % "1.0")
    assert lib.parent == fallback and _value(lib) == 4.0
    assert capsys.readouterr().err == (f"feeddrive: the C cache {cache} cannot be written "
                                       f"({FULL}), so {fallback} is used\n")
    assert _value(cached_library(SOURCE % "2.0")) == 5.0  # the fallback from then on
    assert capsys.readouterr().err == ""
    assert list(cache.iterdir()) == []  # no lock, no temporary folder left
    c_cache.keep_text("model-full.c", "text\n")  # the kept texts go there too
    assert (fallback / "model-full.c").is_file() and c_cache.kept_text("model-full.c") == "text\n"


@posix_only
@needs_cc
def test_a_linker_that_finds_the_disk_full_falls_back_too(folders: dict[str, Path]) -> None:
    """Defect 3: the text written, the library not: ``ld: final link failed: No space left
    on device`` names no file; it is the cache's write, not a compiler failure."""
    cache, fallback = folders["c"], folders["fallback"]
    fake = folders["tmp"].parent / "ld-full"
    fake.write_text(textwrap.dedent(f"""\
        #!/bin/sh
        case "$*" in *" -o {cache}/"*)
            echo "/usr/bin/ld: final link failed: {FULL}" >&2
            echo "collect2: error: ld returned 1 exit status" >&2; exit 1;; esac
        exec {CC[0]} "$@"
        """), encoding="utf-8")
    fake.chmod(0o755)
    lib = cached_library(SOURCE % "3.0", cc=[str(fake)])
    assert lib.parent == fallback and _value(lib) == 6.0
    assert list(cache.iterdir()) == []


def test_a_full_cache_and_a_full_fallback_are_one_error_naming_the_cache(
        folders: dict[str, Path], monkeypatch: pytest.MonkeyPatch) -> None:
    """Defect 3: where the fallback fails too, one line naming the cache and why."""
    _full_in(folders["tmp"].parent, monkeypatch)
    with pytest.raises(OSError) as err:
        cached_library(SOURCE % "1.0", cc=CC or ["cc"])
    assert err.value.filename == str(folders["c"]) and err.value.errno == errno.ENOSPC
    assert err.value.strerror == (f"the C cache cannot be written ({FULL}), nor its fallback "
                                  f"folder {folders['fallback']} ({FULL})")


def test_an_os_error_without_a_file_is_not_called_output(capsys: pytest.CaptureFixture[str]
                                                         ) -> None:
    """Defect 3: a command without an output option printed ``error: output: …``."""

    @user_errors
    def command(table_speed: float, output: str | None = None) -> None:
        raise OSError(errno.ENOSPC, FULL)

    with pytest.raises(typer.Exit) as stopped:
        command(table_speed=2.0)
    assert stopped.value.exit_code == 1
    assert capsys.readouterr().err == f"error: {FULL}\n"
    with pytest.raises(typer.Exit):
        command(table_speed=2.0, output="run.csv")  # its output: named
    assert capsys.readouterr().err == f"error: run.csv: {FULL}\n"


def _mounting() -> list[str] | None:
    """``unshare`` with a mount namespace of its own (as root, else in a user namespace,
    root inside: uid 0), where the system allows one."""
    unshare = shutil.which("unshare")
    if unshare is None or not hasattr(os, "geteuid"):
        return None
    command = [unshare, "-m"] if os.geteuid() == 0 else [unshare, "-rm"]
    probe = subprocess.run([*command, "true"], capture_output=True, check=False)
    return command if probe.returncode == 0 else None


@needs_cc
@pytest.mark.skipif(_mounting() is None, reason="no mount namespace to mount a small tmpfs")
def test_a_real_full_disk_falls_back(tmp_path: Path) -> None:
    """Defect 3 as the outside check made it: a 120 kB tmpfs as the cache."""
    small = tmp_path / "small"
    small.mkdir()
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = dict(os.environ, **{c_cache.CACHE_ENV: str(small)}, TMPDIR=str(tmp),
               FEEDDRIVE_ENGINE="c")
    env.pop(builds.SAID_ENV, None)
    script = 'mount -t tmpfs -o size=120k tmpfs "$1" && shift && exec "$@"'
    proc = subprocess.run([*(_mounting() or []), "sh", "-c", script, "sh", str(small),
                           sys.executable, "-m", "feeddrive", "simulate", "--table-speed", "2",
                           "--duration", "0.2"], env=env, capture_output=True, text=True,
                          timeout=600, check=False)
    fallback = tmp / "feeddrive-c-0"  # root, in the namespace
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == (f"feeddrive: the C cache {small} cannot be written ({FULL}), so "
                           f"{fallback} is used\n")
    assert len(list(fallback.glob(f"*{SUFFIX}"))) == 2


# -- 4, 5. $CC ----------------------------------------------------------------------------------


def test_a_cc_with_an_unbalanced_quote_is_named(monkeypatch: pytest.MonkeyPatch) -> None:
    """Defect 4: ``error: No closing quotation``, exit status 2, the variable not named."""
    value = "gcc '-O2"
    monkeypatch.setenv("CC", value)
    with pytest.raises(CompilerNotFound) as err:
        c_cache.find_compiler()
    assert str(err.value) == (f"CC = {value!r} is not a command line (no closing quotation): "
                              "expected a C compiler and its options, quoted as in a shell "
                              "(CC='gcc -O2')")
    # every message about $CC says it in find_compiler's words (c_cache.cc_problem)
    assert c_cache.no_compiler_text().startswith(f"feeddrive: {err.value}, so the numba build")
    assert builds.no_engine_text().startswith(f"{err.value} and numba is not installed; ")
    monkeypatch.setenv("FEEDDRIVE_ENGINE", "c")
    done = CliRunner().invoke(app, ["simulate", "--table-speed", "2", "--duration", "0.05"])
    assert done.exit_code == 1, done.output
    if HAVE_NUMBA:
        assert done.stderr == (f"error: FEEDDRIVE_ENGINE = 'c': {err.value}; or unset it to use "
                               "numba\n")
    else:  # nothing to run: the one line says how to get either build
        assert done.stderr == f"error: FEEDDRIVE_ENGINE = 'c': {builds.no_engine_text()}\n"


@pytest.mark.parametrize(("value", "said"), [
    ("/nonexistent/cc", "'/nonexistent/cc' is not an executable file"),
    ("no-such-cc-s20", "'no-such-cc-s20' is not an executable on PATH")])
def test_a_cc_path_that_is_not_there_is_not_looked_for_on_path(
        monkeypatch: pytest.MonkeyPatch, value: str, said: str) -> None:
    """Defect 5: ``CC=/nonexistent`` was "not an executable on PATH"."""
    monkeypatch.setenv("CC", value)
    with pytest.raises(CompilerNotFound) as err:
        c_cache.find_compiler()
    assert str(err.value) == f"CC = {value!r}: {said}"


def test_the_no_compiler_line_said_while_numba_runs_does_not_say_to_install_numba(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    """Defect 5: "…, so the numba build is used; …; without numba either: pip install
    'feeddrive[numba]'" — said only where numba runs (without it, NoEngine says how)."""
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))
    monkeypatch.delenv(builds.SAID_ENV, raising=False)
    monkeypatch.setattr(c_cache, "_SAID", [])
    assert c_cache.available_compiler() is None
    err = capsys.readouterr().err
    assert err == c_cache.NO_COMPILER + "\n" and "numba build is used" in err
    assert "pip install" not in err and "without numba" not in err
    monkeypatch.setattr(builds, "HAVE_NUMBA", False)
    monkeypatch.setenv("FEEDDRIVE_ENGINE", "auto")
    with pytest.raises(builds.NoEngine, match=r"pip install 'feeddrive\[numba\]'"):
        builds.engine_name()


# -- 5. the fallback folder, a damaged library, the kept texts' digests -------------------------


@needs_cc
def test_a_read_only_cache_that_holds_everything_makes_no_fallback_folder(
        folders: dict[str, Path], monkeypatch: pytest.MonkeyPatch) -> None:
    """Defect 5: ``<tmp>/feeddrive-c-<uid>`` was made, empty, by a run that found everything
    in a read-only cache and wrote nothing."""
    lib = cached_library(SOURCE % "1.0")
    monkeypatch.setattr(c_cache, "writable", lambda folder: False)  # read-only from now on
    assert cached_library(SOURCE % "1.0") == lib
    assert c_cache.kept("model-none.c") is None
    assert list(folders["tmp"].iterdir()) == []
    cached_library(SOURCE % "2.0")  # a write: made now
    assert [p.name for p in folders["tmp"].iterdir()] == [folders["fallback"].name]


def test_kept_texts_read_from_a_read_only_cache_make_no_fallback_folder(
        folders: dict[str, Path], monkeypatch: pytest.MonkeyPatch) -> None:
    """Defect 5, the texts' side."""
    c_cache.keep_text("model-ro.c", "kept\n")
    monkeypatch.setattr(c_cache, "writable", lambda folder: False)
    assert c_cache.kept_text("model-ro.c") == "kept\n"
    assert c_cache.kept_text("model-none.c") is None
    assert list(folders["tmp"].iterdir()) == []


@needs_cc
@pytest.mark.parametrize("damage", ["truncated", "digest gone"])
def test_a_damaged_library_compiled_again_is_said_once(
        folders: dict[str, Path], capsys: pytest.CaptureFixture[str], damage: str) -> None:
    """Defect 5: a damaged library was compiled again without a word."""
    lib = cached_library(SOURCE % "7.0")
    digest = lib.with_suffix(c_cache.DIGEST_SUFFIX)
    if damage == "truncated":
        os.truncate(lib, 100)
        why = f"did not match {digest.name}"
    else:
        digest.unlink()
        why = f"had no {digest.name} beside it"
    assert cached_library(SOURCE % "7.0") == lib and _value(lib) == 10.0
    said = f"feeddrive: {lib} {why} (damaged), so it was compiled again\n"
    assert capsys.readouterr().err == said
    assert cached_library(SOURCE % "7.0") == lib
    assert capsys.readouterr().err == ""


def test_a_kept_text_has_its_digest_beside_it(folders: dict[str, Path],
                                              capsys: pytest.CaptureFixture[str]) -> None:
    """Defect 1: a kept text is used only whole, as it was written; a text without a digest
    (kept before digests) is made again without a word."""
    cache = folders["c"]
    c_cache.keep_text("driver-x.json", '{"c": "é"}')
    digest = cache / f"driver-x.json{c_cache.DIGEST_SUFFIX}"
    data = (cache / "driver-x.json").read_bytes()
    assert digest.read_text(encoding="ascii") == hashlib.sha256(data).hexdigest() + "\n"
    assert c_cache.kept_text("driver-x.json") == '{"c": "é"}'
    (cache / "driver-x.json").write_bytes(data[:-2])
    assert c_cache.kept_text("driver-x.json") is None
    assert c_cache.kept_text("driver-x.json") is None
    assert capsys.readouterr().err.count("\n") == 1  # said once
    digest.unlink()
    (cache / "driver-x.json").write_bytes(data)
    assert c_cache.kept_text("driver-x.json") is None and capsys.readouterr().err == ""


def test_a_kept_text_not_written_in_a_full_cache_goes_to_the_fallback(
        folders: dict[str, Path], monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """Defect 3, the texts' side: they were dropped silently on a full disk (translated again
    by every run)."""
    real = outputs.atomic_path

    def atomic_path(path: Any) -> Any:
        if Path(path).is_relative_to(folders["c"]):
            raise OSError(errno.EDQUOT, os.strerror(errno.EDQUOT))
        return real(path)

    monkeypatch.setattr(outputs, "atomic_path", atomic_path)
    c_cache.keep_text("model-q.c", "quota\n")
    assert (folders["fallback"] / "model-q.c").read_text(encoding="utf-8") == "quota\n"
    assert c_cache.kept_text("model-q.c") == "quota\n"
    assert capsys.readouterr().err == (
        f"feeddrive: the C cache {folders['c']} cannot be written "
        f"({os.strerror(errno.EDQUOT)}), so {folders['fallback']} is used\n")
