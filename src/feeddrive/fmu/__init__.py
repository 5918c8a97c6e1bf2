"""FMU export: a drive as a standalone Functional Mock-up Unit (FMI 2.0 or 3.0).

``export_fmu(parameters, drive, out, ...)`` assembles the drive with its reference and load
force as inputs (:mod:`feeddrive.fmu.model`), declares every state, signal and parameter
(:mod:`feeddrive.fmu.description`), translates the model and the integrator to C
(:mod:`feeddrive.backends.c_backend`, :mod:`feeddrive.fmu.solver`), compiles them with the
machine's C compiler and zips the FMU with its sources (:mod:`feeddrive.fmu.build`).
docs/fmu.md describes the inputs, outputs and the use from fmpy, PathSim, OpenModelica and
Simulink.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from ..parameters import DriveParameters, ParameterError

FMI_VERSIONS = (2, 3)
KINDS = ("cs", "me")


@dataclass(frozen=True)
class ExportedFmu:
    """What :func:`export_fmu` wrote.

    Parameters
    ----------
    path : Path
        The ``.fmu`` file.
    fmi : int
        FMI version, 2 or 3.
    kind : str
        ``"cs"`` (co-simulation) or ``"me"`` (model exchange).
    identifier : str
        The model identifier (the binary's name).
    n_variables : int
        Number of FMU variables.
    n_states : int
        Number of continuous states.
    inputs : tuple of str
        Names of the input variables.
    outputs : tuple of str
        Names of the output variables.
    size_bytes : int
        Size of the file [bytes].
    sampled : bool
        Whether any loop is sampled (events in the FMU).
    """

    path: Path
    fmi: int
    kind: str
    identifier: str
    n_variables: int
    n_states: int
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    size_bytes: int
    sampled: bool


def check_request(drive: str, fmi: int, kind: str, out: str | os.PathLike[str], *,
                  force: bool = False, inputs: tuple[str | None, ...] = (),
                  option: str = "--out") -> Path:
    """Refuse a request that cannot succeed, before any work: unknown drive, FMI version or
    kind, an output that is not a writable new ``.fmu`` file (an existing one only with
    ``force``; never one of ``inputs``), no C compiler.  One-line errors name what to change.

    Parameters
    ----------
    drive : str
        The drive name.
    fmi : int
        FMI version, 2 or 3.
    kind : str
        ``"cs"`` or ``"me"``.
    out : str or os.PathLike
        The ``.fmu`` file to write.
    force : bool, default False
        Replace an existing file.
    inputs : tuple of (str or None), default ()
        Files the command reads, which the output may never replace.
    option : str, default "--out"
        The option named in messages.

    Returns
    -------
    Path
        The output path.

    Raises
    ------
    ParameterError
        For an unknown drive, FMI version or kind.
    OutputError
        For an output that cannot be written.
    ValueError
        Without a C compiler (the compiler search's message).
    """
    from ..io.outputs import check_output_file
    from ..model.mechanisms import drive_names
    from .build import CompilerNotFound, find_compiler

    if drive not in drive_names():
        raise ParameterError("--drive", drive, f"expected one of {', '.join(drive_names())}")
    if fmi not in FMI_VERSIONS:
        raise ParameterError("--fmi", fmi, "expected 2 or 3 (FMI 2.0 or 3.0)")
    if kind not in KINDS:
        raise ParameterError("--kind", kind,
                             "expected cs (co-simulation) or me (model exchange)")
    if Path(out).suffix.lower() != ".fmu":
        raise ParameterError(option, os.fspath(out), "expected a file name ending in .fmu")
    path = check_output_file(out, option=option, inputs=inputs, force=force)
    try:
        find_compiler()
    except CompilerNotFound as err:
        raise ValueError(str(err)) from None
    return path


def export_fmu(parameters: DriveParameters, drive: str, out: str | os.PathLike[str], *,
               table_position: float = 0.4, nut_hold: str = "locked", fmi: int = 2,
               kind: str = "cs", table_speed: float = 0.0, nut_speed: float = 0.0,
               force: bool = False, identifier: str | None = None) -> ExportedFmu:
    """Write ``drive`` with ``parameters`` as an FMU to ``out``.

    ``table_position`` [m]: the nut's start position a (as ``DriveSystem``); ``table_speed``,
    ``nut_speed`` [m/s]: start values of the speed-reference inputs; ``fmi``: 2 or 3;
    ``kind``: ``"cs"`` (co-simulation, the FMU integrates with its own DOPRI5, sampled loops
    as exact events inside a step) or ``"me"`` (model exchange: derivatives, sampled loops as
    time events).  Raises :class:`~feeddrive.parameters.ParameterError` on a bad request
    (before any work) and ``CompilerNotFound`` without a C compiler.

    Parameters
    ----------
    parameters : DriveParameters
        The parameter set [SI].
    drive : str
        The drive name.
    out : str or os.PathLike
        The ``.fmu`` file.
    table_position : float, default 0.4
        The nut's start position a [m].
    nut_hold : str, default "locked"
        How the CDFS holds its nut.
    fmi : int, default 2
        FMI version, 2 or 3.
    kind : str, default "cs"
        ``"cs"`` or ``"me"``.
    table_speed : float, default 0.0
        Start value of the table-speed input [m/s].
    nut_speed : float, default 0.0
        Start value of the nut-speed input [m/s].
    force : bool, default False
        Replace an existing file.
    identifier : str, optional
        The model identifier; derived from the drive by default.

    Returns
    -------
    ExportedFmu
        What was written.

    References
    ----------
    .. [1] Modelica Association, Functional Mock-up Interface 2.0.4 and 3.0,
       https://fmi-standard.org/.
    """
    from .build import package, provenance
    from .description import new_token, variables
    from .model import build

    path = check_request(drive, fmi, kind, out, force=force)
    fm = build(parameters, drive, table_position, nut_hold, table_speed, nut_speed)
    vs = variables(fm, kind)
    ident = identifier or f"feeddrive_{drive.replace('-', '_')}"
    text = (f"feeddrive {drive} drive ({parameters.name}), a = {table_position:g} m; "
            f"reference and load force as inputs")
    package(path, fm, vs, fmi=fmi, kind=kind, identifier=ident, token=new_token(),
            description=text, provenance=provenance())
    sampled = any(v > 0 for v in fm.periods.values())
    return ExportedFmu(
        path=path, fmi=fmi, kind=kind, identifier=ident, n_variables=len(vs),
        n_states=len(fm.model.states), inputs=tuple(v.name for v in vs if v.causality == "input"),
        outputs=tuple(v.name for v in vs if v.causality == "output"),
        size_bytes=path.stat().st_size, sampled=sampled)


__all__ = ["ExportedFmu", "export_fmu", "check_request", "FMI_VERSIONS", "KINDS"]
