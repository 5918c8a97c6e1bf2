"""The simulated ISO 230-2 test (issue 37 item 4): its reference and a physics check."""

from __future__ import annotations

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.analysis.positioning_run import axis_speed_limit, run_positioning_test
from feeddrive.model.positioning_profile import stops_profile
from feeddrive.parameters import ParameterError


def frictionless() -> fd.DriveParameters:
    params = fd.preset("wang2021")
    for site in ("screw", "nut", "guide"):
        params = params.replace_path(f"friction.{site}.law", "none")
    return params


def test_reference_rests_exactly_on_each_stop() -> None:
    stops = [0.012, 0.0121, -0.003, 0.0]  # a long move, a short (triangular) one, back
    prof, ends = stops_profile(stops, feed=0.02, acceleration=0.3, dwell=0.2)
    table = prof.encode()[1]
    k_end = np.rint(ends / 1e-3).astype(int)
    k_start = np.rint((ends - 0.2) / 1e-3).astype(int)
    # the kernel's positions (row 0) are the exact integral of the interpolated speed (row 1)
    assert table[0][k_end] == pytest.approx(stops, abs=1e-15)
    assert table[0][k_start] == pytest.approx(stops, abs=1e-15)
    assert np.all(table[1][k_start[0]:k_end[0] + 1] == 0.0)  # at rest through the dwell
    assert np.max(np.abs(table[1])) <= 0.02 * (1 + 1e-12)
    assert np.max(np.abs(np.diff(table[1]))) <= 0.3 * 1e-3 * (1 + 1e-9)


def test_frictionless_axis_has_no_reversal_value() -> None:
    """Physics: without friction (and with no backlash part) nothing tells an approach from
    below from one from above once the axis is at rest, so B ≈ 0 (wang2021's frictionless
    loop rings at about 1 Hz for seconds: the dwell is long enough to let it settle)."""
    run = run_positioning_test(frictionless(), "cdfs", [0.1, 0.11], feed=0.01,
                               acceleration=0.2, dwell=10.0, overshoot=1e-3)
    assert run.test.reversal < 0.01e-6
    assert abs(run.test.mean_reversal) < 0.01e-6
    assert run.test.deviation_up.shape == (2, 5)
    assert run.result.time[-1] == pytest.approx(run.dwell_ends[-1])


def test_requests_refused_before_the_run(monkeypatch) -> None:
    import feeddrive.engine.simulate as engine

    def no_run(*args: object, **kwargs: object) -> None:
        raise AssertionError("simulated a refused request")

    monkeypatch.setattr(engine, "simulate", no_run)
    params = fd.preset("wang2021")
    with pytest.raises(ParameterError, match="cycles"):
        run_positioning_test(params, "cdfs", [0.1, 0.2], cycles=4)
    with pytest.raises(ParameterError, match="travel 0 … 800 mm"):
        run_positioning_test(params, "cdfs", [0.1, 0.799])
    slow = params.replace_path("controller.voltage_limit", 300.0)
    limit, why = axis_speed_limit(slow, "cdfs")
    # U/K_e·lead/2π = 300/0.15 rad/s × 5 mm/2π
    assert limit == pytest.approx(300 / 0.15 * 0.005 / (2 * np.pi), rel=1e-12)
    assert "voltage limit" in why
    with pytest.raises(ParameterError, match="speed limit"):
        run_positioning_test(slow, "cdfs", [0.1, 0.2], feed=1.1 * limit)


def test_pilgrim_cycle_run_rests_on_every_stop() -> None:
    run = run_positioning_test(frictionless(), "cdfs", [0.1, 0.105], kind="pilgrim",
                               feed=0.02, acceleration=0.5, dwell=0.2, overshoot=1e-3)
    r = run.result
    ref = run.start + np.interp(run.dwell_ends, r.time, np.asarray(r["table_position_reference"]))
    assert ref == pytest.approx([s.position for s in run.stops[1:]], abs=1e-12)
    assert [s.direction for s in run.stops if s.target == 0] == [1] * 5 + [-1] * 5
    assert run.test.deviation_down.shape == (2, 5)
