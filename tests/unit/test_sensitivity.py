"""`feeddrive sensitivity` (issue 22 item 5): elasticities by central differences through the
sweep machinery, the step rule and its halving check; the linear band's upper edge (cheap)."""

from __future__ import annotations

import math

import pytest

import feeddrive as fd
from feeddrive.analysis.linear import stability_band
from feeddrive.analysis.sensitivity import (
    MIN_EFFECT_RESOLUTIONS,
    parameter_paths,
    sensitivity,
)


def _edge(params: fd.DriveParameters) -> float:
    """The quantity as the sweep computes it (the linear-band settings' range, 40 points)."""
    from feeddrive.sweep.quantities import QuantitySettings

    q = QuantitySettings.parse({"kind": "linear-band"})
    band = stability_band(fd.DriveSystem(params, "cdfs", 0.4), low=q.low, high=q.high,
                          points=40)
    return band.intervals[-1][1]


def test_elasticity_matches_direct_central_difference() -> None:
    result = sensitivity("wang2021", quantity="linear-band", in_process=True,
                         patterns=["controller.velocity_gain", "screw.youngs_modulus"])
    by = {e.path: e for e in result.entries}
    kv = by["controller.velocity_gain"]
    assert kv.resolved and kv.step == 0.1 and kv.consistent
    base = fd.preset("wang2021")
    v0 = base.controller.velocity_gain
    plus = _edge(base.replace_path("controller.velocity_gain", v0 * 1.1))
    minus = _edge(base.replace_path("controller.velocity_gain", v0 * 0.9))
    assert kv.elasticity == pytest.approx((plus - minus) / (0.2 * _edge(base)), rel=1e-9)
    assert kv.elasticity < 0  # a stiffer velocity loop narrows the unstable band
    # the rule: a resolved effect is ≥ 10 resolutions; an unresolved one states its bound
    assert abs(kv.q_plus - kv.q_minus) >= MIN_EFFECT_RESOLUTIONS * result.resolution
    # the JSON states Q in mm/s beside its base (before: q_minus in m/s beside base_mm_s)
    shown = {d["path"]: d for d in result.to_dict()["entries"]}["controller.velocity_gain"]
    assert shown["q_plus_mm_s"] == 1e3 * kv.q_plus and shown["q_minus_mm_s"] == 1e3 * kv.q_minus
    assert 0.5 < shown["q_plus_mm_s"] / result.to_dict()["base_mm_s"] < 2.0
    e = by["screw.youngs_modulus"]
    if not e.resolved:
        assert e.step == 0.4 and math.isfinite(e.bound)
        assert abs(e.q_plus - e.q_minus) < MIN_EFFECT_RESOLUTIONS * result.resolution


def test_left_out_parameters_name_their_reason() -> None:
    keep, skipped = parameter_paths(fd.preset("wang2021"), "cdfs")
    assert "controller.velocity_integral_gain" in keep
    assert "hollow mot" not in " ".join(keep)
    assert "CDFS" in skipped["hollow_motor.inertia"]
    assert "negative direction" not in skipped.get("friction.screw.negative.static_force", "x")
    assert "positive direction" in skipped["friction.screw.negative.static_force"]
    assert "structural" in skipped["controller.position_period"]
    assert "no limit" in skipped["controller.current_limit"]


def test_unknown_pattern_is_refused() -> None:
    with pytest.raises(fd.ParameterError, match="matches no numeric parameter"):
        sensitivity("wang2021", quantity="linear-band", in_process=True,
                    patterns=["controller.nothing*"])


def test_report_section_answers_the_axial_rigidity_claim(tmp_path) -> None:
    """The reproduce report's section (feeddrive.reproduce.sensitivity_section) on the
    stiffness rows: Wang2021 claims "the greater the axial rigidity, the lower the critical
    speed"; the answer is read from those rows, with the numbers it rests on."""
    from feeddrive.reproduce import sensitivity_section as sec

    data = sensitivity(fd.preset("wang2021"), quantity="linear-band", in_process=True,
                       linear_points=sec.LINEAR_POINTS,
                       patterns=[*sec.AXIAL, "controller.velocity_gain"]).to_dict()
    text, rows = sec.sensitivity_rows(data)
    assert [r["parameter"] for r in rows][0] == "controller.velocity_gain"
    answer = sec.axial_rigidity_answer(data)
    assert answer in text and "axial rigidity" in answer
    axial = [e for e in data["entries"] if e["path"] in sec.AXIAL]
    if not any(e["resolved"] for e in axial):
        assert "neither supports nor refutes" in answer
        # the number it rests on: the largest move of the edge, from the SI entries
        result = {e.path: e for e in sensitivity(
            fd.preset("wang2021"), quantity="linear-band", in_process=True,
            linear_points=sec.LINEAR_POINTS, patterns=list(sec.AXIAL)).entries}
        largest = max(abs(e.q_plus - e.q_minus) for e in result.values()) * 1e3
        assert f"by at most {largest:.3g} mm/s" in answer
    png = sec.figure(data, tmp_path)
    assert png is not None and png.stat().st_size > 5000


def test_in_process_points_use_the_set_their_task_reads_back() -> None:
    """An in-process point is evaluated on the parameter set it was built from, not on its
    TOML text read back (issue 21: ≈ 5 ms a point): the two give the same values."""
    from feeddrive.parameters import dumps
    from feeddrive.sweep.quantities import evaluate

    params = fd.preset("wang2021").replace_path("controller.velocity_gain", 49.5)
    task = {"parameters": dumps(params), "drive": "cdfs", "table_position": 0.4,
            "nut_speed": 0.0, "quantity": {"kind": "linear-band", "low": 1e-5, "high": 5e-3,
                                           "linear_points": 12}}
    read, held = evaluate(task), evaluate(task, params)
    assert "error" not in read
    assert read["values"] == held["values"] and read["details"] == held["details"]


def test_choosing_the_parameters_imports_no_fitting_library() -> None:
    """`parameter_paths` (the sensitivity's first step, in the report's first task) uses the
    fit module's light helpers only: scipy.optimize and scipy.stats (≈ 1 s to import) are
    imported where the fits use them."""
    import subprocess
    import sys

    code = ("import sys, feeddrive as fd\n"
            "from feeddrive.analysis.sensitivity import parameter_paths\n"
            "parameter_paths(fd.preset('wang2021'), 'cdfs')\n"
            "print(sorted(m for m in ('scipy.optimize', 'scipy.stats') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "[]"


def _count_linearisations(monkeypatch: pytest.MonkeyPatch) -> list[float]:
    """Every operating point :func:`feeddrive.analysis.linear.rightmost_pole` linearises."""
    from feeddrive.analysis import linear

    seen: list[float] = []
    original = linear.rightmost_pole

    def counted(system, v, nut_speed=0.0):  # type: ignore[no-untyped-def]
        seen.append(v)
        return original(system, v, nut_speed)

    monkeypatch.setattr(linear, "rightmost_pole", counted)
    return seen


@pytest.mark.parametrize("position", [0.4, 0.2])
def test_upper_edge_is_the_bands_top_edge_with_fewer_linearisations(
        monkeypatch: pytest.MonkeyPatch, position: float) -> None:
    """issue 42 item 5: the report's sensitivity reads only the band's upper edge; scanning
    down from the top and bisecting that one change gives stability_band's number bit for
    bit (the same grid and midpoints) at 15 of its 37 linearisations on the report's
    20-point grid (CDFS: the top unstable scan point is the 5th from the top, then 10
    halvings to 1e-6 m/s; the full band adds the other 15 scan points, the lower edge's 6
    halvings and the mode frequency)."""
    from feeddrive.analysis.linear import upper_band_edge
    from feeddrive.reproduce.sensitivity_section import LINEAR_POINTS

    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", position)
    seen = _count_linearisations(monkeypatch)
    band = stability_band(system, points=LINEAR_POINTS)
    full = len(seen)
    seen.clear()
    edge = upper_band_edge(system, points=LINEAR_POINTS)
    assert band.intervals and edge == band.intervals[-1][1]
    assert len(seen) < full / 2
    if position == 0.4:
        assert (full, len(seen)) == (37, 15)
        from pathlib import Path

        doc = " ".join((Path(__file__).resolve().parents[2] / "docs" / "linear.md")
                       .read_text(encoding="utf-8").split())
        assert f"({len(seen)} linearisations instead of {full} for the CDFS at mid-screw on " \
               f"a {LINEAR_POINTS}-point grid)" in doc


def test_upper_edge_of_a_band_reaching_the_top_or_of_none(monkeypatch) -> None:
    """The two ends of the rule: unstable at the highest scanned speed → that speed (one
    linearisation); stable everywhere → NaN, as stability_band has no interval."""
    from feeddrive.analysis.linear import upper_band_edge

    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    seen = _count_linearisations(monkeypatch)
    # wang2021's CDFS band is 0.17–1.40 mm/s (linear.stability_band's example)
    assert upper_band_edge(system, low=0.3e-3, high=1.0e-3, points=5) == 1.0e-3
    assert len(seen) == 1
    band = stability_band(system, low=2e-3, high=5e-3, points=4)
    assert not band.intervals
    assert math.isnan(upper_band_edge(system, low=2e-3, high=5e-3, points=4))


def test_in_process_sensitivity_counts_its_linearisations(monkeypatch) -> None:
    """The in-process points (the report's section) linearise for the upper edge only, and
    give the elasticity the store's full bands give."""
    from feeddrive.analysis.sensitivity import _linear_upper
    from feeddrive.parameters import dumps
    from feeddrive.sweep.quantities import evaluate

    params = fd.preset("wang2021")
    task = {"parameters": dumps(params), "drive": "cdfs", "table_position": 0.4,
            "nut_speed": 0.0, "quantity": {"kind": "linear-band", "low": 1e-5, "high": 5e-3,
                                           "linear_points": 20}}
    seen = _count_linearisations(monkeypatch)
    full = evaluate(task, params)
    n_full = len(seen)
    seen.clear()
    upper = _linear_upper(task, params)
    assert upper["values"]["linear_upper"] == full["values"]["linear_upper"]
    assert (n_full, len(seen)) == (37, 15)
    seen.clear()
    result = sensitivity(params, quantity="linear-band", in_process=True, linear_points=20,
                         patterns=["controller.velocity_gain"])
    # base, ±10 %, the halving check's ±5 %: five points of at most 20 + 10 linearisations
    assert result.evaluations == 5 and len(seen) <= 5 * 15
    bad = {**task, "quantity": {**task["quantity"], "low": 6e-3}}
    assert "low" in _linear_upper(bad, params)["error"]


def test_a_points_task_carries_the_integrator_settings_in_force() -> None:
    """``feeddrive sensitivity --accuracy 0.1`` reached neither the worker processes' searches
    nor the store's keys (found 2026-12-06: the keys were identical with and without it); each
    point's task now carries the settings in force, as a sweep's does."""
    from types import SimpleNamespace

    from feeddrive.analysis.sensitivity import _task
    from feeddrive.engine.options import using
    from feeddrive.sweep.quantities import QuantitySettings
    from feeddrive.sweep.store import point_key

    config = SimpleNamespace(table_position=400.0, drive="cdfs",
                             quantity=QuantitySettings.parse({"kind": "critical-speed",
                                                              "linear": False}))
    params = fd.preset("wang2021")
    default = _task(config, params)
    with using(fd.SolverOptions(accuracy=0.1)):
        tighter = _task(config, params)
    assert default["solver"] == fd.SolverOptions().record()
    assert tighter["solver"]["accuracy"] == 0.1
    assert point_key(default) != point_key(tighter)
