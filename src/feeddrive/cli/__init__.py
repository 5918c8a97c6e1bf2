"""Thin Typer CLI: parses arguments, calls the API, prints.  No logic lives here.

Each command group is a module that registers its commands on ``app``.  Command modules
import the numerical code inside the commands, so that ``feeddrive --help`` stays fast.
"""

from __future__ import annotations

import typer

from .. import __version__
from . import (  # noqa: F401,E402  (registers commands)
    analyze_cmd,  # noqa: F401,E402  (registers commands)
    calibrate_cmd,
    compensate_cmd,
    creep_cmd,
    explore_cmd,  # noqa: F401  (registers commands)
    export_cmd,  # noqa: F401  (registers commands)
    fit_cmd,  # noqa: F401  (registers commands)
    identify_cmd,  # noqa: F401,E402  (registers commands)
    linear_cmd,
    params_cmd,  # noqa: F401  (registers commands)
    reproduce_cmd,
    sensitivity_cmd,  # noqa: F401  (registers commands)
    simulate_cmd,
    sweep_cmd,  # noqa: F401  (registers commands)
)
from ._common import app
from .friction_cmd import friction_command  # noqa: F401  (registers commands)
from .stiffness_cmd import stiffness_command  # noqa: F401  (registers commands)


def _print_version(value: bool) -> None:
    if value:
        typer.echo(f"feeddrive {__version__}")
        raise typer.Exit()


@app.callback()
def _options(version: bool = typer.Option(False, "--version", callback=_print_version,
                                          is_eager=True, help="Print the version and exit.")
             ) -> None:
    """feeddrive: low-speed simulation and analysis of ball-screw feed drives (Wang2021)."""


__all__ = ["app"]
