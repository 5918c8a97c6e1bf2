"""ISO 230-2 quantities computed by hand from the standard's formulas (issue 37, acceptance).

The expected values are written out here term by term with plain Python loops from the
definitions of ISO 230-2 (docs/acceptance-tests.md, Clause 3), not with the module's code.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from feeddrive.analysis.positioning import (
    Stop,
    positioning_cycle,
    positioning_test,
    read_approaches,
    reading_motion,
)
from feeddrive.parameters import ParameterError


def synthetic() -> tuple[list[float], list[list[float]], list[list[float]]]:
    """4 targets × 5 cycles: a pitch error, a 3-µm lost motion and a scatter per approach."""
    rng = np.random.default_rng(230)
    targets = [0.010, 0.0335, 0.061, 0.0905]
    up, down = [], []
    for i, p in enumerate(targets):
        pitch = 20e-6 * p / 0.1 + 1.5e-6 * math.sin(2 * math.pi * p / 0.005)
        up.append([pitch - 1.5e-6 + float(v) for v in rng.normal(0, 0.4e-6 * (1 + i), 5)])
        down.append([pitch + 1.5e-6 + float(v) for v in rng.normal(0, 0.3e-6, 5)])
    return targets, up, down


def test_every_quantity_by_hand() -> None:
    targets, up, down = synthetic()
    res = positioning_test(targets, up, down)
    m, n = len(targets), 5

    def mean(v: list[float]) -> float:
        return sum(v) / len(v)

    def s(v: list[float]) -> float:  # estimator of the standard uncertainty, n − 1
        a = mean(v)
        return math.sqrt(sum((x - a) ** 2 for x in v) / (len(v) - 1))

    xu = [mean(up[i]) for i in range(m)]  # x̄_i↑
    xd = [mean(down[i]) for i in range(m)]  # x̄_i↓
    xb = [(xu[i] + xd[i]) / 2 for i in range(m)]  # x̄_i
    su = [s(up[i]) for i in range(m)]
    sd = [s(down[i]) for i in range(m)]
    b = [xu[i] - xd[i] for i in range(m)]  # B_i
    ru = [4 * su[i] for i in range(m)]  # R_i↑
    rd = [4 * sd[i] for i in range(m)]
    r = [max(2 * su[i] + 2 * sd[i] + abs(b[i]), ru[i], rd[i]) for i in range(m)]
    expected = {
        "reversal": max(abs(v) for v in b),
        "mean_reversal": sum(b) / m,
        "repeatability_up": max(ru), "repeatability_down": max(rd), "repeatability": max(r),
        "systematic_up": max(xu) - min(xu), "systematic_down": max(xd) - min(xd),
        "systematic": max(xu + xd) - min(xu + xd),
        "mean_range": max(xb) - min(xb),
        "accuracy_up": max(xu[i] + 2 * su[i] for i in range(m))
        - min(xu[i] - 2 * su[i] for i in range(m)),
        "accuracy_down": max(xd[i] + 2 * sd[i] for i in range(m))
        - min(xd[i] - 2 * sd[i] for i in range(m)),
        "accuracy": max([xu[i] + 2 * su[i] for i in range(m)]
                        + [xd[i] + 2 * sd[i] for i in range(m)])
        - min([xu[i] - 2 * su[i] for i in range(m)] + [xd[i] - 2 * sd[i] for i in range(m)]),
    }
    for name, value in expected.items():
        assert getattr(res, name) == pytest.approx(value, rel=1e-12, abs=1e-18), name
    assert set(expected) == set(res.AXIS_QUANTITIES)  # every quantity of the axis checked
    assert res.reversal_at == pytest.approx(b, rel=1e-12)
    assert res.repeatability_at == pytest.approx(r, rel=1e-12)
    assert res.mean == pytest.approx(xb, rel=1e-12)
    assert res.s_up == pytest.approx(su, rel=1e-12)
    # the lost motion of 3 µm shows as B_i ≈ −3 µm (approached from below it stops short)
    assert res.mean_reversal == pytest.approx(-3e-6, abs=0.6e-6)
    assert res.to_dict()["cycles"] == n


def test_fewer_than_five_cycles_refused() -> None:
    targets, up, down = synthetic()
    with pytest.raises(ParameterError, match="at least 5"):
        positioning_test(targets, [u[:4] for u in up], [d[:4] for d in down])
    with pytest.raises(ParameterError, match="at least 5"):
        positioning_cycle(targets, 4)


def test_linear_cycle_visits_each_target_five_times_each_way() -> None:
    stops = positioning_cycle([0.01, 0.02, 0.03], 5)
    measured = [s for s in stops if s.target >= 0]
    assert len(measured) == 3 * 5 * 2
    for s in measured:  # approached from the side its direction says
        before = stops[stops.index(s) - 1]
        assert np.sign(s.position - before.position) == s.direction
    assert stops[0].position == pytest.approx(0.008)


def test_pilgrim_cycle_visits_each_target_five_times_each_way() -> None:
    stops = positioning_cycle([0.01, 0.02], 5, kind="pilgrim", overshoot=1e-3)
    measured = [s for s in stops if s.target >= 0]
    assert len(measured) == 2 * 5 * 2
    for k, s in enumerate(stops):
        if s.target >= 0:
            assert np.sign(s.position - stops[k - 1].position) == s.direction
            assert abs(s.position - stops[k - 1].position) == pytest.approx(1e-3)


def test_read_approaches_averages_the_end_of_each_dwell() -> None:
    stops = [Stop(0.0, -1, 0, 0)] + [Stop(0.01, 0, 1, j) for j in range(5)] \
        + [Stop(0.01, 0, -1, j) for j in range(5)]
    ends = np.arange(1, 12, dtype=float)
    t = np.linspace(0, 11, 11001)
    x = np.where(t <= 6.0, 0.01 - 1e-6, 0.01 + 2e-6)
    up, down = read_approaches(t, x, stops, ends, 1.0, [0.01])
    assert up == pytest.approx(np.full((1, 5), -1e-6), abs=1e-15)
    assert down == pytest.approx(np.full((1, 5), 2e-6), abs=1e-15)


def test_chart_shows_both_directions_and_bands(tmp_path) -> None:
    from feeddrive.plots.acceptance import positioning_figure, save

    targets, up, down = synthetic()
    res = positioning_test(targets, up, down)
    fig = positioning_figure(res)
    ax = fig.axes[0]
    labels = {line.get_label() for line in ax.get_lines()}
    assert {"x̄↑", "x̄↓", "x̄↑ ± 2s↑", "x̄↓ ± 2s↓", "x̄ (bidirectional)"} <= labels
    band = next(line for line in ax.get_lines() if line.get_label() == "x̄↑ ± 2s↑")
    assert band.get_ydata() == pytest.approx((res.mean_up + 2 * res.s_up) * 1e6)
    assert f"A = {res.accuracy * 1e6:.3f} µm" in ax.get_title()
    assert save(fig, tmp_path / "chart.svg").stat().st_size > 0


def test_reading_motion_is_the_largest_swing_inside_a_reading_window() -> None:
    """Two measured stops and an overshoot stop (target −1, not read): a 3-µm sine inside the
    second window's last quarter of a 1-s dwell, a 50-µm swing at the overshoot stop and one
    before the first window — only the 6-µm peak-to-peak inside a window counts."""
    t = np.linspace(0.0, 3.0, 30001)
    x = np.zeros_like(t)
    x[(t > 0.2) & (t < 0.5)] = 50e-6  # before the first window (0.75 … 1 s)
    inside = (t >= 1.8) & (t <= 2.0)
    x[inside] = 3e-6 * np.sin(2 * np.pi * 10.0 * t[inside])
    x[(t > 2.8)] = 50e-6  # the overshoot stop's window: not a reading
    stops = [Stop(0.0, 0, 1, 0), Stop(0.0, 0, -1, 0), Stop(-1e-3, -1, 1, 0)]
    got = reading_motion(t, x, stops, [1.0, 2.0, 3.0], 1.0)
    assert got == pytest.approx(6e-6, rel=1e-3)
    assert reading_motion(t, x, stops[:1], [1.0], 1.0) == 0.0
