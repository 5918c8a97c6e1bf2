"""Run the model-reading study alone and print it (``feeddrive reproduce`` runs it too).

    python scripts/reading_study.py [OUT.csv]
"""

from __future__ import annotations

import sys
from concurrent.futures import ProcessPoolExecutor

import pandas as pd

from feeddrive.reproduce.reading_study import jobs, run_variant

if __name__ == "__main__":
    with ProcessPoolExecutor(max_workers=2) as pool:
        rows = list(pool.map(run_variant, jobs()))
    df = pd.DataFrame(rows).drop(columns="changes")
    print(df.to_string(index=False))
    if len(sys.argv) > 1:
        df.to_csv(sys.argv[1], index=False)
