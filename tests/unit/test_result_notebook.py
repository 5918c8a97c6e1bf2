"""Issue 41 items 10 and 13: a Result in a notebook (``_repr_html_``, ``.plot()``,
``.to_pandas()``) and the provenance that travels with an export (Parquet ``df.attrs``, a
``#`` line at the top of a CSV that feeddrive's own readers skip)."""

from __future__ import annotations

import matplotlib
import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

import feeddrive as fd
from feeddrive.analysis.fit import read_experiment
from feeddrive.io.measured import read_position_trace

PARAMS = fd.preset("wang2021")


def _run(duration: float) -> fd.Result:
    return fd.simulate(fd.DriveSystem(PARAMS, "cdfs", 0.4), fd.ConstantSpeed(2e-3), duration)


@pytest.fixture(scope="module")
def run() -> fd.Result:
    return _run(0.5)


def test_repr_html_stays_small_whatever_the_run_length(run: fd.Result) -> None:
    """The notebook display shows the summary and the signal names, never the samples: a run
    20× longer gives a display of the same size (numbers differ, not rows)."""
    short, long = run._repr_html_(), _run(10.0)._repr_html_()
    assert _run(10.0).time.size > 19 * run.time.size
    assert len(short.encode()) <= 50_000 and len(long.encode()) <= 50_000
    assert abs(len(long) - len(short)) < 200
    assert "verdict" in long and "table_speed</code> [m/s]" in long
    assert "CDFS, constant 2 mm/s" in long and "10 s" in long
    assert repr(run).startswith("<feeddrive.Result CDFS, constant 2 mm/s")


def test_repr_html_of_a_staircase_counts_its_holds() -> None:
    profile, speeds = fd.model.reference.stepdown(2e-3, 1.98e-3, dwell=0.3, lead_in=0.3)
    r = fd.simulate(fd.DriveSystem(PARAMS, "cdfs", 0.4), profile, float(profile.time[-1]))
    assert f"holds</th><td style='text-align:left'>{speeds.size}, of which" in r._repr_html_()


def test_to_pandas_keeps_units_and_round_trips_through_parquet(run: fd.Result,
                                                                 tmp_path) -> None:
    df = run.to_pandas()
    assert df.index.name == "time" and np.array_equal(df.index.to_numpy(), run.time)
    assert np.array_equal(df["table_speed"].to_numpy(), run["table_speed"])
    assert df.attrs["units"]["table_speed"] == "m/s" and df.attrs["units"]["time"] == "s"
    assert df.attrs["units"]["screw_current"] == "A"
    assert set(df.columns) <= set(df.attrs["units"]) and set(df.columns) <= set(
        df.attrs["long_names"])
    assert df.attrs["drive"] == "cdfs" and df.attrs["parameter_set"] == "wang2021"
    assert df.attrs["feeddrive_version"] == fd.__version__
    assert df.attrs["solver"]["steps"] == run.solver_stats["steps"]
    df.to_parquet(tmp_path / "run.parquet")
    back = pd.read_parquet(tmp_path / "run.parquet")
    assert back.attrs == df.attrs
    pd.testing.assert_frame_equal(back, df)


def test_plot_returns_a_figure_without_pyplot(run: fd.Result, monkeypatch) -> None:
    import matplotlib.pyplot as plt

    backend = matplotlib.get_backend()  # resolves the backend (through pyplot) first

    def refuse(*args, **kwargs):  # type: ignore[no-untyped-def]
        raise AssertionError("pyplot was called")

    for name in ("figure", "subplots", "gcf", "gca", "switch_backend", "close"):
        monkeypatch.setattr(plt, name, refuse)
    fig = run.plot()
    assert isinstance(fig, Figure) and len(fig.get_axes()) == 3
    assert fig.get_axes()[0].get_ylabel() == "table speed [mm/s]"
    assert matplotlib.rcParams._get_backend_or_none() == backend


def test_parquet_export_carries_units_and_provenance_for_pandas(run: fd.Result,
                                                                tmp_path) -> None:
    """Item 13: ``pandas.read_parquet`` of a ``.parquet`` export has the (engineering) units
    and where the numbers come from in ``df.attrs``."""
    df = pd.read_parquet(run.save(tmp_path / "run.parquet"))
    assert df.attrs["units"]["table_speed"] == "mm/s" and df.attrs["units"]["time"] == "s"
    assert df["table_speed"].to_numpy() == pytest.approx(1e3 * run["table_speed"])
    assert df.attrs["drive"] == "cdfs" and df.attrs["parameter_set"] == "wang2021"
    assert df.attrs["table_start_position_m"] == 0.4
    assert df.attrs["profile"].startswith("ConstantSpeed(table_speed=0.002")
    assert df.attrs["feeddrive_version"] == fd.__version__


def _check_provenance_line(path) -> None:
    first = path.read_text(encoding="utf-8").splitlines()[0]
    assert first.startswith(f"# feeddrive {fd.__version__}: drive cdfs, table start position "
                            "0.4 m, parameter set wang2021, profile ConstantSpeed(")
    assert first.endswith("; units in the column names")


def test_csv_export_starts_with_a_provenance_line_feeddrive_reads_past(run: fd.Result,
                                                                      tmp_path) -> None:
    path = run.save(tmp_path / "run.csv")
    _check_provenance_line(path)
    assert "solver modal" in path.read_text(encoding="utf-8").splitlines()[0]
    n = run.time.size
    # the readers behind `analyze` and `fit`
    trace = read_position_trace(path)
    assert trace.time.size == n
    assert trace.position[-1] == pytest.approx(run["table_position"][-1], rel=1e-9)
    exp = read_experiment(path)
    assert exp.time.size == n
    assert pd.read_csv(path, comment="#").shape == (n, len(run.to_pandas().columns) + 1)


def test_streamed_csv_and_parquet_carry_the_same_provenance(tmp_path) -> None:
    system = fd.DriveSystem(PARAMS, "cdfs", 0.4)
    fd.simulate(system, fd.ConstantSpeed(2e-3), 0.3, output=tmp_path / "s.csv")
    _check_provenance_line(tmp_path / "s.csv")
    assert read_position_trace(tmp_path / "s.csv").time.size > 100
    fd.simulate(system, fd.ConstantSpeed(2e-3), 0.3, output=tmp_path / "s.parquet")
    df = pd.read_parquet(tmp_path / "s.parquet")
    assert df.attrs["units"]["table_position"] == "mm" and df.attrs["drive"] == "cdfs"
    assert df.attrs["profile"].startswith("ConstantSpeed(")
