"""Benchmark: how long Ctrl-C takes to stop a running sweep, and what it keeps (issue 25).

Run from the repository root::

    python benchmarks/bench_interrupt.py [--rounds 3]

Each round starts ``python -m feeddrive sweep`` (local pool, 2 workers) on 16 CDFS creep
trials of 20 s simulated time each (a few seconds of compute per point), waits until the first
point is stored, sends SIGINT to the sweep's process only (a terminal's Ctrl-C), and measures:

* **message**: from the signal to the sweep's one-line ``interrupted:`` message (the store is
  closed by then: every point it reports is committed);
* **workers gone**: from the signal until no worker process of the sweep is left
  (multiprocessing's resource tracker is not a worker: it ends with the sweep);
* **exit**: from the signal to the process's exit (status 130): the message, then the Python
  interpreter's own teardown (numba and LLVM loaded; the same for every feeddrive command);
* **kept**: the points the sweep reports stored this run, and the points in the store (they
  must be equal: every finished point kept), and whether the store grows afterwards (it must
  not: the points in flight are cancelled, not left running).

The test (tests/integration/test_reliability3_cli.py) checks the behaviour; the time is measured
here, not asserted.  Writes ``benchmarks/results/bench_interrupt.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import signal
import sqlite3
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CONFIG = """
name = "interrupt"
drive = "cdfs"
[quantity]
kind = "creep-trial"
initial_duration = 20.0
max_duration = 20.0
linear = false
[axes]
table_speed = [0.5, 1.0, 2.0, 3.0]
table_position = [250, 350, 450, 550]
"""


def _stored(path: Path) -> int:
    try:
        db = sqlite3.connect(path, timeout=30)
        try:
            return int(db.execute("SELECT COUNT(*) FROM results").fetchone()[0])
        finally:
            db.close()
    except sqlite3.Error:
        return 0


def _children(pid: int) -> set[int]:
    out = set()
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                out.add(int(entry.name))
    return out


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def one_round(folder: Path) -> dict[str, float]:
    cfg, store = folder / "c.toml", folder / "s.sqlite"
    cfg.write_text(CONFIG)
    proc = subprocess.Popen([sys.executable, "-m", "feeddrive", "sweep", str(cfg), "--store",
                             str(store), "--workers", "2"], cwd=folder,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    while proc.poll() is None and _stored(store) < 1:
        time.sleep(0.02)
    time.sleep(0.5)  # the next points are in flight
    workers = {p for p in _children(proc.pid)
               if b"resource_tracker" not in Path(f"/proc/{p}/cmdline").read_bytes()}
    lines: list[tuple[float, str]] = []

    def read() -> None:
        assert proc.stderr is not None
        for line in proc.stderr:
            lines.append((time.monotonic(), line))

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    sent = time.monotonic()
    proc.send_signal(signal.SIGINT)
    gone = None
    while proc.poll() is None or gone is None:
        if gone is None and not any(_alive(p) for p in workers):
            gone = time.monotonic() - sent
        if time.monotonic() - sent > 120:
            raise TimeoutError("the sweep did not stop")
        time.sleep(0.005)
    stopped = time.monotonic() - sent  # (to 5 ms)
    reader.join(10)
    err = "".join(text for _, text in lines)
    message = next(t for t, text in lines if text.startswith("interrupted:")) - sent
    reported = int(re.findall(r"\((\d+) computed this run", err)[0])
    in_store = _stored(store)
    time.sleep(2.0)
    return {"status": proc.returncode, "message_s": message, "exit_s": stopped,
            "workers_gone_s": gone,
            "kept_reported": reported, "kept_in_store": in_store,
            "grew_afterwards": _stored(store) - in_store, "points": 16}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    rounds = []
    for _ in range(args.rounds):
        with tempfile.TemporaryDirectory() as tmp:
            rounds.append(one_round(Path(tmp)))
            print(rounds[-1], flush=True)
    out = {"machine": {"python": platform.python_version(), "cpus": os.cpu_count(),
                       "load_average": os.getloadavg()[0]},
           "rounds": rounds,
           "max_message_s": max(r["message_s"] for r in rounds),
           "max_exit_s": max(r["exit_s"] for r in rounds),
           "max_workers_gone_s": max(r["workers_gone_s"] for r in rounds)}
    dest = ROOT / "benchmarks" / "results" / "bench_interrupt.json"
    dest.write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
