"""Every script under benchmarks/ parses its command line with argparse, so ``--help`` prints
its usage and stops (a script that read ``sys.argv`` by hand ran the whole benchmark on
``--help`` and overwrote its recorded results)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SCRIPTS = sorted((Path(__file__).parents[2] / "benchmarks").glob("*.py"))


def _calls(tree: ast.AST) -> set[str]:
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            f = node.func
            names.add(f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", ""))
    return names


def test_there_are_scripts() -> None:
    assert len(SCRIPTS) >= 20


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_a_script_parses_its_arguments_with_argparse(script: Path) -> None:
    tree = ast.parse(script.read_text())
    assert {"ArgumentParser", "parse_args"} <= _calls(tree), script.name
