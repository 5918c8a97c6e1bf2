"""Shared CLI plumbing: the Typer app, error reporting, unit conversion at the edge."""

from __future__ import annotations

import functools
import json
import sys
from collections.abc import Callable
from typing import Any, TypeVar

import typer
from rich.console import Console

from .. import units
from ..parameters import DriveParameters, ParameterError, load, preset

app = typer.Typer(
    no_args_is_help=True,
    add_completion=False,
    rich_markup_mode=None,  # Rich markup would eat the units: "[mm/s]" (issue 12 item 1)
    help="feeddrive: low-speed simulation and analysis of ball-screw feed drives (Wang2021).",
)
console = Console()
err_console = Console(stderr=True)

F = TypeVar("F", bound=Callable[..., Any])

# unit conversion at the edge: the CLI speaks mm, mm/s and N/µm
MM, MM_PER_S, N_PER_UM = units.MM, units.MM_PER_S, units.N_PER_UM


def user_errors(fn: F) -> F:
    """Turn a refused input into a one-line message on stderr and exit status 2."""

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return fn(*args, **kwargs)
        except (ParameterError, ValueError, FileNotFoundError) as err:
            err_console.print(f"error: {err}", markup=False, highlight=False, soft_wrap=True)
            raise typer.Exit(code=2) from None

    return wrapper  # type: ignore[return-value]


DEFAULT_PRESETS = {"linear-motor": "linear-motor-example"}


def resolve_parameters(preset_name: str | None, params_file: str | None,
                       drive: str | None = None) -> DriveParameters:
    """The parameter set named by ``--preset`` or loaded from ``--params`` (not both); by
    default ``wang2021``, or the drive's example set (``linear-motor-example``)."""
    if preset_name and params_file:
        raise ParameterError("--params", params_file, "give either --preset or --params, not both")
    if params_file:
        return load(params_file)
    return preset(preset_name or DEFAULT_PRESETS.get(drive or "", "wang2021"))


def print_json(data: Any) -> None:
    sys.stdout.write(json.dumps(data, indent=2, allow_nan=False) + "\n")
