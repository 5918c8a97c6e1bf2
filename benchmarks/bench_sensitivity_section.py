"""Benchmark: the report's sensitivity section (`feeddrive reproduce`'s ``sensitivity`` task,
issue 42 item 5), before and after its points linearise for the linear band's upper edge
only, alternated in one process (the machine is shared: compare within one run).

Run from the repository root::

    python benchmarks/bench_sensitivity_section.py

"before": every in-process point through :func:`feeddrive.sweep.quantities.evaluate` (the
whole stability band: the 20-point scan, both edges bisected, the mode frequency); "after":
:func:`feeddrive.analysis.linear.upper_band_edge` (the scan from the top down to its first
unstable speed, that change bisected).  Records the CPU seconds of
:func:`feeddrive.reproduce.sensitivity_section.compute`, the linearisations (calls of
:func:`feeddrive.analysis.linear.rightmost_pole`), the points, and whether the stored dict is
identical.  Writes ``benchmarks/results/bench_sensitivity_section.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    import feeddrive as fd
    from feeddrive.analysis import linear
    from feeddrive.analysis import sensitivity as sens
    from feeddrive.reproduce import sensitivity_section
    from feeddrive.sweep.quantities import evaluate

    params = fd.preset("wang2021")
    count = [0]
    original = linear.rightmost_pole

    def counted(*args: Any, **kw: Any) -> tuple[float, float]:
        count[0] += 1
        return original(*args, **kw)

    linear.rightmost_pole = counted  # type: ignore[assignment]
    upper = sens._linear_upper
    sensitivity_section.compute(params)  # compiled code loaded
    rows, stored = [], []
    for variant in ("before", "after", "before", "after"):
        sens._linear_upper = evaluate if variant == "before" else upper  # type: ignore
        count[0] = 0
        began = time.process_time()
        data = sensitivity_section.compute(params)
        rows.append({"variant": variant, "cpu_s": round(time.process_time() - began, 3),
                     "linearisations": count[0], "points": data["evaluations"]})
        stored.append(json.dumps(data, sort_keys=True))
        print(rows[-1], flush=True)
    out = {"benchmark": "python benchmarks/bench_sensitivity_section.py (niced, machine "
                        "shared by other sessions)",
           "python": sys.version.split()[0], "rows": rows,
           "stored_dict_identical": len(set(stored)) == 1,
           "load_average_at_end": os.getloadavg()}
    path = ROOT / "benchmarks" / "results" / "bench_sensitivity_section.json"
    path.write_text(json.dumps(out, indent=1) + "\n")
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
