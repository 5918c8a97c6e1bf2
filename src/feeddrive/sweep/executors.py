"""Running a sweep: one code path over any ``concurrent.futures.Executor``.

* local (default): ``concurrent.futures.ProcessPoolExecutor`` with ``workers`` processes
  (default: every core), started by ``spawn``;
* Dask: ``distributed.Client(ADDRESS).get_executor()`` for an existing cluster
  (``--scheduler``), or a ``distributed.LocalCluster`` of N single-threaded worker processes
  (``--dask-workers``).

Whichever executor runs them, every point is one call of :func:`.quantities.evaluate` on one
task; the parent alone writes the store (a remote worker needs no access to it), each result
committed as it arrives.  Before fanning out, the parent compiles every model structure the
sweep needs once (:func:`.quantities.warm`): numba keeps them on disk, so local workers load
them (≈ 1 s) instead of compiling each (5–10 s); Dask workers are warmed the same way
(``Client.run``) before the first point, and their in-process caches keep the modules.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import multiprocessing
import os
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

from .design import Point, SweepConfig
from .quantities import evaluate, warm
from .store import SweepStore

__all__ = ["DASK_HINT", "Estimate", "SweepAborted", "SweepSummary", "estimate", "executor",
           "run_sweep"]

DASK_HINT = "Dask executors need dask.distributed: pip install 'feeddrive[dask]'"
# one thread per worker process: the parallelism is across points
_THREAD_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")

#: progress callback: (points done, points to do, seconds of the last point)
Progress = Callable[[int, int], None]


class SweepAborted(RuntimeError):
    """The executor lost a worker (a process killed, out of memory, a Dask worker gone):
    the points finished so far are stored; rerunning resumes."""


def _lost_worker(err: BaseException) -> bool:
    if isinstance(err, cf.process.BrokenProcessPool):
        return True
    return type(err).__name__ in ("KilledWorker", "CommClosedError", "FutureCancelledError")


@dataclass(frozen=True)
class SweepSummary:
    """What a run did: design points, distinct computations, found already stored, computed
    now, failed (stored with their error), wall time [s] and workers."""

    points: int
    distinct: int
    stored_before: int
    computed: int
    failed: int
    seconds: float
    workers: int
    executor: str

    @property
    def rate(self) -> float:
        """Computed points per second of wall time."""
        return self.computed / self.seconds if self.seconds > 0 else float("nan")


@contextlib.contextmanager
def _single_threaded_children() -> Iterator[None]:
    saved = {k: os.environ.get(k) for k in _THREAD_ENV}
    os.environ.update({k: "1" for k in _THREAD_ENV})
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _dask() -> Any:
    try:
        import distributed
    except ImportError:
        raise ValueError(DASK_HINT) from None
    return distributed


def _warm_worker(tasks: list[dict[str, Any]]) -> None:
    for task in tasks:
        warm(task)


@contextlib.contextmanager
def executor(*, workers: int | None = None, scheduler: str | None = None,
             dask_workers: int | None = None, warm_tasks: list[dict[str, Any]] | None = None
             ) -> Iterator[tuple[cf.Executor, int, str]]:
    """(executor, worker count, description): a local process pool, or Dask."""
    if scheduler is not None and dask_workers is not None:
        raise ValueError("--scheduler and --dask-workers: give one, not both")
    if scheduler is not None or dask_workers is not None:
        distributed = _dask()
        cluster = None
        with contextlib.ExitStack() as stack:
            if scheduler is not None:
                try:
                    client = distributed.Client(scheduler, timeout="20s")
                except OSError as err:
                    raise ValueError(f"--scheduler = {scheduler!r}: cannot connect "
                                     f"({err})") from None
            else:
                assert dask_workers is not None
                if dask_workers < 1:
                    raise ValueError(f"--dask-workers = {dask_workers}: expected ≥ 1")
                stack.enter_context(_single_threaded_children())
                cluster = distributed.LocalCluster(
                    n_workers=dask_workers, threads_per_worker=1, processes=True,
                    dashboard_address=None, silence_logs=40)
                stack.callback(cluster.close)
                client = distributed.Client(cluster)
            stack.callback(client.close)
            n = len(client.scheduler_info()["workers"])
            if warm_tasks:
                client.run(_warm_worker, warm_tasks)
            where = scheduler if scheduler is not None else "LocalCluster"
            pool = client.get_executor(pure=False)
            yield pool, n, f"dask ({where}, {n} workers)"
        return
    n = workers or os.cpu_count() or 1
    if n < 1:
        raise ValueError(f"--workers = {n}: expected ≥ 1")
    # the pool starts its processes on demand (spawn): keep the setting for its lifetime
    with _single_threaded_children():
        pool = cf.ProcessPoolExecutor(max_workers=n,
                                      mp_context=multiprocessing.get_context("spawn"))
        try:
            yield pool, n, f"local ({n} processes)"
        finally:
            pool.shutdown(wait=True, cancel_futures=True)


def _structure_tasks(points: list[Point]) -> list[dict[str, Any]]:
    """One task per distinct model structure among ``points`` (drive, and every non-numeric
    setting: friction laws, modes …; numbers do not change the compiled code)."""
    seen: dict[tuple[Any, ...], dict[str, Any]] = {}
    for p in points:
        sig = (p.task["drive"], p.task["quantity"]["kind"],
               tuple(sorted((k, repr(v)) for k, v in p.coords.items()
                            if not isinstance(v, int | float) or isinstance(v, bool))))
        seen.setdefault(sig, p.task)
    return list(seen.values())


def description(config: SweepConfig) -> dict[str, Any]:
    """What the store records about a sweep (exports and maps read it back)."""
    return {"config": config.raw, "source": config.source, "design": config.design,
            "axes": [{"name": a.name, "unit": a.unit, "relative": a.relative,
                      "values": None if config.design != "grid" else a.grid()}
                     for a in config.axes],
            "quantity": config.quantity.to_dict(), "map": list(config.map_axes)}


def run_sweep(config: SweepConfig, store: SweepStore, *, workers: int | None = None,
              scheduler: str | None = None, dask_workers: int | None = None,
              points: list[Point] | None = None,
              progress: Progress | None = None,
              started: Callable[[int, str], None] | None = None) -> SweepSummary:
    """Compute every design point of ``config`` not yet in ``store``; see the module.

    ``progress(done, todo)`` after each stored point; ``started(todo, executor)`` once the
    executor is up.  Stored points are never recomputed; a failed point (its simulation
    failed) is stored with its error, so a rerun does not retry it.
    """
    t0 = time.perf_counter()
    points = config.points() if points is None else points
    store.register(config.name, description(config),
                   [(p.index, p.key, p.coords) for p in points])
    tasks: dict[str, dict[str, Any]] = {}
    for p in points:
        tasks.setdefault(p.key, p.task)
    done_before = store.finished(tasks)
    todo = {k: t for k, t in tasks.items() if k not in done_before}
    failed = computed = 0
    n_workers, where = 0, "none"
    if todo:
        todo_points = [p for p in points if p.key in todo]
        structures = _structure_tasks(todo_points)
        for task in structures:
            warm(task)
        with executor(workers=workers, scheduler=scheduler, dask_workers=dask_workers,
                      warm_tasks=structures) as (pool, n_workers, where):
            if started is not None:
                started(len(todo), where)
            futures = {pool.submit(evaluate, task): key for key, task in todo.items()}
            try:
                for fut in cf.as_completed(futures):
                    value = fut.result()
                    store.put(futures[fut], value)
                    computed += 1
                    failed += "error" in value
                    if progress is not None:
                        progress(computed, len(todo))
            except BaseException as err:
                for f in futures:
                    f.cancel()
                if isinstance(err, Exception) and _lost_worker(err):
                    raise SweepAborted(f"{where}: a worker was lost ({type(err).__name__}: "
                                       f"{err}); {computed} points stored this run, rerun "
                                       "to resume") from None
                raise
    return SweepSummary(points=len(points), distinct=len(tasks), stored_before=len(done_before),
                        computed=computed, failed=failed, seconds=time.perf_counter() - t0,
                        workers=n_workers, executor=where)


@dataclass(frozen=True)
class Estimate:
    """A sweep's point count and cost.  ``seconds_per_point`` is the mean CPU time [s] of the
    timed points (CPU, not wall: a loaded machine's wall time made the estimate vary 3.0–10.8 s
    between runs of one config, issue 24 item 11); ``point_seconds`` each timed point's."""

    points: int
    distinct: int
    stored: int
    timed: int
    seconds_per_point: float
    workers: int
    point_seconds: tuple[float, ...] = ()

    @property
    def spread(self) -> tuple[float, float]:
        """(fastest, slowest) timed point [s CPU]; the points of a sweep differ in cost."""
        if not self.point_seconds:
            return (0.0, 0.0)
        return (min(self.point_seconds), max(self.point_seconds))

    @property
    def seconds(self) -> float:
        """Estimated wall time [s] of the remaining points on ``workers`` workers."""
        remaining = self.distinct - self.stored
        return remaining * self.seconds_per_point / max(self.workers, 1)


def estimate(config: SweepConfig, store: SweepStore | None, *, workers: int,
             sample: int = 3, points: list[Point] | None = None,
             progress: Callable[[str], None] | None = None) -> Estimate:
    """Count the points and time up to ``sample`` of the unfinished ones here (kernels
    warmed first, nothing written), in CPU seconds of this process; ``progress`` is told
    what is being done."""
    points = config.points() if points is None else points
    tasks: dict[str, dict[str, Any]] = {}
    for p in points:
        tasks.setdefault(p.key, p.task)
    stored = store.finished(tasks) if store is not None else set()
    todo = [k for k in tasks if k not in stored]
    picks = [todo[round(i * (len(todo) - 1) / max(sample - 1, 1))]
             for i in range(min(sample, len(todo)))]
    picks = list(dict.fromkeys(picks))
    if progress is not None and picks:
        progress(f"compiling the model kernels, then timing {len(picks)} of the "
                 f"{len(todo)} points to compute (each a full evaluation, nothing stored)")
    for task in _structure_tasks([p for p in points if p.key in set(picks)]):
        warm(task)
    seconds = []
    for i, key in enumerate(picks, start=1):
        if progress is not None:
            progress(f"timing point {i} of {len(picks)}")
        t = time.process_time()
        evaluate(tasks[key])
        seconds.append(time.process_time() - t)
    mean = sum(seconds) / len(seconds) if seconds else 0.0
    return Estimate(points=len(points), distinct=len(tasks), stored=len(stored),
                    timed=len(seconds), seconds_per_point=mean, workers=workers,
                    point_seconds=tuple(seconds))
