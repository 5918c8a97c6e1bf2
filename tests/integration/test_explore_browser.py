"""Issue 11 acceptance: the explorer page in a real headless Chromium.

`feeddrive explore` is started as a user starts it; Debian's chromium (``/usr/bin/chromium``,
installed with ``apt-get install -y chromium``; no browser is downloaded) is driven through
Playwright's Python driver.  The test sets a DDFS at 0.5 mm/s, runs, reads the verdict from
the page, gives a field an invalid value and sees the CLI's message beside it, opens the
page's own address in a second tab (the settings travel in it), starts and cancels a
critical-speed search, and saves a screenshot that it checks is not blank.

The time from the click to the drawn verdict is recorded (``explore-response.txt`` beside
the screenshot, and the test's ``record_property``), not asserted: it depends on the machine.
"""

from __future__ import annotations

import http.client
import json
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from browser_support import ARGS, CHROMIUM, needs_chromium, playwright

pytestmark = needs_chromium


@pytest.fixture(scope="module")
def explorer(interruptible: dict[str, Any]) -> Iterator[str]:
    """`feeddrive explore --port 0`, started as a user starts it; its address."""
    proc = subprocess.Popen([sys.executable, "-m", "feeddrive", "explore", "--port", "0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            **interruptible)
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert line.startswith("feeddrive explore: http://127.0.0.1:"), line
        yield line.split()[2]
    finally:
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=30)
        assert proc.returncode == 0 and "Traceback" not in err, err


def _check(url: str, settings: dict[str, str]) -> dict[str, str]:
    """The messages the server gives for ``settings`` (what the page must show)."""
    port = int(url.rsplit(":", 1)[1].strip("/"))
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
    conn.request("POST", "/api/check", body=json.dumps({"settings": settings}),
                 headers={"Content-Type": "application/json"})
    out = json.loads(conn.getresponse().read())
    conn.close()
    return dict(out["errors"])


def _jobs_answers(responses: list[Any]) -> list[str]:
    """The page's POST /api/jobs answers as a failure message gives them: status and kind, and
    the job's id and state or the refusal's messages."""
    out = []
    for r in responses:
        kind = json.loads(r.request.post_data or "{}").get("kind")
        try:
            body = r.json()
        except Exception as err:  # a body the page could not read either
            out.append(f"{r.status} {kind}: unreadable ({err})")
            continue
        if r.status == 202:
            out.append(f"{r.status} {kind}: {body.get('id')} {body.get('state')}")
        else:
            out.append(f"{r.status} {kind}: {body.get('errors') or body.get('error')}")
    return out


def _not_blank(png: Path) -> tuple[float, int]:
    from matplotlib import image

    pixels = image.imread(str(png))[..., :3]
    colours = np.unique((pixels * 255).astype(np.uint8).reshape(-1, 3), axis=0)
    return float(pixels.std()), int(len(colours))


def test_the_page_runs_a_ddfs_shows_its_verdict_and_refuses_bad_input(
        explorer: str, tmp_path: Path, record_property: pytest.RecordProperty) -> None:
    sync_api = playwright()
    errors: list[str] = []
    with sync_api.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=str(CHROMIUM), args=ARGS)
        try:
            page = browser.new_page(viewport={"width": 1500, "height": 1000})
            page.on("pageerror", lambda e: errors.append(str(e)))
            jobs: list[Any] = []  # the page's POST /api/jobs answers
            page.on("response", lambda r: jobs.append(r) if r.request.method == "POST"
                    and r.url.endswith("/api/jobs") else None)
            page.goto(explorer)
            page.wait_for_selector("body[data-ready=yes]", timeout=60_000)
            # the first view: the starting settings, run on load (the solver may still be
            # compiling on a fresh machine, hence the long wait)
            page.wait_for_selector("#verdict:not([data-verdict=''])", timeout=300_000)

            page.uncheck("#auto")  # run on the click only, so that the click is timed
            page.select_option("#f-drive", "ddfs")
            page.fill("#f-table_speed", "0.5")
            page.fill("#f-nut_speed", "16")
            page.wait_for_function("location.search.includes('table_speed=0.5')")
            page.click("#run")
            page.wait_for_function(
                "document.querySelector('#run-facts').textContent.startsWith("
                "'DDFS at 0.5 mm/s') && !document.querySelector('#verdict')"
                ".classList.contains('stale')", timeout=120_000)
            verdict = page.get_attribute("#verdict", "data-verdict")
            kind = page.get_attribute("#verdict", "data-kind")
            text = page.inner_text("#verdict")
            assert verdict == "smooth" and kind == "smooth", text
            assert text.startswith("SMOOTH")
            shown = float(page.get_attribute("#verdict", "data-shown-after-s") or "nan")
            record_property("ddfs_10s_shown_after_click_s", shown)
            (tmp_path / "explore-response.txt").write_text(
                f"DDFS, 10 s simulated: verdict shown {shown:.3f} s after the click\n",
                encoding="utf-8")
            # the linear analysis follows: band and poles drawn
            page.wait_for_function("document.querySelector('#linear-facts').textContent"
                                   ".includes('0.5 mm/s')", timeout=120_000)

            # a colleague opening the same address sees the same run
            other = browser.new_page(viewport={"width": 1200, "height": 900})
            other.goto(page.url)
            other.wait_for_function(
                "document.querySelector('#run-facts').textContent.startsWith("
                "'DDFS at 0.5 mm/s')", timeout=120_000)
            assert other.get_attribute("#verdict", "data-verdict") == "smooth"
            assert other.input_value("#f-drive") == "ddfs"
            other.close()

            # bad input: the CLI's one-line message beside the field, and no run
            expected = _check(explorer, {"drive": "ddfs", "table_speed": "0.5",
                                         "velocity_gain": "-5"})["velocity_gain"]
            page.fill("#f-velocity_gain", "-5")
            page.wait_for_function(
                f"document.querySelector('#msg-velocity_gain').textContent === "
                f"{json.dumps(expected)}", timeout=30_000)
            assert "invalid" in (page.get_attribute("#f-velocity_gain", "class") or "")
            expected = _check(explorer, {"table_speed": "fast"})["table_speed"]
            page.fill("#f-table_speed", "fast")
            page.wait_for_function(
                f"document.querySelector('#msg-table_speed').textContent === "
                f"{json.dumps(expected)}", timeout=30_000)
            assert expected.startswith("Invalid value for '--table-speed'")
            page.click("#run")
            page.wait_for_function("document.querySelector('#msg-run').textContent"
                                   ".startsWith('fix the marked fields')", timeout=30_000)

            # critical speed: progress shown, then cancelled
            page.fill("#f-table_speed", "0.5")
            page.fill("#f-velocity_gain", "45")
            # the search starts from the page as it settles: the answer to the check of the
            # last value typed clears the three messages (an answer to 0.5 with -5 clears the
            # first only).  Clicked before it, the click's own check of the field it leaves
            # answered during the press, and the messages going moved the button 77 px up
            # from under the pointer: the click was lost (2 runs in full suites; 7 of 10 with
            # a 100 ms press, 2026-12-07).  The page now draws such an answer after the
            # release (test_explore_browser_press.py).
            page.wait_for_function(
                "['#msg-table_speed', '#msg-velocity_gain', '#msg-run'].every((s) => "
                "document.querySelector(s).textContent === '')", timeout=30_000)
            # the search takes a fraction of a second (0.13 s for this DDFS, 2026-12-06): less
            # than it takes to see the bar and click, so a click timed from here found it done
            # (and, likely, a CI run missed the bar).  An observer in the page records the bar as
            # it shows and presses Cancel at that moment, through the page's own handler.
            page.evaluate("""() => {
              const box = document.querySelector('#critical-progress');
              window.criticalShown = null;
              window.clicked = [];  // where the clicks land (a lost one lands elsewhere)
              document.addEventListener('click', (e) => {
                if (e.isTrusted) window.clicked.push(e.target.id || e.target.tagName);
              }, true);
              new MutationObserver(() => {
                if (!box.hidden && window.criticalShown === null) {
                  window.criticalShown = box.querySelector('.text').textContent;
                  document.querySelector('#critical-cancel').click();
                }
              }).observe(box, {attributes: true, attributeFilter: ['hidden']});
            }""")
            answered = len(jobs)
            page.click("#critical")
            try:
                page.wait_for_function("document.querySelector('#critical-result').dataset"
                                       ".state === 'cancelled'", timeout=60_000)
            except sync_api.TimeoutError:  # say what the page showed instead
                messages = page.evaluate(
                    "Object.fromEntries([...document.querySelectorAll('[id^=msg-]')]"
                    ".filter((e) => e.textContent).map((e) => [e.id, e.textContent]))")
                state = page.evaluate("document.querySelector('#critical-result').dataset"
                                      ".state")
                pytest.fail("the critical-speed search not cancelled 60 s after the click: "
                            f"the click reached {page.evaluate('window.clicked')}, POST "
                            f"/api/jobs answered {_jobs_answers(jobs[answered:]) or 'nothing'}, "
                            f"the bar showed {page.evaluate('window.criticalShown')!r}, the "
                            f"page says {page.inner_text('#critical-result')!r} (state "
                            f"{state!r}), messages {messages}, status "
                            f"{page.inner_text('#status')!r}, errors {errors}")
            assert "trial" in page.evaluate("window.criticalShown")
            assert page.inner_text("#critical-result") == "cancelled"
            assert not page.is_disabled("#critical")  # ready for the next search

            shot = tmp_path / "explore.png"
            page.fill("#f-velocity_gain", "-5")  # show a message in the picture
            page.wait_for_function("document.querySelector('#msg-velocity_gain')"
                                   ".textContent !== ''", timeout=30_000)
            page.screenshot(path=str(shot), full_page=True)
        finally:
            browser.close()
    spread, colours = _not_blank(shot)
    assert spread > 0.05 and colours > 200, (spread, colours)
    assert not errors, errors
