"""The stored Radau traces of reference/fit_traces.py (tests/data/radau_fit_traces.npz) are
what the reference integrates, and are read only for the inputs they were made from."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.fit_traces import (  # noqa: E402
    ATOL_SCALE,
    RTOL,
    SPEEDS,
    STORE,
    radau_trace,
    stored_truths,
    trace_key,
)


def test_every_stored_truth_is_in_the_store() -> None:
    with np.load(STORE) as data:
        names = set(data.files)
    for truth, exponents in stored_truths().values():
        for speed in SPEEDS:
            key = trace_key(truth, speed, 2.0, RTOL, ATOL_SCALE, exponents)
            assert {f"{key}_time", f"{key}_table_position", f"{key}_screw_current"} <= names


def test_a_stored_trace_is_the_one_a_fresh_radau_run_makes() -> None:
    # the calibration's truth at 5 mm/s (the cheapest of the stored runs, ≈ 1 CPU s): the
    # stored trace and a fresh integration agree to 1e-8 of the signals' ranges (a trace is
    # host-dependent at the level of its convergence, rtol 1e-9; the fits read positions in
    # 0.05-µm counts, 5e-6 of this trace's 10-mm travel)
    truth, exponents = stored_truths()["calibration"]
    stored = radau_trace(truth, SPEEDS[-1], 2.0, stribeck_exponents=exponents)
    fresh = radau_trace(truth, SPEEDS[-1], 2.0, stribeck_exponents=exponents, stored=False)
    np.testing.assert_array_equal(stored.time, fresh.time)
    for name in ("table_position", "screw_current"):
        a, b = getattr(stored, name), getattr(fresh, name)
        assert np.max(np.abs(a - b)) <= 1e-8 * np.ptp(b), name


def test_the_key_follows_every_input() -> None:
    truth, _ = stored_truths()["calibration"]
    key = trace_key(truth, 1e-3, 2.0, RTOL, ATOL_SCALE, None)
    other = truth.replace_path("friction.screw.positive.static_force",
                               truth.friction.screw.positive.static_force * (1 + 1e-9))
    assert len({key, trace_key(other, 1e-3, 2.0, RTOL, ATOL_SCALE, None),
                trace_key(truth, 1e-3 * (1 + 1e-12), 2.0, RTOL, ATOL_SCALE, None),
                trace_key(truth, 1e-3, 2.5, RTOL, ATOL_SCALE, None),
                trace_key(truth, 1e-3, 2.0, RTOL / 10, ATOL_SCALE, None),
                trace_key(truth, 1e-3, 2.0, RTOL, ATOL_SCALE, {"screw": 1.0})}) == 6
