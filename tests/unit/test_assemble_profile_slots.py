"""A model built for one profile and re-used for another of the same type (only the
profile's slots of P and its table in T rewritten, `feeddrive.model.assemble._with_profile`)
equals the model built from scratch, field by field — the reuse is what makes a creep trial
and a linearisation skip the ~1 ms of building their model again."""

from __future__ import annotations

import dataclasses
import importlib

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.model.reference import ConstantSpeed, SineSpeed
from feeddrive.parameters import ParameterError

asm = importlib.import_module("feeddrive.model.assemble")  # the module, not the function

CASES = [
    ("wang2021", "cdfs", 0.4, [ConstantSpeed(1e-3), ConstantSpeed(2.5e-3, ramp_time=0.0),
                               ConstantSpeed(0.2e-3, ramp_time=0.3)]),
    ("wang2021", "ddfs", 0.2, [ConstantSpeed(1e-3, 16e-3), ConstantSpeed(0.5e-3, 2e-3, 0.0),
                               ConstantSpeed(-1e-3, 16e-3)]),
    ("wang2021", "ddfs", 0.4, [SineSpeed(1.56e-3, 0.0, 0.2), SineSpeed(2e-3, 16e-3, 0.2)]),
    ("wang2021-ripple", "ddfs", 0.4, [ConstantSpeed(1e-3, 16e-3), ConstantSpeed(2e-3, 30e-3)]),
    ("wang2021-drive", "cdfs", 0.6, [ConstantSpeed(1e-3), ConstantSpeed(3e-3)]),
]


def _same(a: asm.Model, b: asm.Model) -> None:
    for f in dataclasses.fields(asm.Model):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and x.shape == y.shape, f.name
            assert np.array_equal(x, y), f.name  # bit for bit (no NaN in these vectors)
        elif f.name == "module":
            assert x is y  # the compiled module is shared by its source hash
        else:
            assert x == y, f.name


@pytest.mark.parametrize(("preset", "drive", "position", "profiles"), CASES)
def test_a_reused_model_equals_the_one_built_anew(preset: str, drive: str, position: float,
                                                  profiles: list[object]) -> None:
    params = fd.preset(preset)
    first = asm.assemble(params, drive, position, "locked", profiles[0])
    for profile in profiles[1:]:
        fast = asm.assemble(params, drive, position, "locked", profile)
        full = asm._assemble(params, drive, position, "locked", profile, None)
        _same(fast, full)
        assert fast.P is not first.P and fast.T is not first.T  # never the template's arrays
    _same(asm.assemble(params, drive, position, "locked", profiles[0]), first)


def test_a_reused_model_still_refuses_a_nut_speed_on_the_cdfs() -> None:
    params = fd.preset("wang2021")
    asm.assemble(params, "cdfs", 0.3, "locked", ConstantSpeed(1e-3))
    with pytest.raises(ParameterError, match="nut_speed"):
        asm.assemble(params, "cdfs", 0.3, "locked", ConstantSpeed(1e-3, 1e-3))
