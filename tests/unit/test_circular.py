"""ISO 230-4 circular test metrics on synthetic circles (issue 37, acceptance).

The traces are made by applying each *physical* error to the axes' commanded positions — an
axis non-orthogonality, a scale factor per axis, a reversal spike of given height and width
pushed onto the reversing axis, a lost motion, a lag per axis — never from the metric's own
signature; the metric must give the applied value back (tolerances of issue 37: 10 ± 0.1 µm/m,
5 ± 0.05 µm, 3 ± 0.03 µm).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from feeddrive.analysis.circular import circular_test, fit_circle
from feeddrive.parameters import ParameterError

R = 0.05  # [m]
CENTRE = (0.20, 0.15)  # [m] away from the machine zero, as on a real table
FEED = 1.0 / 60.0  # [m/s] 1000 mm/min
LEAD = math.radians(10.0)  # lead-in and lead-out arcs


def command(direction: int, *, step_deg: float = 0.1) -> tuple[np.ndarray, ...]:
    """Commanded X, Y of one run with 10° lead-in/out, its nominal angle and the time."""
    travel = np.arange(-LEAD, 2 * math.pi + LEAD + 1e-12, math.radians(step_deg))
    theta = direction * travel + 0.3  # the run starts between reversals
    t = travel * R / FEED
    return t, CENTRE[0] + R * np.cos(theta), CENTRE[1] + R * np.sin(theta), theta


def spike_shape(after: np.ndarray, width: float) -> np.ndarray:
    """u·e^(1−u), u = travel after the reversal / width: peaks at 1 one width after it."""
    u = np.clip(after / width, 0.0, None)
    return u * np.exp(1.0 - u)


def trace(*, squareness: float = 0.0, scale: tuple[float, float] = (0.0, 0.0),
          spike: float = 0.0, spike_width: float = math.radians(2.0), backlash: float = 0.0,
          lag: tuple[float, float] = (0.0, 0.0), lateral_play: float = 0.0,
          cyclic: tuple[float, float] = (0.0, 0.005)) -> tuple[np.ndarray, ...]:
    """CCW then CW, with the errors applied to the machine axes (X, Y measured from zero)."""
    ts, xs, ys = [], [], []
    t0 = 0.0
    for direction in (1, -1):
        t, x_cmd, y_cmd, theta = command(direction)
        omega = FEED / R
        # servo lag: each axis is where its command was τ earlier
        x = CENTRE[0] + R * np.cos(theta - direction * omega * lag[0])
        y = CENTRE[1] + R * np.sin(theta - direction * omega * lag[1])
        vx = -direction * np.sin(theta)  # sign of each axis's speed
        vy = direction * np.cos(theta)
        # lost motion: the axis trails its command by b/2 in its direction of motion
        x = x - np.sign(vx) * backlash / 2.0
        y = y - np.sign(vy) * backlash / 2.0
        # lateral play of X: the Y position shifts with the sign of X's motion
        y = y + np.sign(vx) * lateral_play / 2.0
        # cyclic error of the X screw: amplitude, pitch
        x = x + cyclic[0] * np.sin(2 * math.pi * x_cmd / cyclic[1] + 0.4)
        # reversal spike: the reversing axis overshoots outward after each reversal
        for q in range(4):
            base = q * math.pi / 2.0
            after = np.mod((theta - base) * direction, 2 * math.pi)
            after = np.where(after > math.pi, -1.0, after)
            push = spike * spike_shape(after, spike_width)
            if q % 2 == 0:
                x = x + math.cos(base) * push
            else:
                y = y + math.sin(base) * push
        # geometry: Y leans towards +X by α, then each axis's scale
        x = x + squareness * y
        x = x * (1.0 + scale[0])
        y = y * (1.0 + scale[1])
        ts.append(t0 + t)
        xs.append(x)
        ys.append(y)
        t0 = float(t[-1]) + 1.0
    return np.concatenate(ts), np.concatenate(xs), np.concatenate(ys)


def analyse(**errors: object) -> object:
    t, x, y = trace(**errors)  # type: ignore[arg-type]
    return circular_test(t, x, y, radius=R, centre=CENTRE)


def spike_heights(result: object) -> np.ndarray:
    return np.array([s.height for s in result.spikes])  # type: ignore[attr-defined]


def test_perfect_circle_has_no_deviation() -> None:
    res = analyse()
    assert [r.direction for r in res.runs] == ["CCW", "CW"]
    assert res.bidirectional_circular_deviation == pytest.approx(0.0, abs=1e-12)
    assert res.feed == pytest.approx(FEED, rel=1e-3)
    assert any("lead-in" in n for n in res.notes)


def test_squareness_alone() -> None:
    res = analyse(squareness=10e-6)
    assert res.squareness * 1e6 == pytest.approx(10.0, abs=0.1)
    assert abs(res.scale_mismatch) < 0.03e-6
    assert np.all(np.abs(spike_heights(res)) < 0.05e-6)
    # an oval at 45°: G = α·R (the radial deviation α·R·sin2θ/2 spans α·R)
    assert res.circular_deviation["CCW"] == pytest.approx(10e-6 * R, rel=0.02)


def test_scale_mismatch_alone() -> None:
    res = analyse(scale=(3e-6 / R, 0.0))
    assert res.scale_mismatch * 1e6 == pytest.approx(3.0, abs=0.03)
    assert abs(res.squareness) * 1e6 < 0.1
    assert np.all(np.abs(spike_heights(res)) < 0.05e-6)


def test_reversal_spike_alone() -> None:
    width = math.radians(2.0)
    res = analyse(spike=5e-6, spike_width=width)
    heights = spike_heights(res)
    assert heights.size == 8
    # the spike is pushed along the reversing axis; its radial part at its peak, one width
    # after the reversal, is 5 µm·cos(2°)
    expected = 5.0 * math.cos(width)
    assert heights * 1e6 == pytest.approx(np.full(8, expected), abs=0.05)
    # half-height width of u·e^(1−u): u from 0.2319 to 2.6783 (roots of u·e^(1−u) = 1/2)
    for s in res.spikes:
        assert s.width == pytest.approx(2.4464 * 2.0, abs=0.25)  # sampled every 0.1°
        assert s.peak_angle == pytest.approx(2.0, abs=0.1)
    assert abs(res.squareness) * 1e6 < 0.1
    assert abs(res.scale_mismatch) < 0.03e-6


def test_all_three_at_once() -> None:
    res = analyse(squareness=10e-6, scale=(1.5e-6 / R, -1.5e-6 / R), spike=5e-6)
    assert res.squareness * 1e6 == pytest.approx(10.0, abs=0.1)
    assert res.scale_mismatch * 1e6 == pytest.approx(3.0, abs=0.03)
    assert spike_heights(res) * 1e6 == pytest.approx(np.full(8, 5.0 * math.cos(math.radians(2))),
                                                     abs=0.05)


def test_backlash_and_servo_mismatch() -> None:
    res = analyse(backlash=4e-6, lag=(2e-3, 1e-3), squareness=10e-6)
    assert res.backlash["x"] * 1e6 == pytest.approx(4.0, abs=0.04)
    assert res.backlash["y"] * 1e6 == pytest.approx(4.0, abs=0.04)
    # servo mismatch is the lag difference: 1 ms; squareness is told apart (same in CW, CCW)
    assert res.servo_mismatch * 1e3 == pytest.approx(1.0, rel=0.01)
    assert res.squareness * 1e6 == pytest.approx(10.0, abs=0.1)


def test_lateral_play_and_cyclic_error() -> None:
    t, x, y = trace(lateral_play=3e-6, cyclic=(1e-6, 0.005), squareness=10e-6)
    res = circular_test(t, x, y, radius=R, centre=CENTRE, pitch=0.005)
    assert res.lateral_play["x"] * 1e6 == pytest.approx(3.0, abs=0.03)
    assert abs(res.lateral_play["y"]) < 0.03e-6
    assert res.cyclic_error["x"] * 1e6 == pytest.approx(1.0, abs=0.01)
    assert res.cyclic_error["y"] < 0.01e-6
    assert res.squareness * 1e6 == pytest.approx(10.0, abs=0.1)


def test_one_run_says_what_it_cannot_give() -> None:
    t, x, y, _ = command(1)
    res = circular_test(t, x + 0.0, y, radius=R, centre=CENTRE)
    assert res.bidirectional_circular_deviation is None
    assert res.servo_mismatch is None and res.lateral_play is None
    assert any("one run" in n for n in res.notes)


def test_a_radial_approach_from_the_centre_is_left_out() -> None:
    t, x, y = trace(squareness=10e-6)
    k = 200  # a straight approach from the centre to the start of the first run
    xs = np.linspace(CENTRE[0], x[0], k, endpoint=False)
    ys = np.linspace(CENTRE[1], y[0], k, endpoint=False)
    t = np.concatenate([np.arange(k) * 1e-3, t - t[0] + k * 1e-3])  # increasing
    res = circular_test(t, np.concatenate([xs, x]), np.concatenate([ys, y]), radius=None,
                        centre=None)
    assert res.squareness * 1e6 == pytest.approx(10.0, abs=0.1)
    # the centre the circle alone gives (the squareness shifts it by α·y_c = 1.5 µm); the
    # approach's last samples, within 1 % of R, move it by less than 0.5 µm
    assert res.centre == pytest.approx(fit_circle(x, y)[:2], abs=0.5e-6)
    assert any("left out (a radial lead-in" in n for n in res.notes)
    assert any("centre (200" in n and "inferred" in n for n in res.notes)


def test_fit_circle_recovers_centre_and_radius() -> None:
    a = np.linspace(0.0, 2 * np.pi, 721)
    cx, cy, r = fit_circle(0.3 + 0.04 * np.cos(a), -0.1 + 0.04 * np.sin(a))
    assert (cx, cy, r) == pytest.approx((0.3, -0.1, 0.04), abs=1e-12)


def test_bad_requests() -> None:
    t, x, y, _ = command(1)
    with pytest.raises(ParameterError, match="radius"):
        circular_test(t, x, y, radius=0.0, centre=CENTRE)
    with pytest.raises(ParameterError, match="radius"):
        circular_test(t, x, y, radius=0.5, centre=CENTRE)
    with pytest.raises(ValueError, match="full revolution"):
        circular_test(t[:1000], x[:1000], y[:1000], radius=R, centre=CENTRE)


def test_polar_plot_overlays_cw_and_ccw(tmp_path) -> None:
    from feeddrive.plots.acceptance import circular_figure, save

    res = analyse(squareness=10e-6, spike=5e-6)
    fig = circular_figure(res, magnification=2000.0)
    ax = fig.axes[0]
    assert ax.name == "polar"
    labels = [line.get_label() for line in ax.get_lines()]
    assert "CCW" in labels and "CW" in labels and "nominal circle" in labels
    assert "×2000" in ax.get_title()
    assert f"G(b) {res.bidirectional_circular_deviation * 1e6:.2f} µm" in ax.get_title()
    # the drawn radius is 0.6 + k·δ/R·0.6: the CCW trace's span is the magnified G about the
    # same centre
    ccw = next(line for line in ax.get_lines() if line.get_label() == "CCW")
    drawn = np.ptp(ccw.get_ydata()) / 0.6 * R / 2000.0
    assert drawn == pytest.approx(res.bidirectional_circular_deviation, rel=0.35)
    assert save(fig, tmp_path / "polar.png").stat().st_size > 0
