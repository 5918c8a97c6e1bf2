"""`feeddrive reproduce`: the paper's whole study, every number beside the paper's."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from ..io.outputs import shown
from ..parameters import ParameterError
from ._common import (
    FOLDER,
    PlainProgress,
    app,
    console,
    err_console,
    interrupted,
    outputs,
    resolve_parameters,
    user_errors,
)


@app.command("reproduce")
@user_errors
@outputs(out=FOLDER)
def reproduce_command(
    out: Path = typer.Option("reproduce-out", "--out", help="Output folder."),
    preset_name: str | None = typer.Option(None, "--preset", help="Named parameter set "
                                           "(default wang2021)."),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
    workers: int = typer.Option(2, "--workers",
                                help="Processes for the critical-speed searches [-]."),
    study: bool = typer.Option(True, "--study/--no-study", help="Also run the model-reading "
                               "study (variants of the wang2021 presets)."),
) -> None:
    """Regenerate Wang2021's figures (PNG) and tables (CSV) and write report.html/report.md.
    Finished studies are kept in OUT/data and reused on a rerun. A --params file's [solver]
    table sets the integrator of every run (and is part of the stored studies' key)."""
    from ..engine.simulate import run_options
    from ..reproduce import run

    if workers < 1:
        raise ParameterError("--workers", workers, "expected a whole number ≥ 1")
    params = resolve_parameters(preset_name, params_file)
    run_options(params)  # its [solver] table: a bad value refused before any work
    def notice(text: str) -> None:
        err_console.print(f"notice: {shown(text)}", markup=False, highlight=False,
                          soft_wrap=True)

    try:
        if console.is_terminal:
            with Progress(TextColumn("{task.description}"), BarColumn(),
                          MofNCompleteColumn(), TimeElapsedColumn(),
                          console=console) as bar:
                task = bar.add_task("starting", total=None)

                def progress(label: str, done: int, total: int) -> None:
                    bar.update(task, description=label, completed=done, total=total)

                results = run(params, out, workers=workers, study=study, progress=progress,
                              notice=notice)
        else:  # a pipe, a file, a CI log: plain lines, one at least every few seconds
            def say(text: str) -> None:
                console.print(text, markup=False, highlight=False)

            with PlainProgress("reproduce", say) as plain:
                results = run(params, out, workers=workers, study=study,
                              progress=plain.update, notice=notice)
    except KeyboardInterrupt:
        err_console.print(f"interrupted: the studies finished so far are kept in "
                          f"{out / 'data'} and reused by a rerun", markup=False,
                          highlight=False, soft_wrap=True)
        raise interrupted() from None
    console.print(f"wrote {out / 'report.html'}, {out / 'report.md'}, "
                  f"{len(results['figures'])} figures, tables in {out} "
                  f"({results['wall_time_s']:.0f} s)")
