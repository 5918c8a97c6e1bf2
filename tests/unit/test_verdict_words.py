"""One verdict vocabulary (issue 19 item 6, issue 24 item 4): the window rule and the
limit-cycle rule answer in the words of ``feeddrive.analysis.verdict_words``, the modules that
decide write no verdict word of their own, and docs/model.md explains each word in the
module's own line."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import numpy as np

from feeddrive.analysis import verdict_words as words
from feeddrive.analysis.creep_window import creep_metrics
from feeddrive.analysis.cycle_verdict import trace_verdict

ROOT = Path(__file__).resolve().parents[2]
DECIDERS = ("creep_window.py", "cycle_verdict.py", "critical.py")


def test_docs_explain_every_verdict_word_as_the_module_does() -> None:
    text = (ROOT / "docs" / "model.md").read_text(encoding="utf-8")
    listed = dict(re.findall(r"^- \*\*([a-z-]+)\*\*: (.+)$", text, re.M))
    assert listed == words.MEANING


def test_the_rules_answer_in_the_vocabulary() -> None:
    t = np.linspace(0.0, 12.0, 12001)
    smooth = np.full(t.size, 1e-3)
    stick = 1e-3 * np.maximum(0.0, 2.0 * np.sin(2 * np.pi * 2.0 * t))  # stops every cycle
    assert creep_metrics(t, smooth, 1e-3).verdict == words.SMOOTH
    assert creep_metrics(t, stick, 1e-3).verdict == words.CREEPING
    assert creep_metrics(t, 50.0 * smooth, 1e-3).verdict == words.UNSTABLE
    assert trace_verdict(t, smooth, 1e-3).kind == words.SMOOTH
    assert trace_verdict(t, stick, 1e-3).kind == words.STICK_SLIP
    assert set(words.WINDOW_VERDICTS) | set(words.KINDS) | {words.UNSTABLE} == set(words.MEANING)
    assert set(words.CREEPING_KINDS) < set(words.KINDS)


def test_deciding_modules_write_no_verdict_word_of_their_own() -> None:
    """A verdict word compared or passed as a value (not inside a message) is a name from the
    vocabulary module, so the two rules cannot drift apart again."""
    offenders = []
    for name in DECIDERS:
        tree = ast.parse((ROOT / "src" / "feeddrive" / "analysis" / name).read_text("utf-8"))
        for node in ast.walk(tree):
            values: list[ast.expr] = []
            if isinstance(node, ast.Compare):
                values = [node.left, *node.comparators]
            elif isinstance(node, ast.Call):
                values = [*node.args, *(k.value for k in node.keywords)]
            elif isinstance(node, ast.Return) and node.value is not None:
                values = [node.value]
            for v in values:
                elems = v.elts if isinstance(v, ast.Tuple | ast.List | ast.Set) else [v]
                offenders += [f"{name}:{e.lineno} {e.value!r}" for e in elems
                              if isinstance(e, ast.Constant) and e.value in words.MEANING]
    assert offenders == []
