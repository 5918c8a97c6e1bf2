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
    guide sites, reads the two measured speeds, the table position and the commanded position
    (as its code reads them: the footprint is derived from the text), and
    owns one state per site; the pattern's rows of those states use nothing else."""
    comp = Compensation(mode="observer", observer_gain=50.0)
    model = fd.DriveSystem(W.replace_path("controller.compensation", comp), "cdfs",
                           0.4).model(ConstantSpeed(1e-3))
    fp = model.compensation
    assert fp is not None
    assert (fp.mode, fp.axis, fp.sites) == ("observer", "screw", ("screw", "guide"))
    assert fp.states == ("screw_friction_observer", "guide_friction_observer")
    assert set(fp.reads) == {"y:screw_speed", "y:table_speed", "y:table_position", "ref_x"}
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
    # the DDFS screw's commanded speed is the table's plus the nut's reference
    assert fp is not None and (fp.reads, fp.states) == (("ref_v", "ref_v_nut"), ())
    plain = fd.DriveSystem(W, "ddfs", 0.4).model(ConstantSpeed(1e-3))
    assert plain.compensation is None


def test_only_a_drive_that_follows_the_nut_reference_reads_it() -> None:
    """Issue 40 item 2: the reference is a set of named signals a topology asks for — the
    DDFS (``followed_references``) reads the nut's, the CDFS, which holds its nut, never
    does: no value of its model is computed from it, no line of its code calls for it."""
    for drive, follows in (("ddfs", True), ("cdfs", False)):
        model = fd.DriveSystem(W, drive, 0.4).model(ConstantSpeed(1e-3))
        values = {w for w, _ in model.flows}
        reads = {r for _, rs in model.flows for r in rs}
        assert ({"ref_x_nut", "ref_v_nut"} <= values) is follows, drive
        assert ({"ref_x_nut", "ref_v_nut"} & reads != set()) is follows, drive
        assert ("ref_x_nut" in model.source) is follows, drive
        assert {"ref_x", "ref_v"} <= values, drive  # the table's, every drive's


def test_the_travel_is_the_mechanism_s() -> None:
    """A ball-screw table run past the screw's end gets the travel warning — from the run and
    from its dataset alone; a linear-motor table has no travel length and no warning (its
    set's screw ends 0.2 mm past where the table starts: a linear motor takes no start
    position of its own since session 30)."""
    length = W.screw.length
    system = fd.DriveSystem(W, "cdfs", length - 2e-4)
    r = fd.simulate(system, ConstantSpeed(10e-3), 0.2)
    live = [w for w in r.summary()["warnings"] if "travel" in w or "screw" in w]
    assert live, r.summary()["warnings"]
    stored = [w for w in Result(r.dataset).summary()["warnings"] if "travel" in w or "screw" in w]
    assert stored == live
    assert mechanism("linear-motor").travel_length == ""
    short = LM.replace_path("screw.length", fd.DriveSystem(LM, "linear-motor").table_position
                            + 2e-4)
    lm = fd.simulate(fd.DriveSystem(short, "linear-motor"), ConstantSpeed(10e-3), 0.2)
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


# ---- the edges ask the topology (issue 19 item 3: no ``drive == "…"`` outside the parts)


def test_the_acting_sites_are_the_declared_ones_less_a_held_nut() -> None:
    """The explorer's friction curves (and anyone else) ask the topology which sites act:
    the locked CDFS's nut does not; the rack-and-pinion's gearbox does, without an edit."""
    def keys(drive: str, params: fd.DriveParameters, nut_hold: str = "locked") -> set[str]:
        topology = fd.DriveSystem(params, drive, 0.4, nut_hold=nut_hold).topology()
        return {s.parameters_key for s in topology.acting_sites()}

    assert keys("cdfs", W) == {"screw", "guide"}
    assert keys("cdfs", W, "servo") == {"screw", "nut", "guide"}
    assert keys("ddfs", W) == {"screw", "nut", "guide"}
    assert keys("linear-motor", LM) == {"guide"}
    assert keys("rack-pinion", RP) == {"rack_pinion.gearbox_friction", "guide"}


def test_the_explorer_s_friction_curves_follow_the_declared_sites() -> None:
    from feeddrive.explore.compute import _sites
    from feeddrive.explore.settings import check

    checked = check({"drive": "rack-pinion", "preset": "rack-pinion-example"})
    assert checked.errors == {}, checked.errors
    sites = _sites(checked)
    assert set(sites) == {"gearbox", "guide"}
    assert sites["gearbox"] == ("rack_pinion.gearbox_friction", RP.section("rack_pinion")
                                .gearbox_friction)
    assert "nut_speed" in checked.disabled  # the topology follows no nut reference
    assert "nut_speed" not in check({"drive": "ddfs"}).disabled
    # the friction-scale knob scales every site, the gearbox's in its part's section too
    scaled = check({"drive": "rack-pinion", "preset": "rack-pinion-example",
                    "friction_scale": "0.5"})
    assert scaled.errors == {}, scaled.errors
    assert scaled.params is not None
    gearbox = RP.section("rack_pinion").gearbox_friction
    assert scaled.params.section("rack_pinion").gearbox_friction == gearbox.scaled(0.5)
    assert scaled.params.friction.guide == RP.friction.guide.scaled(0.5)


def test_which_axes_follow_a_nut_reference() -> None:
    """The nut axis and whether it runs are the topology's: the DDFS drives its nut, the
    CDFS holds it (on its servo the axis runs at zero command), the others have none."""
    def topology(drive: str, params: fd.DriveParameters, nut_hold: str = "locked"):
        return fd.DriveSystem(params, drive, 0.4, nut_hold=nut_hold).topology()

    assert topology("ddfs", W).follows("nut")
    assert not topology("cdfs", W).follows("nut")
    assert topology("cdfs", W).reference_axes == {"nut": "nut"}
    assert topology("cdfs", W, "servo").live_axes() == ("screw", "nut")
    assert not topology("cdfs", W, "servo").follows("nut")
    assert topology("cdfs", W).live_axes() == ("screw",)
    for drive, params in (("linear-motor", LM), ("rack-pinion", RP)):
        assert topology(drive, params).reference_axes == {}
        assert not topology(drive, params).follows("nut")
        assert topology(drive, params).live_axes() == ("motor",)


def test_the_mechanism_base_class_speaks_no_nut() -> None:
    """Issue 40 item 1: the DDFS's nut is its own declared reference signal
    (``BallScrew.reference_axes``), not vocabulary of every topology's base class."""
    from feeddrive.model.mechanisms.base import Mechanism

    assert [name for name in vars(Mechanism) if "nut" in name.lower()] == []
    assert Mechanism.reference_axes == {}


@pytest.mark.parametrize("drive, params, path, reason", [
    ("cdfs", W, "linear_motor.force_constant", "the CDFS has no linear motor"),
    ("ddfs", W, "rack_pinion.mesh_stiffness", "the DDFS has no rack and pinion"),
    ("linear-motor", LM, "screw.lead", "a linear-motor drive has no ball screw"),
    ("linear-motor", LM, "hollow_controller.velocity_gain",
     "a linear-motor drive has no ball screw"),
    ("rack-pinion", RP, "screw_motor.inertia", "a rack-pinion drive has no ball screw"),
    ("rack-pinion", RP, "linear_motor.forcer_mass", "a rack-pinion drive has no linear motor"),
    ("cdfs", W, "hollow_motor.inertia", "the CDFS holds the nut (hollow motor locked)"),
    ("cdfs", W, "friction.nut.bristle_stiffness",
     "the CDFS holds the nut (hollow motor locked)"),
    ("cdfs", W, "friction.ball_nut_share", "the CDFS holds the nut (hollow motor locked)"),
    ("ddfs", W, "hollow_motor.inertia", None),
    ("rack-pinion", RP, "rack_pinion.mesh_stiffness", None),
    ("rack-pinion", RP, "table.mass", None),
])
def test_a_fit_refuses_what_the_topology_does_not_have(drive, params, path, reason) -> None:
    """The fit's "has no effect" rules come from the topologies' declarations (their own
    sections, what they hold), so a new topology's sections are known without an edit."""
    from feeddrive.analysis.fit import _no_effect

    assert _no_effect(params, drive, path, []) == reason


def test_the_fit_reads_the_table_motor_the_topology_names() -> None:
    """``fit``'s torque-to-current constant and a synthetic record's current are those of
    the motor that drives the table (``Mechanism.table_axis``)."""
    from feeddrive.analysis.fit import synthetic_experiment
    from feeddrive.cli.fit_cmd import _table_motor_constant

    assert _table_motor_constant(W, "cdfs", 0.4) == W.screw_motor.torque_constant
    assert _table_motor_constant(LM, "linear-motor", 0.4) == LM.linear_motor.force_constant
    rp = RP.section("rack_pinion")
    assert _table_motor_constant(RP, "rack-pinion", 0.4) == rp.motor.torque_constant
    record = synthetic_experiment(RP, 5e-3, 0.05, drive="rack-pinion")
    assert set(record.signals) == {"table_position", "motor_current"}


def test_the_compensation_study_runs_on_the_drives_that_declare_a_compensator() -> None:
    """``compensate`` asks the topologies: a drive with a compensator and no driven nut,
    with the drive of its topology that drives the nut as the alternative."""
    from feeddrive.analysis.compensation import default_cases, study_drives
    from feeddrive.cli.compensate_cmd import STUDY_DRIVES

    assert study_drives(W) == {"cdfs": "ddfs", "linear-motor": None}
    assert STUDY_DRIVES.split("|") == list(study_drives(W))  # what --help lists
    cases = default_cases(0.2, drive="linear-motor", alternative=None)
    assert [c.drive for c in cases] == ["linear-motor"] * 7
    assert cases[0].label == "LINEAR-MOTOR, no compensation"
    paper = [c.label for c in default_cases(0.2)]
    assert (paper[0], paper[-1]) == ("CDFS, no compensation", "DDFS, v_n = 16 mm/s")


def test_the_result_title_names_the_position_where_the_model_uses_it() -> None:
    from feeddrive.plots.result import run_title

    for drive, params, shown in (("cdfs", W, True), ("rack-pinion", RP, False)):
        run = fd.simulate(fd.DriveSystem(params, drive, 0.4), ConstantSpeed(1e-3), 0.01)
        assert (", position 400 mm" in run_title(run)) is shown, run_title(run)


def test_a_sweep_runs_any_registered_drive_and_asks_it_about_the_nut() -> None:
    """A sweep's drive takes every registered drive; a drive that follows no nut speed (its
    topology's ``followed_references``) shares one result across nut speeds."""
    from feeddrive.sweep import parse_config

    def keys(config: dict) -> int:
        return len({p.key for p in parse_config(config, "study.toml").points()})

    assert keys({"drive": "rack-pinion", "preset": "rack-pinion-example",
                 "axes": {"nut_speed": [2, 10]}}) == 1
    assert keys({"drive": "ddfs", "axes": {"nut_speed": [2, 10]}}) == 2
    assert keys({"drive": "cdfs", "axes": {"nut_speed": [2, 10]}}) == 1
    with pytest.raises(ParameterError, match="rack-pinion"):
        parse_config({"axes": {"drive": ["gantry"]}}, "study.toml").points()
