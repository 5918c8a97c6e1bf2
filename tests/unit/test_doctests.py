"""The docstrings' Examples, run as doctests on the package as it is installed (issue 41 item
10): every module of ``feeddrive`` is imported by name and its docstrings' examples run, so a
wheel install (as CI's) and an editable one run the same code — collecting ``src/feeddrive``
beside an installed copy would import each module twice."""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import feeddrive

#: every module of the package (``__main__`` would run the CLI when imported)
MODULES = sorted(m.name for m in pkgutil.walk_packages(feeddrive.__path__, "feeddrive.")
                 if not m.name.endswith("__main__"))


def _tests(name: str) -> list[doctest.DocTest]:
    module = importlib.import_module(name)
    found = doctest.DocTestFinder().find(module, name)
    return [t for t in found if t.examples]


@pytest.mark.parametrize("name", MODULES)
def test_the_examples_of_each_module_run(name: str) -> None:
    runner = doctest.DocTestRunner(optionflags=doctest.NORMALIZE_WHITESPACE)
    for test in _tests(name):
        runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.failed == 0, f"{name}: {result.failed} of {result.attempted} examples failed"


def test_the_api_pages_examples_are_found() -> None:
    # the finder sees the Examples the API pages promise (test_examples.py): a finder that
    # finds nothing would pass every module above
    names = {t.name for t in _tests("feeddrive.engine.simulate")}
    assert "feeddrive.engine.simulate.simulate" in names
    assert any(t.name.endswith("export_fmu") for t in _tests("feeddrive.fmu"))
