"""docs/parameters.md's "File layout" and "The parameters a run used" describe the code: the
section table is the registry's, the kind's parts are the Composition's, the named files and
commands exist (issue 19 items 1–2)."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

from feeddrive import registry
from feeddrive.model.friction import friction_law
from feeddrive.parameters import composition

ROOT = Path(__file__).resolve().parents[2]
DOC = (ROOT / "docs" / "parameters.md").read_text(encoding="utf-8")
LAYOUT = DOC.split("## File layout")[1].split("\n## ")[0]
SLOTS = DOC.split("## The parameters a run used")[1].split("\n## ")[0]


def test_the_section_table_is_the_registrys():
    rows = re.findall(r"^\| `(\w+)` \| `(\w+)` \| `([\w.]+)` \|$", LAYOUT, re.M)
    assert rows
    sections = registry.table(registry.SECTIONS)
    assert {name for name, _, _ in rows} == set(sections)
    for name, cls, module in rows:
        assert sections[name] is getattr(importlib.import_module(module), cls), name


def test_the_kind_and_its_parts_are_the_compositions():
    assert set(registry.names(registry.MECHANISM_KINDS)) == {"ball-screw"}
    kind = composition("ball-screw")
    needs = LAYOUT.split("It needs ")[1].split(", and gives")[0]
    assert re.findall(r"`(\w+)`", needs) == list(kind.required)
    gives = LAYOUT.split("gives\n")[1].split(" their defaults")[0] if "gives\n" in LAYOUT \
        else LAYOUT.split(", and gives ")[1].split(" their defaults")[0]
    assert re.findall(r"`(\w+)`", gives) == [name for name, _ in kind.defaults]


def test_the_law_classes_are_the_laws():
    from feeddrive.model.friction.gms import GMSParameters
    from feeddrive.model.friction.lugre_parameters import LuGreParameters

    for law in ("lugre", "stribeck", "dahl", "none"):
        assert f"`{law}`" in LAYOUT
        assert friction_law(law).parameters_class is LuGreParameters
    assert friction_law("gms").parameters_class is GMSParameters


def test_the_named_files_commands_and_names_exist():
    for path in ("tests/unit/test_parameter_compat.py", "tests/data/parameter_vectors_ec220f9.json",
                 "scripts/record_parameter_vectors.py"):
        assert path in LAYOUT and (ROOT / path).is_file(), path
    assert "params upgrade" in LAYOUT  # the decision: none is needed, said so
    from feeddrive.cli.params_cmd import slots
    from feeddrive.engine.result import Result
    from feeddrive.model import slots as slots_module

    assert callable(slots) and "feeddrive params slots --drive" in SLOTS
    assert "DERIVED_UNITS" in SLOTS and hasattr(slots_module, "DERIVED_UNITS")
    assert "packed_vector" in SLOTS and hasattr(slots_module, "packed_vector")
    assert isinstance(Result.parameter_slots, property)


def test_the_presets_table_lists_every_shipped_preset():
    """docs/parameters.md's Presets table and the README's count name every preset the
    package ships (an outside check, 2026-12-07: the README said two shipped and the table
    left out rack-pinion-example)."""
    from feeddrive.presets import PRESETS

    doc = (ROOT / "docs" / "parameters.md").read_text(encoding="utf-8")
    section = doc.split("## Presets", 1)[1].split("\n## ", 1)[0]
    assert set(re.findall(r"^\| `([a-z0-9-]+)` \|", section, flags=re.M)) == set(PRESETS)
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    words = {2: "Two", 3: "Three", 4: "Four", 5: "Five", 6: "Six", 7: "Seven", 8: "Eight"}
    shipped = readme.split(" presets ship: ", 1)
    assert shipped[0].endswith(words[len(PRESETS)])
    assert all(f"`{name}`" in shipped[1].split("\n\n", 1)[0] for name in PRESETS)
