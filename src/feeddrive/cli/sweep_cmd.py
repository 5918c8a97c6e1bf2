"""`feeddrive sweep` and `feeddrive map`: parameter studies, their store and maps."""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import typer

from ..io.outputs import PLOT_FORMATS, SWEEP_EXPORT_FORMATS, is_same_file, shown
from ._common import (
    STORE,
    app,
    console,
    err_console,
    interrupted,
    outputs,
    print_json,
    user_errors,
)
from ._solver import accuracy_options


def _speed_column(rate: float) -> str:
    return f"{rate:.3g} points/s" if rate == rate else "– points/s"


def _plot(ds: Any, plot: str, x: str | None, y: str | None, value: str | None) -> str:
    from ..sweep import plot_histogram, plot_map

    if "sample" in ds.dims or (x is None and y is None and len(ds.dims) < 2):
        stats = plot_histogram(ds, plot, value=value)
        return _stats_text(stats)
    dims = [str(d) for d in ds.dims if ds.sizes[d] > 1 and d != "drive"] or \
        [str(d) for d in ds.dims]
    x = x or (dims[0] if dims else None)
    y = y or next((d for d in dims if d != x), None)
    if x is None or y is None:
        raise ValueError("--x/--y: a map needs two swept axes")
    from ..sweep.maps import DEFAULT_VALUE

    plot_map(ds, x, y, plot, value=value)
    shown_value = value or DEFAULT_VALUE.get(str(ds.attrs.get("quantity")), "")
    return f"map of {shown_value} over {x} × {y}"


def _stats_text(stats: dict[str, Any]) -> str:
    unit = f" {stats['unit']}" if stats["unit"] not in ("", "1") else ""
    infinite = stats.get("infinite", 0)  # ∞ (no phase crossover), not missing
    if stats["finite"] == 0:
        return (f"{stats['value']}: no finite value among {stats['points']} points"
                + (f" ({infinite} infinite)" if infinite else ""))
    return (f"{stats['value']}: P5 {stats['p5']:.4g}, median {stats['p50']:.4g}, P95 "
            f"{stats['p95']:.4g}{unit} ({stats['finite']} of {stats['points']} points finite"
            + (f", {infinite} infinite)" if infinite else ")"))


@app.command("sweep")
@user_errors
@outputs(store=STORE, plot=PLOT_FORMATS, output=SWEEP_EXPORT_FORMATS)
@accuracy_options
def sweep_command(
    config: str = typer.Argument(..., help="Sweep configuration (TOML; docs/sweeps.md)."),
    store: str | None = typer.Option(None, "--store", help="Results store (SQLite file); "
                                     "default: the configuration's 'store', else NAME.sqlite "
                                     "in the current folder."),
    workers: int | None = typer.Option(None, "--workers", help="Local worker processes "
                                       "(default: every core)."),
    scheduler: str | None = typer.Option(None, "--scheduler", help="Address of a running "
                                         "Dask scheduler (tcp://HOST:PORT)."),
    dask_workers: int | None = typer.Option(None, "--dask-workers", help="Start a Dask "
                                            "LocalCluster with this many worker processes "
                                            "[processes]."),
    dry_run: bool = typer.Option(False, "--dry-run", help="Print the point count and an "
                                 "estimated time from a few timed points; store nothing."),
    plot: str | None = typer.Option(None, "--plot", help="Map (grid) or histogram (random, "
                                    "lhs) of the result [.png, .pdf, .svg]."),
    x: str | None = typer.Option(None, "--x", help="Map's horizontal axis (default: the "
                                 "configuration's [map] x)."),
    y: str | None = typer.Option(None, "--y", help="Map's vertical axis."),
    output: str | None = typer.Option(None, "--output", help="Export the results "
                                      "[.csv, .parquet (mm, mm/s), .nc (SI)]."),
    force: bool = typer.Option(False, "--force", help="Replace existing --plot/--output."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
    solver: Any = None,
) -> None:
    """Run a parameter study: a grid, random or Latin-hypercube design over any parameter by
    its dotted name, drive, preset, table position [mm], nut speed [mm/s]; at each point the
    critical speed, one creep trial, the linear band or the loop margins.  Each finished point
    is committed at once to the store; a rerun skips the points already there, so an
    interrupted sweep resumes where it stopped.  Everything is checked before the first
    simulation."""
    from ..sweep import SweepStore, estimate, export, load_config, to_dataset
    from ..sweep.executors import PROBE_DURATION

    cfg = load_config(config)
    store_path = Path(store) if store is not None else (
        cfg.store if cfg.store is not None else Path(f"{cfg.name}.sqlite"))
    option = "--store" if store is not None else (
        f"{config}: store" if cfg.store is not None else "store")
    from ..sweep.store import check_existing_store

    check_existing_store(store_path, option)  # before the design is built
    # the loop's own name: `option` names the store in the messages below (it was
    # overwritten here, and a store that is no database was called "--output": an outside
    # check, 2026-12-07)
    for writes, path in (("--plot", plot), ("--output", output)):
        if path is not None and store is None and is_same_file(path, store_path):
            raise ValueError(f"{writes} {shown(path)}: is the sweep's store; refusing to "
                             "overwrite it")
    if dry_run and (plot or output):
        raise ValueError("--dry-run: stores nothing, so --plot and --output have nothing to show")
    from ..sweep.executors import check_executor

    check_executor(workers=workers, scheduler=scheduler, dask_workers=dask_workers)
    if dry_run:  # counts from the design; only the timed points are built
        db = SweepStore(store_path, option=option, create=False) if store_path.exists() \
            else None
        n = dask_workers or workers or os.cpu_count() or 1
        est = estimate(cfg, db, workers=n,
                       progress=None if as_json else
                       lambda text: err_console.print(f"dry run: {text} …", markup=False,
                                                      highlight=False, soft_wrap=True))
        lo, hi = est.spread
        total_range = list(est.seconds_range)
        out = {"sweep": cfg.name, "points": est.points, "distinct": est.distinct,
               "stored": est.stored, "to_compute": max(est.distinct - est.stored, 0),
               "timed_points": est.timed, "seconds_per_point": est.seconds_per_point,
               "seconds_per_point_range": [lo, hi], "workers": n,
               "estimated_seconds": est.seconds,
               "estimated_seconds_range": total_range,
               "worker_startup_seconds": est.startup_seconds,
               "compile_seconds": est.compile_seconds,
               "probe_cpu_per_simulated_second": est.probe_rate,
               "timing": "CPU seconds, one core per worker; the range covers the workers' "
                         "start (imports, kernel loading) and, for a simulated quantity, the "
                         "least and most simulated time its protocol takes",
               "parameter_sets_built": est.built}
        if as_json:
            print_json(out)
            return
        todo = est.distinct - est.stored
        if todo <= 0:
            cost = "nothing to compute"
        elif est.timed:
            cost = (f"{est.seconds_per_point:.3g} s CPU per point ({est.timed} timed: "
                    f"{lo:.3g}–{hi:.3g} s)")
        elif est.probe_rate is not None:
            cost = (f"{lo:.3g}–{hi:.3g} s CPU per point (a {PROBE_DURATION:g}-s probe: "
                    f"{est.probe_rate:.3g} s CPU per simulated second, times the least and "
                    "most simulated time of the quantity's protocol)")
        else:  # not timed (an estimate from elsewhere): the counts only
            cost = "cost not estimated"
        if todo > 0:
            cost += (f" and {est.startup_seconds:.2g} s to start each worker → about "
                     f"{total_range[0]:.3g}–{total_range[1]:.3g} s on {n} workers with a free "
                     "core each; longer on a loaded machine")
            if est.compile_seconds:
                cost += (f"; the model kernels were compiled now ({est.compile_seconds:.3g} s "
                         "CPU, once: the sweep finds them cached)")
        console.print(f"sweep {shown(cfg.name)}: {est.points} points ({est.distinct} distinct, "
                      f"{est.stored} already stored, {max(todo, 0)} to compute); "
                      + cost, markup=False, highlight=False, soft_wrap=True)
        return
    summary, db = _run(cfg, lambda: SweepStore(store_path, option=option, notice=_notice),
                       workers, scheduler, dask_workers, quiet=as_json)
    with db:
        shown_plot = _plot(to_dataset(db, cfg.name), plot, x or cfg.map_axes[0],
                           y or cfg.map_axes[1], None) if plot else None
        if output:
            export(db, cfg.name, output)
    out = {"sweep": cfg.name, "store": os.fspath(store_path), "points": summary.points,
           "distinct": summary.distinct, "stored_before": summary.stored_before,
           "computed": summary.computed, "failed": summary.failed,
           "seconds": summary.seconds, "points_per_second": summary.rate,
           "executor": summary.executor, "computed_elsewhere": summary.elsewhere,
           "plot": plot, "output": output, "integrator": solver.describe()}
    if as_json:
        out["points_per_second"] = None if summary.computed == 0 else summary.rate
        print_json(out)
        return
    console.print(f"sweep {shown(cfg.name)}: {summary.points} points, {summary.distinct} "
                  f"distinct; {summary.stored_before} found in {shown(store_path)}, "
                  f"{summary.computed} computed ({summary.failed} failed)"
                  + (f", {summary.elsewhere} computed meanwhile by another sweep"
                     if summary.elsewhere else "")
                  + f" in {summary.seconds:.1f} s"
                  + (f", {_speed_column(summary.rate)} on {summary.executor}"
                     if summary.computed else ""), markup=False, highlight=False)
    console.print(f"integrator: {solver.describe()}", markup=False, highlight=False)
    if plot:
        console.print(f"{shown(plot)}: {shown_plot}", markup=False, highlight=False)
    if output:
        console.print(f"{shown(output)}: results exported", markup=False, highlight=False)


def _notice(text: str) -> None:
    err_console.print(f"notice: {text}", markup=False, highlight=False, soft_wrap=True)


def _run(cfg: Any, open_store: Any, workers: int | None, scheduler: str | None,
         dask_workers: int | None, *, quiet: bool) -> tuple[Any, Any]:
    """Check every point, then open the store and run: (summary, the open store)."""
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        ProgressColumn,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )
    from rich.text import Text

    from ..sweep import run_sweep
    from ..sweep.executors import SweepAborted, SweepInterrupted, check_design

    class Rate(ProgressColumn):
        def render(self, task: Any) -> Text:
            return Text(_speed_column(task.finished_speed or task.speed or float("nan")))

    bar = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                   Rate(), TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn(),
                   console=err_console, transient=True, disable=quiet)
    with bar:
        name = shown(cfg.name)
        task = bar.add_task(f"sweep {name}: checking points", total=None)

        def checked(done: int, total: int) -> None:
            bar.update(task, completed=done, total=total)

        def started(todo: int, where: str) -> None:
            bar.update(task, completed=0, total=todo, description=f"sweep {name} on {where}")

        def progress(done: int, todo: int) -> None:
            bar.update(task, completed=done, total=todo)

        design = check_design(cfg, checked=checked)  # every point, before the store opens
        db = open_store()
        try:
            try:
                return run_sweep(cfg, db, workers=workers, scheduler=scheduler,
                                 dask_workers=dask_workers, progress=progress,
                                 started=started, design=design), db
            except BaseException:
                db.close()
                raise
        except SweepAborted as err:
            bar.stop()
            err_console.print(f"error: {err}", markup=False, highlight=False, soft_wrap=True)
            raise typer.Exit(code=1) from None
        except KeyboardInterrupt as err:
            bar.stop()
            kept = f"{err.computed} computed this run; " if isinstance(err, SweepInterrupted) \
                else ""
            err_console.print(f"interrupted: every finished point is in {shown(db.path)} "
                              f"({kept}the points in flight were cancelled); rerun the same "
                              "command to resume", markup=False, highlight=False,
                              soft_wrap=True)
            raise interrupted() from None


@app.command("map")
@user_errors
@outputs(plot=PLOT_FORMATS, output=SWEEP_EXPORT_FORMATS)
def map_command(
    store: str = typer.Argument(..., help="Results store of a sweep (SQLite file)."),
    sweep: str | None = typer.Option(None, "--sweep", help="Sweep name (default: the only "
                                     "one, else the latest)."),
    x: str | None = typer.Option(None, "--x", help="Horizontal axis: a swept name, e.g. "
                                 "table_position [mm]."),
    y: str | None = typer.Option(None, "--y", help="Vertical axis, e.g. nut_speed [mm/s]."),
    value: str | None = typer.Option(None, "--value", help="Value shown (default: "
                                     "critical_speed, ripple_ratio, linear_upper or "
                                     "damping_ratio by quantity)."),
    plot: str | None = typer.Option(None, "--plot", help="Map (grid) or histogram (random, "
                                    "lhs) [.png, .pdf, .svg]."),
    output: str | None = typer.Option(None, "--output", help="Export the sweep [.csv, "
                                      ".parquet (mm, mm/s), .nc (SI)]."),
    force: bool = typer.Option(False, "--force", help="Replace existing --plot/--output."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """Maps of a stored sweep: a heatmap of a value over two swept axes with the linear
    stability boundary (dashed) drawn over the simulated creep boundary (solid), one panel
    per value of the other axes (one per drive, say); for a random or Latin-hypercube design the
    histogram and 5/50/95 % percentiles (Monte Carlo).  Reads the store only."""
    from ..sweep import SweepStore, export, percentiles, plot_histogram, plot_map, to_dataset

    if (x is None) != (y is None):
        raise ValueError("--x and --y: give both (a map) or neither")
    with SweepStore(store, option="STORE", create=False, notice=_notice) as db:
        names = db.sweeps()
        if sweep is None:
            if not names:
                raise ValueError(f"STORE {shown(store)}: holds no sweep")
            sweep = names[-1]
        ds = to_dataset(db, sweep)
        if output:
            export(db, sweep, output)
    desc: dict[str, Any] = {"sweep": sweep, "design": ds.attrs["design"],
                            "axes": [str(d) for d in ds.dims],
                            "points": math.prod(ds.sizes.values())}
    if x is not None and y is not None:
        if plot is None:
            raise ValueError("--x/--y: give --plot FILE.png for the map")
        plot_map(ds, x, y, plot, value=value)
        desc["plot"] = plot
        text = f"{shown(plot)}: map over {x} × {y}"
    else:
        stats = plot_histogram(ds, plot, value=value) if plot else percentiles(ds, value)
        desc["statistics"] = stats
        text = _stats_text(stats) + (f"; histogram {shown(plot)}" if plot else "")
    if as_json:
        print_json(desc)
        return
    console.print(f"sweep {sweep} ({desc['design']}, {desc['points']} points): {text}",
                  markup=False, highlight=False)
    if output:
        console.print(f"{shown(output)}: results exported", markup=False, highlight=False)
