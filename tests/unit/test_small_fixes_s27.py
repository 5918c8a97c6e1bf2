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

import numpy as np
import pandas as pd
import pytest
import scipy.io
import xarray as xr
from typer.testing import CliRunner

import feeddrive as fd
import feeddrive.analysis.critical as critical
from feeddrive.analysis import protocol
from feeddrive.analysis.cycle_verdict import VerdictRule
from feeddrive.analysis.trace import analyze_trace
from feeddrive.cli import app, creep_cmd
from feeddrive.engine.machine_axes import axis_parameter_sets
from feeddrive.engine.result import Result
from feeddrive.machine import machine_from_dict, make_contour, simulate_machine

runner = CliRunner()

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


# ------------------------------------------------------------------ 2. analyze's left-out note

def _write(path: Path, t: np.ndarray, position_mm: np.ndarray,
           command_mm_s: np.ndarray | None = None) -> Path:
    """A record in the CSV format analyze reads (docs/measured-data.md section 4)."""
    cols, head = [t, position_mm], "time [s],position [mm]"
    if command_mm_s is not None:
        cols, head = [*cols, command_mm_s], head + ",command_speed [mm/s]"
    np.savetxt(path, np.column_stack(cols), delimiter=",", header=head, comments="",
               fmt="%.9g")
    return path


T = np.arange(10_001) / 1000.0  # 0 … 10 s at 1 kHz
V = 1.0  # [mm/s]


def _analyze(path: Path, *args: str) -> list[str]:
    r = runner.invoke(app, ["analyze", str(path), *args], terminal_width=400)
    assert r.exit_code == 0, r.output
    return r.stdout.splitlines()


def test_a_constant_speed_record_is_one_smooth_segment_at_its_speed(tmp_path: Path) -> None:
    lines = _analyze(_write(tmp_path / "const.csv", T, V * T))
    assert "  segments: one, with no speed step (binary segmentation of the position, "\
           "--min-step 0.005 mm/s, --min-segment 1 s)" in lines
    assert ("  0.00–1.00 s left out as the run-up: segmentation starts --min-segment 1 s after "
            "the speed first reaches 90 % of its mean") in lines
    segments = [line for line in lines if line.startswith("  segment ")]
    assert len(segments) == 1
    assert "1.00–10.00 s" in segments[0] and "command 1 mm/s (estimated): SMOOTH" in segments[0]
    assert not [line for line in lines if "skipped" in line]


def _ramped(ramp: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """The command of ``simulate --table-speed 1`` (ConstantSpeed, ramp_time 0.1 s): 0 at
    t = 0, rising every sample to 1 mm/s at 0.1 s; the position follows it."""
    command = V * np.clip(T / ramp, 0.0, 1.0)
    position = np.concatenate([[0.0], np.cumsum(0.5 * (command[1:] + command[:-1])
                                                * np.diff(T))])
    return position, command


def test_a_ramped_command_is_one_run_and_its_ramp_not_99_pieces(tmp_path: Path) -> None:
    position, command = _ramped()
    lines = _analyze(_write(tmp_path / "run.csv", T, position, command))
    assert "  segments: one run of constant command speed, 1 mm/s over 0.10–10.00 s" in lines
    assert ("  left out, as no command is held there for --min-segment 1 s: 0.00–0.10 s, where "
            "the command keeps changing (0.01 → 0.99 mm/s)") in lines
    assert not [line for line in lines if "skipped" in line]  # "99 shorter than 1 s skipped"
    assert [line for line in lines if line.startswith("  segment 1: 0.10–10.00 s")]


def test_short_holds_are_counted_with_their_duration_and_the_option() -> None:
    """A staircase of 0.5-s holds, 1.5 → 0.7 mm/s, then 0.6 mm/s for 5.5 s."""
    command = 1.5 - 0.1 * np.minimum(np.floor(T / 0.5), 9.0)
    position = np.concatenate([[0.0], np.cumsum(command[1:] * np.diff(T))])
    out = analyze_trace(T, 1e-3 * position, command=1e-3 * command)
    assert "segments: one run of constant command speed, 0.6 mm/s over 4.50–10.00 s" \
        in out.notes
    assert ("left out, as no command is held there for --min-segment 1 s: 9 holds of constant "
            "command (4.5 s in all, the longest 0.5 s)") in out.notes
    assert len(out.segments) == 1
    # a shorter --min-segment keeps them
    held = analyze_trace(T, 1e-3 * position, command=1e-3 * command, min_segment_time=0.4)
    assert len(held.segments) == 10 and not [n for n in held.notes if "left out" in n]


def test_one_short_hold_says_where_it_is() -> None:
    command = np.where(T < 0.5, 1.5, 1.0)
    position = np.concatenate([[0.0], np.cumsum(command[1:] * np.diff(T))])
    out = analyze_trace(T, 1e-3 * position, command=1e-3 * command)
    assert ("left out, as no command is held there for --min-segment 1 s: a 0.5-s hold at "
            "1.5 mm/s (0.00–0.50 s)") in out.notes


def test_a_command_that_never_holds_is_refused_saying_so(tmp_path: Path) -> None:
    """Each sample a different command: it was "no moving segment to analyse (the table does
    not move)" of a table moving at 1 mm/s."""
    command = V + 1e-3 * np.sin(2 * np.pi * 7.3 * T)
    r = runner.invoke(app, ["analyze", str(_write(tmp_path / "noisy.csv", T, V * T, command))],
                      terminal_width=400)
    assert r.exit_code == 2
    line = r.stderr.strip()
    assert line.startswith("error: noisy.csv: no run of constant command speed in the command "
                           "column lasts --min-segment 1 s: 0.00–10.00 s, where the command "
                           "keeps changing"), line
    assert "does not move" not in line and "--command-speed" in line


# ------------------------------------------------------------------ 3. the protocol's steps

def _scanned(low: float, high: float, step: float) -> list[float]:
    """The coarse speeds the search from rest runs (critical.search_kinds, every speed
    smooth: no bisection) [m/s]."""
    seen: list[float] = []

    def kind(v: float) -> str:
        seen.append(v)
        return "smooth"

    critical.search_kinds(kind, low, high, step, protocol.RESOLUTION)
    return seen


def test_the_rest_line_states_the_scans_shorter_last_step() -> None:
    lo, hi = 0.02e-3, 1.61e-3  # creep --high 1.61
    step = creep_cmd._coarse_step((lo, hi))
    gaps = np.round(1e3 * np.diff(_scanned(lo, hi, step)), 9)
    assert set(gaps[:-1]) == {0.2} and gaps[-1] == 0.19  # 1.61 − 1.42
    text = creep_cmd.protocol_text("rest", (lo, hi), step, VerdictRule())
    assert "scan 0.02–1.61 mm/s in 0.2-mm/s steps, the last 0.19 mm/s, then bisection" in text


def test_the_stepdown_line_states_the_staircases_shorter_first_step() -> None:
    lo, hi = 0.02e-3, 1.61e-3
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    _, _, coarse = critical.check_stepdown(
        system, nut_speed=0.0, start_speed=hi, lowest_speed=lo, step=protocol.RESOLUTION,
        coarse_step=protocol.STAIRCASE_COARSE_STEP, rule=None, options=None)
    gaps = np.round(-1e3 * np.diff(coarse), 9)
    assert gaps[0] == 0.09 and set(gaps[1:]) == {0.1}  # 1.61 → 1.52, then whole steps
    text = creep_cmd.protocol_text("running", (lo, hi), 0.0, VerdictRule())
    assert "staircase from 1.61 mm/s in 0.1-mm/s steps, the first 0.09 mm/s, then" in text


def test_whole_steps_read_as_before() -> None:
    """The protocol's own range is 15 whole 0.2-mm/s steps and 30 of 0.1 mm/s."""
    assert protocol.grid_steps(*protocol.SPEED_RANGE, protocol.COARSE_STEP) == (15, None)
    assert protocol.describe("rest") == (
        "from rest: trials of 12 s doubled up to 240 s until decided, scan 0.02–3.02 mm/s in "
        "0.2-mm/s steps, then bisection to 0.01 mm/s")
    assert "staircase from 3.02 mm/s in 0.1-mm/s steps, then 0.01-mm/s" \
        in protocol.describe("running")


def test_creep_prints_the_shorter_step(monkeypatch: pytest.MonkeyPatch) -> None:
    def search(system: Any, **kw: Any) -> critical.CriticalSpeed:
        return critical.CriticalSpeed(drive=system.drive, table_position=0.4, nut_speed=0.0,
                                      start="rest", critical_speed=1.3e-3, status="found",
                                      resolution=kw["resolution"],
                                      speed_range=kw["speed_range"], rule=kw["rule"])

    monkeypatch.setattr(critical, "critical_speed_from_rest", search)
    r = runner.invoke(app, ["creep", "--method", "bisect", "--high", "1.61"],
                      terminal_width=400)
    assert r.exit_code == 0, r.output
    line = [x for x in r.stdout.splitlines() if x.startswith("  protocol ")]
    assert len(line) == 1 and "in 0.2-mm/s steps, the last 0.19 mm/s" in line[0], line
