"""Issue 11: the explorer's server, driven by plain HTTP requests (no browser).

What the page shows is computed here; these tests check the answers, that every bad field
gets the CLI's own message, that settings survive the address and a TOML file, that long
runs report progress and can be cancelled, and that nothing a page sends crashes the server.
"""

from __future__ import annotations

import http.client
import json
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.analysis.critical import format_integration_error
from feeddrive.cli import app
from feeddrive.explore import ExplorerServer, serve_in_thread
from feeddrive.explore import settings as st

runner = CliRunner()
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def server() -> Iterator[ExplorerServer]:
    srv = serve_in_thread(0)
    assert srv.explorer.ready.wait(300), "the solver warm-up did not finish"
    yield srv
    srv.shutdown()
    srv.server_close()


def request(srv: ExplorerServer, method: str, path: str, body: Any = None,
            headers: dict[str, str] | None = None, raw: bytes | None = None
            ) -> tuple[int, Any]:
    conn = http.client.HTTPConnection("127.0.0.1", srv.port, timeout=60)
    try:
        hdrs = {"Content-Type": "application/json"} if body is not None or raw else {}
        hdrs.update(headers or {})
        data = raw if raw is not None else (None if body is None else json.dumps(body))
        conn.request(method, path, body=data, headers=hdrs)
        resp = conn.getresponse()
        payload = resp.read()
        ctype = resp.getheader("Content-Type") or ""
        return resp.status, json.loads(payload) if "json" in ctype else payload
    finally:
        conn.close()


def run_job(srv: ExplorerServer, kind: str, settings: dict[str, Any],
            timeout: float = 120.0) -> dict[str, Any]:
    status, job = request(srv, "POST", "/api/jobs", {"kind": kind, "settings": settings})
    assert status == 202, job
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        status, job = request(srv, "GET", f"/api/jobs/{job['id']}")
        assert status == 200
        if job["state"] != "running":
            return dict(job)
        time.sleep(0.02)
    raise AssertionError(f"{kind} did not finish in {timeout} s")


def check(srv: ExplorerServer, **settings: Any) -> dict[str, Any]:
    status, out = request(srv, "POST", "/api/check", {"settings": settings})
    assert status == 200
    return dict(out)


# ------------------------------------------------------------------ assets: no CDN


def test_page_and_plotly_come_from_the_installed_packages(server: ExplorerServer) -> None:
    from importlib import resources

    status, page = request(server, "GET", "/")
    assert status == 200
    html = page.decode()
    assert '<script src="/static/plotly.min.js"' in html
    assert "http://" not in html and "https://" not in html and "//cdn" not in html
    status, js = request(server, "GET", "/static/plotly.min.js")
    assert status == 200
    shipped = (resources.files("plotly") / "package_data" / "plotly.min.js").read_bytes()
    assert js == shipped and len(js) > 1_000_000
    for name in ("explore.js", "explore.css"):
        status, body = request(server, "GET", f"/static/{name}")
        assert status == 200 and len(body) > 1000
        assert b"https://" not in body


# ------------------------------------------------------------------ the CLI's messages


def _cli_error(*args: str) -> str:
    result = runner.invoke(app, list(args))
    assert result.exit_code == 2, result.output
    return " ".join(result.output.split())


@pytest.mark.parametrize("field, value, cli", [
    ("table_speed", "abc", ["simulate", "--table-speed", "abc"]),
    ("table_speed", "inf", ["simulate", "--table-speed", "inf"]),
    ("nut_speed", "nan", ["simulate", "--drive", "ddfs", "--table-speed", "1", "--nut-speed",
                          "nan"]),
    ("position", "900", ["simulate", "--table-speed", "1", "--position", "900"]),
    ("position", "-4", ["simulate", "--table-speed", "1", "--position", "-4"]),
    ("duration", "0", ["simulate", "--table-speed", "1", "--duration", "0"]),
    ("duration", "1,5", ["simulate", "--table-speed", "1", "--duration", "1,5"]),
])
def test_a_bad_run_field_gets_the_message_the_cli_prints(
        server: ExplorerServer, field: str, value: str, cli: list[str]) -> None:
    out = check(server, drive="ddfs", **{field: value})
    assert set(out["errors"]) == {field}, out["errors"]
    assert out["errors"][field] in _cli_error(*cli)


@pytest.mark.parametrize("field, value, toml", [
    ("velocity_gain", "-3", "[controller]\nvelocity_gain = -3.0"),
    ("velocity_gain", "abc", '[controller]\nvelocity_gain = "abc"'),
    ("position_gain", "2e6", "[controller]\nposition_gain = 2e6"),
    ("velocity_integral_gain", "x1", '[controller]\nvelocity_integral_gain = "x1"'),
    ("ripple_amplitude", "-1", "[disturbances.screw_motor_ripple]\norders = [6.0]\n"
                               "amplitudes = [-1.0]\nphases = [0.0]"),
    ("ripple_order", "1e9", "[disturbances.screw_motor_ripple]\norders = [1e9]\n"
                            "amplitudes = [0.0]\nphases = [0.0]"),
    ("compensation", "magic", '[controller.compensation]\nmode = "magic"'),
])
def test_a_bad_parameter_gets_the_message_params_check_prints(
        server: ExplorerServer, tmp_path: Path, field: str, value: str, toml: str) -> None:
    out = check(server, drive="cdfs", **{field: value})
    assert set(out["errors"]) == {field}, out["errors"]
    path = tmp_path / "bad.toml"
    path.write_text(f'extends = "wang2021"\n{toml}\n', encoding="utf-8")
    result = runner.invoke(app, ["params", "check", str(path)])
    assert result.exit_code != 0
    # the CLI names the file first (issue 13), then the explorer's message word for word
    assert result.stderr.strip() == f"error: {path}: {out['errors'][field]}"


def test_friction_scale_is_checked_like_a_parameter(server: ExplorerServer) -> None:
    for value, text in (("0", "friction_scale = 0.0: expected 0.001 … 10 [-]"),
                        ("ten", "friction_scale = 'ten': expected a number [-]")):
        assert check(server, friction_scale=value)["errors"]["friction_scale"].startswith(text)


def test_several_bad_fields_each_get_their_own_message(server: ExplorerServer) -> None:
    out = check(server, drive="ddfs", table_speed="fast", nut_speed="x", position="0",
                velocity_gain="-1", friction_scale="0", ripple_amplitude="-2")
    assert set(out["errors"]) == {"table_speed", "nut_speed", "position", "velocity_gain",
                                  "friction_scale", "ripple_amplitude"}


def test_si_looking_values_draw_the_cli_warning_beside_the_field(
        server: ExplorerServer) -> None:
    out = check(server, table_speed="0.0005", position="0.4")
    assert not out["errors"]
    # 0.2 s: past the start ramp's 0.1 s, so the run's own summary adds no warning of the
    # ramp (session 25) to the field warnings compared
    cli = runner.invoke(app, ["simulate", "--table-speed", "0.0005", "--position", "0.4",
                              "--duration", "0.2"])
    # the fields' warnings (the run's own summary may add its own about the run, e.g. a stick
    # phase its 1-ms record does not resolve: session 26)
    warnings = [ln.removeprefix("warning: ") for ln in cli.stderr.splitlines()
                if ln.startswith("warning: --")]
    assert sorted(out["warnings"].values()) == sorted(warnings)
    assert set(out["warnings"]) == {"table_speed", "position"}


def test_a_zero_command_is_refused_beside_the_table_speed(server: ExplorerServer) -> None:
    job = run_job(server, "simulate", {"table_speed": "0", "duration": "0.2"})
    assert job["state"] == "failed" and job["field"] == "table_speed"
    assert f"error: {job['error']}" in _cli_error("simulate", "--table-speed", "0",
                                                  "--duration", "0.2")


def test_fields_a_drive_does_not_use_are_disabled(server: ExplorerServer) -> None:
    assert "nut_speed" in check(server, drive="cdfs")["disabled"]
    assert "nut_speed" not in check(server, drive="ddfs")["disabled"]
    lm = check(server, preset="linear-motor-example", drive="linear-motor")
    assert not lm["errors"]
    assert {"nut_speed", "ripple_amplitude", "ripple_order"} <= set(lm["disabled"])
    refused = check(server, preset="wang2021", drive="linear-motor")
    assert "linear_motor" in refused["errors"]["drive"]


# ------------------------------------------------------------------ what it shows


def test_ddfs_at_half_a_mm_per_s_is_smooth_and_the_cdfs_creeps(server: ExplorerServer) -> None:
    """Wang2021 Fig. 8: the DDFS (hollow motor at 16 mm/s) moves smoothly at 0.5 mm/s, where
    the CDFS (critical speed 1.56 mm/s, Sect. 5.2) sticks and slips."""
    ddfs = run_job(server, "simulate", {"drive": "ddfs", "table_speed": "0.5",
                                        "nut_speed": "16"})
    assert ddfs["state"] == "done", ddfs
    res = ddfs["result"]
    assert res["verdict"]["verdict"] == "smooth" and res["verdict"]["kind"] == "smooth"
    direct = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "ddfs", 0.4),
                         fd.ConstantSpeed(0.5e-3, 16e-3), 10.0).summary()
    assert res["summary"]["ripple_ratio"] == pytest.approx(direct["ripple_ratio"], rel=1e-9)
    traces = res["traces"]
    assert len(traces["time_s"]) == res["samples_sent"] <= 4000 < res["samples"]
    assert traces["table_speed_reference_mm_s"][-1] == pytest.approx(0.5)
    sites = {c["site"]: c for c in res["friction"]["sites"]}
    assert set(sites) == {"screw", "nut", "guide"}
    assert sites["nut"]["operating_speed_mm_s"] == pytest.approx(16.0, rel=1e-3)

    # the CDFS's stick-slip at 0.5 mm/s is irregular: the limit-cycle rule's envelope test
    # decides it at some lengths and not at others, moved by the integration error (10, 20,
    # 24, 30 s at accuracy 1 … 0.001: creeping or undecided, measured 2026-12-04); an
    # undecided run says "a longer simulated time decides", and the test follows that advice
    # as the creep protocol does (doubling the length, feeddrive.analysis.critical.decide)
    duration = 10.0
    while True:
        cdfs = run_job(server, "simulate", {"drive": "cdfs", "table_speed": "0.5",
                                            "duration": f"{duration:g}"})
        v = cdfs["result"]["verdict"]
        if v["verdict"] != "undecided" or duration >= 80.0:
            break
        assert "a longer simulated time decides" in v["text"]
        duration *= 2
    assert v["verdict"] == "creeping" and v["kind"] == "stick-slip"
    assert set(c["site"] for c in cdfs["result"]["friction"]["sites"]) == {"screw", "guide"}


def test_friction_curves_show_the_negative_slope_bands(server: ExplorerServer) -> None:
    res = run_job(server, "simulate", {"drive": "cdfs", "table_speed": "2",
                                       "duration": "1", "friction_scale": "0.5"})["result"]
    screw = next(c for c in res["friction"]["sites"] if c["site"] == "screw")
    params = fd.preset("wang2021").friction.screw
    band = fd.friction.negative_slope_band(params.positive)
    assert [pytest.approx(1e3 * band.lower), pytest.approx(1e3 * band.upper)] \
        in screw["negative_slope_mm_s"]
    v = np.array(screw["speed_mm_s"]) * 1e-3
    full = fd.friction.steady_friction(v, params)
    assert np.allclose(screw["force_n"], 0.5 * full, rtol=1e-5)


def test_the_linear_job_gives_the_stability_band_and_the_poles(server: ExplorerServer) -> None:
    from feeddrive.analysis.linear import loop_analysis, stability_band

    job = run_job(server, "linear", {"drive": "cdfs", "table_speed": "1"})
    assert job["state"] == "done", job
    res = job["result"]
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    band = stability_band(system, 0.0).as_dict()
    assert np.allclose(res["band"]["unstable_bands_mm_s"], band["unstable_bands_mm_s"])
    assert res["inside_band"] is True  # 1 mm/s lies in 0.17–1.39 mm/s
    poles = loop_analysis(system, 1e-3, 0.0, frictionless=False).as_dict()
    assert res["least_damped_mode"] == pytest.approx(poles["least_damped_mode"])
    assert res["least_damped_mode"]["damping_ratio"] < 0


def test_the_compensation_knob_switches_the_observer_on(server: ExplorerServer) -> None:
    """Issue 14's result on the page: a LuGre observer removes the CDFS's creep at 1 mm/s."""
    plain = run_job(server, "simulate", {"drive": "cdfs", "table_speed": "1"})
    observed = run_job(server, "simulate", {"drive": "cdfs", "table_speed": "1",
                                            "compensation": "observer"})
    assert plain["result"]["verdict"]["verdict"] == "creeping"
    assert observed["result"]["verdict"]["verdict"] == "smooth"
    assert "compensation=observer" in check(server, compensation="observer")["query"]


# ------------------------------------------------------------------ critical speed


def test_critical_speed_matches_feeddrive_creep(server: ExplorerServer) -> None:
    job = run_job(server, "critical", {"drive": "cdfs"}, timeout=300)
    assert job["state"] == "done", job
    cli = runner.invoke(app, ["creep", "--drive", "cdfs", "--json"])
    assert cli.exit_code == 0, cli.output
    assert job["result"]["critical_speed_mm_s"] == json.loads(cli.stdout)["critical_speed_mm_s"]
    assert job["progress"]["done"] == len(job["result"]["trials"])
    # and the same integration error, said as the CLI says it (the deciding trials' shadow)
    search = json.loads(cli.stdout)["searches"][0]
    assert job["result"]["speed_error_mm_s"] == search["speed_error_mm_s"]
    assert job["result"]["speed_error_method"] == "shadow"
    assert job["result"]["integration_error_text"] == (
        format_integration_error(search).strip(" []"))
    assert job["result"]["integration_error_text"].startswith("integration error estimated")


def test_critical_speed_reports_progress_and_can_be_cancelled(server: ExplorerServer) -> None:
    status, job = request(server, "POST", "/api/jobs",
                          {"kind": "critical", "settings": {"drive": "ddfs"}})
    assert status == 202
    assert job["progress"]["text"].startswith("trial 1 of about")
    # the job as the cancel left it (a GET before the cancel raced with the trials: two could
    # finish between it and the cancel)
    _, at_cancel = request(server, "POST", f"/api/jobs/{job['id']}/cancel", {})
    while job["state"] == "running":
        time.sleep(0.02)
        _, job = request(server, "GET", f"/api/jobs/{job['id']}")
    assert job["state"] == "cancelled"
    assert job["progress"]["done"] < job["progress"]["total"]  # stopped, not finished
    # the work after the cancel: the trial running then at most (issue 24 item 14: was a
    # wall-clock bound of 5 s)
    assert job["progress"]["done"] <= at_cancel["progress"]["done"] + 1


# ------------------------------------------------------------------ sharing


def test_the_address_carries_the_settings(server: ExplorerServer) -> None:
    out = check(server, drive="ddfs", table_speed="0.4", nut_speed="20", position="300",
                velocity_gain="40", ripple_amplitude="0.02", friction_scale="0.8")
    query = out["query"]
    assert "velocity_gain=40" in query and "position_gain" not in query  # overrides only
    status, state = request(server, "GET", f"/api/state?{query}")
    assert status == 200 and not state["errors"]
    assert state["settings"] == out["settings"]
    assert state["query"] == query


def test_export_then_import_gives_the_same_drive(server: ExplorerServer,
                                                 tmp_path: Path) -> None:
    settings = {"drive": "ddfs", "table_speed": "0.45", "nut_speed": "20", "position": "300",
                "duration": "8", "velocity_gain": "40", "ripple_amplitude": "0.01",
                "ripple_order": "12", "friction_scale": "0.7"}
    status, exported = request(server, "POST", "/api/export", {"settings": settings})
    assert status == 200
    path = tmp_path / exported["filename"]
    path.write_text(exported["toml"], encoding="utf-8")
    assert runner.invoke(app, ["params", "check", str(path)]).exit_code == 0
    effective = st.check(settings).params
    loaded = fd.load(path)
    assert loaded.controller == effective.controller
    assert loaded.friction == effective.friction
    assert loaded.disturbances == effective.disturbances

    status, imported = request(server, "POST", "/api/import", {"toml": exported["toml"]})
    assert status == 200 and not imported["errors"]
    s = imported["settings"]
    assert {k: s[k] for k in ("drive", "table_speed", "nut_speed", "position", "duration")} \
        == {"drive": "ddfs", "table_speed": "0.45", "nut_speed": "20", "position": "300",
            "duration": "8"}
    assert s["velocity_gain"] == "40" and s["friction_scale"] == "1"  # baked into the set
    again = st.check(s).params
    assert again.friction == effective.friction and again.controller == effective.controller
    # an imported set travels in the address too
    status, state = request(server, "GET", f"/api/state?{imported['query']}")
    assert status == 200 and not state["errors"]
    assert st.check(state["settings"]).params == again


def test_a_refused_file_is_reported_not_imported(server: ExplorerServer) -> None:
    for text, words in (("not toml [", "not valid TOML"),
                        ('extends = "/etc/other.toml"', "explorer reads no other file"),
                        ('extends = "wang2021"\n[table]\nmass = -1.0', "table.mass")):
        status, out = request(server, "POST", "/api/import", {"toml": text})
        assert status == 422 and words in out["errors"]["import"]


# ------------------------------------------------------------------ robustness


def test_nothing_a_page_sends_crashes_the_server(server: ExplorerServer) -> None:
    bad_settings: list[Any] = [
        {"preset": "nope"}, {"drive": "bicycle"}, {"table_speed": [1, 2]},
        {"position": {"x": 1}}, {"duration": "1e400"}, {"duration": "1000"},
        {"velocity_gain": None}, {"compensation": "magic"}, {"params": "][garbage"},
        {"table_speed": True}, {"ripple_order": "-1"},
    ]
    for settings in bad_settings:
        status, out = request(server, "POST", "/api/check", {"settings": settings})
        assert status == 200, (settings, out)
        status, out = request(server, "POST", "/api/jobs", {"kind": "simulate",
                                                            "settings": settings})
        assert status in (202, 422), (settings, out)
    assert request(server, "POST", "/api/check", raw=b"{not json")[0] == 400
    assert request(server, "POST", "/api/check", raw=b"[1, 2]")[0] == 400
    assert request(server, "POST", "/api/check", raw=b"{}",
                   headers={"Content-Type": "text/plain"})[0] == 415
    assert request(server, "POST", "/api/jobs", {"kind": "dance", "settings": {}})[0] == 400
    assert request(server, "GET", "/api/jobs/none-1")[0] == 404
    assert request(server, "GET", "/etc/passwd")[0] == 404
    assert request(server, "GET", "/static/../server.py")[0] == 404
    assert request(server, "GET", "/api/state?params=AAAA")[1]["errors"]["params"]
    # another host name (a rebound DNS name) is refused
    assert request(server, "GET", "/api/info", headers={"Host": "evil.example:80"})[0] == 403
    assert request(server, "GET", "/api/info")[0] == 200


def test_long_durations_are_refused_with_the_explorer_limit(server: ExplorerServer) -> None:
    out = check(server, duration="1000")
    assert out["errors"]["duration"] == (f"--duration = 1000.0: expected ≤ {st.MAX_DURATION:g}"
                                         " [s] in the explorer (feeddrive simulate runs "
                                         "longer ones)")


def test_a_simulation_reports_its_expected_time(server: ExplorerServer) -> None:
    status, job = request(server, "POST", "/api/jobs", {"kind": "simulate", "settings": {
        "drive": "ddfs", "table_speed": "0.5", "duration": "30"}})
    assert status == 202 and job["expected_s"] is not None and job["expected_s"] > 0
    end = time.monotonic() + 60
    while job["state"] == "running" and time.monotonic() < end:
        time.sleep(0.02)
        _, job = request(server, "GET", f"/api/jobs/{job['id']}")
    assert job["state"] == "done"
    assert job["result"]["duration_s"] == 30.0


# ------------------------------------------------------------------ the command


def test_feeddrive_explore_prints_its_address_and_stops_on_ctrl_c(
        interruptible: dict[str, Any]) -> None:
    proc = subprocess.Popen([sys.executable, "-m", "feeddrive", "explore", "--port", "0",
                             "--preset", "wang2021"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, **interruptible)
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert line.startswith("feeddrive explore: http://127.0.0.1:"), line
        url = line.split()[2]
        port = int(url.rsplit(":", 1)[1].strip("/"))
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
        conn.request("GET", "/api/info")
        info = json.loads(conn.getresponse().read())
        conn.close()
        assert info["initial"]["preset"] == "wang2021"
        from feeddrive.model import drive_names

        assert info["drives"] == list(drive_names())  # every registered topology
        assert {"cdfs", "ddfs", "linear-motor", "rack-pinion"} <= set(info["drives"])
    finally:
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    assert "stopped" in out and "Traceback" not in err


def test_feeddrive_explore_refuses_bad_options_in_one_line(tmp_path: Path) -> None:
    for args in (["--preset", "nope"], ["--port", "70000"],
                 ["--params", str(tmp_path / "missing.toml")],
                 ["--preset", "wang2021", "--params", "x.toml"]):
        result = runner.invoke(app, ["explore", *args])
        assert result.exit_code == 2, (args, result.output)
        lines = [s for s in result.stderr.splitlines() if s.startswith("error: ")]
        assert len(lines) == 1 and "Traceback" not in result.output


def test_a_taken_port_is_refused_with_a_message(server: ExplorerServer) -> None:
    result = runner.invoke(app, ["explore", "--port", str(server.port)])
    assert result.exit_code == 2
    assert result.stderr.startswith(f"error: --port = {server.port}: cannot listen")


def test_without_plotly_the_explorer_says_which_extra_to_install(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from importlib import resources

    from feeddrive.explore import server as srv

    def missing(name: str) -> Any:
        raise ModuleNotFoundError(f"No module named {name!r}")

    monkeypatch.setattr(resources, "files", missing)
    result = runner.invoke(app, ["explore", "--port", "0"])
    assert result.exit_code == 2
    assert "pip install 'feeddrive[explore]'" in result.stderr
    with pytest.raises(srv.MissingDependency):
        srv.plotly_js()


def test_the_started_parameter_file_is_the_page_s_base(tmp_path: Path) -> None:
    path = tmp_path / "mine.toml"
    path.write_text('extends = "wang2021"\nname = "mine"\n[controller]\nvelocity_gain = 30.0\n',
                    encoding="utf-8")
    srv = serve_in_thread(0, {"params": fd.parameters.dumps(fd.load(path))}, warm_up=False)
    try:
        status, info = request(srv, "GET", "/api/info")
        out = check(srv, **info["initial"])
        assert out["base_name"] == "mine" and out["settings"]["velocity_gain"] == "30"
        assert out["query"].startswith("params=")
    finally:
        srv.shutdown()
        srv.server_close()


# ------------------------------------------------------------------ docs


def test_docs_name_the_fields_routes_and_options_the_code_has() -> None:
    import re

    from feeddrive.explore import server as srv

    doc = (ROOT / "docs" / "explore.md").read_text(encoding="utf-8")
    for f in st.FIELDS:
        assert f"`{f.name}`" in doc, f.name
    for route in re.findall(r"``((?:GET|POST) /[^`]*)``", srv.__doc__ or ""):
        assert f"`{route}`" in doc, route
    shown = runner.invoke(app, ["explore", "--help"]).stdout
    for option in re.findall(r"`feeddrive explore[^`]*`", doc):
        for name in re.findall(r"--[a-z-]+", option):
            assert name in shown, name
    assert f"{st.MAX_DURATION:g} s" in doc


def test_a_browser_resetting_a_kept_alive_connection_prints_nothing(
        server: ExplorerServer, capfd: pytest.CaptureFixture[str]) -> None:
    """Closing the page resets its kept-alive connection while the server waits for the next
    request line; socketserver printed a ConnectionResetError traceback in the user's terminal
    (seen in the browser test's teardown)."""
    import socket
    import struct
    import time

    sock = socket.create_connection(("127.0.0.1", server.port))
    sock.sendall(b"GET /api/info HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
    sock.recv(65536)  # the answer; the connection stays open (HTTP/1.1)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    sock.close()  # SO_LINGER 0: an RST, as a browser closing the tab may send
    time.sleep(0.3)
    _, err = capfd.readouterr()
    assert "Traceback" not in err and "ConnectionResetError" not in err, err
    assert request(server, "GET", "/api/info")[0] == 200  # still serving
