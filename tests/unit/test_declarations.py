"""What the parts declare besides their code (issue 19, item 3): the motors the disturbances
act on, the compensator's footprint, the table's travel — and that the generic code reads
these declarations instead of knowing the ball screw.
"""

from __future__ import annotations

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.analysis.linear import averaged
from feeddrive.engine.result import Result
from feeddrive.model.disturbances import TorqueRipple
from feeddrive.model.loops import Compensation
from feeddrive.model.mechanisms import mechanism
from feeddrive.model.reference import ConstantSpeed
from feeddrive.parameters import ParameterError

W = fd.preset("wang2021")
LM = fd.preset("linear-motor-example")
RP = fd.preset("rack-pinion-example")
RIPPLE = TorqueRipple((6.0,), (0.0135,), (0.3,))


def test_every_declared_motor_names_states_of_its_model() -> None:
    """Each mechanism's motors: the rotor-angle state exists in its model (a linear motor
    has none) and the body is one its friction or drive terms act on."""
    for drive, params in (("ddfs", W), ("linear-motor", LM), ("rack-pinion", RP)):
        model = fd.DriveSystem(params, drive, 0.4).model(ConstantSpeed(1e-3))
        motors = mechanism(drive).drive_motors
        assert motors, drive
        for m in motors:
            assert m.angle == "" or m.angle in model.state_names, (drive, m)
            assert f"{m.name}_current" in model.state_names, (drive, m)


@pytest.mark.parametrize("drive, params", [("linear-motor", LM), ("rack-pinion", RP)])
def test_ripple_of_a_motor_the_drive_lacks_is_refused(drive: str,
                                                     params: fd.DriveParameters) -> None:
    p = params.replace_path("disturbances.screw_motor_ripple", RIPPLE)
    with pytest.raises(ParameterError, match=f"screw_motor_ripple.*the {drive} drive has no "
                                              "such motor"):
        fd.DriveSystem(p, drive, 0.4).model(ConstantSpeed(1e-3))


def test_ripple_acts_on_the_declared_motor_s_angle() -> None:
    """The hollow motor's ripple (field ``hollow_motor_ripple`` of the nut motor) is a
    function of the nut angle: its signal equals the harmonic at the nut angle."""
    p = W.replace_path("disturbances.hollow_motor_ripple", RIPPLE)
    model = fd.DriveSystem(p, "ddfs", 0.4).model(ConstantSpeed(0.5e-3, 16e-3))
    assert ("aux:nut_ripple_torque", ("rip_nut",)) in model.flows
    assert ("rip_nut", ("y:nut_angle",)) in model.flows
    y = np.zeros(len(model.states))
    y[model.index("nut_angle")] = 0.2
    aux = np.empty(len(model.aux))
    model.module.rhs(0.1, y, np.zeros(model.n_held), model.P, model.T, np.empty(len(y)), aux)
    ripple = aux[[a.name for a in model.aux].index("nut_ripple_torque")]
    assert ripple == pytest.approx(0.0135 * np.sin(6.0 * 0.2 + 0.3), rel=1e-15)


def test_the_averaged_note_names_the_declared_motor() -> None:
    p = W.replace_path("disturbances.hollow_motor_ripple", RIPPLE)
    _, notes = averaged(fd.DriveSystem(p, "ddfs", 0.4))
    assert notes and notes[0].startswith("warning: hollow-motor torque ripple of the")


def test_the_observer_s_footprint() -> None:
    """The LuGre observer on the CDFS: it adds to the screw axis, compensates the screw and
    guide sites, reads the two measured speeds, the table position and the reference, and
    owns one state per site; the pattern's rows of those states use nothing else."""
    comp = Compensation(mode="observer", observer_gain=50.0)
    model = fd.DriveSystem(W.replace_path("controller.compensation", comp), "cdfs",
                           0.4).model(ConstantSpeed(1e-3))
    fp = model.compensation
    assert fp is not None
    assert (fp.mode, fp.axis, fp.sites) == ("observer", "screw", ("screw", "guide"))
    assert fp.states == ("screw_friction_observer", "guide_friction_observer")
    assert set(fp.reads) == {"y:screw_speed", "y:table_speed", "y:table_position",
                             "reference"}
    assert fp.force == "compensation_force"
    names = model.state_names
    allowed = {names.index(r[2:]) for r in fp.reads if r.startswith("y:")}
    for s in fp.states:
        row = model.jacobian_pattern[names.index(s)]
        assert set(np.flatnonzero(row)) <= allowed | {names.index(s), len(names)}, s


def test_the_feedforward_footprint_reads_the_reference_only() -> None:
    comp = Compensation(mode="feedforward")
    model = fd.DriveSystem(W.replace_path("controller.compensation", comp), "ddfs",
                           0.4).model(ConstantSpeed(1e-3))
    fp = model.compensation
    assert fp is not None and (fp.reads, fp.states) == (("reference",), ())
    plain = fd.DriveSystem(W, "ddfs", 0.4).model(ConstantSpeed(1e-3))
    assert plain.compensation is None


def test_the_travel_is_the_mechanism_s() -> None:
    """A ball-screw table run past the screw's end gets the travel warning — from the run and
    from its dataset alone; a linear-motor table has no travel length and no warning."""
    length = W.screw.length
    system = fd.DriveSystem(W, "cdfs", length - 2e-4)
    r = fd.simulate(system, ConstantSpeed(10e-3), 0.2)
    live = [w for w in r.summary()["warnings"] if "travel" in w or "screw" in w]
    assert live, r.summary()["warnings"]
    stored = [w for w in Result(r.dataset).summary()["warnings"] if "travel" in w or "screw" in w]
    assert stored == live
    assert mechanism("linear-motor").travel_length == ""
    lm = fd.simulate(fd.DriveSystem(LM, "linear-motor", length - 2e-4), ConstantSpeed(10e-3),
                     0.2)
    assert not [w for w in lm.summary()["warnings"] if "travel" in w or "screw" in w]


def test_an_axis_on_a_speed_loop_has_no_position_loop() -> None:
    """Read from the axis' own speed-mode slot, not from the axis name: the DDFS nut on a
    speed loop (``controller.nut_loop = "speed"``, wang2021's) has no position loop in the
    loop analysis and none to ask for; the screw axis keeps its own, and the nut gets one on
    a position loop."""
    speed = fd.DriveSystem(W.replace_path("controller.nut_loop", "speed"), "ddfs", 0.4)
    names = [loop.name for loop in fd.loop_analysis(speed, 1e-3, 16e-3).loops]
    assert "nut position loop" not in names
    assert {"screw position loop", "nut velocity loop"} <= set(names)
    with pytest.raises(ParameterError, match="nut axis runs a speed loop only"):
        fd.frequency_response(speed, "nut_position_loop", nut_speed=16e-3)
    position = fd.DriveSystem(W.replace_path("controller.nut_loop", "position"), "ddfs", 0.4)
    assert "nut position loop" in [loop.name for loop in
                                   fd.loop_analysis(position, 1e-3, 16e-3).loops]


def test_the_run_header_names_the_position_where_the_model_uses_it() -> None:
    """Only the ball screw's stiffness depends on the table position (K_eq(a))."""
    from feeddrive.cli.simulate_cmd import run_header

    for drive, shown in (("cdfs", True), ("ddfs", True), ("linear-motor", False),
                         ("rack-pinion", False)):
        head = run_header(drive, "constant", None, 1.0, 0.0, 400.0, 2.0, "p")
        assert ("position 400 mm" in head) is shown, head
