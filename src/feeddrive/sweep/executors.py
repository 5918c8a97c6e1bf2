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
import logging
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any

from .._workers import single_threaded_children, stop_workers, worker_start
from .design import Point, SweepConfig
from .quantities import check_task, evaluate, warm
from .store import SweepStore

__all__ = ["DASK_HINT", "PROBE_DURATION", "CtrlC", "Estimate", "SweepAborted",
           "SweepInterrupted", "SweepSummary", "check_executor", "estimate", "executor",
           "run_sweep", "simulated_range"]

DASK_HINT = "Dask executors need dask.distributed: pip install 'feeddrive[dask]'"
#: progress callback: (points done, points to do, seconds of the last point)
Progress = Callable[[int, int], None]


class SweepAborted(RuntimeError):
    """The executor lost a worker (a process killed, out of memory, a Dask worker gone):
    the points finished so far are stored; rerunning resumes."""


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped the sweep: ``computed`` points were stored this run, nothing more was
    submitted, the points in flight were cancelled.

    Parameters
    ----------
    computed : int
        Points computed and stored this run.
    """

    def __init__(self, computed: int) -> None:
        super().__init__(computed)
        self.computed = computed


def _lost_worker(err: BaseException) -> bool:
    if isinstance(err, cf.process.BrokenProcessPool):
        return True
    return type(err).__name__ in ("KilledWorker", "CommClosedError", "FutureCancelledError")


@dataclass(frozen=True)
class SweepSummary:
    """What a run did: design points, distinct computations, found already stored, computed
    now, failed (stored with their error), wall time [s] and workers.

    Parameters
    ----------
    points : int
        Design points.
    distinct : int
        Distinct computations among them.
    stored_before : int
        Already stored when the run started.
    computed : int
        Computed now.
    failed : int
        Failed (stored with their error).
    seconds : float
        Wall time [s].
    workers : int
        Number of workers.
    executor : str
        Which executor ran them.
    elsewhere : int, default 0
        Points another sweep on the same store computed meanwhile.
    """

    points: int
    distinct: int
    stored_before: int
    computed: int
    failed: int
    seconds: float
    workers: int
    executor: str
    elsewhere: int = 0  # points another sweep on the same store computed meanwhile

    @property
    def rate(self) -> float:
        """Computed points per second of wall time."""
        return self.computed / self.seconds if self.seconds > 0 else float("nan")


def _dask() -> Any:
    try:
        import distributed
    except ImportError:
        raise ValueError(DASK_HINT) from None
    return distributed


def check_executor(*, workers: int | None = None, scheduler: str | None = None,
                   dask_workers: int | None = None) -> None:
    """Refuse an executor request before any work: a worker count < 1, both a scheduler and
    a local cluster, a local pool's size beside either, Dask without ``dask.distributed``.
    Every command that fans out (``sweep``, ``fit``, ``predict``, ``sensitivity``) calls it
    first (``fit --workers 0`` meant every core, issue 39 item 5).

    Parameters
    ----------
    workers : int, optional
        Local worker processes.
    scheduler : str, optional
        Address of a running Dask scheduler.
    dask_workers : int, optional
        Workers of a local Dask cluster.

    Raises
    ------
    ValueError
        Naming the option.
    """
    for option, n in (("--workers", workers), ("--dask-workers", dask_workers)):
        if n is not None and (isinstance(n, bool) or not isinstance(n, int) or n < 1):
            raise ValueError(f"{option} = {n!r}: expected a whole number ≥ 1")
    if scheduler is not None and dask_workers is not None:
        raise ValueError("--scheduler and --dask-workers: give one, not both")
    if workers is not None and (scheduler is not None or dask_workers is not None):
        # Dask ran and the local pool's count was dropped without a word (a bad-input
        # sweep, session 29): the three are one choice, as the usage lines write them
        other = "--scheduler" if scheduler is not None else "--dask-workers"
        raise ValueError(f"--workers = {workers} and {other}: give one, not both (--workers "
                         f"sizes the local process pool, {other} runs on Dask)")
    if scheduler is not None or dask_workers is not None:
        _dask()


class CtrlC:
    """Ctrl-C seen while work is handed out, so that none is handed out after it.

    As a context manager (in the main thread, while Ctrl-C acts) it installs a SIGINT
    handler that notes the signal and raises ``KeyboardInterrupt`` as Python's own does.  A
    ``KeyboardInterrupt`` raised where it is swallowed (inside a finaliser, a library's
    callback: seen once as a fit that ran on to exit status 0 after its Ctrl-C, issue 39
    item 6) is then not lost: :meth:`check`, called before each work item is handed out,
    raises it again.
    """

    def __init__(self) -> None:
        self.fired: float | None = None  # time.monotonic() of the first Ctrl-C
        self._previous: Any = None
        self._installed = False

    def _handler(self, signum: int, frame: Any) -> None:
        if self.fired is None:
            self.fired = time.monotonic()
        raise KeyboardInterrupt

    def __enter__(self) -> CtrlC:
        if threading.current_thread() is threading.main_thread() and \
                signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            self._previous = signal.signal(signal.SIGINT, self._handler)
            self._installed = True
        return self

    def __exit__(self, *exc: object) -> None:
        if self._installed:
            signal.signal(signal.SIGINT, self._previous)
            self._installed = False

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if a Ctrl-C was seen.

        Raises
        ------
        KeyboardInterrupt
            After a Ctrl-C.
        """
        if self.fired is not None:
            raise KeyboardInterrupt


@contextlib.contextmanager
def _sigint_held() -> Iterator[None]:
    """Hold a Ctrl-C that arrives inside the block until it ends, then raise it.

    For starting a Dask cluster: a ``KeyboardInterrupt`` inside ``LocalCluster(...)`` leaves
    a cluster half started that nobody can close, and distributed's own clean-up at exit
    then fails on a worker still starting (``AssertionError: Status.init``, issue 39 item 6).
    Held, the Ctrl-C is raised once the cluster and its client exist, and the caller's exit
    closes both.  Only in the main thread (where signals arrive), and not when Ctrl-C is
    ignored."""
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) in (signal.SIG_IGN, signal.SIG_DFL, None):
        yield
        return
    held: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: held.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if held:
        raise KeyboardInterrupt


def _kill_workers(cluster: Any) -> None:
    """Kill a local Dask cluster's worker processes at once (their points in flight are
    lost, not stored, as a local pool's): closing the cluster otherwise waits for each worker
    to finish its compiled point, 1.5–4 s measured (benchmarks/bench_interrupt4.py)."""
    for nanny in list(getattr(cluster, "workers", {}).values()):
        pid = getattr(getattr(getattr(nanny, "process", None), "process", None), "pid", None)
        if pid:
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)


def _warm_worker(tasks: list[dict[str, Any]]) -> None:
    for task in tasks:
        warm(task)


@contextlib.contextmanager
def executor(*, workers: int | None = None, scheduler: str | None = None,
             dask_workers: int | None = None, warm_tasks: list[dict[str, Any]] | None = None
             ) -> Iterator[tuple[cf.Executor, int, str]]:
    """Start the executor a sweep runs on: a local process pool, or Dask.

    Parameters
    ----------
    workers : int, optional
        Local worker processes; the CPU count by default.
    scheduler : str, optional
        Address of a running Dask scheduler.
    dask_workers : int, optional
        Start a local Dask cluster of this many workers.
    warm_tasks : list of dict, optional
        One task per model structure, run once on every worker to compile its kernels.

    Yields
    ------
    tuple of (concurrent.futures.Executor, int, str)
        The executor, its worker count and a description.

    Raises
    ------
    ValueError
        For both ``scheduler`` and ``dask_workers``, or a scheduler that cannot be reached.
    """
    check_executor(workers=workers, scheduler=scheduler, dask_workers=dask_workers)
    if scheduler is not None or dask_workers is not None:
        distributed = _dask()
        cluster = None
        with contextlib.ExitStack() as stack:
            with _sigint_held():  # started whole, so that it can be closed whole
                if scheduler is not None:
                    try:
                        client = distributed.Client(scheduler, timeout="20s")
                    except OSError as err:
                        raise ValueError(f"--scheduler = {scheduler!r}: cannot connect "
                                         f"({err})") from None
                else:
                    assert dask_workers is not None
                    stack.enter_context(single_threaded_children())
                    cluster = distributed.LocalCluster(
                        n_workers=dask_workers, threads_per_worker=1, processes=True,
                        # CRITICAL only: a worker's ERROR log of its heartbeat failing as a
                        # Ctrl-C closes the cluster is noise; real failures reach the parent
                        # as exceptions (SweepAborted, a point's error).  The scheduler's HTTP
                        # server (health, metrics) on a free loopback port: with None it took
                        # 0.0.0.0:8787, and two clusters at once printed distributed's "Port
                        # 8787 is already in use" beside the command's one line (a test of
                        # two Dask runs side by side, 2026-12-07)
                        dashboard_address="127.0.0.1:0", silence_logs=50)
                    stack.callback(cluster.close)
                    client = distributed.Client(cluster)
                stack.callback(client.close)
            n = len(client.scheduler_info()["workers"])
            if warm_tasks:
                client.run(_warm_worker, warm_tasks)
            where = scheduler if scheduler is not None else "LocalCluster"
            pool = client.get_executor(pure=False)
            try:
                yield pool, n, f"dask ({where}, {n} workers)"
            except BaseException:
                if cluster is not None:  # Ctrl-C or an error: stop our workers now
                    # the client's comms to the killed workers fail as they close (a
                    # CommClosedError logged with its traceback by distributed.batched):
                    # expected now, so this process's distributed logs go quiet first
                    for name in ("distributed", "distributed.batched", "distributed.client"):
                        logging.getLogger(name).setLevel(logging.CRITICAL)
                    _kill_workers(cluster)
                raise
        return
    n = workers or os.cpu_count() or 1
    # the pool starts its processes on demand (spawn): keep the setting for its lifetime
    with single_threaded_children():
        pool = cf.ProcessPoolExecutor(max_workers=n,
                                      mp_context=multiprocessing.get_context("spawn"),
                                      initializer=worker_start, initargs=(os.getpid(),))
        try:
            yield pool, n, f"local ({n} processes)"
        except BaseException:
            stop_workers(pool)  # Ctrl-C or an error: do not wait for the points in flight
            raise
        pool.shutdown(wait=True)


def _structure(task: dict[str, Any], coords: dict[str, Any]) -> tuple[Any, ...]:
    """A point's model structure: drive, quantity and every non-numeric setting (friction
    laws, modes …; numbers do not change the compiled code)."""
    return (task["drive"], task["quantity"]["kind"],
            tuple(sorted((k, repr(v)) for k, v in coords.items()
                         if not isinstance(v, int | float) or isinstance(v, bool))))


def _structure_tasks(points: Iterable[Point]) -> list[dict[str, Any]]:
    """One task per distinct model structure among ``points``."""
    seen: dict[tuple[Any, ...], dict[str, Any]] = {}
    for p in points:
        seen.setdefault(_structure(p.task, p.coords), p.task)
    return list(seen.values())


def description(config: SweepConfig) -> dict[str, Any]:
    """What the store records about a sweep; exports and maps read it back.

    Parameters
    ----------
    config : SweepConfig
        The configuration.

    Returns
    -------
    dict
        The raw configuration, source, design, the axes (name, unit, relative, grid values)
        and the quantity settings.
    """
    return {"config": config.raw, "source": config.source, "design": config.design,
            "axes": [{"name": a.name, "unit": a.unit, "relative": a.relative,
                      "values": None if config.design != "grid" else a.grid()}
                     for a in config.axes],
            "quantity": config.quantity.to_dict(), "map": list(config.map_axes)}


@dataclass(frozen=True)
class CheckedDesign:
    """Every point of a design built and checked: its key, in design order, and one task
    per model structure (to warm the compiled kernels).

    Parameters
    ----------
    keys : list of str
        Every point's store key, in design order.
    structures : dict
        Model structure → one task of that structure.
    """

    keys: list[str]
    structures: dict[tuple[Any, ...], dict[str, Any]]


def check_design(config: SweepConfig, *, points: list[Point] | None = None,
                 checked: Progress | None = None) -> CheckedDesign:
    """Build and check every point's parameter set, one at a time, keeping only its key (a
    bad value is refused here, before any simulation and before the store is touched).

    Parameters
    ----------
    config : SweepConfig
        The configuration.
    points : list of Point, optional
        Points already built; built one at a time from ``config`` otherwise.
    checked : callable, optional
        ``checked(done, total)``, every 200 points and at the end.

    Returns
    -------
    CheckedDesign
        The keys and one task per structure.

    Raises
    ------
    ParameterError
        At the first point whose parameter set is invalid.
    """
    total = config.count() if points is None else len(points)
    keys: list[str] = []
    structures: dict[tuple[Any, ...], dict[str, Any]] = {}
    for p in (points if points is not None else config.iter_points()):
        keys.append(p.key)
        structures.setdefault(_structure(p.task, p.coords), p.task)
        if checked is not None and (len(keys) % 200 == 0 or len(keys) == total):
            checked(len(keys), total)
    for task in structures.values():
        check_task(task)  # what no point of a structure can compute (a verdict's interval)
    return CheckedDesign(keys, structures)


#: points in flight per worker: enough to keep every worker busy, few enough that a
#: million-point design never holds more than a handful of tasks (and Ctrl-C has little to
#: cancel)
IN_FLIGHT_PER_WORKER = 2


def run_sweep(config: SweepConfig, store: SweepStore, *, workers: int | None = None,
              scheduler: str | None = None, dask_workers: int | None = None,
              points: list[Point] | None = None,
              progress: Progress | None = None,
              started: Callable[[int, str], None] | None = None,
              checked: Progress | None = None,
              design: CheckedDesign | None = None) -> SweepSummary:
    """Compute every design point of ``config`` not yet in ``store``; see the module.

    First every point's parameter set is built and checked (a bad value stops the sweep
    before any simulation) keeping only its key; the design is registered in the store;
    then the points still to compute are built again one at a time and submitted as
    workers free up (at most ``IN_FLIGHT_PER_WORKER`` per worker in flight), each
    claimed in the store first (:meth:`feeddrive.sweep.SweepStore.claim`: a point another
    live sweep is computing is left to it and waited for at the end).

    ``checked(done, total)`` during the check; ``started(todo, executor)`` once the
    executor is up; ``progress(done, todo)`` after each stored point.  Stored points are
    never recomputed; a failed point (its simulation failed) is stored with its error, so a
    rerun does not retry it.  On Ctrl-C (``KeyboardInterrupt``) nothing more is submitted,
    every result already returned is stored, the points in flight are cancelled (local
    workers are stopped at once) and the interrupt is raised again.

    Parameters
    ----------
    config : SweepConfig
        The configuration.
    store : SweepStore
        The store.
    workers : int, optional
        Local worker processes.
    scheduler : str, optional
        Address of a Dask scheduler.
    dask_workers : int, optional
        Workers of a local Dask cluster.
    points : list of Point, optional
        Points already built.
    progress : callable, optional
        ``progress(done, todo)`` after each stored point.
    started : callable, optional
        ``started(todo, executor)`` once the executor is up.
    checked : callable, optional
        ``checked(done, total)`` during the check.
    design : CheckedDesign, optional
        The checked design, when the caller has it already.

    Returns
    -------
    SweepSummary
        What the run did.

    Raises
    ------
    SweepInterrupted
        On Ctrl-C, after storing every result already returned.

    Examples
    --------
    The CDFS's linearly unstable band at three table positions, in a store in a temporary folder:

    >>> import pathlib, tempfile
    >>> from feeddrive.sweep import SweepStore, parse_config, run_sweep, to_dataset
    >>> config = parse_config({"preset": "wang2021", "drive": "cdfs",
    ...                        "quantity": {"kind": "linear-band"},
    ...                        "axes": {"table_position": [200, 400, 600]}}, "example.toml")
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     store = SweepStore(pathlib.Path(folder) / "band.sqlite")
    ...     summary = run_sweep(config, store, workers=1)
    ...     upper = to_dataset(store, config.name)["linear_upper"]
    ...     store.close()
    >>> print(summary.computed, [round(1e3 * float(v), 2) for v in upper])
    3 [1.4, 1.4, 1.4]
    """
    t0 = time.perf_counter()
    check_executor(workers=workers, scheduler=scheduler, dask_workers=dask_workers)
    if design is None:
        design = check_design(config, points=points, checked=checked)
    keys, structures = design.keys, design.structures
    coords = (p.coords for p in points) if points is not None else config.iter_coordinates()
    store.register(config.name, description(config),
                   ((i, k, c) for (i, k), c in zip(enumerate(keys), coords, strict=True)),
                   count=len(keys))
    first: dict[str, int] = {}
    for i, k in enumerate(keys):
        first.setdefault(k, i)
    done_before = store.finished(first)
    todo = {i for k, i in first.items() if k not in done_before}
    failed = computed = elsewhere = 0
    n_workers, where = 0, "none"

    def todo_tasks(indices: set[int]) -> Iterator[tuple[int, dict[str, Any]]]:
        """The tasks of ``indices``, in design order, built one at a time."""
        if points is not None:
            yield from ((p.index, p.task) for p in points if p.index in indices)
            return
        bases: dict[str, Any] = {}
        for i, c in enumerate(config.iter_coordinates()):
            if i in indices:
                yield i, config.task(c, bases)

    if todo:
        for task in structures.values():
            warm(task)
        try:
            with CtrlC() as ctrl_c, \
                    executor(workers=workers, scheduler=scheduler, dask_workers=dask_workers,
                             warm_tasks=list(structures.values())) as (pool, n_workers, where):
                if started is not None:
                    started(len(todo), where)
                limit = max(1, IN_FLIGHT_PER_WORKER * n_workers)
                inflight: dict[cf.Future[Any], str] = {}
                waiting: set[int] = set()  # claimed by another live sweep
                source: Iterator[tuple[int, dict[str, Any]]] = todo_tasks(todo)

                def store_result(fut: cf.Future[Any]) -> None:
                    nonlocal computed, failed
                    value = fut.result()
                    store.put(inflight[fut], value)
                    del inflight[fut]
                    computed += 1
                    failed += "error" in value
                    if progress is not None:
                        progress(computed + elsewhere, len(todo))

                retrying = False

                def fill() -> bool:
                    """Submit until ``limit`` points are in flight; False once none is left."""
                    nonlocal elsewhere, source, retrying
                    while len(inflight) < limit:
                        item = next(source, None)
                        if item is None:
                            if not waiting:
                                return False
                            if inflight:  # come back to them once a worker is free
                                return True
                            # only points other live sweeps hold are left: look again
                            if retrying:
                                time.sleep(0.5)
                            retrying = True
                            source = todo_tasks(set(waiting))
                            waiting.clear()
                            continue
                        i, task = item
                        state = store.claim(keys[i])
                        if state == "stored":
                            elsewhere += 1
                            if progress is not None:
                                progress(computed + elsewhere, len(todo))
                        elif state == "busy":
                            waiting.add(i)
                        else:
                            ctrl_c.check()  # nothing is handed out after a Ctrl-C
                            inflight[pool.submit(evaluate, task)] = keys[i]
                    return True

                try:
                    more = fill()
                    while inflight or more:
                        done, _ = cf.wait(list(inflight), timeout=1.0,
                                          return_when=cf.FIRST_COMPLETED)
                        for fut in done:
                            store_result(fut)
                        store.refresh_claims()
                        more = fill()
                except BaseException as err:
                    # nothing more is submitted; what has returned is stored; the rest is
                    # cancelled (the executor's exit stops local workers at once)
                    for fut in list(inflight):
                        if fut.done() and not fut.cancelled() and fut.exception() is None:
                            store_result(fut)
                        else:
                            fut.cancel()
                    if isinstance(err, Exception) and _lost_worker(err):
                        raise SweepAborted(f"{where}: a worker was lost ({type(err).__name__}: "
                                           f"{err}); {computed} points stored this run, rerun "
                                           "to resume") from None
                    if isinstance(err, KeyboardInterrupt):
                        raise SweepInterrupted(computed) from None
                    raise
                finally:
                    store.release_claims()
        except KeyboardInterrupt as err:
            # a Ctrl-C outside the loop (while the pool starts or shuts down, or the claims
            # are released) still reports what this run stored
            if isinstance(err, SweepInterrupted):
                raise
            raise SweepInterrupted(computed) from None
    return SweepSummary(points=len(keys), distinct=len(first), stored_before=len(done_before),
                        computed=computed, failed=failed, seconds=time.perf_counter() - t0,
                        workers=n_workers, executor=where, elsewhere=elsewhere)


@dataclass(frozen=True)
class Estimate:
    """A sweep's point count and its cost, in CPU seconds (not wall: a loaded machine's wall
    time made the estimate vary 3.0–10.8 s between runs of one config, issue 24 item 11).

    A point's CPU is ``seconds_per_point`` when points were timed (the cheap linear
    quantities), else the range ``point_range`` from a probe run: the CPU per simulated
    second of a short run of the drive times the simulated time the quantity's protocol
    takes at least and at most (:func:`~feeddrive.sweep.executors.simulated_range`).  A
    sweep also starts its workers — each imports the package and loads the model kernels
    (``startup_seconds``, measured on this process) — and compiles kernels not in the cache
    yet (``compile_seconds``, spent by this dry run, once; issue 41 item 8: the estimate had
    left both out).

    Parameters
    ----------
    points : int
        Design points.
    distinct : int
        Distinct computations among them.
    stored : int
        Of them, already stored under this design.
    timed : int
        Points timed for the estimate (the linear quantities).
    seconds_per_point : float
        Mean CPU time of a timed point, or the low end of ``point_range`` [s].
    workers : int
        Workers the estimate assumes.
    point_seconds : tuple of float, default ()
        CPU time of each timed point [s].
    built : int, default 0
        Parameter sets built for the estimate.
    point_range : tuple of (float, float) or None, default None
        (least, most) CPU of one point from the probe [s]; None when points were timed.
    startup_seconds : float, default 0.0
        CPU of one worker's start: imports and kernel loading [s].
    compile_seconds : float, default 0.0
        CPU this dry run spent compiling kernels not cached yet [s] (the sweep then finds
        them compiled).
    probe_rate : float or None, default None
        CPU seconds per simulated second of the probe run [-].
    """

    points: int
    distinct: int
    stored: int
    timed: int
    seconds_per_point: float
    workers: int
    point_seconds: tuple[float, ...] = ()
    built: int = 0  # parameter sets built for the estimate
    point_range: tuple[float, float] | None = None
    startup_seconds: float = 0.0
    compile_seconds: float = 0.0
    probe_rate: float | None = None

    @property
    def spread(self) -> tuple[float, float]:
        """(cheapest, costliest) point [s CPU]: the timed points', or the probe's range."""
        if self.point_range is not None:
            return self.point_range
        if not self.point_seconds:
            return (0.0, 0.0)
        return (min(self.point_seconds), max(self.point_seconds))

    def _wall(self, per_point: float) -> float:
        remaining = self.distinct - self.stored
        if remaining <= 0:
            return 0.0
        workers = max(min(self.workers, remaining), 1)
        return remaining * per_point / workers + self.startup_seconds

    @property
    def seconds(self) -> float:
        """Estimated wall time [s] of the remaining points on ``workers`` workers with a free
        core each, the workers' start included (the low end for a probed quantity)."""
        return self._wall(self.seconds_per_point)

    @property
    def seconds_range(self) -> tuple[float, float]:
        """(least, most) wall time [s] of the remaining points, the workers' start included."""
        lo, hi = self.spread
        return (self._wall(lo), self._wall(hi))


#: simulated time of the probe run of a simulation quantity [s]
PROBE_DURATION = 1.0


def simulated_range(q: dict[str, Any]) -> tuple[float, float]:
    """The least and most simulated time [s] one point of a simulation quantity takes, from
    its protocol: a creep trial runs ``initial_duration``, doubled up to ``max_duration``
    until decided; a critical-speed search from rest scans ``(high − low)/coarse_step + 1``
    speeds, then bisects each change of verdict kind to ``resolution`` (none when nothing
    creeps; counted here for up to four changes, the most the shipped sets show); a
    step-down search holds each coarse step, then at most ``coarse_step/resolution`` fine
    steps.

    Parameters
    ----------
    q : dict
        The quantity settings (:meth:`~feeddrive.sweep.quantities.QuantitySettings.to_dict`).

    Returns
    -------
    tuple of (float, float)
        (least, most) simulated seconds of one point [s].
    """
    import math

    short, long = q["initial_duration"], q["max_duration"]
    if q["kind"] == "creep-trial":
        return short, long
    coarse = min(q["coarse_step"], (q["high"] - q["low"]) / 2)
    scan = math.floor((q["high"] - q["low"]) / coarse + 1e-9) + 1
    fine = math.ceil(math.log2(max(coarse / q["resolution"], 1.0)))
    if q["start"] == "rest":
        return scan * short, (scan + 4 * fine) * long
    return scan * short, (scan + math.ceil(coarse / q["resolution"])) * long



def _c_compiles() -> int:
    """The C libraries this process has compiled so far (the C build's count, read where its
    module is loaded: the sweep does not import the code generators)."""
    c_cache = sys.modules.get("feeddrive.backends.c_cache")
    return int(c_cache.STATS["compiles"]) if c_cache is not None else 0


@contextlib.contextmanager
def _numba_compiles() -> Iterator[list[Any]]:
    """The numba compilations made inside it (an empty list without numba; one entry when
    the numba build was started inside it, whose compilations are not recorded)."""
    from .._jit import HAVE_NUMBA, numba_started

    if not HAVE_NUMBA:
        yield []
        return
    if not numba_started():
        started: list[Any] = []
        yield started
        if numba_started():
            started.append("numba build started")
        return
    from numba.core.event import install_recorder

    with install_recorder("numba:compile") as recorder:
        yield recorder.buffer

def estimate(config: SweepConfig, store: SweepStore | None, *, workers: int,
             sample: int = 3, points: list[Point] | None = None,
             progress: Callable[[str], None] | None = None) -> Estimate:
    """Count the points and estimate their cost cheaply (issue 41 item 8: the dry run of a
    4-point grid had cost 2.8 CPU s against the sweep's 7.2): nothing is written, and at
    most ``sample`` parameter sets are built unless the store must be asked point by point
    (below).

    The counts come from the design alone
    (:meth:`feeddrive.sweep.design.SweepConfig.count`,
    :meth:`feeddrive.sweep.design.SweepConfig.distinct_count`); ``stored`` is how many of
    the distinct points of this call — its design at the integrator settings in force, which
    every key carries — the store holds, as the sweep itself will find them: read from the
    design registered under the sweep's name when that is this one (the same description and
    point count, the same keys at the sampled points), else counted from every point's key
    (each parameter set built, as the sweep's own check does; the distinct count is then the
    keys').  A store without results needs neither.  Nothing to compute: no timing.  The
    kernels are
    loaded (or compiled, and that CPU reported) first; then the linear quantities time up to
    ``sample`` points (milliseconds each), and the simulation quantities one
    :data:`~feeddrive.sweep.executors.PROBE_DURATION`-s run of the middle point's drive at
    the speed the quantity searches around, scaled by
    :func:`~feeddrive.sweep.executors.simulated_range`.  One worker's start-up is this
    process's CPU before the estimate (interpreter, imports) plus the kernels' loading.

    Parameters
    ----------
    config : SweepConfig
        The configuration.
    store : SweepStore or None
        The store, for the count already stored.
    workers : int
        Workers the estimate assumes.
    sample : int, default 3
        Points to time (linear quantities).
    points : list of Point, optional
        Points already built.
    progress : callable, optional
        Told in one line what is being done.

    Returns
    -------
    Estimate
        The counts and the cost.
    """
    started = _cpu()  # this process so far: the interpreter, the CLI and its imports
    count = config.count() if points is None else len(points)
    distinct = config.distinct_count() if points is None else len({p.key for p in points})
    simulates = config.quantity.kind in ("critical-speed", "creep-trial")
    n = 1 if simulates else min(sample, count)
    picks = (sorted({round(i * (count - 1) / max(n - 1, 1)) for i in range(n)}) if n > 1
             else [count // 2])
    if points is not None:
        chosen = [points[i] for i in picks]
    else:
        chosen = []
        from .store import point_key

        bases: dict[str, Any] = {}
        wanted = set(picks)
        for i, coords in enumerate(config.iter_coordinates()):
            if i in wanted:
                task = config.task(coords, bases)
                chosen.append(Point(index=i, coords=coords, task=task, key=point_key(task)))
                if len(chosen) == len(wanted):
                    break
    stored, built = 0, len(chosen)
    todo = chosen
    if store is not None and store.count() > 0:
        if points is None and _registered_here(config, store, chosen, count):
            stored = store.stored_count(config.name)
            finished = {p.key for p in chosen if store.get(p.key) is not None}
        else:
            # another design under this name (another configuration, or the same at other
            # integrator settings: the keys carry them): this call's keys, point by point
            if progress is not None and points is None:
                progress(f"building the keys of the {count} points to count those stored "
                         "(the design registered under this name is not this call's)")
            keys = ({p.key for p in points} if points is not None
                    else {p.key for p in config.iter_points()})
            built += 0 if points is not None else count
            finished = store.finished(keys)
            stored, distinct = len(finished), len(keys)
        # time points still to compute where the sample holds one, else any of the sample
        # (a timing stores nothing)
        todo = [p for p in chosen if p.key not in finished] or chosen
    if distinct - stored <= 0:
        return Estimate(points=count, distinct=distinct, stored=stored, timed=0,
                        seconds_per_point=0.0, workers=workers, built=built)
    if progress is not None:
        progress("loading the model kernels (compiling them if not cached), then "
                 + (f"a {PROBE_DURATION:g}-s probe run of one point's drive" if simulates
                    else f"timing {len(todo)} of the {distinct - stored} points to compute "
                    "(each a full evaluation, nothing stored)"))
    t = _cpu()
    c_compiles = _c_compiles()
    with _numba_compiles() as numba_compiled:
        for task in _structure_tasks(todo):
            warm(task)
    load = _cpu() - t
    compiled = bool(numba_compiled) or _c_compiles() > c_compiles
    compile_seconds = load if compiled else 0.0
    # a worker loads what this process compiled: its start is this process's imports and
    # the loading (after a compile, the next dry run measures the loading)
    startup = started + (0.0 if compiled else load)
    if simulates:
        rate = _probe_rate(todo[0].task)
        lo, hi = simulated_range(todo[0].task["quantity"])
        return Estimate(points=count, distinct=distinct, stored=stored, timed=0,
                        seconds_per_point=lo * rate, workers=workers, built=built,
                        point_range=(lo * rate, hi * rate), startup_seconds=startup,
                        compile_seconds=compile_seconds, probe_rate=rate)
    seconds = []
    for i, p in enumerate(todo, start=1):
        if progress is not None:
            progress(f"timing point {i} of {len(todo)}")
        t = time.process_time()
        evaluate(p.task)
        seconds.append(time.process_time() - t)
    mean = sum(seconds) / len(seconds)
    return Estimate(points=count, distinct=distinct, stored=stored, timed=len(seconds),
                    seconds_per_point=mean, workers=workers, point_seconds=tuple(seconds),
                    built=built, startup_seconds=startup,
                    compile_seconds=compile_seconds)


def _registered_here(config: SweepConfig, store: SweepStore, chosen: list[Point],
                     count: int) -> bool:
    """Whether the design ``store`` registered under ``config``'s name is this call's: the
    same description, the same number of points and the same keys at the ``chosen`` points
    (a key carries the integrator settings in force: a run at another ``--accuracy``
    registered other keys under the same name)."""
    from .store import _json

    if config.name not in store.sweeps() or \
            _json(store.description(config.name)) != _json(description(config)):
        return False
    ends = store.point_keys(config.name, [count - 1, count])
    if count - 1 not in ends or count in ends:
        return False
    registered = store.point_keys(config.name, [p.index for p in chosen])
    return all(registered.get(p.index) == p.key for p in chosen)


def _cpu() -> float:
    """CPU seconds (user + system) of this process so far."""
    import resource

    use = resource.getrusage(resource.RUSAGE_SELF)
    return use.ru_utime + use.ru_stime


def _probe_rate(task: dict[str, Any]) -> float:
    """CPU seconds per simulated second of ``task``'s drive, from a
    :data:`~feeddrive.sweep.executors.PROBE_DURATION`-s run at the speed its quantity
    searches around (a creep trial's speed, the middle of a search's range)."""
    from ..engine.simulate import DriveSystem, simulate
    from ..model.reference import ConstantSpeed
    from ..parameters import loads

    q = task["quantity"]
    speed = q["table_speed"] if q["kind"] == "creep-trial" else 0.5 * (q["low"] + q["high"])
    system = DriveSystem(loads(task["parameters"]), drive=task["drive"],
                         table_position=task["table_position"])
    t = time.process_time()
    simulate(system, ConstantSpeed(speed, task["nut_speed"]), PROBE_DURATION)
    return (time.process_time() - t) / PROBE_DURATION
