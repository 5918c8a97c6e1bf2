"""The reference kernel's held samples (SampledSpeed(hold=True)) and external input block
(REF_INPUT, the FMU's inputs): values against their definitions."""

from __future__ import annotations

import numpy as np
import pytest

from feeddrive.fmu.model import InputReference
from feeddrive.model.reference import PROFILE_PARAMS, REF_INPUT, SampledSpeed, reference_kernel


def _call(profile: object, t: float) -> tuple[float, float, float, float]:
    values, table = profile.encode()  # type: ignore[attr-defined]
    P = np.zeros(len(PROFILE_PARAMS))
    for k, v in values.items():
        P[k] = v
    P[5], P[6] = 0.0, table.shape[1]
    return reference_kernel(t, P, 0, np.ascontiguousarray(table).ravel())


def test_held_samples_are_a_staircase_with_exact_integrals() -> None:
    t = np.arange(6) * 0.01
    v = np.array([0.0, 1.0, 3.0, 2.0, 2.0, 5.0]) * 1e-3
    prof = SampledSpeed(t, v, 2 * v, hold=True)
    x = 0.0
    for k in range(5):
        for f in (0.0, 0.3, 0.999):
            xt, vt, xn, vn = _call(prof, t[k] + f * 0.01)
            assert vt == v[k] and vn == 2 * v[k]  # held, right-continuous at the sample
            assert xt == pytest.approx(x + v[k] * f * 0.01, abs=1e-18)
            assert xn == pytest.approx(2 * (x + v[k] * f * 0.01), abs=1e-18)
        x += v[k] * 0.01
    linear = _call(SampledSpeed(t, v), 0.015)[1]
    assert linear == pytest.approx(2e-3)  # the default still interpolates


def test_a_sample_instant_computed_a_hair_early_takes_the_new_value() -> None:
    t = np.arange(4) * 1e-3
    v = np.array([1.0, 2.0, 3.0, 4.0])
    prof = SampledSpeed(t, v, hold=True)
    assert _call(prof, 0.002 * (1 - 1e-14))[1] == 3.0  # t/dt = 1.99999999999998
    assert _call(prof, 0.002 * (1 - 1e-6))[1] == 2.0  # a real instant before the sample


def test_input_block_reads_positions_speeds_and_rates() -> None:
    values, table = InputReference(2e-3, 5e-3).encode()
    assert values == {0: REF_INPUT}
    P = np.zeros(len(PROFILE_PARAMS))
    P[0], P[4], P[6] = REF_INPUT, 1.5, 2  # the block was written at t0 = 1.5 s
    T = np.array([0.1, 0.0, 2e-3, 1e-3, 0.2, 0.0, 5e-3, -1e-3])
    xt, vt, xn, vn = reference_kernel(1.75, P, 0, T)
    tau = 0.25
    assert (vt, vn) == pytest.approx((2e-3 + 1e-3 * tau, 5e-3 - 1e-3 * tau))
    assert xt == pytest.approx(0.1 + 2e-3 * tau + 0.5e-3 * tau**2)
    assert xn == pytest.approx(0.2 + 5e-3 * tau - 0.5e-3 * tau**2)
    assert table[1, 0] == 2e-3 and table[3, 0] == 5e-3
