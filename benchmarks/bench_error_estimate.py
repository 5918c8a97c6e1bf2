"""Benchmark: the CPU cost of the embedded global-error estimate inside the creep search
(issue 35 item 3: ≤ 10 % extra, embedded, not a second run).

Run from the repository root::

    python benchmarks/bench_error_estimate.py [--repeats N]

The trials of ``reproduce``'s critical-speed searches from rest (the study's settings,
:class:`feeddrive.reproduce.studies.StudySettings`): the CDFS at mid-screw (Table 3's row) and
the DDFS at mid-screw with the hollow motor at the paper's simulated speed (Fig. 8's search),
each searched with and without ``error_estimate`` in the same process, alternating, the
compiled drivers loaded first.  Records the machine's load average before and after, and per
search the CPU seconds of each (the smallest of
the repeats), their ratio, the critical speeds (which must agree: the runs are bit-identical)
and the speed error the estimate states for each.

Writes ``benchmarks/results/bench_error_estimate.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import feeddrive as fd  # noqa: E402
from feeddrive.analysis.critical import critical_speed_from_rest  # noqa: E402
from feeddrive.engine.simulate import DriveSystem, Simulation  # noqa: E402
from feeddrive.model.reference import ConstantSpeed  # noqa: E402
from feeddrive.reproduce.paper import PAPER  # noqa: E402
from feeddrive.reproduce.runner import MID  # noqa: E402
from feeddrive.reproduce.studies import StudySettings  # noqa: E402

SEARCHES = (("cdfs", 0.0), ("ddfs", PAPER["ddfs_sim_nut_speed"]))


def search(drive: str, nut: float, estimate: bool) -> tuple[float, dict]:
    """CPU seconds and the result of one search."""
    settings = StudySettings()
    system = DriveSystem(fd.preset("wang2021"), drive=drive, table_position=MID)
    began = time.process_time()
    res = critical_speed_from_rest(system, nut_speed=nut, speed_range=settings.speed_range,
                                   coarse_step=settings.coarse_step,
                                   resolution=settings.resolution, rule=settings.rule(),
                                   error_estimate=estimate)
    return time.process_time() - began, res.to_dict()


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    load_before = list(os.getloadavg())
    params = fd.preset("wang2021")
    for estimate in (False, True):  # compile / load both paths before timing
        Simulation(DriveSystem(params, "ddfs", MID), ConstantSpeed(1e-3, 16e-3),
                   embedded_estimate=estimate).run(0.05)
    rows = []
    for drive, nut in SEARCHES:
        cpu: dict[bool, list[float]] = {False: [], True: []}
        found: dict[bool, dict] = {}
        for _ in range(args.repeats):
            for estimate in (False, True):
                seconds, found[estimate] = search(drive, nut, estimate)
                cpu[estimate].append(seconds)
        off, on = min(cpu[False]), min(cpu[True])
        same = (found[False]["critical_speed_mm_s"] == found[True]["critical_speed_mm_s"]
                and [t["kind"] for t in found[False]["trials"]]
                == [t["kind"] for t in found[True]["trials"]])
        row = {"drive": drive, "nut_speed_mm_s": 1e3 * nut,
               "trials": len(found[True]["trials"]),
               "simulated_s": found[True]["simulated_time_s"],
               "cpu_s_without": off, "cpu_s_with": on, "cpu_ratio": on / off,
               "cpu_s_all": {"without": cpu[False], "with": cpu[True]},
               "same_verdicts": same,
               "critical_speed_mm_s": found[True]["critical_speed_mm_s"],
               "speed_error_mm_s": found[True].get("speed_error_mm_s"),
               "largest_trial_speed_error_mm_s": max(
                   (t.get("speed_error_mm_s") or 0.0) for t in found[True]["trials"])}
        rows.append(row)
        print(f"{drive} vn={1e3 * nut:g} mm/s: {row['trials']} trials, CPU {off:.2f} s → "
              f"{on:.2f} s with the estimate (×{on / off:.3f}); critical "
              f"{row['critical_speed_mm_s']} mm/s, speed error estimate "
              f"{row['speed_error_mm_s']} mm/s; same verdicts: {same}", flush=True)
    total_off = sum(r["cpu_s_without"] for r in rows)
    total_on = sum(r["cpu_s_with"] for r in rows)
    out = {"machine": {"nproc": os.cpu_count(), "python": sys.version.split()[0],
                       "load_average_before": load_before,
                       "load_average_after": list(os.getloadavg())},
           "recorded": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "target_cpu_ratio": 1.10, "repeats": args.repeats, "searches": rows,
           "cpu_ratio_total": total_on / total_off}
    print(f"total CPU ratio ×{total_on / total_off:.3f} (target ≤ 1.10)")
    path = ROOT / "benchmarks" / "results" / "bench_error_estimate.json"
    path.write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
