"""Thin Typer CLI: parses arguments, calls the API, prints.  No logic lives here.

Each command group is a module that registers its commands on ``app``
(:data:`COMMAND_MODULES`).  Command modules import the numerical code inside the commands, so
that ``feeddrive --help`` stays fast; the entry point (:mod:`feeddrive.__main__`) imports only
the module of the command it runs (:func:`app_for`), so that a short ``feeddrive simulate``
does not pay for the other fifteen (issue 21 item 4).  ``from feeddrive.cli import app``
gives the app with every command registered.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, Any

import typer

from .. import __version__
from . import _common

if TYPE_CHECKING:
    app: typer.Typer

#: every command (and command group) of ``feeddrive`` → the module that registers it, in the
#: order ``feeddrive --help`` lists them (the order the modules register their commands);
#: tests/integration/test_cli_startup.py checks it against the full app
COMMAND_MODULES: dict[str, str] = {
    "analyze": "analyze_cmd",
    "calibrate": "calibrate_cmd",
    "circular": "circular_cmd",
    "compensate": "compensate_cmd",
    "creep": "creep_cmd",
    "explore": "explore_cmd",
    "export": "export_cmd",
    "fit": "fit_cmd",
    "predict": "fit_cmd",
    "validate": "fit_cmd",
    "identify": "identify_cmd",
    "loops": "linear_cmd",
    "stability": "linear_cmd",
    "params": "params_cmd",
    "positioning": "positioning_cmd",
    "reproduce": "reproduce_cmd",
    "sensitivity": "sensitivity_cmd",
    "simulate": "simulate_cmd",
    "sweep": "sweep_cmd",
    "map": "sweep_cmd",
    "friction": "friction_cmd",
    "stiffness": "stiffness_cmd",
    "cache": "cache_cmd",
}


def _print_version(value: bool) -> None:
    if value:
        typer.echo(f"feeddrive {__version__}")
        raise typer.Exit()


@_common.app.callback()
def _options(version: bool = typer.Option(False, "--version", callback=_print_version,
                                          is_eager=True, help="Print the version and exit.")
             ) -> None:
    """feeddrive: low-speed simulation and analysis of ball-screw feed drives (Wang2021)."""


def load_commands(names: Iterable[str] | None = None) -> typer.Typer:
    """The app with the commands ``names`` registered (every command for None).

    Parameters
    ----------
    names : iterable of str or None, default None
        Command names, keys of :data:`COMMAND_MODULES`; None: all of them.

    Returns
    -------
    typer.Typer
        The ``feeddrive`` app.
    """
    wanted = COMMAND_MODULES.values() if names is None else (COMMAND_MODULES[n] for n in names)
    for module in dict.fromkeys(wanted):  # in COMMAND_MODULES' order: --help's order
        importlib.import_module(f"{__name__}.{module}")
    return _common.app


def app_for(argv: Sequence[str]) -> typer.Typer:
    """The app for one command line: only its command's module imported when the line starts
    with a command's name, every command otherwise (``--help``, ``--version``, shell
    completion, a mistyped name: what they print lists or needs all of them).

    Parameters
    ----------
    argv : sequence of str
        The arguments after the program name (``sys.argv[1:]``).

    Returns
    -------
    typer.Typer
        The ``feeddrive`` app.
    """
    if argv and argv[0] in COMMAND_MODULES:
        return load_commands([argv[0]])
    return load_commands()


def __getattr__(name: str) -> Any:
    if name == "app":  # every command registered, as an eager import of all modules did
        full = load_commands()
        globals()["app"] = full
        return full
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["COMMAND_MODULES", "app", "app_for", "load_commands"]
