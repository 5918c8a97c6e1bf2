"""The parameters a run used are written from the assembled model's named slots, with units,
and read back to the same packed vector (issue 19 item 2; :mod:`feeddrive.model.slots`)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import xarray as xr
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive import registry
from feeddrive.cli import app, params_cmd
from feeddrive.engine.simulate import DriveSystem, simulate
from feeddrive.model.assemble import assemble
from feeddrive.model.reference import ConstantSpeed
from feeddrive.model.slots import FORMAT, packed_vector, slot_table, slot_unit, slots_json
from feeddrive.parameters import ParameterError, loads

ROOT = Path(__file__).resolve().parents[2]
CASES = [("wang2021", "cdfs"), ("wang2021", "ddfs"), ("wang2021-ripple", "ddfs"),
         ("wang2021-drive", "cdfs"), ("linear-motor-example", "linear-motor"),
         ("rack-pinion-example", "rack-pinion"), ("gms", "cdfs")]


def _params(name: str) -> fd.DriveParameters:
    if name == "gms":
        path = ROOT / "examples" / "gms_guide.toml"
        return loads(path.read_text(encoding="utf-8"), base_dir=path.parent)
    return fd.preset(name)


@pytest.mark.parametrize(("name", "drive"), CASES)
def test_every_slot_is_written_with_a_unit_and_reads_back_bit_for_bit(name: str, drive: str):
    model = assemble(_params(name), drive, 0.4, "locked", ConstantSpeed(1e-3))
    rows = slot_table(model)
    assert [r[0] for r in rows] == list(model.parameter_names)
    # every slot but the reference profile's encoded block has a unit
    assert [r[0] for r in rows if not r[2] and not r[0].startswith("profile[")] == []
    names, P = packed_vector(slots_json(model))
    assert names == model.parameter_names
    np.testing.assert_array_equal(P, model.P)


def test_units_come_from_the_parts_declarations():
    model = assemble(fd.preset("wang2021"), "ddfs", 0.4, "locked", ConstantSpeed(1e-3))
    assert slot_unit(model, "table.mass") == "kg"  # Table.mass
    assert slot_unit(model, "friction.screw.bristle_stiffness") == "N/m"  # LuGreParameters
    assert slot_unit(model, "friction.guide.positive.stribeck_velocity") == "m/s"
    assert slot_unit(model, "screw_motor.inductance") == "H"  # Motor
    # wang2021 reads K_vp on table speed: the unit follows the axis' gain basis
    assert slot_unit(model, "controller.screw.kvp") == "A s/m"
    literal = assemble(fd.preset("wang2021-literal"), "cdfs", 0.4, "locked",
                       ConstantSpeed(1e-3))
    assert slot_unit(literal, "controller.screw.kvp") == "A s/rad"
    gms = assemble(_params("gms"), "cdfs", 0.4, "locked", ConstantSpeed(1e-3))
    assert slot_unit(gms, "friction.guide.element_stiffness[2]") == "N/m"  # GMSParameters
    assert slot_unit(gms, "friction.guide.attraction") == "N/s"
    lm = assemble(fd.preset("linear-motor-example"), "linear-motor", 0.4, "locked",
                  ConstantSpeed(1e-3))
    assert slot_unit(lm, "motor.back_emf_constant") == "V s/m"
    rp = assemble(fd.preset("rack-pinion-example"), "rack-pinion", 0.4, "locked",
                  ConstantSpeed(1e-3))
    assert slot_unit(rp, "rack_pinion.mesh_stiffness") == "N/m"  # RackPinion
    assert slot_unit(rp, "motor.back_emf_constant") == "V s/rad"


def test_the_record_is_the_models_values_not_the_sets():
    # H and the inertia sums are derived by the mechanism: the record holds them as the
    # kernels read them
    params = fd.preset("wang2021")
    model = assemble(params, "cdfs", 0.4, "locked", ConstantSpeed(1e-3))
    record = {n: (v, u) for n, v, u in slot_table(model)}
    assert record["screw.H"] == (params.screw.transmission_ratio, "m/rad")
    assert record["screw.J"][0] == params.screw_motor.inertia + params.screw.shaft_inertia
    assert record["friction.screw.bristle_stiffness"][0] == model.parameter(
        "friction.screw.bristle_stiffness")


def test_a_record_of_another_kind_is_refused_in_one_line():
    with pytest.raises(ParameterError, match=f"expected a {FORMAT} record"):
        packed_vector('{"slots": []}')


def test_a_run_writes_its_slots_and_they_read_back_from_netcdf_and_mat(tmp_path: Path):
    system = DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    result = simulate(system, ConstantSpeed(1e-3), 0.05)
    model = assemble(system.parameters, "cdfs", 0.4, "locked", ConstantSpeed(1e-3))
    names, P = packed_vector(result.dataset.attrs["parameter_slots"])
    assert names == model.parameter_names
    np.testing.assert_array_equal(P, model.P)
    nc = result.save(tmp_path / "run.nc")
    with xr.open_dataset(nc) as ds:
        back = fd.Result(ds.load())
    assert back.parameter_slots == result.parameter_slots
    np.testing.assert_array_equal(packed_vector(ds.attrs["parameter_slots"])[1], model.P)
    mat = result.save(tmp_path / "run.mat")
    attrs = scipy.io.loadmat(mat, simplify_cells=True)["feeddrive"]["attrs"]
    np.testing.assert_array_equal(packed_vector(json.loads(attrs["parameter_slots"]))[1],
                                  model.P)


def test_params_slots_prints_the_models_record():
    runner = CliRunner()
    out = runner.invoke(app, ["params", "slots", "--drive", "ddfs", "--json"])
    assert out.exit_code == 0, out.output
    model = assemble(fd.preset("wang2021"), "ddfs", 0.4, "locked", ConstantSpeed(0.0))
    names, P = packed_vector(out.output)
    assert names == model.parameter_names
    np.testing.assert_array_equal(P, model.P)
    text = runner.invoke(app, ["params", "slots", "--drive", "ddfs"]).output.splitlines()
    shown = [ln.split()[0] for ln in text]
    assert shown == [n for n in model.parameter_names if not n.startswith("profile[")]
    assert "table.mass" in shown and text[shown.index("table.mass")].endswith("[kg]")
    # the help lists the registered drives
    assert params_cmd.ALL_DRIVES == "|".join(registry.names(registry.MECHANISMS))


def test_the_reproduction_report_writes_the_models_slots():
    from feeddrive.reproduce.report import parameter_slot_rows
    from feeddrive.reproduce.studies import MID

    params = fd.preset("wang2021")
    rows = parameter_slot_rows(params)
    for drive in ("cdfs", "ddfs"):
        model = DriveSystem(params, drive, MID).model(ConstantSpeed(0.0))
        mine = [r for r in rows if r["drive"] == drive]
        keep = [i for i, n in enumerate(model.parameter_names) if not n.startswith("profile[")]
        assert [r["slot"] for r in mine] == [model.parameter_names[i] for i in keep]
        np.testing.assert_array_equal([float(r["value"]) for r in mine], model.P[keep])
        assert all(r["unit"] for r in mine)
