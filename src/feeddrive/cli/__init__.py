"""Thin Typer CLI: parses arguments, calls the API, prints.  No logic lives here.

Each command group is a module that registers its commands on ``app``.
"""

from __future__ import annotations

from . import (  # noqa: F401,E402  (registers commands)
    analyze_cmd,  # noqa: F401,E402  (registers commands)
    calibrate_cmd,
    creep_cmd,
    identify_cmd,  # noqa: F401,E402  (registers commands)
    linear_cmd,
    params_cmd,  # noqa: F401  (registers commands)
    reproduce_cmd,
    simulate_cmd,
)
from ._common import app
from .friction_cmd import friction_command  # noqa: F401  (registers commands)
from .stiffness_cmd import stiffness_command  # noqa: F401  (registers commands)

__all__ = ["app"]
