"""Issue 41 item 10: the API pages had no Examples (0 of 10; python-control and pvlib always
have them).  Each page's main functions carry an Examples section that makes a real call and
prints a number; the README's test command runs them as doctests (tests/unit/test_doctests.py,
on the installed package)."""

from __future__ import annotations

import doctest
import importlib
import re
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

# API page (docs/api/*.rst) → its main functions, by where they are defined
MAIN = {
    "feeddrive": ["feeddrive.engine.simulate.simulate", "feeddrive.engine.result.Result.to_pandas",
                  "feeddrive.model.reference.trapezoid", "feeddrive.model.reference.stepdown",
                  "feeddrive.analysis.creep_window.creep_metrics"],
    "parameters": ["feeddrive.parameters.preset", "feeddrive.parameters.toml_io.loads"],
    "model": ["feeddrive.model.reference.stepdown"],
    "analysis": ["feeddrive.analysis.trace.analyze_trace",
                 "feeddrive.analysis.creep_window.creep_metrics"],
    "linear": ["feeddrive.analysis.linear.loop_analysis",
               "feeddrive.analysis.linear.stability_band"],
    "data": ["feeddrive.io.measured.read_position_trace"],
    "sweep": ["feeddrive.sweep.executors.run_sweep"],
    "apps": ["feeddrive.explore.server.serve_in_thread"],
    "export": ["feeddrive.fmu.export_fmu"],
    "machine": ["feeddrive.machine.machine_from_dict"],
}


def _object(dotted: str) -> object:
    parts = dotted.split(".")
    for cut in range(len(parts) - 1, 0, -1):
        try:
            obj: object = importlib.import_module(".".join(parts[:cut]))
        except ModuleNotFoundError:
            continue
        for name in parts[cut:]:
            obj = getattr(obj, name)
        return obj
    raise AssertionError(dotted)


def test_every_api_page_is_covered() -> None:
    pages = {p.stem for p in (ROOT / "docs" / "api").glob("*.rst")} - {"index"}
    assert pages == set(MAIN)


@pytest.mark.parametrize("dotted", sorted({d for names in MAIN.values() for d in names}))
def test_main_function_has_an_example_that_prints_a_number(dotted: str) -> None:
    doc = _object(dotted).__doc__ or ""
    assert re.search(r"^\s*Examples\n\s*--------\n", doc, re.M), dotted
    examples = doctest.DocTestParser().get_examples(doc)
    calls = [e for e in examples if "(" in e.source]
    printed = [e.want for e in examples if re.search(r"\d", e.want)]
    assert calls and printed, dotted


def test_pytest_collects_the_doctests_of_the_package() -> None:
    """The README's test command (``pytest -n 2``, no paths) runs them: test_doctests.py, in
    the test paths, runs every module's Examples."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    ini = config["tool"]["pytest"]["ini_options"]
    assert "tests" in ini["testpaths"]
    from test_doctests import MODULES

    for dotted in {d for names in MAIN.values() for d in names}:
        owner = _object(dotted)
        module = getattr(owner, "__module__", None) or dotted
        assert module in MODULES, dotted
