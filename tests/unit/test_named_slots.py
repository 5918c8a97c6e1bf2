"""Named parameter slots end to end (issue 19 item 2): a friction law's packed parameters
carry the names of the parameter-file paths they come from, and kernels read them through the
law's named offsets."""

from __future__ import annotations

import ast
import dataclasses
import operator
from pathlib import Path

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.model.friction import friction_law, law_names, lugre
from feeddrive.parameters import ParameterError

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _path(params, path: str) -> float:
    return float(operator.attrgetter(path)(params))


@pytest.mark.parametrize("law", ["lugre", "stribeck", "dahl"])
def test_site_slots_are_the_parameter_paths(law):
    """Every slot of every site, read back by name from the model, equals the value at the
    same dotted path of the parameter set."""
    params = fd.preset("wang2021")
    params = dataclasses.replace(params, friction=dataclasses.replace(
        params.friction, guide=dataclasses.replace(params.friction.guide, law=law)))
    model = fd.DriveSystem(params, "ddfs", 0.4).model(fd.ConstantSpeed(1e-3, 16e-3))
    names = [n for n in model.parameter_names if n.startswith("friction.guide.")]
    assert names == [f"friction.guide.{s}" for s in friction_law(law).slots]
    for name in names:
        assert model.parameter(name) == _path(params, name), name


def test_the_packing_follows_the_slot_names():
    """``LuGreParameters.as_array`` packs in the order the slot names say (a reordering of
    either would make a kernel read the wrong value)."""
    site = fd.preset("wang2021").friction.screw
    packed = site.as_array()
    for i, slot in enumerate(lugre.SLOTS):
        assert packed[i] == _path(site, slot), slot
    assert lugre.SLOTS[lugre.SIGMA0] == "bristle_stiffness"
    assert lugre.SLOTS[lugre.NEGATIVE + lugre.VISCOUS] == "negative.viscous_coefficient"


def test_every_law_names_each_packed_value():
    lugre_site = fd.preset("wang2021").friction.screw
    gms_site = fd.load(EXAMPLES / "gms_guide.toml").friction.guide
    for name in law_names():
        law = friction_law(name)
        site = gms_site if law.parameters_class is type(gms_site) else lugre_site
        if not isinstance(site, law.parameters_class):
            continue  # a law registered by another test, with parameters of its own
        assert len(law.site_slots(site)) == np.size(law.pack(site)), name


def test_unknown_slot_is_refused_with_the_near_names():
    model = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4).model(fd.ConstantSpeed(1e-3))
    with pytest.raises(ParameterError, match="friction.screw.bristle_stiffness"):
        model.parameter("friction.screw.sigma0")


# ---- kernels read P through named offsets only (issue 19 item 2)

MODEL_SOURCES = Path(fd.__file__).resolve().parent / "model"


def _literal_offsets(source: str) -> list[str]:
    """``P[…]`` reads of the kernels in ``source`` that use a literal offset: a number in the
    index (``P[o + 3]``, ``P[o + 2 * n + k]``), or a block offset read bare (``P[o]`` in a
    kernel that also reads ``P[o + NAME]``) — the slot then has no name in the code."""
    found = []
    for fn in ast.walk(ast.parse(source)):
        if not isinstance(fn, ast.FunctionDef):
            continue
        decorated = any(isinstance(d, ast.Name) and d.id.endswith("kernel")
                        for d in fn.decorator_list)
        if not decorated and "P" not in {a.arg for a in fn.args.args}:
            continue
        reads = [n for n in ast.walk(fn) if isinstance(n, ast.Subscript)
                 and isinstance(n.value, ast.Name) and n.value.id == "P"]
        bases = {_leftmost(n.slice) for n in reads if isinstance(n.slice, ast.BinOp)}
        for n in reads:
            literal = any(isinstance(c, ast.Constant) and isinstance(c.value, int | float)
                          and not isinstance(c.value, bool) for c in ast.walk(n.slice))
            bare = isinstance(n.slice, ast.Name) and n.slice.id in bases
            if literal or bare:
                found.append(f"{fn.name}:{n.lineno}: {ast.unparse(n)}")
    return found


def _leftmost(index: ast.expr) -> str | None:
    """The block offset of ``o + A + B`` (its leftmost name)."""
    while isinstance(index, ast.BinOp):
        index = index.left
    return index.id if isinstance(index, ast.Name) else None


def test_the_literal_offset_check_finds_one():
    """The check itself: literal and bare block offsets are found, named ones pass."""
    source = ("@kernel\ndef k(v, P, o, n):\n"
              "    return P[o] + P[o + 3] + P[o + 2 * n] + P[o + SIGMA0] + P[o + FIRST + n]\n")
    assert sorted(_literal_offsets(source)) == ["k:3: P[o + 2 * n]", "k:3: P[o + 3]",
                                                "k:3: P[o]"]


def test_kernels_read_parameters_by_named_offsets():
    """No kernel under ``feeddrive.model`` reads ``P`` at a literal offset: every slot it
    reads has the name its part declares (``P[o + SIGMA0]``)."""
    found = []
    for path in sorted(MODEL_SOURCES.rglob("*.py")):
        found += [f"{path.relative_to(MODEL_SOURCES)}:{hit}"
                  for hit in _literal_offsets(path.read_text(encoding="utf-8"))]
    assert found == []
