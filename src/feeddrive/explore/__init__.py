"""The explorer page (``feeddrive explore``): a feed drive's creep, and knobs to move.

A local web app on 127.0.0.1: the standard library's threading HTTP server answers a single
page and a small JSON API (:mod:`.server`); the page draws with plotly.js taken from the
installed ``plotly`` package (the ``explore`` extra), so nothing is fetched from the network.
Settings are checked as the CLI checks them (:mod:`.settings`), runs go to background
threads with progress and cancellation (:mod:`.jobs`), and what is shown is computed with
the public API (:mod:`.compute`).  See docs/explore.md.
"""

from __future__ import annotations

from .server import Explorer, ExplorerServer, MissingDependency, make_server, serve_in_thread

__all__ = ["Explorer", "ExplorerServer", "MissingDependency", "make_server", "serve_in_thread"]
