"""The sweep results store: one SQLite file (stdlib ``sqlite3``, WAL journal).

It extends :mod:`feeddrive.io.json_store` (the reproduce cache) rather than replacing it: the same
key — :func:`feeddrive.io.json_store.store_key` of the package version, the kernel hash
(:data:`feeddrive._jit.KERNEL_HASH`), a :func:`~feeddrive.io.json_store.code_hash` of the computing
code and the point's full inputs — and the same entry rule: each value is stored with the
SHA-256 of its payload and checked on every read; an entry that fails the check is reported
with a one-line notice and recomputed.  Only the container differs: reproduce keeps a dozen
studies as files (atomic rename), a sweep keeps thousands of points, written one at a time by
concurrent processes and queried for maps and exports, which is what a database is for
(docs/sweeps.md, "Why SQLite").

Guarantees:

* each finished point is committed at once, in its own transaction (``synchronous=FULL``):
  a ``SIGKILL`` loses at most the point being computed, never a finished one;
* ``results.key`` is the primary key: a point is stored once, whoever computes it; two sweeps
  writing to one store at once serialise on SQLite's lock (WAL: readers never block);
* a design point refers to its result by key (``points``), so points with identical inputs
  (a CDFS at two nut speeds, which it ignores; two sweeps sharing points) share one result;
* a point being computed is *claimed* (``claims``: its key, the claiming process and host,
  refreshed while it runs), so two sweeps on one store never compute a point twice: the
  second skips a point claimed by a live sweep and comes back to it at the end (taking it
  over if that sweep died: its process is gone, or, on another host, its claim was not
  refreshed for :data:`CLAIM_STALE` s);
* any SQLite failure (a full disk, a lock held past the timeout, a read-only journal) is a
  :class:`StoreFailure` (an ``OSError`` naming the store): the CLI prints it on one line;
  every point committed before it stays in the store.
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import json
import math
import os
import socket
import sqlite3
import time
import uuid
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any, TypeVar

from .. import __version__
from .._jit import KERNEL_HASH
from ..io.json_store import FORMAT, code_hash, store_key
from ..io.outputs import OutputError, shown

__all__ = ["CLAIM_STALE", "StoreError", "StoreFailure", "SweepStore", "point_key"]

#: [s] a claim from another host not refreshed for this long is taken over
CLAIM_STALE = 600.0
#: [s] how often a running sweep refreshes its claims
CLAIM_REFRESH = 60.0
_F = TypeVar("_F", bound=Callable[..., Any])

_HERE = Path(__file__).resolve().parent.parent
# the code that computes a point beyond the compiled kernels (KERNEL_HASH covers those)
_SOURCES = ("sweep/quantities.py", "analysis/critical.py", "analysis/cycle_verdict.py",
            "analysis/creep_window.py", "analysis/trace_input.py", "analysis/verdict_words.py",
            "analysis/linear.py", "engine/simulate.py", "engine/options.py", "model/reference.py",
            "analysis/protocol.py", "parameters/components.py", "parameters/toml_io.py",
            "model/mechanisms/ball_screw_stiffness.py")

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (name TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS results (
    key TEXT PRIMARY KEY, sha256 TEXT NOT NULL, payload TEXT NOT NULL,
    version TEXT NOT NULL, kernel TEXT NOT NULL, written REAL NOT NULL);
CREATE TABLE IF NOT EXISTS sweeps (
    name TEXT PRIMARY KEY, description TEXT NOT NULL, updated REAL NOT NULL);
CREATE TABLE IF NOT EXISTS points (
    sweep TEXT NOT NULL, idx INTEGER NOT NULL, key TEXT NOT NULL, coords TEXT NOT NULL,
    PRIMARY KEY (sweep, idx));
CREATE INDEX IF NOT EXISTS points_key ON points (key);
CREATE TABLE IF NOT EXISTS claims (
    key TEXT PRIMARY KEY, owner TEXT NOT NULL, host TEXT NOT NULL, pid INTEGER NOT NULL,
    since REAL NOT NULL);
"""


@functools.cache
def _schema_columns() -> dict[str, tuple[str, ...]]:
    """Each table of :data:`_SCHEMA` → its column names (read from the schema itself)."""
    db = sqlite3.connect(":memory:")
    try:
        db.executescript(_SCHEMA)
        names = [r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type = 'table'")]
        return {n: tuple(r[1] for r in db.execute(f"PRAGMA table_info({n})")) for n in names}
    finally:
        db.close()


class StoreError(OutputError):
    """The store cannot be used (not writable, not a store, another format)."""


class StoreFailure(OSError):
    """SQLite failed while the store was in use (disk full, lock timeout, I/O error);
    ``filename`` is the store, ``strerror`` SQLite's message."""


def _guarded(fn: _F) -> _F:
    """A :class:`SweepStore` method whose ``sqlite3.Error`` becomes a :class:`StoreFailure`."""

    @functools.wraps(fn)
    def wrapper(self: SweepStore, *args: Any, **kwargs: Any) -> Any:
        try:
            return fn(self, *args, **kwargs)
        except sqlite3.Error as err:
            raise StoreFailure(0, f"SQLite: {err}; every point stored before is kept",
                               os.fspath(self.path)) from None

    return wrapper  # type: ignore[return-value]


def _alive(host: str, pid: int, since: float) -> bool:
    """Whether the process holding a claim still runs (another host: refreshed lately)."""
    if host != socket.gethostname():
        return time.time() - since < CLAIM_STALE
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


@functools.cache
def _code_hash() -> str:
    return code_hash(_HERE / name for name in _SOURCES)


def point_key(task: Mapping[str, Any]) -> str:
    """The key of one point: :func:`feeddrive.io.json_store.store_key` of the version, kernel hash,
    code hash and the task (full parameter set as TOML, drive, position, nut speed,
    quantity settings).

    Parameters
    ----------
    task : mapping
        The point's task.

    Returns
    -------
    str
        The key (hex).
    """
    return store_key({"version": __version__, "kernel": KERNEL_HASH, "code": _code_hash(),
                      "task": dict(task)})


def _json(value: Any) -> str:
    """Canonical JSON; NaN is stored as null (JSON has no NaN)."""
    def clean(v: Any) -> Any:
        if isinstance(v, float) and not math.isfinite(v):
            return None
        if isinstance(v, dict):
            return {k: clean(x) for k, x in v.items()}
        if isinstance(v, list | tuple):
            return [clean(x) for x in v]
        return v
    return json.dumps(clean(value), sort_keys=True, separators=(",", ":"), allow_nan=False)


def _foreign_tables(db: sqlite3.Connection) -> str | None:
    """Why the SQLite file open in ``db`` is no feeddrive store (a table that is not the
    store's, or one of its names with other columns), or None."""
    ours = _schema_columns()
    tables = [r[0] for r in db.execute(
        "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'")]
    for name in tables:
        quoted = name.replace('"', '""')
        columns = tuple(r[1] for r in db.execute(f'PRAGMA table_info("{quoted}")'))
        if ours.get(name) != columns:
            listed = ", ".join(sorted(tables)[:5])
            return (f"not a feeddrive sweep store (an SQLite file with the tables "
                    f"{shown(listed, 100)})")
    return None


def check_existing_store(path: str | os.PathLike[str], option: str) -> None:
    """Refuse at once an existing file that is not a feeddrive store, read-only, before the
    work that would fill it (a text file given as ``--store`` was refused only when the
    store was opened, after a 10 000-point sweep had been built: 7 s; an outside check,
    2026-12-07).  A missing file passes (it is created later).

    Parameters
    ----------
    path : str or os.PathLike
        The store's file.
    option : str
        The option or key that named it, for the message.

    Raises
    ------
    StoreError
        For a file that is not an SQLite database, or one of other tables.
    """
    p = Path(path)
    if not p.is_file():
        return
    try:
        db = sqlite3.connect(f"{p.resolve().as_uri()}?mode=ro", uri=True, timeout=5.0)
    except sqlite3.Error:
        return  # unreadable here: opening the store says why
    try:
        foreign = _foreign_tables(db)
    except sqlite3.DatabaseError as err:
        foreign = f"not a feeddrive sweep store ({err})"
    finally:
        db.close()
    if foreign is not None:
        raise StoreError(f"{option} {shown(p)}: {foreign}")


class SweepStore:
    """Results by key and the sweeps that refer to them, in one SQLite file ``path``.

    ``option`` names the setting that gave the path (``store``, ``--store``) in messages;
    ``notice`` receives a one-line message for each stored entry found unusable.
    ``create``: a missing file is created (its folder must exist); else it is refused.

    Parameters
    ----------
    path : str or os.PathLike
        The SQLite file.
    option : str, default "store"
        The setting that gave the path, named in messages.
    create : bool, default True
        Create a missing file (its folder must exist).
    notice : callable, optional
        Receives a one-line message for each stored entry found unusable.

    Raises
    ------
    StoreError
        For a file that is not a store, of another format, or on a file system without
        SQLite's WAL journal.
    StoreFailure
        When SQLite cannot open it.
    """

    def __init__(self, path: str | os.PathLike[str], *, option: str = "store",
                 create: bool = True, notice: Callable[[str], None] | None = None) -> None:
        self.path = Path(path)
        self.option = option
        self.notice = notice
        self.owner = uuid.uuid4().hex
        self._refreshed = time.time()
        self._check_writable(create)
        try:
            self._db = sqlite3.connect(self.path, timeout=120.0, isolation_level=None)
            self._db.execute("PRAGMA busy_timeout = 120000")
            self._check_ours()  # before anything is written to it (WAL, the schema)
            mode = self._db.execute("PRAGMA journal_mode = WAL").fetchone()[0]
            self._db.execute("PRAGMA synchronous = FULL")
            self._write(lambda db: db.executescript(_SCHEMA) and None, script=True)
            fmt = self._db.execute("SELECT value FROM meta WHERE name = 'format'").fetchone()
            if fmt is None:
                self._write(lambda db: db.execute(
                    "INSERT OR IGNORE INTO meta VALUES ('format', ?)", (str(FORMAT),)))
            elif fmt[0] != str(FORMAT):
                raise self._error(f"store format {fmt[0]}, expected {FORMAT}")
        except sqlite3.OperationalError as err:
            raise StoreFailure(0, f"SQLite: {err}", os.fspath(self.path)) from None
        except sqlite3.DatabaseError as err:
            raise self._error(f"not a feeddrive sweep store ({err})") from None
        if mode.lower() != "wal":
            raise self._error(f"the file system does not support SQLite's WAL journal ({mode})")

    # ------------------------------------------------------------------ plumbing

    def _error(self, text: str) -> StoreError:
        return StoreError(f"{self.option} {shown(self.path)}: {text}")

    def _check_ours(self) -> None:
        """Refuse an SQLite file of something else: a table that is not the store's, or one
        of its names with other columns (``no such column: key`` was exit status 1, after
        the file had been switched to WAL; issue 39 item 7)."""
        foreign = _foreign_tables(self._db)
        if foreign is not None:
            self._db.close()
            raise self._error(foreign)

    def _check_writable(self, create: bool) -> None:
        p = self.path
        if p.is_dir():
            raise self._error("is a folder; expected a file name")
        if not p.exists():
            if not create:
                raise self._error("no such store")
            if not p.parent.is_dir():
                raise self._error(f"folder {shown(p.parent)} does not exist")
        # SQLite writes p and, beside it, p-wal and p-shm: the folder must be writable too
        probe = p.parent / f".{p.name}.probe-{os.getpid()}"
        try:
            if p.exists():
                with open(p, "r+b"):
                    pass
            fd = os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
            os.close(fd)
            os.unlink(probe)
        except OSError as err:
            raise self._error(f"cannot write here ({err.strerror or err})") from None

    def _write(self, fn: Callable[[sqlite3.Connection], Any], *, script: bool = False) -> Any:
        """Run ``fn`` in one write transaction (taken at once: BEGIN IMMEDIATE)."""
        if script:  # executescript commits by itself
            return fn(self._db)
        if self._db.in_transaction:
            # a write that Ctrl-C interrupted after its BEGIN and before its try (or inside
            # its ROLLBACK): nothing of it was committed; undone here, or this BEGIN fails
            # with "cannot start a transaction within a transaction"
            self._db.execute("ROLLBACK")
        self._db.execute("BEGIN IMMEDIATE")
        try:
            out = fn(self._db)
        except BaseException:
            if self._db.in_transaction:
                self._db.execute("ROLLBACK")
            raise
        self._db.execute("COMMIT")
        return out

    def close(self) -> None:
        """Close the database connection."""
        self._db.close()

    def __enter__(self) -> SweepStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _say(self, text: str) -> None:
        if self.notice is not None:
            self.notice(text)

    # ------------------------------------------------------------------ results

    @_guarded
    def put(self, key: str, value: Mapping[str, Any]) -> None:
        """Store ``value`` under ``key`` in its own committed transaction (a damaged entry
        of that key is replaced; an intact one is kept: the value is the same), releasing
        this store's claim on it.

        Parameters
        ----------
        key : str
            A point's store key (:func:`point_key`).
        value : mapping
            The point's result (JSON-serialisable).
        """
        payload = _json(value)
        digest = hashlib.sha256(payload.encode("utf-8")).hexdigest()

        def write(db: sqlite3.Connection) -> None:
            db.execute(
                "INSERT INTO results VALUES (?, ?, ?, ?, ?, ?) ON CONFLICT(key) DO UPDATE SET "
                "sha256 = excluded.sha256, payload = excluded.payload, "
                "written = excluded.written WHERE results.sha256 != excluded.sha256",
                (key, digest, payload, __version__, KERNEL_HASH, time.time()))
            db.execute("DELETE FROM claims WHERE key = ? AND owner = ?", (key, self.owner))

        self._write(write)

    # ------------------------------------------------------------------ claims

    @_guarded
    def claim(self, key: str) -> str:
        """Claim ``key`` for this store object: ``"stored"`` (an intact result is there),
        ``"busy"`` (claimed by a live sweep) or ``"mine"`` (claimed now, or a dead sweep's
        claim taken over).

        Parameters
        ----------
        key : str
            A point's store key (:func:`point_key`).

        Returns
        -------
        str
            ``"stored"``, ``"busy"`` or ``"mine"``.
        """

        def write(db: sqlite3.Connection) -> str:
            row = db.execute("SELECT sha256, payload FROM results WHERE key = ?",
                             (key,)).fetchone()
            if row is not None and hashlib.sha256(row[1].encode("utf-8")).hexdigest() \
                    == row[0]:
                return "stored"
            held = db.execute("SELECT owner, host, pid, since FROM claims WHERE key = ?",
                              (key,)).fetchone()
            if held is not None and held[0] != self.owner and _alive(held[1], held[2],
                                                                     held[3]):
                return "busy"
            db.execute("INSERT OR REPLACE INTO claims VALUES (?, ?, ?, ?, ?)",
                       (key, self.owner, socket.gethostname(), os.getpid(), time.time()))
            return "mine"

        result: str = self._write(write)
        return result

    @_guarded
    def refresh_claims(self, *, force: bool = False) -> None:
        """Mark this store's claims as alive (every ``CLAIM_REFRESH`` s at most).

        Parameters
        ----------
        force : bool, default False
            Refresh now, however recent the last refresh.
        """
        now = time.time()
        if force or now - self._refreshed >= CLAIM_REFRESH:
            self._refreshed = now
            self._write(lambda db: db.execute("UPDATE claims SET since = ? WHERE owner = ?",
                                              (now, self.owner)))

    @_guarded
    def release_claims(self, keys: Iterable[str] | None = None) -> None:
        """Drop this store's claims (on ``keys`` only, when given).

        Parameters
        ----------
        keys : iterable of str, optional
            The keys; all of this store's claims when omitted.
        """
        if keys is None:
            self._write(lambda db: db.execute("DELETE FROM claims WHERE owner = ?",
                                              (self.owner,)))
        else:
            wanted = [(k, self.owner) for k in keys]
            self._write(lambda db: db.executemany(
                "DELETE FROM claims WHERE key = ? AND owner = ?", wanted))

    def _decode(self, key: str, digest: str, payload: str) -> dict[str, Any] | None:
        if hashlib.sha256(payload.encode("utf-8")).hexdigest() != digest:
            self._say(f"{shown(self.path)}: entry {key[:16]}: checksum mismatch (edited or "
                      "damaged); recomputing")
            return None
        try:
            value = json.loads(payload)
        except ValueError:
            self._say(f"{shown(self.path)}: entry {key[:16]}: not valid JSON; recomputing")
            return None
        return value if isinstance(value, dict) else None

    @_guarded
    def get(self, key: str) -> dict[str, Any] | None:
        """The stored result of a key, or None when absent or damaged (a damaged one is noticed).

        Parameters
        ----------
        key : str
            A point's store key (:func:`point_key`).

        Returns
        -------
        dict or None
            The result.
        """
        row = self._db.execute("SELECT sha256, payload FROM results WHERE key = ?",
                               (key,)).fetchone()
        return None if row is None else self._decode(key, row[0], row[1])

    @_guarded
    def finished(self, keys: Iterable[str]) -> set[str]:
        """Those of ``keys`` with an intact stored result.

        Parameters
        ----------
        keys : iterable of str
            Store keys.

        Returns
        -------
        set of str
            The keys whose result is stored and intact.
        """
        wanted = set(keys)
        out = set()
        for key, digest, payload in self._db.execute("SELECT key, sha256, payload FROM results"):
            if key in wanted and self._decode(key, digest, payload) is not None:
                out.add(key)
        return out

    @_guarded
    def count(self) -> int:
        """Number of results in the store, over all sweeps.

        Returns
        -------
        int
            The count.
        """
        return int(self._db.execute("SELECT COUNT(*) FROM results").fetchone()[0])

    # ------------------------------------------------------------------ sweeps

    @_guarded
    def register(self, name: str, description: Mapping[str, Any],
                 points: Iterable[tuple[int, str, Mapping[str, Any]]],
                 count: int | None = None) -> None:
        """Record sweep ``name`` (its configuration, axes, quantity) and its design points
        ``(index, key, coordinates)``, replacing an earlier design of that name in one
        transaction.  Results are not touched: they are keyed by their inputs.  ``points``
        is read once, as it is written (a generator: never all in memory); ``count`` (how
        many it yields) lets an unchanged design be recognised without reading it.

        Parameters
        ----------
        name : str
            The sweep's name.
        description : mapping
            What ``feeddrive.sweep.executors.description`` records.
        points : iterable of (int, str, mapping)
            (index, key, coordinates) of every design point.
        count : int, optional
            How many ``points`` yields.
        """
        if count is None:
            points = list(points)
            count = len(points)
        text = _json(description)
        it = iter(points)
        first = next(it, None)
        rows = ((name, i, key, _json(coords))
                for i, key, coords in itertools.chain([first] if first else [], it))

        def write(db: sqlite3.Connection) -> None:
            old = db.execute("SELECT description FROM sweeps WHERE name = ?", (name,)).fetchone()
            if old is not None and old[0] == text and db.execute(
                    "SELECT COUNT(*) FROM points WHERE sweep = ?", (name,)).fetchone()[0] \
                    == count:
                # the same design; the same keys unless the code or version changed
                stored = db.execute("SELECT key FROM points WHERE sweep = ? AND idx = ?",
                                    (name, first[0] if first else 0)).fetchone()
                if first is None or (stored is not None and stored[0] == first[1]):
                    return
            db.execute("DELETE FROM points WHERE sweep = ?", (name,))
            db.execute("INSERT OR REPLACE INTO sweeps VALUES (?, ?, ?)", (name, text, time.time()))
            db.executemany("INSERT INTO points VALUES (?, ?, ?, ?)", rows)

        self._write(write)

    @_guarded
    def sweeps(self) -> list[str]:
        """Names of the sweeps registered in the store, oldest update first.

        Returns
        -------
        list of str
            The names.
        """
        return [r[0] for r in self._db.execute("SELECT name FROM sweeps ORDER BY updated")]

    @_guarded
    def description(self, name: str) -> dict[str, Any]:
        """What was recorded about a sweep at registration.

        Parameters
        ----------
        name : str
            The sweep's name.

        Returns
        -------
        dict
            The description (``feeddrive.sweep.executors.description``).

        Raises
        ------
        StoreError
            When no sweep of that name is registered.
        """
        row = self._db.execute("SELECT description FROM sweeps WHERE name = ?",
                               (name,)).fetchone()
        if row is None:
            known = ", ".join(self.sweeps()) or "none"
            raise self._error(f"no sweep named {name!r} (stored: {known})")
        value: dict[str, Any] = json.loads(row[0])
        return value

    @_guarded
    def point_keys(self, name: str, indices: Iterable[int]) -> dict[int, str]:
        """The keys registered for sweep ``name`` at ``indices`` (absent ones left out).

        Parameters
        ----------
        name : str
            The sweep's name.
        indices : iterable of int
            Design-point indices.

        Returns
        -------
        dict of int to str
            Index → key.
        """
        out = {}
        for i in indices:
            row = self._db.execute("SELECT key FROM points WHERE sweep = ? AND idx = ?",
                                   (name, i)).fetchone()
            if row is not None:
                out[i] = str(row[0])
        return out

    @_guarded
    def stored_count(self, name: str) -> int:
        """How many distinct results of sweep ``name``'s registered points are stored.

        Parameters
        ----------
        name : str
            The sweep's name.

        Returns
        -------
        int
            The count.
        """
        return int(self._db.execute(
            "SELECT COUNT(DISTINCT p.key) FROM points p JOIN results r ON r.key = p.key "
            "WHERE p.sweep = ?", (name,)).fetchone()[0])

    @_guarded
    def rows(self, name: str) -> list[tuple[int, str, dict[str, Any], dict[str, Any] | None]]:
        """(index, key, coordinates, result or None) of every design point of ``name``.

        Parameters
        ----------
        name : str
            The sweep's name.

        Returns
        -------
        list of tuple
            (index, key, coordinates, result or None), in design order.
        """
        self.description(name)
        out = []
        for idx, key, coords, digest, payload in self._db.execute(
                "SELECT p.idx, p.key, p.coords, r.sha256, r.payload FROM points p LEFT JOIN "
                "results r ON r.key = p.key WHERE p.sweep = ? ORDER BY p.idx", (name,)):
            value = None if payload is None else self._decode(key, digest, payload)
            out.append((idx, key, json.loads(coords), value))
        return out
