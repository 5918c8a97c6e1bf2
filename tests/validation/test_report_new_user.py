"""Issue 12 items 17–21: the report and its figures, as a new user reads them.

The session's one reproduction (tests/validation/conftest.py, shared with
test_reproduction.py) serves every test here.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from feeddrive.cli import app

runner = CliRunner()


@pytest.fixture(scope="module")
def reproduced(full_reproduction: tuple[Path, dict[str, Any]]) -> tuple[Path, dict[str, Any]]:
    return full_reproduction


# ------------------------------------------------------------------ item 17: None leaks


def test_fig8_title_gives_the_bound_not_none() -> None:
    """Issue 12 item 17: the Fig. 8 title read "at its critical speed None mm/s"."""
    from feeddrive.reproduce.figures import fig8_title

    search = {"critical_speed_mm_s": None, "status": "below-range", "nut_speed_mm_s": 16.0,
              "speed_range_mm_s": [0.02, 3.02]}
    title = fig8_title(search)
    assert "None" not in title and "< 0.02 mm/s" in title
    assert "at its critical speed 0.51 mm/s" in fig8_title({**search,
                                                            "critical_speed_mm_s": 0.51})


def test_reproduce_progress_never_shows_none(monkeypatch: pytest.MonkeyPatch,
                                             tmp_path: Path) -> None:
    """Issue 12 item 17: the progress bar started "0/None".  Ctrl-C before the first study
    also ends with the kept-data message and status 130 (item 7)."""
    import feeddrive.reproduce as rep

    def interrupted(*_: Any, **__: Any) -> Any:
        raise KeyboardInterrupt

    monkeypatch.setattr(rep, "run", interrupted)
    result = runner.invoke(app, ["reproduce", "--out", str(tmp_path / "out")])
    assert result.exit_code == 130
    assert "None" not in result.output
    # not a terminal: plain progress lines (issue 41 item 6; a terminal's bar shows "0/?")
    assert result.stdout.startswith("reproduce: starting (0 s)")
    assert "kept in" in result.stderr


# ------------------------------------------------------------------ item 18: one protocol


def test_creep_and_reproduce_run_one_protocol(monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 12 item 18: the CLI and the report gave the CDFS step-down speed as 1.35 and
    1.32 mm/s (different speed grids).  Both now make identical calls."""
    import feeddrive.analysis.critical as critical
    from feeddrive.parameters import preset
    from feeddrive.reproduce import studies

    calls: dict[str, list[dict[str, Any]]] = {"rest": [], "running": []}

    def fake(start: str) -> Any:
        def search(system: Any, **kwargs: Any) -> Any:
            calls[start].append({"drive": system.drive, "position": system.table_position,
                                 **kwargs})
            return critical.CriticalSpeed(drive=system.drive, table_position=0.4,
                                          nut_speed=0.0, start=start, critical_speed=1.3e-3,
                                          status="found", resolution=1e-5,
                                          speed_range=(0.02e-3, 3.02e-3))
        return search

    for module in (critical, studies):
        monkeypatch.setattr(module, "critical_speed_from_rest", fake("rest"))
        monkeypatch.setattr(module, "critical_speed_stepdown", fake("running"))
    result = runner.invoke(app, ["creep", "--method", "both"])
    assert result.exit_code == 0, result.output
    settings = studies.StudySettings()
    studies.critical_speed(preset("wang2021"), "cdfs", 0.4, 0.0, settings)
    studies.critical_speed_running(preset("wang2021"), "cdfs", 0.4, 0.0, settings)
    for start in ("rest", "running"):
        cli, report = calls[start]
        assert cli == report, start
    assert "protocol step-down on a running table: staircase from 3.02 mm/s" in result.stdout


# ------------------------------------------------------------------ item 19: figures


def _legend_labels(ax: Any) -> list[str]:
    return [t.get_text() for t in ax.get_legend().get_texts()]


@pytest.mark.slow
def test_figs9_10_are_small_multiples_with_the_overshoot_marked(
        reproduced: tuple[Path, dict[str, Any]]) -> None:
    """Issue 12 item 19: Figs. 9/10 overlaid four traces on one axis (the 10 mm/s trace was
    hidden)."""
    import matplotlib.pyplot as plt

    from feeddrive.reproduce.figures import build_sine

    _, results = reproduced
    data = results["figs9_10"]
    for amp in (1.56, 2.0):
        fig = build_sine(data, amp, "Fig. x")
        axes = fig.get_axes()
        rows = [r for r in data["rows"] if abs(1e3 * r["table_amplitude"] - amp) < 1e-9]
        assert len(axes) == len(rows) == 4
        for ax, row in zip(axes, rows, strict=True):
            texts = [ax.get_title(loc="left")]  # issue 24 item 2: a title, not a box on data
            expected = f"reversal overshoot {100 * row['reversal_overshoot']:.0f} %"
            assert any(expected in t for t in texts), (texts, expected)
            assert len(ax.get_lines()) == 3  # table, command, overshoot marker
        plt.close(fig)


@pytest.mark.slow
def test_fig7_legends_stay_off_the_data_and_name_the_axes(
        reproduced: tuple[Path, dict[str, Any]]) -> None:
    """Issue 12 item 19: Fig. 7's seven traces and legend covered the data; its right panel
    did not say which series is on which axis."""
    import matplotlib.pyplot as plt

    from feeddrive.reproduce.figures import build_fig7

    fig = build_fig7(reproduced[1]["fig7"])
    fig.canvas.draw()
    left, right, twin = fig.get_axes()
    legend_box = left.get_legend().get_window_extent()
    # below the axes (issue 24 item 2: beside them it took 40 % of the width)
    assert legend_box.y1 <= left.get_window_extent().y0
    labels = _legend_labels(right)
    assert any("left axis" in s for s in labels) and any("right axis" in s for s in labels)
    assert "circles" in right.get_ylabel() and "squares" in twin.get_ylabel()
    assert right.get_legend().get_window_extent().y1 <= right.get_window_extent().y0
    plt.close(fig)


@pytest.mark.slow
def test_fig14_legend_matches_what_is_drawn(reproduced: tuple[Path, dict[str, Any]]) -> None:
    """Issue 12 item 19: Fig. 14 had a legend entry with no data and none for the dotted
    k_sa line."""
    import matplotlib.pyplot as plt

    from feeddrive.reproduce.figures import build_fig14

    fig = build_fig14(reproduced[1]["table3"])
    ax, twin = fig.get_axes()
    lines = {line.get_label(): line for a in (ax, twin) for line in a.get_lines()}
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "k_sa (right axis)" in labels
    for label in labels:
        assert np.isfinite(np.asarray(lines[label].get_ydata(), float)).any(), label
    plt.close(fig)


@pytest.mark.slow
def test_no_figure_of_the_report_hides_data_under_a_legend_or_label(
        reproduced: tuple[Path, dict[str, Any]]) -> None:
    """Issue 24 item 2: Fig. 6's legend sat on the oscillation at 10–12 s, Figs. 9/10's
    legend on the peak at ~11 s and each panel's label box on the peak at ~1.2 s; Fig. 14's
    legend took 40 % of the width; Fig. 7's seventh trace was viridis yellow.  Checked as
    matplotlib draws them: no legend or boxed label covers a line's points or segments, none
    is cut off, none sits on a title or axis label."""
    import matplotlib.colors as mcolors
    import matplotlib.pyplot as plt

    from feeddrive.plots.layout import clipped_artists, covered_data, overlapping_texts
    from feeddrive.reproduce import figures as F

    res = reproduced[1]
    built = {"fig6": F.build_fig6(res["fig6"]), "fig7": F.build_fig7(res["fig7"]),
             "fig8": F.build_fig8(res["fig8_trace"], res["critical"]["crit-ddfs-fig8"]),
             "fig9": F.build_sine(res["figs9_10"], 1.56, "Fig. 9"),
             "fig10": F.build_sine(res["figs9_10"], 2.0, "Fig. 10"),
             "fig14": F.build_fig14(res["table3"])}
    for name, fig in built.items():
        assert covered_data(fig) == [], name
        assert clipped_artists(fig) == [], name
        assert overlapping_texts(fig) == [], name
        for ax in fig.get_axes():
            assert not ax.get_ylabel().startswith("["), (name, ax.get_ylabel())
    # Fig. 7: every trace darker than viridis's yellow end (luminance 0.87; here < 0.75)
    for line in built["fig7"].get_axes()[0].get_lines():
        r, g, b = mcolors.to_rgb(line.get_color())
        assert 0.2126 * r + 0.7152 * g + 0.0722 * b < 0.75, line.get_label()
    # the 14 legend beside the plot took ~40 % of the width: now the axes keep ≥ 75 %
    fig14 = built["fig14"]
    assert fig14.get_axes()[0].get_window_extent().width >= 0.75 * fig14.bbox.width
    for fig in built.values():
        plt.close(fig)


# ------------------------------------------------------------------ item 20: report layout


@pytest.mark.slow
def test_report_places_each_figure_in_its_section_with_a_caption(
        reproduced: tuple[Path, dict[str, Any]]) -> None:
    """Issue 12 item 20: the HTML report put every figure at the end, captioned by file name;
    the .md report lacked the Settings section."""
    from feeddrive.reproduce.figures import CAPTIONS

    out, results = reproduced
    page = (out / "report.html").read_text(encoding="utf-8")
    md = (out / "report.md").read_text(encoding="utf-8")
    sections = re.split(r"<h2[^>]*>", page)  # (issue 41 item 1: each with its anchor)
    expected_section = {"fig6": "Fig. 6", "fig7": "Fig. 7", "fig8": "Fig. 8",
                        "sine": "Figs. 9–10", "table3": "Table 3 and Fig. 14",
                        "sensitivity": "Which parameter matters"}
    assert len(results["figures"]) == 7  # Figs. 6–10, 14 and the sensitivity chart (issue 22)
    for name in results["figures"]:
        key, caption = CAPTIONS[name]
        holder = [s for s in sections if f'src="{name}"' in s]
        assert len(holder) == 1 and holder[0].startswith(expected_section[key]), name
        match = re.search(rf'src="{re.escape(name)}"[^>]*><figcaption>([^<]*)</figcaption>',
                          holder[0])
        assert match and match.group(1) != name
        # a paper figure's caption cites it; the sensitivity chart says it has no counterpart
        assert ("Wang2021" if key != "sensitivity" else "No counterpart in the paper") in \
            match.group(1)
        assert f"*{caption}*" in md
    # issue 24 item 3: the settings were a Python repr in SI
    assert '<h2 id="settings">Settings</h2>' in page and "<li>creep trials: 12 s" in page
    assert "## Settings" in md and "* creep trials: 12 s" in md
    assert "StudySettings(" not in page + md
    # issue 24 item 1: the summary section was one paragraph of raw Markdown
    summary = next(s for s in sections if s.startswith("What is reproduced"))
    assert "<ul>" in summary and "<li><strong>Reproduced:</strong>" in summary
    assert "<code>wang2021-ripple</code>" in summary
    assert "**" not in page and "`" not in page
    assert page.count("<table>") == md.count("\n|---")


# ------------------------------------------------------------------ item 21: Fig. 6b


def test_fig6b_agrees_only_when_it_settles_near_seven_seconds() -> None:
    """Issue 12 item 21: "Fig. 6b stable after ~7 s" was marked "agrees" although the model
    settles at 11.7 s."""
    from feeddrive.reproduce.report import fig6b_agreement

    assert fig6b_agreement("smooth", 11.7).startswith("differs")
    assert "11.7 s" in fig6b_agreement("smooth", 11.7)
    assert fig6b_agreement("smooth", 7.4).startswith("agrees")
    assert fig6b_agreement("creeping", 7.0).startswith("differs")
    assert fig6b_agreement("smooth", None).startswith("differs")


@pytest.mark.slow
def test_report_fig6b_row_follows_the_settling_time(
        reproduced: tuple[Path, dict[str, Any]]) -> None:
    from feeddrive.reproduce.report import fig6b_agreement

    out, results = reproduced
    run_156 = results["fig6"]["1.56"]
    row = next(s for s in (out / "report.md").read_text(encoding="utf-8").splitlines()
               if "(Fig. 6b)" in s)
    assert fig6b_agreement(run_156["verdict"], run_156["settling_time"]) in row


def test_ripple_table_shows_a_dash_not_none_when_out_of_range() -> None:
    """The torque-ripple table printed "None" as the kind of an above-range search (found
    reading the report, DDFS at v_n = 2 and 5 mm/s)."""
    from feeddrive.analysis.forced import THRESHOLDS
    from feeddrive.reproduce.beyond_section import ripple_rows

    def row(drive: str, vn: float, th: float, crit: float | None, kind: str | None) -> dict:
        return {"drive": drive, "nut_speed_mm_s": vn, "threshold": th, "position_mm": 400.0,
                "critical_speed_mm_s": crit, "status": "found" if crit else "above-range",
                "kind": kind, "speed_range_mm_s": [0.05, 3.0]}

    forced = [row("cdfs", 0.0, th, 1.6, "oscillation") for th in THRESHOLDS]
    forced += [row("ddfs", 2.0, th, None, None) for th in THRESHOLDS]
    _, rows = ripple_rows(forced)
    assert [r["kind (0.5)"] for r in rows] == ["oscillation", "—"]
    assert rows[1]["threshold 0.5"] == "> 3.00"
