"""`feeddrive export fmu`: a drive as a standalone FMU (docs/fmu.md)."""

from __future__ import annotations

from typing import Any

import typer

from . import _units
from ._common import (
    app,
    console,
    err_console,
    outputs,
    print_json,
    refuse_beside_machine,
    resolve_parameters,
    user_errors,
)
from ._solver import tolerance_options

export_app = typer.Typer(no_args_is_help=True,
                         help="Export a drive for other tools (FMU: docs/fmu.md).")
app.add_typer(export_app, name="export")


@export_app.command("fmu")
@user_errors
@outputs(out=(".fmu",))
@tolerance_options
def fmu_command(
    drive: str | None = typer.Option(None, "--drive", help="cdfs, ddfs, linear-motor or "
                                     "another registered drive (rack-pinion)"),
    machine: str | None = typer.Option(None, "--machine", help="A machine file (TOML, "
                                       "docs/machine.md) or a built-in machine (xy-table, "
                                       "gantry) instead of --drive: one FMU (--kind cs or "
                                       "me), each axis' references and load force as inputs "
                                       "<axis>.<name>."),
    out: str = typer.Option(..., "--out", help="The FMU file to write (DRIVE.fmu)."),
    preset_name: str | None = typer.Option(None, "--preset", help="Named parameter set."),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
    position: float = typer.Option(400.0, "--position", help="Table position on the screw "
                                   "at the start [mm]."),
    fmi: int = typer.Option(2, "--fmi", help="FMI version: 2 or 3."),
    kind: str = typer.Option("cs", "--kind", help="cs (co-simulation: the FMU integrates, "
                             "sampled loops as exact events) or me (model exchange: the "
                             "importer integrates, sampled loops as time events)."),
    table_speed: float = typer.Option(0.0, "--table-speed", help="Start value of the "
                                      "table_speed_reference input [mm/s]."),
    nut_speed: float = typer.Option(0.0, "--nut-speed", help="Start value of the "
                                    "nut_speed_reference input [mm/s] (DDFS)."),
    nut_hold: str | None = typer.Option(None, "--nut-hold", help="How the CDFS holds its "
                                        "nut: locked (the hollow motor's states frozen; the "
                                        "default) or servo (its loop at zero command).  "
                                        "Refused for a drive that holds no nut (the DDFS "
                                        "drives its own; the linear motor and the rack and "
                                        "pinion have none)."),
    platform: str | None = typer.Option(None, "--platform", help="Comma-separated platforms "
                                        "to build a binary for, each with a C compiler found "
                                        "for it: linux64, win64 (MinGW-w64), darwin64 "
                                        "(default: this machine's)."),
    force: bool = typer.Option(False, "--force", help="Replace an existing --out file."),
    as_json: bool = typer.Option(False, "--json", help="Print what was written as JSON."),
    solver: Any = None,
) -> None:
    """Write the drive as an FMU (FMI 2.0 or 3.0, co-simulation or model exchange): a binary
    for this platform (or each --platform) built with a C compiler found for it (needs only
    libc and libm) and its C sources with their CMakeLists.txt.  Inputs: the position/speed
    references and a table load force; outputs: table position and speed, motor angles,
    speeds, currents and torques, friction forces, following error; every model parameter
    tunable, checked against its parameter-file range when set.  With --machine: one FMU
    of every axis, its variables named <axis>.<name>.  The tolerances (--accuracy, --rtol and
    the absolute ones, or the parameter file's [solver] table) become the start values of the
    co-simulation FMU's embedded DOPRI5 (and a [solver] max_step its solver.max_step); a
    [solver] method other than dopri5, rosenbrock, output_interval and max_steps have no
    counterpart in an FMU and are not taken: a note line names each (docs/fmu.md)."""
    from ..fmu import check_request, export_fmu
    from ..model.mechanisms import mechanism
    from ..model.mechanisms.base import check_nut_hold
    from ..parameters import ParameterError

    if machine is not None:
        refuse_beside_machine((
            ("--drive", drive, None), ("--preset", preset_name, None),
            ("--params", params_file, None), ("--position", position, 400.0),
            ("--table-speed", table_speed, 0.0), ("--nut-speed", nut_speed, 0.0),
            ("--nut-hold", nut_hold, None)),
            "its axes are set in the machine file; the references are inputs")
        _export_machine(machine, out, fmi=fmi, kind=kind, force=force, platform=platform,
                        as_json=as_json)
        return
    if drive is None:
        raise ParameterError("--drive", "", "expected a drive name, or --machine FILE")

    check_request(drive, fmi, kind, out, force=force, inputs=(params_file,),
                  platforms=platform)
    if nut_hold is not None:
        if nut_hold not in ("locked", "servo"):
            raise ParameterError("--nut-hold", nut_hold, "expected locked or servo")
        # any value typed for a drive whose nut nothing holds is refused (it was dropped)
        check_nut_hold(drive, nut_hold, field="--nut-hold", given=True)
    hold = nut_hold or "locked"
    v_t = _units.speed("--table-speed", table_speed)
    v_n = _units.speed("--nut-speed", nut_speed)
    params = resolve_parameters(preset_name, params_file, drive)
    if v_n != 0.0:
        topology = mechanism(drive)(params, drive, 0.4, hold)
        axis = topology.reference_axes.get("nut")
        if axis is None or axis not in topology.live_axes():
            raise ParameterError("--nut-speed", nut_speed,
                                 f"the {drive} drive has no live nut axis; expected 0 [mm/s]")
    a = _units.position("--position", position, params, drive)
    result = export_fmu(params, drive, out, table_position=a, nut_hold=hold, fmi=fmi,
                        kind=kind, table_speed=v_t, nut_speed=v_n, force=force,
                        platforms=platform)
    data = {"fmu": str(result.path), "fmi_version": f"{fmi}.0",
            "kind": "co-simulation" if kind == "cs" else "model exchange",
            "model_identifier": result.identifier, "size_bytes": result.size_bytes,
            "variables": result.n_variables, "states": result.n_states,
            "sampled_loops": result.sampled, "binaries": list(result.binaries),
            "inputs": list(result.inputs),
            "outputs": list(result.outputs),
            "solver_settings_not_taken": list(result.not_taken)}
    _not_taken_note(result.not_taken)
    if as_json:
        print_json(data)
        return
    console.print(f"wrote {result.path} ({result.size_bytes / 1024:.0f} kB): FMI {fmi}.0 "
                  f"{data['kind']}, {drive} ({params.name}), {result.n_states} states, "
                  f"{result.n_variables} variables, binaries {', '.join(result.binaries)}"
                  f"{_sampling_note(kind) if result.sampled else ''}",
                  markup=False, highlight=False, soft_wrap=True)
    console.print(f"  inputs:  {', '.join(result.inputs)}", markup=False, highlight=False,
                  soft_wrap=True)
    console.print(f"  outputs: {', '.join(result.outputs)}", markup=False, highlight=False,
                  soft_wrap=True)


def _not_taken_note(not_taken: tuple[str, ...]) -> None:
    """One line on standard error naming the integrator settings the FMU does not take."""
    if not_taken:
        err_console.print("note: the FMU does not take " + "; ".join(not_taken) + " (its "
                          "embedded solver is DOPRI5 with its tolerances and solver.max_step; "
                          "outputs at the importer's communication points: docs/fmu.md)",
                          markup=False, highlight=False, soft_wrap=True)


def _export_machine(machine: str, out: str, *, fmi: int, kind: str, force: bool,
                    platform: str | None, as_json: bool) -> None:
    from ..fmu import export_machine_fmu
    from ..machine import load_machine

    result = export_machine_fmu(load_machine(machine), out, fmi=fmi, kind=kind, force=force,
                                platforms=platform, inputs=(machine,))
    data = {"fmu": str(result.path), "fmi_version": f"{fmi}.0",
            "kind": "co-simulation" if kind == "cs" else "model exchange",
            "model_identifier": result.identifier, "size_bytes": result.size_bytes,
            "variables": result.n_variables, "states": result.n_states,
            "sampled_loops": result.sampled, "binaries": list(result.binaries),
            "inputs": list(result.inputs), "outputs": list(result.outputs),
            "solver_settings_not_taken": list(result.not_taken)}
    _not_taken_note(result.not_taken)
    if as_json:
        print_json(data)
        return
    console.print(f"wrote {result.path} ({result.size_bytes / 1024:.0f} kB): FMI {fmi}.0 "
                  f"{data['kind']}, machine {machine}, {result.n_states} states, "
                  f"{result.n_variables} variables, binaries {', '.join(result.binaries)}"
                  f"{_sampling_note(kind) if result.sampled else ''}",
                  markup=False, highlight=False, soft_wrap=True)
    console.print(f"  inputs:  {', '.join(result.inputs)}", markup=False, highlight=False,
                  soft_wrap=True)
    console.print(f"  outputs: {', '.join(result.outputs)}", markup=False, highlight=False,
                  soft_wrap=True)


def _sampling_note(kind: str) -> str:
    return (", sampled loops as time events" if kind == "me"
            else ", sampled loops as exact events inside each step")
