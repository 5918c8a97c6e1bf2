"""Issue 41 item 11: 19 modules of commit 7831378 (before the core-v3 work) no longer imported
and ``feeddrive.parameters`` had lost 14 classes, with no alias and no note.

``tests/data/public_api_7831378.json`` lists every public module and name of 7831378
(generated from that commit by ``scripts/public_api.py``; regenerated only at a release tag).
Each name must import from its old place: unchanged without a warning, moved with one
DeprecationWarning naming its new place (``feeddrive._compat``) and the very object found
there; only the internals of :data:`feeddrive._compat.REMOVED` are gone, and CHANGELOG.md
names every move and every removal."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from feeddrive import _compat

ROOT = Path(__file__).resolve().parents[2]
FIXTURE = json.loads((ROOT / "tests" / "data" / "public_api_7831378.json").read_text())
CHANGELOG = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")


def _removed(module: str, name: str) -> bool:
    return f"{module}.{name}" in _compat.REMOVED or module in _compat.REMOVED


def test_the_fixture_is_the_commit_before_core_v3() -> None:
    assert FIXTURE["commit"].startswith("7831378")
    # what the issue counted: 19 modules gone, 14 classes gone from feeddrive.parameters
    gone = [m for m in FIXTURE["modules"] if m in _compat.MOVED_MODULES]
    assert len(gone) == 19 and len(_compat.MOVED_NAMES["feeddrive.parameters"]) == 14


@pytest.mark.parametrize("module", sorted(FIXTURE["modules"]))
def test_every_name_of_7831378_imports_from_its_old_place(module: str) -> None:
    names = FIXTURE["modules"][module]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mod = importlib.import_module(module)  # importing a moved module does not warn
    problems = []
    for name in names:
        if _removed(module, name):
            continue
        target = _compat._target(module, name)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                value = getattr(mod, name)
            except AttributeError as err:
                problems.append(f"{module}.{name}: {err}")
                continue
        found = [w for w in caught if issubclass(w.category, DeprecationWarning)]
        short = module in _compat.SHORT_NAMES and (
            target is None or target[0] == _compat.MOVED_MODULES[module][0])
        if target is None or short:
            if found or caught:
                problems.append(f"{module}.{name}: unexpected warning {caught[0].message}")
            continue
        new_module, new_name = target
        if len(found) != 1 or f"moved to {new_module}.{new_name}" not in str(found[0].message):
            problems.append(f"{module}.{name}: expected one DeprecationWarning naming "
                            f"{new_module}.{new_name}, got {[str(w.message) for w in caught]}")
        elif found[0].filename != __file__:
            problems.append(f"{module}.{name}: the warning points at {found[0].filename}")
        if value is not getattr(importlib.import_module(new_module), new_name):
            problems.append(f"{module}.{name} is not {new_module}.{new_name}")
    assert not problems, problems


def test_from_import_of_a_moved_name_warns_at_the_caller() -> None:
    with pytest.warns(DeprecationWarning, match="feeddrive.parameters.LuGreParameters moved "
                      "to feeddrive.model.friction.lugre_parameters.LuGreParameters"):
        from feeddrive.parameters import LuGreParameters
    from feeddrive.model.friction.lugre_parameters import LuGreParameters as new

    assert LuGreParameters is new
    with pytest.warns(DeprecationWarning, match="feeddrive.stiffness.axial_stiffness moved"):
        from feeddrive.stiffness import axial_stiffness  # noqa: F401


def test_importing_the_old_short_names_keeps_the_documented_modules() -> None:
    """``import feeddrive.linear`` (a module at 7831378) must not replace ``feeddrive.linear``,
    the documented short name of feeddrive.analysis.linear."""
    code = ("import warnings; warnings.simplefilter('error')\n"
            "import feeddrive, feeddrive.linear, feeddrive.friction, feeddrive.simulate\n"
            "import feeddrive.analysis.linear as L, feeddrive.model.friction.stribeck as S\n"
            "from feeddrive.engine.simulate import simulate\n"
            "assert feeddrive.linear is L and feeddrive.friction is S, 'short names'\n"
            "assert feeddrive.simulate is simulate, 'simulate'\n"
            "from feeddrive.linear import loop_analysis\n"
            "print('ok')\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert done.stdout.strip() == "ok", done.stderr[-2000:]


def test_an_unknown_name_is_still_an_attribute_error() -> None:
    import feeddrive.parameters

    with pytest.raises(AttributeError, match="has no attribute 'NoSuchThing'"):
        _ = feeddrive.parameters.NoSuchThing
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("feeddrive.no_such_module")


def test_the_changelog_lists_every_move_and_removal() -> None:
    section = CHANGELOG.split("### Deprecated", 1)[1].split("\n### ", 1)[0]
    items = [" ".join(item.split()) for item in section.split("\n- ")]
    missing = []
    for old, (default, elsewhere) in _compat.MOVED_MODULES.items():
        item = next((i for i in items if i.startswith(f"`{old}` → `{default}`")), "")
        for name, where in elsewhere.items():
            if f"`{name}` → `{where.partition(':')[0]}`" not in item and not (
                    f"`{name}`" in item and f"→ `{where.partition(':')[0]}`" in item):
                missing.append(f"{old}.{name} → {where}")
        if not item:
            missing.append(old)
    for old, names in _compat.MOVED_NAMES.items():
        item = next((i for i in items if i.startswith(f"From `{old}`:")), "")
        for name, where in names.items():
            if f"`{name}`" not in item or f"`{where.partition(':')[0]}`" not in item:
                missing.append(f"{old}.{name} → {where}")
    removed = " ".join(CHANGELOG.split("### Removed", 1)[1].split("\n### ", 1)[0].split())
    missing += [f"removed {name}" for name in _compat.REMOVED if f"`{name}`" not in removed]
    assert not missing, missing
