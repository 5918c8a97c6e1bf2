"""`feeddrive cache`: what the package keeps in the user's cache, and pruning it
(:mod:`feeddrive.caches`)."""

from __future__ import annotations

import typer

from ..caches import DEFAULT_AGE
from ._common import EXIT_FAILED, app, console, err_console, print_json, user_errors

#: bytes in a MB, as the sizes are printed
MB = 1e6


@app.command("cache")
@user_errors
def cache(
    prune: bool = typer.Option(False, "--prune", help="Remove what has not been used for "
                               "--older-than days: numba caches of other feeddrive versions, "
                               "C libraries and texts (compiled again, ≈ 0.4 s each, when "
                               "needed), unfinished compilations older than an hour; in the "
                               "C cache and its fallback folder. The running version's numba "
                               "cache is kept, and nothing that is not feeddrive's (named as "
                               "feeddrive names what it writes) is touched. What cannot be "
                               "removed, or a cache folder that cannot be read, is listed, and "
                               "the exit status is then 1."),
    older_than: float | None = typer.Option(None, "--older-than", help="Age for --prune "
                                            f"[days], {DEFAULT_AGE:g} if not given; 0 prunes "
                                            "everything it may; a finite number ≥ 0."),
    dry_run: bool = typer.Option(False, "--dry-run", help="With --prune: only list what "
                                 "would be removed."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """Where feeddrive's compile caches are and how large (numba's, one folder per version of
    its kernels; the C build's libraries), and, with --prune, remove the unused."""
    from ..caches import FALLBACK, fallback_unavailable, usage
    from ..caches import prune as prune_caches
    from ..io.outputs import shown
    from ..parameters import ParameterError

    for given, option in ((dry_run, "--dry-run"), (older_than is not None, "--older-than")):
        if given and not prune:
            raise ValueError(f"{option}: give it with --prune")
    days = DEFAULT_AGE if older_than is None else older_than
    try:
        report = prune_caches(days, dry_run=dry_run) if prune else None
    except ParameterError as err:  # the option the user typed
        raise ParameterError("--older-than", err.value, err.message) from None
    parts = usage()
    unavailable = fallback_unavailable()
    if as_json:
        data: dict[str, object] = {"parts": [
            {"name": p.name, "folder": str(p.folder), "entries": p.entries,
             "size_mb": p.size / MB, "note": p.note, "foreign": p.foreign} for p in parts],
            "fallback_unavailable": unavailable}
        if report is not None:
            data["pruned"] = {"dry_run": report.dry_run, "older_than_days": days,
                              "entries": report.entries,
                              "removed": [str(p) for p in report.removed],
                              "freed_mb": report.freed / MB,
                              "failed": [{"path": str(p), "reason": why}
                                         for p, why in report.failed],
                              "unread": [{"path": str(p), "reason": why}
                                         for p, why in report.unread]}
        print_json(data)
    else:
        if report is not None:
            verb = "would remove" if report.dry_run else "removed"
            for path in report.removed if report.dry_run else ():
                console.print(f"  {shown(path, None)}", markup=False, highlight=False)
            entries = "1 entry" if report.entries == 1 else f"{report.entries} entries"
            console.print(f"{verb} {entries} not used for {days:g} days, "
                          f"{report.freed / MB:.1f} MB", markup=False, highlight=False)
            for path, why in report.failed:
                err_console.print(f"error: could not remove {shown(path, None)}: {why}",
                                  markup=False, highlight=False, soft_wrap=True)
            for path, why in report.unread:
                err_console.print(f"error: could not read {shown(path, None)}: {why}; "
                                  "nothing there was pruned",
                                  markup=False, highlight=False, soft_wrap=True)
        for p in parts:
            entries = "1 entry" if p.entries == 1 else f"{p.entries} entries"
            others = "1 other file" if p.foreign == 1 else f"{p.foreign} other files"
            notes = [*([p.note] if p.note else []),
                     *([f"{others} not feeddrive's, left alone"] if p.foreign else [])]
            note = f" ({'; '.join(notes)})" if notes else ""
            console.print(f"{p.name}: {entries}, {p.size / MB:.1f} MB in "
                          f"{shown(p.folder, None)}{note}", markup=False, highlight=False)
        if unavailable:
            console.print(f"{FALLBACK}: unavailable, {unavailable}", markup=False,
                          highlight=False, soft_wrap=True)
    if report is not None and (report.failed or report.unread):
        raise typer.Exit(code=EXIT_FAILED)
