"""Sweep exports (an outside audit, 2026-12-07): a parameter axis named by its dotted path
carries the unit its declaration states (it had none in the CSV and unit '1' in .nc and
.parquet: a speed labelled dimensionless), and a loop without a gain margin (no phase
crossover) is +inf (``inf`` in the CSV), told apart from a point not computed (NaN)."""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq
import pytest
import xarray as xr

from feeddrive.sweep import SweepStore, export
from feeddrive.sweep.design import parse_config
from feeddrive.sweep.executors import description
from feeddrive.sweep.quantities import evaluate

STRIBECK = "friction.screw.positive.stribeck_velocity"
GM_VELOCITY = "screw_velocity_loop_gain_margin_db"
GM_POSITION = "screw_position_loop_gain_margin_db"

CONFIG: dict[str, Any] = {
    "name": "swc", "drive": "cdfs", "table_position": 300,
    "quantity": {"kind": "loop-margins", "table_speed": 1.0},
    "axes": {STRIBECK: [0.0005, 0.001, 0.002],
             "friction.screw": {"values": [1.1], "relative": True}}}


@pytest.fixture(scope="module")
def exported(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The audit's sweep, its first two points computed, the third not: .nc, .csv, .parquet."""
    folder = tmp_path_factory.mktemp("sw")
    config = parse_config(CONFIG, str(folder / "sw.toml"))
    points = list(config.iter_points())
    store = SweepStore(folder / "sw.sqlite")
    store.register(config.name, description(config), ((p.index, p.key, p.coords)
                                                     for p in points))
    for p in points[:2]:
        store.put(p.key, evaluate(p.task))
    for ext in (".nc", ".csv", ".parquet"):
        export(store, config.name, folder / f"sw{ext}")
    store.close()
    return folder


def test_nc_parameter_axis_in_its_si_unit(exported: Path) -> None:
    with xr.open_dataset(exported / "sw.nc") as ds:
        axis = ds["friction_screw_positive_stribeck_velocity"]
        assert axis.attrs["units"] == "m/s" and axis.attrs["parameter"] == STRIBECK
        assert axis.values.tolist() == [0.0005, 0.001, 0.002]
        assert ds["friction_screw"].attrs["units"] == "1"  # a relative axis: a factor


def test_csv_parameter_axis_in_engineering_units(exported: Path) -> None:
    with open(exported / "sw.csv", newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert f"{STRIBECK} [mm/s]" in rows[0] and "friction.screw [factor]" in rows[0]
    assert [float(r[f"{STRIBECK} [mm/s]"]) for r in rows] == [0.5, 1.0, 2.0]
    assert "table_position [mm]" not in rows[0]  # not an axis here


def test_parquet_parameter_axis_unit_in_metadata(exported: Path) -> None:
    table = pq.read_table(exported / "sw.parquet")
    units = {f.name: f.metadata[b"unit"].decode() for f in table.schema}
    assert units[STRIBECK] == "mm/s" and units["friction.screw"] == "1"
    assert table[STRIBECK].to_pylist() == [0.5, 1.0, 2.0]  # the CSV's numbers


def test_no_gain_margin_is_infinite_not_missing(exported: Path) -> None:
    """The velocity loop's phase never crosses −180°: +inf; the third point is not computed:
    NaN; the position loop's margin stays the number it was."""
    with xr.open_dataset(exported / "sw.nc") as ds:
        gm = ds[GM_VELOCITY].squeeze().values
        assert np.isposinf(gm[:2]).all() and np.isnan(gm[2])
        assert ds["done"].squeeze().values.tolist() == [1, 1, 0]
        assert ds[GM_POSITION].squeeze().values[0] == pytest.approx(2.5895, abs=1e-4)
    table = pq.read_table(exported / "sw.parquet")
    got = table[GM_VELOCITY].to_pylist()
    assert got[:2] == [math.inf, math.inf] and math.isnan(got[2])
    with open(exported / "sw.csv", newline="", encoding="utf-8") as f:
        cells = [r[GM_VELOCITY] for r in csv.DictReader(f)]
    assert cells == ["inf", "inf", ""]


def test_infinite_margin_does_not_move_with_the_band() -> None:
    """+inf is a fact of the loop, not of loop_analysis's 0.5–500 Hz: no phase crossover up
    to 50 kHz either."""
    import feeddrive as fd
    from feeddrive.analysis.linear import loop_analysis
    from feeddrive.sweep.quantities import compute

    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.3)
    values = compute(system, 0.0, {"kind": "loop-margins", "table_speed": 1e-3})["values"]
    assert values[GM_VELOCITY] == math.inf
    assert math.isfinite(values[GM_POSITION])
    wide = loop_analysis(system, 1e-3, 0.0, f_min=0.01, f_max=5e4, points=2000)
    velocity = next(lp for lp in wide.loops if lp.name == "screw velocity loop")
    assert velocity.gain_margin_db is None


def test_axis_unit_follows_the_declaration_and_the_gain_basis() -> None:
    """A velocity gain per table speed is A s/m (wang2021), per motor speed A s/rad
    (wang2021-literal); a preset axis over both gives the axis no single unit."""
    def unit(extra: dict[str, Any]) -> str:
        data = {**CONFIG, **extra,
                "axes": {"controller.velocity_gain": [40, 50], **extra.get("axes", {})}}
        config = parse_config(data, "sw.toml")
        return next(a.unit for a in config.axes if a.name == "controller.velocity_gain")

    assert unit({}) == "A s/m"
    assert unit({"preset": "wang2021-literal"}) == "A s/rad"
    assert unit({"axes": {"preset": ["wang2021", "wang2021-literal"]}}) == ""
