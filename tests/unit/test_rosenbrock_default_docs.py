"""Where the docs name the default Rosenbrock method of ``modal`` and ``auto``, they name the
one the code uses (``feeddrive.engine.options.DEFAULT_ROSENBROCK``): docs/model.md's RODAS5P
paragraph and the tableaux' module docstring (which once called RODAS5P the default while
RODAS4 was)."""

from __future__ import annotations

from pathlib import Path

from feeddrive.engine import options
from feeddrive.solvers import tableaux

ROOT = Path(__file__).resolve().parents[2]


def test_model_md_names_the_default_rosenbrock_method() -> None:
    text = (ROOT / "docs" / "model.md").read_text(encoding="utf-8")
    paragraph = text[text.index("**RODAS5P, the default Rosenbrock method**"):]
    paragraph = paragraph[:paragraph.index("\n\n")]
    assert f'default `"{options.DEFAULT_ROSENBROCK}"`' in paragraph


def test_the_tableaux_docstring_names_the_default_rosenbrock_method() -> None:
    doc = " ".join((tableaux.__doc__ or "").split())
    label = options.ROSENBROCKS[options.DEFAULT_ROSENBROCK].label
    assert f"default {label}" in doc
    other = [r.label for name, r in options.ROSENBROCKS.items()
             if name != options.DEFAULT_ROSENBROCK]
    assert all(f"default {x}" not in doc for x in other)
