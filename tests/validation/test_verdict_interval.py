"""A creep verdict's output interval (session 21, an outside finding): a parameter file's
``[solver] output_interval = 0.5`` reached every creep search, whose trials judge the table
speed sampled at it — ``feeddrive creep --params`` then answered a step-down critical speed of
1.39 mm/s with two undecided bands (0.32 and 0.42 mm/s) where the default sampling answers
1.40 mm/s and none, stated as if it were the same measurement.

The verdicts are judged at ≤ :data:`~feeddrive.analysis.critical.VERDICT_INTERVAL` (1 ms, the
default, at which the verdict corpus was built); the critical speeds below are the same at
0.25, 0.5 and 1 ms (so the 1 ms is no arbitrary grid of the answer), and a coarser interval is
refused before the first trial, naming where it was set."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.analysis import critical
from feeddrive.analysis.critical import (
    VERDICT_INTERVAL,
    critical_speed_from_rest,
    critical_speed_stepdown,
)
from feeddrive.analysis.forced import threshold_critical_speed
from feeddrive.cli import app
from feeddrive.parameters import ParameterError, loads

COARSE = 'extends = "wang2021"\n[solver]\noutput_interval = 0.5\n'


def _at(interval: float) -> fd.SolverOptions:
    return replace(fd.SolverOptions(), output_interval=interval)


@pytest.mark.parametrize("search", [critical_speed_from_rest, critical_speed_stepdown],
                         ids=["rest", "running"])
def test_the_critical_speed_does_not_move_with_the_interval_below_the_limit(search) -> None:
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    found = {dt: search(system, options=_at(dt)) for dt in (VERDICT_INTERVAL / 4,
                                                             VERDICT_INTERVAL / 2,
                                                             VERDICT_INTERVAL)}
    speeds = {dt: r.critical_speed for dt, r in found.items()}
    assert len(set(speeds.values())) == 1, speeds
    # and it is a creeping drive (Wang2021 Sect. 6: the CDFS creeps below ≈ 1.4 mm/s)
    assert all(r.status == "found" for r in found.values())
    kinds = {dt: [(t.speed, t.kind) for t in r.trials] for dt, r in found.items()}
    assert len({tuple(k) for k in kinds.values()}) == 1


class _NoRun:
    def __init__(self, *args: object, **kwargs: object) -> None:
        raise AssertionError("a trial ran")


@pytest.mark.parametrize("search", [critical_speed_from_rest, critical_speed_stepdown],
                         ids=["rest", "running"])
def test_a_coarser_interval_from_the_api_is_refused_before_a_trial(search, monkeypatch) -> None:
    monkeypatch.setattr(critical, "Simulation", _NoRun)
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    with pytest.raises(ParameterError) as info:
        search(system, options=_at(2e-3))
    text = str(info.value)
    assert "options.output_interval" in text and "0.002" in text and "≤ 0.001 [s]" in text


def test_the_files_table_is_named(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(critical, "Simulation", _NoRun)
    path = tmp_path / "coarse.toml"
    path.write_text(COARSE, encoding="utf-8")
    system = fd.DriveSystem(fd.load(path), "cdfs", 0.4)
    with pytest.raises(ParameterError, match=r"solver\.output_interval = 0\.5.*coarse\.toml"):
        critical_speed_from_rest(system)
    with pytest.raises(ParameterError, match=r"solver\.output_interval"):
        threshold_critical_speed(system)


def test_the_command_refuses_it_in_one_line(tmp_path: Path) -> None:
    path = tmp_path / "coarse.toml"
    path.write_text(COARSE, encoding="utf-8")
    for extra in ([], ["--ripple-threshold", "0.5"]):
        result = CliRunner().invoke(app, ["creep", "--drive", "cdfs", "--params", str(path),
                                          *extra])
        assert result.exit_code == 2, result.output
        lines = [line for line in result.output.splitlines() if line.strip()]
        assert len(lines) == 1 and "solver.output_interval = 0.5" in lines[0], result.output
        assert "Traceback" not in result.output


def test_a_finer_interval_from_a_file_is_taken() -> None:
    # the limit refuses only coarser: a table's 0.5 ms runs (its samples are the trial's)
    params = loads(COARSE.replace("0.5", "0.0005"))
    system = fd.DriveSystem(params, "cdfs", 0.4)
    trial = critical.creep_trial(system, 2.0e-3)
    assert trial.kind == "smooth"


def test_the_sweep_machinery_says_it_as_a_verdicts_limit(tmp_path: Path, monkeypatch) -> None:
    # sensitivity and sweep warm their kernels with a 20-ms run first; the set's 0.5 s was
    # refused there as the warm-up's ("expected ≤ the run's duration, 0.02 [s]"), a run the
    # user never asked for, and after the store had been made; now with the design's check,
    # before the store is touched
    monkeypatch.chdir(tmp_path)  # sensitivity's default store is made in the working folder
    path = tmp_path / "coarse.toml"
    path.write_text(COARSE, encoding="utf-8")
    sweep = tmp_path / "sw.toml"
    sweep.write_text(f'drive = "cdfs"\ntable_position = 400\nparams = "{path.name}"\n'
                     '[design]\nkind = "grid"\n[quantity]\nkind = "creep-trial"\n'
                     'initial_duration = 3\nmax_duration = 3\nlinear = false\n'
                     '[axes]\ntable_speed = [1.0, 1.6]\n', encoding="utf-8")
    for args in (["sensitivity", str(path), "--workers", "1"],
                 ["sweep", str(sweep), "--workers", "1", "--store",
                  str(tmp_path / "sw.sqlite")]):
        result = CliRunner().invoke(app, args)
        assert result.exit_code == 2, result.output
        lines = [line for line in result.output.splitlines() if line.strip()]
        assert len(lines) == 1 and "for a creep verdict" in lines[0], result.output
    assert not list(tmp_path.glob("*.sqlite"))  # no store made


def test_a_fits_warm_up_takes_its_sets_interval() -> None:
    # a fit with workers warms its kernels with a creep-trial task (feeddrive.analysis.fit)
    # but judges no verdict: its set's [solver] interval (0.01 s here, as
    # test_s19_solver_table's fit set) is its own and must not be refused there; the sweep's
    # design check refuses it for a creep quantity
    from feeddrive.sweep.quantities import check_task, warm

    params = loads(COARSE.replace("0.5", "0.01"))
    task = {"parameters": fd.parameters.dumps(params), "drive": "cdfs", "table_position": 0.4,
            "nut_speed": 0.0, "quantity": {"kind": "creep-trial", "table_speed": 1e-3,
                                           "linear": False}}
    warm(task)
    with pytest.raises(ParameterError, match="for a creep verdict"):
        check_task(task)
