"""Leftovers of the earlier bad-input sweeps (session 30): arguments read and dropped without
a word, now refused in one line naming the argument, its value and what was expected.

1. ``frequency_response(lin, …, table_speed=…)``: a LinearModel keeps the operating point it
   was linearised at; ``table_speed``, ``nut_speed`` and ``frictionless`` were ignored.
2. ``analyze_trace(…, command…, segment=False)``: a command sets the segments; ``segment``
   was ignored.
3. ``DriveParameters.section("backlsh")``: a misspelt section read as an absent one (None).
4. A machine axis' ``nut_hold`` / ``table_position`` on a drive that does not use them were
   read and dropped (``machine_toml`` wrote both on every axis).
5. ``validate`` with one record twice scored it twice.
"""

from __future__ import annotations

import tomllib
from typing import Any

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.analysis.fit import Experiment, FitError
from feeddrive.analysis.linear import frequency_response, linearize
from feeddrive.analysis.trace import analyze_trace
from feeddrive.machine import machine_from_dict, machine_toml
from feeddrive.parameters import ParameterError

# ------------------------------------------- 1: frequency_response's operating point


@pytest.fixture(scope="module")
def cdfs() -> fd.DriveSystem:
    return fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)


@pytest.mark.parametrize(("keyword", "value", "shown"), [
    ("table_speed", 2e-3, "0.002"), ("nut_speed", 0.0, "0.0"),
    ("frictionless", True, "True"), ("frictionless", False, "False")])
def test_a_linear_model_refuses_an_operating_point(cdfs: fd.DriveSystem, keyword: str,
                                                   value: object, shown: str) -> None:
    """Each was dropped: the response was the model's own, at 1 mm/s, whatever was given
    (even a value equal to the model's own is refused: it is not read)."""
    lin = linearize(cdfs, 1e-3, frictionless=True)
    with pytest.raises(ParameterError, match=rf"^{keyword} = {shown}: not with a LinearModel: "
                                             r"it keeps the point it was linearised at \(1 "
                                             r"mm/s table, v_n 0 mm/s, frictionless True\); "
                                             rf"expected None, or linearize\(system, "
                                             rf"{keyword}=…\) for another$"):
        frequency_response(lin, "tracking", **{keyword: value})


def test_none_is_the_documented_point_for_a_drive_system(cdfs: fd.DriveSystem) -> None:
    """None stands for the documented defaults (1e-3 m/s, 0 m/s, frictionless) with a
    DriveSystem: its response is the one of the model linearised there, and a point given is
    taken; the model itself takes none."""
    f = np.array([1.0, 30.0, 300.0])
    default = frequency_response(cdfs, "dynamic_compliance", frequency_hz=f).response
    lin = linearize(cdfs, 1e-3, 0.0, frictionless=True)
    np.testing.assert_array_equal(
        default, frequency_response(lin, "dynamic_compliance", frequency_hz=f).response)
    faster = frequency_response(cdfs, "dynamic_compliance", frequency_hz=f, table_speed=2e-3,
                                frictionless=False).response
    np.testing.assert_array_equal(faster, frequency_response(
        linearize(cdfs, 2e-3, frictionless=False), "dynamic_compliance",
        frequency_hz=f).response)
    with pytest.raises(ParameterError, match=r"^table_speed = 0\.002: not with a LinearModel"):
        frequency_response(lin, "dynamic_compliance", frequency_hz=f, table_speed=2e-3)


# -------------------------------------------------- 2: analyze_trace's segment


def _trace() -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(0.0, 20.0, 5e-3)
    return t, 1e-3 * t


@pytest.mark.parametrize(("given", "says"), [
    ({"command_speed": 1e-3}, "command_speed, which makes the whole trace one segment"),
    ({"command": np.full(4000, 1e-3)}, "command, whose steps set the segments")])
def test_segment_false_is_refused_beside_a_command(given: dict[str, Any], says: str) -> None:
    t, x = _trace()
    with pytest.raises(ParameterError, match=rf"^segment = False: not with {says} \(segments "
                                             r"are detected only without a command\); "
                                             r"expected True or no command$"):
        analyze_trace(t, x, segment=False, **given)
    assert len(analyze_trace(t, x, **given).segments) == 1  # segment=True, the default
    assert len(analyze_trace(t, x, segment=False).segments) == 1  # without a command


# ---------------------------------------------------- 3: a misspelt section's name


@pytest.mark.parametrize(("name", "meant"), [("backlsh", "backlash"), ("Screw", "screw"),
                                             ("linear_motors", "linear_motor")])
def test_a_misspelt_section_is_refused(name: str, meant: str) -> None:
    params = fd.preset("wang2021")
    with pytest.raises(ParameterError, match=rf"^name = '{name}': no section of that name "
                                             rf"\(did you mean '{meant}'\?\); expected one "
                                             r"of acceleration_feedforward, backlash, .*, "
                                             r"table$"):
        params.section(name)
    # what test_sections pins: a name no installed part registers (a plugin's section, its
    # package not installed here) is no section of the set, None; so is a registered
    # section the set does not give
    assert params.section("toy_gear") is None
    assert params.section("backlash") is None
    assert params.section("screw") is params.screw


# ----------------------------------------------------- 4: a machine axis' extra keys


@pytest.mark.parametrize(("drive", "key", "value", "says"), [
    ("linear-motor", "nut_hold", "locked", r"applies to a drive that holds its nut \(cdfs\), "
                                           r"not to linear-motor \(it has no nut\)"),
    ("ddfs", "nut_hold", "locked", r"applies to a drive that holds its nut \(cdfs\), not to "
                                   r"ddfs \(it drives its nut: the nut speed reference\)"),
    ("linear-motor", "table_position", 0.4, r"applies to a drive whose model depends on the "
                                            r"table's position \(cdfs, ddfs\), not to "
                                            r"linear-motor; omit it"),
    ("rack-pinion", "table_position", 0.25, r"applies to a drive whose model depends on the "
                                            r"table's position \(cdfs, ddfs\), not to "
                                            r"rack-pinion; omit it")])
def test_a_machine_axis_refuses_a_key_its_drive_does_not_read(drive: str, key: str,
                                                              value: object, says: str) -> None:
    axis = {"drive": drive, key: value}
    with pytest.raises(ParameterError, match=rf"^axes\.y\.{key} = {value!r}: {says}$"):
        machine_from_dict({"name": "m", "axes": {"y": axis}})
    del axis[key]
    machine_from_dict({"name": "m", "axes": {"y": axis}})


def test_a_written_machine_reads_back_identical() -> None:
    machine = machine_from_dict({"name": "mixed", "axes": {
        "x": {"extends": "wang2021", "drive": "cdfs", "table_position": 0.3,
              "nut_hold": "servo"},
        "y": {"drive": "linear-motor"},
        "z": {"extends": "wang2021", "drive": "ddfs", "table_position": 0.5}}})
    text = machine_toml(machine)
    axes = tomllib.loads(text)["axes"]
    assert (axes["x"]["table_position"], axes["x"]["nut_hold"]) == (0.3, "servo")
    assert "table_position" not in axes["y"] and "nut_hold" not in axes["y"]
    assert axes["z"]["table_position"] == 0.5 and "nut_hold" not in axes["z"]
    again = machine_from_dict(tomllib.loads(text))
    assert again == machine
    assert machine_toml(again) == text


# ----------------------------------------------------- 5: validate's repeated record


def _record(source: str) -> Experiment:
    t = np.arange(0.0, 1.0, 1e-3)
    v = np.full(t.size, 1e-3)
    return Experiment(source=source, time=t, signals={"table_position": v * t},
                      reference_time=t, table_speed=v, noise={"table_position": 1e-8})


@pytest.mark.parametrize(("second", "says"), [
    ("a.csv", "a.csv: given twice"), ("copy.csv", "copy.csv: the same record as a.csv")])
def test_validate_refuses_one_record_given_twice(monkeypatch: pytest.MonkeyPatch, second: str,
                                                 says: str) -> None:
    """Refused before the fitted file is read or anything simulated (the fitted file named
    here does not exist)."""
    from feeddrive.analysis import validate as valmod

    def no_run(task: object) -> dict[str, object]:
        raise AssertionError("a simulation ran although the input was refused")

    monkeypatch.setattr(valmod, "simulate_experiment", no_run)
    with pytest.raises(FitError, match=rf"^{says}; each held-out record is scored once "
                                       r"\(twice, its rows would repeat\)$"):
        valmod.validate("no-such-fit.toml", [_record("a.csv"), _record(second)])
