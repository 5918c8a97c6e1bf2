"""The axes of a machine's run, from its attributes: the one reading both the
:class:`~feeddrive.engine.result.Result` and its figures use (a module of its own, so that
neither imports the other for it)."""

from __future__ import annotations

import json
from typing import Any


def run_attrs(result: Any) -> dict[str, Any]:
    """A run's attributes, a machine's marks included: what ``result.attrs`` holds (the
    Dataset is not built for them), and for a run kept as arrays whose system is a machine
    (``feeddrive.machine.MachineSystem.run_attrs``: a run following given references, such
    as each run of a circular test) the machine's name as its parameter set, the path it
    followed and its ``axes``, which its own attributes lack.

    Parameters
    ----------
    result : Result
        The run.

    Returns
    -------
    dict
        Attribute name → value.
    """
    attrs = dict(result.attrs)
    run = getattr(result, "_run", None)
    marks = getattr(getattr(run, "system", None), "run_attrs", None)
    if run is not None and callable(marks) and "axes" not in attrs:
        attrs.update(marks(run.profile))
    return attrs


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
    text = run_attrs(result).get("axes")
    if not text:
        return []
    try:
        return list(json.loads(str(text)))
    except ValueError:
        return []
