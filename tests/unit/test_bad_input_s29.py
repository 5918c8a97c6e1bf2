"""Library-level findings of the bad-input sweep of session 29: each was taken without a word
(a worker count dropped, a setting the quantity never reads, a resting table judged, one
trace counted twice) and is now one refusal naming what was given and what was expected."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from feeddrive.sweep.executors import check_executor


@pytest.mark.parametrize("kw", [{"workers": 2, "dask_workers": 2},
                                {"workers": 2, "scheduler": "tcp://127.0.0.1:1"}])
def test_a_local_pool_size_beside_dask_is_refused(kw: dict[str, Any]) -> None:
    """``--workers 2 --dask-workers 2`` ran on Dask and dropped ``--workers``."""
    other = "--dask-workers" if "dask_workers" in kw else "--scheduler"
    with pytest.raises(ValueError, match=f"--workers = 2 and {other}: give one, not both"):
        check_executor(**kw)


@pytest.mark.parametrize("held_at", [0.0, 0.005, 0.1234567, 0.8])
def test_a_table_at_rest_is_not_judged(held_at: float) -> None:
    """A trace of a table held still (at 5 mm: its fitted slope -7.7e-16 mm/s, the rounding
    of the fit's sums) was judged against that "command": UNSTABLE, ripple ratio 1.24e+04."""
    from feeddrive.analysis.trace import analyze_trace

    t = np.arange(3000) * 1e-3
    with pytest.raises(ValueError, match=r"^still\.csv: no moving segment to analyse \(the "
                                         r"table does not move\)$"):
        analyze_trace(t, np.full(t.size, held_at), source="still.csv")


def test_a_slow_table_still_moves() -> None:
    from feeddrive.analysis.trace import analyze_trace

    t = np.arange(3000) * 1e-3
    result = analyze_trace(t, 0.8 + 1e-6 * t, source="slow.csv")  # 1 µm/s at 800 mm
    assert [round(s.command_speed, 12) for s in result.segments] == [1e-6]
