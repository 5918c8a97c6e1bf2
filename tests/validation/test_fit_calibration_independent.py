"""Calibration of `feeddrive fit`'s intervals on traces feeddrive did not make (issue 36
item 6), the seeded 20-set version of benchmarks/fit_calibration_independent.py.

Truth: ``wang2021``'s CDFS with the gain ×1.2, screw viscous coefficient ×0.8 and static
force ×1.1, integrated by scipy's Radau on the plain-Python model (reference/fit_traces.py,
rtol 1e-9) at 1, 2 and 5 mm/s for 2 s; each seed measures it as a rig does (0.05-µm counts
from a start drawn within a count, 1 % current noise). This checks the numerical part of the
intervals (integration error, quantised records), not the model's structure.
Acceptance (issue 36): each 95 % interval covers the truth in ≥ 16 of 20 seeds (met), the
mean (estimate − truth)/s.e. lies within ±0.5 and its mean |…| within 0.6–1.4 (not met on
these 20 seeds: marked xfail with the measured values); "model inadequate" in ≤ 5 % of the
seeds (met).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.fit_traces import FACTORS as FREE  # noqa: E402
from reference.fit_traces import SPEEDS, calibration_truth, measured, radau_trace  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.analysis.fit import fit_drive  # noqa: E402

SEEDS = 20


@pytest.fixture(scope="module")
def calibration() -> tuple[dict[str, np.ndarray], dict[str, int], int]:
    """Per parameter the 20 values of (estimate − truth)/s.e. and the number of intervals
    covering the truth; and how many fits said "model inadequate"."""
    base = fd.preset("wang2021")
    truth, values = calibration_truth()
    traces = [radau_trace(truth, v, 2.0) for v in SPEEDS]
    z: dict[str, list[float]] = {p: [] for p in FREE}
    inside = dict.fromkeys(FREE, 0)
    inadequate = 0
    for seed in range(SEEDS):
        result = fit_drive(base, [measured(tr, 1000 * seed + k)
                                  for k, tr in enumerate(traces)], list(FREE))
        inadequate += result.inadequate is not None
        for e in result.estimates:
            z[e.path].append((e.value - values[e.path]) / e.stderr)
            inside[e.path] += e.low <= values[e.path] <= e.high
    return {p: np.array(v) for p, v in z.items()}, inside, inadequate


@pytest.mark.slow
def test_intervals_cover_an_independent_integrators_truth(calibration) -> None:
    _, inside, inadequate = calibration
    for path in FREE:
        assert inside[path] >= 16, (path, inside[path])
    assert inadequate <= 1  # ≤ 5 % of 20


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="issue 36 Acceptance not met on these 20 seeds: mean "
                   "(estimate - truth)/s.e. -0.26, -0.54, -0.60 (over 100 seeds -0.12, -0.25, "
                   "-0.34: a one-signed bias remains; docs/fitting.md, Calibration)")
def test_no_one_signed_bias(calibration) -> None:
    z, _, _ = calibration
    for path in FREE:
        assert abs(float(z[path].mean())) <= 0.5, (path, z[path].mean())


@pytest.mark.slow
@pytest.mark.xfail(strict=False, reason="borderline on these 20 seeds: mean |(estimate - "
                   "truth)/s.e.| 0.60, 0.73, 0.99, the gain's on the edge of 0.6-1.4 (over 100 "
                   "seeds 0.65, 0.77, 0.99; docs/fitting.md, Calibration)")
def test_intervals_are_calibrated_not_only_wide(calibration) -> None:
    z, _, _ = calibration
    for path in FREE:
        assert 0.6 <= float(np.abs(z[path]).mean()) <= 1.4, (path, np.abs(z[path]).mean())
