"""CPU seconds (user + sys) of the test suite per test file (issue 41 item 14).

Run it on an otherwise idle machine, from the repository root, with the test extra installed:

    .venv/bin/python benchmarks/cpu_per_test_file.py            # pytest -n 2, as the README
    .venv/bin/python benchmarks/cpu_per_test_file.py -n 0 -- tests/unit   # any pytest args

It runs pytest with this file as a plugin (``-p cpu_per_test_file``): around every test's
setup, call and teardown the plugin reads ``resource.getrusage`` of the process and of its
finished children (subprocesses, process pools; a pool still alive when the test ends is
counted where it is reaped) and adds the difference to the test's file; collection is counted
as ``(collection)``.  Each process (each xdist worker) writes its share to a JSON file; the
script adds them up, writes ``benchmarks/results/cpu_per_test_file.json`` and ``.md``, and
states the whole pytest command's CPU (the script's children: every worker and what they
started) beside the sum over the files.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
_ENV = "FEEDDRIVE_CPU_PER_FILE_DIR"


def _cpu() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


# ------------------------------------------------------------------ the pytest plugin

_per_file: dict[str, float] = defaultdict(float)
_tests: dict[str, int] = defaultdict(int)
_start = [0.0]


def pytest_sessionstart(session: Any) -> None:
    _start[0] = _cpu()


def pytest_collection_finish(session: Any) -> None:
    _per_file["(collection)"] += _cpu() - _start[0]


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item: Any, nextitem: Any) -> Any:
    before = _cpu()
    yield
    name = item.location[0]
    _per_file[name] += _cpu() - before
    _tests[name] += 1


def pytest_sessionfinish(session: Any) -> None:
    folder = os.environ.get(_ENV)
    if not folder:
        return
    worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
    data = {"worker": worker, "cpu_s": dict(_per_file), "tests": dict(_tests),
            "process_cpu_s": _cpu()}
    Path(folder, f"cpu-{worker}-{os.getpid()}.json").write_text(json.dumps(data))


# ------------------------------------------------------------------ the script


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-n", default="2", help="pytest-xdist workers (0: none) [default 2]")
    ap.add_argument("--out", default=str(RESULTS / "cpu_per_test_file.json"))
    ap.add_argument("pytest_args", nargs="*", help="after --: further pytest arguments")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        env = {**os.environ, _ENV: folder,
               "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT / "benchmarks"),
                                                           os.environ.get("PYTHONPATH")]))}
        cmd = [sys.executable, "-m", "pytest", "-p", "cpu_per_test_file", "-q",
               *(["-n", args.n] if args.n != "0" else []), *args.pytest_args]
        wall = time.perf_counter()
        done = subprocess.run(cmd, cwd=ROOT, env=env)
        wall = time.perf_counter() - wall
        kids = resource.getrusage(resource.RUSAGE_CHILDREN)
        command_cpu = kids.ru_utime + kids.ru_stime
        per_file: dict[str, float] = defaultdict(float)
        tests: dict[str, int] = defaultdict(int)
        for f in Path(folder).glob("cpu-*.json"):
            data = json.loads(f.read_text())
            for name, s in data["cpu_s"].items():
                per_file[name] += s
            for name, k in data["tests"].items():
                tests[name] += k
    rows = sorted(per_file.items(), key=lambda kv: -kv[1])
    record = {"command": " ".join(cmd[2:]), "exit_status": done.returncode,
              "wall_s": round(wall, 1), "command_cpu_s": round(command_cpu, 1),
              "sum_over_files_cpu_s": round(sum(per_file.values()), 1),
              "files": [{"file": n, "cpu_s": round(s, 2), "tests": tests.get(n, 0)}
                        for n, s in rows]}
    out = Path(args.out)
    out.write_text(json.dumps(record, indent=1) + "\n")
    lines = [f"`{record['command']}`: exit {done.returncode}, {record['wall_s']} s wall, "
             f"**{record['command_cpu_s']} CPU s** (user + sys of every process), "
             f"{record['sum_over_files_cpu_s']} s of it inside the tests and collection", "",
             "| file | tests | CPU s |", "| --- | ---: | ---: |"]
    lines += [f"| {n} | {tests.get(n, 0)} | {s:.1f} |" for n, s in rows]
    out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines[:12]))
    print(f"… {len(rows)} files; {out} and {out.with_suffix('.md')}")


if __name__ == "__main__":
    main()
