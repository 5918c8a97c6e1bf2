"""The axes of a machine's run, from its attributes: the one reading both the
:class:`~feeddrive.engine.result.Result` and its figures use (a module of its own, so that
neither imports the other for it)."""

from __future__ import annotations

import json
from typing import Any


def machine_axes(result: Any) -> list[str]:
    """The axes of a machine's run (``feeddrive.machine.simulate_machine``, a circular test's
    runs), in order; [] for one drive's.

    Parameters
    ----------
    result : Result
        The run.

    Returns
    -------
    list of str
        The axis names its signals are prefixed with.
    """
    text = result.attrs.get("axes")  # the run's own: the Dataset is not built for them
    if not text:
        return []
    try:
        return list(json.loads(str(text)))
    except ValueError:
        return []
