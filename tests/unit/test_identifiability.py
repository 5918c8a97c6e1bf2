"""Every fitted value carries an identifiability flag: issue 13, item 6.

Guard: a 5-point static fit printed F_c = 8.5e-19 N with no warning; a header-only static
file was reported as "tests in the negative direction only".  Synthetic data: the Wang2021
Table 1 screw branches (``preset("wang2021")``), steady LuGre curve (Wang2021 Eq. 9).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import feeddrive
from feeddrive.analysis.fit_statistics import MAX_CORRELATION, Estimate
from feeddrive.analysis.static_fit import fit_static
from feeddrive.io.measured import MeasuredDataError, read_static_test
from feeddrive.model.friction.stribeck import steady_friction

SCREW = feeddrive.preset("wang2021").friction.screw


def static_data(speeds: np.ndarray, noise: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    v = np.concatenate([speeds, -speeds])
    f = steady_friction(v, SCREW)
    return v, f * (1 + noise * np.random.default_rng(seed).standard_normal(v.size))


def test_well_designed_fit_is_identifiable() -> None:
    v, f = static_data(np.repeat(np.geomspace(0.05e-3, 50e-3, 40), 5), 0.02)
    fit = fit_static(v, f)
    for b in fit.branches().values():
        assert b.unidentifiable() == {}
        for est in b.estimates().values():
            assert est.identifiable and est.to_dict()["identifiable"] is True
            assert abs(est.max_correlation) < MAX_CORRELATION


def test_five_point_fit_is_flagged() -> None:
    v, f = static_data(np.geomspace(0.05e-3, 50e-3, 5), 0.05)
    fit = fit_static(v, f)
    flagged = {(d, name) for d, b in fit.branches().items() for name in b.unidentifiable()}
    assert flagged  # one degree of freedom per branch: some value is not pinned down
    d = fit.to_dict()
    assert any(d[direction]["unidentifiable"] for direction in ("positive", "negative"))


def test_flag_reasons() -> None:
    good = Estimate(10.0, 0.1, 9.8, 10.2, "N", 0.95)
    assert good.identifiable
    wide = Estimate(8.5e-19, 3.0, -6.0, 6.0, "N", 0.95)
    assert "wider than ±50 %" in (wide.identifiability_issue or "")
    loose = Estimate(1.0, float("inf"), float("-inf"), float("inf"), "N", 0.95)
    assert "not determined" in (loose.identifiability_issue or "")
    coupled = Estimate(10.0, 0.1, 9.8, 10.2, "N", 0.95, max_correlation=0.9999,
                       correlated_with="F_s")
    assert "correlation +0.9999 with F_s" in (coupled.identifiability_issue or "")



def test_header_only_static_file_says_empty(tmp_path: Path) -> None:
    path = tmp_path / "empty.csv"
    path.write_text("# exported\nspeed [mm/s],force [N]\n", encoding="utf-8")
    with pytest.raises(MeasuredDataError, match=r"empty.csv: empty: a header \(line 2\) and no "
                                                "data rows"):
        read_static_test(path)
