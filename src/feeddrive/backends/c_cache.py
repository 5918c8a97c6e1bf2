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
folder (:func:`fallback_folder`, made only when something is written there), for the libraries
and for the translated texts (:func:`store_folder`, :func:`kept`); so is one whose write fails
(a full disk, an exceeded quota: :func:`in_store`); either is said once per process in one
line naming both folders and why.  A kept text has its SHA-256 beside it too
(``<name>.sha256``, :func:`keep_text`, :func:`kept_text`): one that does not match is made
again, never used.

docs/c-backend.md, "The compiled-object cache", says where it lives and how to clear it.
"""

from __future__ import annotations

import contextlib
import errno
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
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TypeVar

from .. import _disk
from .._disk import DAY, existing_private, file_lock, private_folder, user_cache_root, writable

__all__ = ["CACHE_ENV", "COMPILE_FAILED_ADVICE", "CompileError", "CompilerNotFound",
           "DIGEST_SUFFIX", "LIBRARY_FLAGS", "NO_COMPILER", "STATS",
           "available_compiler", "cache_folder", "cache_key", "cached_library", "compile_c",
           "compiler_identity", "fallback_folder", "find_compiler", "in_store",
           "keep_text", "kept", "kept_text", "library_suffix", "mark_used",
           "no_compiler_text", "store_folder"]

#: environment variable naming the cache folder (instead of the user's cache)
CACHE_ENV = "FEEDDRIVE_C_CACHE"
#: flags of a library :func:`cached_library` builds by default: ISO C99, optimised, no fused
#: multiply-add (it rounds differently from numba), position independent and shared
LIBRARY_FLAGS = ("-std=c99", "-O2", "-ffp-contract=off", "-fPIC", "-shared")
#: what is said, once per process, when no C compiler is found (:func:`available_compiler`):
#: numba runs then (without numba, :data:`feeddrive.solvers.builds.NO_ENGINE` is the error)
NO_COMPILER = ("feeddrive: no C compiler found, so the numba build is used; to compile C, "
               "install gcc or clang (Debian: apt-get install gcc; macOS: xcode-select "
               "--install) or set CC")
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
#: the notes said once per process (a damaged file made again, a cache left for the fallback)
_NOTED: set[str] = set()
#: the errors of a write a folder cannot take, as a compiler prints them (the linker's
#: "final link failed: No space left on device" names no file)
_FULL = tuple(code for code in (errno.ENOSPC, getattr(errno, "EDQUOT", None), errno.EROFS)
              if code is not None)
T = TypeVar("T")


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
        from ..solvers.builds import cc_problem

        problem = cc_problem(env)
        if problem is not None:
            raise CompilerNotFound(problem)
        return shlex.split(env)
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
    """What is said when no C compiler is found: :data:`NO_COMPILER`, or, where ``$CC`` is set
    but gives none (:func:`feeddrive.solvers.builds.cc_problem`), that (the compilers on PATH
    are not looked at then).

    Returns
    -------
    str
        One line.
    """
    env = os.environ.get("CC", "").strip()
    if not env:
        return NO_COMPILER
    from ..solvers.builds import cc_problem

    return (f"feeddrive: {cc_problem(env) or f'CC = {env!r} gives no compiler'}, so the numba "
            "build is used; set CC to a C compiler, or unset it to use cc, gcc or clang from "
            "PATH")


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
              cc: Sequence[str], flags: Sequence[str], libraries: Sequence[str] = (),
              shown: str | None = None) -> Path:
    """Write ``files`` into ``folder`` and compile the first of them with
    ``cc flags -o folder/output folder/<first> libraries``, the compiler's own temporary
    files in ``folder`` too (``$TMPDIR``: no system temporary folder is needed).

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
    shown : str, optional
        What a failure calls the source, in place of its path (a folder that is temporary is
        gone when the message is read): its kept copy's path, or a name; by default its path.

    Returns
    -------
    Path
        What was built.

    Raises
    ------
    CompileError
        The compiler failed (exit status not 0), in one line with its first error line; or
        could not be run (not an executable format).
    """
    where = Path(folder)
    where.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (where / name).write_text(text, encoding="utf-8")
    src = where / next(iter(files))
    out = where / output
    cmd = [*cc, *flags, "-o", str(out), str(src), *libraries]
    command = " ".join([Path(cc[0]).name, *cc[1:], *flags])
    try:
        # its own temporary files in ``folder`` too (TMPDIR): not in a system temporary folder
        # that may be read-only or full while the cache is not (gcc then tries ./ as well)
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False,
                              env=dict(os.environ, TMPDIR=os.path.abspath(where)))
    except OSError as err:  # not the folder's fault: the compiler cannot be run
        raise CompileError(f"the C compiler could not be run ({command}): "
                           f"{err.strerror or err}", str(err)) from None
    if proc.returncode != 0:
        text = (proc.stderr or proc.stdout).strip()
        if shown is not None:
            text = text.replace(str(src), shown)
        more = len([line for line in text.splitlines() if line.strip()]) - 1
        raise CompileError(f"the C compiler failed ({command} on {shown or src.name}): "
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
    Made here: called when something is to be written there (a lookup uses
    :func:`_fallback_found`).

    Returns
    -------
    Path
        A folder this user alone can write.
    """
    folder = private_folder("feeddrive-c")
    _MADE[:] = [folder]
    return folder


#: the fallback folder this process made (:func:`fallback_folder`)
_MADE: list[Path] = []


def _fallback_found() -> Path | None:
    """The fallback folder if it is there, not made: the one this process made, else the
    shared one if it is this user's private folder (:func:`feeddrive._disk.existing_private`).
    """
    return _MADE[0] if _MADE else existing_private("feeddrive-c")


def _lookup_folders() -> list[Path]:
    """Where a cached file is looked for: :func:`cache_folder`, then the fallback folder if it
    is there (what a run wrote while the cache could not be written)."""
    folders = [cache_folder()]
    other = _fallback_found()
    if other is not None and other != folders[0]:
        folders.append(other)
    return folders


def _writable(folder: Path) -> bool:
    """:func:`feeddrive._disk.writable`, a folder found not writable not tried again by this
    process (why it is not, :func:`feeddrive._disk.unwritable_reason`, kept for the message)."""
    if folder in _NOT_WRITABLE:
        return False
    if writable(folder):
        return True
    _NOT_WRITABLE[folder] = _disk.unwritable_reason(folder) or "not writable"
    return False


#: the folders found not writable, or whose write failed, with why
_NOT_WRITABLE: dict[Path, str] = {}


def store_folder() -> Path:
    """Where this process writes what it caches: :func:`cache_folder` if a file can be made
    there (it is made if missing) and no write there has failed, else :func:`fallback_folder`
    (said once per process, in one line naming both and why, when something is written there:
    :func:`in_store`).

    Returns
    -------
    Path
        The folder.

    Raises
    ------
    OSError
        The fallback folder cannot be made either (:func:`_fallback`).
    """
    folder = cache_folder()
    return folder if _writable(folder) else _fallback(folder)


def _fallback(cache: Path) -> Path:
    """:func:`fallback_folder`, for the cache folder ``cache`` that cannot be written; an
    ``OSError`` naming the cache and both reasons when the fallback folder cannot be made
    (no temporary folder is usable)."""
    try:
        return fallback_folder()
    except OSError as err:
        raise _disk.unwritable_error(_WHAT, cache, _why(cache), None, err) from None


def _why(cache: Path) -> str:
    """Why the cache folder ``cache`` was left (:data:`_NOT_WRITABLE`)."""
    return _NOT_WRITABLE.get(cache) or "not writable"


#: the C cache, as a message names it
_WHAT = "the C cache"


def _note(key: str, line: str) -> None:
    """Say ``line`` on standard error, once per process for ``key``."""
    if key not in _NOTED:
        _NOTED.add(key)
        print(line, file=sys.stderr)


def in_store(write: Callable[[Path], T]) -> T:
    """``write(folder)`` in :func:`store_folder`.  An ``OSError`` there (a full disk, an
    exceeded quota, a read-only mount, a refused permission) leaves the cache folder for the
    fallback folder, as one that cannot be written is left, and ``write`` runs again there;
    once it has, the fallback is said once per process, in one line naming both folders and
    why the cache was left (a read-only mount, a file where the folder should be, a full
    disk).

    Parameters
    ----------
    write : callable
        Writes into the folder it is given; what it returns is returned.

    Returns
    -------
    object
        What ``write`` returned.

    Raises
    ------
    OSError
        The fallback folder failed too, or could not be made: one line naming the cache
        folder (``filename``) and why each failed (:func:`feeddrive._disk.unwritable_error`).
    """
    cache = cache_folder()
    if _writable(cache):
        try:
            return write(cache)
        except OSError as err:
            _NOT_WRITABLE[cache] = _disk.reason(err)
    other = _fallback(cache)
    try:
        done = write(other)
    except OSError as err:
        raise _disk.unwritable_error(_WHAT, cache, _why(cache), other, err) from None
    _note(f"left {cache}", f"feeddrive: {_WHAT} {cache} cannot be written ({_why(cache)}), so "
          f"{other} is used")
    return done


def _is_file(path: Path) -> bool:
    """``path.is_file()``, False where the folder cannot be read."""
    try:
        return path.is_file()
    except OSError:
        return False


def kept(name: str) -> Path | None:
    """A file this package keeps in the cache (a translated text): in :func:`cache_folder`,
    else in the fallback folder if it is there (:func:`store_folder`).

    Parameters
    ----------
    name : str
        The file's name.

    Returns
    -------
    Path or None
        The file, or None when neither holds it.
    """
    for folder in _lookup_folders():
        if _is_file(folder / name):
            return folder / name
    return None


def kept_text(name: str) -> str | None:
    """The text of the file ``name`` kept by :func:`keep_text` (in the cache folder, else the
    fallback folder), if its bytes' SHA-256 is the one beside it (``<name>.sha256``); marked
    used.  A text cut short or edited is not used — said once per process, and the caller
    makes it again (a missing digest, as of a text kept before digests, is not said).

    Parameters
    ----------
    name : str
        The file's name.

    Returns
    -------
    str or None
        The text, or None when no whole copy is there.
    """
    for folder in _lookup_folders():
        path = folder / name
        digest = folder / f"{name}{DIGEST_SUFFIX}"
        if not _is_file(path):
            continue
        try:
            data = path.read_bytes()
        except OSError:
            continue
        whole = _matches(data, digest)
        if whole is None:  # no digest (a text kept before texts had one): made again, unsaid
            continue
        if not whole:
            _note(str(path), f"feeddrive: {path} does not match {digest.name} (damaged or "
                  "edited), so it is translated again")
            continue
        try:
            text = data.decode("utf-8")
        except ValueError:
            continue
        mark_used(path)
        mark_used(digest)
        return text
    return None


def keep_text(name: str, text: str) -> None:
    """Keep ``text`` as the file ``name`` of the cache (:func:`in_store`: the fallback folder
    when the cache cannot be written), with its SHA-256 beside it (``<name>.sha256``), each
    written whole or not at all (:func:`feeddrive.io.outputs.atomic_path`).  What neither
    folder takes is not kept: it is made again by the next process.

    Parameters
    ----------
    name : str
        The file's name.
    text : str
        Its text.
    """
    from ..io.outputs import atomic_path

    data = text.encode("utf-8")
    digest = _digest(data)

    def write(folder: Path) -> None:
        with atomic_path(folder / name) as tmp:
            tmp.write_bytes(data)
        with atomic_path(folder / f"{name}{DIGEST_SUFFIX}") as tmp:
            tmp.write_text(digest, encoding="ascii")

    with contextlib.suppress(OSError):
        in_store(write)


def _intact(folder: Path, key: str, name: str) -> Path | None:
    """The library ``name`` in ``folder`` if it is whole — its bytes' SHA-256 is the one
    written beside it (``<key>.sha256``) when it was compiled — else None: a truncated or
    damaged file (a full disk, a copy cut short) is compiled again instead of loaded (loading
    a truncated library can kill the process with a bus error).  A library found whole is
    marked used (:func:`mark_used`)."""
    lib = folder / name
    try:
        data = lib.read_bytes()
    except OSError:
        return None
    if not _matches(data, folder / f"{key}{DIGEST_SUFFIX}"):
        return None
    mark_used(lib)
    return lib


def _digest(data: bytes) -> str:
    """The text of the ``.sha256`` file kept beside a file of bytes ``data`` (a library, a
    text): their SHA-256 in hexadecimal, and a newline."""
    return hashlib.sha256(data).hexdigest() + "\n"


def _matches(data: bytes, digest: Path) -> bool | None:
    """Whether ``data`` has the SHA-256 that the file ``digest`` holds (:func:`_digest`);
    None when that file cannot be read (missing, or not ASCII)."""
    try:
        want = digest.read_text(encoding="ascii").strip()
    except (OSError, ValueError):
        return None
    return _digest(data).strip() == want


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
                   cc: Sequence[str] | None = None, name: str = "model.c",
                   shown: str | None = None, again: bool = False) -> Path:
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
    name : str, default "model.c"
        The source's file name where it is compiled (a temporary folder).
    shown : str, optional
        What a compiler failure calls the source (:func:`compile_c`): a kept copy's path, or
        by default ``name``, never the temporary folder's path.
    again : bool, default False
        The library the cache holds for ``source`` is damaged though its digest matches (it
        lacks what the source defines): compiled again, in its place.

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
    OSError
        Neither the cache folder nor the fallback folder could be written (:func:`in_store`).
    """
    command = list(cc) if cc is not None else find_compiler()
    key = cache_key(source, command, flags, libraries)
    lib_name = f"{key}{library_suffix()}"
    if not again:
        for folder in _lookup_folders():
            found = _intact(folder, key, lib_name)
            if found is not None:
                STATS["hits"] += 1
                return found

    def compile_into(folder: Path) -> Path:
        return _compile_into(folder, source, key, lib_name, command, flags, libraries,
                             name, shown or name, again)

    return in_store(compile_into)


def _compile_into(folder: Path, source: str, key: str, lib_name: str, command: list[str],
                  flags: Sequence[str], libraries: Sequence[str], name: str, shown: str,
                  again: bool) -> Path:
    """:func:`cached_library`'s compilation into ``folder``, under the lock ``<key>.lock``
    (removed again when the compilation failed and no library is there: no orphan lock).
    The compiler's own failure to write there (a full disk) is an ``OSError``."""
    lib = folder / lib_name
    lock = folder / f"{key}.lock"
    with file_lock(lock) as held:
        if not again and _intact(folder, key, lib_name) is not None:  # compiled meanwhile
            STATS["hits"] += 1
            return lib
        digest_name = f"{key}{DIGEST_SUFFIX}"
        damaged = None if again or not _is_file(lib) else (
            f"did not match {digest_name}" if _is_file(folder / digest_name) else
            f"had no {digest_name} beside it")
        try:
            with tempfile.TemporaryDirectory(dir=folder, prefix=f".{key[:16]}-") as tmp:
                try:
                    built = compile_c({name: source}, tmp, lib_name, command, flags,
                                      libraries, shown=shown)
                except CompileError as err:
                    full = next((code for code in _FULL if os.strerror(code) in err.output),
                                None)
                    if full is None:
                        raise
                    raise OSError(full, os.strerror(full), str(folder)) from None
                digest = Path(tmp) / digest_name
                digest.write_text(_digest(built.read_bytes()), encoding="ascii")
                try:
                    os.replace(built, lib)
                except OSError:
                    if not lib.is_file():  # a library in use cannot be replaced on Windows
                        raise
                os.replace(digest, folder / digest.name)
        except BaseException:
            # a waiting process then locks the file unlinked here, a later one a new file:
            # both may compile, which the atomic rename makes safe (as without fcntl)
            if held and not _is_file(lib):
                with contextlib.suppress(OSError):
                    lock.unlink()
            raise
    STATS["compiles"] += 1
    if damaged:
        _note(str(lib), f"feeddrive: {lib} {damaged} (damaged), so it was compiled again")
    return lib
