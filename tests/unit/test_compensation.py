"""Friction compensation (issue 14): static feed-forward and the LuGre observer of Canudas de
Wit et al. (IEEE TAC 40 (1995) 419–425, Sect. V) on the wang2021 CDFS."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.analysis.compensation import Case, default_cases, evaluate
from feeddrive.analysis.critical import creep_trial
from feeddrive.analysis.linear import stability_band
from feeddrive.parameters import Compensation, ParameterError

W = fd.preset("wang2021")


def _system(**comp: object) -> fd.DriveSystem:
    return fd.DriveSystem(W.replace_path("controller.compensation", Compensation(**comp)),
                          "cdfs", 0.4)


def test_exact_observer_removes_the_creep_band_and_the_simulation_agrees() -> None:
    """Issue 14 acceptance: linear band gone with the exact model; at 1 mm/s (inside the
    uncompensated band, where the CDFS creeps) the compensated table runs smoothly."""
    plain = stability_band(_system(), points=15)
    assert plain.intervals and plain.intervals[0][0] < 1e-3 < plain.intervals[0][1]
    observer = stability_band(_system(mode="observer"), points=15)
    assert observer.intervals == []
    assert creep_trial(_system(), 1e-3).kind == "stick-slip"
    assert creep_trial(_system(mode="observer"), 1e-3).kind == "smooth"


def test_static_feedforward_leaves_the_linear_band_unchanged() -> None:
    """Feed-forward of the steady curve at the commanded speed is a constant at steady sliding:
    it cannot change the damping the Stribeck slope takes away."""
    plain = stability_band(_system(), points=15)
    ff = stability_band(_system(mode="feedforward"), points=15)
    np.testing.assert_allclose(ff.intervals, plain.intervals, rtol=1e-9)


def test_feedforward_force_is_the_steady_curve_of_the_compensated_sites() -> None:
    r = fd.simulate(_system(mode="feedforward"), fd.ConstantSpeed(2e-3, ramp_time=0.0), 0.2)
    v = r["table_speed_reference"]
    expected = (fd.friction.steady_friction(v, W.friction.screw)
                + fd.friction.steady_friction(v, W.friction.guide))
    np.testing.assert_allclose(r["compensation_force"], expected, rtol=1e-12)


def test_mismatch_scales_the_compensators_model() -> None:
    r1 = fd.simulate(_system(mode="feedforward"), fd.ConstantSpeed(2e-3, ramp_time=0.0), 0.1)
    r2 = fd.simulate(_system(mode="feedforward", coulomb_scale=1.2, static_scale=1.2,
                             stribeck_velocity_scale=1.2),
                     fd.ConstantSpeed(2e-3, ramp_time=0.0), 0.1)
    assert r2["compensation_force"][-1] == pytest.approx(1.2 * r1["compensation_force"][-1],
                                                         rel=0.05)
    assert r2["compensation_force"][-1] != r1["compensation_force"][-1]


def test_study_cases_and_a_fast_row() -> None:
    cases = default_cases(0.2)
    assert [c.compensation.mode for c in cases].count("observer") == 3
    assert cases[-1].drive == "ddfs"
    row = evaluate(W, Case("exact observer", "cdfs", Compensation(mode="observer")),
                   search=False)
    assert row["linear_unstable_bands_mm_s"] == []
    assert row["verdict_at_tracking_speed"] == "smooth"
    assert row["following_error_rms_um"] < 1.0


def test_compensation_with_sampled_loops_is_refused() -> None:
    p = (W.replace_path("controller.compensation", Compensation(mode="observer"))
         .replace_path("controller.velocity_period", 5e-4))
    with pytest.raises(ParameterError, match="compensation.mode.*continuous"):
        fd.simulate(fd.DriveSystem(p, "cdfs", 0.4), fd.ConstantSpeed(1e-3), 0.1)


def test_observer_gain_table_of_the_docs_and_the_warning() -> None:
    """Issue 24 item 9: at k = 100 1/s the observer destabilised the loop at 0.5 mm/s and
    nothing said what k is usable.  docs/linear.md's table (marked entries) and the warning
    `feeddrive simulate` prints."""
    from feeddrive.analysis.compensation import observer_gain_warning
    from feeddrive.analysis.linear import rightmost_pole

    def system(k: float) -> fd.DriveSystem:
        comp = Compensation(mode="observer", observer_gain=k)
        return fd.DriveSystem(W.replace_path("controller.compensation", comp), "cdfs", 0.4)

    for k, growth in ((0.0, -1.15), (3.0, -0.75), (100.0, 16.7)):
        # the table's 3 significant digits
        assert rightmost_pole(system(k), 0.5e-3)[0] == pytest.approx(growth, rel=0.005,
                                                                      abs=0.006), k
    text = observer_gain_warning(system(100.0), 0.5e-3)
    assert text is not None and "observer_gain = 100 1/s" in text and "0.5 mm/s" in text
    assert observer_gain_warning(system(100.0), 5e-3) is None  # stable there
    assert observer_gain_warning(system(0.0), 0.5e-3) is None
    assert observer_gain_warning(system(3.0), 0.5e-3) is None
    doc = (Path(__file__).resolve().parents[2] / "docs" / "linear.md").read_text()
    assert "| 100 | +45.1 | **+16.7** |" in doc and "| 3 | +4.57 | **−0.75** |" in doc
