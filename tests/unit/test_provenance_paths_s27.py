"""One run's provenance on every path it is written by (session 27, an outside look).

What says where a run's numbers come from — feeddrive's version, the drive (a machine: its
name and axes), the start position, the parameter set's name and its values as TOML
(``parameters_toml``; a machine's ``<axis>_parameters_toml``), the profile, the friction laws
and the solver record — is the same on every path (docs/outputs.md): a whole-run CSV's first
and last ``#`` lines, a Parquet file's ``df.attrs``, NetCDF's global attributes, a ``.mat``
file's ``feeddrive.attrs``, a streamed CSV or Parquet file (written chunk by chunk during the
run: ``simulate --output``, ``simulate(..., output=)``) and ``Result.to_pandas()``.  The CSV
carries its comment line's part (no TOML).  Gaps found, each a test below:

1. a streamed Parquet file had no parameter sets, a streamed CSV's first line no solver;
2. ``Result.attrs`` left the parameter TOML out until ``.dataset`` was built, and
   ``to_pandas()`` carried no parameter set values at all;
3. a machine run's ``parameter_slots`` had no unit for any axis slot
   (``['x.table.mass', 20.0, '']``);

and a ``.mat`` file did not name the feeddrive version.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
import scipy.io
import xarray as xr
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.cli import app
from feeddrive.engine.result import Result
from feeddrive.io.results import add_solver_record
from feeddrive.machine import MachineProfile, MachineSystem, machine_from_dict, make_contour

pytest.importorskip("pyarrow")

#: the provenance of one drive's run, on every path but the CSV (docs/outputs.md)
DRIVE_KEYS = {"feeddrive_version", "drive", "table_start_position_m", "parameter_set",
              "parameters_toml", "profile", "friction_laws", "solver"}
#: a machine's: its name and axes (each one's drive, set and start) instead of one start
MACHINE_KEYS = {"feeddrive_version", "machine", "drive", "parameter_set", "x_parameters_toml",
                "y_parameters_toml", "profile", "axes", "friction_laws", "solver"}
#: attributes a file holds as JSON text
JSON_KEYS = ("axes", "friction_laws", "solver")
#: what two runs of one setting may differ in: timing, and the output evaluations a
#: streamed run makes per chunk (tests/integration/test_s19_outputs.py)
RUN_DEPENDENT = {"wall_time_s", "rhs_evaluations", "output_rhs_evaluations"}

#: the paths every run is written by, compared with its own record (``Result.attrs``, the
#: record itself, has no version: test_in_memory_attrs_do_not_depend_on_the_dataset_being_built)
PATHS = ("to_pandas untouched", "to_pandas after .dataset", "parquet", "streamed parquet",
         "nc", "mat")

runner = CliRunner()


def _provenance(attrs: Any, keys: set[str]) -> dict[str, Any]:
    """The provenance among ``attrs`` as plain values (JSON text parsed, numbers from
    text), the solver record less what differs between two runs."""
    out: dict[str, Any] = {}
    for key in sorted(keys):
        if key in attrs:
            value = attrs[key]
            if key in JSON_KEYS and isinstance(value, str):
                value = json.loads(value)
            if key == "table_start_position_m":
                value = float(value)
            out[key] = value
    out["solver"] = {k: v for k, v in out.get("solver", {}).items() if k not in RUN_DEPENDENT}
    return out


def _record(run: Result, keys: set[str]) -> dict[str, Any]:
    """The run's own record (its dataset's attributes) and the version that made it."""
    return _provenance({**run.dataset.attrs, "feeddrive_version": fd.__version__}, keys)


def _written(run: Result, folder: Path, name: str) -> dict[str, Any]:
    """Each path's attributes of ``run``, and its CSV lines: in-memory ones first (before
    ``.dataset`` is built), then the files."""
    out: dict[str, Any] = {"Result.attrs untouched": run.attrs,
                           "to_pandas untouched": run.to_pandas().attrs}
    assert run._dataset is None  # nothing above built it
    out["dataset"] = dict(run.dataset.attrs)
    out["to_pandas after .dataset"] = run.to_pandas().attrs
    for ext in ("csv", "parquet", "nc", "mat"):
        run.save(folder / f"{name}.{ext}")
    out["parquet"] = pd.read_parquet(folder / f"{name}.parquet").attrs
    with xr.open_dataset(folder / f"{name}.nc") as ds:
        source = re.fullmatch(r"feeddrive (\S+)", ds.attrs["source"])
        assert source is not None, ds.attrs["source"]
        out["nc"] = {**ds.attrs, "feeddrive_version": source.group(1)}
        out["nc slots"] = Result(ds.load()).parameter_slots
    out["mat"] = scipy.io.loadmat(folder / f"{name}.mat", simplify_cells=True)[
        "feeddrive"]["attrs"]
    out["csv"] = (folder / f"{name}.csv").read_text(encoding="utf-8").splitlines()
    out["streamed parquet"] = pd.read_parquet(folder / f"{name}_s.parquet").attrs
    out["streamed csv"] = (folder / f"{name}_s.csv").read_text(encoding="utf-8").splitlines()
    return out


@pytest.fixture(scope="module")
def drive(tmp_path_factory: pytest.TempPathFactory) -> tuple[Result, dict[str, Any]]:
    """One drive's 0.1-s run in memory, saved whole, and streamed by the command line."""
    folder = tmp_path_factory.mktemp("drive")
    for ext in ("csv", "parquet"):  # .csv and .parquet are written as the run goes
        done = runner.invoke(app, ["simulate", "--table-speed", "2", "--duration", "0.1",
                                   "--output", str(folder / f"cdfs_s.{ext}")])
        assert done.exit_code == 0, done.output
    run = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4),
                      fd.ConstantSpeed(2e-3), 0.1)  # the command line's run, in Python
    return run, _written(run, folder, "cdfs")


def _machine_run(output: Path | None = None) -> Result:
    machine = machine_from_dict({"name": "xy", "extends": "xy-table"})
    path = make_contour("line", feed=0.01, acceleration=1.0, length=0.001)  # 0.11 s
    profile = MachineProfile.from_contour(path, machine, None)
    run: Result = fd.simulate(MachineSystem(machine), profile, 0.1, output=output)
    return run


@pytest.fixture(scope="module")
def machine(tmp_path_factory: pytest.TempPathFactory) -> tuple[Result, dict[str, Any]]:
    """The built-in XY table's 0.1-s run in memory, saved whole, and streamed in Python (the
    command line writes a machine's run whole)."""
    folder = tmp_path_factory.mktemp("machine")
    for ext in ("csv", "parquet"):
        out = folder / f"xy_s.{ext}"
        add_solver_record(out, _machine_run(out).solver_stats)
    run = _machine_run()
    return run, _written(run, folder, "xy")


@pytest.mark.parametrize("path", PATHS)
def test_a_drives_run_carries_one_provenance_on_every_path(
        drive: tuple[Result, dict[str, Any]], path: str) -> None:
    run, written = drive
    expected = _record(run, DRIVE_KEYS)
    assert set(expected) == DRIVE_KEYS
    assert fd.parameters.loads(expected["parameters_toml"]) == fd.preset("wang2021")
    assert _provenance(written[path], DRIVE_KEYS) == expected


@pytest.mark.parametrize("path", PATHS)
def test_a_machines_run_carries_one_provenance_on_every_path(
        machine: tuple[Result, dict[str, Any]], path: str) -> None:
    run, written = machine
    expected = _record(run, MACHINE_KEYS)
    assert set(expected) == MACHINE_KEYS
    for axis in ("x", "y"):  # the xy-table's axes: wang2021 each (feeddrive.machine)
        assert fd.parameters.loads(expected[f"{axis}_parameters_toml"]) == fd.preset("wang2021")
    assert _provenance(written[path], MACHINE_KEYS) == expected


@pytest.mark.parametrize("kind", ["drive", "machine"])
def test_in_memory_attrs_do_not_depend_on_the_dataset_being_built(
        kind: str, request: pytest.FixtureRequest) -> None:
    _, written = request.getfixturevalue(kind)
    assert written["Result.attrs untouched"] == written["dataset"]
    assert written["to_pandas untouched"] == written["to_pandas after .dataset"]


@pytest.mark.parametrize("kind", ["drive", "machine"])
def test_a_streamed_csv_says_what_the_whole_runs_csv_says(
        kind: str, request: pytest.FixtureRequest) -> None:
    run, written = request.getfixturevalue(kind)
    whole, streamed = written["csv"], written["streamed csv"]
    assert streamed[0] == whole[0]  # the first line: what wrote the file, its solver named
    assert f", solver {run.solver_stats['method']};" in whole[0]
    assert "parameter set wang2021" in whole[0]
    records = [json.loads(lines[-1].removeprefix("# solver: ")) for lines in (whole, streamed)]
    keys = DRIVE_KEYS if kind == "drive" else MACHINE_KEYS
    assert [_provenance({"solver": r}, keys)["solver"] for r in records] == \
        [_record(run, keys)["solver"]] * 2


def test_a_machine_runs_axis_slots_have_their_drives_units(
        machine: tuple[Result, dict[str, Any]]) -> None:
    run, written = machine
    one = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4),
                      fd.ConstantSpeed(2e-3), 0.01)  # the axes' drive and set, alone
    units = {name: unit for name, _, unit in one.parameter_slots}
    rows = run.parameter_slots
    assert ("x.table.mass", fd.preset("wang2021").table.mass, "kg") in rows
    for axis in ("x", "y"):
        mine = {name.removeprefix(f"{axis}."): unit for name, _, unit in rows
                if name.startswith(f"{axis}.")}
        assert mine == units  # every slot, the profile's block ("") included
    assert written["nc slots"] == rows  # and as a file records them
