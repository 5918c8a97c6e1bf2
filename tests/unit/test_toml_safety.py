"""TOML written and read safely: issue 13, items 2 and 7.

Guards: a deeply nested TOML file ended in a ``RecursionError`` traceback; a parameter-set
name with a newline was written as invalid TOML; a data-file name with newlines injected
``table.mass = 99`` into an identification fragment (confirmed through ``identify merge``).
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from feeddrive.analysis.fragments import friction_fragment, merge_fragment
from feeddrive.analysis.static_fit import fit_static
from feeddrive.model.friction.stribeck import steady_friction
from feeddrive.parameters import ParameterError, dumps, load, loads, preset, to_dict
from feeddrive.parameters.toml_io import MAX_TOML_DEPTH, parse_toml, toml_comment, toml_string

PARAMS = preset("wang2021")


@pytest.mark.parametrize("text", [
    "a = " + "[" * 5000 + "]" * 5000,
    "a = " + "{b = " * 3000 + "1" + "}" * 3000,
    "a = " + "[" * 40 + "]" * 40,
    "".join(f"[{'.'.join(['t'] * k)}]\n" for k in range(1, 60)),
], ids=["arrays-5000", "inline-tables-3000", "arrays-40", "table-headers-60"])
def test_deep_nesting_is_one_line_error(tmp_path: Path, text: str) -> None:
    path = tmp_path / "deep.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ParameterError, match=f"nested more than {MAX_TOML_DEPTH} deep") as err:
        load(path)
    assert str(path) in str(err.value) and "\n" not in str(err.value)


def test_binary_and_folder_parameter_files_name_the_file(tmp_path: Path) -> None:
    path = tmp_path / "blob.toml"
    path.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(ParameterError, match="blob.toml.*not UTF-8 text"):
        load(path)
    with pytest.raises(ParameterError, match="is a folder"):
        load(tmp_path)


_TEXT = st.text(st.characters(blacklist_categories=("Cs",)), max_size=40)


@settings(max_examples=200, deadline=None)
@given(_TEXT)
def test_every_string_round_trips_through_tomllib(text: str) -> None:
    assert tomllib.loads(f"v = {toml_string(text)}")["v"] == text
    comment = toml_comment(text)
    assert tomllib.loads(f"# {comment}\nv = 1") == {"v": 1}


@pytest.mark.parametrize("name", ["a\nb", 'x"\n[table]\nmass = 99\n#', "tab\there",
                                  "bell\x07\x7f", "back\\slash\\n", "unicode µ ✓"])
def test_parameter_set_names_cannot_break_the_file(name: str) -> None:
    """A description may hold line breaks and tabs and still cannot break the file; a name
    with a control character is refused (issue 25 item 6: it was printed raw)."""
    printable = name.isprintable()
    if not printable:
        with pytest.raises(ParameterError, match="control character"):
            PARAMS.with_values(name=name)
    description = f"from {name}".replace("\x07", "").replace("\x7f", "")
    params = PARAMS.with_values(name=name if printable else "n", description=description)
    back = loads(dumps(params))
    assert back.name == params.name and back.description == description
    assert to_dict(back) == to_dict(params)


def test_file_name_with_newlines_cannot_inject_a_key() -> None:
    v = np.repeat(np.geomspace(0.05e-3, 50e-3, 12), 2)
    v = np.concatenate([v, -v])
    fit = fit_static(v, steady_friction(v, PARAMS.friction.screw))
    source = "victim.csv\n[table]\nmass = 99.0\n# "
    text = friction_fragment("screw", static=fit, source=source)
    data = tomllib.loads(text)
    assert "table" not in data
    merged = merge_fragment(PARAMS, text)
    assert merged.table.mass == PARAMS.table.mass


def test_parse_toml_names_its_source() -> None:
    with pytest.raises(ParameterError, match="fragment = 'x.toml': not valid TOML"):
        parse_toml("a = ", field="fragment", source="x.toml")
