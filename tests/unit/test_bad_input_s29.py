"""Library-level findings of the bad-input sweep of session 29: each was taken without a word
(a worker count dropped, a setting the quantity never reads, a resting table judged, one
trace counted twice) and is now one refusal naming what was given and what was expected."""

from __future__ import annotations

from typing import Any

import pytest

from feeddrive.sweep.executors import check_executor


@pytest.mark.parametrize("kw", [{"workers": 2, "dask_workers": 2},
                                {"workers": 2, "scheduler": "tcp://127.0.0.1:1"}])
def test_a_local_pool_size_beside_dask_is_refused(kw: dict[str, Any]) -> None:
    """``--workers 2 --dask-workers 2`` ran on Dask and dropped ``--workers``."""
    other = "--dask-workers" if "dask_workers" in kw else "--scheduler"
    with pytest.raises(ValueError, match=f"--workers = 2 and {other}: give one, not both"):
        check_executor(**kw)
