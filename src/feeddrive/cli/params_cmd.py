"""`feeddrive params show|check`."""

from __future__ import annotations

import json

import typer

from ..io.outputs import shown
from ..parameters import dumps, load, preset, to_dict
from ._common import app, console, user_errors

params_app = typer.Typer(no_args_is_help=True, help="Show and check parameter sets.")
app.add_typer(params_app, name="params")


@params_app.command("show")
@user_errors
def show(
    preset_name: str | None = typer.Option(None, "--preset",
                                           help="Named parameter set (default wang2021)."),
    params_file: str | None = typer.Option(
        None, "--params", help="Parameter file (TOML): print the whole set it resolves to, "
        "with everything its `extends` brings in."),
    fmt: str = typer.Option("toml", "--format", help="toml or json"),
) -> None:
    """Print a parameter set (SI units) as TOML or JSON: a preset, or the resolved set of a
    parameter file."""
    if preset_name is not None and params_file is not None:
        raise ValueError("--preset and --params: give one, not both")
    params = load(params_file) if params_file is not None else preset(preset_name or "wang2021")
    if fmt == "toml":
        typer.echo(dumps(params), nl=False)
    elif fmt == "json":
        typer.echo(json.dumps(to_dict(params), indent=2))
    else:
        raise ValueError(f"--format = {fmt!r}: expected toml or json")


@params_app.command("check")
@user_errors
def check(file: str = typer.Argument(..., help="Parameter file (TOML).")) -> None:
    """Validate a parameter file; exit non-zero with the offending field if it is refused."""
    params = load(file)
    console.print(f"ok: {shown(file)} is a valid parameter set ({shown(params.name)})",
                  markup=False, highlight=False, soft_wrap=True)
