"""A machine's exports (an outside check, 2026-12-07): its NetCDF variables had dotted names
(``x.screw_angle``: 66 CF-checker warnings, docs/outputs.md promises plain names); its CSV
comment and attributes gave the first axis' start position alone and the machine's name as
drive and parameter set; a ``.mat`` past the MATLAB 5 format's 4 GiB ended the run with
scipy's traceback (``MatWriteError``), the run lost."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
import scipy.io
import xarray as xr
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.cli import app
from feeddrive.io import results
from feeddrive.machine import machine_from_dict, make_contour, simulate_machine
from feeddrive.parameters import ParameterError

runner = CliRunner()

#: the audit's m2.toml: the XY table with its own start positions
M2 = {"name": "m2", "extends": "xy-table",
      "axes": {"x": {"table_position": 0.2}, "y": {"table_position": 0.55}}}
M2_TOML = ('name = "m2"\nextends = "xy-table"\n[axes.x]\ntable_position = 0.2\n'
           '[axes.y]\ntable_position = 0.55\n')
CF_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


@pytest.fixture(scope="module")
def m2_run() -> Any:
    machine = machine_from_dict(M2)
    path = make_contour("line", feed=0.01, acceleration=1.0, length=0.001)
    return simulate_machine(machine, path)


def test_a_machine_nc_has_cf_names_each_keeping_its_signal_name(m2_run: Any,
                                                                tmp_path: Path) -> None:
    out = m2_run.save(tmp_path / "m2.nc")
    with xr.open_dataset(out) as ds:
        names = [str(n) for n in [*ds.coords, *ds.data_vars]]
        assert all(CF_NAME.match(n) for n in names), [n for n in names if not CF_NAME.match(n)]
        assert ds["x_table_position"].attrs["signal"] == "x.table_position"
        assert ds["x_table_position"].attrs["units"] == "m"
        assert "signal" not in ds["contour_error"].attrs  # a plain name stays as it was
        # round trip: every signal back under its own name, the same numbers
        back = ds.rename({n: ds[n].attrs["signal"] for n in ds.data_vars
                          if "signal" in ds[n].attrs})
        assert sorted(map(str, back.data_vars)) == sorted(map(str, m2_run.dataset.data_vars))
        np.testing.assert_array_equal(back["y.table_position"].to_numpy(),
                                      m2_run["y.table_position"])
    assert "x.table_position" in m2_run.dataset  # the run's own names are unchanged


def test_plain_names_refuses_two_names_made_one() -> None:
    ds = xr.Dataset({"x.a_b": ("time", [0.0]), "x_a.b": ("time", [1.0])})
    with pytest.raises(ParameterError, match=r"^output = 'x_a_b': two variables would share"):
        results.plain_names(ds, "signal")


def test_a_machine_runs_attributes_give_each_axis_start_and_the_machines_name(
        m2_run: Any, tmp_path: Path) -> None:
    attrs = m2_run.attrs
    assert attrs["machine"] == "m2"
    assert attrs["drive"] == "cdfs" and attrs["parameter_set"] == "wang2021"
    assert "table_start_position_m" not in attrs  # a machine has no one start position
    assert attrs["x_table_start_position_m"] == 0.2
    assert attrs["y_table_start_position_m"] == 0.55
    with xr.open_dataset(m2_run.save(tmp_path / "m2.nc")) as ds:
        assert isinstance(ds.attrs["y_table_start_position_m"], float | np.floating)
        assert ds.attrs["y_table_start_position_m"] == 0.55
        assert ds.attrs["machine"] == "m2" and ds.attrs["drive"] == "cdfs"
        assert ds.attrs["title"] == ("feeddrive simulation: machine m2, cdfs drive, "
                                     "parameter set wang2021")


def test_a_machine_csv_comment_gives_each_axis_start_position(m2_run: Any,
                                                              tmp_path: Path) -> None:
    first = (m2_run.save(tmp_path / "m2.csv")).read_text(encoding="utf-8").splitlines()[0]
    assert re.match(r"^# feeddrive \S+: machine m2, axis x \(drive cdfs, table start position "
                    r"0\.2 m, parameter set wang2021\), axis y \(drive cdfs, table start "
                    r"position 0\.55 m, parameter set wang2021\), profile Line\(", first), first


def test_a_machine_parquet_names_the_machine_and_its_axes(m2_run: Any, tmp_path: Path) -> None:
    pytest.importorskip("pyarrow")
    frame = pd.read_parquet(m2_run.save(tmp_path / "m2.parquet"))
    assert frame.attrs["machine"] == "m2" and frame.attrs["drive"] == "cdfs"
    assert frame.attrs["axes"]["y"]["table_start_position_m"] == 0.55


def test_a_mixed_machine_names_each_drive_once() -> None:
    machine = machine_from_dict({"name": "mix", "axes": {
        "x": {"extends": "wang2021", "drive": "cdfs"},
        "y": {"drive": "linear-motor"}}})
    attrs = fd.machine.MachineSystem(machine).run_attrs(
        make_contour("line", feed=0.01, acceleration=1.0, length=0.001))
    assert attrs["drive"] == "cdfs, linear-motor"
    assert attrs["parameter_set"] == "wang2021, linear-motor-example"
    assert attrs["machine"] == "mix" and attrs["table_start_position_m"] is None


# ------------------------------------------------------------------ .mat past its format

def test_mat_bytes_counts_the_struct_scipy_writes(tmp_path: Path) -> None:
    """The signals' bytes of :func:`mat_bytes` are what scipy writes for them: the file holds
    them plus its header and the field names only."""
    samples, signals = 1000, 5
    data = {f"s{k}": np.zeros(samples) for k in range(signals + 1)}
    scipy.io.savemat(tmp_path / "s.mat", {"feeddrive": data}, long_field_names=True,
                     do_compression=False, oned_as="column")
    size = (tmp_path / "s.mat").stat().st_size
    need = results.mat_bytes(samples, signals)
    assert need <= size < need + 128 + 8 + 64 + 64 * (signals + 1)


def test_a_cdfs_run_at_1_ms_fits_a_mat_up_to_about_15800_s() -> None:
    signals = 33  # a CDFS run's Dataset variables besides time (checked below)
    results.check_mat_output("run.mat", duration=15_790.0, output_interval=1e-3,
                             signals=signals)
    with pytest.raises(ParameterError, match=r"^--duration = 15800(\.0)?: a \.mat --output "
                                             r"\(run\.mat\) .* past the MATLAB 5 format's 4 "
                                             r"GiB .*expected ≤ 15790\.\d+ \[s\]"):
        results.check_mat_output("run.mat", duration=15_800.0, output_interval=1e-3,
                                 signals=signals)
    results.check_mat_output("run.nc", duration=1e6, output_interval=1e-3, signals=signals)


def test_recorded_signals_are_the_runs_dataset_variables(m2_run: Any) -> None:
    from feeddrive.cli.machine_run import recorded_machine_signals
    from feeddrive.engine.result import recorded_signals

    machine = machine_from_dict(M2)
    path = make_contour("line", feed=0.01, acceleration=1.0, length=0.001)
    assert recorded_machine_signals(machine, path) == list(map(str, m2_run.dataset.data_vars))
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    profile = fd.ConstantSpeed(1e-3)
    run = fd.simulate(system, profile, 0.01)
    names = recorded_signals(system.model(profile), system, profile)
    assert names == list(map(str, run.dataset.data_vars)) and len(names) == 33


@pytest.fixture
def no_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """Any simulation fails the test: a refusal comes before the run."""
    from feeddrive.engine import simulate as engine

    def fail(*args: Any, **kw: Any) -> Any:
        raise AssertionError("the run started")

    monkeypatch.setattr(engine, "simulate", fail)
    monkeypatch.setattr("feeddrive.machine.simulate_machine", fail)


def _one_error(result: Any) -> str:
    assert result.exception is None or isinstance(result.exception, SystemExit), \
        repr(result.exception)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    return str(lines[0])


@pytest.mark.parametrize("args", [
    ["--table-speed", "1", "--duration", "1"],
    ["--machine", "m2.toml", "--contour", "line", "--length", "1", "--feed", "600"]])
def test_a_mat_output_past_the_limit_is_refused_before_the_run(
        args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        no_run: None) -> None:
    monkeypatch.setattr(results, "MAT5_LIMIT", 10_000)  # these runs: ≈ 270 kB, 60 kB
    monkeypatch.chdir(tmp_path)
    (tmp_path / "m2.toml").write_text(M2_TOML)
    r = runner.invoke(app, ["simulate", *args, "--output", "run.mat"])
    line = _one_error(r)
    assert r.exit_code == 2
    assert re.match(r"^error: --duration = [\d.]+: a \.mat --output \(run\.mat\) would hold "
                    r".* past the MATLAB 5 format's .* expected ≤ [\d.e+-]+ \[s\] at the "
                    r"output interval", line), line
    assert not list(tmp_path.glob("*run*"))


@pytest.fixture
def mat_too_large(monkeypatch: pytest.MonkeyPatch) -> None:
    """scipy's writer fails as it does past 4 GiB (the audit's big.py)."""
    import scipy.io.matlab._mio5 as mio5
    from scipy.io.matlab import MatWriteError

    def too_large(self: Any, start_pos: int) -> None:
        raise MatWriteError("Matrix too large to save with Matlab 5 format")

    monkeypatch.setattr(mio5.VarWriter5, "update_matrix_tag", too_large)


def test_a_mat_writer_failure_after_the_run_is_one_line_after_the_summary(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, mat_too_large: None) -> None:
    monkeypatch.chdir(tmp_path)
    r = runner.invoke(app, ["simulate", "--table-speed", "1", "--duration", "0.2",
                            "--output", "big.mat", "--plot", "big.png"])
    line = _one_error(r)
    assert r.exit_code == 1
    assert re.match(r"^error: big\.mat: the run's \d+ samples of 34 columns .* past the "
                    r"MATLAB 5 format's 4 GiB per variable .*\[s\].*; not written \(the run "
                    r"finished: its summary is printed\)$", line), line
    assert "verdict" in r.stdout and "wrote big.png" in r.stdout  # the run is not lost
    assert not (tmp_path / "big.mat").exists() and not list(tmp_path.glob(".*partial*"))


def test_a_machine_mat_writer_failure_keeps_the_summary(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, mat_too_large: None) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "m2.toml").write_text(M2_TOML)
    r = runner.invoke(app, ["simulate", "--machine", "m2.toml", "--contour", "line",
                            "--length", "1", "--feed", "600", "--json", "--output", "m2.mat"])
    line = _one_error(r)
    assert r.exit_code == 1 and line.startswith("error: m2.mat: the run's ")
    assert "not written" in line
    assert json.loads(r.stdout)["axes"]["y"]["drive"] == "cdfs"
    assert not (tmp_path / "m2.mat").exists()


def test_result_save_past_the_mat_limit_is_a_parameter_error(
        m2_run: Any, tmp_path: Path, mat_too_large: None) -> None:
    with pytest.raises(ParameterError, match=r"^output = '.*m2\.mat': the run's \d+ samples .* "
                                             r"MATLAB 5 .*\[s\]"):
        m2_run.save(tmp_path / "m2.mat")
    assert not list(tmp_path.iterdir())
