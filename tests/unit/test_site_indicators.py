"""Issue 24 item 7: `feeddrive friction --site guide` reported LuGre numbers (a negative-slope
band 0.008–3.571 mm/s, a passivity FAIL) for a guide set to the Dahl law or to none."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from feeddrive.model.friction.indicators import site_sliding_stability, steady_slope
from feeddrive.model.friction.stribeck import negative_slope_band, sliding_stability
from feeddrive.parameters import preset

GUIDE = preset("wang2021").friction.guide


def test_generic_linearisation_matches_the_lugre_cubic() -> None:
    """Cross-path check: the eigenvalues of the oscillator built from LuGre.linearise agree
    with the Åström–Canudas de Wit cubic of feeddrive.model.friction.stribeck (a light, stiff
    case where the scan has an unstable band, and the drive's own K_eq case)."""
    speeds = np.geomspace(1e-5, 5e-3, 60)
    for mass, k, c in ((1.0, 2e4, 0.0), (20.0, 32.3e6, 2541.0)):
        poly = sliding_stability(speeds, [GUIDE], mass, k, c)
        eig = site_sliding_stability(speeds, GUIDE, mass, k, c, analytic=False)
        assert np.array_equal(poly.stable, eig.stable)
        np.testing.assert_allclose(eig.max_real_part, poly.max_real_part, rtol=1e-4,
                                   atol=1e-6 * np.max(np.abs(poly.max_real_part)))
    assert not sliding_stability(speeds, [GUIDE], 1.0, 2e4, 0.0).stable.all()


def test_dahl_has_no_negative_slope_and_none_no_friction() -> None:
    dahl = replace(GUIDE, law="dahl")
    for branch in ("positive", "negative"):
        s = steady_slope(dahl, branch)
        # Dahl's steady curve is F_c + σ2 v: its slope is σ2 (61.6 N s/m on the + branch)
        assert s.band is None
        assert s.min_slope == pytest.approx(GUIDE.branch(branch).viscous_coefficient,
                                            rel=1e-3)
    none = replace(GUIDE, law="none")
    assert steady_slope(none, "positive").band is None
    speeds = np.geomspace(1e-5, 5e-3, 20)
    assert site_sliding_stability(speeds, none, 1.0, 2e4, 10.0).stable.all()
    # LuGre keeps the analytic band of Wang2021 Eq. (11)
    assert steady_slope(GUIDE, "positive").band == negative_slope_band(GUIDE.positive)
