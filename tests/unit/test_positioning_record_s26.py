"""Targets are written as typed (an outside check, 2026-12-07): `--targets …,175,…` came out as
``175.00000000000003`` in the JSON's ``target_mm`` and in the ``--output`` record (175 mm read
as 0.17500000000000002 m), while the record still reads back to the same deviations."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from feeddrive.analysis.positioning import positioning_test
from feeddrive.io.acceptance import read_positioning_record, write_positioning_record

TARGETS = [v * 1e-3 for v in (100.0, 175.0, 200.3)]  # [m], as the CLI reads mm


def _deviations() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(26)
    return rng.normal(0, 1e-6, (3, 5)), rng.normal(2e-6, 1e-6, (3, 5))


def test_the_json_and_the_record_show_the_targets_as_typed(tmp_path: Path) -> None:
    up, down = _deviations()
    assert repr(TARGETS[1] * 1e3) == "175.00000000000003"  # the float the test is about
    test = positioning_test(TARGETS, up, down)
    assert [t["target_mm"] for t in test.to_dict()["targets"]] == [100.0, 175.0, 200.3]
    path = write_positioning_record(tmp_path / "r.csv", TARGETS, up, down)
    rows = [line.split(",")[0] for line in path.read_text().splitlines()[1:]]
    assert set(rows) == {"100.0", "175.0", "200.3"}
    again = read_positioning_record(path)
    np.testing.assert_allclose(np.asarray(again.deviation_up), up, rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.asarray(again.deviation_down), down, rtol=0, atol=1e-15)


def test_a_reading_of_a_ringing_axis_converges_with_the_output_interval() -> None:
    """The reading is the time average of the trace over the last quarter of the dwell (an
    outside check, 2026-12-07: the plain mean of the samples moved A by 4e-4 µm between 1-
    and 5-ms outputs on a CDFS still ringing while read).  A damped 5.4-Hz ring of 0.3 µm,
    against its closed-form average over the window: at 1-ms samples within 1e-6 of the
    ring's amplitude (measured 2.4e-7; the mean of the samples 7.5e-6), and second order —
    halving the interval divides the error by about 4 (measured 4.0)."""
    from feeddrive.analysis.positioning import Stop, read_approaches

    amp, sigma, omega, centre = 0.3e-6, 1.8, 2 * np.pi * 5.4, 0.1
    end, dwell = 2.0, 2.0
    a = end - 0.25 * dwell  # READ_FRACTION

    def x(t: np.ndarray) -> np.ndarray:
        return centre + amp * np.exp(-sigma * t) * np.sin(omega * t)

    def primitive(t: float) -> float:  # of amp·e^{−σt}·sin ωt
        return amp * np.exp(-sigma * t) * (-sigma * np.sin(omega * t) - omega * np.cos(omega * t)) \
            / (sigma**2 + omega**2)

    exact = centre + (primitive(end) - primitive(a)) / (end - a)
    errors = []
    for h in (1e-3, 5e-4):
        t = np.arange(0.0, end + 0.3, h)
        up, _ = read_approaches(t, x(t), [Stop(centre, 0, 1, 0)], [end], dwell, [centre])
        errors.append(abs(up[0, 0] + centre - exact) / amp)
    assert errors[0] < 1e-6, errors
    assert 3.0 < errors[0] / errors[1] < 5.0, errors
