"""Issue 41 item 12: the site's top navigation had 19 flat entries with the API under "More",
and the guide pages an empty sidebar.  These tests read the build the README's test command
makes (as tests/integration/test_docs_site.py does: skipped without a build, except in CI)."""

from __future__ import annotations

import os
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
HTML = ROOT / "docs" / "_build" / "html"
TOP = ["User guide", "API", "CLI", "Examples", "Project"]
GUIDE = ["getting-started", "model", "model-reading", "parameters", "extending", "machine",
         "linear",
         "measured-data", "acceptance-tests", "fitting", "sweeps", "explore", "fmu", "c-backend",
         "outputs"]


class _Links(HTMLParser):
    """The link texts inside the element whose class contains ``container`` (e.g.
    ``navbar-nav``, ``bd-docs-nav``), in order."""

    def __init__(self, container: str) -> None:
        super().__init__()
        self.container, self.depth, self.inside_a = container, 0, False
        self.links: list[str] = []
        self._text = ""

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        classes = (dict(attrs).get("class") or "").split()
        if self.depth:
            self.depth += 1
        elif self.container in classes:
            self.depth = 1
        if self.depth and tag == "a":
            self.inside_a, self._text = True, ""

    def handle_endtag(self, tag: str) -> None:
        if self.depth and tag == "a" and self.inside_a:
            self.links.append(" ".join(self._text.split()))
            self.inside_a = False
        if self.depth:
            self.depth -= 1

    def handle_data(self, data: str) -> None:
        if self.inside_a:
            self._text += data


def _page(name: str) -> str:
    path = HTML / name
    if not path.exists():
        if os.environ.get("CI"):
            pytest.fail("docs/_build/html is missing: the README's test command builds it")
        pytest.skip("the site is not built (README: sphinx-build … docs docs/_build/html)")
    return path.read_text(encoding="utf-8")


def _links(page: str, container: str) -> list[str]:
    parser = _Links(container)
    parser.feed(page)
    return parser.links


def test_the_top_navigation_is_guide_api_cli_examples() -> None:
    for name in ("index.html", "model.html", "api/index.html"):
        top = _links(_page(name), "navbar-nav")
        # the first four, as the issue asked; the contributor pages apart, after them
        assert top[:len(TOP)] == TOP, (name, top)
        assert "More" not in top


@pytest.mark.parametrize("name", ["model.html", "fitting.html", "getting-started.html"])
def test_guide_pages_have_a_populated_sidebar(name: str) -> None:
    side = _links(_page(name), "bd-docs-nav")
    assert len(side) >= len(GUIDE), side
    for first in ("Getting started", "The model feeddrive simulates", "Fitting a whole drive"):
        assert any(t.startswith(first) for t in side), (first, side)


def test_the_toctrees_hold_every_guide_page_once() -> None:
    guide = (ROOT / "docs" / "user-guide.md").read_text(encoding="utf-8")
    listed = re.findall(r"^([\w-]+)$", guide.split("```{toctree}", 1)[1].split("```", 1)[0],
                        re.M)
    assert listed == GUIDE
    index = (ROOT / "docs" / "index.md").read_text(encoding="utf-8")
    top = re.findall(r"^([\w/-]+)$", index.split("```{toctree}", 1)[1].split("```", 1)[0],
                     re.M)
    assert top == ["user-guide", "api/index", "cli", "auto_examples/index", "project"]
