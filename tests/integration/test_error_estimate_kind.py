"""Each signal's integration-error attributes say which estimate they hold (an outside check,
2026-12-06: the shadow's and the embedded estimate's attributes read the same, though their
measured ratios to the true error are 0.5–1.5 (a run's shadow, ``RUN_RATIO``) and 0.15–200 000;
only the dataset's ``solver`` string told them apart)."""

from __future__ import annotations

from pathlib import Path

import pytest
import xarray as xr

import feeddrive as fd
from feeddrive.engine.error_estimate import RUN_RATIO
from feeddrive.solvers.global_error import MEASURED_RATIO


@pytest.mark.parametrize(("asked", "kind", "ratio"), [
    (True, "shadow", RUN_RATIO), ("embedded", "embedded", MEASURED_RATIO)])
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


def test_the_second_run_of_an_estimate_reports_progress_under_its_own_label() -> None:
    """``simulate --error-estimate``'s bar sat at 100 % while the second, tighter run worked
    (an outside check, 2026-12-06): ``simulate`` reports the second run's progress too, and
    the CLI's bar starts again under the label it was given when the time goes back."""
    from feeddrive.cli._common import progress_bar

    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    seen: list[float] = []
    fd.simulate(system, fd.ConstantSpeed(2e-3), 25.0, error_estimate=True,
                progress=lambda t, _: seen.append(t))
    back = [k for k in range(1, len(seen)) if seen[k] < seen[k - 1]]
    assert len(back) == 1 and seen[back[0] - 1] == pytest.approx(25.0), seen
    assert seen[-1] == pytest.approx(25.0)
    bar, advance = progress_bar(25.0, again="error estimate: the run 10× tighter")
    try:
        for t in seen:
            advance(t, 25.0)
        task = bar.tasks[0]
        assert task.description == "error estimate: the run 10× tighter"
        assert task.completed == pytest.approx(25.0)
    finally:
        bar.stop()
    bar, advance = progress_bar(25.0)  # no second pass expected: the label stays
    try:
        for t in seen:
            advance(t, 25.0)
        assert bar.tasks[0].description == "simulating"
    finally:
        bar.stop()
