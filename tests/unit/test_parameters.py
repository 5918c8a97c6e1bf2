"""Parameter sets: validation names the offending field; TOML io is lossless."""

from __future__ import annotations

import copy
import dataclasses
import math
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from feeddrive.parameters import (
    PRESETS,
    DriveParameters,
    ParameterError,
    dumps,
    from_dict,
    load,
    loads,
    preset,
    save,
    to_dict,
)
from feeddrive.parameters.validation import MISSING


def numeric_leaves(obj: Any, prefix: str = "") -> list[tuple[str, dict[str, Any]]]:
    """(dotted path, field metadata) of every declared scalar quantity in a parameter tree
    (vector quantities, e.g. harmonic amplitudes, are tested in test_model_parts.py)."""
    out = []
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        path = f"{prefix}.{f.name}" if prefix else f.name
        if f.name == "sections":  # the composition's parts, each a section of its own
            for name, section in value:
                out.extend(numeric_leaves(section, f"{prefix}.{name}" if prefix else name))
        elif dataclasses.is_dataclass(value):
            out.extend(numeric_leaves(value, path))
        elif "unit" in f.metadata and not f.metadata.get("vector"):
            out.append((path, dict(f.metadata)))
    return out


LEAVES = numeric_leaves(preset("wang2021"))


def edited(path: str, value: Any) -> dict[str, Any]:
    data = copy.deepcopy(to_dict(preset("wang2021")))
    node = data
    *parents, last = path.split(".")
    for part in parents:
        node = node[part]
    node[last] = value
    return data


def removed(path: str) -> dict[str, Any]:
    data = copy.deepcopy(to_dict(preset("wang2021")))
    node = data
    *parents, last = path.split(".")
    for part in parents:
        node = node[part]
    del node[last]
    return data


# ------------------------------------------------------------------ TOML round trip


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_toml_round_trip_is_lossless(name: str, tmp_path: Any) -> None:
    params = preset(name)
    text = dumps(params)
    again = loads(text)
    assert again == params
    assert to_dict(again) == to_dict(params)
    assert dumps(again) == text
    path = tmp_path / f"{name}.toml"
    save(params, path)
    assert load(path) == params


@settings(max_examples=60, deadline=None)
@given(mass=st.floats(min_value=0.011, max_value=9.9e4, allow_nan=False),
       sigma2=st.floats(min_value=0.0, max_value=9.9e6, allow_nan=False))
def test_toml_round_trip_keeps_every_bit(mass: float, sigma2: float) -> None:
    params = (preset("wang2021")
              .replace_path("table.mass", mass)
              .replace_path("friction.guide.positive.viscous_coefficient", sigma2))
    again = loads(dumps(params))
    assert again.table.mass == mass
    assert again.friction.guide.positive.viscous_coefficient == sigma2
    assert again == params


def test_toml_names_units_beside_values() -> None:
    text = dumps(preset("wang2021"))
    assert "lead = 0.005  # [m]" in text
    assert "screw_support = \"fixed-fixed\"  # one of fixed-fixed, fixed-free" in text


# ------------------------------------------------------------------ refused inputs


BAD_INPUTS = [
    # (description, data, field named in the error, text the message must contain)
    ("unknown top-level key", {**to_dict(preset("wang2021")), "colour": "red"}, "colour",
     "unknown key"),
    ("unknown nested key", edited("screw.pitch", 0.005), "screw.pitch", "unknown key"),
    ("missing field", removed("table.mass"), "table.mass", "missing field"),
    ("missing component", removed("coupling"), "coupling", "missing field"),
    ("nan", edited("table.mass", math.nan), "table.mass", "not finite"),
    ("inf", edited("screw.nut_axial_stiffness", math.inf), "screw.nut_axial_stiffness",
     "not finite"),
    ("negative", edited("friction.nut.bristle_damping", -1.0), "friction.nut.bristle_damping",
     "[N s/m]"),
    ("zero", edited("friction.screw.bristle_stiffness", 0.0),
     "friction.screw.bristle_stiffness", "[N/m]"),
    ("zero Stribeck speed", edited("friction.guide.negative.stribeck_velocity", 0.0),
     "friction.guide.negative.stribeck_velocity", "[m/s]"),
    ("F_s < F_c", edited("friction.screw.positive.static_force", 50.0),
     "friction.screw.positive.static_force", "F_s must be ≥ F_c"),
    ("lead in mm", edited("screw.lead", 5.0), "screw.lead", "millimetres"),
    ("inductance in mH", edited("screw_motor.inductance", 5.9), "screw_motor.inductance",
     "0.0059 H"),
    ("inertia typo of Table 2", edited("hollow_motor.inertia", 1380.0), "hollow_motor.inertia",
     "1.38×10⁻³"),
    ("string for a number", edited("table.mass", "20 kg"), "table.mass", "expected a number"),
    ("bool for a number", edited("table.mass", True), "table.mass", "expected a number"),
    ("bad choice", edited("stiffness.screw_support", "pinned"), "stiffness.screw_support",
     "fixed-fixed"),
    ("efficiency above 1", edited("screw.efficiency", 95.0), "screw.efficiency", "fraction"),
]


@pytest.mark.parametrize(("data", "field", "text"), [case[1:] for case in BAD_INPUTS],
                         ids=[case[0] for case in BAD_INPUTS])
def test_bad_input_raises_parameter_error_naming_the_field(data: dict[str, Any], field: str,
                                                           text: str) -> None:
    with pytest.raises(ParameterError) as info:
        from_dict(data)
    assert info.value.field == field
    message = str(info.value)
    if text == "missing field":  # nothing was given: no value shown (not "= None")
        assert info.value.value is MISSING
        assert message.startswith(f"{field}: missing field")
    else:
        assert message.startswith(f"{field} = ")
    assert text in message
    assert "\n" not in message


def test_a_missing_value_is_one_object_that_shows_no_value() -> None:
    import pickle

    err = ParameterError("--table-speed", MISSING, "required for --profile constant [mm/s]")
    assert str(err) == "--table-speed: required for --profile constant [mm/s]"
    assert pickle.loads(pickle.dumps(MISSING)) is MISSING
    # None given is a value given, and shown as one
    assert str(ParameterError("rtol", None, "expected a number")) == (
        "rtol = None: expected a number")


@settings(max_examples=120, deadline=None)
@given(leaf=st.sampled_from(LEAVES),
       bad=st.sampled_from(["nan", "inf", "-inf", "negative", "zero", "huge"]))
def test_any_out_of_range_quantity_is_refused_by_name(leaf: tuple[str, dict[str, Any]],
                                                      bad: str) -> None:
    path, meta = leaf
    value = {"nan": math.nan, "inf": math.inf, "-inf": -math.inf, "negative": -1.0,
             "zero": 0.0, "huge": meta["high"] * 10.0 + 1.0}[bad]
    lo = meta["low"]
    in_range = {"zero": 0.0 > lo or (0.0 == lo and meta["low_inclusive"]),
                "negative": -1.0 > lo, "huge": math.isinf(meta["high"])}
    refused = not in_range.get(bad, False)
    if not refused:
        from_dict(edited(path, value))
        return
    with pytest.raises(ParameterError) as info:
        from_dict(edited(path, value))
    assert info.value.field == path
    # the unit the value is read in: wang2021 works per m/s of table speed, so a velocity
    # gain's message says its metadata's table unit (issue 23)
    unit = meta.get("table_unit") or meta["unit"]
    assert f"[{unit}]" in str(info.value)


def test_toml_syntax_error_is_a_parameter_error() -> None:
    with pytest.raises(ParameterError, match="not valid TOML"):
        loads("[screw\nlead = ")


def test_replace_path_validates_and_names_unknown_fields() -> None:
    params = preset("wang2021")
    assert params.replace_path("stiffness.equivalent_stiffness", 2.16e7) \
        .stiffness.equivalent_stiffness == 2.16e7
    with pytest.raises(ParameterError) as info:
        params.replace_path("screw.pitch", 1.0)
    assert info.value.field == "screw.pitch"
    with pytest.raises(ParameterError):
        params.replace_path("screw.lead", 5.0)


def test_unknown_preset_is_refused() -> None:
    with pytest.raises(ParameterError) as info:
        preset("wang2020")
    assert info.value.field == "preset"


def test_presets_are_drive_parameters() -> None:
    for name in PRESETS:
        params = preset(name)
        assert isinstance(params, DriveParameters)
        assert params.name == name


@settings(max_examples=60, deadline=None)
@given(leaf=st.sampled_from(LEAVES), bad=st.sampled_from([math.nan, -1.0, math.inf]))
def test_replace_path_names_the_full_path_of_a_refused_value(leaf: tuple[str, dict[str, Any]],
                                                             bad: float) -> None:
    """Guards a fixed bug: replace_path named the component label ("motor.inductance",
    "friction_branch.static_force") instead of the path the caller gave."""
    path, meta = leaf
    if bad == -1.0 and meta["low"] < -1.0:  # a signed quantity (a load force) allows -1
        bad = meta["low"] * 10.0 - 1.0
    with pytest.raises(ParameterError) as info:
        preset("wang2021").replace_path(path, bad)
    assert info.value.field == path


def test_replace_path_names_the_full_path_for_cross_field_checks() -> None:
    with pytest.raises(ParameterError) as info:
        preset("wang2021").replace_path("friction.nut.negative.static_force", 1.0)
    assert info.value.field == "friction.nut.negative.static_force"
    assert "F_s must be ≥ F_c" in str(info.value)


def test_refusal_message_survives_a_value_containing_colon_space() -> None:
    """Guards a fixed bug: the path rewrite split the message at the first ": ", which
    garbled it when the refused value's repr contained ": "."""
    with pytest.raises(ParameterError) as info:
        from_dict(edited("table.mass", "20: kg"))
    assert str(info.value) == "table.mass = '20: kg': expected a number [kg]"
    with pytest.raises(ParameterError) as info:
        preset("wang2021").replace_path("table.mass", "20: kg")
    assert str(info.value) == "table.mass = '20: kg': expected a number [kg]"


@pytest.mark.parametrize("name", ["set.json", "set.yaml", "set", "set.toml.bak"])
def test_save_refuses_a_name_that_is_not_toml_before_writing(tmp_path: Path, name: str) -> None:
    """A set is TOML whatever the name says: ``x.json`` was written as TOML under a JSON name."""
    with pytest.raises(ParameterError, match=r"path = .*expected a \.toml file name"):
        save(preset("wang2021"), tmp_path / name)
    assert not (tmp_path / name).exists()


def test_the_json_the_save_message_points_to_round_trips(tmp_path: Path) -> None:
    import json

    params = preset("wang2021")
    text = json.dumps(to_dict(params))
    assert from_dict(json.loads(text)) == params


def test_a_refusal_crosses_a_process_boundary_whole() -> None:
    """A worker process's ParameterError reached the pool's parent as a pickling failure that
    broke the pool (its constructor takes the field, value and message, the default pickling
    passed the message alone; found 2026-12-06 with a bad [solver] table in ``reproduce``)."""
    import pickle

    from feeddrive.explore.settings import UsageError

    err = ParameterError("solver.rtol", -1.0, "expected a value > 0", source="run.toml")
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is ParameterError and str(back) == str(err)
    assert (back.field, back.value, back.message, back.source) == (
        "solver.rtol", -1.0, "expected a value > 0", "run.toml")
    assert pickle.loads(pickle.dumps(ParameterError("x", MISSING, "give x"))).value is MISSING
    usage = pickle.loads(pickle.dumps(UsageError("--table-speed", "fast")))
    assert type(usage) is UsageError and str(usage) == str(UsageError("--table-speed", "fast"))
