"""Exports follow their conventions (issue 26 item 3, docs/outputs.md): a ``.nc`` from
``simulate`` and from a sweep is CF-1.8 by the CF checker (cfchecker with Debian's
UDUNITS-2) and by its attributes; Parquet has plain names with a unit in each field's
metadata; CSV keeps the bracketed names."""

from __future__ import annotations

import ctypes.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
import xarray as xr

import feeddrive as fd
from feeddrive.sweep import SweepStore, export

CF_TABLES = Path(__file__).resolve().parents[1] / "data" / "cf"
CFCHECKS = Path(sys.executable).with_name("cfchecks")

SWEEP = """
name = "cf"
drive = "cdfs"
[quantity]
kind = "loop-margins"
[axes]
table_position = [300, 500]
"friction.screw" = { values = [0.9, 1.1], relative = true }
"""


def _cf_check(path: Path) -> str:
    """The CF checker's report on ``path``; fails the test on any error or warning."""
    if not CFCHECKS.exists() or ctypes.util.find_library("udunits2") is None:
        pytest.skip("cfchecker or Debian's libudunits2-0 not installed (README test command)")
    out = subprocess.run([str(CFCHECKS), "-v", "1.8",
                          "-s", str(CF_TABLES / "cf-standard-name-table.xml"),
                          "-a", str(CF_TABLES / "area-type-table.xml"),
                          "-r", str(CF_TABLES / "standardized-region-list.xml"), str(path)],
                         capture_output=True, text=True, timeout=120)
    report = out.stdout + out.stderr
    assert "Checking against CF Version CF-1.8" in report, report
    assert "ERRORS detected: 0" in report and "WARNINGS given: 0" in report, report
    return report


@pytest.fixture(scope="module")
def run_nc(tmp_path_factory: pytest.TempPathFactory) -> Path:
    r = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "ddfs", 0.4),
                    fd.ConstantSpeed(1e-3, 16e-3), 0.2)
    return r.save(tmp_path_factory.mktemp("cf") / "run.nc")


def test_simulate_nc_passes_the_cf_checker(run_nc: Path) -> None:
    report = _cf_check(run_nc)
    assert "Checking variable: table_speed" in report  # the signals were read and checked


def test_cf_checker_catches_a_bad_unit(run_nc: Path, tmp_path: Path) -> None:
    """The check can fail: a unit UDUNITS does not know is reported."""
    with xr.open_dataset(run_nc) as ds:
        bad = ds.load()
    bad["table_speed"].attrs["units"] = "mm/s at the table"
    bad.to_netcdf(tmp_path / "bad.nc", engine="h5netcdf")
    with pytest.raises(AssertionError, match="ERRORS detected: [1-9]"):
        _cf_check(tmp_path / "bad.nc")


def test_simulate_nc_attributes(run_nc: Path) -> None:
    with xr.open_dataset(run_nc) as ds:
        assert ds.attrs["Conventions"] == "CF-1.8"
        assert ds.attrs["title"] == "feeddrive simulation: ddfs drive, parameter set wang2021"
        assert ds.attrs["history"].endswith(f"feeddrive {fd.__version__}: simulate")
        assert "conventions" not in ds.attrs and "torque ÷ H" in ds.attrs["comment"]
        units = {name: var.attrs["units"] for name, var in ds.variables.items()}
        assert units["time"] == "s" and units["table_position"] == "m"
        assert units["nut_speed"] == "rad/s" and "µ" not in "".join(units.values())


def test_sweep_exports(tmp_path: Path) -> None:
    cfg = tmp_path / "cf.toml"
    cfg.write_text(SWEEP)
    res = subprocess.run([sys.executable, "-m", "feeddrive", "sweep", str(cfg), "--workers",
                          "1", "--output", "cf.nc"], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    # the other formats from the same store, as `feeddrive map cf.sqlite --output …` writes
    store = SweepStore(tmp_path / "cf.sqlite")
    for out in ("cf.parquet", "cf.csv"):
        export(store, "cf", tmp_path / out)
    with xr.open_dataset(tmp_path / "cf.nc") as ds:
        assert ds.attrs["Conventions"] == "CF-1.8"
        assert ds.attrs["title"].startswith("feeddrive sweep cf: grid design")
        # the program, then the sweep's configuration file
        assert ds.attrs["source"].startswith(f"feeddrive {fd.__version__}; ")
        assert ds.attrs["source"].endswith("cf.toml")
        assert ds["table_position"].attrs["units"] == "m"
        assert ds["friction_screw"].attrs == {
            "units": "1", "long_name": "factor on the base value of friction.screw",
            "parameter": "friction.screw"}
    _cf_check(tmp_path / "cf.nc")
    table = pq.read_table(tmp_path / "cf.parquet")
    assert not [name for name in table.column_names if "[" in name]
    assert {"table_position", "friction.screw"} <= set(table.column_names)
    units = {f.name: f.metadata[b"unit"].decode() for f in table.schema}
    assert units["table_position"] == "mm" and units["friction.screw"] == "1"
    assert sorted(table["table_position"].to_pylist()) == [300.0, 300.0, 500.0, 500.0]
    header = (tmp_path / "cf.csv").read_text(encoding="utf-8").splitlines()[0]
    assert "table_position [mm]" in header and "friction.screw [factor]" in header


def test_outputs_doc_states_the_writers_conventions() -> None:
    """docs/outputs.md against feeddrive.io.results: the CF version, the time coordinate's long
    name, the engine and the Parquet metadata keys it names."""
    from feeddrive.io import results as io

    doc = (Path(__file__).resolve().parents[2] / "docs" / "outputs.md").read_text("utf-8")
    assert f'`Conventions = "{io.CF_CONVENTIONS}"`' in doc
    assert f'`long_name = "{io.TIME_LONG_NAME}"`' in doc
    assert f"`{io.NETCDF_ENGINE}` engine" in doc
    table = io.arrow_table({"x": (np.zeros(2), "mm", "a length")})
    assert set(table.schema.field("x").metadata) == {b"unit", b"long_name"}
    assert "`unit` (`mm`), `long_name`" in doc
