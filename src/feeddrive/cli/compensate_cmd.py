"""`feeddrive compensate`: the CDFS (or another drive) with friction compensation against
the DDFS."""

from __future__ import annotations

import typer

from ._common import MM, MM_PER_S, app, console, print_json, resolve_parameters, user_errors

#: the drives the study compensates, for --help (feeddrive.analysis.compensation.study_drives
#: asks the topologies; tests/unit/test_declarations.py checks this against it)
STUDY_DRIVES = "cdfs|linear-motor"


@app.command("compensate")
@user_errors
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
) -> None:
    """Critical speed, linear creep band and tracking error of the CDFS without and with
    friction compensation (static feed-forward, LuGre observer; exact and ±mismatch), and of
    the DDFS: is the second motor worth it?"""
    from rich.progress import Progress

    from ..analysis.compensation import compensation_study, default_cases, study_drives
    from ..parameters import ParameterError

    if not 0 <= mismatch < 100:
        raise ParameterError("--mismatch", mismatch, "expected 0 … 100 [%]")
    params = resolve_parameters(preset_name, params_file, drive)
    eligible = study_drives(params)  # what the topologies declare
    if drive not in eligible:
        raise ParameterError("--drive", drive, "the study compensates a drive with friction "
                             f"compensation and no driven nut; expected {' or '.join(eligible)}")
    cases = default_cases(mismatch / 100.0, nut_speed * MM_PER_S, drive=drive,
                          alternative=eligible[drive])
    with Progress(console=console, transient=True, disable=as_json) as bar:
        task = bar.add_task("compensation study", total=len(cases))
        rows = compensation_study(params, cases, search=not no_search,
                                  table_position=position * MM,
                                  tracking_speed=tracking_speed * MM_PER_S,
                                  progress=lambda done, total: bar.update(task, completed=done))
    if as_json:
        print_json({"parameter_set": params.name, "rows": rows})
        return
    console.print(f"[bold]Friction compensation vs DDFS[/] ({params.name}, "
                  f"{position:g} mm, tracking at {tracking_speed:g} mm/s)")
    for r in rows:
        bands = ", ".join(f"{lo:.3f}–{hi:.3f}" for lo, hi in r["linear_unstable_bands_mm_s"])
        crit = r.get("critical_speed_mm_s", "—")
        console.print(f"  {r['case']:34s} critical {with_unit(crit):>13s}  linear band "
                      f"{with_unit(bands or 'none'):>18s}  "
                      f"{r['verdict_at_tracking_speed']:11s} "
                      f"error rms {r['following_error_rms_um']:.2f} µm", markup=False)


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
        ``text`` followed by ``" mm/s"`` when it starts with a digit, ``<`` or ``>``.
    """
    return f"{text} mm/s" if text[:1].isdigit() or text[:1] in "<>" else text
