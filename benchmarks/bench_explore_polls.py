"""Benchmark (issue 23): how fast the explorer's server answers status polls while a compiled
run computes.

Run from the repository root (about 1 minute)::

    python benchmarks/bench_explore_polls.py [--seconds 25] [--interval 0.05]

Before issue 23 the compiled solver held Python's GIL for a whole solver call: during a CDFS
run with ``position_gain = 45`` one ``GET /api/jobs/ID`` took 45.8 s and the next timed out at
120 s.  Now every kernel is compiled with ``nogil=True`` (:mod:`feeddrive._jit`).

Scenarios (the explorer's own API, a server in this process as ``serve_in_thread`` starts it,
the solver loaded first by a short run):

* ``cdfs_120s``: wang2021 CDFS at 1 mm/s, 120 s simulated (the page's longest), polled until
  it is done;
* ``cdfs_pg45``: the issue's run, wang2021 CDFS at 1 mm/s with ``position_gain = 45`` for
  120 s simulated — the loop is unstable and the solver grinds through tiny steps; polled for
  ``--seconds`` of wall time, then cancelled (the cancel stops the compiled loop after the
  step it is in: ``cancelled_after_ms`` is the time until the job says so).

``progress_values`` counts the distinct simulated times the polls saw: the compiled solver
writes its time into its memory as it steps and the explorer reads it 10 times a second.

Each poll is a fresh HTTP connection, as the page's ``fetch`` makes; latency is wall time
(``perf_counter``) from the request to the parsed answer.  Writes
``benchmarks/results/bench_explore_polls.json``.
"""

from __future__ import annotations

import argparse
import http.client
import json
import os
import platform
import statistics
import time
from pathlib import Path
from typing import Any

OUT = Path(__file__).resolve().parent / "results" / "bench_explore_polls.json"


def _request(port: int, method: str, path: str, body: Any = None) -> tuple[int, Any]:
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=180)
    try:
        headers = {"Content-Type": "application/json"} if body is not None else {}
        conn.request(method, path, body=None if body is None else json.dumps(body),
                     headers=headers)
        resp = conn.getresponse()
        return resp.status, json.loads(resp.read())
    finally:
        conn.close()


def _poll(port: int, settings: dict[str, str], seconds: float, interval: float
          ) -> dict[str, Any]:
    status, job = _request(port, "POST", "/api/jobs", {"kind": "simulate",
                                                       "settings": settings})
    assert status == 202, job
    latencies, progress = [], []
    started = time.perf_counter()
    state = "running"
    while time.perf_counter() - started < seconds:
        t0 = time.perf_counter()
        status, answer = _request(port, "GET", f"/api/jobs/{job['id']}")
        latencies.append(time.perf_counter() - t0)
        assert status == 200, answer
        progress.append(answer["progress"]["done"])
        state = answer["state"]
        if state != "running":
            break
        time.sleep(interval)
    wall = time.perf_counter() - started
    cancel_ms = None
    if state == "running":
        # the cancel stops the compiled loop after the step it is in
        t0 = time.perf_counter()
        _request(port, "POST", f"/api/jobs/{job['id']}/cancel", {})
        end = time.monotonic() + 120
        while state == "running" and time.monotonic() < end:
            time.sleep(0.01)
            _, answer = _request(port, "GET", f"/api/jobs/{job['id']}")
            state = answer["state"]
        cancel_ms = round(1e3 * (time.perf_counter() - t0), 1)
    ms = sorted(1e3 * x for x in latencies)
    return {"polls": len(ms), "wall_s": round(wall, 2), "final_state": state,
            "cancelled_after_ms": cancel_ms,
            "median_ms": round(statistics.median(ms), 2),
            "p95_ms": round(ms[int(0.95 * (len(ms) - 1))], 2), "max_ms": round(ms[-1], 2),
            "over_50_ms": sum(x > 50.0 for x in ms),
            "progress_values": len(set(progress)),
            "simulated_s_reached": max(progress) if progress else 0.0}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=25.0)
    parser.add_argument("--interval", type=float, default=0.05)
    args = parser.parse_args()
    from feeddrive.explore import serve_in_thread

    srv = serve_in_thread(0, warm_up=False)
    try:
        _poll(srv.port, {"drive": "cdfs", "table_speed": "1", "duration": "2"}, 300, 0.05)
        results = {
            "cdfs_120s": _poll(srv.port, {"drive": "cdfs", "table_speed": "1",
                                          "duration": "120"}, 300, args.interval),
            "cdfs_pg45": _poll(srv.port, {"drive": "cdfs", "table_speed": "1",
                                          "duration": "120", "position_gain": "45"},
                               args.seconds, args.interval),
        }
    finally:
        srv.shutdown()
        srv.server_close()
    record = {"machine": {"python": platform.python_version(), "cpus": os.cpu_count(),
                          "processor": platform.processor() or platform.machine()},
              "interval_s": args.interval, "results": results}
    OUT.parent.mkdir(exist_ok=True)
    OUT.write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")
    print(json.dumps(record, indent=2))


if __name__ == "__main__":
    main()
