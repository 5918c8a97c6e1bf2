"""Stiffness chain (feeddrive.model.mechanisms.ball_screw_stiffness): Wang2021 Eqs. (2)–(5),
written out independently."""

from __future__ import annotations

import math

import numpy as np
import pytest

from feeddrive import ParameterError, preset
from feeddrive.model.mechanisms import ball_screw_stiffness as stiffness

PARAMS = preset("wang2021")
S = PARAMS.screw


def eq4(a: float) -> float:
    """k_sa = π d² E l / (4 a (l − a)) [N/m], Wang2021 Eq. (4)."""
    return math.pi * S.diameter**2 * S.youngs_modulus * S.length / (4.0 * a * (S.length - a))


def chain(a: float, n: float = 2.0, eta: float | None = None, torsion: bool = True) -> float:
    """K_eq [N/m] from Eqs. (2), (3) and (5) with k_sa of Eq. (4)."""
    k_t1 = 1.0 / (1.0 / PARAMS.coupling.torsional_stiffness + 1.0 / S.torsional_stiffness)
    k_a = 1.0 / (n / S.support_bearing_axial_stiffness + 1.0 / eq4(a)
                 + 1.0 / S.nut_axial_stiffness + 1.0 / S.nut_bearing_axial_stiffness)
    h = S.lead / (2.0 * math.pi)
    inv = 1.0 / k_a + (h**2 / (eta or S.efficiency) / k_t1 if torsion else 0.0)
    return 1.0 / inv


@pytest.mark.parametrize("a", [0.05, 0.2, 0.4, 0.61, 0.79])
def test_chain_follows_eqs_2_to_5(a: float) -> None:
    c = stiffness.stiffness_chain(PARAMS, a)
    assert float(c.screw_axial) == pytest.approx(eq4(a), rel=1e-13)
    assert float(c.equivalent_chain) == pytest.approx(chain(a), rel=1e-13)
    assert float(c.equivalent) == float(c.equivalent_chain)
    assert c.torsional == pytest.approx(1.0 / (1 / 2.81e4 + 1 / 61368.0), rel=1e-13)


def test_chain_is_vectorised_and_symmetric_about_mid_screw() -> None:
    a = np.array([0.1, 0.25, 0.4, 0.55, 0.7])
    c = stiffness.stiffness_chain(PARAMS, a)
    assert c.equivalent.shape == a.shape
    np.testing.assert_allclose(c.equivalent, c.equivalent[::-1], rtol=1e-13)
    assert np.argmin(c.screw_axial) == 2


def test_fixed_free_reading() -> None:
    params = PARAMS.replace_path("stiffness.screw_support", "fixed-free")
    a = 0.3
    want = math.pi * S.diameter**2 * S.youngs_modulus / (4.0 * a)
    assert float(stiffness.stiffness_chain(params, a).screw_axial) == pytest.approx(want, rel=1e-13)


def test_equivalent_stiffness_override_is_honoured() -> None:
    params = PARAMS.replace_path("stiffness.equivalent_stiffness", 2.16e7)
    a = np.array([0.2, 0.4, 0.6])
    c = stiffness.stiffness_chain(params, a)
    np.testing.assert_array_equal(c.equivalent, np.full(3, 2.16e7))
    np.testing.assert_allclose(c.equivalent_chain, [chain(x) for x in a], rtol=1e-13)
    assert stiffness.equivalent_stiffness(params, 0.123) == 2.16e7


@pytest.mark.parametrize("a", [0.0, -0.1, 0.8, 0.9, math.nan, math.inf])
def test_positions_outside_the_supports_are_refused(a: float) -> None:
    with pytest.raises(ParameterError) as info:
        stiffness.stiffness_chain(PARAMS, a)
    assert info.value.field == "table_position"
    assert "m" in str(info.value)


def test_mid_screw_readings_are_sorted_distinct_and_none_is_exact() -> None:
    readings = stiffness.mid_screw_readings(PARAMS)
    deviations = [abs(r.deviation) for r in readings]
    assert deviations == sorted(deviations)
    assert len({r.description for r in readings}) == len(readings)
    # 3 spans × 3 bearing counts × (3 η with torsion + 1 without)
    assert len(readings) == 36
    assert min(deviations) > 0.01
    mid = stiffness.mid_screw_position(S)
    assert mid == 0.4
    for r in (r for r in readings if r.screw_support == "fixed-fixed"):
        assert r.equivalent_stiffness == pytest.approx(
            chain(mid, r.bearing_count, r.efficiency, r.include_torsion), rel=1e-12)
