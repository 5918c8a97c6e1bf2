"""The page's knob units from the parameters' own metadata, resolved for the parameter set
(a velocity-loop gain is per rad/s of the motor, or per m/s of table speed on the set's
``velocity_gain_basis = "table"``: A s/rad or A s/m, a factor H ≈ 10⁻³ apart)."""

from __future__ import annotations

import re
from typing import Any

from ..parameters import DriveParameters
from ..parameters.validation import resolved_unit
from .settings import FIELDS, Field


def field_unit(f: Field, params: DriveParameters | None) -> str:
    """The unit of field ``f`` for ``params``: its parameter's metadata when it has a path
    (``controller.velocity_gain``, ``disturbances.screw_motor_ripple.amplitudes[0]``), else
    the field's own."""
    if not f.path or params is None:
        return f.unit
    parts = [re.sub(r"\[\d+\]$", "", p) for p in f.path.split(".")]
    obj: Any = params
    for part in parts[:-1]:
        obj = getattr(obj, part, None)
        if obj is None:
            return f.unit
    try:
        unit = resolved_unit(obj, parts[-1])
    except (KeyError, TypeError):
        return f.unit
    if unit == "-" and f.unit not in ("", "-"):
        return f.unit  # e.g. a ripple order: "per rev" says more than "-"
    return unit or f.unit


def field_units(params: DriveParameters | None) -> dict[str, str]:
    """Every field's unit for ``params``."""
    return {f.name: field_unit(f, params) for f in FIELDS}
