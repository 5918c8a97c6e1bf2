"""Issue 40: the gantry — two wang2021 CDFS axes carrying one beam — and its synchronisation.

The static check is against the hand balance of the beam (feeddrive.machine.couplings.gantry
module docstring): a load F at the fraction λ of the span from carriage x1, both carriages
held at one position by their servos (integral action), gives
θ = −(λ − 1/2) L F / (k L²/2 + k_θ) and carriage loads (F ± k L θ)/2.

The move compares the synchronisation controllers on a 10-mm/s trapezoid with x1's screw
friction doubled, each at a gain chosen by a stated rule, not from the yaw it gives:

* master–slave at K = K_p, the slave's own position gain (8 1/s): the slave's position loop
  closed on the master's measured position instead of the reference — the usual scheme;
* the cross-coupled controller at K_c = K_c,max / 2, half the gain at which the machine's
  linearised closed loop (frictionless, both axes at 10 mm/s) loses stability
  (``feeddrive.machine.linear.gain_limit``): a 6-dB gain margin on the coupling loop.
  K_c,max = 1.78 1/s, so K_c = 0.89 1/s (the former default, 2 1/s, was beyond the limit;
  linearised with the friction at 10 mm/s sliding the limit is 2.61 1/s).

Measured (dopri5 defaults), peak beam yaw: master–slave 69.0 µrad, no synchronisation
37.1 µrad, cross-coupled 35.8 µrad (36.1 and 35.4 at 0.75 and 1.25 × K_c).  The ratio
cross-coupled / master–slave is 0.519 (0.523 … 0.514 over ±25 % of K_c; 0.510 at half the
with-friction limit; 0.501 at the frictionless limit, 0.485 at the with-friction one): the
issue's "≤ 0.5 ×" needs K_c ≳ 1.85 1/s, beyond the frictionless limit and within 3 dB of the
with-friction one, so it is not met by a rule-designed gain and is not asserted.
Master–slave is worse than no synchronisation because the slave is driven by the master's
ringing at the lightly damped 5.5-Hz velocity-loop mode, which it amplifies: the machine's
least damping ratio falls from 0.031 (independent axes) to 0.020.
"""

from __future__ import annotations

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.machine import Machine, MachineProfile, machine_from_dict, simulate_machine
from feeddrive.machine.linear import gain_limit, linearize_machine, spectral_abscissa
from feeddrive.model.reference import SampledSpeed, trapezoid


def _doubled(branch: object) -> dict[str, float]:
    return {k: 2.0 * getattr(branch, k)
            for k in ("coulomb_force", "static_force", "viscous_coefficient")}


@pytest.mark.slow
def test_static_yaw_matches_the_hand_balance_of_the_beam() -> None:
    force, where = 1000.0, 1.0 / 3.0
    machine = machine_from_dict({"name": "g", "extends": "gantry", "couplings": {
        "beam": {"load_force": force, "load_position": where}}})
    t = np.arange(0.0, 3.5, 1e-3)
    rest = MachineProfile.common(machine, SampledSpeed(time=t, table_speed=np.zeros_like(t)))
    result = simulate_machine(machine, rest, 3.0)
    beam = machine.couplings[0]
    L, k, k_yaw = beam.span, beam.joint_stiffness, beam.yaw_stiffness  # type: ignore[attr-defined]
    yaw = -(where - 0.5) * L * force / (k * L ** 2 / 2 + k_yaw)
    assert result["beam.yaw"][-1] == pytest.approx(yaw, rel=0.05)
    assert result["x1.external_force"][-1] == pytest.approx((force + k * L * yaw) / 2,
                                                            rel=0.05)
    assert result["x2.external_force"][-1] == pytest.approx((force - k * L * yaw) / 2,
                                                            rel=0.05)


def _machine(sync: dict | None, x1: dict | None = None) -> Machine:  # type: ignore[type-arg]
    return machine_from_dict({"name": "g", "extends": "gantry",
                              "axes": {"x1": x1} if x1 else {},
                              "couplings": {"sync": sync} if sync else {}})


def _peak_yaw(sync: dict | None) -> float:  # type: ignore[type-arg]
    screw = fd.preset("wang2021").friction.screw
    x1 = {"extends": "wang2021", "drive": "cdfs", "friction": {"screw": {
        "positive": _doubled(screw.positive), "negative": _doubled(screw.negative)}}}
    machine = _machine(sync, x1)
    move = MachineProfile.common(machine, trapezoid(10e-3, 2.0, ramp_time=0.2))
    return float(np.max(np.abs(simulate_machine(machine, move, 2.0)["beam.yaw"])))


_MOVE_SPEEDS = {"x1": 10e-3, "x2": 10e-3}


def _damping(sync: dict | None, frictionless: bool = True) -> float:  # type: ignore[type-arg]
    pole = spectral_abscissa(linearize_machine(_machine(sync), _MOVE_SPEEDS,
                                               frictionless=frictionless))
    return -pole.real / abs(pole)


def test_master_slave_lowers_the_damping_of_the_velocity_loop_mode() -> None:
    # why master–slave is worse than independent axes: the slave is driven by the master's
    # ringing at the 5.5-Hz mode (measured: ζ 0.031 without synchronisation, 0.020 with it)
    kp = fd.preset("wang2021").controller.position_gain
    independent = _damping(None)
    master_slave = _damping({"part": "master_slave", "gain": kp})
    assert master_slave < 0.75 * independent


@pytest.mark.parametrize("frictionless", [True, False])
def test_the_gain_limit_is_where_the_linearised_machine_loses_stability(
        frictionless: bool) -> None:
    # measured: 1.78 1/s frictionless, 2.61 1/s with the friction at 10 mm/s sliding
    sync = {"part": "cross_coupled"}
    limit = gain_limit(_machine(sync), "sync", table_speeds=_MOVE_SPEEDS,
                       frictionless=frictionless)
    below = _damping({**sync, "gain": 0.98 * limit}, frictionless)
    above = _damping({**sync, "gain": 1.02 * limit}, frictionless)
    assert below > 0.0 > above


@pytest.mark.slow
def test_cross_coupled_synchronisation_beats_master_slave_and_independent_axes() -> None:
    kp = fd.preset("wang2021").controller.position_gain
    limit = gain_limit(_machine({"part": "cross_coupled"}), "sync", table_speeds=_MOVE_SPEEDS)
    rule = limit / 2  # a 6-dB gain margin on the coupling loop
    master_slave = _peak_yaw({"part": "master_slave", "master": "x1", "slave": "x2",
                              "gain": kp})
    independent = _peak_yaw(None)
    cross_coupled = {f: _peak_yaw({"part": "cross_coupled", "a": "x1", "b": "x2",
                                   "gain": f * rule}) for f in (0.75, 1.0, 1.25)}
    assert cross_coupled[1.0] < independent < master_slave
    # the ratio barely moves with the rule's margin: it is the scheme, not a tuned gain
    ratios = [v / master_slave for v in cross_coupled.values()]
    assert max(ratios) - min(ratios) < 0.02
