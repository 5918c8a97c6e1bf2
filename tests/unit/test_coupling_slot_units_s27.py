"""A machine's coupling parameters carry their units in the parameters a run used.

A machine's coupling part packs its parameters as slots ``couplings.<name>.<field>``; the run's
record (``parameter_slots``, ``feeddrive params slots``) wrote every one of them without a
unit (``['couplings.beam.mass', 100.0, '']``), although the part's class declares them
(:attr:`feeddrive.machine.couplings.Coupling.units`): the model did not record which part
packed them (session 27).  Every slot of every built-in machine now has a unit, "-" when it
is dimensionless (the convention of the one-drive slots: ``controller.<axis>.ff``,
``nut.active``); the reference profile's encoded block alone has none (a slot of mixed
meaning, :func:`feeddrive.model.slots.slot_unit`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import xarray as xr

import feeddrive as fd
from feeddrive import registry
from feeddrive.machine import MACHINES, Machine, MachineProfile, MachineSystem, machine_from_dict
from feeddrive.model.reference import SampledSpeed
from feeddrive.model.slots import packed_vector, slot_table

#: every built-in machine, and each with the coupling parts a machine file may add
#: (docs/machine.md: the gantry's [couplings.sync], the XY table's [couplings.carry])
CASES: dict[str, dict[str, Any]] = {
    **{name: {"extends": name} for name in MACHINES},
    "gantry+master_slave": {"extends": "gantry", "couplings": {
        "sync": {"part": "master_slave", "master": "x1", "slave": "x2"}}},
    "gantry+cross_coupled": {"extends": "gantry", "couplings": {
        "sync": {"part": "cross_coupled", "a": "x1", "b": "x2"}}},
    "xy-table+inertial": {"extends": "xy-table", "couplings": {
        "carry": {"part": "inertial", "source": "x", "target": "y", "mass": 5.0,
                  "factor": 0.1}}},
}


def _machine(case: str) -> Machine:
    return machine_from_dict({"name": case, **CASES[case]})


def _profile(machine: Machine, duration: float = 0.1) -> MachineProfile:
    t = np.linspace(0.0, duration, 11)
    return MachineProfile.common(machine, SampledSpeed(time=t, table_speed=np.full_like(t, 1e-3)))


def _rows(case: str) -> list[tuple[str, float, str]]:
    machine = _machine(case)
    return slot_table(MachineSystem(machine).model(_profile(machine)))


def test_the_cases_cover_every_built_in_machine_and_coupling_part() -> None:
    parts = {t["part"] for case in CASES.values()
             for t in (MACHINES.get(case.get("extends", ""), {}).get("couplings", {})
                       | case.get("couplings", {})).values()}
    assert set(MACHINES) <= set(CASES)
    assert parts == set(registry.names(registry.COUPLINGS))


@pytest.mark.parametrize("case", sorted(CASES))
def test_every_slot_of_a_built_in_machine_has_a_unit(case: str) -> None:
    rows = _rows(case)
    empty = [name for name, _, unit in rows
             if not unit and not name.partition(".")[2].startswith("profile[")]
    assert empty == []  # it was every couplings.<name>.<field> (session 27)
    assert all(unit == "" for name, _, unit in rows if "profile[" in name)


@pytest.mark.parametrize("case", sorted(CASES))
def test_a_coupling_slot_has_the_unit_its_part_declares(case: str) -> None:
    machine = _machine(case)
    rows = _rows(case)
    coupled = {name: unit for name, _, unit in rows if name.startswith("couplings.")}
    expected = {f"couplings.{c.name}.{field}": unit
                for c in machine.couplings for field, unit in type(c).units.items()}
    assert coupled == expected
    assert len(coupled) == sum(len(c.parameters()) for c in machine.couplings)


def test_the_gantry_beams_slots_read_as_its_class_declares() -> None:
    # feeddrive.machine.couplings.gantry.GantryBeam.units; "-" dimensionless (load_position,
    # the share of the span)
    rows = {name: (value, unit) for name, value, unit in _rows("gantry")}
    assert rows["couplings.beam.mass"] == (100.0, "kg")
    assert rows["couplings.beam.inertia"][1] == "kg m^2"
    assert rows["couplings.beam.joint_stiffness"][1] == "N/m"
    assert rows["couplings.beam.yaw_stiffness"][1] == "N m/rad"
    assert rows["couplings.beam.load_position"] == (0.5, "-")
    assert rows["x1.table.mass"][1] == "kg"  # the axes' slots keep theirs


def test_a_coupled_machine_runs_slots_keep_their_units_through_netcdf(tmp_path: Path) -> None:
    machine = _machine("gantry+cross_coupled")
    profile = _profile(machine)
    run = fd.simulate(MachineSystem(machine), profile, 0.1)
    rows = run.parameter_slots
    assert ("couplings.sync.integral_gain", 0.0, "1/s^2") in rows  # CrossCoupled.units
    assert ("couplings.beam.mass", 100.0, "kg") in rows
    assert rows == slot_table(MachineSystem(machine).model(profile))
    nc = run.save(tmp_path / "gantry.nc")
    with xr.open_dataset(nc) as ds:
        back = fd.Result(ds.load())
        names, P = packed_vector(ds.attrs["parameter_slots"])
    assert back.parameter_slots == rows
    assert names == tuple(name for name, _, _ in rows)
    np.testing.assert_array_equal(P, [value for _, value, _ in rows])
