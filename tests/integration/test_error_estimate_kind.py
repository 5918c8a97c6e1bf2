"""Each signal's integration-error attributes say which estimate they hold (an outside check,
2026-12-06: the shadow's and the embedded estimate's attributes read the same, though their
measured ratios to the true error are 0.8–1.2 and 0.15–200 000; only the dataset's ``solver``
string told them apart)."""

from __future__ import annotations

from pathlib import Path

import pytest
import xarray as xr

import feeddrive as fd
from feeddrive.engine.error_estimate import SHADOW_RATIO
from feeddrive.solvers.global_error import MEASURED_RATIO


@pytest.mark.parametrize(("asked", "kind", "ratio"), [
    (True, "shadow", SHADOW_RATIO), ("embedded", "embedded", MEASURED_RATIO)])
def test_the_attributes_name_the_estimate_and_its_measured_range(
        asked: bool | str, kind: str, ratio: tuple[float, float], tmp_path: Path) -> None:
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    result = fd.simulate(system, fd.ConstantSpeed(2e-3), 1.0, error_estimate=asked)
    entry = result.solver_stats["error_estimate"]
    assert entry["kind"] == kind and entry["ratio_to_true_error"] == list(ratio)
    attrs = result.dataset["table_speed"].attrs
    assert attrs["integration_error_estimate_kind"] == kind
    assert list(attrs["integration_error_estimate_ratio_to_true_error"]) == list(ratio)
    assert attrs["integration_error_estimate"] == \
        entry["signals"]["table_speed"]["absolute"]
    path = tmp_path / "run.nc"
    result.save(path)
    with xr.open_dataset(path) as saved:
        back = saved["table_speed"].attrs
        assert back["integration_error_estimate_kind"] == kind
        assert list(back["integration_error_estimate_ratio_to_true_error"]) == list(ratio)


def test_simulate_states_the_measured_ranges_of_the_code() -> None:
    from feeddrive.engine.error_estimate import ratio_text

    doc = " ".join(fd.simulate.__doc__.split())
    assert f"{ratio_text(MEASURED_RATIO)} × the true error where measured" in doc


def test_each_signals_estimate_states_its_unit() -> None:
    """``simulate --json`` gave the absolute errors in SI without a unit (an outside check,
    2026-12-06: ``table_speed.absolute = 1.07e-08`` beside a text in mm/s)."""
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    result = fd.simulate(system, fd.ConstantSpeed(2e-3), 1.0, error_estimate=True)
    signals = result.solver_stats["error_estimate"]["signals"]
    for name in ("table_speed", "table_position", "screw_current"):
        assert signals[name]["unit"] == result.dataset[name].attrs["units"], name
    assert signals["table_speed"]["unit"] == "m/s" and signals["table_position"]["unit"] == "m"
