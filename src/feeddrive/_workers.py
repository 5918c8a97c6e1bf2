"""Local worker processes of a pool (a sweep's, ``reproduce``'s): started single-threaded,
tied to their parent, stopped at once.

A module of its own, outside :mod:`feeddrive.sweep`, so that a spawned worker of
``reproduce``, which imports its job's module, need not import the sweep package (whose maps
and exports imported matplotlib and pandas when it was imported: ≈ 0.5 CPU s per worker).
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import ctypes
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator

# one thread per worker process: the parallelism is across points
_THREAD_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")


@contextlib.contextmanager
def single_threaded_children() -> Iterator[None]:
    """While it lasts, processes started get one thread per numerical library (OpenMP,
    OpenBLAS, MKL, numba): a pool of single-core workers whose BLAS threads would otherwise
    busy-wait beside them on the same cores (reproduce's workers: 60.7 → 52.5 CPU s,
    benchmarks/README.md).  Only processes *started* meanwhile see it (``spawn``: a forked
    child inherits its parent's already started BLAS).  What a worker would say once about the
    engine's build (no C compiler: numba runs) is said here, once, and not by the workers."""
    from .solvers.builds import SAID_ENV, announce

    announce()  # what each worker would say about the build, said once here
    saved = {k: os.environ.get(k) for k in (*_THREAD_ENV, SAID_ENV)}
    os.environ.update({k: "1" for k in (*_THREAD_ENV, SAID_ENV)})
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def worker_start(parent: int) -> None:
    """Set up one local worker process: Ctrl-C is the parent's to handle (it stops the
    workers itself), and the worker exits when its parent dies (``SIGKILL`` of the sweep
    leaves no orphan): Linux's parent-death signal, and on every system a thread that
    checks the parent once a second."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None).prctl(1, int(signal.SIGKILL))  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent:  # the parent died before this line
        os._exit(1)

    def watch() -> None:
        while True:
            time.sleep(1.0)
            if os.getppid() != parent:
                os._exit(1)

    threading.Thread(target=watch, name="feeddrive-parent-watch", daemon=True).start()


def stop_workers(pool: cf.ProcessPoolExecutor) -> None:
    """Cancel what is queued and stop the worker processes now (their points in flight are
    lost, not stored: a rerun computes them).

    Parameters
    ----------
    pool : concurrent.futures.ProcessPoolExecutor
        The pool (a sweep's, ``reproduce``'s).
    """
    processes = list((getattr(pool, "_processes", None) or {}).values())
    manager = getattr(pool, "_executor_manager_thread", None)  # shutdown() forgets it
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in processes:
        with contextlib.suppress(Exception):
            proc.terminate()
    for proc in processes:
        with contextlib.suppress(Exception):
            proc.join(2.0)
            if proc.is_alive():
                proc.kill()
    if manager is not None:
        # the pool's manager thread closes its wake-up pipe as it ends; ended before the
        # interpreter's exit, which writes to that pipe unlocked (CPython 3.11's
        # ``_python_exit``): a Ctrl-C on ``reproduce`` printed "OSError: [Errno 9] Bad file
        # descriptor" when the two met (a fresh-clone test run, 2026-12-07)
        manager.join(2.0)
