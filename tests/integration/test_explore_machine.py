"""Issue 40 item 4: the explorer shows a machine's XY path — a built-in machine or a machine
file (with its coupling parts) follows a circle; the page gets the actual and commanded path
and the contour error.  Driven by plain HTTP requests as tests/integration/
test_explore_api.py does, and in headless Chromium as test_explore_browser.py does."""

from __future__ import annotations

import http.client
import json
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from browser_support import ARGS, CHROMIUM, MISSING, explorer, playwright

from feeddrive.explore import ExplorerServer
from feeddrive.explore.compute import MAX_POINTS

#: the inertial cross-axis part of docs/machine.md: x's acceleration loads y's table
CARRY = """name = "xy-carry"
extends = "xy-table"
[couplings.carry]
part = "inertial"
source = "x"
target = "y"
mass = 20.0
factor = 0.5
"""


@pytest.fixture(scope="module")
def server() -> Iterator[ExplorerServer]:
    with explorer(warm_up=False) as srv:  # a machine run needs no single-drive warm-up
        yield srv


def request(srv: ExplorerServer, method: str, path: str, body: Any = None
            ) -> tuple[int, Any]:
    conn = http.client.HTTPConnection("127.0.0.1", srv.port, timeout=60)
    try:
        headers = {"Content-Type": "application/json"} if body is not None else {}
        conn.request(method, path, body=None if body is None else json.dumps(body),
                     headers=headers)
        resp = conn.getresponse()
        return resp.status, json.loads(resp.read())
    finally:
        conn.close()


def run_machine(srv: ExplorerServer, body: dict[str, Any], timeout: float = 300.0
                ) -> dict[str, Any]:
    status, job = request(srv, "POST", "/api/machine", body)
    assert status == 202, job
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        status, job = request(srv, "GET", f"/api/jobs/{job['id']}")
        assert status == 200
        if job["state"] != "running":
            assert job["state"] == "done", job
            return dict(job["result"])
        time.sleep(0.05)
    raise AssertionError(f"the machine run did not finish in {timeout} s")


def _circle_fit(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """Centre and radius of the least-squares circle (Kåsa's algebraic fit)."""
    A = np.column_stack([x, y, np.ones_like(x)])
    (a, b, c), *_ = np.linalg.lstsq(A, x ** 2 + y ** 2, rcond=None)
    cx, cy = a / 2, b / 2
    return cx, cy, float(np.sqrt(c + cx ** 2 + cy ** 2))


def test_a_machine_shows_its_xy_path_and_contour_error(server: ExplorerServer) -> None:
    status, info = request(server, "GET", "/api/info")
    assert status == 200 and {"xy-table", "gantry"} <= set(info["machines"])
    res = run_machine(server, {"machine": "xy-table", "radius": 50, "feed": 5000})
    assert res["axes"] == ["x", "y"]
    p = {k: np.array(v, dtype=float) for k, v in res["path"].items()}
    assert 100 < len(p["time_s"]) <= MAX_POINTS
    assert np.all(np.diff(p["time_s"]) >= 0)
    # the commanded path is the 50-mm circle; the contour error is the actual point's signed
    # distance to it, computed here from the returned positions and the commanded circle
    cx, cy, radius = _circle_fit(p["x_reference_mm"], p["y_reference_mm"])
    assert radius == pytest.approx(50.0, abs=1e-4)
    mine = (np.hypot(p["x_mm"] - cx, p["y_mm"] - cy) - radius) * 1e3  # [µm]
    assert np.max(np.abs(mine - p["contour_error_um"])) < 0.05
    s = res["summary"]
    assert s["contour_error_max_um"] == pytest.approx(np.max(p["contour_error_um"]), rel=1e-6)
    assert set(s["following_error_max_um"]) == {"x", "y"}


def test_the_inertial_coupling_part_acts_in_the_explorer(server: ExplorerServer) -> None:
    plain = run_machine(server, {"machine": "xy-table"})
    carry = run_machine(server, {"machine": CARRY})
    assert carry["machine"] == "xy-carry" and carry["couplings"] == ["carry (inertial)"]
    assert carry["path"]["time_s"] == plain["path"]["time_s"]
    # x's acceleration loads y: y's path moves (measured 2.2 µm), x's — which nothing loads —
    # only by the integrator's error and the 7-digit rounding (measured 0.01 µm)
    shift = {k: np.max(np.abs(np.array(carry["path"][k]) - np.array(plain["path"][k])))
             for k in ("x_mm", "y_mm")}
    assert shift["y_mm"] > 1e-3 > 1e-4 > shift["x_mm"]  # [mm]


@pytest.mark.parametrize(("body", "field", "words"), [
    ({"machine": 'name = "a"\n[axes.x]\nextends = "nope"\n[axes.y]\n'}, "machine",
     "axes.x.extends = 'nope'"),
    ({"machine": CARRY.replace('source = "x"', 'source = "z"')}, "machine", "z."),
    ({"machine": "x = ["}, "machine", "not valid TOML"),
    ({"machine": 'name = "a"\n[axes.x]\nextends = "/etc/set.toml"\n[axes.y]\n'}, "machine",
     "reads no other file"),
    ({"machine": "xy-table", "radius": -1}, "radius", "radius = -1"),
    ({"machine": "xy-table", "feed": "fast"}, "feed", "feed = 'fast'"),
    ({"machine": "xy-table", "feed": 1}, "feed", "expected ≤ 120 s"),
    # an outside check, 2026-12-07: these went to a 500, another field or SI units
    ({"machine": "xy-table", "radius": 10 ** 400}, "radius", "expected a number 0.1 … 1000 [mm]"),
    ({"machine": "xy-table", "feed": 1e300}, "feed", "expected 1 … 60000 [mm/min]"),
    ({"machine": "xy-table", "radius": 1e-300}, "radius", "expected 0.1 … 1000 [mm]"),
    ({"machine": "xy-table", "radius": 100000}, "radius", "expected 0.1 … 1000 [mm]"),
    ({"machine": "xy-table", "acceleration": 1e300}, "acceleration", "[mm/s^2]"),
    ({"machine": "xy-table", "feed": True}, "feed", "expected a number"),
    ({"machine": 'name = "m"\n' + "".join(f'[axes.a{i}]\nextends = "wang2021"\n'
                                          for i in range(9))}, "machine", "has 9 axes"),
])
def test_a_bad_machine_request_is_refused_in_one_line_naming_the_field(
        server: ExplorerServer, body: dict[str, Any], field: str, words: str) -> None:
    status, out = request(server, "POST", "/api/machine", body)
    assert status == 422, out
    message = out["errors"][field]
    assert words in message and "\n" not in message


def test_the_page_draws_a_machine_file_s_xy_path(server: ExplorerServer,
                                                 tmp_path: Path) -> None:
    if not CHROMIUM.exists():
        pytest.skip(MISSING)
    sync_api = playwright()
    machine_file = tmp_path / "carry.toml"
    machine_file.write_text(CARRY, encoding="utf-8")
    errors: list[str] = []
    with sync_api.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=str(CHROMIUM), args=ARGS)
        try:
            page = browser.new_page(viewport={"width": 1500, "height": 1100})
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(server.url)
            page.wait_for_selector("#machine-name option[value='xy-table']", state="attached",
                                   timeout=60_000)
            page.set_input_files("#machine-file", str(machine_file))
            page.wait_for_function("document.querySelector('#machine-name').value "
                                   "=== '__file__'", timeout=30_000)
            page.click("#machine-run")
            page.wait_for_function("document.querySelector('#machine-facts').textContent"
                                   ".includes('carry (inertial)')", timeout=300_000)
            traces = page.evaluate("() => document.querySelector('#plot-xy').data"
                                   ".map(t => [t.name, t.x.length])")
            assert [name for name, _ in traces] == ["command", "actual"]
            assert all(n > 100 for _, n in traces)
            error_trace = page.evaluate("() => document.querySelector('#plot-contour')"
                                        ".data[0].y.length")
            assert error_trace == traces[1][1]
        finally:
            browser.close()
    assert errors == []
