"""`feeddrive simulate`: an outside tester's five defects, one test (or more) per defect.

1. ``--error-estimate`` with ``--machine`` was ignored without a word;
2. refusals named API fields in SI (``command_speed = 0.0 … [m/s]``, ``drive = 'bogus'``,
   ``profile.frequency``, ``ramp_time``, ``error_estimate = True``), and ``--output F --plot F``
   called the first output "an input of this command";
3. ``--rtol``'s help did not say what it weighs (speeds and currents only);
4. ``--max-steps``'s help promised a refusal before the start that only a lower bound gives;
5. ``--json`` printed ``"warnings": []`` beside a warning printed on stderr.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

import feeddrive as fd
import feeddrive.machine
from feeddrive.cli import app
from feeddrive.cli._common import _refusal
from feeddrive.cli._solver import RTOL_WEIGHS_NOT
from feeddrive.cli.simulate_cmd import MAX_STEPS_HELP
from feeddrive.engine import budget
from feeddrive.engine import options as opt
from feeddrive.engine import simulate as sim_module
from feeddrive.model import codegen
from feeddrive.parameters import ParameterError

runner = CliRunner()
#: every command that takes --rtol (as tests/integration/test_cli_accuracy.py)
SOLVER_COMMANDS = (["simulate"], ["creep"], ["calibrate"], ["fit"], ["predict"], ["validate"],
                   ["sensitivity"], ["sweep"], ["export", "fmu"])


def _never(*_: Any, **__: Any) -> Any:
    raise AssertionError("a simulation started although the input was refused")


@pytest.fixture
def no_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """Any run of a drive or a machine fails the test: refusals come before any work."""
    monkeypatch.setattr(sim_module.Simulation, "run", _never)
    monkeypatch.setattr(feeddrive.machine, "simulate_machine", _never)


def _error_line(*args: str, code: int = 2) -> str:
    """The one line a refused command prints on stderr (nothing on stdout)."""
    result = runner.invoke(app, list(args))
    assert result.exit_code == code, result.output
    assert "Traceback" not in result.output and not result.stdout.strip(), result.output
    lines = [ln for ln in result.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    return lines[0]


def _help(*command: str) -> str:
    out = runner.invoke(app, [*command, "--help"], terminal_width=400).output
    return " ".join(out.split())


# ------------------------------------------------------------------ 1: --error-estimate


@pytest.mark.parametrize("json_flag", [[], ["--json"]], ids=["text", "json"])
def test_error_estimate_with_machine_is_refused_before_any_work(
        no_run: None, json_flag: list[str]) -> None:
    line = _error_line("simulate", "--machine", "xy-table", "--contour", "line", "--length",
                       "5", "--error-estimate", *json_flag)
    assert line.startswith("error: --error-estimate: not available with --machine"), line


def test_error_estimate_help_says_it_is_not_available_with_machine() -> None:
    assert re.search(r"--error-estimate [^-]*not available with --machine\.",
                     _help("simulate")), _help("simulate")


def test_a_machine_run_without_error_estimate_still_runs(no_run: None) -> None:
    # the refusal is of the flag only: without it the machine run starts (and here meets
    # the patched run)
    with pytest.raises(AssertionError, match="a simulation started"):
        runner.invoke(app, ["simulate", "--machine", "xy-table", "--contour", "line",
                            "--length", "5"], catch_exceptions=False)


# ------------------------------------------------------------------ 2: options, not fields


@pytest.mark.parametrize(("args", "expected"), [
    (["--table-speed", "0", "--duration", "1"],
     "error: --table-speed = 0.0: expected a non-zero speed [mm/s]"),
    (["--table-speed", "0", "--profile", "sine", "--duration", "1"],
     "error: --table-speed = 0.0: expected a non-zero speed [mm/s]"),
    (["--table-speed", "1", "--drive", "bogus", "--duration", "1"],
     "error: --drive = 'bogus': expected one of cdfs, ddfs, linear-motor, rack-pinion"),
    (["--table-speed", "1", "--profile", "sine", "--frequency", "0", "--duration", "1"],
     "error: --frequency = 0.0: expected a frequency > 0, ≤ 1000 [Hz]"),
    (["--table-speed", "1", "--profile", "sine", "--frequency", "nan", "--duration", "1"],
     "error: --frequency = nan: expected a frequency > 0, ≤ 1000 [Hz]"),
    (["--table-speed", "1", "--profile", "trapezoid", "--ramp-time", "5", "--duration", "1"],
     "error: --ramp-time = 5 [s]: expected < duration / 2 = 0.5 [s]"),
    (["--table-speed", "2", "--duration", "1", "--rtol", "5e-14", "--error-estimate"],
     "error: --error-estimate: needs a run 10× tighter than rtol 5e-14, below 1e-14"),
], ids=["zero-command", "zero-amplitude", "drive", "frequency", "frequency-nan", "ramp-time",
        "error-estimate"])
def test_a_refusal_names_the_option_in_its_unit_before_any_work(
        no_run: None, args: list[str], expected: str) -> None:
    line = _error_line("simulate", *args)
    assert line.startswith(expected), line
    for internal in ("command_speed", "profile.frequency", "ramp_time", "error_estimate",
                     "error: drive", "[m/s]"):
        assert internal not in line, line


def test_the_one_table_converts_si_to_the_option_unit_for_a_command_taking_the_option() -> None:
    refused = ParameterError("nut_speed", 0.016, "the CDFS holds the hollow motor")
    assert _refusal(refused, {"nut_speed": 16.0}) == \
        "--nut-speed = 16 [mm/s]: the CDFS holds the hollow motor"
    # a command without the option is not told about it: the field stays as the API named it
    assert _refusal(refused, {"table_speed": 1.0}) == str(refused)
    # a value from a file keeps naming the file's field
    from_file = ParameterError("drive", "x", "expected one of cdfs", source="set.toml")
    assert _refusal(from_file, {"drive": "x"}) == str(from_file)
    # a flag is named, not valued
    assert _refusal(ParameterError("error_estimate", True, "needs a run"),
                    {"error_estimate": True}) == "--error-estimate: needs a run"


def test_one_file_for_two_outputs_is_named_as_such(no_run: None, tmp_path: Path) -> None:
    same = tmp_path / "same.csv"
    for other in (str(same), str(tmp_path / "sub" / ".." / "same.csv")):
        (tmp_path / "sub").mkdir(exist_ok=True)
        line = _error_line("simulate", "--table-speed", "2", "--duration", "1", "--output",
                           str(same), "--plot", other)
        assert line == f"error: --plot {other}: the same file as --output; expected a file " \
                       "of its own", line
        assert "is an input" not in line
    assert not same.exists()


def test_an_input_is_still_named_as_an_input(no_run: None, tmp_path: Path) -> None:
    profile = tmp_path / "profile.csv"
    profile.write_text("time,table_speed\n0,1\n1,1\n", encoding="utf-8")
    line = _error_line("simulate", "--profile", "csv", "--profile-file", str(profile),
                       "--output", str(profile), "--force")
    assert "is an input of this command" in line, line


# ------------------------------------------------------------------ 3: --rtol


def test_rtol_help_says_what_it_weighs_on_every_command() -> None:
    sentence = (f"It weighs only speeds and currents ({RTOL_WEIGHS_NOT} have absolute "
                "tolerances only)")
    for command in SOLVER_COMMANDS:
        text = _help(*command)
        assert sentence in text, command
        assert "--rtol alone barely changes a run; --accuracy tightens every tolerance" \
            in text, command


def test_the_rtol_words_are_the_models_relative_kinds() -> None:
    words = {"speed": "speeds", "rotary_speed": "speeds", "current": "currents",
             "position": "positions", "angle": "angles", "current_integral": "loop integrals",
             "velocity_integral": "loop integrals", "deflection": "friction deflections"}
    assert set(words) == set(codegen.TOLERANCE_KINDS) - {"none"}
    assert {words[k] for k in codegen.RELATIVE_KINDS} == {"speeds", "currents"}
    absolute = {words[k] for k in words if k not in codegen.RELATIVE_KINDS}
    assert set(re.split(r", | and ", RTOL_WEIGHS_NOT)) == absolute
    # and an assembled model weighs exactly those states relatively
    system = fd.DriveSystem(fd.preset("wang2021"), drive="ddfs")
    sim = sim_module.Simulation(system, fd.ConstantSpeed(1e-3, 16e-3), opt.SolverOptions())
    kinds = [s.kind for s in sim.model.states]
    assert np.array_equal(sim.rel, [float(k in codegen.RELATIVE_KINDS) for k in kinds])
    assert {"position", "angle", "deflection"} <= set(kinds)


def test_at_the_defaults_a_speeds_absolute_tolerance_is_ten_times_rtol_times_the_command() -> None:
    v = 2e-3
    tol = opt.SolverOptions().resolve(opt.RunScales(speed=v, table_speed=v, current=1.0))
    ratio = tol.speed / (tol.rtol * v)
    assert ratio == pytest.approx(10.0)
    assert f"is {ratio:g}× rtol × the commanded speed" in _help("simulate")


# ------------------------------------------------------------------ 4: --max-steps


def test_max_steps_help_is_the_stated_checks() -> None:
    assert " ".join(MAX_STEPS_HELP.split()) in _help("simulate")
    # its numbers: dopri5's largest step, the probe's length and margin, the shortest run
    # probed (a run of 4 probes or less is not)
    assert opt.SolverOptions(method="dopri5").largest_step == opt.DOPRI5_STEP == 1e-3
    assert all(math.isinf(opt.SolverOptions(method=m).largest_step)
               for m in ("modal", "auto", "rodas4", "dopri5-dense"))
    assert budget.probe_time(0.4, 1e-4) == 0.0 and budget.probe_time(0.41, 1e-4) > 0.0
    assert "dopri5: 1 ms at --accuracy 1" in MAX_STEPS_HELP
    assert "longer than 0.4 s" in MAX_STEPS_HELP and "first 0.1 s, × 1.5, exceed" \
        in MAX_STEPS_HELP


def test_dopri5_is_refused_before_the_start_by_its_largest_step(no_run: None) -> None:
    line = _error_line("simulate", "--table-speed", "2", "--method", "dopri5", "--duration",
                       "2", "--max-steps", "1500")
    assert line.startswith("error: --duration = 2.0: needs at least 2e+03 solver steps "
                           "(step ≤ 1 ms), more than --max-steps = 1.5e+03"), line


def test_dopri5_is_refused_before_integrating_by_its_probe() -> None:
    line = _error_line("simulate", "--table-speed", "2", "--method", "dopri5", "--duration",
                       "1", "--max-steps", "1100", code=1)
    assert line.startswith("error: refused before integrating: the run would exceed the "
                           "maximum number of steps, max_steps = 1100"), line


def test_the_default_method_reaches_the_limit_during_the_run_and_names_the_time() -> None:
    line = _error_line("simulate", "--table-speed", "2", "--duration", "100", "--max-steps",
                       "1000", code=1)
    found = re.match(r"error: integration stopped at t = ([0-9.e+-]+) s of 100 s: maximum "
                     r"number of steps reached", line)
    assert found and 0.0 < float(found.group(1)) < 100.0, line
    assert "--max-steps" in line


# ------------------------------------------------------------------ 5: --json warnings


@pytest.mark.parametrize(("args", "warned"), [
    (["--table-speed", "2", "--duration", "0.2", "--position", "0.4"],
     "--position = 0.4 mm looks like a value in metres"),
    (["--table-speed", "0.05", "--profile", "stepdown", "--lowest-speed", "0.005", "--step",
      "0.01", "--dwell", "0.1"], "--lowest-speed = 0.005 mm/s looks like a value in m/s"),
], ids=["position", "lowest-speed"])
def test_json_carries_the_warnings_printed_on_stderr(args: list[str], warned: str) -> None:
    result = runner.invoke(app, ["simulate", *args, "--json"])
    assert result.exit_code == 0, result.output
    printed = [ln.removeprefix("warning: ") for ln in result.stderr.splitlines()
               if ln.startswith("warning: ")]
    # each warning once (--lowest-speed's used to be printed twice)
    assert sum(w.startswith(warned) for w in printed) == 1, result.stderr
    assert json.loads(result.stdout)["warnings"] == printed


def test_json_without_a_warning_has_none() -> None:
    result = runner.invoke(app, ["simulate", "--table-speed", "2", "--duration", "0.2",
                                 "--json"])
    assert result.exit_code == 0, result.output
    assert "warning:" not in result.stderr
    assert json.loads(result.stdout)["warnings"] == []


# ------------------------------------------------------------------ the docs say the same


def test_docs_outputs_md_states_the_clash_and_the_step_limit_as_the_cli(
        no_run: None, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    doc = " ".join((Path(__file__).resolve().parents[2] / "docs" / "outputs.md")
                   .read_text(encoding="utf-8").split())
    monkeypatch.chdir(tmp_path)
    line = _error_line("simulate", "--table-speed", "2", "--output", "r.csv", "--plot", "r.csv")
    assert f"`{line.removeprefix('error: ')}`" in doc
    assert (f"longer than {4 * budget.PROBE_TIME:g} s whose solver steps, projected from a "
            f"{budget.PROBE_TIME:g}-s probe, × {budget.STEP_MARGIN:g} exceed `max_steps`") in doc
    assert f"(`dopri5`: {1e3 * opt.DOPRI5_STEP:g} ms at `--accuracy` 1;" in doc


@pytest.mark.parametrize("command", ["circular", "positioning"])
def test_the_machine_tests_max_steps_help_is_the_shared_one(command: str) -> None:
    """``circular`` and ``positioning`` said a test needing more steps "is refused before it
    starts", which only the largest-step bound does (dopri5's; none for the default method):
    they give the shared text, without simulate's dopri5 probe (they have none)."""
    from feeddrive.cli._solver import max_steps_help

    text = _help(command)
    assert " ".join(max_steps_help().split()) in text
    assert "refused before it starts" not in text
