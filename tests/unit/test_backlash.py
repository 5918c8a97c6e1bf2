"""Backlash at the ball nut and semi-closed-loop position feedback (issue 37 item 3)."""

from __future__ import annotations

import control
import numpy as np
import pytest

import feeddrive as fd
from feeddrive.model.parts.backlash import (
    Backlash,
    backlash_describing_function,
    friction_backlash_output,
    gap_force,
    gap_hold,
)
from feeddrive.parameters import ParameterError


def with_backlash(params: fd.DriveParameters, part: Backlash) -> fd.DriveParameters:
    return fd.DriveParameters(params.name, params.description, params.mechanism,
                              sections={**dict(params.sections), "backlash": part})


@pytest.mark.parametrize("ratio", [0.6, 0.75, 1.0, 1.5, 2.0, 3.0, 5.0, 7.5, 10.0])
def test_describing_function_matches_python_control(ratio: float) -> None:
    """Acceptance: N(A) of the friction-dominated backlash within 1e-3 of python-control's
    ``friction_backlash_nonlinearity(b).describing_function(A)`` (its b is the full width, as
    ours: the output stays within b/2 of the input) for A in [0.6b, 10b]."""
    b = 1e-5
    amplitude = ratio * b
    ours = backlash_describing_function(amplitude, b)
    theirs = control.friction_backlash_nonlinearity(b).describing_function(amplitude)
    assert abs(ours - theirs) < 1e-3
    assert abs(ours) > 0.05  # not a trivially small value on both sides


def test_describing_function_closed_form_limits() -> None:
    b = 2e-6
    # A ≤ b/2: the driven side never moves (Gelb & Vander Velde 1968, Sect. 2.3)
    assert backlash_describing_function(0.5 * b, b) == 0
    # no gap: the identity
    assert backlash_describing_function(3e-6, 0.0) == pytest.approx(1.0, abs=1e-9)
    with pytest.raises(ParameterError, match="amplitude"):
        backlash_describing_function(-1.0, b)
    with pytest.raises(ParameterError, match="backlash.gap"):
        backlash_describing_function(1e-5, float("nan"))


def test_rigid_law_is_python_controls_nonlinearity() -> None:
    """The part's rigid limit, sample by sample, equals python-control's stateful law."""
    rng = np.random.default_rng(7)
    x = np.cumsum(rng.normal(scale=3e-6, size=400))
    ref = control.friction_backlash_nonlinearity(1e-5)
    expected = [ref(v) for v in x]
    assert friction_backlash_output(x, 1e-5) == pytest.approx(expected, abs=1e-18)


def test_dead_zone_spring() -> None:
    k, c, half = 2e8, 1e3, 5e-6
    assert gap_force(4.9e-6, 1.0, k, c, half) == 0.0  # inside: nothing, whatever the rate
    assert gap_force(-4.9e-6, -1.0, k, c, half) == 0.0
    assert gap_force(6e-6, 0.0, k, c, half) == pytest.approx(k * 1e-6)
    assert gap_force(-6e-6, 0.0, k, c, half) == pytest.approx(-k * 1e-6)
    assert gap_force(6e-6, 1e-4, k, c, half) == pytest.approx(k * 1e-6 + c * 1e-4)
    assert gap_force(5.1e-6, -1.0, k, c, half) == 0.0  # the damping never pulls
    assert gap_hold(0.0, 1e-3, half, 20.0, 1e-4) == pytest.approx(-20.0 * 1e-3 / 1e-4)
    assert gap_hold(6e-6, 1e-3, half, 20.0, 1e-4) == 0.0  # in contact: no hold
    assert gap_hold(0.0, 1e-3, half, 20.0, 0.0) == 0.0  # inertia-dominated


def test_bad_backlash_refused() -> None:
    with pytest.raises(ParameterError, match="backlash.gap"):
        Backlash(gap=-1e-6)
    with pytest.raises(ParameterError, match="backlash.location"):
        Backlash(gap=1e-5, location="gear")
    with pytest.raises(ParameterError, match="backlash.gap_behaviour"):
        Backlash(gap=1e-5, gap_behaviour="sticky")
    params = with_backlash(fd.preset("linear-motor-example"), Backlash(gap=1e-5))
    with pytest.raises(ParameterError, match="no ball nut"):
        fd.simulate(fd.DriveSystem(params, "linear-motor"), fd.ConstantSpeed(1e-3), 1e-3)


def test_motor_feedback_refused_without_a_lead() -> None:
    params = fd.preset("linear-motor-example").replace_path("controller.position_feedback",
                                                            "motor")
    with pytest.raises(ParameterError, match="controller.position_feedback"):
        fd.simulate(fd.DriveSystem(params, "linear-motor"), fd.ConstantSpeed(1e-3), 1e-3)
    with pytest.raises(ParameterError, match="controller.position_feedback"):
        fd.preset("wang2021").replace_path("controller.position_feedback", "encoder")


def test_docs_describe_the_part() -> None:
    """docs/acceptance-tests.md's [backlash] block loads as the part with its defaults;
    docs/extending.md names every field and both gap behaviours."""
    import dataclasses
    import re
    from pathlib import Path

    from feeddrive.parameters.toml_io import parse_toml

    docs = Path(__file__).resolve().parents[2] / "docs"
    text = (docs / "acceptance-tests.md").read_text(encoding="utf-8")
    block = re.search(r"```toml\n(\[backlash\].*?)```", text, re.S)
    assert block is not None
    given = parse_toml(block.group(1))["backlash"]
    assert Backlash(**given) == Backlash(gap=1e-5)
    extending = (docs / "extending.md").read_text(encoding="utf-8")
    for f in dataclasses.fields(Backlash):
        assert f"`{f.name}`" in extending
    for option in ("friction", "inertia", "coupling"):
        assert f'"{option}"' in extending


def test_hollow_controller_position_feedback_refused() -> None:
    """The option is the table axis' ([controller]); the hollow motor reads its encoder."""
    params = fd.preset("wang2021")
    params = params.replace_path("hollow_controller",
                                 params.controller.with_values(position_feedback="motor"))
    with pytest.raises(ParameterError, match="hollow_controller.position_feedback"):
        fd.simulate(fd.DriveSystem(params, "ddfs", 0.4), fd.ConstantSpeed(1e-3, 8e-3), 1e-3)


def test_coupling_gap_gives_the_shaft_its_own_body() -> None:
    """Only a gap at the coupling adds the shaft's states; a shaft without inertia beyond it
    is refused with one line naming the field."""
    from feeddrive.model.mechanisms.ball_screw import BallScrewDrive

    params = fd.preset("wang2021")
    gap = with_backlash(params, Backlash(gap=1e-5, location="coupling"))
    run = fd.simulate(fd.DriveSystem(gap, "cdfs", 0.4), fd.ConstantSpeed(1e-3), 1e-3)
    assert "shaft_angle" in run.signal_names() and "shaft_speed" in run.signal_names()
    nut = with_backlash(params, Backlash(gap=1e-5))
    run = fd.simulate(fd.DriveSystem(nut, "cdfs", 0.4), fd.ConstantSpeed(1e-3), 1e-3)
    assert "shaft_angle" not in run.signal_names()
    steady = BallScrewDrive(gap, "cdfs", 0.4, "locked").steady_motion(1e-3, 0.0)
    assert steady["shaft_angle"] == ("shaft_speed", steady["screw_angle"][1])
    massless = with_backlash(params.replace_path("screw.shaft_inertia", 0.0),
                             Backlash(gap=1e-5, location="coupling"))
    with pytest.raises(ParameterError, match="screw.shaft_inertia"):
        fd.simulate(fd.DriveSystem(massless, "cdfs", 0.4), fd.ConstantSpeed(1e-3), 1e-3)
    with pytest.raises(ParameterError, match="backlash.motor_side_share"):
        Backlash(gap=1e-5, location="coupling", motor_side_share=1.0)
