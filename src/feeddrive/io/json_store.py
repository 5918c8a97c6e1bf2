"""A small on-disk store of computed results (JSON) whose entries cannot lie.

Used by ``feeddrive reproduce`` to keep each finished study (``OUT/data/``) and meant for
any other long computation that is resumed after an interruption (parameter sweeps).
Guarantees:

* **keyed by what produced the value**: the key is a SHA-256 of the package version, a
  hash of the compiled kernels' sources, a hash of the computing code and the inputs (see
  :func:`store_key`), so a value from other code or other inputs is never reused;
* **atomic writes**: an entry is written to a temporary file with a unique name in the
  same folder, flushed to disk, then renamed over the entry (``os.replace``, through
  :func:`feeddrive.io.outputs.atomic_path`, the helper every output file uses), so a reader
  sees the old entry or the new one, never half of one, even with concurrent writers or a
  ``SIGKILL`` at any point;
* **checksummed**: each entry's first line is a header with its name, key and the SHA-256
  of the payload; an entry that is truncated, damaged or written for another key is not
  used: it is reported with a one-line notice and recomputed.  The checksum is *unkeyed*:
  it guards against accidents (a truncated write, a damaged disk, a careless edit), not
  against someone who edits an entry and recomputes its SHA-256 — such an entry is
  accepted, as is anything a user with write access to the folder puts there;
* **a folder in an entry's place** is reported with a one-line notice; the value is then
  recomputed on every run (the folder is never removed) until the folder is moved away.

Entry file ``<name>-<key16>.json``::

    {"feeddrive-store": 1, "name": ..., "key": <64 hex>, "sha256": <64 hex>}
    <payload JSON>
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

from .outputs import atomic_path, shown

__all__ = ["FORMAT", "ResultStore", "code_hash", "store_key"]

FORMAT = 1
_STALE_TEMP_SECONDS = 3600.0


def code_hash(paths: Iterable[str | os.PathLike[str]]) -> str:
    """SHA-256 (hex) of the contents of ``paths``, in the given order."""
    digest = hashlib.sha256()
    for p in paths:
        data = Path(p).read_bytes()
        digest.update(len(data).to_bytes(8, "little"))
        digest.update(data)
    return digest.hexdigest()


def store_key(parts: Mapping[str, Any]) -> str:
    """SHA-256 (hex) of ``parts`` (version, kernel hash, inputs …) as canonical JSON."""
    blob = json.dumps(parts, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(blob.encode("utf-8")).hexdigest()


class ResultStore:
    """JSON values by name under ``root``, for one key (see the module)."""

    def __init__(self, root: str | os.PathLike[str], key: str, *,
                 notice: Callable[[str], None] | None = None) -> None:
        self.root = Path(root)
        self.root.mkdir(parents=True, exist_ok=True)
        self.key = key
        self.notice = notice
        self._clean_stale_temporaries()

    def path(self, name: str) -> Path:
        return self.root / f"{name}-{self.key[:16]}.json"

    def _say(self, text: str) -> None:
        if self.notice is not None:
            self.notice(text)

    def get(self, name: str) -> Any | None:
        """The stored value, or None when absent or unusable (which is then noticed)."""
        p = self.path(name)
        try:
            raw = p.read_bytes()
        except FileNotFoundError:
            return None
        except IsADirectoryError:
            self._say(f"{shown(p)}: is a folder, not a store entry; recomputing (move the "
                      "folder away to keep the result)")
            return None
        except OSError as err:
            self._say(f"{p}: unreadable ({err.strerror or err}); recomputing")
            return None
        problem = self._check(raw, name)
        if problem is not None:
            self._say(f"{p}: {problem}; recomputing")
            return None
        return json.loads(raw.partition(b"\n")[2])

    def _check(self, raw: bytes, name: str) -> str | None:
        head, newline, body = raw.partition(b"\n")
        if not newline:
            return "truncated entry (no header line)"
        try:
            header = json.loads(head)
        except ValueError:
            return "not a store entry (bad header)"
        if not isinstance(header, dict) or header.get("feeddrive-store") != FORMAT:
            return "not a store entry of this format"
        if header.get("name") != name or header.get("key") != self.key:
            return "written for other inputs or another feeddrive version"
        if hashlib.sha256(body).hexdigest() != header.get("sha256"):
            return "checksum mismatch (truncated or edited)"
        try:
            json.loads(body)
        except ValueError:
            return "payload is not valid JSON"
        return None

    def put(self, name: str, value: Any) -> Any:
        """Store ``value`` atomically; returns it as a later :meth:`get` will (through
        JSON), so a first run and a rerun from the store compute from identical data."""
        body = json.dumps(value).encode("utf-8")
        header = json.dumps({"feeddrive-store": FORMAT, "name": name, "key": self.key,
                             "sha256": hashlib.sha256(body).hexdigest()}).encode("utf-8")
        target = self.path(name)
        if target.is_dir():  # noticed by get(); the value is used, not stored
            return json.loads(body)
        with atomic_path(target) as tmp:
            tmp.write_bytes(header + b"\n" + body)
        return json.loads(body)

    def get_or_compute(self, name: str, compute: Callable[[], Any]) -> Any:
        value = self.get(name)
        return self.put(name, compute()) if value is None else value

    def _clean_stale_temporaries(self) -> None:
        """Remove temporary files left by a killed writer (older than an hour)."""
        now = time.time()
        for tmp in [*self.root.glob(".*.tmp"), *self.root.glob(".*.partial.*")]:
            try:
                if now - tmp.stat().st_mtime > _STALE_TEMP_SECONDS:
                    tmp.unlink()
            except OSError:
                pass
