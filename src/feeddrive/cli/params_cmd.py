"""`feeddrive params show|slots|check`."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from ..io.outputs import shown
from ..parameters import dumps, load, preset, to_dict
from . import _units
from ._common import (
    EXIT_REFUSED,
    app,
    console,
    err_console,
    print_json,
    refuse_beside_machine,
    resolve_parameters,
    user_errors,
)
from .simulate_cmd import ALL_DRIVES

#: every drive topology, for --help (as `feeddrive simulate` lists them)

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
    machine_file: str | None = typer.Option(
        None, "--machine", help="A machine file (docs/machine.md) or built-in machine: print "
        "each axis' drive and whole resolved set, and the coupling parts (TOML, or JSON with "
        "--format json); not with --preset or --params."),
) -> None:
    """Print a parameter set (SI units) as TOML or JSON: a preset, or the resolved set of a
    parameter file, with the file's [solver] table (its integrator settings, SI; JSON: under
    "solver"); or a machine file resolved (--machine)."""
    if machine_file is not None:
        import tomllib

        from ..machine import load_machine, machine_toml

        refuse_beside_machine((("--preset", preset_name, None), ("--params", params_file, None)))
        if fmt not in ("toml", "json"):
            raise ValueError(f"--format = {fmt!r}: expected toml or json")
        text = machine_toml(load_machine(machine_file))
        typer.echo(text if fmt == "toml" else json.dumps(tomllib.loads(text), indent=2))
        return
    if preset_name is not None and params_file is not None:
        raise ValueError("--preset and --params: give one, not both")
    params = load(params_file) if params_file is not None else preset(preset_name or "wang2021")
    if fmt == "toml":
        typer.echo(dumps(params), nl=False)
    elif fmt == "json":
        data = to_dict(params)
        if params.solver:  # not a parameter: beside them, as the TOML's [solver] table
            data["solver"] = {name: value for name, value, _ in params.solver}
        typer.echo(json.dumps(data, indent=2))
    else:
        raise ValueError(f"--format = {fmt!r}: expected toml or json")


@params_app.command("slots")
@user_errors
def slots(
    preset_name: str | None = typer.Option(None, "--preset", help="Named parameter set "
                                           "(default wang2021, or the drive's example set)."),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
    drive: str | None = typer.Option(None, "--drive", metavar=ALL_DRIVES,
                                     help="The drive whose model is assembled (default "
                                     "cdfs)."),
    position: float = typer.Option(400.0, "--position", help="Table position on the screw "
                                   "[mm]."),
    machine_file: str | None = typer.Option(
        None, "--machine", help="A machine file (docs/machine.md) or built-in machine: its "
        "assembled model's slots instead, <axis>.<slot> and couplings.<name>.<field>."),
    as_json: bool = typer.Option(False, "--json", help="Print the slot record as JSON (the "
                                 "parameter_slots attribute a run writes; its profile "
                                 "block is a zero command)."),
) -> None:
    """Print the parameters a run of DRIVE (or of a machine, --machine) uses, as the
    assembled model's named slots (SI value and unit per slot), the record a run writes; the
    reference profile's block is left out (it is the command, not a parameter)."""
    from ..engine.slot_listing import drive_slot_model, listed_slots, machine_slot_model
    from ..model.slots import slots_json

    if machine_file is not None:
        from ..machine import load_machine

        refuse_beside_machine((("--drive", drive, None), ("--preset", preset_name, None),
                               ("--params", params_file, None), ("--position", position, 400.0)))
        model = machine_slot_model(load_machine(machine_file))
    else:
        drive = drive or "cdfs"
        params = resolve_parameters(preset_name, params_file, drive)
        model = drive_slot_model(params, drive,
                                 _units.position("--position", position, params, drive))
    if as_json:
        print_json(json.loads(slots_json(model)))
        return
    rows = listed_slots(model)
    width = max(len(name) for name, _, _ in rows)
    for name, value, unit in rows:
        typer.echo(f"{name:<{width}}  {value!r:>24}  [{unit}]")


@params_app.command("check")
@user_errors
def check(file: str | None = typer.Argument(None, help="Parameter file (TOML)."),
          machine_file: str | None = typer.Option(
              None, "--machine", help="Check a machine file instead (not with FILE): one line "
              "per error, naming the axis or coupling part.")) -> None:
    """Validate a parameter file (or a machine file); exit non-zero with the offending field
    (every error of a machine file, one line each) if it is refused."""
    if machine_file is not None:
        from ..machine import check_machine
        from ..parameters import ParameterError
        from ..parameters.toml_io import read_toml_file

        if file is not None:
            raise ParameterError("FILE", file, "give a parameter file or --machine FILE, not "
                                 "both")

        errors = check_machine(read_toml_file(machine_file, field="--machine"),
                               base_dir=Path(machine_file).parent)
        for line in errors:
            err_console.print(f"error: {line}", markup=False, highlight=False,
                              soft_wrap=True)
        if errors:
            raise typer.Exit(code=EXIT_REFUSED)
        console.print(f"ok: {shown(machine_file)} is a valid machine file", markup=False,
                      highlight=False, soft_wrap=True)
        return
    if file is None:
        raise ValueError("FILE: give a parameter file, or --machine FILE")
    from ._solver import solver_options

    solver_options({}, file)  # its [solver] table, as a run with --params reads it first
    params = load(file)
    console.print(f"ok: {shown(file)} is a valid parameter set ({shown(params.name)})",
                  markup=False, highlight=False, soft_wrap=True)
