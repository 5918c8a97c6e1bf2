"""What the package keeps in the user's cache, and pruning what is no longer used.

Two caches grow there (docs/c-backend.md, "The compiled-object cache"):

* **numba's**, one folder ``numba-<hash>`` per version of the package's kernels
  (:data:`feeddrive._jit.CACHE_DIR`, ≈ 40 MB each): a new version of feeddrive, or an edited
  kernel in a development install, starts a new folder and leaves the old one;
* **the C build's** (:func:`feeddrive.backends.c_cache.cache_folder`): one library per model
  structure and compiler (≈ 15–100 kB) with its ``<key>.sha256`` and empty ``<key>.lock``,
  the drivers' and models' translated texts, the temporary folders of compilations that were
  killed before they finished and the partial files of writes cut short
  (:func:`feeddrive.io.outputs.atomic_path`).  When that folder cannot be written the C build
  uses ``<temporary folder>/feeddrive-c-<user id>``
  (:func:`feeddrive.backends.c_cache.fallback_folder`); it is listed and pruned as a part of
  its own when it exists, as is ``<temporary folder>/feeddrive-py-<user id>``, where numba's
  cache and the generated modules go when the user's cache cannot be written
  (:func:`feeddrive._jit.cache_dir`).

An entry is a numba folder, a library (its library file, ``.sha256`` and ``.lock`` together),
a text, or an unfinished compilation.  Nothing is removed by the package on its own.
:func:`usage` says what there is; :func:`prune` removes what has not been used for
``older_than`` days: numba folders of *other* kernel versions (another installed version of
feeddrive that still uses its folder compiles it again, ≈ 30 CPU s, at its next run), C
libraries and texts (a library is marked used each day it is loaded,
:func:`feeddrive.backends.c_cache.cached_library`, and goes whole, by the age of its newest
file; one pruned and needed again is compiled in ≈ 0.4 CPU s; a ``.lock`` or ``.sha256``
whose library is gone goes by its own age) and unfinished compilations older than an hour.
The folder of the running version's numba kernels is never pruned.  What cannot be removed is
passed over and reported (:attr:`CacheReport.failed`).
"""

from __future__ import annotations

import math
import os
import re
import time
from dataclasses import dataclass
from pathlib import Path

from ._disk import DAY, existing_private, user_cache_root

__all__ = ["CacheReport", "CachePart", "DEFAULT_AGE", "UNFINISHED_AGE", "numba_root",
           "prune", "usage"]

#: what :func:`prune` removes by default: not used for this many days [days]
DEFAULT_AGE = 30.0
#: a compilation's temporary folder (or a write's partial file) older than this is one that
#: was killed [s]
UNFINISHED_AGE = 3600.0

#: the name :func:`feeddrive.io.outputs.atomic_path` writes under, ``.STEM.XXXXXXXX.partial.EXT``
_PARTIAL = re.compile(r"\..+\.[0-9a-f]{8}\.partial(\.[^.]+)?")
#: the parts' names
_THIS, _OTHERS = "numba, this version", "numba, other versions"
_C, _UNFINISHED = "C libraries and texts", "unfinished compilations"
_FALLBACK_C = "C libraries and texts (fallback folder, used when the cache cannot be written)"
_FALLBACK_UNFINISHED = "unfinished compilations (fallback folder)"
_FALLBACK_THIS = "numba, this version (fallback folder, used when the cache cannot be written)"
_FALLBACK_OTHERS = "numba, other versions (fallback folder)"


@dataclass(frozen=True)
class CachePart:
    """One part of the caches: what it is, where, and how much.

    Parameters
    ----------
    name : str
        ``"numba, this version"``, ``"numba, other versions"``, ``"C libraries and texts"``,
        ``"unfinished compilations"``, and, when the fallback folders exist,
        ``"numba, this version (fallback folder, used when the cache cannot be written)"``,
        ``"numba, other versions (fallback folder)"``,
        ``"C libraries and texts (fallback folder, used when the cache cannot be written)"``
        and ``"unfinished compilations (fallback folder)"``.
    folder : Path
        Where it lives.
    entries : int
        Numba folders; libraries (a library file with its ``.sha256`` and ``.lock``), texts
        and lone ``.lock``/``.sha256`` files; unfinished compilations' folders and partial
        files.
    size : int
        Bytes on disk [B].
    note : str or None, default None
        What is wrong with the folder (``"is not a folder: ..."``, ``"cannot be read: ..."``),
        on the first part of that folder; None when nothing is.
    """

    name: str
    folder: Path
    entries: int
    size: int
    note: str | None = None


@dataclass(frozen=True)
class CacheReport:
    """What :func:`prune` removed (or, with ``dry_run``, would remove), and what it could not.

    Parameters
    ----------
    removed : tuple of Path
        The folders and files (each file of a library's entry).
    freed : int
        Their size [B].
    dry_run : bool
        Nothing was removed.
    entries : int
        The entries they make (a library's files are one).
    failed : tuple of (Path, str), default ()
        What could not be removed, with why (``"Permission denied"``); the rest was removed.
    """

    removed: tuple[Path, ...]
    freed: int
    dry_run: bool
    entries: int
    failed: tuple[tuple[Path, str], ...] = ()


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
    stat_ = path.lstat()
    if not path.is_dir() or path.is_symlink():
        return stat_.st_size, stat_.st_mtime
    size, newest = 0, stat_.st_mtime
    for p in path.rglob("*"):
        stat_ = p.lstat()
        newest = max(newest, stat_.st_mtime)
        if not p.is_dir():
            size += stat_.st_size
    return size, newest


def _current_numba() -> str:
    from ._jit import SOURCE_DIGEST

    return f"numba-{SOURCE_DIGEST}"


def _c_folder() -> Path:
    from .backends.c_cache import cache_folder

    return cache_folder()


def _items(folder: Path) -> tuple[list[Path], str | None]:
    """What ``folder`` holds, sorted, and what is wrong with it (None for a missing folder:
    nothing was cached yet)."""
    try:
        return sorted(folder.iterdir()), None
    except FileNotFoundError:
        return [], None
    except NotADirectoryError:
        return [], "is not a folder: nothing can be cached there"
    except OSError as err:
        return [], f"cannot be read: {err.strerror or err}"


#: one entry: its files (or its folder), the one it is named by first
_Entry = tuple[Path, ...]


def _c_entries(items: list[Path]) -> tuple[list[_Entry], list[_Entry]]:
    """The C folder's (libraries and texts, unfinished compilations): a library's file,
    ``<key>.sha256`` and ``<key>.lock`` are one entry; a ``.lock`` or ``.sha256`` whose library
    is gone is one of its own, as is every other file; a folder or a partial file
    (:data:`_PARTIAL`) whose name starts with a dot is an unfinished compilation."""
    from .backends.c_cache import DIGEST_SUFFIX, library_suffix

    roles = (library_suffix(), DIGEST_SUFFIX, ".lock")  # in the order an entry lists them
    kept: list[_Entry] = []
    unfinished: list[_Entry] = []
    keys: dict[str, dict[str, Path]] = {}
    for p in items:
        if p.name.startswith("."):
            if p.is_dir() or (_PARTIAL.fullmatch(p.name) and p.is_file()):
                unfinished.append((p,))
            continue
        if not p.is_file():
            continue
        role = next((r for r in roles if p.name.endswith(r) and len(p.name) > len(r)), None)
        if role is None:
            kept.append((p,))
        else:
            keys.setdefault(p.name[:-len(role)], {})[role] = p
    for files in keys.values():
        if roles[0] in files:
            kept.append(tuple(files[r] for r in roles if r in files))
        else:  # orphans: each on its own
            kept += [(p,) for p in files.values()]
    return sorted(kept), unfinished


@dataclass(frozen=True)
class _Part:
    """A part's entries; ``age`` says which cutoff of :func:`prune` applies (None: never
    pruned)."""

    name: str
    folder: Path
    entries: list[_Entry]
    note: str | None
    age: str | None


def _parts() -> list[_Part]:
    """Every part with its entries, in the order :func:`usage` gives them."""
    root, c_folder, current = numba_root(), _c_folder(), _current_numba()
    items, note = _items(root)
    numba = [p for p in items if p.name.startswith("numba-") and p.is_dir()]
    c_items, c_note = _items(c_folder)
    c_kept, c_unfinished = _c_entries(c_items)
    parts = [_Part(_THIS, root, [(p,) for p in numba if p.name == current], note, None),
             _Part(_OTHERS, root, [(p,) for p in numba if p.name != current], None, "used"),
             _Part(_C, c_folder, c_kept, c_note, "used"),
             _Part(_UNFINISHED, c_folder, c_unfinished, None, "unfinished")]
    py = existing_private("feeddrive-py")  # _jit's, when the user's cache is read-only
    if py is not None and not _same(py, root):
        items, note = _items(py)
        numba = [p for p in items if p.name.startswith("numba-") and p.is_dir()]
        parts += [_Part(_FALLBACK_THIS, py, [(p,) for p in numba if p.name == current], note,
                        None),
                  _Part(_FALLBACK_OTHERS, py, [(p,) for p in numba if p.name != current], None,
                        "used")]
    fallback = existing_private("feeddrive-c")
    if fallback is not None and not _same(fallback, c_folder):
        items, note = _items(fallback)
        kept, unfinished = _c_entries(items)
        parts += [_Part(_FALLBACK_C, fallback, kept, note, "used"),
                  _Part(_FALLBACK_UNFINISHED, fallback, unfinished, None, "unfinished")]
    return parts


def _same(a: Path, b: Path) -> bool:
    """Whether two paths are one folder."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def _sizes(entry: _Entry) -> tuple[dict[Path, int], float]:
    """(size [B] of each of the entry's paths still there, newest modification time among
    them [s since epoch]; -inf if none is)."""
    sizes: dict[Path, int] = {}
    newest = -math.inf
    for path in entry:
        try:
            size, written = _footprint(path)
        except OSError:  # removed meanwhile by another process
            continue
        sizes[path] = size
        newest = max(newest, written)
    return sizes, newest


def usage() -> list[CachePart]:
    """What the caches hold, part by part.

    Returns
    -------
    list of CachePart
        The four parts, in the order of :class:`CachePart`'s names, and the two of the
        fallback folder when it exists.
    """
    return [CachePart(p.name, p.folder, len(p.entries),
                      sum(sum(_sizes(e)[0].values()) for e in p.entries), p.note)
            for p in _parts()]


def _remove(path: Path, failed: list[tuple[Path, str]]) -> bool:
    """Remove a file, or a folder and everything in it, carrying on past what cannot be
    removed: that is added to ``failed`` with why (a folder left not empty by it is not).
    Whether ``path`` was removed here (False too when another process removed it first)."""
    try:
        if path.is_dir() and not path.is_symlink():
            before = len(failed)
            for child in list(path.iterdir()):
                _remove(child, failed)
            if len(failed) > before:
                return False
            path.rmdir()
        else:
            path.unlink()
    except FileNotFoundError:  # another process removed it meanwhile
        return False
    except OSError as err:
        failed.append((path, err.strerror or str(err)))
        return False
    return True


def prune(older_than: float = DEFAULT_AGE, *, dry_run: bool = False) -> CacheReport:
    """Remove what the caches hold that has not been used for ``older_than`` days (see the
    module): numba folders of other kernel versions, C libraries and texts (in the C cache
    folder and in its fallback folder), and unfinished compilations older than
    :data:`UNFINISHED_AGE` (whatever ``older_than``: a compilation takes a second, so one that
    old was killed).

    An entry goes whole, by the newest modification time of its files: a library with its
    ``.sha256`` and ``.lock``, the library file first (if it cannot be removed, the others are
    kept).  What cannot be removed is passed over and reported in :attr:`CacheReport.failed`.

    Parameters
    ----------
    older_than : float, default :data:`DEFAULT_AGE`
        Age [days] (0: everything but the running version's numba folder); ≥ 0.
    dry_run : bool, default False
        Only say what would be removed.

    Returns
    -------
    CacheReport
        What was (or would be) removed and its size, and what could not be removed.

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
    # the last write before which an entry goes (unfinished compilations by their own age,
    # whatever older_than says)
    cutoff = {"used": now - older_than * DAY, "unfinished": now - UNFINISHED_AGE}
    removed: list[Path] = []
    failed: list[tuple[Path, str]] = []
    freed = entries = 0
    for part in _parts():
        if part.age is None:
            continue
        for entry in part.entries:
            sizes, written = _sizes(entry)
            if not sizes or written > cutoff[part.age]:
                continue
            gone = 0
            for path, size in sizes.items():  # the library file first
                before = len(failed)
                if dry_run or _remove(path, failed):
                    removed.append(path)
                    freed += size
                    gone += 1
                elif len(failed) > before:
                    if path.is_dir() and not path.is_symlink():  # removed in part
                        try:
                            freed += size - _footprint(path)[0]
                        except OSError:
                            pass
                    if path == entry[0] and len(entry) > 1:
                        break  # a library that stays keeps its .sha256 and .lock
            entries += gone > 0
    return CacheReport(tuple(removed), freed, dry_run, entries, tuple(failed))
