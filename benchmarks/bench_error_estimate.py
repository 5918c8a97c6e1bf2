"""Benchmark: the CPU cost of the integration-error estimate inside the creep search (issue 35
item 3: ≤ 10 % extra).

Run from the repository root::

    python benchmarks/bench_error_estimate.py [--repeats N]

The trials of ``reproduce``'s critical-speed searches from rest (the study's settings,
:class:`feeddrive.reproduce.studies.StudySettings`): the CDFS at mid-screw (Table 3's row) and
the DDFS at mid-screw with the hollow motor at the paper's simulated speed (Fig. 8's search),
each searched without an estimate, with the default one (``error_estimate=True``: the
deciding trials run again with every tolerance 10× tighter once the search is done, the
"shadow") and with the embedded one carried along every trial (``"embedded"``), in the same
process, in turn, the compiled drivers loaded first.  Records the machine's load average
before and after, and per search the CPU seconds of each (the smallest and the median of the
repeats), their ratios to the search without, the critical speeds (which must agree: the
trials' runs are bit-identical) and the speed error each estimate states.

Writes ``benchmarks/results/bench_error_estimate.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
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


def search(drive: str, nut: float, estimate: bool | str) -> tuple[float, dict]:
    """CPU seconds and the result of one search."""
    settings = StudySettings()
    system = DriveSystem(fd.preset("wang2021"), drive=drive, table_position=MID)
    began = time.process_time()
    res = critical_speed_from_rest(system, nut_speed=nut, speed_range=settings.speed_range,
                                   coarse_step=settings.coarse_step,
                                   resolution=settings.resolution, rule=settings.rule(),
                                   error_estimate=estimate)
    return time.process_time() - began, res.to_dict()


ESTIMATES: tuple[bool | str, ...] = (False, True, "embedded")
NAMES = {False: "without", True: "shadow", "embedded": "embedded"}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    load_before = list(os.getloadavg())
    params = fd.preset("wang2021")
    for embedded in (False, True):  # compile / load both paths before timing
        Simulation(DriveSystem(params, "ddfs", MID), ConstantSpeed(1e-3, 16e-3),
                   embedded_estimate=embedded).run(0.05)
    rows = []
    for drive, nut in SEARCHES:
        cpu: dict[str, list[float]] = {NAMES[e]: [] for e in ESTIMATES}
        found: dict[str, dict] = {}
        for _ in range(args.repeats):
            for estimate in ESTIMATES:
                seconds, found[NAMES[estimate]] = search(drive, nut, estimate)
                cpu[NAMES[estimate]].append(seconds)
        least = {k: min(v) for k, v in cpu.items()}
        median = {k: float(statistics.median(v)) for k, v in cpu.items()}
        kinds = {k: [t["kind"] for t in f["trials"]] for k, f in found.items()}
        same = (len({f["critical_speed_mm_s"] for f in found.values()}) == 1
                and kinds["shadow"] == kinds["without"] == kinds["embedded"])
        row = {"drive": drive, "nut_speed_mm_s": 1e3 * nut,
               "trials": len(found["without"]["trials"]),
               "simulated_s": found["without"]["simulated_time_s"],
               "cpu_s_least": least, "cpu_s_median": median,
               "cpu_ratio_least": {k: least[k] / least["without"] for k in ("shadow", "embedded")},
               "cpu_ratio_median": {k: median[k] / median["without"]
                                    for k in ("shadow", "embedded")},
               "cpu_s_all": cpu, "same_verdicts": same,
               "critical_speed_mm_s": found["without"]["critical_speed_mm_s"],
               "speed_error_mm_s": {k: found[k].get("speed_error_mm_s")
                                    for k in ("shadow", "embedded")}}
        rows.append(row)
        print(f"{drive} vn={1e3 * nut:g} mm/s: {row['trials']} trials, CPU (median) "
              f"{median['without']:.3f} s; the shadow ×{row['cpu_ratio_median']['shadow']:.3f}, "
              f"the embedded ×{row['cpu_ratio_median']['embedded']:.3f}; critical "
              f"{row['critical_speed_mm_s']} mm/s, speed error {row['speed_error_mm_s']} mm/s; "
              f"same verdicts: {same}", flush=True)
    total = {k: sum(r["cpu_s_median"][k] for r in rows) for k in NAMES.values()}
    out = {"machine": {"nproc": os.cpu_count(), "python": sys.version.split()[0],
                       "load_average_before": load_before,
                       "load_average_after": list(os.getloadavg())},
           "recorded": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "target_cpu_ratio": 1.10, "repeats": args.repeats, "searches": rows,
           "cpu_ratio_total_median": {k: total[k] / total["without"]
                                      for k in ("shadow", "embedded")}}
    print(f"total CPU ratio (medians): the shadow ×{out['cpu_ratio_total_median']['shadow']:.3f}, "
          f"the embedded ×{out['cpu_ratio_total_median']['embedded']:.3f} (target ≤ 1.10)")
    path = ROOT / "benchmarks" / "results" / "bench_error_estimate.json"
    path.write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
