"""An error estimate whose tighter (shadow) run would fall below a floor is refused naming the
setting the user gave, in the unit it was given in (outside check 35, defect 2).

``--position-tolerance 1e-21 --error-estimate`` was answered ``options.position_tolerance =
9.999999999999999e-26: expected a finite value 1e-24 … 1e-06 [m]`` — an internal field, in SI,
with a value nobody typed: ``engine.error_estimate.tightened`` checked the tighter run's rtol
against ``MIN_RELATIVE`` only, not the absolute tolerances (``MIN_ABSOLUTE``) nor
``accuracy`` (``MIN_ACCURACY``).  One rule (``tightening_refused``) now serves the estimate,
the fit's tightening and ``analysis.critical.shadow_possible`` (the creep searches).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.analysis.critical import shadow_possible
from feeddrive.cli import app
from feeddrive.engine import error_estimate
from feeddrive.engine import options as opt
from feeddrive.engine import simulate as sim_module
from feeddrive.engine.error_estimate import tightened
from feeddrive.parameters import ParameterError

runner = CliRunner()


def _never(*_: Any, **__: Any) -> Any:
    raise AssertionError("a simulation started although the estimate was refused")


@pytest.fixture
def no_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """Any run fails the test: the refusal comes before any work."""
    monkeypatch.setattr(sim_module.Simulation, "run", _never)


def _error_line(*args: str) -> str:
    """The one line a refused command prints on stderr (exit status 2, nothing on stdout)."""
    result = runner.invoke(app, list(args))
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output and not result.stdout.strip(), result.output
    lines = [ln for ln in result.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    return lines[0]


def _solver_file(tmp_path: Path, body: str) -> str:
    path = tmp_path / "set.toml"
    path.write_text(f'extends = "wang2021"\nname = "s19"\n[solver]\n{body}\n', encoding="utf-8")
    return str(path)


PREFIX = "error: --error-estimate: needs a run 10× tighter than "


@pytest.mark.parametrize(("args", "expected"), [
    (["--position-tolerance", "1e-21"],
     "position tolerance 1e-21 mm, below 1e-21 mm: give a looser --position-tolerance "),
    (["--speed-tolerance", "1e-16"],
     "speed tolerance 1e-16 mm/s, below 1e-16 mm/s: give a looser --speed-tolerance "),
    (["--current-tolerance", "1e-17"],
     "current tolerance 1e-17 A, below 1e-17 A: give a looser --current-tolerance "),
    (["--accuracy", "1e-8"], "accuracy 1e-8, below 1e-8: give a looser --accuracy "),
    # the one refused before, unchanged but for naming the option to loosen
    (["--rtol", "1e-14"], "rtol 1e-14, below 1e-14: give a looser --rtol "),
], ids=["position", "speed", "current", "accuracy", "rtol"])
def test_a_shadow_below_a_floor_is_refused_naming_the_option_in_its_unit(
        no_run: None, args: list[str], expected: str) -> None:
    line = _error_line("simulate", "--table-speed", "1", "--duration", "1", *args,
                       "--error-estimate")
    assert line.startswith(PREFIX + expected), line
    assert line.endswith("to estimate its error"), line
    for internal in ("options.", "[m]", "[m/s]", "e-25", "e-26", "e-20", "e-18", "e-09"):
        assert internal not in line, line


def test_a_files_accuracy_under_the_command_lines_rtol_names_the_files_setting(
        no_run: None, tmp_path: Path) -> None:
    """``[solver] accuracy = 1e-8`` with ``--rtol 1e-6``: the tighter run's accuracy (on the
    default absolute tolerances) would be 1e-9; the file's setting is named, not
    ``options.accuracy = 1e-09``."""
    path = _solver_file(tmp_path, "accuracy = 1e-8")
    line = _error_line("simulate", "--table-speed", "1", "--duration", "1", "--params", path,
                       "--rtol", "1e-6", "--error-estimate")
    assert line.startswith(PREFIX + "accuracy 1e-8, below 1e-8: give a looser "
                           f"solver.accuracy ([solver] in {path}) to estimate its error"), line
    assert "options.accuracy" not in line and "1e-09" not in line, line


def test_a_files_absolute_tolerance_is_named_in_si_as_the_file_gives_it(
        no_run: None, tmp_path: Path) -> None:
    path = _solver_file(tmp_path, "position_tolerance = 1e-24")
    line = _error_line("simulate", "--table-speed", "1", "--duration", "1", "--params", path,
                       "--error-estimate")
    assert line.startswith(PREFIX + "position tolerance 1e-24 m, below 1e-24 m: give a looser "
                           f"solver.position_tolerance ([solver] in {path})"), line


def test_the_api_is_refused_as_the_estimate_not_as_an_internal_field(no_run: None) -> None:
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    for options in (fd.SolverOptions(current_tolerance=1e-17),
                    fd.SolverOptions(speed_tolerance=5e-19),
                    fd.SolverOptions(accuracy=5e-8)):
        with pytest.raises(ParameterError) as caught:
            fd.simulate(system, fd.ConstantSpeed(2e-3), 0.2, options=options,
                        error_estimate=True)
        assert caught.value.field == "error_estimate", caught.value
        assert "needs a run 10× tighter than" in caught.value.message


#: settings at, just above and ten times their floors (the division's rounding: 1e-16 A ÷ 10
#: is 9.999999999999999e-18, which is the floor 1e-17 A and not below it)
FLOORS = {"rtol": opt.MIN_RELATIVE, **opt.MIN_ABSOLUTE, "accuracy": opt.MIN_ACCURACY}
CASES = {
    **{f"{name}-{k:g}x-floor": fd.SolverOptions(**{name: FLOORS[name] * k})
       for name in FLOORS for k in (1.0, 5.0, 10.0)},
    "dopri5-explicit": fd.SolverOptions(rtol=1e-7, current_tolerance=1e-16, method="dopri5"),
    "defaults": fd.SolverOptions(),
}


@pytest.mark.parametrize("options", CASES.values(), ids=CASES.keys())
def test_one_rule_serves_the_estimate_and_the_creep_searches(options: fd.SolverOptions) -> None:
    """``shadow_possible`` (``feeddrive creep``, ``reproduce``) and the estimate's refusal
    can't disagree: the shadow is possible exactly where ``tightened`` makes its options, at
    ten times a floor or more (the floor itself and five times it leave none), and a refusal
    is the estimate's, never an internal field's."""
    try:
        shadow, refused = tightened(options), None
    except ParameterError as err:
        shadow, refused = None, err
    assert shadow_possible(options) is (refused is None)
    given = {name: getattr(options, name) for name in FLOORS
             if name != "accuracy" and getattr(options, name) is not None}
    given["accuracy"] = options.accuracy  # (every case leaves a default tolerance: it acts)
    possible = all(v >= 10 * FLOORS[n] * (1 - 1e-9) for n, v in given.items())
    assert (refused is None) is possible, (given, refused)
    if refused is not None:
        assert refused.field == "error_estimate", refused
        assert refused.message.startswith("needs a run 10× tighter than "), refused
        assert error_estimate.tightening_refused(options) == refused.message
    else:
        assert shadow is not None
        for name in FLOORS:
            value = getattr(shadow, name)
            assert value is None or value >= FLOORS[name]
        assert error_estimate.tightening_refused(options) is None
