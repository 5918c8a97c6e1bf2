"""What the package keeps in the user's cache, and pruning what is no longer used.

Two caches grow there (docs/c-backend.md, "The compiled-object cache"):

* **numba's**, one folder ``numba-<hash>`` per version of the package's kernels
  (:data:`feeddrive._jit.CACHE_DIR`, ≈ 40 MB each): a new version of feeddrive, or an edited
  kernel in a development install, starts a new folder and leaves the old one;
* **the C build's** (:func:`feeddrive.backends.c_cache.cache_folder`): one library per model
  structure and compiler (≈ 15–100 kB) with its ``<key>.sha256`` and empty ``<key>.lock``,
  the drivers' and models' translated texts (each with its ``<name>.sha256``, where it has
  one), the temporary folders of compilations that were killed before they finished and the
  partial files of writes cut short
  (:func:`feeddrive.io.outputs.atomic_path`).  When that folder cannot be written the C build
  uses ``<temporary folder>/feeddrive-c-<user id>``
  (:func:`feeddrive.backends.c_cache.fallback_folder`); it is listed and pruned as a part of
  its own when it exists, as is ``<temporary folder>/feeddrive-py-<user id>``, where numba's
  cache and the generated modules go when the user's cache cannot be written
  (:func:`feeddrive._jit.cache_dir`).

An entry is a numba folder, a library (its library file, ``.sha256`` and ``.lock`` together),
a text (with its ``.sha256``), or an unfinished compilation.  Only what the package writes is
an entry, known by its exact name (:func:`_c_kind`, :func:`_numba_folder`): a configured folder
may hold other things (``FEEDDRIVE_C_CACHE=~``), which are counted
(:attr:`CachePart.foreign`) and never touched.  Nothing is removed by the package on its own.
:func:`usage` says what there is; :func:`prune` removes what has not been used for
``older_than`` days: numba folders of *other* kernel versions (another installed version of
feeddrive that still uses its folder compiles it again, ≈ 30 CPU s, at its next run), C
libraries and texts (a library is marked used each day it is loaded,
:func:`feeddrive.backends.c_cache.cached_library`, and goes whole, by the age of its newest
file; one pruned and needed again is compiled in ≈ 0.4 CPU s; a ``.sha256`` whose library or
text is gone goes by its own age) and unfinished compilations older than an hour (among them a
``.lock`` whose library is not there: the leftover of a compilation that failed or was
killed).  The folder of the running version's numba kernels is never pruned.  What cannot be
removed is passed over and reported (:attr:`CacheReport.failed`), as is a folder that cannot
be read (:attr:`CacheReport.unread`).
"""

from __future__ import annotations

import functools
import hashlib
import math
import os
import re
import time
from dataclasses import dataclass
from pathlib import Path

from ._disk import DAY, PROBE_PREFIX, existing_private, user_cache_root

__all__ = ["CacheReport", "CachePart", "DEFAULT_AGE", "FALLBACK", "UNFINISHED_AGE",
           "fallback_unavailable", "numba_root", "prune", "usage"]

#: what :func:`prune` removes by default: not used for this many days [days]
DEFAULT_AGE = 30.0
#: a compilation's temporary folder (or a write's partial file) older than this is one that
#: was killed [s]
UNFINISHED_AGE = 3600.0

#: a name :func:`feeddrive.io.outputs.atomic_path` writes under, ``.STEM.XXXXXXXX.partial.EXT``
#: (``secrets.token_hex(4)``); a partial file is the package's when ``STEM.EXT`` is the name of
#: a text or of a text's digest
_PARTIAL = re.compile(r"\.(?P<stem>.+)\.[0-9a-f]{8}\.partial(?P<ext>\.[^.]+)?")
#: the texts :mod:`feeddrive.backends.c_engine` keeps: ``model-<hash>.c`` (``_model_text``, 24
#: hexadecimal digits) and ``driver-<use>-<hash>.json`` (``driver_unit``, 20 digits)
_TEXT = r"model-[0-9a-f]{24}\.c|driver-[a-z][a-z_]*-[0-9a-f]{20}\.json"
#: :mod:`tempfile`'s random part of a name: 8 of ``a-z0-9_``
_RANDOM = "[a-z0-9_]{8}"
#: the temporary folder of a compilation, ``.<first 16 digits of its key>-XXXXXXXX``
#: (:func:`feeddrive.backends.c_cache.cached_library`)
_COMPILING = re.compile(rf"\.[0-9a-f]{{16}}-{_RANDOM}")
#: the probe file of :func:`feeddrive._disk.writable`
_PROBE = re.compile(re.escape(PROBE_PREFIX) + _RANDOM)
#: a cache key (:func:`feeddrive.backends.c_cache.cache_key`): a SHA-256 in hexadecimal
_KEY = f"[0-9a-f]{{{2 * hashlib.sha256().digest_size}}}"
#: the parts' names
_THIS, _OTHERS = "numba, this version", "numba, other versions"
_C, _UNFINISHED = "C libraries and texts", "unfinished compilations"
_FALLBACK_C = "C libraries and texts (fallback folder, used when the cache cannot be written)"
_FALLBACK_UNFINISHED = "unfinished compilations (fallback folder)"
_FALLBACK_THIS = "numba, this version (fallback folder, used when the cache cannot be written)"
_FALLBACK_OTHERS = "numba, other versions (fallback folder)"
#: the fallback folders, as :func:`fallback_unavailable`'s line in ``feeddrive cache`` names them
FALLBACK = "fallback folders (used when the cache cannot be written)"


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
        (with their ``.sha256``) and lone ``.sha256`` files; unfinished compilations' folders,
        partial files and lone ``.lock`` files.
    size : int
        Bytes on disk [B].
    note : str or None, default None
        What is wrong with the folder (``"is not a folder: ..."``, ``"cannot be read: ..."``),
        on the first part of that folder; None when nothing is.
    foreign : int, default 0
        Files and folders in the folder that are not the package's (not named as it names what
        it writes there), on the first part of that folder: never entries, never removed.
    """

    name: str
    folder: Path
    entries: int
    size: int
    note: str | None = None
    foreign: int = 0


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
    unread : tuple of (Path, str), default ()
        The cache folders that could not be read, with why: nothing in them was looked at,
        so nothing was removed there.
    """

    removed: tuple[Path, ...]
    freed: int
    dry_run: bool
    entries: int
    failed: tuple[tuple[Path, str], ...] = ()
    unread: tuple[tuple[Path, str], ...] = ()


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


def _items(folder: Path) -> tuple[list[Path], str | None, str | None]:
    """What ``folder`` holds, sorted, what is wrong with it (None for a missing folder:
    nothing was cached yet), and why it could not be read, if it could not (a folder that can
    be listed but not searched, mode 0666 or 0444, counts: nothing in it can be looked at)."""
    try:
        items = sorted(folder.iterdir())
        if items:
            items[0].lstat()
    except FileNotFoundError:
        return [], None, None
    except NotADirectoryError:
        return [], "is not a folder: nothing can be cached there", None
    except OSError as err:
        why = err.strerror or str(err)
        return [], f"cannot be read: {why}", why
    return items, None, None


@functools.cache
def _c_names() -> dict[str, re.Pattern[str]]:
    """The names of the files the package keeps in the C folder, by kind: a library's three,
    ``<key><suffix>``, ``<key>.sha256`` and ``<key>.lock``; a text (:data:`_TEXT`) and its
    digest, ``<text>.sha256`` (:func:`feeddrive.backends.c_cache.keep_text`)."""
    from .backends.c_cache import DIGEST_SUFFIX, library_suffix

    digest = re.escape(DIGEST_SUFFIX)
    return {"library": re.compile(_KEY + re.escape(library_suffix())),
            "digest": re.compile(_KEY + digest),
            "lock": re.compile(_KEY + re.escape(".lock")),
            "text": re.compile(_TEXT),
            "text digest": re.compile(f"(?:{_TEXT}){digest}")}


def _c_kind(name: str) -> str | None:
    """What the package writes in the C folder under ``name``: ``"library"``, ``"digest"`` or
    ``"lock"`` (a library's files), ``"text"`` or ``"text digest"`` (a kept text and its
    SHA-256), ``"compiling"`` (a compilation's temporary folder), ``"partial"`` (the partial
    file of a text's or its digest's write, or a probe of :func:`feeddrive._disk.writable`);
    None for a name it never writes there: not its own.

    Parameters
    ----------
    name : str
        A file's or folder's name.

    Returns
    -------
    str or None
        The kind.
    """
    names = _c_names()
    kind = next((kind for kind, pattern in names.items() if pattern.fullmatch(name)), None)
    if kind is not None:
        return kind
    if _COMPILING.fullmatch(name):
        return "compiling"
    partial = _PARTIAL.fullmatch(name)
    whole = partial["stem"] + (partial["ext"] or "") if partial else ""
    if (partial and (names["text"].fullmatch(whole) or names["text digest"].fullmatch(whole))) \
            or _PROBE.fullmatch(name):
        return "partial"
    return None


def _numba_folder(name: str) -> bool:
    """Whether ``name`` is one of numba's folders as :mod:`feeddrive._jit` names them,
    ``numba-<hash of the kernels' sources>`` (:data:`feeddrive._jit.SOURCE_DIGEST`'s length
    in hexadecimal digits)."""
    from ._jit import SOURCE_DIGEST

    return re.fullmatch(f"numba-[0-9a-f]{{{len(SOURCE_DIGEST)}}}", name) is not None


#: one entry: its files (or its folder), the one it is named by first
_Entry = tuple[Path, ...]


def _c_entries(items: list[Path]) -> tuple[list[_Entry], list[_Entry]]:
    """The C folder's (libraries and texts, unfinished compilations), the package's alone
    (:func:`_c_kind`): a library's file, ``<key>.sha256`` and ``<key>.lock`` are one entry, as
    are a text and its ``.sha256``; a ``.sha256`` whose library or text is gone is one of its
    own; a compilation's temporary folder, a partial file and a ``.lock`` whose library is not
    there (left by a compilation that failed or was killed) are unfinished compilations."""
    kept: list[_Entry] = []
    unfinished: list[_Entry] = []
    libraries: dict[str, dict[str, Path]] = {}
    texts: dict[str, dict[str, Path]] = {}
    for p in items:
        kind = _c_kind(p.name)
        if kind == "compiling" and p.is_dir():
            unfinished.append((p,))
        elif kind == "partial" and p.is_file():
            unfinished.append((p,))
        elif kind in ("library", "digest", "lock") and p.is_file():
            libraries.setdefault(p.name.split(".", 1)[0], {})[kind] = p  # by its key
        elif kind == "text" and p.is_file():
            texts.setdefault(p.name, {})[kind] = p
        elif kind == "text digest" and p.is_file():
            texts.setdefault(p.name[:-len(p.suffix)], {})[kind] = p
    for files in libraries.values():
        if "library" in files:
            kept.append(tuple(files[r] for r in ("library", "digest", "lock") if r in files))
        else:  # orphans: each on its own
            kept += [(p,) for r, p in files.items() if r != "lock"]
            unfinished += [(p,) for r, p in files.items() if r == "lock"]
    for files in texts.values():
        kept.append(tuple(files[r] for r in ("text", "text digest") if r in files))
    return sorted(kept), sorted(unfinished)


@dataclass(frozen=True)
class _Part:
    """A part's entries; ``age`` says which cutoff of :func:`prune` applies (None: never
    pruned); ``note``, ``unread`` and ``foreign`` are its folder's, on the first part of it."""

    name: str
    folder: Path
    entries: list[_Entry]
    note: str | None
    age: str | None
    unread: str | None = None
    foreign: int = 0


def _numba_parts(folder: Path, this: str, others: str, current: str) -> list[_Part]:
    """A numba root's two parts: the running version's folder, and the other versions'."""
    items, note, unread = _items(folder)
    numba = [p for p in items if _numba_folder(p.name) and p.is_dir()]
    return [_Part(this, folder, [(p,) for p in numba if p.name == current], note, None, unread),
            _Part(others, folder, [(p,) for p in numba if p.name != current], None, "used")]


def _c_parts(folder: Path, c_name: str, unfinished_name: str) -> list[_Part]:
    """A C folder's two parts: libraries and texts, and unfinished compilations."""
    items, note, unread = _items(folder)
    kept, unfinished = _c_entries(items)
    return [_Part(c_name, folder, kept, note, "used", unread),
            _Part(unfinished_name, folder, unfinished, None, "unfinished")]


def _parts() -> list[_Part]:
    """Every part with its entries, in the order :func:`usage` gives them, the first part of
    each folder with the count of what is there but not the package's."""
    root, c_folder, current = numba_root(), _c_folder(), _current_numba()
    parts = [*_numba_parts(root, _THIS, _OTHERS, current),
             *_c_parts(c_folder, _C, _UNFINISHED)]
    py = existing_private("feeddrive-py")  # _jit's, when the user's cache is read-only
    if py is not None and not _same(py, root):
        parts += _numba_parts(py, _FALLBACK_THIS, _FALLBACK_OTHERS, current)
    fallback = existing_private("feeddrive-c")
    if fallback is not None and not _same(fallback, c_folder):
        parts += _c_parts(fallback, _FALLBACK_C, _FALLBACK_UNFINISHED)
    return _with_foreign(parts)


def _with_foreign(parts: list[_Part]) -> list[_Part]:
    """``parts``, the first of each folder counting what that folder holds that no part
    claims (neither an entry nor another part's folder: the C folder ``c`` inside the user's
    cache folder is numba's root's neighbour, not a stranger)."""
    claimed = {path for part in parts for entry in part.entries for path in entry}
    folders = [part.folder for part in parts]
    done: list[Path] = []
    out = []
    for part in parts:
        if any(_same(part.folder, f) or part.folder == f for f in done):
            out.append(part)
            continue
        done.append(part.folder)
        items = _items(part.folder)[0]
        foreign = [p for p in items if p not in claimed
                   and not any(p == f or _same(p, f) for f in folders)]
        out.append(_Part(part.name, part.folder, part.entries, part.note, part.age,
                         part.unread, len(foreign)))
    return out


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
        fallback folder when it exists (none when no temporary folder is usable:
        :func:`fallback_unavailable`).
    """
    return [CachePart(p.name, p.folder, len(p.entries),
                      sum(sum(_sizes(e)[0].values()) for e in p.entries), p.note, p.foreign)
            for p in _parts()]


def fallback_unavailable() -> str | None:
    """Why the fallback folders (``<temporary folder>/feeddrive-c-<user id>`` and
    ``feeddrive-py-<user id>``) cannot be looked at, when no temporary folder is usable (then
    :func:`usage` and :func:`prune` pass them over); None when one is.

    Returns
    -------
    str or None
        ``"no temporary folder is usable (…where tempfile looked…)"``, or None.
    """
    from ._disk import NoTemporaryFolder, temporary_folder

    try:
        temporary_folder()
    except NoTemporaryFolder as err:
        return f"no temporary folder is usable ({err.strerror})"
    return None


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

    Only the package's entries are looked at (:func:`_c_kind`, :func:`_numba_folder`): what
    else a folder holds is never removed.  An entry goes whole, by the newest modification
    time of its files: a library with its ``.sha256`` and ``.lock``, the library file first
    (if it cannot be removed, the others are kept).  What cannot be removed is passed over and
    reported in :attr:`CacheReport.failed`; a folder that cannot be read, in
    :attr:`CacheReport.unread`.

    Parameters
    ----------
    older_than : float, default :data:`DEFAULT_AGE`
        Age [days] (0: everything but the running version's numba folder); finite, ≥ 0.
    dry_run : bool, default False
        Only say what would be removed.

    Returns
    -------
    CacheReport
        What was (or would be) removed and its size, what could not be removed, and the
        folders that could not be read.

    Raises
    ------
    ParameterError
        For a negative or non-finite ``older_than``.
    """
    if not (isinstance(older_than, int | float) and math.isfinite(older_than)
            and older_than >= 0.0):
        from .parameters import ParameterError

        raise ParameterError("older_than", older_than, "expected a finite number of days ≥ 0")
    now = time.time()
    # the last write before which an entry goes (unfinished compilations by their own age,
    # whatever older_than says)
    cutoff = {"used": now - older_than * DAY, "unfinished": now - UNFINISHED_AGE}
    removed: list[Path] = []
    failed: list[tuple[Path, str]] = []
    unread: list[tuple[Path, str]] = []
    freed = entries = 0
    for part in _parts():
        if part.unread is not None:
            unread.append((part.folder, part.unread))
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
    return CacheReport(tuple(removed), freed, dry_run, entries, tuple(failed), tuple(unread))
