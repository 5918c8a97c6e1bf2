"""Issue 24 item 1: report.html showed its most important section as raw Markdown (literal
``* **Reproduced:**`` and backticks in one paragraph).  report.md is the source and the HTML
its rendering by one Markdown renderer; these tests read the HTML's structure."""

from __future__ import annotations

from html.parser import HTMLParser
from typing import Any

from feeddrive.reproduce.beyond_section import summary_text
from feeddrive.reproduce.report import _table_md, render_html, run_text, settings_markdown
from feeddrive.reproduce.studies import StudySettings


class _Tags(HTMLParser):
    """Every start tag with its attributes, and the text directly inside each tag."""

    def __init__(self) -> None:
        super().__init__()
        self.tags: list[tuple[str, dict[str, str | None]]] = []
        self.stack: list[str] = []
        self.text: list[tuple[tuple[str, ...], str]] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append((tag, dict(attrs)))
        self.stack.append(tag)

    def handle_endtag(self, tag: str) -> None:
        while self.stack and self.stack.pop() != tag:
            pass

    def handle_data(self, data: str) -> None:
        if data.strip():
            self.text.append((tuple(self.stack), data))


def _parse(page: str) -> _Tags:
    p = _Tags()
    p.feed(page)
    return p


def _search(value: float | None, status: str = "found") -> dict[str, Any]:
    return {"critical_speed_mm_s": value, "status": status, "speed_range_mm_s": [0.02, 3.02],
            "bands": []}


def _results() -> dict[str, Any]:
    forced = [{"drive": "ddfs", "nut_speed_mm_s": vn, "threshold": 0.5, "position_mm": 400.0,
               "critical_speed_mm_s": v} for vn, v in ((16.0, 0.51), (20.0, 0.49))]
    return {"critical": {"crit-cdfs-0.4": _search(1.56),
                         "crit-ddfs-fig8": _search(None, "below-range")},
            "forced_study": forced}


def test_summary_renders_as_a_list_with_bold_and_code() -> None:
    page = render_html(summary_text(_results()))
    p = _parse(page)
    names = [t for t, _ in p.tags]
    assert names.count("ul") == 1 and names.count("li") == 4
    strong = [text for stack, text in p.text if stack[-1] == "strong"]
    assert "Reproduced:" in strong
    code = [text for stack, text in p.text if stack[-1] == "code"]
    assert "wang2021-ripple" in code
    # nothing of the Markdown source is left as text
    for _, text in p.text:
        assert "**" not in text and "`" not in text and not text.lstrip().startswith("* "), text


def test_tables_links_and_escaping() -> None:
    rows = [{"quantity": "CDFS `creep`", "value": "a | b", "note": "<script>x</script>"}]
    p = _parse(render_html(_table_md(rows)))
    names = [t for t, _ in p.tags]
    assert names.count("table") == 1 and names.count("th") == 3 and names.count("td") == 3
    cells = [text for stack, text in p.text if "td" in stack]
    assert "creep" in cells and "a | b" in cells  # the pipe stays in its cell
    assert "script" not in names  # raw HTML in the text is shown, not run
    link = _parse(render_html("see [docs/linear.md](docs/linear.md)"))
    assert ("a", {"href": "docs/linear.md"}) in link.tags


def test_settings_are_a_list_in_mm_s_not_a_repr() -> None:
    """Issue 24 item 3: the settings block was ``StudySettings(...)`` in SI."""
    text = settings_markdown(StudySettings())
    assert "StudySettings(" not in text and "e-05" not in text
    assert "0.02–3.02 mm/s" in text and "240 s" in text
    # trials, search, Fig. 7, Figs. 9–10 and (issue 21) the integrator
    assert [t for t, _ in _parse(render_html(text)).tags].count("li") == 5


def test_resumed_run_says_how_many_studies_were_reused() -> None:
    """Issue 24 item 3: a resumed run's header said "wall time 279 s" without saying that
    14 studies were reused."""
    text = run_text({"wall_time_s": 279.0, "studies_total": 40, "studies_reused": 14})
    assert "279 s" in text and "14 of 40 studies reused" in text and "26 computed" in text
    fresh = run_text({"wall_time_s": 300.0, "studies_total": 40, "studies_reused": 0})
    assert "all 40 studies computed" in fresh
