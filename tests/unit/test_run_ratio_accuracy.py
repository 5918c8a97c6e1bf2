"""Where a run's shadow-estimate ratio was measured (an outside check, 2026-12-06): the JSON
wrote ``ratio_to_true_error`` 0.5–1.5 beside every estimate, measured at ``accuracy`` 0.01–1
(tests/validation/test_error_estimate.py, test_accuracy_friction.py), and a CDFS run at
``accuracy`` 100 measured 1.6× on one signal.  The record now names the accuracy range, and a
run outside it carries a note."""

from __future__ import annotations

import feeddrive as fd
from feeddrive.engine.error_estimate import RUN_RATIO, RUN_RATIO_ACCURACY


def _entry(accuracy: float) -> dict:
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    r = fd.simulate(system, fd.ConstantSpeed(2e-3), 0.3,
                    options=fd.SolverOptions(accuracy=accuracy), error_estimate=True)
    return r.solver_stats["error_estimate"]


def test_the_record_names_where_its_ratio_was_measured() -> None:
    inside = _entry(1.0)
    assert inside["ratio_to_true_error"] == list(RUN_RATIO)
    assert inside["ratio_measured_at_accuracy"] == list(RUN_RATIO_ACCURACY) == [0.01, 1.0]
    assert "ratio_note" not in inside


def test_a_run_outside_that_range_says_so() -> None:
    outside = _entry(100.0)
    assert "accuracy 100 is outside" in outside["ratio_note"]
    assert "0.01–1" in outside["ratio_note"]
