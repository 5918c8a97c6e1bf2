"""Linear stability of steady sliding (feeddrive.model.friction.stribeck.characteristic_polynomial).

Reference: Åström & Canudas de Wit, "Revisiting the LuGre friction model", IEEE Control
Systems Magazine 28(6), 2008: a mass m pulled at constant speed through a spring k and a
damper c, sliding on one LuGre site, has the characteristic polynomial
m s³ + (mλ + c + σ2 − aσ1) s² + (cλ + k + σ2λ − aσ0) s + kλ,
with λ = σ0|v|/G(v) and a = −|v| G'(|v|)/G(v), G the Stribeck magnitude σ0 g.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from feeddrive import friction, preset
from feeddrive.parameters import LuGreParameters

PARAMS = preset("wang2021")
SITES: dict[str, LuGreParameters] = {
    "screw": PARAMS.friction.screw,
    "nut": PARAMS.friction.nut,
    "guide": PARAMS.friction.guide,
}


def linearisation(v: float, p: LuGreParameters) -> tuple[float, float, float]:
    """(λ [1/s], a [-], σ2 [N s/m]) at steady sliding speed v, written out independently."""
    b = p.positive if v >= 0 else p.negative
    u = abs(v) / b.stribeck_velocity
    drop = b.static_force - b.coulomb_force
    g = b.coulomb_force + drop * math.exp(-u * u)
    dg = -2.0 * drop * u / b.stribeck_velocity * math.exp(-u * u)  # dG/d|v|
    return p.bristle_stiffness * abs(v) / g, -abs(v) * dg / g, b.viscous_coefficient


def explicit_cubic(v: float, p: LuGreParameters, m: float, k: float, c: float) -> np.ndarray:
    lam, a, s2 = linearisation(v, p)
    s0, s1 = p.bristle_stiffness, p.bristle_damping
    return np.array([m, m * lam + c + s2 - a * s1, c * lam + k + s2 * lam - a * s0, k * lam])


def steady_slope(v: float, p: LuGreParameters) -> float:
    """d(steady friction)/dv [N s/m] = σ2 + G'(|v|) for the branch of v."""
    lam, a, s2 = linearisation(v, p)
    return s2 - a * p.bristle_stiffness / lam


@pytest.mark.parametrize("site", sorted(SITES))
@pytest.mark.parametrize("v", [3e-5, -3e-5, 7e-4, -7e-4, 1.6e-3, -1.6e-3, 6e-3])
@pytest.mark.parametrize(("m", "k", "c"), [(20.0, 3.23e7, 0.0), (2370.0, 1e5, 250.0),
                                           (0.5, 1e3, 1e4)])
def test_one_site_polynomial_is_the_astrom_canudas_cubic(site: str, v: float, m: float,
                                                         k: float, c: float) -> None:
    p = SITES[site]
    got = friction.characteristic_polynomial(v, [p], m, k, c)
    want = explicit_cubic(v, p, m, k, c)
    assert got.shape == (4,)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.max(np.abs(want)))


def test_two_identical_sites_share_the_factor_s_plus_lambda() -> None:
    """Two sites with the same state dynamics: the quartic has the root s = −λ."""
    p = SITES["screw"]
    v = 1e-3
    lam, _, _ = linearisation(v, p)
    quartic = friction.characteristic_polynomial(v, [p, p], 20.0, 3e7, 10.0)
    assert quartic.shape == (5,)
    assert np.polyval(quartic, -lam) == pytest.approx(0.0, abs=1e-9 * np.polyval(np.abs(quartic),
                                                                                  lam))


@pytest.mark.parametrize("site", sorted(SITES))
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_huge_damping_is_stable_at_all_speeds(site: str, sign: float) -> None:
    p = SITES[site]
    speeds = sign * np.geomspace(1e-5, 1e-2, 200)
    scan = friction.sliding_stability(speeds, [p], mass=20.0, stiffness=3.23e7, damping=1e7)
    assert scan.stable.all()
    assert friction.unstable_speed_band(scan) is None
    assert np.all(scan.max_real_part < 0.0)


@pytest.mark.parametrize("site", sorted(SITES))
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_soft_undamped_spring_is_unstable_inside_the_negative_slope_band(site: str,
                                                                         sign: float) -> None:
    p = SITES[site]
    branch = p.positive if sign > 0 else p.negative
    band = friction.negative_slope_band(branch)
    assert band is not None
    m, k = 20.0, 1e2
    # Routh–Hurwitz on the cubic: the s¹ coefficient is k + λ·slope, negative (→ unstable)
    # wherever the steady slope is steep enough; check that set independently
    speeds = sign * np.geomspace(band.lower, band.upper, 102)[1:-1]
    expected_unstable = np.array([k + linearisation(v, p)[0] * steady_slope(v, p) < 0.0
                                  for v in speeds])
    assert expected_unstable.sum() > 50
    scan = friction.sliding_stability(speeds, [p], mass=m, stiffness=k, damping=0.0)
    assert np.all(~scan.stable[expected_unstable])
    centre = sign * math.sqrt(band.lower * band.upper)
    assert not friction.sliding_stability(centre, [p], m, k, 0.0).stable[0]
    # every unstable speed lies inside the band; above the band sliding is stable
    wide = sign * np.geomspace(1e-6, 2e-2, 300)
    wide_scan = friction.sliding_stability(wide, [p], m, k, 0.0)
    lo, hi = friction.unstable_speed_band(wide_scan) or (math.nan, math.nan)
    assert band.lower <= lo and hi <= band.upper
    above = sign * np.geomspace(1.05 * band.upper, 2e-2, 50)
    assert friction.sliding_stability(above, [p], m, k, 0.0).stable.all()


def test_stability_scan_refuses_zero_speed() -> None:
    with pytest.raises(ValueError, match="speed"):
        friction.sliding_stability([1e-3, 0.0], [SITES["screw"]], 20.0, 1e7, 0.0)
