"""A machine's parameter slots can be seen without running it, and their ranges read.

``feeddrive params slots`` listed one drive's slots only: a machine's (``<axis>.<slot>``,
``couplings.<name>.<field>``) were seen only in a run's record, and
:func:`feeddrive.model.slot_ranges.slot_range` raised a bare ``KeyError`` for every one of them
(``x.table.mass``, ``couplings.beam.mass``): it had no machine scoping (session 27).
``params slots --machine NAME_OR_FILE`` lists them
(:func:`feeddrive.engine.slot_listing.machine_slot_model`); a machine's axis slot has the range
of the axis' own slot, a coupling slot none declared, refused in one line naming it.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.cli import app
from feeddrive.engine.simulate import DriveSystem
from feeddrive.engine.slot_listing import machine_slot_model
from feeddrive.machine import (
    Machine,
    MachineProfile,
    MachineSystem,
    load_machine,
    machine_from_dict,
)
from feeddrive.model.reference import ConstantSpeed, SampledSpeed
from feeddrive.model.slot_ranges import slot_range
from feeddrive.model.slots import packed_vector
from feeddrive.parameters import ParameterError

RUNNER = CliRunner()
#: one printed slot: name, value (repr), [unit] (the unit may hold spaces: "kg m^2")
LINE = re.compile(r"^(\S+)\s+(\S+)\s+\[(.*)\]$")
#: a machine of three topologies (docs/machine.md: an axis without extends takes its drive's
#: example set), for the scoping of the topology-dependent slots (motor.*, screw.H, the
#: controller axes' H)
MIXED: dict[str, Any] = {"name": "mixed", "axes": {
    "x": {"extends": "wang2021", "drive": "ddfs"},
    "y": {"drive": "linear-motor"},
    "z": {"drive": "rack-pinion"}}}


def _short_run_slots(machine: Machine) -> list[tuple[str, float, str]]:
    """The slots a 0.1-s run of the machine records, without its axes' profile blocks."""
    t = np.linspace(0.0, 0.1, 11)
    moving = SampledSpeed(time=t, table_speed=np.full_like(t, 1e-3))
    profile = MachineProfile.common(machine, moving)
    run = fd.simulate(MachineSystem(machine), profile, 0.1)
    return [row for row in run.parameter_slots if ".profile[" not in row[0]]


def _listed(args: list[str]) -> list[tuple[str, float, str]]:
    out = RUNNER.invoke(app, ["params", "slots", *args])
    assert out.exit_code == 0, out.output
    rows = []
    for line in out.stdout.splitlines():
        match = LINE.match(line)
        assert match, line
        rows.append((match.group(1), float(match.group(2)), match.group(3)))
    return rows


@pytest.mark.parametrize("name", ["xy-table", "gantry"])
def test_the_listing_of_a_built_in_machine_is_its_runs_slot_table(name: str) -> None:
    listed = _listed(["--machine", name])  # old code: no such option (exit 2)
    assert listed == _short_run_slots(load_machine(name))
    names = [row[0] for row in listed]
    axes = [ax.name for ax in load_machine(name).axes]
    assert {n.partition(".")[0] for n in names} == set(axes) | (
        {"couplings"} if name == "gantry" else set())
    assert (f"{axes[0]}.table.mass", 20.0, "kg") in listed  # wang2021's table mass
    if name == "gantry":  # feeddrive.machine.couplings.gantry.GantryBeam's default, its unit
        assert ("couplings.beam.mass", 100.0, "kg") in listed


def test_a_machine_file_is_listed_with_its_coupling_parts(tmp_path: Path) -> None:
    path = tmp_path / "synced.toml"
    path.write_text('name = "synced"\nextends = "gantry"\n[couplings.sync]\n'
                    'part = "cross_coupled"\na = "x1"\nb = "x2"\n', encoding="utf-8")
    listed = _listed(["--machine", str(path)])
    assert listed == _short_run_slots(load_machine(path))
    assert ("couplings.sync.integral_gain", 0.0, "1/s^2") in listed  # CrossCoupled's default


@pytest.mark.parametrize("name", ["xy-table", "gantry"])
def test_the_json_form_is_the_record_a_run_writes(name: str) -> None:
    out = RUNNER.invoke(app, ["params", "slots", "--machine", name, "--json"])
    assert out.exit_code == 0, out.output
    data = json.loads(out.stdout)
    model = machine_slot_model(load_machine(name))
    names, P = packed_vector(data)
    assert names == model.parameter_names
    np.testing.assert_array_equal(P, model.P)
    listed = {row[0]: row for row in _listed(["--machine", name])}
    assert all(tuple(row) == listed[row[0]] for row in data["slots"] if row[0] in listed)


@pytest.mark.parametrize("extra", [["--drive", "ddfs"], ["--preset", "wang2021"],
                                   ["--params", "any.toml"], ["--position", "300"]])
def test_a_drives_options_with_machine_are_refused_in_one_line(extra: list[str]) -> None:
    out = RUNNER.invoke(app, ["params", "slots", "--machine", "xy-table", *extra])
    assert out.exit_code == 2
    assert out.stdout == ""
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1, out.stderr
    assert extra[0] in lines[0] and "not with --machine" in lines[0]


def test_a_drive_is_listed_as_before_without_machine() -> None:
    listed = _listed(["--drive", "ddfs"])
    assert ("table.mass", 20.0, "kg") in listed
    assert listed[0][0] != "x.table.mass" and not any("profile[" in r[0] for r in listed)


@pytest.mark.parametrize("spec", ["xy-table", "gantry", "mixed"])
def test_a_machine_axis_slot_has_the_range_of_the_axis_own_slot(spec: str) -> None:
    machine = machine_from_dict(MIXED) if spec == "mixed" else load_machine(spec)
    model = machine_slot_model(machine)
    first = machine.axes[0]
    drive = DriveSystem(first.parameters, first.drive, first.table_position,
                        first.nut_hold).model(ConstantSpeed(0.0))
    # old code: KeyError("no declared range for the model slot 'x.table.mass'")
    assert slot_range(model, f"{first.name}.table.mass") == slot_range(drive, "table.mass")
    for ax in machine.axes:  # every slot of every axis, as its drive alone has it
        own = DriveSystem(ax.parameters, ax.drive, ax.table_position,
                          ax.nut_hold).model(ConstantSpeed(0.0))
        prefix = f"{ax.name}."
        for name in model.parameter_names:
            if name.startswith(prefix) and name[len(prefix):] in own.parameter_names:
                assert slot_range(model, name) == slot_range(own, name[len(prefix):]), name


def test_a_coupling_slot_is_refused_in_one_line_naming_it() -> None:
    model = machine_slot_model(load_machine("gantry"))
    with pytest.raises(ParameterError) as caught:  # old code: a bare KeyError
        slot_range(model, "couplings.beam.mass")
    text = str(caught.value)
    assert not isinstance(caught.value, KeyError)
    assert "\n" not in text
    assert text.startswith("couplings.beam.mass: ")
    assert "no range is declared" in text and "[kg]" in text
