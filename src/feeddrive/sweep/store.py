"""The sweep results store: one SQLite file (stdlib ``sqlite3``, WAL journal).

It extends :mod:`feeddrive.store` (the reproduce cache) rather than replacing it: the same
key — :func:`feeddrive.store.store_key` of the package version, the kernel hash
(:data:`feeddrive._jit.KERNEL_HASH`), a :func:`~feeddrive.store.code_hash` of the computing
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
  (a CDFS at two nut speeds, which it ignores; two sweeps sharing points) share one result.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
import sqlite3
import time
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

from .. import __version__
from .._jit import KERNEL_HASH
from ..outputs import OutputError, shown
from ..store import FORMAT, code_hash, store_key

__all__ = ["SweepStore", "StoreError", "point_key"]

_HERE = Path(__file__).resolve().parent.parent
# the code that computes a point beyond the compiled kernels (KERNEL_HASH covers those)
_SOURCES = ("sweep/quantities.py", "analysis/critical.py", "analysis/metrics.py", "linear.py",
            "simulate.py", "control.py", "protocol.py", "parameters/components.py",
            "parameters/toml_io.py", "stiffness.py")

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
"""


class StoreError(OutputError):
    """The store cannot be used (not writable, not a store, another format)."""


@functools.cache
def _code_hash() -> str:
    return code_hash(_HERE / name for name in _SOURCES)


def point_key(task: Mapping[str, Any]) -> str:
    """The key of one point: :func:`feeddrive.store.store_key` of the version, kernel hash,
    code hash and the task (full parameter set as TOML, drive, position, nut speed,
    quantity settings)."""
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


class SweepStore:
    """Results by key and the sweeps that refer to them, in one SQLite file ``path``.

    ``option`` names the setting that gave the path (``store``, ``--store``) in messages;
    ``notice`` receives a one-line message for each stored entry found unusable.
    ``create``: a missing file is created (its folder must exist); else it is refused.
    """

    def __init__(self, path: str | os.PathLike[str], *, option: str = "store",
                 create: bool = True, notice: Callable[[str], None] | None = None) -> None:
        self.path = Path(path)
        self.option = option
        self.notice = notice
        self._check_writable(create)
        try:
            self._db = sqlite3.connect(self.path, timeout=120.0, isolation_level=None)
            self._db.execute("PRAGMA busy_timeout = 120000")
            mode = self._db.execute("PRAGMA journal_mode = WAL").fetchone()[0]
            self._db.execute("PRAGMA synchronous = FULL")
            self._write(lambda db: db.executescript(_SCHEMA) and None, script=True)
            fmt = self._db.execute("SELECT value FROM meta WHERE name = 'format'").fetchone()
            if fmt is None:
                self._write(lambda db: db.execute(
                    "INSERT OR IGNORE INTO meta VALUES ('format', ?)", (str(FORMAT),)))
            elif fmt[0] != str(FORMAT):
                raise self._error(f"store format {fmt[0]}, expected {FORMAT}")
        except sqlite3.DatabaseError as err:
            raise self._error(f"not a feeddrive sweep store ({err})") from None
        if mode.lower() != "wal":
            raise self._error(f"the file system does not support SQLite's WAL journal ({mode})")

    # ------------------------------------------------------------------ plumbing

    def _error(self, text: str) -> StoreError:
        return StoreError(f"{self.option} {shown(self.path)}: {text}")

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
        self._db.execute("BEGIN IMMEDIATE")
        try:
            out = fn(self._db)
        except BaseException:
            self._db.execute("ROLLBACK")
            raise
        self._db.execute("COMMIT")
        return out

    def close(self) -> None:
        self._db.close()

    def __enter__(self) -> SweepStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _say(self, text: str) -> None:
        if self.notice is not None:
            self.notice(text)

    # ------------------------------------------------------------------ results

    def put(self, key: str, value: Mapping[str, Any]) -> None:
        """Store ``value`` under ``key`` in its own committed transaction (a damaged entry
        of that key is replaced; an intact one is kept: the value is the same)."""
        payload = _json(value)
        digest = hashlib.sha256(payload.encode("utf-8")).hexdigest()
        self._write(lambda db: db.execute(
            "INSERT INTO results VALUES (?, ?, ?, ?, ?, ?) ON CONFLICT(key) DO UPDATE SET "
            "sha256 = excluded.sha256, payload = excluded.payload, written = excluded.written "
            "WHERE results.sha256 != excluded.sha256",
            (key, digest, payload, __version__, KERNEL_HASH, time.time())))

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

    def get(self, key: str) -> dict[str, Any] | None:
        row = self._db.execute("SELECT sha256, payload FROM results WHERE key = ?",
                               (key,)).fetchone()
        return None if row is None else self._decode(key, row[0], row[1])

    def finished(self, keys: Iterable[str]) -> set[str]:
        """Those of ``keys`` with an intact stored result."""
        wanted = set(keys)
        out = set()
        for key, digest, payload in self._db.execute("SELECT key, sha256, payload FROM results"):
            if key in wanted and self._decode(key, digest, payload) is not None:
                out.add(key)
        return out

    def count(self) -> int:
        return int(self._db.execute("SELECT COUNT(*) FROM results").fetchone()[0])

    # ------------------------------------------------------------------ sweeps

    def register(self, name: str, description: Mapping[str, Any],
                 points: Iterable[tuple[int, str, Mapping[str, Any]]]) -> None:
        """Record sweep ``name`` (its configuration, axes, quantity) and its design points
        ``(index, key, coordinates)``, replacing an earlier design of that name in one
        transaction.  Results are not touched: they are keyed by their inputs."""
        rows = [(name, i, key, _json(coords)) for i, key, coords in points]
        text = _json(description)

        def write(db: sqlite3.Connection) -> None:
            old = db.execute("SELECT description FROM sweeps WHERE name = ?", (name,)).fetchone()
            if old is not None and old[0] == text and db.execute(
                    "SELECT COUNT(*) FROM points WHERE sweep = ?", (name,)).fetchone()[0] \
                    == len(rows):
                return
            db.execute("DELETE FROM points WHERE sweep = ?", (name,))
            db.execute("INSERT OR REPLACE INTO sweeps VALUES (?, ?, ?)", (name, text, time.time()))
            db.executemany("INSERT INTO points VALUES (?, ?, ?, ?)", rows)

        self._write(write)

    def sweeps(self) -> list[str]:
        return [r[0] for r in self._db.execute("SELECT name FROM sweeps ORDER BY updated")]

    def description(self, name: str) -> dict[str, Any]:
        row = self._db.execute("SELECT description FROM sweeps WHERE name = ?",
                               (name,)).fetchone()
        if row is None:
            known = ", ".join(self.sweeps()) or "none"
            raise self._error(f"no sweep named {name!r} (stored: {known})")
        value: dict[str, Any] = json.loads(row[0])
        return value

    def rows(self, name: str) -> list[tuple[int, str, dict[str, Any], dict[str, Any] | None]]:
        """(index, key, coordinates, result or None) of every design point of ``name``."""
        self.description(name)
        out = []
        for idx, key, coords, digest, payload in self._db.execute(
                "SELECT p.idx, p.key, p.coords, r.sha256, r.payload FROM points p LEFT JOIN "
                "results r ON r.key = p.key WHERE p.sweep = ? ORDER BY p.idx", (name,)):
            value = None if payload is None else self._decode(key, digest, payload)
            out.append((idx, key, json.loads(coords), value))
        return out
