"""A diverging run is called unstable, not creeping: issue 13, item 5.

Guard: with maximum gains or a 100-t table the loop diverged (table from −1.24 m to +2.05 m
on a 0.8-m screw) and the verdict was "creeping", exit 0.
"""

from __future__ import annotations

import numpy as np
import pytest

from feeddrive.analysis.creep_window import creep_metrics
from feeddrive.analysis.tracking import travel_warning


def test_growing_oscillation_is_unstable_stick_slip_is_not() -> None:
    t = np.linspace(0.0, 10.0, 10001)
    vc = 1e-3
    diverging = vc + vc * 0.5 * np.exp(t) * np.sin(2 * np.pi * 0.5 * t)
    assert creep_metrics(t, diverging, vc).verdict == "unstable"
    backwards = np.full_like(t, -2 * vc)
    assert creep_metrics(t, backwards, vc).verdict == "unstable"
    # stick-slip: stuck, then slipping at ~2.2× the command (the Wang2021 CDFS at 1 mm/s)
    stick_slip = np.where(np.sin(2 * np.pi * 0.6 * t) > 0.1, 2.2 * vc, 0.0)
    m = creep_metrics(t, stick_slip, vc)
    assert m.verdict == "creeping" and m.creeping and not m.unstable


def test_travel_warning() -> None:
    assert travel_warning(0.4, np.array([0.0, 0.1]), 0.8) is None
    text = travel_warning(0.4, np.array([-1.64, 1.65]), 0.8)
    assert text is not None and "-1240 … 2050 mm on a 800-mm screw" in text



@pytest.mark.parametrize("verdict", ["smooth", "creeping", "unstable"])
def test_verdict_values_are_documented(verdict: str) -> None:
    from pathlib import Path
    readme = (Path(__file__).parents[2] / "README.md").read_text(encoding="utf-8")
    assert f"`{verdict}`" in readme
