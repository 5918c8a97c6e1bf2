"""Friction compensation (issue 14): static feed-forward and the LuGre observer of Canudas de
Wit et al. (IEEE TAC 40 (1995) 419–425, Sect. V) on the wang2021 CDFS."""

from __future__ import annotations

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.analysis.compensation import Case, default_cases, evaluate
from feeddrive.analysis.critical import creep_trial
from feeddrive.linear import stability_band
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
