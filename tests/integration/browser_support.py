"""What the explorer's browser tests share: Debian's chromium and its flags, the skip when it
is missing, Playwright's driver (in the test extra), and an explorer served in this process."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from feeddrive.explore import ExplorerServer, serve_in_thread

CHROMIUM = Path("/usr/bin/chromium")
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
        "--disable-component-update", "--disable-sync", "--no-first-run"]
MISSING = ("Debian's chromium is not installed (apt-get install -y chromium): the explorer's "
           "browser test drives /usr/bin/chromium and downloads no browser")

#: the mark of a module or test that drives the browser
needs_chromium = pytest.mark.skipif(not CHROMIUM.exists(), reason=MISSING)


def playwright() -> Any:
    """``playwright.sync_api``, or the test skipped saying where it comes from."""
    return pytest.importorskip("playwright.sync_api", reason="Playwright's Python driver "
                               "is in the test extra: pip install '.[test]'")


@contextmanager
def explorer(initial: dict[str, Any] | None = None, *,
             warm_up: bool = True) -> Iterator[ExplorerServer]:
    """An explorer on a free port in a daemon thread, its solver warmed up unless
    ``warm_up`` is false; shut down on leaving."""
    srv = serve_in_thread(0, initial, warm_up=warm_up)
    try:
        if warm_up:
            assert srv.explorer.ready.wait(300), "the solver warm-up did not finish"
        yield srv
    finally:
        srv.shutdown()
        srv.server_close()
