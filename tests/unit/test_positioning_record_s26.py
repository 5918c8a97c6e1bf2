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
