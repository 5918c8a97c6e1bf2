"""The system C compiler, run once per source: C text → a shared library, cached on disk.

:func:`find_compiler` finds the compiler (``$CC``, else cc, gcc, clang on PATH; a
gcc-compatible command line — MinGW too; MSVC is not supported); :func:`compile_c` runs it on
source files (the one compile step of the C backend and of the FMU export);
:func:`cached_library` compiles a source text once per machine: the library lives in
:func:`cache_folder` under the hash of the source text, the compiler's identity (its resolved
path, its fixed arguments and its ``--version`` output), the flags and the platform
(:func:`cache_key`).  It is written to a temporary file in the cache folder and renamed into
place (``os.replace``: a reader never sees half a library) while a lock on
``<key>.lock`` is held (``fcntl.flock``): of two processes that need one model at once, one
compiles and the other waits and loads the same file.  Beside it ``<key>.sha256`` holds its
SHA-256; a library whose bytes do not match (a disk that filled, a copy cut short) is compiled
again, never loaded.  Where ``fcntl`` is missing (Windows), nothing is locked: both may
compile, each into its own temporary file, and the rename keeps one.  A cache folder that
cannot be written (or read) is left for a folder of this user's under the system's temporary
folder (:func:`fallback_folder`), for the libraries and for the translated texts
(:func:`store_folder`, :func:`kept`).

docs/c-backend.md, "The compiled-object cache", says where it lives and how to clear it.
"""

from __future__ import annotations

import functools
import hashlib
import os
import platform
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

from .._disk import DAY, file_lock, private_folder, user_cache_root, writable

__all__ = ["CACHE_ENV", "COMPILE_FAILED_ADVICE", "CompileError", "CompilerNotFound",
           "DIGEST_SUFFIX", "LIBRARY_FLAGS", "NO_COMPILER", "STATS",
           "available_compiler", "cache_folder", "cache_key", "cached_library", "compile_c",
           "compiler_identity", "fallback_folder", "find_compiler", "kept", "library_suffix",
           "mark_used", "no_compiler_text", "store_folder"]

#: environment variable naming the cache folder (instead of the user's cache)
CACHE_ENV = "FEEDDRIVE_C_CACHE"
#: flags of a library :func:`cached_library` builds by default: ISO C99, optimised, no fused
#: multiply-add (it rounds differently from numba), position independent and shared
LIBRARY_FLAGS = ("-std=c99", "-O2", "-ffp-contract=off", "-fPIC", "-shared")
#: what is said, once per process, when no C compiler is found (:func:`available_compiler`)
NO_COMPILER = ("feeddrive: no C compiler found, so the numba build is used; to compile C, "
               "install gcc or clang (Debian: apt-get install gcc; macOS: xcode-select "
               "--install) or set CC; without numba either: pip install 'feeddrive[numba]'")
#: what a command adds to a compiler failure (:class:`CompileError`)
COMPILE_FAILED_ADVICE = ("the C build could not be made: set CC to a working C compiler, or "
                         "use the numba build (FEEDDRIVE_ENGINE=numba, pip install "
                         "'feeddrive[numba]')")
#: this process's counts: ``compiles`` (libraries this process compiled into a cache) and
#: ``hits`` (libraries found there)
STATS = {"compiles": 0, "hits": 0}
#: the file beside a library ``<key><suffix>`` holding its SHA-256: ``<key>.sha256``
DIGEST_SUFFIX = ".sha256"
_SAID: list[str] = []


class CompilerNotFound(RuntimeError):
    """No C compiler: set $CC or install gcc/clang."""


class CompileError(RuntimeError):
    """The C compiler failed.  The message is one line with the compiler's first error line;
    ``output`` holds everything it printed.

    Parameters
    ----------
    message : str
        The one-line message.
    output : str
        The compiler's whole output.
    """

    def __init__(self, message: str, output: str) -> None:
        super().__init__(message)
        self.output = output


def find_compiler() -> list[str]:
    """The C compiler command.

    Returns
    -------
    list of str
        ``$CC`` split into words (it may hold options), else the first of ``cc``, ``gcc``,
        ``clang`` found on PATH.

    Raises
    ------
    CompilerNotFound
        None of them is there.
    """
    env = os.environ.get("CC", "").strip()
    if env:
        cmd = shlex.split(env)
        if shutil.which(cmd[0]) is None:
            raise CompilerNotFound(f"CC = {env!r}: {cmd[0]!r} is not an executable on PATH")
        return cmd
    for name in ("cc", "gcc", "clang"):
        path = shutil.which(name)
        if path:
            return [path]
    raise CompilerNotFound("no C compiler found: set CC or install gcc or clang "
                           "(looked for cc, gcc, clang on PATH)")


def available_compiler() -> list[str] | None:
    """The C compiler command, or None without one — then :data:`NO_COMPILER` is written to
    standard error, once per process, so a caller can fall back to numba.

    Returns
    -------
    list of str or None
        The command (:func:`find_compiler`), or None.
    """
    try:
        return find_compiler()
    except CompilerNotFound as err:
        from ..solvers.builds import SAID_ENV

        if not _SAID and not os.environ.get(SAID_ENV):
            _SAID.append(str(err))
            print(no_compiler_text(), file=sys.stderr)
        return None


def no_compiler_text() -> str:
    """What is said when no C compiler is found: :data:`NO_COMPILER`, or, where ``$CC`` names
    one that is not there, that (the compilers on PATH are not looked at then).

    Returns
    -------
    str
        One line.
    """
    env = os.environ.get("CC", "").strip()
    if not env:
        return NO_COMPILER
    return (f"feeddrive: CC = {env!r} is not an executable, so the numba build is used; set "
            "CC to a C compiler, or unset it to use cc, gcc or clang from PATH")


def library_suffix() -> str:
    """The shared-library extension of this machine.

    Returns
    -------
    str
        ``".dll"``, ``".dylib"`` or ``".so"``.
    """
    return {"win32": ".dll", "darwin": ".dylib"}.get(sys.platform, ".so")


def _first_error(output: str) -> str:
    """The compiler's first error line (the first line naming an error, else its first line)."""
    lines = [line.strip() for line in output.splitlines() if line.strip()]
    for line in lines:
        if re.search(r"\b(error|fatal error)\b", line, re.IGNORECASE):
            return line
    return lines[0] if lines else "(no output)"


def compile_c(files: Mapping[str, str], folder: str | os.PathLike[str], output: str,
              cc: Sequence[str], flags: Sequence[str], libraries: Sequence[str] = ()) -> Path:
    """Write ``files`` into ``folder`` and compile the first of them with
    ``cc flags -o folder/output folder/<first> libraries``.

    Parameters
    ----------
    files : mapping of str to str
        File name → text; the first is the translation unit, the others (headers) sit beside
        it.
    folder : path-like
        Existing or new folder.
    output : str
        The file name of what is built.
    cc : sequence of str
        The compiler command (:func:`find_compiler`).
    flags : sequence of str
        Flags before ``-o``.
    libraries : sequence of str
        Arguments after the source (``-lm``).

    Returns
    -------
    Path
        What was built.

    Raises
    ------
    CompileError
        The compiler failed (exit status not 0), in one line with its first error line.
    """
    where = Path(folder)
    where.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (where / name).write_text(text, encoding="utf-8")
    src = where / next(iter(files))
    out = where / output
    cmd = [*cc, *flags, "-o", str(out), str(src), *libraries]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        text = (proc.stderr or proc.stdout).strip()
        more = len([line for line in text.splitlines() if line.strip()]) - 1
        command = " ".join([Path(cc[0]).name, *cc[1:], *flags])
        raise CompileError(f"the C compiler failed ({command} on {src.name}): "
                           f"{_first_error(text)}"
                           + (f" (+{more} more lines)" if more > 0 else ""), text)
    return out


@functools.cache
def compiler_identity(cc: tuple[str, ...]) -> str:
    """What identifies a compiler in the cache key: its resolved path, its fixed arguments and
    what ``--version`` prints (asked once per process and command).

    Parameters
    ----------
    cc : tuple of str
        The compiler command.

    Returns
    -------
    str
        The identity text.
    """
    path = os.path.realpath(shutil.which(cc[0]) or cc[0])
    try:
        proc = subprocess.run([*cc, "--version"], capture_output=True, text=True,
                              check=False, timeout=60)
        version = (proc.stdout or proc.stderr).strip()
    except (OSError, subprocess.TimeoutExpired) as err:
        version = f"(--version failed: {err})"
    return "\n".join([path, *cc[1:], version])


def cache_key(source: str, cc: Sequence[str], flags: Sequence[str],
              libraries: Sequence[str] = ()) -> str:
    """The cache key of a library: SHA-256 of the source text, the compiler's identity
    (:func:`compiler_identity`), the flags and libraries, and the platform
    (``sysconfig.get_platform()``, the machine and ``sys.platform``).

    Parameters
    ----------
    source : str
        The C source.
    cc : sequence of str
        The compiler command.
    flags, libraries : sequence of str
        Its arguments (:func:`compile_c`).

    Returns
    -------
    str
        64 hexadecimal digits.
    """
    parts = (source, compiler_identity(tuple(cc)), "\0".join(flags), "\0".join(libraries),
             sysconfig.get_platform(), platform.machine(), sys.platform)
    digest = hashlib.sha256()
    for part in parts:
        data = part.encode("utf-8")
        digest.update(len(data).to_bytes(8, "little"))
        digest.update(data)
    return digest.hexdigest()


def cache_folder() -> Path:
    """Where compiled libraries are kept: ``$FEEDDRIVE_C_CACHE`` (``~`` expanded), else the
    folder ``c`` of the user's cache (``$XDG_CACHE_HOME/feeddrive/c``, else
    ``~/.cache/feeddrive/c``).

    Returns
    -------
    Path
        The folder (not created here).
    """
    env = os.environ.get(CACHE_ENV, "").strip()
    return Path(env).expanduser() if env else user_cache_root() / "c"


def fallback_folder() -> Path:
    """The folder used when :func:`cache_folder` cannot be written:
    ``<temporary folder>/feeddrive-c-<user id>``, private (mode 0700) and kept between runs;
    if that name is taken by a folder that is not this user's own, private one, a temporary
    folder of this process, removed when it exits (:func:`feeddrive._disk.private_folder`).

    Returns
    -------
    Path
        A folder this user alone can write.
    """
    return private_folder("feeddrive-c")


def _writable(folder: Path) -> bool:
    """:func:`feeddrive._disk.writable`, a folder found not writable not tried again by this
    process."""
    if folder in _NOT_WRITABLE:
        return False
    if writable(folder):
        return True
    _NOT_WRITABLE.add(folder)
    return False


_NOT_WRITABLE: set[Path] = set()


def store_folder() -> Path:
    """Where this process writes what it caches: :func:`cache_folder` if a file can be made
    there (it is made if missing), else :func:`fallback_folder`.

    Returns
    -------
    Path
        The folder.
    """
    folder = cache_folder()
    return folder if _writable(folder) else fallback_folder()


def _is_file(path: Path) -> bool:
    """``path.is_file()``, False where the folder cannot be read."""
    try:
        return path.is_file()
    except OSError:
        return False


def kept(name: str) -> Path | None:
    """A file this package keeps in the cache (a translated text): in :func:`cache_folder`,
    else in the fallback folder when the cache cannot be written (:func:`store_folder`).

    Parameters
    ----------
    name : str
        The file's name.

    Returns
    -------
    Path or None
        The file, or None when neither holds it.
    """
    path = cache_folder() / name
    if _is_file(path):
        return path
    store = store_folder()
    if store != cache_folder() and _is_file(store / name):
        return store / name
    return None


def _intact(folder: Path, key: str, name: str) -> Path | None:
    """The library ``name`` in ``folder`` if it is whole — its bytes' SHA-256 is the one
    written beside it (``<key>.sha256``) when it was compiled — else None: a truncated or
    damaged file (a full disk, a copy cut short) is compiled again instead of loaded (loading
    a truncated library can kill the process with a bus error).  A library found whole is
    marked used (:func:`mark_used`)."""
    lib = folder / name
    try:
        want = (folder / f"{key}{DIGEST_SUFFIX}").read_text(encoding="ascii").strip()
        whole = hashlib.sha256(lib.read_bytes()).hexdigest() == want
    except (OSError, ValueError):
        return None
    if not whole:
        return None
    mark_used(lib)
    return lib


def mark_used(path: Path) -> None:
    """Set a cached file's modification time to now if it is more than a day old: what
    ``feeddrive cache --prune`` (:func:`feeddrive.caches.prune`) reads as its last use.  A
    cache that cannot be written is left as it is.

    Parameters
    ----------
    path : Path
        The file.
    """
    try:
        if time.time() - path.stat().st_mtime > DAY:
            os.utime(path)
    except OSError:
        pass


def cached_library(source: str, *, flags: Sequence[str] = LIBRARY_FLAGS,
                   libraries: Sequence[str] = ("-lm",),
                   cc: Sequence[str] | None = None) -> Path:
    """The shared library compiled from ``source``, from the cache when it is there, else
    compiled into it (see the module's description: key, lock, atomic rename, fallback).

    Parameters
    ----------
    source : str
        The C source (one translation unit needing only the C library and libm).
    flags : sequence of str, default :data:`LIBRARY_FLAGS`
        Compiler flags (they must make a shared library).
    libraries : sequence of str, default ``("-lm",)``
        Arguments after the source.
    cc : sequence of str, optional
        The compiler command; :func:`find_compiler` by default.

    Returns
    -------
    Path
        The library, ``<folder>/<key><suffix>``, to load with ``ctypes.CDLL``.

    Raises
    ------
    CompilerNotFound
        Without a C compiler.
    CompileError
        When the compiler fails (one line, with its first error line).
    """
    command = list(cc) if cc is not None else find_compiler()
    key = cache_key(source, command, flags, libraries)
    name = f"{key}{library_suffix()}"
    found = _intact(cache_folder(), key, name)
    folder = store_folder()
    if found is None and folder != cache_folder():
        found = _intact(folder, key, name)
    if found is not None:
        STATS["hits"] += 1
        return found
    lib = folder / name
    with file_lock(folder / f"{key}.lock"):
        if _intact(folder, key, name) is not None:  # compiled by another process meanwhile
            STATS["hits"] += 1
            return lib
        with tempfile.TemporaryDirectory(dir=folder, prefix=f".{key[:16]}-") as tmp:
            built = compile_c({"model.c": source}, tmp, name, command, flags, libraries)
            digest = Path(tmp) / f"{key}{DIGEST_SUFFIX}"
            digest.write_text(hashlib.sha256(built.read_bytes()).hexdigest() + "\n",
                              encoding="ascii")
            try:
                os.replace(built, lib)
            except OSError:
                if not lib.is_file():  # a library in use cannot be replaced on Windows
                    raise
            os.replace(digest, folder / digest.name)
    STATS["compiles"] += 1
    return lib
