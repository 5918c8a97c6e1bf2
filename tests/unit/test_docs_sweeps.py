"""docs/sweeps.md against the code (issue 10): every option of `sweep` and `map`, every
configuration key, design and quantity is documented; the examples parse with the point
counts the doc states; the refusal quoted in the doc is the one the code prints."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
import typer

from feeddrive.cli import app
from feeddrive.parameters import ParameterError
from feeddrive.sweep import QUANTITIES, load_config, parse_config
from feeddrive.sweep import design as design_mod
from feeddrive.sweep import quantities as quantities_mod

ROOT = Path(__file__).resolve().parents[2]
DOC = (ROOT / "docs" / "sweeps.md").read_text()


def _command(name: str) -> Any:
    return typer.main.get_command(app).commands[name]  # type: ignore[attr-defined]


@pytest.mark.parametrize("name", ["sweep", "map"])
def test_every_option_is_documented(name: str) -> None:
    options = [o for p in _command(name).params for o in p.opts if o.startswith("--")]
    section = DOC.split("## Options", 1)[1]
    paragraph = next(p for p in section.split("\n\n") if p.startswith(f"`feeddrive {name} "))
    documented = re.findall(r"`(--[a-z-]+)`", paragraph)
    assert sorted(set(options) - {"--help"}) == sorted(set(documented))


def test_every_key_design_and_quantity_is_documented() -> None:
    for key in design_mod._TOP_KEYS + design_mod._AXIS_KEYS + quantities_mod._KEYS:
        assert f"`{key}`" in DOC, key
    for name in design_mod.DESIGNS + QUANTITIES + tuple(design_mod.SPECIAL_AXES):
        assert name in DOC, name
    for name in quantities_mod.UNITS:
        if name != "seconds":
            assert f"`{name}`" in DOC, name


def test_examples_parse_with_the_documented_counts() -> None:
    pos = load_config(ROOT / "examples" / "position_velocity_gain.toml").points()
    assert len(pos) == 15 and len({p.key for p in pos}) == 15
    # the CDFS holds its nut: its points at every nut speed share one key (computed once)
    shared = parse_config({"axes": {"drive": ["cdfs", "ddfs"], "table_position": [200, 400],
                                    "nut_speed": [2, 10]}}, "study.toml").points()
    assert len(shared) == 8 and len({p.key for p in shared}) == 6
    unc = load_config(ROOT / "examples" / "uncertainty.toml")
    assert unc.design == "lhs" and len(unc.coordinates()) == 200
    assert "| 15 |" in DOC and "| 200 |" in DOC


def test_the_quoted_refusal_is_the_code_s() -> None:
    with pytest.raises(ParameterError) as err:
        parse_config({"axes": {"friction.screw.positive.static_force": [-5.0]}},
                     "study.toml").points()
    quoted = re.search(r"^error: study\.toml: (.*)$", DOC, re.MULTILINE)
    assert quoted is not None
    assert str(err.value) == quoted.group(1)
