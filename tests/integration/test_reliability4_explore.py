"""Issue 39 (reliability, round 4) items 2 and 7 in the explorer: a client's name is never
used in a path, no route answers 500 to a hostile request (a seeded fuzz of 300+ requests
over every route, names included), an internal error still is a 500, and half-open sockets
held by a local process cannot keep the page from being served.
"""

from __future__ import annotations

import json
import random
import socket
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from feeddrive.explore import server as srv_mod
from feeddrive.explore import settings as st
from feeddrive.explore.server import ExplorerServer, serve_in_thread

READ_TIMEOUT = 3.0  # [s] the test's; the explorer's is srv_mod.READ_TIMEOUT
CONNECTIONS = 8

#: the names every route that takes one is tried with (issue 39 item 2)
HOSTILE_NAMES = [".", "..", "/", "a\x00b", "n" * 300, "CON", "../../etc/passwd", "a/b.csv",
                 "\x1b[2J", "", " ", "nul.csv", "..\\..\\x.csv"]

TRACE = "time [s],position [mm]\n" + "\n".join(f"{k * 1e-3:.3f},{k * 1e-3:.6f}"
                                               for k in range(40)) + "\n"
BAD_TRACE = "time,position\n" + "".join(f"{k},x\n" for k in range(20))


@pytest.fixture(scope="module")
def server() -> Iterator[ExplorerServer]:
    patch = pytest.MonkeyPatch()
    patch.setattr(srv_mod.Handler, "timeout", READ_TIMEOUT)
    patch.setattr(srv_mod, "MAX_CONNECTIONS", CONNECTIONS)
    srv = serve_in_thread(0, warm_up=False)
    yield srv
    srv.shutdown()
    srv.server_close()
    patch.undo()


def raw(srv: ExplorerServer, data: bytes, timeout: float = 30.0) -> tuple[int, bytes]:
    """Send ``data`` as it is; (status, body) of the answer (0: closed without one)."""
    with socket.create_connection(("127.0.0.1", srv.port), timeout=timeout) as sock:
        try:
            sock.sendall(data)
            sock.shutdown(socket.SHUT_WR)
        except OSError:
            pass
        answer = b""
        while True:
            try:
                chunk = sock.recv(65536)
            except (ConnectionResetError, TimeoutError):
                break
            if not chunk:
                break
            answer += chunk
    if not answer:
        return 0, b""
    head, _, body = answer.partition(b"\r\n\r\n")
    return int(head.split()[1]), body


def request(srv: ExplorerServer, method: str, path: str, body: Any = None
            ) -> tuple[int, Any]:
    data = b"" if body is None else json.dumps(body).encode()
    head = (f"{method} {path} HTTP/1.1\r\nHost: 127.0.0.1:{srv.port}\r\nConnection: close\r\n"
            f"Content-Type: application/json\r\nContent-Length: {len(data)}\r\n\r\n")
    status, payload = raw(srv, head.encode() + data)
    try:
        return status, json.loads(payload)
    except ValueError:
        return status, payload


def _quoted(name: str) -> str:
    from urllib.parse import quote

    return quote(name, safe="")


@pytest.fixture(scope="module")
def run_id(server: ExplorerServer) -> str:
    """A finished 0.2-s run kept by the server (its signals and downloads are routes)."""
    status, job = request(server, "POST", "/api/jobs", {"kind": "simulate", "settings": {
        "drive": "cdfs", "table_speed": "1", "duration": "0.2"}})
    assert status == 202, job
    end = time.monotonic() + 300
    while time.monotonic() < end:
        _, job = request(server, "GET", f"/api/jobs/{job['id']}")
        if job["state"] != "running":
            assert job["state"] == "done", job
            return str(job["id"])
        time.sleep(0.05)
    raise AssertionError("the run did not finish")


def _no_traceback(capfd: pytest.CaptureFixture[str]) -> None:
    out, err = capfd.readouterr()
    assert "Traceback" not in err and "Traceback" not in out, err


# ------------------------------------------------------------------ item 2: names


@pytest.mark.parametrize("name", HOSTILE_NAMES)
def test_a_measured_trace_name_is_never_a_path_and_only_named_in_messages(
        server: ExplorerServer, capfd: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch, name: str) -> None:
    """``"name": ".."`` was a 500 with a traceback and the temp folder in the answer."""
    from feeddrive.io import measured

    opened: list[str] = []
    original = measured.read_csv_table

    def spy(path: Any, **kw: Any) -> Any:
        opened.append(str(path))
        return original(path, **kw)

    monkeypatch.setattr(measured, "read_csv_table", spy)
    status, good = request(server, "POST", "/api/measured", {"csv": TRACE, "name": name})
    assert status == 200, good
    assert good["samples"] == 40
    status, bad = request(server, "POST", "/api/measured", {"csv": BAD_TRACE, "name": name})
    assert status == 422, bad
    assert "line 2" in bad["error"] and "'x' is not a number" in bad["error"]
    assert tempfile.gettempdir() not in bad["error"] and "feeddrive-" not in bad["error"]
    assert len(opened) == 2
    for path in opened:  # the server's own name in its own folder, never the client's
        assert Path(path).name == "measured.csv"
        assert Path(path).parent.parent == Path(tempfile.gettempdir())
    shown_name = good["name"]
    assert "\x00" not in shown_name and "\x1b" not in shown_name and len(shown_name) <= 220
    base = name.rsplit("/", 1)[-1].strip() or "measured.csv"  # as the page's file.name
    if base.isprintable() and len(base) < 200:
        assert shown_name == base and bad["error"].startswith(f"{base}, line 2: ")
    _no_traceback(capfd)


@pytest.mark.parametrize("name", HOSTILE_NAMES)
def test_every_route_that_takes_a_name_answers_it_without_a_500(
        server: ExplorerServer, run_id: str, capfd: pytest.CaptureFixture[str],
        name: str) -> None:
    q = _quoted(name)
    gets = [f"/api/runs/{run_id}/signal?name={q}", f"/api/runs/{q}/signals",
            f"/api/runs/{q}/data.csv", f"/api/runs/{run_id}/{q}", f"/api/jobs/{q}",
            f"/static/{q}", f"/api/state?preset={q}", f"/api/state?params={q}"]
    for path in gets:
        status, body = request(server, "GET", path)
        assert status in (200, 404), (path, status, body)
        if status == 404:
            assert isinstance(body, dict) and "error" in body
    status, body = request(server, "POST", f"/api/jobs/{q}/cancel", {})
    assert status == 404, body
    for route, payload in (("/api/check", {"settings": {"preset": name}}),
                           ("/api/export", {"settings": {"preset": name}}),
                           ("/api/import", {"toml": f'name = {json.dumps(name)}\n'
                                                    'extends = "wang2021"\n'}),
                           ("/api/import", {"toml": f'extends = {json.dumps(name)}\n'})):
        status, body = request(server, "POST", route, payload)
        assert status in (200, 422), (route, status, body)
    _no_traceback(capfd)


def test_an_exported_file_name_is_built_from_safe_characters_only(
        server: ExplorerServer) -> None:
    status, body = request(server, "POST", "/api/import", {
        "toml": 'name = "../../CON\\u0000x"\nextends = "wang2021"\n'})
    if status == 200:
        status, body = request(server, "POST", "/api/export", {"settings": body["settings"]})
        assert status == 200, body
        assert "/" not in body["filename"] and "\x00" not in body["filename"]
    else:
        assert status == 422 and "name" in json.dumps(body)


# ------------------------------------------------------------------ errors stay errors


def test_an_internal_error_is_still_a_500(server: ExplorerServer,
                                          capfd: pytest.CaptureFixture[str],
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """No handler maps an unknown exception to a refusal: a bug is a 500 with its type, and
    its traceback in the terminal."""
    def broken(*args: Any, **kw: Any) -> Any:
        raise RuntimeError("injected internal error")

    monkeypatch.setattr("feeddrive.io.measured.read_position_trace", broken)
    status, body = request(server, "POST", "/api/measured", {"csv": TRACE, "name": "a.csv"})
    assert status == 500 and "RuntimeError" in body["error"], body
    _, err = capfd.readouterr()
    assert "injected internal error" in err


# ------------------------------------------------------------------ fuzz


def _random_json(rng: random.Random, depth: int = 0) -> Any:
    kind = rng.randrange(8 if depth < 5 else 5)
    if kind == 0:
        return rng.choice([None, True, False])
    if kind == 1:
        return rng.choice([0, -1, 10**30, 1.5e308, -0.0, 3.25, 2**63])
    if kind == 2:
        return rng.choice(HOSTILE_NAMES + ["1", "nan", "-inf", "x" * 5000])
    if kind == 3:
        return rng.choice(list(st.FIELD) + ["csv", "name", "toml", "settings"])
    if kind == 4:
        return rng.choice([TRACE, BAD_TRACE, TRACE.replace("time [s]", "time [ms]"),
                           "time,position\n" + "1,1\n" * 16, "\xff" * 20, TRACE[:30]])
    if kind == 5:
        return [_random_json(rng, depth + 1) for _ in range(rng.randrange(4))]
    keys = list(st.FIELD) + ["settings", "toml", "kind", "csv", "name"]
    return {rng.choice(keys): _random_json(rng, depth + 1) for _ in range(rng.randrange(5))}


def test_a_seeded_fuzz_of_300_requests_over_every_route_never_answers_500(
        server: ExplorerServer, run_id: str, capfd: pytest.CaptureFixture[str]) -> None:
    rng = random.Random(39)
    paths = ["/api/check", "/api/export", "/api/import", "/api/jobs", "/api/measured",
             "/api/jobs/{n}/cancel", "/api/jobs/{n}", "/api/state", "/api/info",
             "/api/runs/{run}/signals", "/api/runs/{run}/signal", "/api/runs/{n}/data.csv",
             "/api/runs/{run}/{n}", "/static/{n}", "/", "/nowhere/{n}"]
    statuses = []
    for _ in range(320):
        method = rng.choice(["GET", "GET", "POST", "POST", "POST", "HEAD", "PUT"])
        n = _quoted(rng.choice(HOSTILE_NAMES))
        path = rng.choice(paths + ["/api/measured"] * 3).format(n=n, run=run_id)
        if path.endswith("/signal") or path == "/api/state":
            path += "?" + rng.choice([f"name={n}", f"preset={n}", "name=table_speed",
                                      f"params={n}", "table_speed=1e400"])
        body = _random_json(rng)
        if path == "/api/measured" and rng.random() < 0.8:
            body = {"csv": rng.choice([TRACE, BAD_TRACE, TRACE, 5]),
                    "name": rng.choice([*HOSTILE_NAMES, ".", "..", 3])}
        if isinstance(body, dict) and "kind" in body:
            body["kind"] = "none"  # a valid job would start a simulation
        data = json.dumps(body).encode() if rng.random() < 0.85 else rng.randbytes(
            rng.randrange(1, 200))
        headers = [f"Host: 127.0.0.1:{server.port}", "Connection: close"]
        if rng.random() < 0.95:
            headers.append("Content-Type: application/json" if rng.random() < 0.85 else
                           "Content-Type: text/plain")
        length = len(data) if rng.random() < 0.85 else rng.choice(["x", -1, len(data) + 3])
        headers.append(f"Content-Length: {length}")
        request_bytes = (f"{method} {path} HTTP/1.1\r\n" + "\r\n".join(headers) +
                         "\r\n\r\n").encode() + (data if method != "GET" else b"")
        status, _ = raw(server, request_bytes, timeout=READ_TIMEOUT + 20)
        statuses.append(status)
        assert status != 500, request_bytes[:300]
    assert len(statuses) >= 300 and statuses.count(0) == 0  # every request answered
    assert {200, 404, 422} <= set(statuses)
    _no_traceback(capfd)


# ------------------------------------------------------------------ item 7: half-open sockets


@pytest.fixture()
def patient_server(monkeypatch: pytest.MonkeyPatch) -> Iterator[ExplorerServer]:
    """A server whose read timeout is far longer than any wait below: what frees a slot
    there is the explorer's own doing, not a timeout."""
    monkeypatch.setattr(srv_mod.Handler, "timeout", 120.0)
    monkeypatch.setattr(srv_mod, "MAX_CONNECTIONS", CONNECTIONS)
    srv = serve_in_thread(0, warm_up=False)
    yield srv
    srv.shutdown()
    srv.server_close()


def _hold(srv: ExplorerServer, n: int, partial: bool) -> list[socket.socket]:
    """``n`` connections that send nothing (or half a request line) and stay open."""
    held = []
    for _ in range(n):
        s = socket.create_connection(("127.0.0.1", srv.port), timeout=30)
        if partial:
            s.sendall(b"GET /api/info HTTP/1.1\r\nHost: 127.0.0.1\r\n")
        held.append(s)
    deadline = time.monotonic() + 10
    while srv._slots._value > 0 and time.monotonic() < deadline:  # all accepted
        time.sleep(0.01)
    return held


def test_half_open_sockets_cannot_hold_the_explorer(
        patient_server: ExplorerServer, capfd: pytest.CaptureFixture[str]) -> None:
    """A local process that keeps every slot with idle connections (and opens them again)
    was answered 503 for every real request until its sockets timed out; now a connection
    waiting for its request gives its slot to a new one, oldest first."""
    srv = patient_server
    info = (f"GET /api/info HTTP/1.1\r\nHost: 127.0.0.1:{srv.port}\r\n"
            "Connection: close\r\n\r\n").encode()
    held: list[socket.socket] = []
    try:
        for round_ in range(3):  # the process reconnects what it lost
            held += _hold(srv, CONNECTIONS, partial=round_ % 2 == 1)
            status, _ = raw(srv, info)
            assert status == 200, round_
        closed = 0
        for s in held:
            s.settimeout(0.5)
            try:
                closed += s.recv(65536) == b""
            except (TimeoutError, ConnectionResetError):
                pass
        assert closed >= 3  # evicted, oldest first; the rest still held
    finally:
        for s in held:
            s.close()
    _no_traceback(capfd)


def test_connections_busy_with_requests_are_never_evicted(
        patient_server: ExplorerServer, monkeypatch: pytest.MonkeyPatch,
        capfd: pytest.CaptureFixture[str]) -> None:
    """Only a connection waiting for its request gives way: with every slot computing an
    answer, one more connection is answered 503 at once, and every busy one is answered."""
    import threading

    srv = patient_server
    release = threading.Event()
    entered = threading.Semaphore(0)
    original = srv_mod.check

    def slow_check(settings: Any) -> Any:
        entered.release()
        release.wait(60)
        return original(settings)

    monkeypatch.setattr(srv_mod, "check", slow_check)
    answers: list[int] = []

    def busy() -> None:
        answers.append(request(srv, "POST", "/api/check", {"settings": {}})[0])

    threads = [threading.Thread(target=busy) for _ in range(CONNECTIONS)]
    for t in threads:
        t.start()
    for _ in range(CONNECTIONS):
        assert entered.acquire(timeout=30)
    status, body = raw(srv, f"GET /api/info HTTP/1.1\r\nHost: 127.0.0.1:{srv.port}\r\n"
                       "Connection: close\r\n\r\n".encode())
    assert status == 503 and b"too many connections" in body
    release.set()
    for t in threads:
        t.join(60)
    assert answers == [200] * CONNECTIONS
    _no_traceback(capfd)
