"""Issue 40 acceptance: the XY circle of a frictionless machine against the cascade's T(jω).

Two matched ``wang2021`` CDFS axes (friction law ``none`` at every site, velocity
feed-forward off, K_eq fixed so the axis is linear) follow a circle of R = 50 mm at
F = 5000 mm/min.  After the lead-in the actual path is a circle of radius R·|T(jω)|,
ω = F/R, T the position loop's tracking response: its roundness (max − min radius) must be
below 1 % of the mean radius reduction, and the mean reduction must equal R(1 − |T(jω)|)
within 0.1 %.  T is built here from the physical equations with python-control's
``interconnect`` (blocks joined by signal names), not from feeddrive's own frequency
response.

Solver settings: ``dopri5`` with rtol = 1e-9 and absolute tolerances 1e-12 m (positions),
1e-10 m/s (speeds), 1e-9 A (currents); references sampled every 1e-4 s.
"""

from __future__ import annotations

import math

import control
import numpy as np
import pytest

import feeddrive as fd
from feeddrive.machine import Circle, machine_from_dict, simulate_machine

K_EQ = 1.5e8  # [N/m], fixed equivalent axial stiffness (chosen; the order of Wang2021's)
AXIS = {"extends": "wang2021", "drive": "cdfs",
        "friction": {"screw": {"law": "none"}, "nut": {"law": "none"},
                     "guide": {"law": "none"}},
        "controller": {"velocity_feedforward": False},
        "stiffness": {"equivalent_stiffness": K_EQ}}
RADIUS = 0.05  # [m]
FEED = 5000.0 / 60e3  # [m/s]


def tracking_loop(params: fd.DriveParameters) -> control.StateSpace:
    """x_ref → x of one CDFS axis (nut held), from Wang2021 Eqs. (7)–(8) and the cascade of
    docs/model.md: position P, velocity PI on the table basis, current PI, armature R–L with
    back-EMF, screw shaft and table joined by K_eq and the axial damping."""
    c, s, m = params.controller, params.screw, params.screw_motor
    H = s.lead / (2.0 * math.pi)
    J = m.inertia + s.shaft_inertia
    mass, damping = params.table.mass, params.stiffness.axial_damping
    position = control.ss([], [], [], [[c.position_gain / H, -c.position_gain / H]],
                          inputs=["x_ref", "x"], outputs=["w_cmd"], name="position")
    speed_error = control.summing_junction(inputs=["w_cmd", "-w_s"], output="e_w")
    velocity = control.tf([H * c.velocity_gain, H * c.velocity_integral_gain], [1, 0],
                          inputs="e_w", outputs="i_cmd", name="velocity")
    current_error = control.summing_junction(inputs=["i_cmd", "-i"], output="e_i")
    current = control.tf([c.current_gain, c.current_integral_gain], [1, 0],
                         inputs="e_i", outputs="u", name="current")
    # L di/dt = u − R i − K_e ω_s
    armature = control.ss([[-m.resistance / m.inductance]],
                          [[1 / m.inductance, -m.back_emf_constant / m.inductance]],
                          [[1.0]], [[0.0, 0.0]], inputs=["u", "w_s"], outputs=["i"],
                          name="armature")
    # states θ_s, ω_s, x, v; F_d = K(Hθ_s − x) + c(Hω_s − v)
    A = np.array([
        [0, 1, 0, 0],
        [-H * K_EQ * H / J, -H * damping * H / J, H * K_EQ / J, H * damping / J],
        [0, 0, 0, 1],
        [K_EQ * H / mass, damping * H / mass, -K_EQ / mass, -damping / mass]])
    B = np.array([[0], [m.torque_constant / J], [0], [0]])
    C = np.array([[0, 0, 1, 0], [0, 1, 0, 0]])
    mechanics = control.ss(A, B, C, np.zeros((2, 1)), inputs=["i"], outputs=["x", "w_s"],
                           name="mechanics")
    return control.interconnect([position, speed_error, velocity, current_error, current,
                                 armature, mechanics], inplist=["x_ref"], outlist=["x"])


@pytest.mark.slow
def test_frictionless_xy_circle_matches_the_cascade_tracking_response() -> None:
    machine = machine_from_dict({"name": "xy", "axes": {"x": AXIS, "y": AXIS}})
    loop = tracking_loop(machine.axes[0].parameters)
    # measure over one full turn once the slowest mode (a lightly damped pair, decay rate
    # ≈ 1.16 1/s) has decayed for 7 of its time constants after the lead-in
    slowest = min(-p.real for p in loop.poles())
    period = 2 * math.pi * RADIUS / FEED
    lead_in = FEED / 1.0
    start = lead_in + 7.0 / slowest
    circle = Circle(feed=FEED, acceleration=1.0, radius=RADIUS,
                    turns=(start + period) / period + 0.05)
    options = fd.SolverOptions(method="dopri5", rtol=1e-9, position_tolerance=1e-12,
                               speed_tolerance=1e-10, current_tolerance=1e-9,
                               output_interval=1e-3)
    cruise_end = circle.length / circle.feed  # the lead-out starts here
    result = simulate_machine(machine, circle, cruise_end, options=options)
    t = result.time
    window = t >= cruise_end - period  # the last full turn before the lead-out
    assert t[window][0] >= start
    radius = RADIUS + result["contour_error"][window]
    reduction = RADIUS - radius.mean()
    expected = RADIUS * (1.0 - abs(complex(np.squeeze(loop(1j * FEED / RADIUS)))))
    assert reduction >= 1e-6
    assert np.ptp(radius) < 0.01 * reduction
    assert abs(reduction / expected - 1.0) < 1e-3


def test_the_machine_mimo_loop_has_each_axis_cascade_on_its_diagonal() -> None:
    """`loops --machine`'s MIMO StateSpace: x_ref → x equals the hand-built cascade's T(jω)
    at every frequency tried, and x_ref → y is 0 for the independent XY table."""
    from feeddrive.machine.linear import cross_coupling, linearize_machine

    machine = machine_from_dict({"name": "xy", "axes": {"x": AXIS, "y": AXIS}})
    ss = linearize_machine(machine).to_control()
    assert ss.input_labels == ["x:table_position_reference", "x:load_force",
                               "y:table_position_reference", "y:load_force"]
    T = tracking_loop(machine.axes[0].parameters)
    for w in (0.5, FEED / RADIUS, 30.0, 300.0):
        got = complex(ss(1j * w)[ss.output_labels.index("x:table_position"), 0])
        want = complex(np.squeeze(T(1j * w)))
        assert abs(got - want) < 1e-6 * abs(want)
    assert cross_coupling(linearize_machine(machine)) == {"x -> y": 0.0, "y -> x": 0.0}
