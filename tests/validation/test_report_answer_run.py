"""Issue 41 items 1 and 5 on the report of the session's reproduction (conftest.py): the
answer first, a linked contents list, solver details under Settings, no nan in a table, the
period count of the runs, one colour per Fig. 7 trace."""

from __future__ import annotations

import re
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import pytest

from feeddrive.analysis.critical import format_critical_speed
from feeddrive.reproduce.report import integrator_text

pytestmark = pytest.mark.slow


class _Page(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.order: list[tuple[str, dict[str, str | None]]] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.order.append((tag, dict(attrs)))


def _page(out: Path) -> tuple[str, _Page]:
    text = (out / "report.html").read_text(encoding="utf-8")
    page = _Page()
    page.feed(text)
    return text, page


def test_the_answer_comes_first_with_this_runs_numbers(full_reproduction) -> None:
    out, results = full_reproduction
    text, page = _page(out)
    first_h2 = next(i for i, (tag, _) in enumerate(page.order) if tag == "h2")
    assert page.order[first_h2 - 1] == ("section", {"class": "answer", "id": "answer"})
    box = text.split('id="answer">', 1)[1].split("</section>", 1)[0]
    crit = results["critical"]
    for key in ("crit-cdfs-0.4", "crit-cdfs-running", "crit-ddfs-fig8"):
        assert f"{format_critical_speed(crit[key])} mm/s".replace("<", "&lt;") in box, key
    assert "<em>fitted</em>" in box and "<em>predicted</em>" in box
    assert "Mechanism:" in box and "Hz, ζ " in box and "linearly unstable at" in box


def test_the_contents_link_every_section(full_reproduction) -> None:
    text, page = _page(full_reproduction[0])
    ids = [a["id"] for tag, a in page.order if tag == "h2" and a.get("id")]
    nav = text.split('<nav id="contents">', 1)[1].split("</nav>", 1)[0]
    links = re.findall(r'href="#([\w-]+)"', nav)
    assert links == ids and len(ids) == 20 and ids[-1] == "settings"  # 20: + the quadrant study
    # every h2 but the box's and the contents' own has an anchor
    assert sum(tag == "h2" for tag, _ in page.order) == len(ids) + 2


def test_the_solver_details_are_under_settings(full_reproduction) -> None:
    text, _ = _page(full_reproduction[0])
    where = text.find(integrator_text().split(":")[0])
    assert where > text.find('<h2 id="settings">') > 0


def test_no_report_table_shows_nan_or_none(full_reproduction) -> None:
    md = (full_reproduction[0] / "report.md").read_text(encoding="utf-8")
    rows = [line for line in md.splitlines() if line.startswith("|")]
    assert len(rows) > 150
    bad = [r for r in rows if re.search(r"\b(nan|NaN|None)\b", r)]  # "none": no band
    assert bad == []


def test_the_period_count_matches_the_runs(full_reproduction) -> None:
    out, results = full_reproduction
    data = results["figs9_10"]
    spans = {round((t["time"][-1] - t["time"][0]) * data["frequency"])
             for t in data["traces"].values()}
    (periods,) = spans
    md = (out / "report.md").read_text(encoding="utf-8")
    assert f"{periods} periods simulated" in md


def test_every_fig7_trace_has_its_own_colour(full_reproduction: tuple[Path, dict[str, Any]]
                                             ) -> None:
    from matplotlib.colors import to_hex

    from feeddrive.reproduce.figures import build_fig7

    fig = build_fig7(full_reproduction[1]["fig7"])
    left, right, _ = fig.get_axes()
    colours = [to_hex(h.get_color()) for h in left.get_legend().legend_handles]
    assert len(colours) == len(full_reproduction[1]["fig7"]["traces"]) == len(set(colours))
    assert 0.0 in list(right.get_lines()[0].get_xdata())  # v_n = 0 on the right panel
