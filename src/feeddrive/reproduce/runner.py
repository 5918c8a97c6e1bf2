"""`feeddrive reproduce`: run every study, write figures, tables and the report.

Each finished study is stored at once under ``DIR/data/``
(:class:`feeddrive.io.json_store.ResultStore`: atomic, checksummed entries keyed by the
package version, the kernel hash, the study code and the parameter set and settings), so an
interrupted run loses nothing and a rerun skips what is done; an entry that is corrupt or
from other code is recomputed with a notice.
Critical-speed searches run in a process pool (2 workers by default).
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import signal
import time
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

from .._jit import KERNEL_HASH
from .._workers import single_threaded_children, stop_workers
from ..engine.simulate import DriveSystem, simulate
from ..io.json_store import ResultStore, code_hash, store_key
from ..model.reference import ConstantSpeed
from ..parameters import DriveParameters, dumps

# figures and report (matplotlib, the report's writers) are imported where the parent uses
# them, so that a pool worker, which imports this module to find its job, does not (≈ 0.3 s)
from . import (
    forced_study,
    quadrant_study,
    reading_study,
    sensitivity_section,
    studies,
)
from .studies import MID, PAPER, StudySettings, write_csv

_HERE = Path(__file__).resolve().parent
# the code that computes the stored studies (beyond the compiled kernels)
_STUDY_SOURCES = (_HERE / "studies.py", _HERE / "reading_study.py", _HERE / "forced_study.py",
                  _HERE / "quadrant_study.py",
                  *(_HERE.parent / "machine" / f"{name}.py" for name in ("__init__", "contour")),
                  *(_HERE.parent / "analysis" / f"{name}.py"
                    for name in ("critical", "cycle_verdict", "creep_window", "tracking",
                                 "trace_input", "verdict_words", "forced", "compensation",
                                 "sensitivity", "circular", "circular_run",
                                 "positioning_run")),
                  _HERE.parent / "engine" / "simulate.py", _HERE.parent / "engine" / "options.py",
                  _HERE.parent / "engine" / "error_estimate.py",
                  _HERE.parent / "engine" / "result.py",
                  _HERE.parent / "model" / "mechanisms" / "ball_screw_stiffness.py",
                  _HERE.parent / "analysis" / "protocol.py")


def study_store(out: Path, params: DriveParameters, settings: StudySettings, *,
                notice: Callable[[str], None] | None = None) -> ResultStore:
    """The store of ``out/data`` for this parameter set, these settings and this code.

    The key holds the set's text (:func:`feeddrive.parameters.dumps`, with the ``[solver]``
    table the set carries) and the integrator settings in force
    (:meth:`feeddrive.SolverOptions.record`): a table, or another value in it, is another
    store.

    Parameters
    ----------
    out : Path
        The report folder.
    params : DriveParameters
        The parameter set.
    settings : StudySettings
        The search settings.
    notice : callable, optional
        Receives a one-line message for each unusable stored entry.

    Returns
    -------
    ResultStore
        The store, keyed by the set, the settings and the code.
    """
    from .. import __version__
    from ..engine.options import current

    key = store_key({"version": __version__, "kernel": KERNEL_HASH,
                     "code": code_hash(_STUDY_SOURCES), "parameters": dumps(params),
                     "settings": asdict(settings), "solver": current().record()})
    return ResultStore(out / "data", key, notice=notice)


class WorkerLost(RuntimeError):
    """A worker process of the pool ended while computing a study (killed, out of memory, a
    crash in compiled code): the run stops; the studies stored so far are kept."""


def _lost(what: str, handle: cf.Future[Any], out: Path) -> WorkerLost:
    return WorkerLost(f"a worker process ended unexpectedly while computing {what} "
                      f"({handle.exception()}); the studies finished so far are kept in "
                      f"{out / 'data'} and reused by a rerun")


def _timed(fn: Callable[..., Any], *args: Any) -> tuple[Any, float]:
    """``fn(*args)`` and the CPU time it took in the worker [s]."""
    began = time.process_time()
    value = fn(*args)
    return value, time.process_time() - began


def prepare_models(tasks: list[tuple[Callable[..., Any], tuple[Any, ...]]]) -> int:
    """On a cold compile cache: the models of ``tasks`` compiled (their first-class functions),
    each task run only up to its first driver call
    (:class:`feeddrive.solvers.shared.prepared_models`), until the drivers are on disk.

    Submitted third on a cold cache, after the sensitivity section and the first search, whose
    worker compiles the drivers (≈ 20 CPU s) while this one has nothing else to do; each model
    it compiles is one a later search loads instead.  Nothing it computes is kept.

    Parameters
    ----------
    tasks : list of (callable, tuple)
        The study's tasks, in the order submitted.

    Returns
    -------
    int
        The tasks gone through.
    """
    from ..solvers.shared import drivers_on_disk, prepared_models

    count = 0
    for fn, args in tasks:
        if drivers_on_disk():
            break
        try:
            with prepared_models():
                fn(*args)
        except Exception:  # noqa: BLE001 - the real run of the task reports it
            pass
        count += 1
    return count


class TaskQueue:
    """The studies not yet started, handed to the pool as its workers free up: at most
    ``slots`` in the pool (the running ones and one waiting), so that a study whose input
    became known (:meth:`first`) starts next instead of after every task submitted before it
    (the compensation study, submitted once its searches were done, used to run last and
    alone for ≈ 4 s).

    Parameters
    ----------
    items : iterable of (str or None, (callable, tuple))
        (key, (function, arguments)) in the order to start them; key None: a helper whose
        result is not kept.
    slots : int
        Tasks in the pool at most.
    """

    def __init__(self, items: Any, slots: int) -> None:
        self.items: list[tuple[str | None, tuple[Callable[..., Any], tuple[Any, ...]]]] = \
            list(items)
        self.slots = slots

    def first(self, key: str, task: tuple[Callable[..., Any], tuple[Any, ...]]) -> None:
        """Start ``task`` next.

        Parameters
        ----------
        key : str
            The study's key.
        task : tuple of (callable, tuple)
            Its function and arguments.
        """
        self.items.insert(0, (key, task))

    def take(self, in_pool: int) -> list[tuple[str | None, tuple[Callable[..., Any],
                                                                  tuple[Any, ...]]]]:
        """The tasks to submit now, removed from the queue.

        Parameters
        ----------
        in_pool : int
            Tasks submitted and not finished.

        Returns
        -------
        list of (str or None, (callable, tuple))
            As many as fit in the free slots, in order.
        """
        n = max(0, min(len(self.items), self.slots - in_pool))
        taken, self.items = self.items[:n], self.items[n:]
        return taken


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _critical_job(args: tuple[DriveParameters, str, float, float, StudySettings, str]
                  ) -> dict[str, Any]:
    params, drive, position, nut_speed, settings, start = args
    if start == "rest":
        return studies.critical_speed(params, drive, position, nut_speed, settings)
    return studies.critical_speed_running(params, drive, position, nut_speed, settings)


def _compensation_job(params: DriveParameters, settings: StudySettings,
                      found: dict[int, dict[str, Any]] | None = None) -> dict[str, Any]:
    from ..analysis.compensation import compensation_study

    return {"rows": compensation_study(params, rule=settings.rule(), found=found)}


def _shared_rows(study_jobs: dict[str, tuple[str, str, dict[str, Any], str, float]],
                 jobs: dict[str, tuple[DriveParameters, str, float, float, StudySettings, str]]
                 ) -> dict[str, str]:
    """The model-reading study's rows whose search is one of the paper's ``jobs`` (same set,
    drive, mid-screw, nut speed, from rest): study key → job key."""
    out: dict[str, str] = {}
    for k, job in study_jobs.items():
        for key, (p, drive, position, nut, _, start) in jobs.items():
            if start == "rest" and (drive, position, nut) == (job[3], MID, job[4]) \
                    and reading_study.variant_parameters(job) == p:
                out[k] = key
                break
    return out


def _compensation_shares(params: DriveParameters, settings: StudySettings,
                         jobs: dict[str, tuple[DriveParameters, str, float, float,
                                               StudySettings, str]]) -> dict[int, str]:
    """The compensation study's cases whose critical-speed search is one of ``jobs`` (the
    uncompensated CDFS and the DDFS at 16 mm/s are Table 3's mid-screw CDFS and Fig. 8's
    DDFS when the study runs on the protocol's grid): case index → job key."""
    from ..analysis import protocol
    from ..analysis.compensation import case_parameters, default_cases

    if (settings.speed_range, settings.coarse_step, settings.resolution) != (
            protocol.SPEED_RANGE, protocol.COARSE_STEP, protocol.RESOLUTION):
        return {}
    out: dict[int, str] = {}
    for i, case in enumerate(default_cases()):
        for key, (p, drive, position, nut, _, start) in jobs.items():
            if (start == "rest" and drive == case.drive and position == MID
                    and nut == case.nut_speed and case_parameters(params, case) == p):
                out[i] = key
                break
    return out


def run(params: DriveParameters, out: Path, *, settings: StudySettings | None = None,
        workers: int = 2, study: bool = True,
        progress: Callable[[str, int, int], None] | None = None,
        notice: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Run the whole study into ``out``; returns the collected results.

    ``study``: also run the model-reading study (variants of the Wang2021 presets).
    ``notice``: receives a one-line message for each stored entry found unusable (corrupt,
    edited, other code) and recomputed.

    Parameters
    ----------
    params : DriveParameters
        The parameter set studied; every run takes the ``[solver]`` table it carries (under
        the options in force: :func:`feeddrive.engine.simulate.run_options`), which is part
        of the store's key (``study_store``).
    out : Path
        The report folder; studies already stored in ``out/data`` are reused.
    settings : StudySettings, optional
        The search settings; the defaults when omitted.
    workers : int, default 2
        Processes that run the studies.
    study : bool, default True
        Also run the model-reading study.
    progress : callable, optional
        ``progress(stage, done, total)`` as the studies finish.
    notice : callable, optional
        Receives a one-line message for each unusable stored entry.

    Returns
    -------
    dict
        Every study's results.

    References
    ----------
    .. [1] Wang2021 (the figures, tables and sections the studies reproduce).
    """
    from ..engine.simulate import run_options

    run_options(params)  # the set's [solver] table: a bad value refused before any work
    settings = settings or StudySettings()
    out.mkdir(parents=True, exist_ok=True)
    store = study_store(out, params, settings, notice=notice)
    started = time.perf_counter()
    results: dict[str, Any] = {}

    # --- critical speeds: Table 3 (both drives, five positions) + Fig. 8 + running starts
    jobs: dict[str, tuple[DriveParameters, str, float, float, StudySettings, str]] = {}
    for a in PAPER["positions"]:
        jobs[f"crit-cdfs-{a}"] = (params, "cdfs", a, 0.0, settings, "rest")
        jobs[f"crit-ddfs-{a}"] = (params, "ddfs", a, PAPER["experiment_nut_speed"], settings,
                                  "rest")
    jobs["crit-ddfs-fig8"] = (params, "ddfs", MID, PAPER["ddfs_sim_nut_speed"], settings, "rest")
    jobs["crit-cdfs-running"] = (params, "cdfs", MID, 0.0, settings, "running")
    jobs["crit-ddfs-running"] = (params, "ddfs", MID, PAPER["ddfs_sim_nut_speed"], settings,
                                 "running")
    study_jobs = {f"study-{i}": job for i, job in enumerate(reading_study.jobs())} if study \
        else {}
    forced_jobs = {f"forced-{i}": job for i, job in enumerate(forced_study.jobs())} if study \
        else {}
    figure_jobs = [f"readingfig-{i}" for i in range(len(forced_study.FIGURE_READINGS))] \
        if study else []
    extra = [*(["compensation", "sensitivity", "quadrant"] if study else []), *figure_jobs]
    figure_studies = ["fig6", "figs9_10", "fig7", "fig8_trace"]
    names = [*jobs, *study_jobs, *forced_jobs, *extra, *figure_studies]
    found = {k: store.get(k) for k in names}
    done = sum(v is not None for v in found.values())
    if progress:
        progress("critical speeds", done, len(names))
    # a study row whose search is one of the paper's (the shipped reading at mid-screw is
    # Table 3's CDFS and Fig. 8's DDFS): taken from that search, not searched twice
    shared = _shared_rows(study_jobs, jobs)
    comp_shares = _compensation_shares(params, settings, jobs) if study else {}
    # submitted roughly longest first, so that no long study starts last and runs alone:
    # the sensitivity (linearisations only), the step-down searches, the searches the other
    # studies share, the model-reading study (whose undecided readings run their trials to
    # the longest duration), the rest, the paper's other searches from rest
    tasks: dict[str, tuple[Callable[..., Any], tuple[Any, ...]]] = {}
    if study:
        tasks["sensitivity"] = (sensitivity_section.compute, (params,))
        tasks["quadrant"] = (quadrant_study.run, (params,))
    tasks.update({k: (_critical_job, (v,)) for k, v in jobs.items() if v[5] != "rest"})
    tasks.update({k: (_critical_job, (jobs[k],))
                  for k in dict.fromkeys([*shared.values(), *comp_shares.values()])})
    tasks.update({k: (reading_study.run_variant, (v, settings)) for k, v in study_jobs.items()
                  if k not in shared})
    tasks.update({k: (forced_study.run, (v,)) for k, v in forced_jobs.items()})
    tasks.update({k: (forced_study.reading_figures, (i, settings))
                  for i, k in enumerate(figure_jobs)})
    tasks["fig6"] = (studies.fig6, (params, settings))
    tasks["figs9_10"] = (studies.figs9_10, (params, settings))
    tasks.update({k: (_critical_job, (v,)) for k, v in jobs.items() if k not in tasks})

    def speed(key: str) -> float | None:
        v = _entry(found, key)["critical_speed_mm_s"]
        return None if v is None else v * 1e-3

    # studies that need another's result: submitted once it is known
    cdfs_mid = f"crit-cdfs-{MID}"
    Task = tuple[Callable[..., Any], tuple[Any, ...]]
    after: dict[str, tuple[tuple[str, ...], Callable[[], Task]]] = {
        "fig7": ((cdfs_mid,), lambda: (studies.fig7, (
            params, speed(cdfs_mid) or PAPER["cdfs_critical_sim"], settings))),
        "fig8_trace": (("crit-ddfs-fig8",), lambda: (
            _fig8_trace, (params, speed("crit-ddfs-fig8")))),
    }
    if study:
        after["compensation"] = (tuple(comp_shares.values()), lambda: (
            _compensation_job, (params, settings,
                                {i: found[key] for i, key in comp_shares.items()})))
    todo = {k: v for k, v in tasks.items() if found[k] is None}
    cpu_seconds: dict[str, float] = {}  # of each study computed in this run
    if todo or any(found[k] is None for k in [*after, *shared]):
        # workers ignore SIGINT; on Ctrl-C the parent stops them at once (a pool that waits
        # for its running searches took ~53 s to stop, issue 12 item 7).  Started by spawn
        # with one BLAS thread each: forked, they inherited the parent's OpenBLAS threads,
        # which busy-waited beside them (60.7 against 52.5 CPU s of the workers,
        # benchmarks/README.md).  A worker that dies (killed, a crash in compiled code) breaks
        # the pool, and the run ends with WorkerLost instead of waiting for it for ever.
        with single_threaded_children():  # for the pool's life: it starts workers on demand
            pool = cf.ProcessPoolExecutor(max(1, workers),
                                          mp_context=multiprocessing.get_context("spawn"),
                                          initializer=_ignore_sigint)
            try:
                from ..solvers.shared import drivers_on_disk

                queue = TaskQueue(todo.items(), slots=max(1, workers) + 1)
                if len(todo) > 2 and workers > 1 and not drivers_on_disk():
                    # third in the queue: the first free worker's while the one that took
                    # the second task compiles the drivers (its result is not kept)
                    queue.items.insert(2, (None, (prepare_models, ([*todo.values()][2:],))))
                pending: dict[str, cf.Future[Any]] = {}
                preparing: list[cf.Future[Any]] = []
                waiting = {k: deps for k, (deps, _) in after.items() if found[k] is None}
                copies = {k: key for k, key in shared.items() if found[k] is None}
                while pending or waiting or copies or queue.items:
                    for h in preparing:
                        if h.done() and isinstance(h.exception(), cf.process.BrokenProcessPool):
                            raise _lost("preparing the compiled models", h, out)
                    preparing = [h for h in preparing if not h.done()]
                    for k, (fn, args) in queue.take(len(pending) + len(preparing)):
                        if k is None:
                            preparing.append(pool.submit(fn, *args))
                        else:
                            pending[k] = pool.submit(_timed, fn, *args)
                    for k, key in list(copies.items()):
                        if found[key] is not None:  # stored at once, as a computed study
                            found[k] = store.put(k, reading_study.row_from_search(
                                study_jobs[k], _entry(found, key)))
                            cpu_seconds[k] = 0.0
                            done += 1
                            del copies[k]
                            if progress:
                                progress(k, done, len(names))
                    for k, deps in list(waiting.items()):
                        if all(found[dep] is not None for dep in deps):
                            queue.first(k, after[k][1]())
                            del waiting[k]
                    finished = [k for k, handle in pending.items() if handle.done()]
                    for k in finished:  # each finished study is on disk at once
                        handle = pending.pop(k)
                        if isinstance(handle.exception(), cf.process.BrokenProcessPool):
                            raise _lost(k, handle, out)
                        value, cpu_seconds[k] = handle.result()
                        found[k] = store.put(k, value)
                        done += 1
                        if progress:
                            progress(k, done, len(names))
                    if not finished:
                        time.sleep(0.02)
            except BaseException:
                stop_workers(pool)
                raise
            pool.shutdown(wait=True)
    crit: dict[str, Any] = {k: found[k] for k in jobs}
    results["critical"] = crit
    results["reading_study"] = [found[k] for k in study_jobs]
    results["forced_study"] = [row for k in forced_jobs for row in _entry(found, k)["rows"]]
    results["compensation"] = found["compensation"] if study else None
    results["sensitivity"] = found["sensitivity"] if study else None
    results["quadrant"] = found["quadrant"] if study else None
    results["reading_figures"] = [found[k] for k in figure_jobs]
    for name in figure_studies:
        results[name] = found[name]

    # --- tables and figures
    from . import figures, report

    table3 = []
    for i, (a, row) in enumerate(zip(PAPER["positions"], studies.stiffness_rows(params),
                                     strict=True)):
        table3.append({**row, "cdfs": speed(f"crit-cdfs-{a}"),
                       "cdfs_paper": PAPER["cdfs_table3"][i], "ddfs": speed(f"crit-ddfs-{a}"),
                       "ddfs_paper": PAPER["ddfs_table3"][i],
                       "cdfs_status": crit[f"crit-cdfs-{a}"]["status"],
                       "ddfs_status": crit[f"crit-ddfs-{a}"]["status"],
                       "speed_range": [1e-3 * v for v in
                                       crit[f"crit-cdfs-{a}"]["speed_range_mm_s"]]})
    results["table3"] = table3
    _write_tables(out, results)
    pngs = [figures.fig6(results["fig6"], out), figures.fig7(results["fig7"], out),
            figures.fig8(results["fig8_trace"], crit["crit-ddfs-fig8"], out),
            *figures.figs9_10(results["figs9_10"], out), figures.fig14(table3, out)]
    tornado = sensitivity_section.figure(results["sensitivity"], out)
    pngs += [tornado] if tornado is not None else []
    results["figures"] = [p.name for p in pngs]
    results["wall_time_s"] = time.perf_counter() - started
    results["cpu_seconds"] = cpu_seconds
    results["studies_total"] = len(names)
    results["studies_reused"] = len(names) - len(cpu_seconds)
    results["studies_shared"] = [k for k in shared if k in cpu_seconds]
    report.write(params, settings, results, out)
    return results


def _entry(found: dict[str, Any | None], key: str) -> Any:
    value = found[key]
    assert value is not None, key  # every entry is found or computed by now
    return value


def _fig8_trace(params: DriveParameters, critical: float | None) -> dict[str, Any]:
    v = critical if critical is not None else PAPER["ddfs_critical_sim"]
    r = simulate(DriveSystem(params, "ddfs", MID), ConstantSpeed(v, PAPER["ddfs_sim_nut_speed"]),
                 12.0)
    return studies.speed_trace(r)


def _mm(v: float | None) -> float | None:
    return None if v is None else 1e3 * v


def _write_tables(out: Path, results: dict[str, Any]) -> None:
    write_csv([{
        "position_mm": 1e3 * r["position"], "k_sa_N_per_um": 1e-6 * r["k_sa"],
        "k_sa_paper_N_per_um": 1e-6 * r["k_sa_paper"], "k_eq_N_per_um": 1e-6 * r["k_eq"],
        "cdfs_critical_mm_s": _mm(r["cdfs"]), "cdfs_paper_mm_s": _mm(r["cdfs_paper"]),
        "ddfs_critical_mm_s": _mm(r["ddfs"]), "ddfs_paper_mm_s": _mm(r["ddfs_paper"]),
    } for r in results["table3"]], out / "table3_position.csv")
    write_csv([{
        "multiple_of_cdfs_critical": r["multiple"], "nut_speed_mm_s": _mm(r["nut_speed"]),
        "overshoot_percent": 100 * r["overshoot"], "settling_time_s": r["settling_time"],
        "verdict": r["verdict"],
    } for r in results["fig7"]["rows"]], out / "fig7_nut_speed.csv")
    write_csv([{
        "table_amplitude_mm_s": _mm(r["table_amplitude"]),
        "nut_amplitude_mm_s": _mm(r["nut_amplitude"]),
        "screw_amplitude_mm_s": _mm(r["screw_amplitude"]),
        "reversal_overshoot_percent": 100 * r["reversal_overshoot"],
    } for r in results["figs9_10"]["rows"]], out / "figs9_10_reversal.csv")
    write_csv([{
        "search": k, "drive": v["drive"], "position_mm": v["table_position_mm"],
        "nut_speed_mm_s": v["nut_speed_mm_s"], "start": v["start"],
        "critical_speed_mm_s": v["critical_speed_mm_s"], "status": v["status"],
        "trials": len(v["trials"]),
    } for k, v in results["critical"].items()], out / "critical_speeds.csv")
