"""The negative-slope band of the Stribeck curve (``negative_slope_band``), in closed form by
Lambert's W since 2026-12-06, against a bracketing root search written here (scipy's brentq on
the slope of Wang2021 Eq. 11's steady curve, differenced independently), and the band without
viscous friction: [0, ∞), no zero-slope speed (the root search before had stopped where the
slope underflowed, 39.1 mm/s for the wang2021 screw's + branch)."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.cli import app
from feeddrive.model.friction.stribeck import FrictionBranch, negative_slope_band


def _slope(v: float, b: FrictionBranch) -> float:
    """d/dv of F_c + (F_s − F_c)·exp(−(v/v_s)²) + σ2·v (Wang2021 Eq. 11), central difference."""
    def f(x: float) -> float:
        return (b.coulomb_force + (b.static_force - b.coulomb_force)
                * math.exp(-(x / b.stribeck_velocity) ** 2) + b.viscous_coefficient * x)
    h = 1e-7 * b.stribeck_velocity
    return (f(v + h) - f(v - h)) / (2 * h)


def _branches() -> list[FrictionBranch]:
    p = fd.preset("wang2021").friction
    out = [getattr(getattr(p, s), n) for s in ("screw", "nut", "guide")
           for n in ("positive", "negative")]
    rng = np.random.default_rng(7)
    for _ in range(20):
        fc = rng.uniform(10, 200)
        out.append(FrictionBranch(coulomb_force=fc, static_force=fc * rng.uniform(1.05, 2.0),
                                  stribeck_velocity=rng.uniform(1e-4, 5e-3),
                                  viscous_coefficient=rng.uniform(0.0, 1.0) * 1e3))
    return out


@pytest.mark.parametrize("branch", _branches())
def test_the_edges_are_where_an_independent_root_search_finds_the_slope_zero(
        branch: FrictionBranch) -> None:
    band = negative_slope_band(branch)
    vs = branch.stribeck_velocity
    peak = vs / math.sqrt(2.0)
    if _slope(peak, branch) >= 0.0:  # σ2 above the Stribeck slope's peak
        assert band is None
        return
    assert band is not None and band.bounded
    lower = brentq(lambda v: _slope(v, branch), 1e-9 * vs, peak, xtol=1e-16, rtol=1e-10)
    upper = brentq(lambda v: _slope(v, branch), peak, 50 * vs, xtol=1e-16, rtol=1e-10)
    assert band.lower == pytest.approx(lower, rel=1e-6)
    assert band.upper == pytest.approx(upper, rel=1e-6)
    assert band.zero_slope_speed == band.upper


def test_without_viscous_friction_the_band_never_ends() -> None:
    screw = fd.preset("wang2021").friction.screw.positive
    band = negative_slope_band(dataclasses.replace(screw, viscous_coefficient=0.0))
    assert band is not None and band.lower == 0.0 and band.upper == math.inf
    assert not band.bounded
    # the slope, −(F_s − F_c)·2v/v_s²·exp(−(v/v_s)²) without σ2, is negative at every speed
    # (at 10 mm/s ≈ −4e-53 N s/m; where the earlier search stopped, 39.1 mm/s, it underflows)
    u = 0.01 / screw.stribeck_velocity
    assert -(screw.static_force - screw.coulomb_force) * 2 * u / screw.stribeck_velocity \
        * math.exp(-u * u) < 0.0


def test_the_friction_command_says_so_in_json_table_and_plot(tmp_path) -> None:
    path = tmp_path / "s0.toml"
    path.write_text('extends = "wang2021"\n[friction.screw.positive]\n'
                    'viscous_coefficient = 0.0\n')
    runner = CliRunner()
    res = runner.invoke(app, ["friction", "--params", str(path), "--json"])
    assert res.exit_code == 0, res.output
    pos = json.loads(res.output)["branches"]["positive"]
    assert pos["negative_slope_band_mm_s"] == [0.0, None]
    assert pos["zero_slope_speed_mm_s"] is None
    res = runner.invoke(app, ["friction", "--params", str(path), "--plot",
                              str(tmp_path / "s0.png")], terminal_width=200)
    assert res.exit_code == 0, res.output
    assert "0.000 … ∞ (σ2 = 0)" in res.output
    assert "Zero-slope speed, + branch" not in res.output  # no number to compare
    assert (tmp_path / "s0.png").stat().st_size > 5000


def test_the_explorer_draws_an_unending_band_to_the_curves_end() -> None:
    """The page's friction curves: a band without end (σ2 = 0) is cut at the curves' speed
    range, finite for JSON; the bounded branch's band is the closed form's."""
    from feeddrive.explore.compute import friction_curves
    from feeddrive.explore.settings import check

    text = 'extends = "wang2021"\n[friction.screw.positive]\nviscous_coefficient = 0.0\n'
    checked = check({"drive": "cdfs", "params": text})
    assert not checked.errors, checked.errors
    curves = friction_curves(checked)
    screw = next(c for c in curves["sites"] if c["site"] == "screw")
    top = max(screw["speed_mm_s"])
    json.dumps(curves, allow_nan=False)  # no inf reaches the page
    negative = negative_slope_band(fd.preset("wang2021").friction.screw.negative)
    assert screw["negative_slope_mm_s"] == [
        [0.0, pytest.approx(top)],  # the + branch, σ2 = 0: to the curves' end
        [pytest.approx(-1e3 * negative.upper), pytest.approx(-1e3 * negative.lower)],
    ]


def test_the_report_and_the_friction_command_print_one_band_text(tmp_path) -> None:
    """One formatter (``units.slope_band_text``) for both: the report's indicator table and
    ``feeddrive friction``'s table show the same cells, bounded and without end."""
    from feeddrive.parameters.toml_io import load
    from feeddrive.reproduce.report import indicator_rows

    path = tmp_path / "s0.toml"
    path.write_text('extends = "wang2021"\n[friction.screw.positive]\n'
                    'viscous_coefficient = 0.0\n')
    rows = {(r["site"], r["branch"]): r["negative-slope band [mm/s]"]
            for r in indicator_rows(load(path))}
    assert rows[("screw", "positive")] == "0.000 … ∞ (σ2 = 0)"
    bounded = rows[("screw", "negative")]
    low, high = (float(x) for x in bounded.split(" … "))
    assert 0.0 < low < high  # σ2 > 0 on this branch: a band with an end
    res = CliRunner().invoke(app, ["friction", "--params", str(path), "--site", "screw"],
                             terminal_width=200)
    assert res.exit_code == 0, res.output
    assert "0.000 … ∞ (σ2 = 0)" in res.output and bounded in res.output
