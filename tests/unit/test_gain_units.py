"""The velocity-loop gains' units come from their own metadata, resolved for the set's
``velocity_gain_basis`` (issue 23 item 6): per m/s of table speed on the table basis."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.cli import app
from feeddrive.parameters import ParameterError
from feeddrive.parameters.validation import resolved_unit


def test_resolved_units_follow_the_basis() -> None:
    table = fd.preset("wang2021").controller
    motor = fd.preset("wang2021-literal").controller
    assert table.velocity_gain_basis == "table" and motor.velocity_gain_basis == "motor"
    assert resolved_unit(table, "velocity_gain") == "A s/m"
    assert resolved_unit(table, "velocity_integral_gain") == "A/m"
    assert resolved_unit(motor, "velocity_gain") == "A s/rad"
    assert resolved_unit(motor, "velocity_integral_gain") == "A/rad"
    assert resolved_unit(table, "position_gain") == "1/s"  # no basis: its own unit


def test_messages_and_params_show_use_the_resolved_unit() -> None:
    with pytest.raises(ParameterError, match=r"\[A s/m\]"):
        fd.preset("wang2021").replace_path("controller.velocity_gain", -1.0)
    with pytest.raises(ParameterError, match=r"\[A s/rad\]"):
        fd.preset("wang2021-literal").replace_path("controller.velocity_gain", -1.0)
    shown = CliRunner().invoke(app, ["params", "show", "--preset", "wang2021"]).stdout
    line = next(ln for ln in shown.splitlines() if ln.startswith("velocity_integral_gain"))
    assert "[A/m, per table speed]" in line
    literal = CliRunner().invoke(app, ["params", "show", "--preset", "wang2021-literal"]).stdout
    line = next(ln for ln in literal.splitlines() if ln.startswith("velocity_gain "))
    assert "[A s/rad]" in line
