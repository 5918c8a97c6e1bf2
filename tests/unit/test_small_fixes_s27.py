"""Three small fixes (session 27).

1. A machine run recorded ``parameters_toml`` of its first axis alone: a saved XY run (.nc,
   .mat, .parquet) lost the y axis' parameter set.  Each axis' set is now
   ``<axis>_parameters_toml`` (as ``<axis>_table_start_position_m``), read back by
   ``Result.axis_parameter_sets`` / ``feeddrive.engine.machine_axes.axis_parameter_sets``.
2. ``feeddrive analyze`` of a simulated constant-speed run said "1 runs of constant command
   speed (99 shorter than 1 s skipped)": the 99 were the samples of the command's 0.1-s ramp
   at 1 kHz, one run each.  It now says where the command keeps changing, counts only holds
   a user finds in the record, with their duration and ``--min-segment``.
3. The creep protocol line said "in 0.2-mm/s steps" when the grid (which now ends at
   ``--high``) ends on a shorter step.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd
import pytest
import scipy.io
import xarray as xr

import feeddrive as fd
from feeddrive.engine.machine_axes import axis_parameter_sets
from feeddrive.engine.result import Result
from feeddrive.machine import machine_from_dict, make_contour, simulate_machine

# ------------------------------------------------------------------ 1. every axis' parameters

#: the built-in XY table with a y axis of its own (a heavier table): the two sets differ
XY = {"name": "xy", "extends": "xy-table", "axes": {"y": {"table": {"mass": 123.0}}}}


@pytest.fixture(scope="module")
def xy_run() -> Any:
    machine = machine_from_dict(XY)
    path = make_contour("line", feed=0.01, acceleration=1.0, length=0.001)  # 0.1 s
    return machine, simulate_machine(machine, path)


def _given(machine: Any) -> dict[str, fd.DriveParameters]:
    return {ax.name: ax.parameters for ax in machine.axes}


def test_the_xy_axes_have_different_sets() -> None:
    sets = _given(machine_from_dict(XY))
    assert sets["x"] != sets["y"] and sets["y"].table.mass == 123.0


def test_a_machine_run_records_each_axis_parameter_set(xy_run: Any) -> None:
    machine, run = xy_run
    attrs = run.dataset.attrs
    assert "parameters_toml" not in attrs  # a machine has no one set (as no one start)
    for name, params in _given(machine).items():
        assert fd.parameters.loads(attrs[f"{name}_parameters_toml"]) == params
    assert run.axis_parameter_sets == _given(machine)


@pytest.mark.parametrize("ext", ["nc", "mat", "parquet"])
def test_a_saved_machine_run_reads_back_every_axis_set(xy_run: Any, tmp_path: Path,
                                                        ext: str) -> None:
    if ext == "parquet":
        pytest.importorskip("pyarrow")
    machine, run = xy_run
    path = run.save(tmp_path / f"xy.{ext}")
    if ext == "nc":
        with xr.open_dataset(path) as ds:
            back = Result(ds).axis_parameter_sets
    elif ext == "mat":
        mat = scipy.io.loadmat(path, simplify_cells=True)["feeddrive"]
        back = axis_parameter_sets(mat["attrs"])
    else:
        back = axis_parameter_sets(pd.read_parquet(path).attrs)
    assert list(back) == ["x", "y"]
    assert back == _given(machine)


def test_one_drives_run_keeps_its_one_set(tmp_path: Path) -> None:
    params = fd.preset("wang2021")
    run = fd.simulate(fd.DriveSystem(params, "cdfs", 0.4), fd.ConstantSpeed(1e-3), 0.02)
    attrs = run.dataset.attrs
    assert fd.parameters.loads(attrs["parameters_toml"]) == params
    assert not [k for k in attrs if k.endswith("_parameters_toml")]
    assert run.axis_parameter_sets == {}
    with xr.open_dataset(run.save(tmp_path / "one.nc")) as ds:
        assert fd.parameters.loads(ds.attrs["parameters_toml"]) == params
        assert Result(ds).axis_parameter_sets == {}
