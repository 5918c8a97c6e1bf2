"""Parameter sweeps: designs, quantities, executors (local pool, Dask), store, maps, export.

Pipeline: a TOML configuration (:func:`load_config`) → design points, each a task keyed by a
hash of its inputs → :func:`run_sweep` on a local process pool or a Dask cluster, each result
committed at once to a :class:`SweepStore` (SQLite) → :func:`to_dataset` / :func:`export`,
:func:`plot_map`, :func:`plot_histogram`.  See docs/sweeps.md.
"""

from __future__ import annotations

from .design import Axis, Point, SweepConfig, load_config, parse_config
from .executors import Estimate, SweepSummary, estimate, executor, run_sweep
from .export import EXPORT_FORMATS, export, to_dataset, to_frame, to_table
from .maps import percentiles, plot_histogram, plot_map
from .quantities import QUANTITIES, QuantitySettings, evaluate
from .store import StoreError, SweepStore, point_key

__all__ = [
    "EXPORT_FORMATS", "QUANTITIES", "Axis", "Estimate", "Point", "QuantitySettings",
    "StoreError", "SweepConfig", "SweepStore", "SweepSummary", "estimate", "evaluate",
    "executor", "export", "load_config", "parse_config", "percentiles", "plot_histogram",
    "plot_map", "point_key", "run_sweep", "to_dataset", "to_frame", "to_table",
]
