"""`loops`, `stability` and `compensate` read their operating point as `simulate` and `creep`
do (``feeddrive.cli._units``): a speed or position the drive cannot have is refused before any
linearisation, in one line naming the option as typed and its CLI unit.

Before 2026-12-06 these three passed the values on in SI: ``stability --points 0`` ended in an
IndexError traceback, ``--points 1`` reported "stable at every speed scanned" from one speed,
``--nut-speed 1e6`` (1000 m/s) reached the steady-state solver ("no steady sliding state
found"), and ``--position -5`` was answered as ``table_position = -0.005 … [m]``.  The trial
lengths of `creep` and `calibrate` likewise: ``--initial-duration 1e-9`` ended in "time: 0
samples; need at least 16", ``--max-duration 5`` under the rule's field names."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.analysis.linear import stability_band, upper_band_edge
from feeddrive.cli import app
from feeddrive.parameters import ParameterError

runner = CliRunner()

REFUSED = [
    (["stability", "--points", "0"], "--points = 0", "2 … 10000"),
    (["stability", "--points", "1"], "--points = 1", "2 … 10000"),
    (["stability", "--low", "3", "--high", "1"], "--high = 1.0", "[mm/s]"),
    (["stability", "--low", "-1"], "--low = -1.0", "[mm/s]"),
    (["stability", "--drive", "ddfs", "--nut-speed", "1e6"], "--nut-speed = 1000000.0",
     "[mm/s]"),
    (["stability", "--position", "0"], "--position = 0.0", "[mm]"),
    (["loops", "--position", "5000"], "--position = 5000.0", "[mm]"),
    (["loops", "--table-speed", "1e9"], "--table-speed = 1000000000.0", "[mm/s]"),
    (["loops", "--table-speed", "nan"], "--table-speed = nan", "[mm/s]"),
    (["loops", "--drive", "ddfs", "--nut-speed", "1e7"], "--nut-speed = 10000000.0", "[mm/s]"),
    (["compensate", "--no-search", "--nut-speed", "1e7"], "--nut-speed = 10000000.0",
     "[mm/s]"),
    (["compensate", "--no-search", "--tracking-speed", "0"], "--tracking-speed = 0.0",
     "[mm/s]"),
    (["compensate", "--no-search", "--position", "-5"], "--position = -5.0", "[mm]"),
    (["compensate", "--compare", "--position", "900"], "--position = 900.0", "[mm]"),
    # trial lengths (the rule's settle time 2 s; the first trial 12 s, cycle_verdict.VerdictRule)
    (["creep", "--initial-duration", "0"], "--initial-duration = 0.0", "≥ 2 [s]"),
    (["creep", "--initial-duration", "1e-9", "--max-duration", "1e-9"],
     "--max-duration = 1e-09", "≥ 2 [s]"),
    (["creep", "--initial-duration", "10", "--max-duration", "5"], "--max-duration = 5.0",
     "≥ 10 [s]"),
    (["creep", "--max-duration", "nan"], "--max-duration = nan", "[s]"),
    (["calibrate", "--target", "1.5", "--max-duration", "5"], "--max-duration = 5.0",
     "≥ 12 [s]"),
    (["calibrate", "--target", "1.5", "--max-duration", "inf"], "--max-duration = inf", "[s]"),
    # the unknown and its bracket, before any trial (was "nope = 1.0: unknown field 'nope'")
    (["calibrate", "--target", "1.5", "--unknown", "nope"], "--unknown = 'nope'",
     "params show"),
    (["calibrate", "--target", "1.5", "--unknown", "table.mass", "--low", "1e-9", "--high", "2"],
     "table.mass = 1e-09", "[kg]"),
    # analyze: the window rule's thresholds (creep_window.CreepThresholds) and the command
    (["analyze", "{trace}", "--command-speed", "0"], "--command-speed = 0.0", "[mm/s]"),
    (["analyze", "{trace}", "--command-speed", "1e9"], "--command-speed = 1000000000.0",
     "[mm/s]"),
    (["analyze", "{trace}", "--stick-level", "2"], "--stick-level = 2.0", "< 1 [-]"),
    (["analyze", "{trace}", "--max-stick-fraction", "-1"], "--max-stick-fraction = -1.0",
     "≥ 0 [-]"),
    (["analyze", "{trace}", "--max-ripple-ratio", "nan"], "--max-ripple-ratio = nan", "[-]"),
    # friction's oscillator scan (friction_cmd.MAX_POINTS)
    (["friction", "--speed-max", "1e9"], "--speed-max = 1000000000.0", "[mm/s]"),
    (["friction", "--speed-min", "0"], "--speed-min = 0.0", "[mm/s]"),
    (["friction", "--points", "100001"], "--points = 100001", "2 … 100000"),
]


@pytest.mark.parametrize(("args", "named", "unit"), REFUSED,
                         ids=[" ".join(a) for a, _, _ in REFUSED])
def test_an_impossible_operating_point_is_refused_in_one_line(args: list[str], named: str,
                                                              unit: str, tmp_path: Path) -> None:
    trace = tmp_path / "trace.csv"  # 5 s of a table at 1 mm/s with a 3-Hz ripple [s, mm]
    t = np.arange(0.0, 5.0, 1e-3)
    np.savetxt(trace, np.c_[t, t + 0.05 * np.sin(6 * np.pi * t)], delimiter=",",
               header="time,position", comments="")
    result = runner.invoke(app, [a.format(trace=trace) for a in args])
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {named}:"), result.stderr
    assert unit in lines[0]


def test_the_smallest_scan_still_finds_the_band() -> None:
    """``--points 2`` is allowed; on wang2021's CDFS at mid-screw the band of the 40-point
    default (0.17–1.40 mm/s, the docstring of ``stability_band``) is found from three scan
    points too: the edges are bisected, not read off the scan."""
    result = runner.invoke(app, ["stability", "--points", "3"])
    assert result.exit_code == 0, result.output
    assert "unstable from 0.172 to 1.398 mm/s" in result.output


@pytest.mark.parametrize("points", [0, 1, 2.5])
def test_the_library_refuses_a_scan_of_fewer_than_two_speeds(points: object) -> None:
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    for scan in (stability_band, upper_band_edge):
        with pytest.raises(ParameterError, match=r"points = .*expected a whole number 2 … 10000"):
            scan(system, points=points)  # type: ignore[arg-type]


def test_the_help_states_the_shortest_trial_the_code_enforces() -> None:
    from feeddrive.analysis.cycle_verdict import VerdictRule

    shortest = VerdictRule().settle_time
    text = " ".join(runner.invoke(app, ["creep", "--help"]).output.split())
    assert f"First trial length [s], at least {shortest:g} (the rule's settle time)" in text
    refused = runner.invoke(app, ["creep", "--initial-duration", f"{0.99 * shortest:g}"])
    assert f"expected ≥ {shortest:g} [s]" in refused.stderr


def test_creep_takes_a_drives_example_set_as_simulate_does() -> None:
    """``creep --drive linear-motor`` read wang2021 (no [linear_motor] section) where
    ``simulate``, ``loops`` and ``stability`` take the drive's example set."""
    import json

    result = runner.invoke(app, ["creep", "--drive", "linear-motor", "--method", "bisect",
                                 "--low", "1", "--high", "1.2", "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["parameter_set"] == "linear-motor-example"


@pytest.mark.parametrize("command", [["analyze"], ["identify", "static"]])
def test_a_device_is_not_called_a_missing_file(command: list[str]) -> None:
    """``analyze /dev/null`` said "no such file" of a path that exists (2026-12-06)."""
    result = runner.invoke(app, [*command, "/dev/null"])
    assert result.exit_code == 2
    assert result.stderr.strip() == "error: null: is not a regular file; expected a CSV file"


def _help(command: str) -> str:
    return " ".join(runner.invoke(app, [command, "--help"], terminal_width=200).output.split())


def test_the_trial_length_floors_the_help_states_are_those_enforced() -> None:
    """`calibrate --help` states the first trial's length as --max-duration's floor and `creep
    --help` the settle time as --initial-duration's: both the numbers the checks refuse by
    (protocol.TRIAL_DURATION, VerdictRule().settle_time)."""
    from feeddrive.analysis import protocol
    from feeddrive.analysis.cycle_verdict import VerdictRule

    first, settle = protocol.TRIAL_DURATION, VerdictRule().settle_time
    assert f"at least the first trial's {first:g} s" in _help("calibrate")
    assert f"at least {settle:g} (the rule's settle time)" in _help("creep")
    assert "at least the first (--initial-duration)" in _help("creep")
    below = runner.invoke(app, ["calibrate", "--max-duration", f"{first - 0.5:g}"])
    assert f"expected ≥ {first:g} [s], the first trial's length" in below.output
    below = runner.invoke(app, ["creep", "--initial-duration", f"{settle - 0.5:g}"])
    assert f"expected ≥ {settle:g} [s]" in below.output
    below = runner.invoke(app, ["creep", "--initial-duration", "20", "--max-duration", "15"])
    assert "--max-duration = 15.0: expected ≥ 20 [s]" in below.output
