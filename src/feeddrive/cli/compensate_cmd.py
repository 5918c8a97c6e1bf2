"""`feeddrive compensate`: the CDFS (or another drive) with friction compensation against
the DDFS."""

from __future__ import annotations

import math
from typing import Any

import typer

from ..io.outputs import PLOT_FORMATS
from . import _units
from ._common import (
    app,
    console,
    err_console,
    interrupted,
    outputs,
    print_json,
    resolve_parameters,
    user_errors,
)
from ._solver import accuracy_options

#: the drives the study compensates, for --help (feeddrive.analysis.compensation.study_drives
#: asks the topologies; tests/unit/test_declarations.py checks this against it)
STUDY_DRIVES = "cdfs|linear-motor"


#: the quantities --compare computes by default
METRICS = "critical,spike,reversal,settling"
#: the schemes of --compare, for --help (tests/unit/test_compensation_compare.py checks this
#: against feeddrive.analysis.compensation_compare.SCHEMES)
COMPARE_SCHEMES = ("none,none-continuous,feedforward,observer,disturbance-observer,"
                   "reset-integrator,reversal-feedforward")


@app.command("compensate")
@user_errors
@outputs(output=(".csv",), plot=PLOT_FORMATS)
@accuracy_options
def compensate_command(
    drive: str = typer.Option("cdfs", "--drive", metavar=STUDY_DRIVES,
                              help="The drive compensated (one with friction compensation and "
                              "no driven nut); for the CDFS the DDFS is added as the "
                              "alternative."),
    position: float = typer.Option(400.0, "--position", help="Table position [mm]."),
    mismatch: float = typer.Option(20.0, "--mismatch", help="Model error of the mismatched "
                                   "cases on F_c, F_s and v_s [%]."),
    nut_speed: float = typer.Option(16.0, "--nut-speed", help="Hollow-motor speed of the "
                                    "DDFS row [mm/s]."),
    tracking_speed: float = typer.Option(1.0, "--tracking-speed", help="Constant table speed "
                                         "of the tracking run [mm/s]."),
    no_search: bool = typer.Option(False, "--no-search", help="Skip the critical-speed "
                                   "searches (fast: linear band and tracking only)."),
    preset_name: str | None = typer.Option(None, "--preset", help="Named parameter set."),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
    compare: bool = typer.Option(False, "--compare", help="Compare every compensation scheme "
                                 "(none, static feed-forward, LuGre observer, disturbance "
                                 "observer, reset integrator, reversal feed-forward) from one "
                                 "sampled drive (default preset wang2021-drive; feed-forward "
                                 "and observer on its continuous-loop version): critical "
                                 "speed, largest circular-test reversal spike, ISO 230-2 B, "
                                 "settling time."),
    schemes: str = typer.Option(COMPARE_SCHEMES, "--schemes", help="--compare: the schemes, "
                                "comma-separated."),
    metrics: str = typer.Option(METRICS, "--metrics",
                                help="--compare: the quantities, comma-separated."),
    band: float = typer.Option(1.0, "--band", help="--compare: settling band, ± [µm]."),
    output: str | None = typer.Option(None, "--output", help="--compare: write the table "
                                      "(CSV)."),
    plot: str | None = typer.Option(None, "--plot", help="--compare: write the figure."),
    force: bool = typer.Option(False, "--force", help="Replace existing --output/--plot "
                               "files."),
    solver: Any = None,
) -> None:
    """Critical speed, linear creep band and tracking error of the CDFS without and with
    friction compensation (static feed-forward, LuGre observer; exact and ±mismatch), and of
    the DDFS: is the second motor worth it?  With --compare: every compensation scheme side
    by side on a sampled drive."""
    from rich.progress import Progress

    if compare:
        _unused({"--mismatch": mismatch != 20.0, "--nut-speed": nut_speed != 16.0,
                 "--tracking-speed": tracking_speed != 1.0, "--no-search": no_search},
                "an option of the study, which --compare does not use")
        _compare(drive, position, schemes, metrics, band, preset_name, params_file, as_json,
                 output, plot, solver.describe())
        return
    if output or plot:
        from ..parameters import ParameterError

        raise ParameterError("--output" if output else "--plot", output or plot,
                             "written by --compare only")
    # they were ignored without a word (an outside check, 2026-12-07)
    _unused({"--schemes": schemes != COMPARE_SCHEMES, "--metrics": metrics != METRICS,
             "--band": band != 1.0}, "an option of --compare, which this run does not use")

    from ..analysis.compensation import compensation_study, default_cases, study_drives
    from ..parameters import ParameterError

    if not 0 <= mismatch < 100:
        raise ParameterError("--mismatch", mismatch, "expected 0 … 100 [%]")
    params = resolve_parameters(preset_name, params_file, drive)
    eligible = study_drives(params)  # what the topologies declare
    if drive not in eligible:
        raise ParameterError("--drive", drive, "the study compensates a drive with friction "
                             f"compensation and no driven nut; expected {' or '.join(eligible)}")
    table_position = _units.position("--position", position, params, drive)
    v_track = _units.speed("--tracking-speed", tracking_speed, nonzero=True)
    cases = default_cases(mismatch / 100.0, _units.speed("--nut-speed", nut_speed),
                          drive=drive, alternative=eligible[drive])
    from ..analysis.compensation import RowsInterrupted

    stopped: RowsInterrupted | None = None
    with Progress(console=console, transient=True, disable=as_json) as bar:
        task = bar.add_task("compensation study", total=len(cases))
        try:
            rows = compensation_study(params, cases, search=not no_search,
                                      table_position=table_position, tracking_speed=v_track,
                                      progress=lambda done, total: bar.update(task,
                                                                              completed=done))
        except RowsInterrupted as stop:  # the finished cases are shown (they were dropped)
            stopped, rows = stop, stop.rows
    _show_study(rows, params.name, position, tracking_speed, solver.describe(), as_json,
                stopped is not None)
    if stopped is not None:
        err_console.print(f"interrupted: {stopped} (those shown)", markup=False,
                          highlight=False)
        raise interrupted()


def _show_study(rows: list[dict[str, Any]], name: str, position: float,
                tracking_speed: float, integrator: str, as_json: bool,
                interrupted: bool) -> None:
    """Print the study's rows (text or JSON; ``interrupted``: the rows before a Ctrl-C)."""
    from ..analysis.linear import bands_text, stored_band_cuts

    if as_json:
        print_json({"parameter_set": name, "rows": rows, "integrator": integrator,
                    "interrupted": interrupted})
        return
    console.print(f"[bold]Friction compensation vs DDFS[/] ({name}, "
                  f"{position:g} mm, tracking at {tracking_speed:g} mm/s)")
    console.print(f"  integrator: {integrator}", markup=False, highlight=False)
    for r in rows:
        found = r["linear_unstable_bands_mm_s"]
        bands = bands_text(found, stored_band_cuts(found), 3)
        crit = r.get("critical_speed_mm_s", "—")
        console.print(f"  {r['case']:34s} critical {with_unit(crit):>13s}  linear band "
                      f"{with_unit(bands or 'none'):>18s}  "
                      f"{r['verdict_at_tracking_speed']:11s} "
                      f"error rms {r['following_error_rms_um']:.2f} µm", markup=False)


def _unused(changed: dict[str, bool], why: str) -> None:
    """Refuse the first option given (``changed``) that the run asked for does not use."""
    given = [name for name, was in changed.items() if was]
    if given:
        from ..parameters import ParameterError

        raise ParameterError(given[0], "given", why)


def _compare(drive: str, position: float, schemes: str, metrics: str, band: float,
             preset_name: str | None, params_file: str | None, as_json: bool,
             output: str | None, plot: str | None, integrator: str) -> None:
    """`feeddrive compensate --compare`: parse, call compare_compensations, print."""
    from rich.progress import Progress

    from ..analysis.compensation_compare import (
        METRIC_ONCE,
        METRICS,
        SCHEME_ONCE,
        SCHEMES,
        check_names,
        check_sampled,
        compare_compensations,
    )

    names = [n.strip() for n in schemes.split(",") if n.strip()]
    wanted = [m.strip() for m in metrics.split(",") if m.strip()]
    for option, given, items, known, each in (
            ("--schemes", schemes, names, SCHEMES, SCHEME_ONCE),
            ("--metrics", metrics, wanted, METRICS, METRIC_ONCE)):
        if not items:  # an empty table, exit 0 (an outside check, 2026-12-07)
            from ..parameters import ParameterError

            raise ParameterError(option, given, "expected one name or more, comma-separated")
        # a scheme twice ran twice, its row repeated; a quantity twice was counted twice in
        # the progress (an earlier sweep, session 30); an unknown name was refused as the
        # API's argument (schemes = […]), not as the option typed
        check_names(items, known, each, option)
    if not math.isfinite(band) or band <= 0:
        from ..parameters import ParameterError

        raise ParameterError("--band", band, "expected a band > 0 [µm]")
    if preset_name is None and params_file is None:
        preset_name = "wang2021-drive"
    params = resolve_parameters(preset_name, params_file, drive)
    check_sampled(params)
    table_position = _units.position("--position", position, params, drive)
    from ..analysis.compensation import RowsInterrupted

    stopped: RowsInterrupted | None = None
    with Progress(console=console, transient=True, disable=as_json) as bar:
        task = bar.add_task("compensation comparison", total=None)

        def progress(done: int, total: int, label: str) -> None:
            bar.update(task, completed=done, total=total, description=label)

        try:
            rows = compare_compensations(params, drive=drive, table_position=table_position,
                                         names=names, metrics=wanted, band=band * 1e-6,
                                         progress=progress)
        except RowsInterrupted as stop:  # the finished schemes are kept (they were dropped)
            stopped, rows = stop, stop.rows
    if stopped is not None and not rows:
        err_console.print(f"interrupted: {stopped}; nothing written", markup=False,
                          highlight=False)
        raise interrupted()
    _show_comparison(rows, params.name, drive, position, band, integrator, as_json, output,
                     plot, stopped is not None)
    if stopped is not None:
        err_console.print(f"interrupted: {stopped} (those shown"
                          + (", and written" if output or plot else "") + ")",
                          markup=False, highlight=False)
        raise interrupted()


def _show_comparison(rows: list[dict[str, Any]], name: str, drive: str, position: float,
                     band: float, integrator: str, as_json: bool, output: str | None,
                     plot: str | None, interrupted: bool) -> None:
    """Write and print the comparison's rows (``interrupted``: those before a Ctrl-C)."""
    from ..analysis.compensation_compare import COLUMNS, comparison_csv

    if output:
        from ..io.outputs import atomic_path

        with atomic_path(output) as tmp:
            tmp.write_text(comparison_csv(rows), encoding="utf-8")
    if plot:
        from ..plots.acceptance import compensation_figure, save

        save(compensation_figure(rows), plot)
    if as_json:
        print_json({"parameter_set": name, "drive": drive, "position_mm": position,
                    "rows": rows, "output": output, "plot": plot, "integrator": integrator,
                    "interrupted": interrupted})
        return
    console.print(f"[bold]Friction compensation compared[/] ({name}, {drive}, "
                  f"{position:g} mm; settling band ±{band:g} µm)")
    console.print(f"  integrator: {integrator}", markup=False, highlight=False)
    console.print("  " + f"{'scheme':22s}" + "".join(f"{h:>30s}" for _, h in COLUMNS),
                  markup=False)
    for r in rows:
        cells = []
        for key, _ in COLUMNS:
            v = r.get(key, "—")
            cells.append(f"{v:>30.4g}" if isinstance(v, float) else f"{v!s:>30s}")
        console.print(f"  {r['scheme']:22s}" + "".join(cells), markup=False)
    for r in rows:
        console.print(f"  {r['scheme']}: " + "; ".join(f"{k} = {v}" for k, v in
                                                      r["settings"].items()), markup=False)
    if output:
        console.print(f"wrote table {output}", markup=False)
    if plot:
        console.print(f"wrote figure {plot}", markup=False)


def with_unit(text: str) -> str:
    """A speed or band as printed, with its unit; a word (``none``, ``undecided``, ``—``) without.

    Issue 24 item 13: the output read "none mm/s", "undecided mm/s".

    Parameters
    ----------
    text : str
        A formatted speed, band (``"<0.5"``, ``"1.2–1.6"``) or word.

    Returns
    -------
    str
        ``text`` followed by ``" mm/s"`` when it starts with a digit, ``<``, ``>``, or ``≤``
        (a band whose lower edge is the scan's end).
    """
    return f"{text} mm/s" if text[:1].isdigit() or text[:1] in "<>≤≥" else text
