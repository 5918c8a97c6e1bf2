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
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from ..parameters import DriveParameters, ParameterError

if TYPE_CHECKING:
    from ..engine.options import SolverOptions
    from ..machine import Machine

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
    binaries : tuple of str
        The ``binaries/`` folders written (one per platform).
    not_taken : tuple of str
        The integrator settings given that the FMU does not take (:func:`settings_not_taken`).
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
    binaries: tuple[str, ...] = ()
    #: the integrator settings given that the FMU does not take (:func:`settings_not_taken`)
    not_taken: tuple[str, ...] = ()


def check_request(drive: str | None, fmi: int, kind: str, out: str | os.PathLike[str], *,
                  force: bool = False, inputs: tuple[str | None, ...] = (),
                  option: str = "--out", platforms: str | tuple[str, ...] | None = None
                  ) -> tuple[Path, tuple[str, ...] | None]:
    """Refuse a request that cannot succeed, before any work: unknown drive, FMI version or
    kind, an output that is not a writable new ``.fmu`` file (an existing one only with
    ``force``; never one of ``inputs``), an unknown platform or one without a C compiler on
    this machine.  One-line errors name what to change.

    Parameters
    ----------
    drive : str or None
        The drive name (None: a machine, whose axes name theirs).
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
    platforms : str or tuple of str, optional
        Platforms to build a binary for (``"linux64,win64"`` or a tuple; names of
        ``feeddrive.fmu.platforms.PLATFORMS``); None: this machine's.

    Returns
    -------
    path : Path
        The output path.
    platforms : tuple of str or None
        The platforms, parsed (None: this machine's).

    Raises
    ------
    ParameterError
        For an unknown drive, FMI version or kind.
    OutputError
        For an output that cannot be written.
    ValueError
        Without a C compiler for a platform (the compiler search's message).
    """
    from ..io.outputs import check_output_file
    from ..model.mechanisms import drive_names
    from .platforms import PLATFORMS, CompilerNotFound, find_compiler, platform_compiler

    if drive is not None and drive not in drive_names():
        raise ParameterError("--drive", drive, f"expected one of {', '.join(drive_names())}")
    if fmi not in FMI_VERSIONS:
        raise ParameterError("--fmi", fmi, "expected 2 or 3 (FMI 2.0 or 3.0)")
    if kind not in KINDS:
        raise ParameterError("--kind", kind,
                             "expected cs (co-simulation) or me (model exchange)")
    if Path(out).suffix.lower() != ".fmu":
        raise ParameterError(option, os.fspath(out), "expected a file name ending in .fmu")
    names: tuple[str, ...] | None = None
    if platforms is not None:
        given = platforms.split(",") if isinstance(platforms, str) else list(platforms)
        names = tuple(dict.fromkeys(n.strip() for n in given))
        bad = [n for n in names if n not in PLATFORMS]
        if bad or not names:
            raise ParameterError("--platform", ",".join(given),
                                 f"expected a comma-separated list of {', '.join(PLATFORMS)}")
    path = check_output_file(out, option=option, inputs=inputs, force=force)
    try:
        if names is None:
            find_compiler()
        for name in names or ():
            platform_compiler(name)
    except CompilerNotFound as err:
        where = "" if names is None else "--platform: "
        raise ValueError(f"{where}{err}") from None
    return path, names


#: the speed scale of an export whose start speeds are both 0 [m/s] (1 mm/s): the FMU's inputs
#: may change at run time, so its tolerances are set for a typical feed speed, not the floor
FMU_SPEED_SCALE = 1e-3


def solver_starts(parameters: DriveParameters, table_speed: float, nut_speed: float,
                  options: SolverOptions | None = None) -> dict[str, float]:
    """The start values of the FMU's solver settings: the tolerances of ``options`` (None:
    those in force) over the set's ``[solver]`` table, as a run of the set takes them
    (:func:`feeddrive.engine.simulate.run_options`), resolved as
    :mod:`feeddrive.engine.options` does for a run at the export's start speeds.  The embedded
    DOPRI5 has one position and one speed tolerance for every state (the friction deflections
    take the position tolerance): the tighter of the table's and the motors' is taken.

    Parameters
    ----------
    parameters : DriveParameters
        The exported set (its current limit).
    table_speed, nut_speed : float
        The start values of the speed inputs [m/s].
    options : SolverOptions or None, default None
        The integrator settings.

    Returns
    -------
    dict
        ``solver.relative_tolerance`` [-], ``solver.position_tolerance`` [m],
        ``solver.speed_tolerance`` [m/s], ``solver.current_tolerance`` [A].

    Raises
    ------
    ParameterError
        For a speed that is not a finite number within ``units.LARGEST_SPEED``
        (:func:`~feeddrive.parameters.validation.check_speed`).
    """
    from ..engine import options as opt
    from ..engine.simulate import run_options
    from ..parameters.validation import check_speed

    # NaN tolerances were returned for a NaN speed, a str failed in abs() (session 27)
    table_speed = check_speed("table_speed", table_speed, sign="any")
    nut_speed = check_speed("nut_speed", nut_speed, sign="any")
    options = run_options(parameters, options)
    table = abs(table_speed) or FMU_SPEED_SCALE
    limit = float(parameters.controller.current_limit)
    scales = opt.RunScales(speed=max(abs(table_speed) + abs(nut_speed), table),
                           table_speed=table,
                           current=limit if 0.0 < limit < opt.NO_CURRENT_LIMIT else 1.0)
    tol = options.resolve(scales)
    starts = {"solver.relative_tolerance": tol.rtol,
              "solver.position_tolerance": min(tol.position, tol.motor_position),
              "solver.speed_tolerance": min(tol.speed, tol.motor_speed),
              "solver.current_tolerance": tol.current}
    if options.source("max_step") != "default" and options.max_step is not None:
        starts["solver.max_step"] = float(options.max_step)  # the embedded DOPRI5's step cap
    return starts


#: the integrator settings an FMU has no counterpart for: its embedded solver is DOPRI5 (a
#: model-exchange FMU's importer integrates), its outputs are at the importer's communication
#: points, its step limit per call is ``solver.max_steps_per_call``
NOT_TAKEN = ("method", "rosenbrock", "output_interval", "max_steps")


def settings_not_taken(parameters: DriveParameters,
                       options: SolverOptions | None = None) -> tuple[str, ...]:
    """The integrator settings given (by the command line, the API or the set's ``[solver]``
    table) that an exported FMU does not take (:data:`NOT_TAKEN`; ``method = "dopri5"`` is
    its own), each as ``name = value (where)``, for the export to say so.

    Parameters
    ----------
    parameters : DriveParameters
        The exported set (its ``[solver]`` table).
    options : SolverOptions or None, default None
        The integrator settings (None: those in force).

    Returns
    -------
    tuple of str
        E.g. ``("method = rodas4 ([solver] in run.toml)",)``; empty when every setting given
        is taken.
    """
    from ..engine.simulate import run_options

    merged = run_options(parameters, options)
    out = []
    for name in NOT_TAKEN:
        where = merged.source(name)
        value = getattr(merged, name)
        if where == "default" or (name == "method" and value == "dopri5"):
            continue
        out.append(f"{name} = {value} ({where})")
    return tuple(out)


def export_fmu(parameters: DriveParameters, drive: str, out: str | os.PathLike[str], *,
               table_position: float = 0.4, nut_hold: str = "locked", fmi: int = 2,
               kind: str = "cs", table_speed: float = 0.0, nut_speed: float = 0.0,
               force: bool = False, identifier: str | None = None,
               platforms: str | tuple[str, ...] | None = None,
               options: SolverOptions | None = None) -> ExportedFmu:
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
    platforms : str or tuple of str, optional
        Platforms to build a binary for, each with a compiler found for it
        (``"linux64,win64"``; ``feeddrive.fmu.platforms.PLATFORMS``); None: this machine's.
    options : SolverOptions or None, default None
        The integrator settings (None: those in force, :func:`feeddrive.engine.options.current`):
        the start values of the embedded solver's tunable tolerances, resolved for the start
        speeds (or, when both are 0, for :data:`FMU_SPEED_SCALE`) as a run of ``simulate``
        would (:func:`solver_starts`).

    Returns
    -------
    ExportedFmu
        What was written.

    References
    ----------
    .. [1] Modelica Association, Functional Mock-up Interface 2.0.4 and 3.0,
       https://fmi-standard.org/.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import feeddrive as fd
    >>> from feeddrive.fmu import export_fmu
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     fmu = export_fmu(fd.preset("wang2021"), "cdfs", pathlib.Path(folder) / "cdfs.fmu")
    >>> print(fmu.fmi, fmu.kind, fmu.n_states, fmu.inputs[1])
    2 cs 15 table_speed_reference
    """
    from .build import package, provenance
    from .description import new_token, variables
    from .model import build

    path, names = check_request(drive, fmi, kind, out, force=force, platforms=platforms)
    fm = replace(build(parameters, drive, table_position, nut_hold, table_speed, nut_speed),
                 solver_starts=solver_starts(parameters, table_speed, nut_speed, options))
    vs = variables(fm, kind)
    ident = identifier or f"feeddrive_{drive.replace('-', '_')}"
    text = (f"feeddrive {drive} drive ({parameters.name}), a = {table_position:g} m; "
            f"reference and load force as inputs")
    package(path, fm, vs, fmi=fmi, kind=kind, identifier=ident, token=new_token(),
            description=text, provenance=provenance(), platforms=names)
    sampled = any(v > 0 for v in fm.periods.values())
    return ExportedFmu(
        path=path, fmi=fmi, kind=kind, identifier=ident, n_variables=len(vs),
        n_states=len(fm.model.states), inputs=tuple(v.name for v in vs if v.causality == "input"),
        outputs=tuple(v.name for v in vs if v.causality == "output"),
        size_bytes=path.stat().st_size, sampled=sampled, binaries=_binaries(path),
        not_taken=settings_not_taken(parameters, options))


def export_machine_fmu(machine: Machine, out: str | os.PathLike[str], *, fmi: int = 2,
                       kind: str = "cs", force: bool = False, identifier: str | None = None,
                       platforms: str | tuple[str, ...] | None = None,
                       options: SolverOptions | None = None,
                       inputs: tuple[str | None, ...] = ()) -> ExportedFmu:
    """Write a machine of axes as one FMU (co-simulation or model exchange) to ``out``.

    Each axis has the inputs, outputs, parameters and loop-period settings of its
    single-drive FMU, named ``<axis>.<name>`` (its load force acts from t = 0); the coupling
    parts' states and written signals are outputs, their parameters fixed at export
    (:mod:`feeddrive.fmu.machine`).  Model exchange adds every continuous state's rate and
    the directional derivatives of the machine's right-hand side.

    Parameters
    ----------
    machine : Machine
        The machine (:func:`feeddrive.machine.load_machine`).
    out : str or os.PathLike
        The ``.fmu`` file.
    fmi : int, default 2
        FMI version, 2 or 3.
    kind : str, default "cs"
        ``"cs"`` (co-simulation) or ``"me"`` (model exchange), as :func:`export_fmu`.
    force : bool, default False
        Replace an existing file.
    identifier : str, optional
        The model identifier; derived from the machine's name by default.
    platforms : str or tuple of str, optional
        As :func:`export_fmu`.
    options : SolverOptions or None, default None
        The integrator settings whose tolerances start the embedded solver's (as
        :func:`export_fmu`, resolved with the first axis' parameter set).
    inputs : tuple of (str or None), default ()
        Files the command reads, which ``out`` may never replace.

    Returns
    -------
    ExportedFmu
        What was written.

    Raises
    ------
    ParameterError
        For a bad request, before any work.
    """
    import re

    from .build import package, provenance
    from .description import new_token
    from .machine import build_machine, machine_variables

    path, names = check_request(None, fmi, kind, out, force=force, platforms=platforms,
                                inputs=inputs)
    fm, axes = build_machine(machine)
    fm = replace(fm, solver_starts=solver_starts(fm.parameters, 0.0, 0.0, options))
    vs = machine_variables(fm, axes, kind)
    ident = identifier or "feeddrive_" + re.sub(r"\W", "_", machine.name)
    text = (f"feeddrive machine {machine.name}: axes "
            + ", ".join(f"{ax.name} ({ax.drive}, {ax.parameters.name})" for ax in machine.axes)
            + "; each axis' reference and load force as inputs")
    package(path, fm, vs, fmi=fmi, kind=kind, identifier=ident, token=new_token(),
            description=text, provenance=provenance(), platforms=names)
    return ExportedFmu(
        path=path, fmi=fmi, kind=kind, identifier=ident, n_variables=len(vs),
        n_states=len(fm.model.states), inputs=tuple(v.name for v in vs if v.causality == "input"),
        outputs=tuple(v.name for v in vs if v.causality == "output"),
        size_bytes=path.stat().st_size, sampled=any(v > 0 for v in fm.periods.values()),
        binaries=_binaries(path), not_taken=settings_not_taken(fm.parameters, options))


def _binaries(path: Path) -> tuple[str, ...]:
    import zipfile

    with zipfile.ZipFile(path) as zf:
        return tuple(sorted({n.split("/")[1] for n in zf.namelist()
                             if n.startswith("binaries/") and n.count("/") >= 2}))


__all__ = ["ExportedFmu", "NOT_TAKEN", "export_fmu", "export_machine_fmu", "check_request",
           "settings_not_taken", "solver_starts",
           "FMI_VERSIONS", "KINDS",
           "FMU_SPEED_SCALE"]
