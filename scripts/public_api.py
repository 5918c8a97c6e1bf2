"""Record the public API of a commit: every public module of ``feeddrive`` and its public names
(JSON fixture for ``tests/unit/test_api_stability.py``).

    python scripts/public_api.py 7831378 tests/data/public_api_7831378.json

The commit's ``src/`` is unpacked with ``git archive`` into a temporary folder and imported by
this interpreter with that folder first on ``PYTHONPATH`` (the tree's dependencies must be
installed).  Regenerate only at a release tag (CHANGELOG.md, "API stability").

Public module: a module under ``feeddrive`` with no path component starting with ``_``, the
CLI's modules (``feeddrive.cli.*``: the CLI is the interface there) left out.  Public name of a
module: its ``__all__`` when it has one; otherwise every name not starting with ``_`` that is a
class or function defined in ``feeddrive``, or an upper-case constant.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

LIST = r'''
import importlib, inspect, json, pkgutil, sys, types, warnings
warnings.simplefilter("ignore")
import feeddrive

def public(module):
    if hasattr(module, "__all__"):
        return sorted(str(n) for n in module.__all__)
    out = []
    for name, obj in vars(module).items():
        if name.startswith("_") or isinstance(obj, types.ModuleType):
            continue
        if inspect.isclass(obj) or inspect.isfunction(obj) or callable(obj):
            if str(getattr(obj, "__module__", "")).startswith("feeddrive"):
                out.append(name)
        elif name.isupper() and name != "TYPE_CHECKING":
            out.append(name)
    return sorted(out)

modules = {"feeddrive": public(feeddrive)}
for info in pkgutil.walk_packages(feeddrive.__path__, "feeddrive."):
    parts = info.name.split(".")
    if any(p.startswith("_") for p in parts) or parts[1] == "cli":
        continue
    modules[info.name] = public(importlib.import_module(info.name))
json.dump({"feeddrive_file": feeddrive.__file__, "modules": modules}, sys.stdout)
'''


def surface(commit: str) -> dict[str, list[str]]:
    """Every public module of ``commit`` and its public names."""
    with tempfile.TemporaryDirectory() as tmp:
        archive = subprocess.run(["git", "archive", commit, "src"], cwd=ROOT, check=True,
                                 capture_output=True).stdout
        archive_path = Path(tmp) / "src.tar"
        archive_path.write_bytes(archive)
        with tarfile.open(archive_path) as tar:
            tar.extractall(tmp, filter="data")
        env = {**os.environ, "PYTHONPATH": str(Path(tmp) / "src"),
               "NUMBA_CACHE_DIR": str(Path(tmp) / "numba-cache")}
        done = subprocess.run([sys.executable, "-c", LIST], env=env, check=True,
                              capture_output=True, text=True, cwd=tmp)
        data = json.loads(done.stdout)
        assert data["feeddrive_file"].startswith(tmp), data["feeddrive_file"]
        modules: dict[str, list[str]] = data["modules"]
        return modules


def main() -> None:
    commit, out = sys.argv[1], Path(sys.argv[2])
    full = subprocess.run(["git", "rev-parse", commit], cwd=ROOT, check=True,
                          capture_output=True, text=True).stdout.strip()
    record = {"commit": full, "generated_by": "scripts/public_api.py",
              "modules": surface(commit)}
    out.write_text(json.dumps(record, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    names = sum(len(v) for v in record["modules"].values())
    print(f"{out}: {len(record['modules'])} modules, {names} names of {full[:7]}")


if __name__ == "__main__":
    main()
