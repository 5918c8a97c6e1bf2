"""A DriveSystem built from the wrong kind of value says which argument and what it expected
(brief, non-negotiable 3), instead of an AttributeError or TypeError from inside the
mechanism's check (found 2026-12-07: ``DriveSystem(None)``, a path string, a dict, a string
table position, ``initial_state=None``)."""

from __future__ import annotations

import numpy as np
import pytest

import feeddrive as fd

P = fd.preset("wang2021")


@pytest.mark.parametrize(("kwargs", "field"), [
    ({"parameters": None}, "parameters"),
    ({"parameters": "examples/gms_guide.toml"}, "parameters"),
    ({"parameters": {}}, "parameters"),
    ({"table_position": "0.4"}, "table_position"),
    ({"table_position": None}, "table_position"),
    ({"table_position": True}, "table_position"),
    ({"initial_state": None}, "initial_state"),
    ({"initial_state": [("table_speed", 1e-3)]}, "initial_state"),
])
def test_the_wrong_kind_of_value_is_refused_by_name(kwargs: dict, field: str) -> None:
    args = {"parameters": P, "drive": "cdfs", "table_position": 0.4, **kwargs}
    with pytest.raises(fd.ParameterError) as info:
        fd.DriveSystem(**args)
    assert info.value.field == field
    assert str(info.value).startswith(f"{field} = ")


@pytest.mark.parametrize("position", [0.4, np.float64(0.4), np.float32(0.5)])
def test_numbers_of_any_real_kind_are_taken(position: object) -> None:
    system = fd.DriveSystem(P, "cdfs", position)  # type: ignore[arg-type]
    assert system.table_position == position
