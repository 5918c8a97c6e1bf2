"""Issue 21: the reproduction report states the integrator its numbers rest on — method,
tolerances and step cap — read from the code, not written as a literal."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import feeddrive.reproduce as reproduce_pkg
from feeddrive.engine import options as opt
from feeddrive.engine.simulate import METHODS, SolverOptions
from feeddrive.reproduce.report import (
    header_text,
    integrator_text,
    settings_markdown,
    settings_section,
)
from feeddrive.reproduce.studies import StudySettings
from feeddrive.solvers import modes, switching

_DEFAULT = opt.ROSENBROCKS[opt.DEFAULT_ROSENBROCK]


def test_the_default_label_names_the_method_its_cap_and_tolerances() -> None:
    options = SolverOptions()
    text = options.describe()
    assert text.startswith(f"{options.method} (")
    for piece in (f"h·|λ| ≤ {modes.H_LAMBDA:g}",
                  f"damping ratio < {modes.ZETA_LIGHT:g}",
                  f"a {_DEFAULT.label} step counted as {_DEFAULT.cost:g} DOPRI5 steps",
                  f"rtol {opt._num(opt.DEFAULT_RTOL)}",
                  f"positions {opt._num(opt.POSITION_TIME)} s × V",
                  f"speeds {opt._num(opt.SPEED_FRACTION)} × V",
                  f"currents {opt._num(opt.CURRENT_FRACTION)} × the current limit",
                  f"deflections {opt._num(opt.DEFLECTION_FRACTION)} × their onset deflection",
                  f"output every {options.output_interval:g} s",
                  # DOPRI5's continuous extension, order 4; RODAS4's 3, RODAS5P's 4
                  f"continuous extension of order 4 (DOPRI5 steps) / "
                  f"{ {'RODAS4': 3, 'RODAS5P': 4}[_DEFAULT.label]} ({_DEFAULT.label} steps)"):
        assert piece in text, piece
    # the compiled dense driver takes its cap from the modes module, as the label does
    source = "\n".join(switching.template_sources())
    assert "ZETA_LIGHT as MODAL_ZETA_LIGHT" in source and "H_LAMBDA as MODAL_H_LAMBDA" in source
    assert "from feeddrive.solvers.modes import" in source


def test_the_label_follows_the_code(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(modes, "H_LAMBDA", 0.123)
    assert "h·|λ| ≤ 0.123 " in integrator_text()
    # the default Rosenbrock method's cost constant (RODAS5P_COST since 2026-12-05)
    monkeypatch.setattr(switching, f"{_DEFAULT.label}_COST", 4.0)
    assert f"a {_DEFAULT.label} step counted as 4 DOPRI5 steps" in integrator_text()
    assert "rtol 1e-8" in SolverOptions(rtol=1e-8).describe()
    assert "every output a step end" in SolverOptions(method="dopri5").describe()
    assert "steps ≤ 0.001 s" in SolverOptions(method="dopri5").describe()
    # dopri5's cap follows the accuracy (1 ms × accuracy^(1/5) = 0.631 ms at 0.1)
    assert "steps ≤ 0.000631 s" in SolverOptions(method="dopri5", accuracy=0.1).describe()
    across = "friction reversals stepped across (locate_reversals off)"
    assert across in SolverOptions(method="dopri5", locate_reversals=False).describe()
    assert across not in SolverOptions(method="dopri5").describe()
    assert "steps ≤ 0.0005 s" in SolverOptions(method="modal", max_step=5e-4).describe()
    sampled = "every sample of a sampled profile a step end"
    assert sampled in SolverOptions(sample_steps=True).describe()
    assert sampled not in SolverOptions().describe()


@pytest.mark.parametrize("method", METHODS)
def test_every_method_is_described(method: str) -> None:
    assert SolverOptions(method=method).describe().startswith(f"{method} (")


def test_the_report_settings_state_it() -> None:
    """Stated under Settings, moved there as it is from the report's top (issue 41 item 1:
    the report opened with solver internals)."""
    text = integrator_text()
    assert text == f"Integrator of every run: {SolverOptions().describe()}."
    results = {"wall_time_s": 12.0, "studies_reused": 0, "studies_total": 84}
    assert "Integrator" not in header_text(results, "2026-12-02 01:00 UTC")
    assert settings_section(StudySettings()).startswith(text + "\n\n")
    assert f"* integrator: {SolverOptions().describe()}" in settings_markdown(StudySettings())


def test_no_study_runs_other_options() -> None:
    # the label is the default's: it holds only while no study passes its own options
    root = Path(reproduce_pkg.__file__).parent
    for path in sorted(root.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.Call):
                continue
            assert not any(k.arg == "options" for k in node.keywords), (path.name, node.lineno)
            name = getattr(node.func, "id", getattr(node.func, "attr", ""))
            if name == "SolverOptions":
                assert not node.args and not node.keywords, (path.name, node.lineno)


def test_the_label_gives_lengths_and_speeds_in_the_command_lines_units() -> None:
    """The sentence is read beside the command line's options, which take tolerances in mm
    and mm/s (``feeddrive.cli._solver.CLI_UNITS``): 1e-9 m is written 1e-6 mm."""
    from feeddrive.cli import _solver
    from feeddrive.engine.options import RunScales

    assert _solver.CLI_UNITS["position_tolerance"][0] == "mm"
    text = SolverOptions(position_tolerance=1e-9, speed_tolerance=2e-8).describe()
    assert "positions 1e-6 mm" in text and "speeds 2e-5 mm/s" in text
    assert " m," not in text and " m/s" not in text
    scaled = SolverOptions().describe_tolerances(RunScales(table_speed=1e-3, speed=0.017,
                                                           current=10.0))
    # position 1e-10 s × 1 mm/s, speed 1e-5 × 1 mm/s, scales in mm/s
    assert "1e-10 mm (positions)" in scaled and "1e-5 mm/s (speeds)" in scaled
    assert "table 1 mm/s, motors 17 mm/s" in scaled
