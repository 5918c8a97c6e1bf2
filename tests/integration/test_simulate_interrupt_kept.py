"""An interrupted `simulate --output X.mat|X.nc` keeps the run so far, as `.csv` and `.parquet`
(written as the run goes) do: it wrote nothing (an outside check, 2026-12-07).  The run's
Ctrl-C is stood in for by the engine's own exception, raised with a real partial run."""

from __future__ import annotations

from pathlib import Path

import pytest
import scipy.io
import xarray as xr
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.cli import app
from feeddrive.engine import simulate as engine


@pytest.mark.parametrize("suffix", [".mat", ".nc"])
def test_the_run_so_far_is_written(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                   suffix: str) -> None:
    partial = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4),
                          fd.ConstantSpeed(1e-3), 0.25)

    def interrupted(*args: object, **kwargs: object) -> None:
        raise engine.SimulationInterrupted(0.25, partial, None)

    monkeypatch.setattr(engine, "simulate", interrupted)
    out = tmp_path / f"run{suffix}"
    result = CliRunner().invoke(app, ["simulate", "--drive", "cdfs", "--table-speed", "1",
                                      "--duration", "10", "--output", str(out)])
    assert result.exit_code == 130, result.output
    assert f"writing the run so far to {out}" in result.output
    assert f"{out} holds 0 … 0.25 s" in result.output
    if suffix == ".mat":
        time = scipy.io.loadmat(out)["feeddrive"]["time"][0, 0].ravel()
    else:
        with xr.open_dataset(out) as ds:
            time = ds["time"].values
    assert time[-1] == pytest.approx(0.25) and time.size == partial.time.size


def test_nothing_is_written_without_an_output(tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    def interrupted(*args: object, **kwargs: object) -> None:
        raise engine.SimulationInterrupted(0.25, None, None)

    monkeypatch.setattr(engine, "simulate", interrupted)
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(app, ["simulate", "--drive", "cdfs", "--table-speed", "1",
                                      "--output", "run.mat"])
    assert result.exit_code == 130 and not (tmp_path / "run.mat").exists()


def test_a_streamed_runs_summary_says_which_part_it_judged(tmp_path: Path) -> None:
    """A streamed run keeps its last KEEP_STREAMED seconds for the summary: its window and
    numbers differ from the same run's without --output (300 s at 0.3 mm/s: 244–300 s against
    60–300 s), which was not said (an outside check, 2026-12-07)."""
    from feeddrive.engine.simulate import KEEP_STREAMED

    out = tmp_path / "run.csv"
    args = ["simulate", "--drive", "cdfs", "--table-speed", "2", "--duration",
            str(KEEP_STREAMED + 20)]
    streamed = CliRunner().invoke(app, [*args, "--output", str(out)])
    assert streamed.exit_code == 0, streamed.output
    assert (f"within the last {KEEP_STREAMED:g} s a streamed --output keeps in memory"
            in streamed.output)
    assert f"feeddrive analyze {out}" in streamed.output
    plain = CliRunner().invoke(app, args)
    assert "a streamed --output keeps" not in plain.output
