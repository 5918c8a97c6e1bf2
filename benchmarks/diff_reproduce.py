"""Compare two ``feeddrive reproduce`` output folders entry by entry, number by number.

Run from the repository root::

    python benchmarks/diff_reproduce.py BASE NEW [--json OUT.json] [--quiet-path KEY ...]

Every stored study (``DIR/data/<name>-<key16>.json``, :class:`feeddrive.io.json_store.ResultStore`
entries; the key differs between code versions, so entries are matched by ``<name>``) is read
and its payload compared recursively:

* numbers: exact match, or the difference with its relative size |new − base| / |base|
  (the absolute difference when base is 0);
* strings, booleans, None: exact match;
* lists: element by element; a list of dicts that all have a ``"speed"`` key (the trials
  of a search) is matched by speed, so a trial added or dropped is listed as such and the
  others are still compared;
* dicts: key by key (a key missing on one side is listed).

Long numeric lists (traces) are summarised per path: how many elements differ and the
largest relative difference.  Paths named with ``--quiet-path`` (by default
``simulated_time_s``, each search's simulated seconds, which a faster search is meant to
change) are reported apart as diagnostics, not as changed entries.

Prints one line per entry (identical / changed: N numbers, max rel …) then the differences,
and exits with status 1 if any entry differs (0 if all are identical).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from pathlib import Path
from typing import Any

_ENTRY = re.compile(r"^(?P<name>.+)-[0-9a-f]{16}\.json$")
TRACE_LENGTH = 32  # numeric lists at least this long are summarised, not listed


def load(folder: Path) -> dict[str, Any]:
    """The stored studies of a reproduce folder by name.

    Parameters
    ----------
    folder : Path
        The ``--out`` folder of a reproduce run (or its ``data`` subfolder).

    Returns
    -------
    dict
        Entry name → payload (JSON).
    """
    data = folder / "data" if (folder / "data").is_dir() else folder
    out: dict[str, Any] = {}
    for p in sorted(data.glob("*.json")):
        m = _ENTRY.match(p.name)
        if m is None or p.name.startswith("."):
            continue
        raw = p.read_bytes()
        out[m.group("name")] = json.loads(raw.partition(b"\n")[2])
    return out


def _rel(a: float, b: float) -> float:
    if a == b:
        return 0.0
    if not (math.isfinite(a) and math.isfinite(b)):
        return math.inf if not (math.isnan(a) and math.isnan(b)) else 0.0
    return abs(b - a) / abs(a) if a != 0 else abs(b - a)


def _is_num(x: Any) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool)


class Diff:
    """The differences found between two payloads (paths, base and new value, relative size)."""

    def __init__(self) -> None:
        self.items: list[tuple[str, Any, Any, float | None]] = []
        self.numbers = 0

    def add(self, path: str, a: Any, b: Any, rel: float | None = None) -> None:
        self.items.append((path, a, b, rel))

    def compare(self, a: Any, b: Any, path: str = "") -> None:
        if _is_num(a) and _is_num(b):
            self.numbers += 1
            fa, fb = float(a), float(b)
            if not (fa == fb or (math.isnan(fa) and math.isnan(fb))):
                self.add(path, a, b, _rel(fa, fb))
            return
        if isinstance(a, dict) and isinstance(b, dict):
            for k in sorted(set(a) | set(b), key=str):
                if k not in a:
                    self.add(f"{path}.{k}", "<absent>", _short(b[k]))
                elif k not in b:
                    self.add(f"{path}.{k}", _short(a[k]), "<absent>")
                else:
                    self.compare(a[k], b[k], f"{path}.{k}")
            return
        if isinstance(a, list) and isinstance(b, list):
            if _by_speed(a) and _by_speed(b):
                sa = {round(float(t["speed"]), 9): t for t in a}
                sb = {round(float(t["speed"]), 9): t for t in b}
                for s in sorted(set(sa) | set(sb)):
                    p = f"{path}[speed={s:g}]"
                    if s not in sa:
                        self.add(p, "<absent>", _short(sb[s]))
                    elif s not in sb:
                        self.add(p, _short(sa[s]), "<absent>")
                    else:
                        self.compare(sa[s], sb[s], p)
                return
            if (len(a) >= TRACE_LENGTH or len(b) >= TRACE_LENGTH) and all(map(_is_num, a)) \
                    and all(map(_is_num, b)):
                n = min(len(a), len(b))
                self.numbers += n
                rels = [_rel(float(x), float(y)) for x, y in zip(a[:n], b[:n], strict=True)]
                differ = [r for r in rels if r != 0.0]
                if differ or len(a) != len(b):
                    self.add(f"{path}[{len(a)}→{len(b)} samples]",
                             f"{len(differ)} of {n} differ", "",
                             max(differ) if differ else None)
                return
            if len(a) != len(b):
                self.add(f"{path}[len]", len(a), len(b))
            for i, (x, y) in enumerate(zip(a, b, strict=False)):
                self.compare(x, y, f"{path}[{i}]")
            return
        if a != b:
            self.add(path, _short(a), _short(b))


def _by_speed(x: list[Any]) -> bool:
    return bool(x) and all(isinstance(t, dict) and _is_num(t.get("speed")) for t in x)


def _short(x: Any, limit: int = 100) -> str:
    text = json.dumps(x) if not isinstance(x, str) else x
    return text if len(text) <= limit else text[:limit - 1] + "…"


def main(argv: list[str] | None = None) -> int:
    """Compare two reproduce folders; prints the result.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments (``sys.argv[1:]`` when omitted).

    Returns
    -------
    int
        0 when every entry is identical, 1 otherwise.
    """
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("base", type=Path)
    ap.add_argument("new", type=Path)
    ap.add_argument("--json", type=Path, help="also write the differences as JSON here")
    ap.add_argument("--quiet-path", action="append", default=None,
                    help="a key whose differences are diagnostics (default simulated_time_s)")
    args = ap.parse_args(argv)
    quiet = set(args.quiet_path or ["simulated_time_s"])
    base, new = load(args.base), load(args.new)
    report: dict[str, Any] = {}
    changed = 0
    for name in sorted(set(base) | set(new)):
        if name not in base or name not in new:
            print(f"{name}: only in {'new' if name in new else 'base'}")
            report[name] = {"status": "missing"}
            changed += 1
            continue
        d = Diff()
        d.compare(base[name], new[name])
        noisy = [it for it in d.items if it[0].rsplit(".", 1)[-1] not in quiet]
        diag = [it for it in d.items if it[0].rsplit(".", 1)[-1] in quiet]
        rels = [it[3] for it in noisy if it[3] is not None]
        if noisy:
            changed += 1
            worst = f", max rel {max(rels):.3g}" if rels else ""
            print(f"{name}: CHANGED ({len(noisy)} of {d.numbers} numbers/fields differ{worst})")
        else:
            print(f"{name}: identical ({d.numbers} numbers)"
                  + (f"; diagnostics differ: {len(diag)}" if diag else ""))
        for path, a, b, rel in [*noisy, *diag]:
            tag = " [diagnostic]" if (path, a, b, rel) in diag else ""
            size = "" if rel is None else f"  (rel {rel:.3g})"
            print(f"    {path}: {a} → {b}{size}{tag}")
        report[name] = {"status": "changed" if noisy else "identical", "numbers": d.numbers,
                        "differences": [{"path": p, "base": a, "new": b, "rel": r,
                                         "diagnostic": (p, a, b, r) in diag}
                                        for p, a, b, r in d.items]}
    total = len(set(base) | set(new))
    print(f"\n{total - changed} of {total} entries identical, {changed} changed")
    if args.json:
        args.json.write_text(json.dumps(report, indent=1, default=str) + "\n")
    return 1 if changed else 0


if __name__ == "__main__":
    sys.exit(main())
