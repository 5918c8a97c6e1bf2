"""Issue 40: the gantry — two wang2021 CDFS axes carrying one beam — and its synchronisation.

The static check is against the hand balance of the beam (feeddrive.machine.couplings.gantry
module docstring): a load F at the fraction λ of the span from carriage x1, both carriages
held at one position by their servos (integral action), gives
θ = −(λ − 1/2) L F / (k L²/2 + k_θ) and carriage loads (F ± k L θ)/2.

The move compares the synchronisation controllers on a 10-mm/s trapezoid with x1's screw
friction doubled: the peak yaw of the beam with master–slave, with no synchronisation
part, and with the cross-coupled controller (K_c = 2 1/s, the default; the coupled loop is
unstable from about 5 1/s on these axes, whose velocity loop has ζ = 0.034 at 5.5 Hz).
Measured (dopri5 defaults): master–slave 69.0 µrad, none 37.1 µrad, cross-coupled 34.2
µrad.  The issue's "cross-coupled ≤ 0.5 × master–slave" holds (0.50) but only because
master–slave is worse than independent axes here (the slave follows a master that lags);
the test states what the numbers show instead of a ratio tuned to pass.
"""

from __future__ import annotations

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.machine import MachineProfile, machine_from_dict, simulate_machine
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


def _peak_yaw(sync: dict | None) -> float:  # type: ignore[type-arg]
    screw = fd.preset("wang2021").friction.screw
    x1 = {"extends": "wang2021", "drive": "cdfs", "friction": {"screw": {
        "positive": _doubled(screw.positive), "negative": _doubled(screw.negative)}}}
    couplings = {"sync": sync} if sync else {}
    machine = machine_from_dict({"name": "g", "extends": "gantry", "axes": {"x1": x1},
                                 "couplings": couplings})
    move = MachineProfile.common(machine, trapezoid(10e-3, 2.0, ramp_time=0.2))
    return float(np.max(np.abs(simulate_machine(machine, move, 2.0)["beam.yaw"])))


@pytest.mark.slow
def test_cross_coupled_synchronisation_beats_master_slave_and_independent_axes() -> None:
    master_slave = _peak_yaw({"part": "master_slave", "master": "x1", "slave": "x2",
                              "gain": 8.0})
    independent = _peak_yaw(None)
    cross_coupled = _peak_yaw({"part": "cross_coupled", "a": "x1", "b": "x2"})
    assert cross_coupled < independent < master_slave
