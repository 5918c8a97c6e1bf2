"""The ISO 230-4 circular test run on a machine (issue 37 items 1 and 5): the runs' layout,
a DDFS's nut speed, and which friction sites reverse."""

from __future__ import annotations

import math

import numpy as np
import pytest

from feeddrive.analysis.circular_run import circular_start_angles, run_circular_test
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
