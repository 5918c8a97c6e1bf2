"""Whether a run waits for its compiled solver calls in a helper thread so that Ctrl-C stops
the solver within a step (:func:`feeddrive.engine.simulate._advance`).

The command line asks for it (``feeddrive.__main__``): a command's trials have no progress
callback of their own, and a user presses Ctrl-C there.  From Python a run asks for it by
passing ``progress`` (something watched is long enough to stop), or every run on the main
thread does after :func:`stop_within_a_step`.  It is not the default for every run: the
helper thread costs 0.1–0.2 ms a run (a 1-s CDFS run takes 0.56 ms), what a loop of short
runs would pay for nothing.  A module of its own so that the CLI sets it without importing
the engine.
"""

from __future__ import annotations

_ON = [False]


def stop_within_a_step(on: bool = True) -> None:
    """Let Ctrl-C stop every run started on the main thread within a solver step (``on``),
    not only the runs given a ``progress`` callback.

    Parameters
    ----------
    on : bool, default True
        Whether to.
    """
    _ON[0] = bool(on)


def asked() -> bool:
    """Whether :func:`stop_within_a_step` is on.

    Returns
    -------
    bool
        True when on.
    """
    return _ON[0]
