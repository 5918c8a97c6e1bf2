"""Every parameter file that loaded before the composition (issue 19 item 1) still loads and
gives the same numbers.

Reference: ``tests/data/parameter_vectors_ec220f9.json``, written by
``scripts/record_parameter_vectors.py`` on main at commit ec220f9 (the last tree with the
fixed ball-screw ``DriveParameters`` record): every registered preset, every parameter file of
``examples/``, every TOML block of the docs and every ``extends`` string of the tests, with
each value by dotted path and, per drive, the assembled model's slot names and packed
parameter vector ``P``.  The v2 layout is read directly (docs/parameters.md, "File layout"):
this test is the evidence that no ``feeddrive params upgrade`` is needed.

The model itself may gain slots after the record: the loops' sample periods became slots of
the vector when the solver driver stopped taking them as fixed arguments (merge of the
"solvers" branch, issue 19 item 3).  Every recorded slot must keep its name, its order among
the recorded slots and its value bit for bit; a slot added since must be one of
:data:`ADDED_SLOTS` and hold the set's own value.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from feeddrive.model.assemble import assemble
from feeddrive.model.mechanisms import mechanism
from feeddrive.model.reference import ConstantSpeed
from feeddrive.parameters import ParameterError, dumps, loads, preset, to_dict

ROOT = Path(__file__).resolve().parents[2]
RECORD = json.loads((ROOT / "tests" / "data" / "parameter_vectors_ec220f9.json")
                    .read_text(encoding="utf-8"))
SETS: dict[str, Any] = RECORD["sets"]


#: fields a file gained after the record, each with its default (the recorded behaviour)
ADDED_FIELDS = {f"{section}.position_feedback": "table"
                for section in ("controller", "hollow_controller")}

#: slots the model gained after the record, each with the parameter path it is packed from
ADDED_SLOTS = {f"controller.{loop}_period": f"controller.{loop}_period"
               for loop in ("position", "velocity", "current")}


def _value(params: Any, path: str) -> float:
    obj = params
    for part in path.split("."):
        obj = getattr(obj, part)
    return float(obj)


def _load(key: str) -> Any:
    kind, _, rest = key.partition(":")
    if kind == "preset":
        return preset(rest)
    if kind == "file":  # the shipped file as it is now
        path = ROOT / rest
        return loads(path.read_text(encoding="utf-8"), base_dir=path.parent)
    base = (ROOT / rest.split("#")[0]).parent if kind == "docs" else None
    return loads(SETS[key]["text"], base_dir=base)  # the text as it was recorded


def _flat(value: Any, prefix: str, out: dict[str, Any]) -> dict[str, Any]:
    if isinstance(value, dict):
        for key, sub in value.items():
            _flat(sub, f"{prefix}.{key}" if prefix else key, out)
    elif isinstance(value, tuple | list):
        out[prefix] = [float(v) for v in value]
    else:
        out[prefix] = value
    return out


def test_the_record_covers_every_kind_of_source():
    kinds = {key.split(":")[0] for key in SETS}
    assert kinds == {"preset", "file", "docs", "tests"}
    assert {"preset:wang2021", "preset:wang2021-literal", "preset:linear-motor-example",
            "preset:rack-pinion-example", "file:examples/gms_guide.toml"} <= set(SETS)
    assert RECORD["source"].startswith("scripts/record_parameter_vectors.py at commit ec220f9")


@pytest.mark.parametrize("key", sorted(SETS))
def test_every_recorded_file_gives_the_same_values(key: str):
    values = _flat(to_dict(_load(key)), "", {})
    recorded = SETS[key]["values"]
    assert {k: values.get(k) for k in recorded} == recorded
    # the new values: the mechanism kind every file before the composition describes, and
    # fields added since the record at their defaults, which keep the old behaviour
    # (controller.position_feedback, issue 37 item 3: the table scale, as before)
    added = set(values) - set(recorded)
    assert added - {"mechanism"} <= set(ADDED_FIELDS)
    assert "mechanism" in added and values["mechanism"] == "ball-screw"
    for path in added - {"mechanism"}:
        assert values[path] == ADDED_FIELDS[path], path


@pytest.mark.parametrize("key", sorted(SETS))
def test_every_recorded_file_gives_the_same_packed_vectors(key: str):
    params = _load(key)
    for drive, rec in SETS[key]["vectors"].items():
        if "refused" in rec:
            with pytest.raises(ParameterError) as err:
                mechanism(drive).check(params, drive, RECORD["table_position"])
                assemble(params, drive, RECORD["table_position"], "locked",
                         ConstantSpeed(1e-3))
            # the same field refused for the same reason; the value shown changed on purpose
            # ("linear_motor = None" read as a value, issue 41 item 7)
            field, reason = rec["refused"].split(" = ", 1)[0], rec["refused"].split(": ", 1)[1]
            assert err.value.field == field and err.value.message == reason
            continue
        mechanism(drive).check(params, drive, RECORD["table_position"])
        model = assemble(params, drive, RECORD["table_position"], "locked",
                         ConstantSpeed(1e-3))
        names = list(model.parameter_names)
        kept = [i for i, name in enumerate(names) if name in set(rec["names"])]
        assert [names[i] for i in kept] == rec["names"], drive
        np.testing.assert_array_equal(model.P[kept], np.array(rec["P"]), err_msg=drive)
        added = [name for name in names if name not in set(rec["names"])]
        assert set(added) <= set(ADDED_SLOTS), (drive, added)
        for name in added:
            assert model.parameter(name) == _value(params, ADDED_SLOTS[name]), (drive, name)


@pytest.mark.parametrize("key", sorted(SETS))
def test_the_v3_text_reads_back_to_the_same_set(key: str):
    params = _load(key)
    text = dumps(params)
    assert 'mechanism = "ball-screw"' in text
    assert loads(text) == params
