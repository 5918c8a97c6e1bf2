"""The axes of a machine's run, from its attributes: the one reading both the
:class:`~feeddrive.engine.result.Result` and its figures use (a module of its own, so that
neither imports the other for it)."""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..parameters import DriveParameters


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
    return axes_of(result.attrs)  # the run's own: the Dataset is not built for them


def axes_of(attrs: Mapping[str, Any]) -> list[str]:
    """The axis names a run's attributes list (``axes``: JSON text in a NetCDF or ``.mat``
    file, a mapping in a Parquet file's ``df.attrs``), in order; [] for one drive's run.

    Parameters
    ----------
    attrs : mapping
        A run's attributes.

    Returns
    -------
    list of str
        The axis names.
    """
    value = attrs.get("axes")
    if isinstance(value, Mapping):
        return [str(name) for name in value]
    if not value:
        return []
    try:
        return [str(name) for name in json.loads(str(value))]
    except ValueError:
        return []


def axis_parameter_sets(attrs: Mapping[str, Any]) -> dict[str, DriveParameters]:
    """Each axis' parameter set a machine's run recorded (``<axis>_parameters_toml``), read
    back; {} for one drive's run (its set is ``parameters_toml``).

    Parameters
    ----------
    attrs : mapping
        A run's attributes: a NetCDF file's, a ``.mat`` file's ``feeddrive.attrs``, a Parquet
        file's ``df.attrs``.

    Returns
    -------
    dict of str to DriveParameters
        Axis name → its parameter set as the run was given it, in axis order (the axes whose
        set the attributes hold).
    """
    from ..parameters import loads

    keys = {name: f"{name}_parameters_toml" for name in axes_of(attrs)}
    return {name: loads(str(attrs[key])) for name, key in keys.items() if key in attrs}
