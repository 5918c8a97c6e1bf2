"""What every on-disk cache of the package needs, free of numba: the user's cache folder, a
private folder for when that one cannot be written, and a lock between processes (the numba
cache, :mod:`feeddrive._jit`, and the compiled-object cache,
:mod:`feeddrive.backends.c_cache`)."""

from __future__ import annotations

import atexit
import contextlib
import errno
import functools
import os
import shutil
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path

try:
    import fcntl as _fcntl
except ImportError:  # pragma: no cover - not on Windows
    _fcntl = None  # type: ignore[assignment]

#: whether :func:`file_lock` locks (POSIX ``fcntl.flock``); elsewhere it does nothing
LOCKS = _fcntl is not None
#: a day [s]: a cached file loaded this long after its last mark is marked used again
#: (:func:`feeddrive.backends.c_cache.mark_used`), and the unit of ``feeddrive cache --prune``
DAY = 86400.0
#: the start of the name of the file :func:`writable` makes and removes at once
#: (``.probe-XXXXXXXX``; one is left only by a process killed in between)
PROBE_PREFIX = ".probe-"


def user_cache_root() -> Path:
    """The package's folder in the user's cache: ``$XDG_CACHE_HOME/feeddrive``, else
    ``~/.cache/feeddrive`` (on every system, as numba's cache folder always was).

    Returns
    -------
    Path
        The folder (not created here).
    """
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(Path.home(), ".cache")
    return Path(base) / "feeddrive"


def private_folder(prefix: str) -> Path:
    """A folder under the system's temporary folder that this user alone can write, for a
    cache whose own folder cannot be written: ``<temporary folder>/<prefix>-<user id>``, made
    private (mode 0700) and kept between processes; if that name is taken by a folder that is
    not this user's own, private one (another user could plant files there), a temporary
    folder of this process instead — one per process and prefix, removed when it exits.

    Parameters
    ----------
    prefix : str
        The folder's name before the user id (``feeddrive-c``, ``feeddrive-py``).

    Returns
    -------
    Path
        The folder.

    Raises
    ------
    OSError
        Neither folder can be made (a full disk); :class:`NoTemporaryFolder` when no
        temporary folder is usable.
    """
    folder = private_path(prefix)
    try:
        folder.mkdir(mode=0o700, exist_ok=True)
        if _private(folder):
            return folder
    except OSError:
        pass
    return _own_folder(prefix)


def private_path(prefix: str) -> Path:
    """Where :func:`private_folder` keeps its folder between processes (not made here):
    ``<temporary folder>/<prefix>-<user id>``.

    Parameters
    ----------
    prefix : str
        The folder's name before the user id.

    Returns
    -------
    Path
        The path.
    """
    uid = os.getuid() if hasattr(os, "getuid") else 0
    return temporary_folder() / f"{prefix}-{uid}"


class NoTemporaryFolder(OSError):
    """No temporary folder is usable: none of ``$TMPDIR``, ``/tmp``, ``/var/tmp``,
    ``/usr/tmp`` and the working folder takes a file (:func:`tempfile.gettempdir`).  Not a
    ``FileNotFoundError``, as the one ``tempfile`` raises is (a command reports that as
    refused input): the environment failed, not the user's input."""


def temporary_folder() -> Path:
    """The system's temporary folder (:func:`tempfile.gettempdir`).

    Returns
    -------
    Path
        The folder.

    Raises
    ------
    NoTemporaryFolder
        None is usable; the message says where ``tempfile`` looked.
    """
    try:
        return Path(tempfile.gettempdir())
    except OSError as err:
        raise NoTemporaryFolder(errno.ENOENT, err.strerror or str(err)) from None


def _private(folder: Path) -> bool:
    """Whether ``folder`` is a folder of this user's that no one else can write (not a link)."""
    info = folder.lstat()
    return (stat.S_ISDIR(info.st_mode)
            and (not hasattr(os, "getuid") or info.st_uid == os.getuid())
            and not info.st_mode & (stat.S_IWGRP | stat.S_IWOTH))


def existing_private(prefix: str) -> Path | None:
    """:func:`private_path` if it is there as :func:`private_folder` would use it (a folder of
    this user's alone), else None: where a cache lister looks without making it.

    Parameters
    ----------
    prefix : str
        The folder's name before the user id.

    Returns
    -------
    Path or None
        The folder.
    """
    try:
        folder = private_path(prefix)
        return folder if _private(folder) else None
    except OSError:  # not there, or no temporary folder is usable (NoTemporaryFolder)
        return None


@functools.cache
def _own_folder(prefix: str) -> Path:
    """A temporary folder of this process, made once per prefix and removed when it exits."""
    folder = Path(tempfile.mkdtemp(prefix=f"{prefix}-", dir=temporary_folder()))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    return folder


def writable(folder: Path) -> bool:
    """Whether a file can be made in ``folder`` (made if missing) and the folder read back:
    tried, since ``os.access`` does not see read-only mounts (nor, for root, modes).  A folder
    that can be written but not listed (mode 0333) is not one: what is cached there could not
    be found again, nor listed and pruned by ``feeddrive cache``.

    Parameters
    ----------
    folder : Path
        The folder.

    Returns
    -------
    bool
        True if a file could be made there and the folder listed (:func:`unwritable_reason`
        says why not).
    """
    return unwritable_reason(folder) is None


def unwritable_reason(folder: Path) -> str | None:
    """Why :func:`writable` finds ``folder`` not writable, in a few words for a message
    (``"Read-only file system"``, ``"not a folder"``, ``"Permission denied"``, ``"cannot be
    read: Permission denied"``); None when it is writable (a file was made there and
    removed).

    Parameters
    ----------
    folder : Path
        The folder (made if missing).

    Returns
    -------
    str or None
        The reason, or None.
    """
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        return reason(err)
    try:
        with os.scandir(folder) as listing:
            next(listing, None)
    except OSError as err:
        return f"cannot be read: {reason(err)}"
    try:
        fd, probe = tempfile.mkstemp(dir=folder, prefix=PROBE_PREFIX)
    except OSError as err:
        return reason(err)
    os.close(fd)
    os.unlink(probe)
    return None


def reason(err: OSError) -> str:
    """A cache write's ``OSError`` in a few words for a message: ``"not a folder"`` for a
    folder's path that is a file or lies under one (``mkdir(exist_ok=True)`` raises
    ``FileExistsError`` only for what is not a folder), else its ``strerror`` (``"No space
    left on device"``, ``"Read-only file system"``), else its text.

    Parameters
    ----------
    err : OSError
        The error.

    Returns
    -------
    str
        The reason.
    """
    if isinstance(err, FileExistsError | NotADirectoryError):
        return "not a folder"
    return err.strerror or str(err)


class CacheUnwritable(OSError):
    """Neither a cache folder nor its fallback folder could be written: one line naming the
    cache folder (``filename``) and both reasons (:func:`unwritable_error`).  A class of its
    own, so that no ``errno`` makes it a ``FileNotFoundError`` (refused input, to a command)."""


def unwritable_error(what: str, cache: Path, first: str, other: Path | None,
                     err: OSError) -> CacheUnwritable:
    """The error of a write that neither a cache folder nor its fallback folder took.

    Parameters
    ----------
    what : str
        The cache, as a message names it (``"the C cache"``).
    cache : Path
        Its folder: the error's ``filename``.
    first : str
        Why the cache folder could not be written.
    other : Path or None
        The fallback folder, or None when it could not be made (``err`` says why).
    err : OSError
        Why the fallback failed (:class:`NoTemporaryFolder`: no temporary folder is usable).

    Returns
    -------
    CacheUnwritable
        ``err``'s ``errno``; the message is one line.
    """
    if isinstance(err, NoTemporaryFolder):
        tail = f"and no temporary folder is usable for its fallback ({reason(err)})"
    else:
        where = other if other is not None else err.filename  # the folder mkdir could not make
        tail = f"nor its fallback folder{f' {where}' if where else ''} ({reason(err)})"
    return CacheUnwritable(err.errno, f"{what} cannot be written ({first}), {tail}", str(cache))


@contextlib.contextmanager
def file_lock(path: str | os.PathLike[str]) -> Iterator[bool]:
    """An exclusive lock on the file ``path`` (made if missing) while the block runs, so that
    of two processes doing the same first work, the second waits for the first.

    Where ``fcntl`` is missing (Windows), the lock file cannot be opened or the file system
    does not lock (``flock`` fails: ``ENOLCK`` on some network and FUSE mounts, ``EOPNOTSUPP``,
    ``ENOSYS``), nothing is locked and the block runs at once; callers stay correct without
    the lock (they write atomically), only the work may be done twice.  Any ``OSError`` of
    the lock call counts, not only those three: the lock only saves work, so no failure of it
    is worth stopping a run for.

    Parameters
    ----------
    path : path-like
        The lock file.

    Yields
    ------
    bool
        Whether the lock is held.
    """
    if _fcntl is None:
        yield False
        return
    try:
        fh = open(path, "a")  # noqa: SIM115 (held across the yield)
    except OSError:
        fh = None
    if fh is None:  # yielded outside the handler: the block's own errors chain nothing
        yield False
        return
    with fh:
        try:
            _fcntl.flock(fh, _fcntl.LOCK_EX)
            locked = True
        except OSError:
            locked = False
        try:
            yield locked
        finally:
            if locked:
                with contextlib.suppress(OSError):  # closing the file releases it anyway
                    _fcntl.flock(fh, _fcntl.LOCK_UN)
