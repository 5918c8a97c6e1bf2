"""Two things every on-disk cache of the package needs, free of numba: the user's cache folder
and a lock between processes (the numba cache, :mod:`feeddrive._jit`, and the compiled-object
cache, :mod:`feeddrive.backends.c_cache`)."""

from __future__ import annotations

import contextlib
import os
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


@contextlib.contextmanager
def file_lock(path: str | os.PathLike[str]) -> Iterator[bool]:
    """An exclusive lock on the file ``path`` (made if missing) while the block runs, so that
    of two processes doing the same first work, the second waits for the first.

    Where ``fcntl`` is missing (Windows) or the lock file cannot be opened, nothing is locked
    and the block runs at once; callers stay correct without the lock (they write atomically),
    only the work may be done twice.

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
        yield False
        return
    with fh:
        _fcntl.flock(fh, _fcntl.LOCK_EX)
        try:
            yield True
        finally:
            _fcntl.flock(fh, _fcntl.LOCK_UN)
