"""Thin Typer CLI: parses arguments, calls the API, prints.  No logic lives here.

Each command group is a module that registers its commands on ``app``.
"""

from __future__ import annotations

from . import params_cmd  # noqa: F401  (registers commands)
from ._common import app
from .friction_cmd import friction_command  # noqa: F401  (registers commands)
from .stiffness_cmd import stiffness_command  # noqa: F401  (registers commands)
from . import calibrate_cmd, creep_cmd, reproduce_cmd, simulate_cmd  # noqa: F401,E402  (registers commands)

__all__ = ["app"]
