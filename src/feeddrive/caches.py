"""What the package keeps in the user's cache, and pruning what is no longer used.

Two caches grow there (docs/c-backend.md, "The compiled-object cache"):

* **numba's**, one folder ``numba-<hash>`` per version of the package's kernels
  (:data:`feeddrive._jit.CACHE_DIR`, ≈ 40 MB each): a new version of feeddrive, or an edited
  kernel in a development install, starts a new folder and leaves the old one;
* **the C build's** (:func:`feeddrive.backends.c_cache.cache_folder`): one library per model
  structure and compiler (15–900 kB), the drivers' and models' translated texts, and the
  temporary folders of compilations that were killed before they finished.

Nothing is removed by the package on its own.  :func:`usage` says what there is;
:func:`prune` removes what has not been used for ``older_than`` days: numba folders of
*other* kernel versions (another installed version of feeddrive that still uses its folder
compiles it again, ≈ 30 CPU s, at its next run), C files (a library is marked used each day
it is loaded, :func:`feeddrive.backends.c_cache.cached_library`; one pruned and needed again
is compiled in ≈ 0.4 CPU s) and unfinished compilations older than an hour.  The folder of
the running version's numba kernels is never pruned.
"""

from __future__ import annotations

import math
import os
import shutil
import time
from dataclasses import dataclass
from pathlib import Path

from ._disk import DAY, user_cache_root

__all__ = ["CacheReport", "CachePart", "DEFAULT_AGE", "UNFINISHED_AGE", "numba_root",
           "prune", "usage"]

#: what :func:`prune` removes by default: not used for this many days [days]
DEFAULT_AGE = 30.0
#: a compilation's temporary folder older than this is one that was killed [s]
UNFINISHED_AGE = 3600.0


@dataclass(frozen=True)
class CachePart:
    """One part of the caches: what it is, where, and how much.

    Parameters
    ----------
    name : str
        ``"numba, this version"``, ``"numba, other versions"``, ``"C libraries and texts"``
        or ``"unfinished compilations"``.
    folder : Path
        Where it lives.
    entries : int
        Folders (numba, unfinished compilations) or files (C).
    size : int
        Bytes on disk [B].
    """

    name: str
    folder: Path
    entries: int
    size: int


@dataclass(frozen=True)
class CacheReport:
    """What :func:`prune` removed (or, with ``dry_run``, would remove).

    Parameters
    ----------
    removed : tuple of Path
        The folders and files.
    freed : int
        Their size [B].
    dry_run : bool
        Nothing was removed.
    """

    removed: tuple[Path, ...]
    freed: int
    dry_run: bool


def numba_root() -> Path:
    """The folder holding numba's ``numba-<hash>`` folders: ``$NUMBA_CACHE_DIR``, else the
    user's cache (:func:`feeddrive._disk.user_cache_root`), as :mod:`feeddrive._jit` reads it.

    Returns
    -------
    Path
        The folder (it may not exist).
    """
    return Path(os.environ.get("NUMBA_CACHE_DIR") or user_cache_root())


def _footprint(path: Path) -> tuple[int, float]:
    """(bytes, newest modification time [s since epoch]) of a file, or of every file under a
    folder and the folder itself, in one walk (links not followed)."""
    stat = path.lstat()
    if not path.is_dir() or path.is_symlink():
        return stat.st_size, stat.st_mtime
    size, newest = 0, stat.st_mtime
    for p in path.rglob("*"):
        stat = p.lstat()
        newest = max(newest, stat.st_mtime)
        if not p.is_dir():
            size += stat.st_size
    return size, newest


def _current_numba() -> str:
    from ._jit import SOURCE_DIGEST

    return f"numba-{SOURCE_DIGEST}"


def _c_folder() -> Path:
    from .backends.c_cache import cache_folder

    return cache_folder()


def _listing() -> dict[str, list[Path]]:
    """The entries of each part, by :class:`CachePart` name."""
    root, c_folder, current = numba_root(), _c_folder(), _current_numba()
    numba = sorted(p for p in root.glob("numba-*") if p.is_dir()) if root.is_dir() else []
    c_all = sorted(c_folder.iterdir()) if c_folder.is_dir() else []
    return {
        "numba, this version": [p for p in numba if p.name == current],
        "numba, other versions": [p for p in numba if p.name != current],
        "C libraries and texts": [p for p in c_all if not p.name.startswith(".")
                                  and p.is_file()],
        "unfinished compilations": [p for p in c_all if p.name.startswith(".")
                                    and p.is_dir()],
    }


def usage() -> list[CachePart]:
    """What the caches hold, part by part.

    Returns
    -------
    list of CachePart
        The four parts, in the order of :class:`CachePart`'s names.
    """
    root, c_folder = numba_root(), _c_folder()
    return [CachePart(name, root if name.startswith("numba") else c_folder, len(entries),
                      sum(_footprint(p)[0] for p in entries))
            for name, entries in _listing().items()]


def prune(older_than: float = DEFAULT_AGE, *, dry_run: bool = False) -> CacheReport:
    """Remove what the caches hold that has not been used for ``older_than`` days (see the
    module): numba folders of other kernel versions, C libraries and texts, and unfinished
    compilations older than :data:`UNFINISHED_AGE` (whatever ``older_than``: a compilation
    takes a second, so one that old was killed).

    Parameters
    ----------
    older_than : float, default :data:`DEFAULT_AGE`
        Age [days] (0: everything but the running version's numba folder); ≥ 0.
    dry_run : bool, default False
        Only say what would be removed.

    Returns
    -------
    CacheReport
        What was (or would be) removed and its size.

    Raises
    ------
    ParameterError
        For a negative or non-finite ``older_than``.
    """
    if not (isinstance(older_than, int | float) and math.isfinite(older_than)
            and older_than >= 0.0):
        from .parameters import ParameterError

        raise ParameterError("older_than", older_than, "expected a number of days ≥ 0")
    now = time.time()
    limit = now - older_than * DAY
    parts = _listing()
    # the last write before which an entry goes (unfinished compilations by their own age,
    # whatever older_than says); each entry walked once for its size and its last write
    cutoff = {"numba, other versions": limit, "C libraries and texts": limit,
              "unfinished compilations": now - UNFINISHED_AGE}
    removed: list[Path] = []
    freed = 0
    for part, before in cutoff.items():
        for path in parts[part]:
            try:
                size, written = _footprint(path)
                if written > before:
                    continue
                if not dry_run:
                    if path.is_dir() and not path.is_symlink():
                        shutil.rmtree(path)
                    else:
                        path.unlink()
            except FileNotFoundError:  # another process removed it meanwhile
                continue
            removed.append(path)
            freed += size
    return CacheReport(tuple(removed), freed, dry_run)
