"""Benchmark: Ctrl-C on a sweep, a prediction and a fit, each on a local pool of 2 workers
and on a Dask LocalCluster of 2 (issue 39 item 6).

Run from the repository root::

    python benchmarks/bench_interrupt4.py [--rounds 3]   # ~5 min

Each round starts the command as a user does (``python -m feeddrive …``), waits until work
is under way (the first point stored; for the fit, its third evaluation printed), sends
SIGINT to the command's process only (a terminal's Ctrl-C; the workers ignore it: the
parent stops them) and measures from the signal:

* **message**: the one-line ``interrupted`` message on stderr (or, for the fit, the printed
  result of its best point);
* **workers gone**: no worker process of the command left;
* **exit**: the process's exit (status 130);
* **clean**: no traceback on stderr, no worker process left after the exit;
* **kept**: for the sweep and the prediction, the points in the store at the signal, at the
  exit and 2 s later (what was stored after the signal are points that had returned; the
  store must not grow after the exit: nothing was left running), and whether every reported
  point is in the store; for the fit, whether the best point was written
  (``interrupted = true``).

The load average (1 min) is recorded before and after each round: the machine is shared.
The tests (tests/integration/test_reliability4_ctrl_c.py, test_reliability3_cli.py) check the
behaviour; the times are measured here, not asserted.  Writes
``benchmarks/results/bench_interrupt4.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from bench_interrupt import ROOT, _alive, _children, _stored

#: 64 CDFS creep trials of 40 s: the sweep is still running when the signal comes
CONFIG = """
name = "interrupt"
drive = "cdfs"
[quantity]
kind = "creep-trial"
initial_duration = 40.0
max_duration = 40.0
linear = false
[axes]
table_speed = [0.5, 0.75, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5]
table_position = [250, 300, 350, 400, 450, 500, 550, 600]
"""

FIT_RECORD = """extends = "wang2021"
name = "fitted"
[fit]
drive = "cdfs"
table_position = 0.4
free = ["controller.velocity_integral_gain"]
estimates = [3925.28]
covariance = [[40000.0]]
interrupted = false
"""


def _trace(path: Path) -> None:
    """A 10-s record at 1 kHz (table position, current, command 1 mm/s)."""
    lines = ["time [s],table_position [mm],screw_current [A],table_speed_reference [mm/s]"]
    for k in range(10001):
        t = k * 1e-3
        lines.append(f"{t:.3f},{max(t - 0.1, 0.0):.6f},{0.1 + 0.01 * (k % 7):.4f},1")
    path.write_text("\n".join(lines) + "\n")


def _workers(pid: int) -> set[int]:
    return {p for p in _children(pid)
            if b"resource_tracker" not in Path(f"/proc/{p}/cmdline").read_bytes()}


def one_round(command: str, folder: Path, dask: bool = False) -> dict[str, Any]:
    store = folder / "s.sqlite"
    pool = ["--dask-workers", "2"] if dask else ["--workers", "2"]
    if command == "sweep":
        (folder / "c.toml").write_text(CONFIG)
        args = ["sweep", "c.toml", "--store", str(store), *pool]
    elif command == "predict":
        (folder / "fit.toml").write_text(FIT_RECORD)
        args = ["predict", "fit.toml", "--samples", "16", *pool, "--store", str(store)]
    else:
        _trace(folder / "t.csv")
        args = ["fit", "t.csv", "--free", "controller.velocity_integral_gain", "--free",
                "controller.velocity_gain", "--free", "friction.screw.positive.coulomb_force",
                *pool, "--no-profile", "--out", "best.toml"]
    load_before = os.getloadavg()[0]
    proc = subprocess.Popen([sys.executable, "-m", "feeddrive", *args], cwd=folder,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lines: list[tuple[float, str, str]] = []

    def read(stream: Any, name: str) -> None:
        for line in stream:
            lines.append((time.monotonic(), name, line))

    readers = [threading.Thread(target=read, args=(proc.stdout, "out"), daemon=True),
               threading.Thread(target=read, args=(proc.stderr, "err"), daemon=True)]
    for r in readers:
        r.start()
    deadline = time.monotonic() + 300
    if command == "fit":
        while proc.poll() is None and not any("evaluation 3" in t for _, _, t in lines):
            time.sleep(0.02)
    else:
        while proc.poll() is None and _stored(store) < 1:
            time.sleep(0.02)
        time.sleep(0.5)  # the next points are in flight
    if time.monotonic() > deadline or proc.poll() is not None:
        raise RuntimeError(f"{command}: ended before the signal")
    workers = _workers(proc.pid)
    at_signal = _stored(store) if command != "fit" else 0
    sent = time.monotonic()
    proc.send_signal(signal.SIGINT)
    gone = None
    while proc.poll() is None or gone is None:
        if gone is None and not any(_alive(p) for p in workers):
            gone = time.monotonic() - sent
        if time.monotonic() - sent > 120:
            proc.kill()
            raise TimeoutError(f"{command} did not stop")
        time.sleep(0.005)
    stopped = time.monotonic() - sent
    for r in readers:
        r.join(10)
    after = [(t, s, text) for t, s, text in lines if t >= sent]
    key = "interrupted (Ctrl-C) in stage" if command == "fit" else "interrupted"
    message = next((t - sent for t, _, text in after if key in text), None)
    err_text = "".join(text for _, s, text in lines if s == "err")
    out: dict[str, Any] = {"command": command, "executor": "dask" if dask else "local",
                           "status": proc.returncode, "traceback": "Traceback" in err_text,
                           "orphans": sum(_alive(p) for p in workers),
                           "message_s": message, "workers_gone_s": gone, "exit_s": stopped,
                           "workers": len(workers), "load_before": load_before}
    if command == "fit":
        best = folder / "best.toml"
        out["best_written"] = best.exists() and "interrupted = true" in best.read_text()
    else:
        at_exit = _stored(store)
        time.sleep(2.0)
        reported = re.findall(r"\((\d+) computed this run", err_text)
        out.update(stored_at_signal=at_signal, stored_at_exit=at_exit,
                   stored_after_signal=at_exit - at_signal,
                   grew_after_exit=_stored(store) - at_exit,
                   reported=int(reported[0]) if reported else None)
    out["load_after"] = os.getloadavg()[0]
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--commands", default="sweep,predict,fit")
    ap.add_argument("--executors", default="local,dask")
    args = ap.parse_args()
    rounds = []
    for _ in range(args.rounds):
        for where in args.executors.split(","):
            for command in args.commands.split(","):
                with tempfile.TemporaryDirectory() as tmp:
                    rounds.append(one_round(command, Path(tmp), dask=where == "dask"))
                    print(rounds[-1], flush=True)
    summary = {}
    for where in args.executors.split(","):
        for command in args.commands.split(","):
            mine = [r for r in rounds if r["command"] == command and r["executor"] == where]
            summary[f"{command} {where}"] = {
                k: max(r[k] for r in mine if r[k] is not None)
                for k in ("message_s", "workers_gone_s", "exit_s")}
    out = {"machine": {"python": platform.python_version(), "cpus": os.cpu_count()},
           "rounds": rounds, "max": summary}
    dest = ROOT / "benchmarks" / "results" / "bench_interrupt4.json"
    dest.write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(summary, indent=2))


if __name__ == "__main__":
    main()
