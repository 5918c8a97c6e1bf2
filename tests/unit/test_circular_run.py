"""The ISO 230-4 circular test run on a machine (issue 37 items 1 and 5): the runs' layout,
a DDFS's nut speed, and which friction sites reverse."""

from __future__ import annotations

import math

import numpy as np
import pytest

from feeddrive.analysis.circular_run import (
    _lead_in,
    circular_start_angles,
    run_circular_test,
    settling_lead,
)
from feeddrive.machine import load_machine, machine_from_dict
from feeddrive.parameters import ParameterError

FEED = 5000.0 / 6e4  # [m/s]
DDFS = {"extends": "wang2021", "drive": "ddfs"}


def test_runs_measure_from_45_degrees_and_join_into_one_path() -> None:
    lead = math.radians(90.0)
    starts = circular_start_angles(lead)
    # the CCW run ends (start + 360° + 2 lead arcs) where the CW run starts
    assert math.isclose((starts["CCW"] + 2 * math.pi + 2 * lead) % (2 * math.pi),
                        starts["CW"] % (2 * math.pi))
    assert math.degrees(starts["CCW"] + lead) == pytest.approx(45.0)
    assert math.degrees(starts["CW"] - lead) == pytest.approx(45.0)


def test_a_ddfs_nut_faster_than_the_table_keeps_screw_and_nut_from_reversing() -> None:
    """Issue 37 item 5, what the study rests on: on the circle every axis reverses twice per
    run; a CDFS's screw reverses with its table, a DDFS's screw and nut at a nut speed above
    the feed (200 > 83.3 mm/s) never do — only the guide's friction reverses."""
    ddfs = machine_from_dict({"name": "ddfs-xy", "axes": {"x": DDFS, "y": DDFS}})
    run = run_circular_test(ddfs, radius=0.05, feed=FEED, nut_speed=0.2)
    assert run.start_time == pytest.approx(0.2 / 1.0 + 0.5)
    nut = np.asarray(run.results["CW"]["x.nut_speed"])[
        np.asarray(run.results["CW"].time) > run.start_time]
    lead = 0.005 / (2 * math.pi)  # wang2021 lead 5 mm
    assert nut * lead == pytest.approx(0.2, rel=0.02)  # the nut runs at its speed
    assert run.reversing_sites() == {axis: {"screw": 0, "nut": 0, "guide": 4}
                                     for axis in ("x", "y")}
    cdfs = run_circular_test(load_machine("xy-table"), radius=0.05, feed=FEED)
    assert {axis: sites["screw"] for axis, sites in cdfs.reversing_sites().items()} == {
        "x": 4, "y": 4}


def test_refusals_come_before_any_run(monkeypatch) -> None:
    import feeddrive.engine.simulate as engine

    def no_run(*a: object, **k: object) -> None:
        raise AssertionError("simulated a refused request")

    monkeypatch.setattr(engine, "simulate", no_run)
    xy = load_machine("xy-table")
    with pytest.raises(ParameterError, match="nut_speed = 0.1: no axis of the test drives"):
        run_circular_test(xy, radius=0.05, feed=FEED, nut_speed=0.1)
    with pytest.raises(ParameterError, match="axes = "):
        run_circular_test(xy, radius=0.05, feed=FEED, axes=("x", "x"))
    with pytest.raises(ParameterError, match="lead_arc = 0.05: the feed ramp"):
        run_circular_test(xy, radius=0.05, feed=FEED, lead_arc=0.05)
    with pytest.raises(ParameterError, match="lead_arc = -1.0: expected a value > 0"):
        run_circular_test(xy, radius=0.05, feed=FEED, lead_arc=-1.0)


def test_a_loop_that_does_not_settle_has_no_rule_lead_and_is_refused_before_any_run(
        monkeypatch) -> None:
    """The settling rule needs a decaying slowest mode: at K_vi = 15000 the wang2021 loop's
    rightmost pole at 5000 mm/min is +2.09 1/s (10.4 Hz; docs/extending.md: friction off
    diverges at 15000), so no lead-in settles it — refused in one line, no run; a lead arc
    given is taken, with the rule's stated as not computed."""
    import feeddrive.engine.simulate as engine
    def no_run(*a: object, **k: object) -> None:
        raise AssertionError("simulated a refused request")

    monkeypatch.setattr(engine, "simulate", no_run)
    axis = {"extends": "wang2021", "drive": "cdfs",
            "controller": {"velocity_integral_gain": 15000.0}}
    hunting = machine_from_dict({"name": "u", "axes": {"x": axis, "y": axis}})
    with pytest.raises(ParameterError, match=r"pole at 2.09 1/s \(10.4 Hz\) that does not "
                       "decay; no lead-in lets it settle; expected the lead arc given"):
        settling_lead(hunting, ("x", "y"), radius=0.05, feed=FEED, acceleration=1.0)
    with pytest.raises(ParameterError, match="does not decay"):
        run_circular_test(hunting, radius=0.05, feed=FEED)
    given = _lead_in(hunting, ("x", "y"), 0.05, FEED, 1.0, 0.0, math.radians(90.0))
    assert given.given and math.isnan(given.rule_arc)
    assert given.describe() == "lead arcs 90° as given (the settling rule not computed)"
    # the JSON names what was not computed as null (print_json refuses NaN)
    shown = given.to_dict()
    assert shown["rule_lead_arc_deg"] is None and shown["slowest_mode_decay_1_s"] is None
    assert "does not decay" in shown["notes"][0]


def test_a_given_lead_arc_carries_the_rules_beside_it() -> None:
    xy = load_machine("xy-table")
    rule = settling_lead(xy, ("x", "y"), radius=0.05, feed=FEED, acceleration=1.0)
    given = _lead_in(xy, ("x", "y"), 0.05, FEED, 1.0, 0.0, math.radians(90.0))
    assert given.given and not rule.given and given.rule_arc == rule.arc
    assert given.arc == math.radians(90.0)
    assert given.describe().startswith(
        f"lead arcs 90° as given (the settling rule's {math.degrees(rule.arc):.4g}°: the feed "
        "ramp, then the slowest closed-loop mode (axis x, 5.44 Hz, decaying at 1.79 1/s) "
        "down to 0.1%")
