"""Resampling is bounded by the data's size: issue 13, item 1.

Guard: ``feeddrive analyze`` on a 31-row CSV whose last timestamp is 1e6 s built a 10⁹-point
grid and died with MemoryError; a gap of 1e5 s grew to 8.9 GB over 86 s first.
"""

from __future__ import annotations

import numpy as np
import pytest

from feeddrive.analysis.creep_window import creep_metrics
from feeddrive.analysis.presliding import fit_presliding
from feeddrive.analysis.trace import analyze_trace, estimate_speed
from feeddrive.analysis.trace_input import MAX_RESAMPLE_FACTOR


def gap_trace(gap: float) -> tuple[np.ndarray, np.ndarray]:
    t = np.append(np.arange(30) * 0.01, gap)
    return t, 1e-3 * t


@pytest.mark.parametrize("gap", [1e5, 1e6])
def test_gap_is_refused_naming_the_line(gap: float) -> None:
    t, x = gap_trace(gap)
    lines = np.arange(2, 33)
    with pytest.raises(ValueError, match=r"trace.csv: time: a gap of .* before line 32 .* "
                                         f"more than {MAX_RESAMPLE_FACTOR}× the 31 samples"):
        analyze_trace(t, x, source="trace.csv", lines=lines)
    with pytest.raises(ValueError, match="before sample 30"):
        estimate_speed(t, x)
    with pytest.raises(ValueError, match="a gap"):
        analyze_trace(t, x, speed=np.full(t.size, 1e-3), source="trace.csv")
    with pytest.raises(ValueError, match="a gap"):
        creep_metrics(t, 1e-3 + 1e-3 * np.sin(40 * t), 1e-3, window=(0.0, gap))


def test_jittered_sampling_is_still_resampled() -> None:
    t = np.arange(2000) * 1e-3
    t = t + np.random.default_rng(0).uniform(0, 3e-5, t.size)
    est = estimate_speed(t, 1.5e-3 * t)
    assert est.resampled and est.time.size <= MAX_RESAMPLE_FACTOR * t.size


def test_presliding_gap_is_refused() -> None:
    t = np.append(np.arange(40) * 1e-3, 1e6)
    f = np.linspace(0, 10, t.size)
    with pytest.raises(ValueError, match=r"line 42: time jumps by 1e\+06 s"):
        fit_presliding(t, f, f * 1e-7, mass=100.0, model="linear", lines=np.arange(2, 43))
