"""Record every shipped parameter set's values and packed parameter vectors (JSON fixture).

The compatibility test ``tests/unit/test_parameter_compat.py`` loads the same sources with the
current tree and compares them to this record.  It was generated on main at commit ec220f9
(the last tree with the fixed ball-screw ``DriveParameters`` record), with::

    python scripts/record_parameter_vectors.py tests/data/parameter_vectors_ec220f9.json

Sources: every registered preset; every TOML file under ``examples/`` that is a parameter
file; every ```` ```toml ```` block of ``docs/`` and ``README.md`` that loads (a block without
``extends`` is read on top of ``wang2021``, as the docs present them); every string constant
of ``tests/`` that contains ``extends =`` and loads.  For each set: every value by dotted path
(:func:`feeddrive.parameters.to_dict`, flattened) and, for each drive that assembles it, the
model's parameter-slot names and packed vector ``P`` (table at 0.4 m, nut locked, a constant
1 mm/s command).
"""

from __future__ import annotations

import ast
import json
import re
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
DRIVES = ("cdfs", "ddfs", "linear-motor", "rack-pinion")
TABLE_POSITION = 0.4  # [m]


def _flat(value: Any, prefix: str, out: dict[str, Any]) -> None:
    if isinstance(value, dict):
        for key, sub in value.items():
            _flat(sub, f"{prefix}.{key}" if prefix else key, out)
    elif isinstance(value, tuple | list):
        out[prefix] = [float(v) for v in value]
    else:
        out[prefix] = value


def sources() -> list[tuple[str, str | None, str | None, Path | None]]:
    """(key, preset name, TOML text, base folder) of every set to record."""
    from feeddrive import registry

    found: list[tuple[str, str | None, str | None, Path | None]] = []
    for name in registry.names(registry.PRESETS):
        found.append((f"preset:{name}", name, None, None))
    for path in sorted((ROOT / "examples").glob("*.toml")):
        found.append((f"file:{path.relative_to(ROOT)}", None, path.read_text(), path.parent))
    for doc in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]:
        text = doc.read_text(encoding="utf-8")
        for i, block in enumerate(re.findall(r"```toml\n(.*?)```", text, re.S)):
            if "extends" not in block:
                block = 'extends = "wang2021"\n' + block
            found.append((f"docs:{doc.relative_to(ROOT)}#{i}", None, block, doc.parent))
    for test in sorted((ROOT / "tests").rglob("*.py")):
        tree = ast.parse(test.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if (isinstance(node, ast.Constant) and isinstance(node.value, str)
                    and "extends =" in node.value and "\n" in node.value):
                found.append((f"tests:{test.relative_to(ROOT)}:{node.lineno}", None,
                              node.value, None))
    return found


def record() -> dict[str, Any]:
    try:  # the tree of the record (ec220f9), or the tree after the layout commit
        from feeddrive.control import ConstantSpeed  # type: ignore[import-not-found]
    except ImportError:
        from feeddrive.model.reference import ConstantSpeed
    from feeddrive.model.assemble import assemble
    from feeddrive.model.mechanisms import mechanism
    from feeddrive.parameters import ParameterError, loads, preset, to_dict

    sets: dict[str, Any] = {}
    for key, name, text, base in sources():
        try:
            params = preset(name) if name is not None else loads(text or "", base_dir=base)
        except (ParameterError, ValueError):
            continue  # not a parameter file (a sweep file, a deliberately bad example)
        values: dict[str, Any] = {}
        _flat(to_dict(params), "", values)
        vectors: dict[str, Any] = {}
        for drive in DRIVES:
            try:
                mechanism(drive).check(params, drive, TABLE_POSITION)
                model = assemble(params, drive, TABLE_POSITION, "locked",
                                 ConstantSpeed(1e-3))
            except (ParameterError, ValueError) as err:
                vectors[drive] = {"refused": str(err)}
                continue
            vectors[drive] = {"names": list(model.parameter_names),
                              "P": [float(v) for v in model.P]}
        sets[key] = {"text": text, "values": values, "vectors": vectors}
    return sets


def main(out: str) -> None:
    import subprocess

    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                            capture_output=True, text=True, check=True).stdout.strip()
    data = {"source": f"scripts/record_parameter_vectors.py at commit {commit} (main)",
            "table_position": TABLE_POSITION, "sets": record()}
    Path(out).write_text(json.dumps(data, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    print(f"{len(data['sets'])} parameter sets recorded in {out}")


if __name__ == "__main__":
    main(sys.argv[1])
