"""Session 27: the explorer printed "—" for the wang2021 CDFS screw velocity loop's gain
margin, which is infinite (its phase never crosses −180°; `feeddrive loops` prints "∞ dB"),
and left it out of the Bode legend.  In a real headless Chromium (Debian's
``/usr/bin/chromium`` through Playwright's Python driver, as
tests/integration/test_explore_browser_v2.py); the server's JSON:
tests/unit/test_infinite_margin_views_s27.py."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from browser_support import ARGS, CHROMIUM, explorer, needs_chromium, playwright

from feeddrive.explore import ExplorerServer

pytestmark = needs_chromium


@pytest.fixture(scope="module")
def server() -> Iterator[ExplorerServer]:
    with explorer({"drive": "cdfs", "table_speed": "1.5", "duration": "0.5"}) as srv:
        yield srv


def test_the_page_prints_an_infinite_gain_margin(server: ExplorerServer) -> None:
    sync_api = playwright()
    errors: list[str] = []
    with sync_api.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=str(CHROMIUM), args=ARGS)
        try:
            page = browser.new_page(viewport={"width": 1500, "height": 1100})
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(server.url)
            page.wait_for_selector("body[data-ready=yes]", timeout=60_000)
            page.wait_for_function("document.querySelector('#linear-facts').textContent"
                                   ".includes('gain margin')", timeout=300_000)
            facts = page.inner_text("#linear-facts")
            velocity = facts.split("screw velocity loop: ")[1].split(" · ")[0]
            assert velocity.startswith("phase margin ") and \
                velocity.endswith(", gain margin ∞ dB"), facts
            position = facts.split("screw position loop: ")[1].split(" · ")[0]
            assert "∞" not in position and "—" not in position, facts

            legend = page.eval_on_selector(
                "#plot-bode", "el => el.data.filter((t) => t.showlegend !== false)"
                ".map((t) => t.name)")
            labels = {name.split(",")[0]: name for name in legend}
            assert labels["screw velocity loop"].endswith(", GM ∞ dB"), labels
            assert ", GM " in labels["screw position loop"] and \
                "∞" not in labels["screw position loop"], labels
            drawn = str(page.eval_on_selector("#plot-bode .legend", "el => el.textContent"))
            assert "GM ∞ dB" in drawn, drawn

            # a value the loop has not (no gain crossover) stays "—" and out of the legend;
            # a null the server names infinite is ∞
            shown = page.evaluate("""() => {
                const lp = { loop: "x", gain_margin_db: null, phase_margin_deg: null,
                             crossover_hz: null, infinite: ["gain_margin_db"] };
                return [fmt(loopValue(lp, "gain_margin_db"), 3, "dB"),
                        fmt(loopValue(lp, "phase_margin_deg"), 3, "°"),
                        fmt(loopValue({ ...lp, infinite: [] }, "gain_margin_db"), 3, "dB"),
                        fmt(2.5894, 3, "dB")];
            }""")
            assert shown == ["∞ dB", "—", "—", "2.59 dB"]
        finally:
            browser.close()
    assert not errors, errors
