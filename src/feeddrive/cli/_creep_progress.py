"""`feeddrive creep`'s progress on a terminal: the search under way, its trials and the
time elapsed (stderr; nothing with ``--json`` or off a terminal)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from . import _common

__all__ = ["SearchProgress", "search_progress", "stage"]


class SearchProgress:
    """The searches' progress on stderr, as a drive's ``simulate`` shows its run's
    (``feeddrive.cli._common.progress_bar``: rich, transient, on the error console): the
    search under way, the trials it has run (where it reports them) and the time elapsed.

    Parameters
    ----------
    bar : rich.progress.Progress
        The display, started.
    """

    def __init__(self, bar: Any) -> None:
        self.bar = bar
        self.task = bar.add_task("starting", total=None, count="")

    def stage(self, label: str) -> Callable[[int, int], None]:
        """A new search: its label shown, its count cleared.

        Parameters
        ----------
        label : str
            What is searched.

        Returns
        -------
        callable
            ``advance(done, total)``, the search's ``progress`` (total 0: not known).
        """
        self.bar.update(self.task, description=label, count="")
        return self.advance

    def advance(self, done: int, total: int) -> None:
        """``done`` trials of ``total`` (0: not known) run.

        Parameters
        ----------
        done, total : int
            Trials run and to run.
        """
        count = f"{done} of {total}" if total else f"{done}"
        self.bar.update(self.task, count=f"{count} trial{'' if (total or done) == 1 else 's'}")


@contextmanager
def search_progress(shown: bool) -> Iterator[SearchProgress | None]:
    """:class:`SearchProgress` while the searches run, if ``shown`` and stderr is a terminal
    (elsewhere a transient rich display draws nothing; and with ``--json`` rich.progress is
    not imported); else None.

    Parameters
    ----------
    shown : bool
        Whether progress may be shown (not with ``--json``).

    Yields
    ------
    SearchProgress or None
        The display.
    """
    if not (shown and _common.err_console.is_terminal):
        yield None
        return
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    with Progress(TextColumn("{task.description}"), BarColumn(),
                  TextColumn("{task.fields[count]}"), TimeElapsedColumn(),
                  console=_common.err_console, transient=True) as bar:
        yield SearchProgress(bar)


def stage(shown: SearchProgress | None, label: str) -> dict[str, Any]:
    """The ``progress`` keyword of a search with a counting callback: none without a
    display (the call is then the one ``reproduce`` makes).

    Parameters
    ----------
    shown : SearchProgress or None
        The display.
    label : str
        What is searched.

    Returns
    -------
    dict
        ``{"progress": advance}`` or empty.
    """
    return {} if shown is None else {"progress": shown.stage(label)}
