"""Benchmark: the C build without numba against the C build with numba installed (issue 42
item 2: numba an optional extra).

Run from the repository root, in an environment where numba is importable (``pip install -e
".[numba]"``, or its folder given with ``--numba-path``)::

    python benchmarks/bench_nonumba.py [--rounds 3] [--numba-path DIR]

Two commands, each in fresh processes, both with the engine's C build (a compiler present):

* ``feeddrive simulate --drive cdfs --table-speed 2 --duration 10 --json`` — a CDFS 10-s run;
* ``feeddrive creep --drive cdfs --json`` — the critical-speed search, from rest and by the
  step-down protocol.

"with numba": numba importable (the kernels numba dispatchers, compiled on first use from
numba's disk cache).  "without numba": numba hidden by a folder first on ``PYTHONPATH`` whose
``numba`` package raises ``ImportError`` at import (the children of the command — the
pool's workers — inherit it), so the package runs as after ``pip install feeddrive``.
What the acceptance asks: nothing hot falls into plain Python, so "without" is about as fast
as "with".

One warm-up run of each command and configuration fills the caches (the C libraries, numba's
cache, bytecode); then ``--rounds`` rounds, the two configurations alternating within each
round (the same load).  CPU is user + system of the whole process tree
(``getrusage(RUSAGE_CHILDREN)``: a pool's workers are waited for by the command, the command
by this script), wall from start to exit; medians, the load average before and after.
The JSON outputs of the two configurations are compared (the solver's own ``wall_time_s``
left out): the same numbers, or the script fails.

Writes ``benchmarks/results/bench_nonumba.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from bench_startup import fresh_process  # the benchmarks' folder is the script's

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "bench_nonumba.json"

COMMANDS = {
    "simulate CDFS 10 s": ["simulate", "--drive", "cdfs", "--table-speed", "2", "--duration",
                           "10", "--json"],
    "creep CDFS": ["creep", "--drive", "cdfs", "--json"],
}


def _without_wall_time(data: Any) -> Any:
    if isinstance(data, dict):
        return {k: _without_wall_time(v) for k, v in data.items()
                if k not in ("wall_time_s", "seconds")}
    if isinstance(data, list):
        return [_without_wall_time(v) for v in data]
    return data


def _run(args: list[str], env: dict[str, str]) -> tuple[float, float, Any, str]:
    """CPU [s] of the process tree, wall [s], the JSON output and the engine's stderr."""
    wall, cpu, proc = fresh_process([sys.executable, "-m", "feeddrive", *args], env)
    return cpu, wall, json.loads(proc.stdout), proc.stderr.decode()


def _environments(numba_path: str | None, hide: Path) -> dict[str, dict[str, str]]:
    base = {k: v for k, v in os.environ.items() if k not in ("FEEDDRIVE_ENGINE", "PYTHONPATH")}
    src = str(ROOT / "src")
    with_numba = dict(base, PYTHONPATH=os.pathsep.join(p for p in (src, numba_path) if p))
    without = dict(base, PYTHONPATH=os.pathsep.join((str(hide), src)))
    return {"with numba": with_numba, "without numba": without}


def _check_numba(envs: dict[str, dict[str, str]]) -> dict[str, str]:
    """The numba each configuration sees (a version, or "absent")."""
    # importing it, not feeddrive._jit.HAVE_NUMBA: that one only finds the package (numba is
    # imported where its build runs), and the hiding folder's package is found
    code = ("try:\n"
            "    import numba\n"
            "    print(numba.__version__)\n"
            "except ImportError:\n"
            "    print('absent')")
    seen = {}
    for name, env in envs.items():
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             env=env, cwd=ROOT, check=True)
        seen[name] = out.stdout.strip()
    if seen["with numba"] == "absent" or seen["without numba"] != "absent":
        raise SystemExit(f"numba not as wanted: {seen} (give --numba-path)")
    return seen


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--numba-path", default=None,
                        help="a folder holding numba (pip install --target), put on PYTHONPATH "
                             "for the 'with numba' runs")
    opts = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        hide = Path(tmp)
        (hide / "numba").mkdir()
        (hide / "numba" / "__init__.py").write_text(
            'raise ImportError("numba hidden by benchmarks/bench_nonumba.py")\n')
        envs = _environments(opts.numba_path, hide)
        versions = _check_numba(envs)
        load_before = os.getloadavg()
        rows = []
        for label, args in COMMANDS.items():
            outputs: dict[str, Any] = {}
            engines: dict[str, str] = {}
            for config, env in envs.items():  # warm-up: the caches filled
                _, _, outputs[config], stderr = _run(args, env)
                engines[config] = stderr.strip()
            cpu: dict[str, list[float]] = {c: [] for c in envs}
            wall: dict[str, list[float]] = {c: [] for c in envs}
            for _ in range(opts.rounds):
                for config, env in envs.items():
                    c, w, out, _ = _run(args, env)
                    cpu[config].append(c)
                    wall[config].append(w)
                    if _without_wall_time(out) != _without_wall_time(outputs[config]):
                        raise SystemExit(f"{label}: {config} gave another output on a rerun")
            same = (_without_wall_time(outputs["with numba"])
                    == _without_wall_time(outputs["without numba"]))
            if not same:
                raise SystemExit(f"{label}: the outputs with and without numba differ")
            row = {"command": "feeddrive " + " ".join(args), "label": label,
                   "outputs_equal": same, "stderr": engines,
                   **{f"cpu_s_{c.replace(' ', '_')}": statistics.median(cpu[c]) for c in envs},
                   **{f"wall_s_{c.replace(' ', '_')}": statistics.median(wall[c]) for c in envs},
                   "cpu_s_all": cpu, "wall_s_all": wall}
            row["cpu_ratio_without_to_with"] = (row["cpu_s_without_numba"]
                                                / row["cpu_s_with_numba"])
            engine = outputs["without numba"].get("solver", {}).get("engine")
            if engine is not None:
                row["engine_without_numba"] = engine
            rows.append(row)
            print(f"{label}: CPU with numba {row['cpu_s_with_numba']:.2f} s, without "
                  f"{row['cpu_s_without_numba']:.2f} s (ratio "
                  f"{row['cpu_ratio_without_to_with']:.2f}); wall "
                  f"{row['wall_s_with_numba']:.2f} / {row['wall_s_without_numba']:.2f} s")
        load_after = os.getloadavg()
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                          text=True, cwd=ROOT, check=False).stdout.strip()
    record = {"recorded": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
              "tree": head, "python": platform.python_version(), "numba": versions,
              "rounds": opts.rounds, "cpus": os.cpu_count(),
              "load_before": load_before, "load_after": load_after, "rows": rows}
    RESULTS.write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")
    print(f"written {RESULTS.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
