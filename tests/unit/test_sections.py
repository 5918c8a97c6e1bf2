"""A part's own parameter section (issue 19 item 1): registered by name (registry group
``feeddrive.sections``), read from and written to a file's top-level table, addressed by
dotted path, refused with one line when unknown."""

from __future__ import annotations

from dataclasses import dataclass

import pytest

import feeddrive as fd
from feeddrive import registry
from feeddrive.parameters import Component, ParameterError, composition, dumps, loads
from feeddrive.parameters.validation import quantity


@dataclass(frozen=True)
class ToyGear(Component):
    """A test section."""

    ratio: float = quantity("-", low=1, high=100)
    backlash: float = quantity("m", low=0, high=1e-3, low_inclusive=True, default=0.0)
    _label = "toy_gear"


@pytest.fixture()
def toy_section(monkeypatch):
    for group in registry.BUILTIN_PROVIDERS:  # load the groups into the tables copied below
        registry.table(group)
    monkeypatch.setattr(registry, "_TABLES", {g: dict(t) for g, t in registry._TABLES.items()})
    registry.register(registry.SECTIONS, "toy_gear", ToyGear)
    return ToyGear


def test_a_section_is_read_written_and_addressed(toy_section):
    params = loads('extends = "wang2021"\nname = "geared"\n[toy_gear]\nratio = 7.5\n')
    assert params.section("toy_gear") == ToyGear(ratio=7.5)
    assert params.toy_gear.ratio == 7.5  # reads like a field
    assert loads(dumps(params)) == params  # round trip through the file format
    assert "[toy_gear]" in dumps(params)
    changed = params.replace_path("toy_gear.backlash", 2e-5)
    assert changed.toy_gear.backlash == 2e-5 and params.toy_gear.backlash == 0.0
    child = loads(dumps(changed).replace('name = "geared"', 'name = "child"'))
    assert child.toy_gear == changed.toy_gear


def test_a_section_value_is_validated_with_its_path(toy_section):
    with pytest.raises(ParameterError) as err:
        loads('extends = "wang2021"\n[toy_gear]\nratio = 0.5\n')
    assert err.value.field == "toy_gear.ratio"


def test_an_unknown_section_is_an_unknown_key():
    with pytest.raises(ParameterError, match="no_such_part.*unknown key"):
        loads('extends = "wang2021"\n[no_such_part]\nx = 1\n')


def test_a_set_has_exactly_its_kinds_sections():
    # every part is a section (issue 19 item 1): the ball-screw kind's, and no part's own
    params = fd.preset("wang2021")
    assert {name for name, _ in params.sections} == set(composition("ball-screw").order())
    assert params.section("toy_gear") is None
    assert params.linear_motor is None  # a registered section the set does not give
    with pytest.raises(AttributeError):
        _ = params.toy_gear


def test_a_file_names_its_mechanism_kind():
    plain = loads('extends = "wang2021"\n')
    named = loads('extends = "wang2021"\nmechanism = "ball-screw"\n')
    assert named == plain and plain.mechanism == "ball-screw"
    with pytest.raises(ParameterError, match="mechanism = 'gantry': unknown mechanism kind; "
                       "expected one of ball-screw"):
        loads('extends = "wang2021"\nmechanism = "gantry"\n')


def test_a_kinds_required_part_is_named_when_missing():
    text = dumps(fd.preset("wang2021"))
    start = text.index("[coupling]")
    end = text.index("\n[", start + 1)
    with pytest.raises(ParameterError) as err:
        loads(text[:start] + text[end + 1:])
    assert err.value.field == "coupling" and "missing field" in err.value.message


def test_the_kinds_defaults_fill_what_a_set_leaves_out():
    from feeddrive.model.disturbances import Disturbances
    from feeddrive.model.mechanisms.ball_screw_parameters import StiffnessModel

    base = fd.preset("wang2021-literal")
    bare = fd.DriveParameters(name="bare", description="", screw=base.screw,
                              coupling=base.coupling, screw_motor=base.screw_motor,
                              hollow_motor=base.hollow_motor, table=base.table,
                              friction=base.friction)
    assert bare.stiffness == StiffnessModel() and bare.disturbances == Disturbances()
    assert bare.controller == base.controller  # Table 2's gains
    assert bare.with_values(controller=None).controller == base.controller


def test_a_written_file_carries_its_kinds_note():
    note = composition("ball-screw").file_note
    assert "torques divided by H" in note
    assert f"# {note}\n" in dumps(fd.preset("wang2021"))
