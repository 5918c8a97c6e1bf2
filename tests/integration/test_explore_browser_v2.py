"""Issue 23: explorer v2 in a real headless Chromium (Debian's ``/usr/bin/chromium`` through
Playwright's Python driver, as tests/integration/test_explore_browser.py): pick a signal of
the run, overlay a second run with the settings diff shown, download the run's CSV and read it
back, overlay it as a measured trace; the knob units follow the parameter set; the Bode plot
is drawn; a run that fails clears the plots and says why."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pandas as pd
import pytest
from browser_support import ARGS, CHROMIUM, explorer, needs_chromium, playwright

from feeddrive.explore import ExplorerServer
from feeddrive.io.measured import read_position_trace

pytestmark = needs_chromium


@pytest.fixture(scope="module")
def server() -> Iterator[ExplorerServer]:
    with explorer({"drive": "cdfs", "table_speed": "2", "duration": "2"}) as srv:
        yield srv


def svg_text(page: object, selector: str) -> str:
    """The text of a plotly SVG element (not an HTMLElement: no inner_text)."""
    return str(page.eval_on_selector(selector, "el => el.textContent"))  # type: ignore[attr-defined]


def test_pick_a_signal_overlay_two_runs_download_and_read_back(server: ExplorerServer,
                                                               tmp_path: Path) -> None:
    sync_api = playwright()
    errors: list[str] = []
    with sync_api.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=str(CHROMIUM), args=ARGS)
        try:
            page = browser.new_page(viewport={"width": 1500, "height": 1100},
                                    accept_downloads=True)
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(server.url)
            page.wait_for_selector("body[data-ready=yes]", timeout=60_000)
            # the first run (on load): its signals fill the picker
            page.wait_for_selector("#signal:not([disabled])", timeout=300_000)
            page.wait_for_selector("#plot-signal[data-signal='following_error']",
                                   timeout=60_000)
            # the knob units are the set's own: wang2021 works per m/s of table speed
            assert page.inner_text("#row-velocity_gain .unit") == \
                "[A s/m, per table speed]"
            options = page.eval_on_selector_all("#signal option", "els => els.map(e => e.value)")
            assert {"table_speed", "following_error", "screw_current", "drive_force"} <= \
                set(options)

            page.select_option("#signal", "screw_current")
            page.wait_for_selector("#plot-signal[data-signal='screw_current']", timeout=30_000)
            title = svg_text(page, "#plot-signal .gtitle")
            assert "[A]" in title

            # a second run with another speed; the first becomes B
            page.uncheck("#auto")
            page.fill("#f-table_speed", "1")
            page.click("#run")
            page.wait_for_function("document.querySelector('#compare').options.length >= 2",
                                   timeout=120_000)
            page.wait_for_function("document.querySelector('#run-facts').textContent"
                                   ".startsWith('CDFS at 1 mm/s')", timeout=120_000)
            b_value = page.eval_on_selector("#compare", "s => s.options[1].value")
            page.select_option("#compare", b_value)
            page.wait_for_selector("#plot-signal[data-traces='2']", timeout=30_000)
            diff = page.inner_text("#settings-diff")
            assert "table speed: A 1 → B 2 [mm/s]" in diff, diff
            legend = svg_text(page, "#plot-signal .legend")
            assert "A:" in legend and "B:" in legend

            # download the run's CSV and read it back as `feeddrive analyze` would
            with page.expect_download(timeout=60_000) as got:
                page.click("#download-csv")
            csv = tmp_path / "run.csv"
            got.value.save_as(csv)
            frame = pd.read_csv(csv, comment="#")
            assert {"time [s]", "table_speed [mm/s]", "screw_current [A]"} <= set(frame.columns)
            assert frame["time [s]"].iloc[-1] == pytest.approx(2.0)
            tail = frame["table_speed [mm/s]"][frame["time [s]"] > 1.0]
            assert tail.mean() == pytest.approx(1.0, rel=0.1)
            trace = read_position_trace(csv)
            assert trace.time.size == len(frame)

            # the file overlaid as a measured trace on the speed plot and the picked signal
            page.select_option("#signal", "table_speed")
            page.wait_for_selector("#plot-signal[data-signal='table_speed']", timeout=30_000)
            page.set_input_files("#measured-file", str(csv))
            page.wait_for_selector("#plot-signal[data-traces='3']", timeout=60_000)
            assert "measured (run.csv)" in svg_text(page, "#plot-speed .legend")

            # the loops' Bode plot with its margins
            page.wait_for_function("document.querySelector('#plot-bode .legend') && "
                                   "document.querySelector('#plot-bode .legend').textContent"
                                   ".includes('PM')", timeout=300_000)
            page.screenshot(path=str(tmp_path / "explore-v2.png"), full_page=True)

            # a run that fails: its message, and no earlier plots under it
            page.fill("#f-table_speed", "0")  # checked fine; the run refuses it, as the CLI
            page.fill("#f-duration", "0.5")
            page.click("#run")
            page.wait_for_function("document.querySelector('#verdict').textContent"
                                   ".startsWith('the run failed')", timeout=300_000)
            for plot in ("#plot-speed", "#plot-signal", "#plot-bode", "#plot-poles"):
                assert page.eval_on_selector(plot, "el => el.data === undefined || "
                                             "el.data.length === 0"), plot
            refusal = "--table-speed = 0.0: expected a non-zero speed [mm/s]"
            assert refusal in page.inner_text("#verdict") or \
                refusal in page.inner_text("#msg-table_speed")
        finally:
            browser.close()
    assert not errors, errors
