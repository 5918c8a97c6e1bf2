"""The ``[solver]`` tables of a command's files: an outside check's five defects, a test (or
more) per defect.

1. ``sweep CONFIG --rtol`` was refused when the configuration's ``accuracy`` lay over explicit
   tolerances in its ``params`` file (the replaced tolerances were still counted as given);
2. ``calibrate --out`` wrote a ``[solver]`` table that was neither the file's nor the run's
   (``--accuracy 0.5`` over ``accuracy = 0.1`` saved, ``--rtol`` not);
3. the command line read a ``[solver]`` table with checks of its own, in worse words than
   :func:`feeddrive.parameters.load` (no "did you mean", a quoted number as a range error);
4. the tolerances', ``--accuracy``'s and ``--rosenbrock``'s help did not name the file's
   table as their first default;
5. docs/parameters.md said every command prints ``SolverOptions.describe()``; docs/model.md
   and the README left simulating commands out of their lists.
"""

from __future__ import annotations

import inspect
import json
import re
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
import typer.main
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.cli import app
from feeddrive.cli._solver import OPTIONS, carried_tables, command_tables, solver_options
from feeddrive.engine import options as opt
from feeddrive.engine import simulate as sim_module
from feeddrive.parameters import ParameterError
from feeddrive.parameters.toml_io import read_toml_file

runner = CliRunner()
ROOT = Path(__file__).resolve().parents[2]

#: s2.toml of the outside check: explicit tolerances (SI) and a step cap
TOLERANCES = ('method = "dopri5"\nrtol = 1e-7\nposition_tolerance = 1e-12\n'
              "speed_tolerance = 1e-9\nmax_step = 5e-4\n")


def _file(path: Path, table: str = "") -> Path:
    path.write_text('extends = "wang2021"\n' + (f"\n[solver]\n{table}" if table else ""),
                    encoding="utf-8")
    return path


def _sweep_config(tmp_path: Path, table: str) -> Path:
    """A one-point sweep of ``s2.toml`` that simulates nothing (loop margins)."""
    _file(tmp_path / "s2.toml", TOLERANCES)
    config = tmp_path / "sw9.toml"
    config.write_text('params = "s2.toml"\nstore = "sw9.sqlite"\n'
                      '[quantity]\nkind = "loop-margins"\ntable_speed = 1.0\n'
                      f"[axes]\ntable_position = [400]\n[solver]\n{table}", encoding="utf-8")
    return config


def _never(*_: Any, **__: Any) -> Any:
    raise AssertionError("a simulation started although the input was refused")


def _one_line(result: Any, code: int = 2) -> str:
    assert result.exit_code == code, result.output
    lines = [ln for ln in result.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), result.output
    return str(lines[0])


def _commands() -> dict[str, Any]:
    """Every command of the CLI by its path (``"export fmu"``; typer's own click: a group
    known by its ``commands``)."""
    found: dict[str, Any] = {}

    def walk(command: Any, path: str) -> None:
        if hasattr(command, "commands"):
            for name, sub in command.commands.items():
                walk(sub, f"{path} {name}".strip())
        else:
            found[path] = command

    walk(typer.main.get_command(app), "")
    return found


def _simulating() -> dict[str, Any]:
    """The commands that take the integrator settings (``--accuracy``)."""
    return {path: c for path, c in _commands().items()
            if any("--accuracy" in p.opts for p in c.params)}


def _help(*command: str) -> str:
    return " ".join(runner.invoke(app, [*command, "--help"], terminal_width=400).output.split())


# ------------------------------------------------------------------ 1: sweep --rtol


def test_sweep_rtol_over_a_configuration_accuracy_that_replaced_the_files_tolerances(
        tmp_path: Path) -> None:
    """``sweep sw9.toml --rtol 1e-9`` was refused: ``solver.accuracy = 0.5: given with
    solver.rtol ([solver] in sw9.toml)``, s2.toml's rtol (replaced by sw9's accuracy) still
    counted as given.  It runs at the command line's rtol and the configuration's accuracy."""
    config = _sweep_config(tmp_path, "accuracy = 0.5\n")
    result = runner.invoke(app, ["sweep", str(config), "--workers", "1", "--rtol", "1e-9",
                                 "--json"])
    assert result.exit_code == 0, result.output
    described = json.loads(result.output)["integrator"]
    assert "rtol 1e-9 (from --rtol)" in described
    assert f"accuracy 0.5 (from [solver] in {config})" in described
    assert f"dopri5 (adaptive Dormand–Prince 5(4)) (from [solver] in {tmp_path / 's2.toml'})" \
        in described


@pytest.mark.parametrize(("sweep_table", "file_table", "cli"), [
    ("accuracy = 0.5\n", None, {"rtol": (1e-9, "--rtol")}),  # the outside check's case
    ("accuracy = 0.5\n", None, {"accuracy": (1.0, "--accuracy")}),
    ("accuracy = 0.5\n", None, {"speed_tolerance": (1e-6, "--speed-tolerance")}),
    (None, "accuracy = 0.1\n", {"rtol": (1e-8, "--rtol")}),
    (None, "accuracy = 0.1\n", {"accuracy": (1.0, "--accuracy")}),
    (None, TOLERANCES, {"accuracy": (0.5, "--accuracy")}),
    (None, TOLERANCES, {"rtol": (1e-9, "--rtol")}),
], ids=["sweep-accuracy+rtol", "sweep-accuracy+accuracy1", "sweep-accuracy+speed",
        "file-accuracy+rtol", "file-accuracy+accuracy1", "file-tolerances+accuracy",
        "file-tolerances+rtol"])
def test_the_carried_table_gives_a_worker_the_commands_options(
        tmp_path: Path, sweep_table: str | None, file_table: str | None,
        cli: dict[str, tuple[Any, str]]) -> None:
    """The set a command's file gives carries one valid table (:func:`carried_tables`) under
    which a run takes the command's options, in this process (options with their sources)
    and in a worker (options from their record, without sources)."""
    if sweep_table is not None:
        kwargs: dict[str, Any] = {"config": str(_sweep_config(tmp_path, sweep_table))}
        carrier = str(tmp_path / "s2.toml")
    else:
        carrier = str(_file(tmp_path / "s1.toml", file_table or ""))
        kwargs = {"params_file": carrier}
    tables = command_tables(kwargs)
    options = solver_options(cli, tables=tables)
    carried = carried_tables(options, tables)[carrier]
    params = replace(fd.preset("wang2021"), solver=carried)
    here = sim_module.run_options(params, options)
    worker = sim_module.run_options(params, fd.SolverOptions.from_record(options.record()))
    assert here.record() == options.record()
    assert worker.record() == options.record()


# ------------------------------------------------------------------ 2: calibrate --out


@pytest.mark.parametrize(("table", "args", "written"), [
    ('accuracy = 0.1\nrosenbrock = "rodas4"\n', ["--accuracy", "0.5"],
     {"accuracy": 0.1, "rosenbrock": "rodas4"}),
    ('accuracy = 0.1\nrosenbrock = "rodas4"\n', ["--rtol", "1e-8"],
     {"accuracy": 0.1, "rosenbrock": "rodas4"}),
    ('accuracy = 0.1\nrosenbrock = "rodas4"\n', [], {"accuracy": 0.1, "rosenbrock": "rodas4"}),
    (TOLERANCES, ["--accuracy", "0.5", "--rosenbrock", "rodas5p"],
     {"method": "dopri5", "rtol": 1e-7, "position_tolerance": 1e-12,
      "speed_tolerance": 1e-9, "max_step": 5e-4}),
    ("", ["--accuracy", "0.5"], None),
], ids=["accuracy", "rtol", "none", "tolerances", "no-table"])
def test_calibrate_out_writes_the_input_files_own_table(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path, table: str, args: list[str],
        written: dict[str, Any] | None) -> None:
    """``calibrate --params s1.toml --accuracy 0.5 --out cal.toml`` wrote ``accuracy = 0.5``
    (and with ``--rtol 1e-8`` kept 0.1): the written file carries the input file's own
    ``[solver]`` table as read; the command line's settings are the run's, never saved.  The
    fit is replaced by a stand-in (the rule is the written file's, not the search's)."""
    import feeddrive.analysis.calibrate as calibration

    ran: list[Any] = []

    def fit(params: Any, target: Any, unknown: Any, **_: Any) -> Any:
        ran.append(opt.current())
        achieved = SimpleNamespace(to_dict=lambda: {
            "critical_speed_mm_s": 1.56, "display": "1.56 mm/s", "kind": "stick-slip",
            "bands": []})
        return SimpleNamespace(parameters=params.replace_path(unknown.path, 4321.0),
                               value=4321.0, reached=True, achieved=achieved,
                               interval=(4000.0, 4500.0), evaluations=3, reason=lambda: "")

    monkeypatch.setattr(calibration, "calibrate", fit)
    monkeypatch.setattr(sim_module.Simulation, "run", _never)
    source = _file(tmp_path / "s1.toml", table)
    out = tmp_path / "cal.toml"
    result = runner.invoke(app, ["calibrate", "--params", str(source), "--out", str(out),
                                 *args])
    assert result.exit_code == 0, result.output
    data = read_toml_file(out)
    assert data.get("solver") == written
    # the run itself took the command line's settings over the file's
    for flag, value in zip(args[::2], args[1::2], strict=True):
        name = flag.removeprefix("--")
        assert str(getattr(ran[0], name)) == value or getattr(ran[0], name) == float(value)
    # and the file reads back to the table as written
    assert {n: v for n, v, _ in fd.parameters.load(out).solver} == (written or {})


def test_calibrate_out_help_says_what_table_is_written() -> None:
    text = _help("calibrate")
    assert "with the --params file's own [solver] table as read (none from a preset)" in text
    assert "integrator settings (--accuracy, --rtol, …) are this run's, not saved" in text


# ------------------------------------------------------------------ 3: one reading


@pytest.mark.parametrize(("table", "words"), [
    ("[solver]\nrtoll = 1e-6\n", "(did you mean 'rtol'?)"),
    ('[solver]\nrtol = "1e-6"\n', "expected a number [-]"),
    ("[solver]\nmax_steps = 1.5\n", "expected a whole number"),
    ("[solver]\nmethod = 3\n", "expected text"),
    ("[solver]\naccuracy = 0.1\nrtol = 1e-8\n", "given with solver.rtol"),
    ("solver = 3\n", "expected a table [solver]"),
], ids=["unknown", "quoted-number", "count", "text", "accuracy+rtol", "not-a-table"])
def test_the_command_line_reads_a_solver_table_as_the_api_does(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path, table: str, words: str) -> None:
    """``rtoll = 1e-6`` had no "did you mean" on the command line, and ``rtol = "1e-6"`` was
    called out of range there (``expected a finite value 1e-14 … 0.1``): one line, the API's
    words, before any work."""
    monkeypatch.setattr(sim_module.Simulation, "run", _never)
    path = tmp_path / "bad.toml"
    path.write_text(('extends = "wang2021"\n' + table) if table.startswith("[") else
                    (table + 'extends = "wang2021"\n'), encoding="utf-8")
    with pytest.raises(ParameterError) as api:
        fd.parameters.load(path)
    assert words in str(api.value)
    line = _one_line(runner.invoke(app, ["simulate", "--params", str(path), "--table-speed",
                                         "1", "--duration", "0.1"]))
    # the API's refusal, which also names the file in front
    assert f"{path}: {line.removeprefix('error: ')}" == str(api.value)
    assert f"([solver] in {path})" in line, line
    assert _one_line(runner.invoke(app, ["params", "check", str(path)])) == line
    # a sweep configuration's own table is read the same way
    config = tmp_path / "sweep.toml"
    body = ('[quantity]\nkind = "loop-margins"\ntable_speed = 1.0\n'
            "[axes]\ntable_position = [400]\n")
    config.write_text('preset = "wang2021"\n' + (body + table if table.startswith("[") else
                                                 table + body), encoding="utf-8")
    swept = _one_line(runner.invoke(app, ["sweep", str(config), "--workers", "1"]))
    assert words in swept and f"([solver] in {config})" in swept, swept


# ------------------------------------------------------------------ 4: help defaults


def test_the_settings_help_names_the_files_table_before_the_default() -> None:
    """``--rtol`` said "(default 1e-06 × --accuracy …)", ``--accuracy`` named no default,
    ``--rosenbrock`` "(default rodas5p …)": none named the [solver] table that comes first."""
    defaults = {"rtol": f"{opt.DEFAULT_RTOL:g} × --accuracy",
                "position_tolerance": "scaled with the run",
                "speed_tolerance": f"{opt.SPEED_FRACTION:g} × the speed scale",
                "current_tolerance": f"{opt.CURRENT_FRACTION:g} × the current limit",
                "accuracy": f"{fd.SolverOptions().accuracy:g};",
                "rosenbrock": f"{opt.DEFAULT_ROSENBROCK};"}
    assert set(defaults) == {name for name, _, _ in OPTIONS}
    commands = _simulating()
    assert {"simulate", "sweep", "calibrate", "export fmu"} <= set(commands)
    for path in commands:
        text = _help(*path.split())
        for name, flag, _ in OPTIONS:
            if flag not in text:  # export fmu: no --rosenbrock (a test holds it)
                continue
            # the table takes SI where the option takes mm, mm/s: its unit said
            shown = {"position_tolerance": f"{name} [m]",
                     "speed_tolerance": f"{name} [m/s]"}.get(name, name)
            assert f"default: the parameter file's [solver] {shown}, else {defaults[name]}" \
                in text, (path, flag)


# ------------------------------------------------------------------ 5: the docs


def _ticked(text: str) -> set[str]:
    return set(re.findall(r"`([^`]+)`", text))


def test_the_docs_list_every_command_that_takes_the_settings() -> None:
    """docs/model.md's list left out ``validate`` (and both lists ``circular`` and
    ``positioning``), which take them."""
    commands = set(_simulating())
    model = " ".join((ROOT / "docs" / "model.md").read_text(encoding="utf-8").split())
    start = model.index("**Where the settings come from**")
    listed = _ticked(model[start:model.index("the API (", start)]) & set(_commands())
    assert listed == commands
    readme = " ".join((ROOT / "README.md").read_text(encoding="utf-8").split())
    start = readme.index("Every simulating command (")
    listed = _ticked(readme[start:readme.index(") takes", start)]) & set(_commands())
    assert listed == commands


def test_the_docs_say_which_commands_print_the_described_settings() -> None:
    """docs/parameters.md said every command prints ``SolverOptions.describe()`` as its
    ``integrator`` line: ``simulate`` prints numbers without sources, several print none."""
    text = " ".join((ROOT / "docs" / "parameters.md").read_text(encoding="utf-8").split())
    commands = _simulating()
    end = text.index("print it as their `integrator` line")
    start = text.rindex(". ", 0, end)
    printing = _ticked(text[start:end]) & set(commands)
    none_end = text.index("print none.", end)
    quiet = _ticked(text[text.rindex("; ", end, none_end):none_end]) & set(commands)
    describing = {path for path, c in commands.items()
                  if "solver.describe()" in inspect.getsource(inspect.unwrap(c.callback))}
    assert printing == describing
    assert "`simulate` prints the settings its run took, in numbers and without sources" \
        in text and "simulate" not in describing
    assert quiet == set(commands) - describing - {"simulate"}
