"""Stopping a local worker pool (:func:`feeddrive._workers.stop_workers`, a sweep's and
``reproduce``'s Ctrl-C)."""

from __future__ import annotations

import concurrent.futures as cf
import time

from feeddrive._workers import stop_workers


def test_the_pools_manager_thread_has_ended_when_stop_workers_returns() -> None:
    """A fresh-clone test run (2026-12-07) saw Ctrl-C on ``reproduce`` end with a traceback
    from the interpreter's exit: "OSError: [Errno 9] Bad file descriptor".  CPython 3.11's
    ``concurrent.futures`` exit hook writes to the pool's wake-up pipe unlocked, while the
    pool's manager thread, still ending after ``stop_workers``, closes that pipe (3 of 60 runs
    of a pool stopped and the interpreter left at once).  Now ``stop_workers`` waits for the
    manager thread, so nothing is left to race the exit."""
    pool = cf.ProcessPoolExecutor(1)
    future = pool.submit(time.sleep, 30.0)
    while not pool._processes:  # the worker is started
        time.sleep(0.01)
    manager = pool._executor_manager_thread  # shutdown() forgets it
    assert manager is not None and manager.is_alive()
    stop_workers(pool)
    assert not manager.is_alive()
    assert future.cancelled() or future.done()
