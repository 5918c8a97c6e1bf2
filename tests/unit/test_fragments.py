"""TOML fragments of identified friction and their merge into parameter sets."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

import feeddrive
from feeddrive.analysis.fragments import friction_fragment, merge_fragment
from feeddrive.analysis.presliding import fit_presliding
from feeddrive.analysis.presliding_rig import simulate_presliding
from feeddrive.analysis.static_fit import fit_static
from feeddrive.model.friction.stribeck import steady_friction
from feeddrive.parameters import ParameterError

BASE = feeddrive.preset("wang2021")
SCREW = BASE.friction.screw


@pytest.fixture(scope="module")
def static_fit() -> object:
    v = np.geomspace(0.05e-3, 50e-3, 30)
    v = np.concatenate([v, -v])
    rng = np.random.default_rng(0)
    return fit_static(v, steady_friction(v, SCREW) * (1 + 0.01 * rng.standard_normal(v.size)))


def test_static_fragment_merges_into_a_validated_set(static_fit: object) -> None:
    text = friction_fragment("nut", static=static_fit, source="tests.csv")  # type: ignore[arg-type]
    data = tomllib.loads(text)
    assert set(data["friction"]["nut"]) == {"positive", "negative"}
    merged = merge_fragment(BASE, text)
    assert merged.friction.nut.positive == static_fit.positive.branch  # type: ignore[attr-defined]
    # untouched: σ0, σ1 of the site and every other site
    assert merged.friction.nut.bristle_stiffness == BASE.friction.nut.bristle_stiffness
    assert merged.friction.screw == BASE.friction.screw
    assert "95 % CI" in text


def test_undetermined_sigma1_is_left_out() -> None:
    t = np.arange(0.0, 4.0, 0.01)
    f = 15.0 * (1.0 - np.cos(np.pi * t))  # slow and smooth: σ1 invisible
    x = simulate_presliding(t, f, 2000.0, SCREW)
    x = x + 0.01 * np.ptp(x) * np.random.default_rng(2).standard_normal(x.size)
    dyn = fit_presliding(t, f, x, mass=2000.0, friction=SCREW)
    assert not dyn.sigma1_determined
    text = friction_fragment("screw", dynamic=dyn)
    data = tomllib.loads(text)["friction"]["screw"]
    assert "bristle_damping" not in data
    assert data["bristle_stiffness"] == pytest.approx(SCREW.bristle_stiffness, rel=0.05)
    assert "poorly determined" in text
    merged = merge_fragment(BASE, text)
    assert merged.friction.screw.bristle_damping == SCREW.bristle_damping
    forced = tomllib.loads(friction_fragment("screw", dynamic=dyn, include_undetermined=True))
    assert "bristle_damping" in forced["friction"]["screw"]


def test_merge_from_file_and_mapping(tmp_path: Path) -> None:
    p = tmp_path / "frag.toml"
    p.write_text("[friction.guide]\nbristle_damping = 1000.0\n", encoding="utf-8")
    assert merge_fragment(BASE, p).friction.guide.bristle_damping == 1000.0
    assert merge_fragment(BASE, {"table": {"mass": 25.0}}).table.mass == 25.0


@pytest.mark.parametrize(
    ("fragment", "match"),
    [
        ("[friction.screw.positiv]\ncoulomb_force = 1.0\n", "friction.screw.positiv.*unknown key"),
        ("[friction.screw.positive]\ncoulomb_force = 200.0\n", "static_force.*F_s must be"),
        ("[friction.screw.positive]\nstribeck_velocity = 0.9\n", "stribeck_velocity"),
        ("[friction]\nscrew = 1.0\n", "friction.screw.*expected a table"),
        ("[friction.screw\n", "not valid TOML"),
    ],
)
def test_bad_fragments_name_the_field(fragment: str, match: str) -> None:
    with pytest.raises(ParameterError, match=match):
        merge_fragment(BASE, fragment)


def test_fragment_needs_something() -> None:
    with pytest.raises(ValueError, match="give a static fit"):
        friction_fragment("screw")
    with pytest.raises(ParameterError, match="site"):
        friction_fragment("spindle", static=None)
