"""Issue 41 item 7: messages a new user met in the first hour, one test per defect."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.cli import app

runner = CliRunner()


def _error(*args: str) -> str:
    result = runner.invoke(app, list(args))
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    return lines[0]


def test_nut_speed_on_the_cdfs_is_answered_in_mm_s_and_points_to_the_ddfs() -> None:
    line = _error("simulate", "--drive", "cdfs", "--table-speed", "1", "--nut-speed", "16",
                  "--duration", "0.1")
    assert line.startswith("error: --nut-speed = 16 [mm/s]: the CDFS holds the hollow motor")
    assert "--drive ddfs" in line and "0.016" not in line and "[m/s]" not in line


def test_a_drive_without_its_section_does_not_print_none() -> None:
    # wang2021 named: by default `creep` takes the drive's example set (2026-12-06)
    line = _error("creep", "--drive", "linear-motor", "--preset", "wang2021")
    assert "None" not in line and "wang2021" in line
    assert "needs a [linear_motor] section (e.g. --preset linear-motor-example)" in line


@pytest.mark.parametrize(("args", "hint"), [
    (("simulate", "--drive", "cdfz", "--table-speed", "1"), "(did you mean 'cdfs'?)"),
    (("params", "show", "--preset", "wang2012"), "(did you mean 'wang2021'?)"),
])
def test_misspelt_names_get_a_suggestion(args: tuple[str, ...], hint: str) -> None:
    assert _error(*args).endswith(hint)


@pytest.mark.parametrize(("text", "hint"), [
    ('extends = "wang2021"\n[controler]\nvelocity_gain = 50\n', "(did you mean 'controller'?)"),
    ('extends = "wang2021"\n[controller]\nvelocity_gian = 50\n',
     "(did you mean 'velocity_gain'?)"),
])
def test_misspelt_keys_get_a_suggestion(tmp_path: Path, text: str, hint: str) -> None:
    path = tmp_path / "set.toml"
    path.write_text(text, encoding="utf-8")
    assert _error("params", "check", str(path)).endswith(hint)


@pytest.fixture(scope="module")
def trace(tmp_path_factory: Any) -> Path:
    path = tmp_path_factory.mktemp("trace") / "run.csv"
    fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4), fd.ConstantSpeed(2e-3),
                0.5).save(path)
    return path


@pytest.mark.parametrize(("free", "hint"), [
    ("controller.velocity_gian", "(did you mean 'velocity_gain'?)"),
    ("controler.velocity_gain", "(did you mean 'controller'?)"),
])
def test_misspelt_free_paths_get_a_suggestion(trace: Path, free: str, hint: str) -> None:
    line = _error("fit", str(trace), "--free", free)
    assert f"--free {free}: unknown parameter" in line and line.endswith(hint)


def test_an_unknown_output_extension_lists_the_formats_not_a_tuple(tmp_path: Path) -> None:
    line = _error("simulate", "--table-speed", "1", "--duration", "0.1", "--output",
                  str(tmp_path / "run.xlsx"))
    # the one output check of every command (issue 39 item 4) names the formats in words
    assert line.endswith("expected a .csv, .parquet, .nc or .mat file name"), line
    assert "(" not in line.split("expected", 1)[1] and "'" not in line


def test_identify_static_on_a_time_trace_says_what_a_static_file_is(trace: Path) -> None:
    line = _error("identify", "static", str(trace))
    assert "this looks like a time trace" in line
    assert "one row per constant-speed test" in line and "speed [mm/s] and force [N]" in line
    assert "`feeddrive analyze FILE`" in line


def test_a_run_that_never_sticks_has_no_stick_slip_frequency_in_its_json() -> None:
    """2 mm/s on the CDFS oscillates (ripple 1.5 at 5.3 Hz over its first 0.5 s) without
    sticking: the JSON called that frequency stick-slip while the text said oscillation."""
    result = runner.invoke(app, ["simulate", "--table-speed", "2", "--duration", "0.5",
                                 "--json"])
    assert result.exit_code == 0, result.output
    s = json.loads(result.stdout)
    assert s["stick_fraction"] == 0.0 and s["oscillation_frequency_hz"] > 1.0
    assert s["stick_slip_frequency_hz"] is None
    text = runner.invoke(app, ["simulate", "--table-speed", "2", "--duration", "0.5"]).stdout
    assert "oscillation frequency" in text and "stick-slip frequency" not in text
    sticks = runner.invoke(app, ["simulate", "--table-speed", "1.2", "--duration", "3",
                                 "--json"])
    s = json.loads(sticks.stdout)
    assert s["stick_fraction"] > 0
    assert s["stick_slip_frequency_hz"] == s["oscillation_frequency_hz"] > 1.0
