"""A run's limits from a parameter file's ``[solver]`` table (an outside check, 2026-12-06):

1. ``simulate`` ignored the file's ``max_steps``: ``--max-steps`` had a default of its own
   (50 000 000), always layered over the file as a command-line setting, and its budget check
   used it (656 steps where ``creep``, ``sweep`` and the API stopped at step 101); the same on
   ``simulate --machine``;
2. an ``output_interval`` at or above the run's length failed after the run with an unrelated
   message (``attempt to get argmax of an empty sequence``; ``time: 2 samples; need at least
   16``); through the API the Result had no sample and its summary raised a bare numpy error;
3. the step-limit advice of a run out of steps named ``--max-steps`` on ``creep`` and
   ``sweep``, which have none, for a limit set in the file;
4. the memory refusal said ``(or, from Python, raise options.output_interval)`` for an
   interval set in the file.

Each refusal is one line naming the setting where it came from, its value and the range.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

import feeddrive as fd
import feeddrive.machine
from feeddrive.analysis import trace_input
from feeddrive.cli import app
from feeddrive.cli._solver import DEFAULT_MAX_STEPS
from feeddrive.cli.simulate_cmd import MAX_STEPS_HELP
from feeddrive.engine import budget
from feeddrive.engine import simulate as sim_module
from feeddrive.engine.simulate import FAILURE_ADVICE, SimulationError
from feeddrive.parameters import ParameterError, load
from feeddrive.solvers import dopri5

runner = CliRunner()
SET = 'extends = "wang2021"\nname = "s20-limits"\n'


def _never(*_: Any, **__: Any) -> Any:
    raise AssertionError("a simulation started although the input was refused")


@pytest.fixture
def no_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """Any run of a drive or a machine fails the test: refusals come before any work."""
    monkeypatch.setattr(sim_module.Simulation, "run", _never)
    monkeypatch.setattr(feeddrive.machine, "simulate_machine", _never)


@pytest.fixture
def no_integration(monkeypatch: pytest.MonkeyPatch) -> None:
    """The engine's own refusals: the run is checked, nothing is integrated."""
    monkeypatch.setattr(sim_module, "_advance", _never)
    monkeypatch.setattr(sim_module, "_check_step_rate", _never)


def _file(tmp_path: Path, table: str, name: str = "run.toml") -> Path:
    path = tmp_path / name
    path.write_text(f"{SET}[solver]\n{table}", encoding="utf-8")
    return path


def _error_line(*args: str, code: int = 2) -> str:
    """The one error line of a failed command (a command may print its protocol first)."""
    result = runner.invoke(app, list(args))
    assert result.exit_code == code, result.output
    assert "Traceback" not in result.output, result.output
    errors = [ln for ln in result.stderr.splitlines() if ln.startswith("error: ")]
    assert len(errors) == 1, result.stderr
    return errors[0]


def _system(params: fd.DriveParameters | None = None) -> fd.DriveSystem:
    return fd.DriveSystem(params or fd.preset("wang2021"), "cdfs", 0.4)


# ------------------------------------------------------------------ 1: simulate's max_steps


def test_simulate_stops_at_the_files_max_steps(tmp_path: Path) -> None:
    """The outside check's case: 656 steps and exit 0; creep, sweep and the API stop at 101."""
    path = _file(tmp_path, "max_steps = 100\n")
    line = _error_line("simulate", "--params", str(path), "--table-speed", "2", "--duration",
                       "1", code=1)
    assert "maximum number of steps reached (steps 101," in line, line
    assert f"raise solver.max_steps ([solver] in {path})" in line, line


def test_the_command_line_still_overrides_the_files_max_steps(tmp_path: Path) -> None:
    path = _file(tmp_path, "max_steps = 100\n")
    result = runner.invoke(app, ["simulate", "--params", str(path), "--table-speed", "2",
                                 "--duration", "1", "--max-steps", "5000", "--json"])
    assert result.exit_code == 0, result.output


def test_the_budget_check_takes_the_files_max_steps_and_names_it(tmp_path: Path,
                                                                  no_run: None) -> None:
    """dopri5's 1-ms steps: a 1-s run needs 1000, more than the file's 100 — refused before
    the start, naming the file's setting (it checked the fixed 50 000 000)."""
    path = _file(tmp_path, "max_steps = 100\n")
    line = _error_line("simulate", "--params", str(path), "--table-speed", "2", "--duration",
                       "1", "--method", "dopri5")
    assert line == (f"error: --duration = 1.0: needs at least 1e+03 solver steps (step ≤ 1 ms), "
                    f"more than solver.max_steps = 100 ([solver] in {path}); expected ≤ 0.1 "
                    "[s], or raise it there or give --max-steps"), line


def test_the_default_step_limit_is_named_as_the_default(no_run: None) -> None:
    line = _error_line("simulate", "--table-speed", "1", "--duration", "100000", "--method",
                       "dopri5")
    assert "more than max_steps = 5e+07 (the default); expected ≤ 50000 [s], or raise " \
           "--max-steps" in line, line


def test_the_probe_names_the_files_max_steps(tmp_path: Path) -> None:
    """dopri5's probe projects the run's steps from its first 0.1 s: over the file's limit it
    refuses, naming the file's setting (the probe said ``raise max_steps (--max-steps)``)."""
    path = _file(tmp_path, "max_steps = 1100\n")
    line = _error_line("simulate", "--params", str(path), "--table-speed", "2", "--method",
                       "dopri5", "--duration", "1", code=1)
    assert line.startswith("error: refused before integrating: the run would exceed the "
                           "maximum number of steps, max_steps = 1100"), line
    assert f"raise solver.max_steps ([solver] in {path})" in line, line
    assert "--max-steps" not in line, line


def test_simulate_machine_stops_at_the_files_max_steps(tmp_path: Path) -> None:
    path = _file(tmp_path, "max_steps = 100\n")
    line = _error_line("simulate", "--machine", "xy-table", "--params", str(path),
                       "--duration", "0.5", code=1)
    assert "maximum number of steps reached (steps 101," in line, line
    assert f"raise solver.max_steps ([solver] in {path})" in line, line


def test_max_steps_help_states_its_default() -> None:
    assert DEFAULT_MAX_STEPS == fd.SolverOptions().max_steps
    assert MAX_STEPS_HELP.endswith("Default: the parameter file's [solver] max_steps, else "
                                   "50 000 000.")
    result = runner.invoke(app, ["simulate", "--help"], env={"COLUMNS": "200"})
    assert " ".join(MAX_STEPS_HELP.split()) in " ".join(result.output.split())


# ------------------------------------------------------------------ 2: output_interval


@pytest.mark.parametrize(("interval", "gives"), [(0.5, 1), (0.2, 2), (0.1, 3), (0.05, 5)])
def test_an_output_interval_too_long_for_the_summary_is_refused_before_the_run(
        tmp_path: Path, no_run: None, interval: float, gives: int) -> None:
    path = _file(tmp_path, f"output_interval = {interval}\n")
    line = _error_line("simulate", "--params", str(path), "--table-speed", "2", "--duration",
                       "0.2")
    assert line == (f"error: solver.output_interval = {interval}: expected ≤ duration/15 = "
                    f"0.0133 [s], or a run of at least {15 * interval:g} s: the summary takes "
                    "at least 16 samples, one at t = 0 and one per output interval (0.2 s at "
                    f"{interval:g} s gives {gives}) ([solver] in {path})"), line


def test_a_run_too_short_for_its_summary_is_refused_naming_the_duration(no_run: None) -> None:
    line = _error_line("simulate", "--table-speed", "2", "--duration", "0.01")
    assert line == ("error: --duration = 0.01 [s]: expected ≥ 0.015 [s], 15 output intervals "
                    "of 0.001 s (the default output_interval): the summary takes at least 16 "
                    "samples, one at t = 0 and one per output interval (0.01 s at 0.001 s "
                    "gives 11)"), line


def test_the_summary_samples_are_the_trace_analyses_minimum() -> None:
    assert budget.SUMMARY_SAMPLES == trace_input.MIN_SAMPLES


def test_the_api_refuses_an_interval_longer_than_the_run(no_integration: None) -> None:
    """A Result without a sample, whose summary raised numpy's ``attempt to get argmax of an
    empty sequence``: refused before integrating, naming the API's field."""
    with pytest.raises(ParameterError) as err:
        fd.simulate(_system(), fd.ConstantSpeed(2e-3), 0.2,
                    options=fd.SolverOptions(output_interval=0.5))
    assert err.value.field == "options.output_interval" and err.value.value == 0.5
    assert str(err.value).startswith("options.output_interval = 0.5: expected ≤ the run's "
                                     "duration, 0.2 [s], or a run of at least 0.5 s: ")
    assert "its summary takes 16 samples, an interval ≤ duration/15 = 0.0133 s" \
        in str(err.value)


def test_the_api_names_the_files_interval(tmp_path: Path, no_integration: None) -> None:
    path = _file(tmp_path, "output_interval = 0.5\n")
    with pytest.raises(ParameterError) as err:
        fd.simulate(_system(load(path)), fd.ConstantSpeed(2e-3), 0.2)
    assert err.value.field == "solver.output_interval"
    assert str(err.value).endswith(f"([solver] in {path})")


def test_a_run_shorter_than_one_output_interval_is_refused(no_integration: None) -> None:
    """0.4 ms at the default 1-ms interval rounded to a run of no length, without a sample."""
    with pytest.raises(ParameterError) as err:
        fd.simulate(_system(), fd.ConstantSpeed(2e-3), 0.0004)
    assert str(err.value).startswith("duration = 0.0004: expected ≥ 0.001 [s], 1 output "
                                     "interval of 0.001 s (the default output_interval): ")


def test_the_summary_of_a_short_record_names_the_interval() -> None:
    """A Result of 5 samples: its summary said ``time: 5 samples; need at least 16``."""
    result = fd.simulate(_system(), fd.ConstantSpeed(2e-3), 0.2,
                         options=fd.SolverOptions(output_interval=0.05))
    assert result.time.size == 5
    with pytest.raises(ParameterError) as err:
        result.summary()
    assert err.value.field == "options.output_interval"
    assert "expected ≤ duration/15 = 0.0133 [s]" in str(err.value)
    # a notebook shows the run without its summary, saying why
    assert "the summary takes at least 16 samples" in result._repr_html_()


def test_a_record_of_the_summarys_samples_is_summarised() -> None:
    result = fd.simulate(_system(), fd.ConstantSpeed(2e-3), 0.015)
    assert result.time.size == budget.SUMMARY_SAMPLES
    assert result.summary()["verdict"]


# ------------------------------------------------------------------ 3: the step-limit advice


def test_creep_names_the_files_max_steps(tmp_path: Path) -> None:
    path = _file(tmp_path, "max_steps = 100\n")
    line = _error_line("creep", "--params", str(path), "--initial-duration", "2",
                       "--max-duration", "5", code=1)
    assert "maximum number of steps reached (steps 101," in line, line
    assert f"raise solver.max_steps ([solver] in {path})" in line, line
    assert "--max-steps" not in line, line


def test_a_sweeps_point_names_the_parameter_sets_max_steps(tmp_path: Path) -> None:
    """A sweep's worker reads its options back from their record, without sources: the
    setting is named from the set's table (not ``--max-steps``, which sweep has not)."""
    from feeddrive.sweep.store import SweepStore

    _file(tmp_path, "max_steps = 100\n")
    config = tmp_path / "study.toml"
    config.write_text('name = "s20"\nparams = "run.toml"\ndrive = "cdfs"\nstore = "s20.sqlite"\n'
                      '[design]\nkind = "grid"\n[quantity]\nkind = "creep-trial"\n'
                      'table_speed = 2\ninitial_duration = 2\nmax_duration = 2\nlinear = false\n'
                      '[axes]\ntable_position = [400]\n', encoding="utf-8")
    result = runner.invoke(app, ["sweep", str(config), "--workers", "1"])
    assert result.exit_code == 0, result.output
    with SweepStore(tmp_path / "s20.sqlite") as store:
        (_, _, _, value), = store.rows("s20")
    assert value is not None
    error = str(value["error"])
    assert "maximum number of steps reached (steps 101," in error, error
    assert "raise solver.max_steps ([solver]" in error and "--max-steps" not in error, error


def test_a_limit_given_in_python_keeps_the_general_advice() -> None:
    system = _system()
    with pytest.raises(SimulationError) as err:
        fd.simulate(system, fd.ConstantSpeed(2e-3), 0.2, options=fd.SolverOptions(max_steps=50))
    assert str(err.value).endswith(FAILURE_ADVICE[dopri5.STATUS_MAX_STEPS])
    assert FAILURE_ADVICE[dopri5.STATUS_MAX_STEPS].startswith(
        "raise max_steps (options.max_steps, a [solver] table's max_steps, or --max-steps "
        "where a command takes it)")


# ------------------------------------------------------------------ 4: the memory refusal


def test_the_memory_refusal_names_the_files_interval(tmp_path: Path, no_run: None) -> None:
    path = _file(tmp_path, "output_interval = 1e-12\n")
    line = _error_line("simulate", "--params", str(path), "--table-speed", "2", "--duration",
                       "0.2")
    assert line.startswith("error: --duration = 0.2 [s]: 2e+11 output samples (one per 1e-12 "
                           "s) would need about "), line
    assert line.endswith(f"shorten the duration [s] or raise solver.output_interval ([solver] "
                         f"in {path})"), line
    assert "from Python" not in line


def test_the_engines_memory_refusal_names_the_files_interval(tmp_path: Path,
                                                             no_integration: None) -> None:
    path = _file(tmp_path, "output_interval = 1e-12\n")
    with pytest.raises(ParameterError) as err:
        fd.simulate(_system(load(path)), fd.ConstantSpeed(2e-3), 0.2)
    assert err.value.field == "duration"
    assert str(err.value).endswith(f"raise solver.output_interval ([solver] in {path})")


def test_the_machines_memory_refusal_names_the_files_interval(tmp_path: Path,
                                                              no_run: None) -> None:
    """``simulate --machine`` checks the memory without the options: those in force name it."""
    path = _file(tmp_path, "output_interval = 1e-12\n")
    line = _error_line("simulate", "--machine", "xy-table", "--params", str(path),
                       "--duration", "0.2")
    assert line.endswith(f"raise solver.output_interval ([solver] in {path})"), line


def test_the_memory_refusal_in_python_names_the_field(no_integration: None) -> None:
    with pytest.raises(ParameterError) as err:
        fd.simulate(_system(), fd.ConstantSpeed(2e-3), 0.2,
                    options=fd.SolverOptions(output_interval=1e-12))
    assert str(err.value).endswith("shorten the duration [s] or raise options.output_interval")


# ------------------------------------- 1 (continued): the other commands with --max-steps


def test_positioning_honours_the_files_max_steps(tmp_path: Path) -> None:
    """``positioning --max-steps`` had the fixed default too (50 000 000, layered over the
    file): with ``[solver] max_steps = 100`` the run went to the end; now it stops at step 101
    and names the file's setting."""
    params = _file(tmp_path, "max_steps = 100\n", "ms.toml")
    result = runner.invoke(app, ["positioning", "--params", str(params), "--count", "3",
                                 "--span", "100,120", "--dwell", "0.5", "--overshoot", "1"])
    assert result.exit_code == 1, result.output
    assert "maximum number of steps reached (steps 101," in result.output
    assert f"raise solver.max_steps ([solver] in {params})" in " ".join(result.output.split())


@pytest.mark.parametrize("command", ["simulate", "circular", "positioning"])
def test_every_max_steps_option_names_the_file_first(command: str) -> None:
    """The three commands with ``--max-steps`` share its help (``cli._solver.max_steps_help``)
    and none has a default of its own."""
    import typer.main

    commands = typer.main.get_command(app).commands  # type: ignore[attr-defined]
    option = next(p for p in commands[command].params if "--max-steps" in p.opts)
    assert option.default is None
    assert option.help is not None and option.help.endswith(
        "Default: the parameter file's [solver] max_steps, else 50 000 000.")


def test_a_command_is_told_the_step_limit_it_can_raise(monkeypatch: pytest.MonkeyPatch) -> None:
    """The engine's general advice names Python's field, a table's and the option; a command
    line user gets the last two, once each (``cli._common.run_outcome``)."""
    import io

    import typer
    from rich.console import Console

    from feeddrive.cli import _common

    buffer = io.StringIO()
    # a console of its own: setting the shared one's ``file`` would pin it to this test's
    # stderr after the undo (rich's ``file`` reads sys.stderr only while unset)
    monkeypatch.setattr(_common, "err_console", Console(file=buffer, width=400))
    with pytest.raises(typer.Exit), _common.run_outcome(None):
        raise SimulationError(f"stopped; {FAILURE_ADVICE[dopri5.STATUS_MAX_STEPS]}")
    text = " ".join(buffer.getvalue().split())
    assert "options.max_steps" not in text and text.count("--max-steps") == 1
    assert "raise max_steps (a [solver] table's max_steps, or --max-steps" in text
