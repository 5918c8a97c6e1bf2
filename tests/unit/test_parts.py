"""A model part with a sample rate of its own (issue 19, "a loop with its own rate"): the
acceleration feed-forward of model/parts/, updated at 1 kHz while the current loop runs at
8 kHz, its schedule merged into the breakpoint grid."""

from __future__ import annotations

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.parameters import ParameterError, loads

LOOPS = """extends = "wang2021"
name = "sampled"
[controller]
current_period = 1.25e-4
velocity_period = 2.5e-4
position_period = 1e-3
"""
PART = """[acceleration_feedforward]
gain = {gain}
period = {period}
"""
SINE = fd.SineSpeed(10e-3, frequency=2.0)
OPTIONS = fd.SolverOptions(output_interval=1.25e-4)


def run(text: str, duration: float = 0.3) -> fd.Result:
    return fd.simulate(fd.DriveSystem(loads(text), "cdfs", 0.4), SINE, duration,
                       options=OPTIONS)


def test_the_current_is_held_between_its_own_samples():
    """It changes only at multiples of its 1-ms period, to K_a·Δv_ref/T_a over the last
    period (the recorded reference), while the loops run at 8/4/1 kHz."""
    gain, period = 1.6, 1e-3
    r = run(LOOPS + PART.format(gain=gain, period=period))
    t, i = r.time, r["acceleration_feedforward_current"]
    v_ref = r["table_speed_reference"]
    changes = t[1:][np.diff(i) != 0]
    assert changes.size > 100
    assert np.allclose(changes / period, np.round(changes / period), atol=1e-9)
    k = np.flatnonzero(np.isclose(t % period, 0.0, atol=1e-12) | np.isclose(
        t % period, period, atol=1e-12))
    k = k[(t[k] > 1.5 * period)]
    step = int(round(period / OPTIONS.output_interval))
    expected = gain * (v_ref[k] - v_ref[k - step]) / period
    assert np.allclose(i[k], expected, rtol=1e-9, atol=1e-12)


def test_it_reduces_the_following_error_of_a_sine():
    without = run(LOOPS, 0.5).summary()["following_error_max_um"]
    with_ff = run(LOOPS + PART.format(gain=1.6, period=1e-3), 0.5).summary()[
        "following_error_max_um"]
    assert with_ff < 0.8 * without


def test_zero_gain_leaves_the_run_unchanged():
    a = run(LOOPS)
    b = run(LOOPS + PART.format(gain=0.0, period=1e-3))
    np.testing.assert_array_equal(a["table_position"], b["table_position"])


@pytest.mark.parametrize("text, field", [
    (LOOPS + PART.format(gain=1.0, period=3e-4), "acceleration_feedforward.period"),
    (LOOPS.replace("velocity_period = 2.5e-4", "velocity_period = 3e-4"),
     "controller.velocity_period"),
])
def test_schedules_off_the_grid_are_refused(text, field):
    """A period that is no multiple of the fastest one is refused before any integration,
    naming the field."""
    with pytest.raises(ParameterError) as err:
        run(text)
    assert err.value.field == field


def test_an_unknown_axis_is_refused():
    text = LOOPS + PART.format(gain=1.0, period=1e-3) + 'axis = "nut_motor"\n'
    with pytest.raises(ParameterError, match="acceleration_feedforward.axis.*screw"):
        run(text)


@pytest.mark.parametrize("method", ["dopri5", "modal"])
def test_a_sampled_part_runs_beside_continuous_loops(method):
    """With every loop continuous the part's clock alone is the sample schedule: its current
    is K_a·Δv_ref/T_a over each period (the recorded reference), it cuts the following error,
    and both drivers agree on the motion."""
    gain, period = 1.6, 1e-3
    text = 'extends = "wang2021"\n'

    def go(extra, how=method):
        return fd.simulate(fd.DriveSystem(loads(text + extra), "cdfs", 0.4), SINE, 0.5,
                           options=fd.SolverOptions(method=how, output_interval=period))

    part = PART.format(gain=gain, period=period)
    r = go(part)
    i, v_ref = r["acceleration_feedforward_current"], r["table_speed_reference"]
    np.testing.assert_allclose(i[2:], gain * np.diff(v_ref)[1:] / period, rtol=1e-9,
                               atol=1e-12)
    assert r.summary()["following_error_max_um"] < 0.8 * go("").summary()[
        "following_error_max_um"]
    other = go(part, "modal" if method == "dopri5" else "dopri5")
    assert np.max(np.abs(other["table_position"] - r["table_position"])) < 1e-7


# --- the reversal feed-forward (issue 37 item 4): a current step at each zero crossing of the
# commanded table speed, faded out as exp(−|v|/v_w)
REVERSAL = """[reversal_feedforward]
current = {current}
width = {width}
period = 1e-3
"""


def _coulomb_current(text: str) -> float:
    """I_r = F_c·H/K_t: the screw's and the guide's Coulomb friction (wang2021 Table 1,
    positive branch) as screw-motor current."""
    import math

    p = loads(text)
    force = p.friction.screw.positive.coulomb_force + p.friction.guide.positive.coulomb_force
    return force * p.screw.lead / (2 * math.pi) / p.screw_motor.torque_constant


def test_the_reversal_current_is_the_weighted_step_held_between_samples():
    current, width, period = 0.2, 2e-3, 1e-3
    r = run(LOOPS + REVERSAL.format(current=current, width=width), 0.6)
    t, i = r.time, r["reversal_feedforward_current"]
    v_ref = r["table_speed_reference"]
    changes = t[1:][np.diff(i) != 0]
    assert changes.size > 100
    assert np.allclose(changes / period, np.round(changes / period), atol=1e-9)
    k = np.flatnonzero(np.isclose(t % period, 0.0, atol=1e-12) | np.isclose(
        t % period, period, atol=1e-12))
    expected = current * np.sign(v_ref[k]) * np.exp(-np.abs(v_ref[k]) / width)
    assert np.allclose(i[k], expected, rtol=1e-9, atol=1e-12)
    assert np.max(np.abs(i)) == pytest.approx(current, rel=0.05)  # just after a reversal


def test_the_reversal_feedforward_cuts_the_speed_error_after_reversals():
    """With I_r = F_c·H/K_t (no tuning) the table-speed error in the 0.1 s after each of the
    sine's three reversals is smaller on average (measured at v_w = 1, 2, 5 mm/s: 1.58, 1.45,
    1.30 mm/s against 1.70 mm/s without)."""
    def glitch(r: fd.Result) -> float:
        t = r.time
        err = np.abs(r["table_speed"] - r["table_speed_reference"])
        return float(np.mean([np.max(err[(t > t0) & (t < t0 + 0.1)])
                              for t0 in (0.25, 0.5, 0.75)]))

    without = glitch(run(LOOPS, 1.0))
    with_ff = glitch(run(LOOPS + REVERSAL.format(current=_coulomb_current(LOOPS),
                                                 width=2e-3), 1.0))
    assert with_ff < 0.9 * without


def test_zero_reversal_current_leaves_the_run_unchanged_and_parts_add_up():
    a = run(LOOPS)
    b = run(LOOPS + REVERSAL.format(current=0.0, width=2e-3))
    np.testing.assert_array_equal(a["table_position"], b["table_position"])
    # with the acceleration feed-forward on the same axis both currents are added
    both = run(LOOPS + REVERSAL.format(current=0.2, width=2e-3) + PART.format(
        gain=1.6, period=1e-3))
    for alone in (run(LOOPS + REVERSAL.format(current=0.2, width=2e-3)),
                  run(LOOPS + PART.format(gain=1.6, period=1e-3))):
        assert np.max(np.abs(both["table_position"] - alone["table_position"])) > 1e-9
