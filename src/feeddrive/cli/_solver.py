"""The integrator settings every simulating command takes: ``--rtol``, the absolute
tolerances, ``--accuracy``, ``--rosenbrock`` (:mod:`feeddrive.engine.options`), layered over the
``[solver]`` tables of the command's files: its parameter file (``--params``, or the positional
``FIT.toml`` of ``predict``, ``validate`` and ``sensitivity``) and a sweep configuration's
(its ``params`` file's table, then its own)."""

from __future__ import annotations

import dataclasses
import functools
import inspect
import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, TypeVar

import typer

from ..engine import options as opt
from ..parameters import ParameterError, toml_io
from ..parameters.components import SOLVER_TOLERANCES, solver_over, solver_table

F = TypeVar("F", bound=Callable[..., Any])

#: the states whose error rtol does not weigh, in words: the kinds outside feeddrive.model.
#: codegen's RELATIVE_KINDS (the model is not imported for --help;
#: tests/integration/test_cli_simulate_s18.py checks these words against it)
RTOL_WEIGHS_NOT = "positions, angles, loop integrals and friction deflections"


#: the absolute tolerances the command line takes in engineering units, as its other lengths
#: and speeds: field → (unit, SI per unit), from the one table of the command line's units
#: (:data:`feeddrive.engine.options.CLI_UNITS`); a parameter file's ``[solver]`` table and the
#: API take SI (an outside check, 2026-12-06: ``--speed-tolerance 0.001`` was 1 mm/s)
CLI_UNITS = {name: (unit, 1.0 / per) for name, (unit, per) in opt.CLI_UNITS.items()
             if unit in ("mm", "mm/s")}


def _limits(name: str) -> tuple[float, float]:
    """The range an explicit absolute tolerance takes (``opt.MIN_ABSOLUTE`` …
    ``opt.MAX_ABSOLUTE``) in the command line's unit."""
    per = CLI_UNITS.get(name, ("A", 1.0))[1]
    return opt.MIN_ABSOLUTE[name] / per, opt.MAX_ABSOLUTE[name] / per


def _range(name: str) -> str:
    """:func:`_limits` for the option's help."""
    low, high = _limits(name)
    return f"at least {low:g}, at most {high:g}"


def _to_si(cli: dict[str, tuple[Any, str]]) -> dict[str, tuple[Any, str]]:
    """The command line's absolute tolerances checked in its units (a bad one refused naming
    the option, the value and the range in the unit typed) and converted to SI."""
    out = dict(cli)
    for name, (unit, per) in CLI_UNITS.items():
        value, flag = cli.get(name, (None, ""))
        if value is None:
            continue
        low, high = _limits(name)
        if not (math.isfinite(value) and low <= value <= high):
            raise ParameterError(flag, value, f"expected a finite value {low:g} … {high:g} "
                                              f"[{unit}]")
        out[name] = (min(max(value * per, opt.MIN_ABSOLUTE[name]), opt.MAX_ABSOLUTE[name]),
                     flag)
    return out


def _default(name: str) -> Any:
    """The default of :class:`feeddrive.SolverOptions`' field ``name``."""
    return next(f.default for f in dataclasses.fields(opt.SolverOptions) if f.name == name)


#: the default accuracy factor and step limit (:class:`feeddrive.SolverOptions`' fields): the
#: options have no default of their own, so that a parameter file's ``[solver]`` table holds
#: where they are not given (an outside check, 2026-12-06: a fixed ``--max-steps`` default
#: replaced the file's ``max_steps``)
DEFAULT_ACCURACY = _default("accuracy")
DEFAULT_MAX_STEPS = _default("max_steps")


def max_steps_help(probe: bool = False) -> str:
    """``--max-steps``' help: what is checked before a run starts (its duration over the
    largest step, :func:`feeddrive.engine.budget.run_budget`: dopri5's step bound; the dense
    methods have none unless a ``[solver]`` table sets ``max_step``; with ``probe``, dopri5's
    projection from its first steps, ``engine.simulate._check_step_rate``), and that otherwise
    a run stops at the limit.  Tested against the budget's behaviour
    (tests/integration/test_cli_simulate_s18.py).

    Parameters
    ----------
    probe : bool, default False
        Whether the command's dopri5 runs are probed first (a drive's ``simulate``).

    Returns
    -------
    str
        The help text.
    """
    from ..engine.budget import PROBE_TIME, STEP_MARGIN

    probed = (f", and a dopri5 run longer than {4 * PROBE_TIME:g} s is refused when the steps "
              f"projected from its first {PROBE_TIME:g} s, × {STEP_MARGIN:g}, exceed it"
              if probe else "")
    return ("Solver step limit per run [-]. Checked before the start: the run's duration over "
            f"the largest step (dopri5: {1e3 * opt.DOPRI5_STEP:g} ms at --accuracy 1; the other "
            "methods have none unless the --params file's [solver] sets max_step) may not "
            f"exceed it{probed}. Otherwise a run that reaches it stops there with an error "
            "naming the time reached. Default: the parameter file's [solver] max_steps, else "
            f"{f'{DEFAULT_MAX_STEPS:,}'.replace(',', ' ')}.")


def file_default(name: str, unit: str = "") -> str:
    """How an option's help opens its default: the ``[solver]`` table's setting ``name``
    first (precedence: the command line, the file, the default; a sweep's: its
    configuration's table over its ``params`` file's), as ``--method``'s help says it.

    Parameters
    ----------
    name : str
        The setting (a key of the ``[solver]`` table).
    unit : str, default ""
        The table's unit where it differs from the option's (the table takes SI: ``"m"``
        for ``position_tolerance``, which the option takes in mm).

    Returns
    -------
    str
        ``"default: the parameter file's [solver] NAME [UNIT], else "``, the default to follow.
    """
    return f"default: the parameter file's [solver] {name}{f' [{unit}]' if unit else ''}, else "



#: (parameter, option, help) of the settings added to a command; the numbers are the engine's
#: (feeddrive.engine.options), each default after the parameter file's [solver] setting
OPTIONS = (
    ("rtol", "--rtol", f"Relative tolerance of the integrator [-] ({file_default('rtol')}"
     f"{opt.DEFAULT_RTOL:g} × --accuracy; {opt.MIN_RELATIVE:g} … {opt.MAX_RTOL:g}). It weighs "
     f"only speeds and currents ({RTOL_WEIGHS_NOT} have absolute tolerances only), and at the "
     f"defaults a speed's absolute tolerance ({opt.SPEED_FRACTION:g} × the speed scale) is "
     f"{opt.SPEED_FRACTION / opt.DEFAULT_RTOL:g}× rtol × the commanded speed: --rtol alone "
     "barely changes a run; --accuracy tightens every tolerance."),
    ("position_tolerance", "--position-tolerance",
     f"Absolute tolerance of positions [mm] ({file_default('position_tolerance', 'm')}"
     f"scaled with the run, {opt.POSITION_TIME:g} s × the speed scale, × --accuracy; "
     f"docs/model.md; {_range('position_tolerance')})."),
    ("speed_tolerance", "--speed-tolerance",
     f"Absolute tolerance of speeds [mm/s] ({file_default('speed_tolerance', 'm/s')}"
     f"{opt.SPEED_FRACTION:g} × the speed scale × --accuracy; {_range('speed_tolerance')})."),
    ("current_tolerance", "--current-tolerance",
     f"Absolute tolerance of currents [A] ({file_default('current_tolerance')}"
     f"{opt.CURRENT_FRACTION:g} × the current limit, or × 1 A, × --accuracy; "
     f"{_range('current_tolerance')})."),
    ("accuracy", "--accuracy",
     f"Factor on every default tolerance [-] (0.1: ten times tighter; "
     f"{file_default('accuracy')}{DEFAULT_ACCURACY:g}; "
     f"{opt.MIN_RELATIVE / opt.DEFAULT_RTOL:g} … {opt.MAX_ACCURACY:g}); not with an explicit "
     "tolerance."),
    ("rosenbrock", "--rosenbrock",
     f"The Rosenbrock method of modal and auto where the run is stiff: "
     f"{' or '.join(opt.ROSENBROCKS)} ({file_default('rosenbrock')}"
     f"{opt.DEFAULT_ROSENBROCK}; docs/model.md)."),
)
#: the settings that are not numbers
_TEXT = ("rosenbrock",)


def _settings_options(settings: tuple[tuple[str, str, str], ...]) -> Callable[[F], F]:
    """The decorator adding ``settings`` (entries of :data:`OPTIONS`) to a command
    (:func:`accuracy_options`)."""

    def decorate(fn: F) -> F:
        # annotations evaluated: a string "Annotated[..., typer.Option(...)]" in the
        # signature given to typer would lose its option (the --free, --weight and --signal
        # help texts did)
        sig = inspect.signature(fn, eval_str=True)
        kept = [p for p in sig.parameters.values() if p.name != "solver"]
        added = [inspect.Parameter(
            name, inspect.Parameter.KEYWORD_ONLY,
            default=typer.Option(None, flag, help=text,
                                 metavar="|".join(opt.ROSENBROCKS) if name in _TEXT else None),
            annotation=str | None if name in _TEXT else float | None)
            for name, flag, text in settings]

        @functools.wraps(fn)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            cli = _to_si({name: (kwargs.pop(name, None), flag) for name, flag, _ in settings})
            tables = command_tables(kwargs)
            options = solver_options(cli, tables=tables)
            # the sets of the command's files carry their tables as they stand under the
            # command line (toml_io.tables_applied): a worker process takes the same settings
            with opt.using(options), toml_io.tables_applied(carried_tables(options, tables)):
                return fn(*args, solver=options, **kwargs)

        wrapper.__signature__ = sig.replace(  # type: ignore[attr-defined]
            parameters=[*kept, *added])
        return wrapper  # type: ignore[return-value]

    return decorate


#: Add the integrator settings (:data:`OPTIONS`) to a command.  Before the command's body runs,
#: the settings are merged over the ``[solver]`` tables of its files (:func:`command_tables`,
#: :func:`solver_options`) and checked (a bad value is refused before any work); the body runs
#: with them in force (:func:`feeddrive.engine.options.using`: every run it starts takes them,
#: in this process and in the workers of a sweep, fit or prediction), the sets it loads from
#: those files carrying their tables as they stand under the command line
#: (:func:`carried_tables`), and receives them as its parameter ``solver``.
accuracy_options = _settings_options(OPTIONS)
#: the same without ``--rosenbrock``: ``export fmu`` (the FMU's embedded solver is DOPRI5)
tolerance_options = _settings_options(tuple(o for o in OPTIONS if o[0] not in _TEXT))


#: the command parameters that name a parameter file, in order of preference: ``--params``,
#: the positional ``FIT.toml`` of ``predict``, ``validate`` and ``sensitivity`` ("the same as
#: --params")
PARAMETER_FILES = ("params_file", "fit_file")
#: the command parameter that names a sweep configuration (``feeddrive sweep CONFIG``)
SWEEP_CONFIG = "config"


class FileTable:
    """A ``[solver]`` table of one of a command's files.

    Parameters
    ----------
    path : str
        The file, as the command was given it (or as a sweep configuration names it).
    settings : dict
        The table's settings (:func:`feeddrive.engine.options.file_settings`) [SI].
    carrier : bool
        Whether the command loads a parameter set from the file (its ``--params`` or
        ``FIT.toml``, a sweep's ``params``): that set carries the tables.
    """

    def __init__(self, path: str, settings: dict[str, Any], carrier: bool) -> None:
        self.path, self.settings, self.carrier = path, settings, carrier

    @property
    def source(self) -> str:
        """The settings' source, as :meth:`feeddrive.SolverOptions.describe` names it."""
        return f"[solver] in {self.path}"


def command_tables(kwargs: Mapping[str, Any]) -> list[FileTable]:
    """The ``[solver]`` tables of a command's files, lowest precedence first: its parameter
    file (``--params``, or the positional ``FIT.toml``), or a sweep configuration's
    ``params`` file and then the configuration's own table.

    Parameters
    ----------
    kwargs : mapping
        The command's arguments.

    Returns
    -------
    list of FileTable
        The tables (a file without one gives an empty table).

    Raises
    ------
    ParameterError
        For a table that is not a table, names an unknown setting, has a value of the wrong
        kind or ``accuracy`` with a tolerance: read as :func:`feeddrive.parameters.load` reads
        it (:func:`feeddrive.engine.options.file_settings`), in the same words.
    """
    tables: list[FileTable] = []
    named = next((kwargs[k] for k in PARAMETER_FILES if kwargs.get(k)), None)
    if named:
        tables.append(FileTable(str(named), opt.file_settings(named), carrier=True))
    config = kwargs.get(SWEEP_CONFIG)
    if isinstance(config, str) and Path(config).is_file():
        try:
            data = toml_io.read_toml_file(config)
        except ParameterError:
            return tables  # not a configuration the command reads: it says so itself
        base = data.get("params")
        if isinstance(base, str) and base.endswith(".toml"):
            path = base if Path(base).is_absolute() else str(Path(config).parent / base)
            if Path(path).is_file():  # else the command refuses it, naming the key
                tables.append(FileTable(path, opt.file_settings(path), carrier=True))
        tables.append(FileTable(config, opt.file_settings(config), carrier=False))
    return tables


def file_table(path: str | Path | None) -> tuple[tuple[str, Any, str], ...]:
    """Parameter file ``path``'s own ``[solver]`` table as read, what a parameter file a
    command writes from it carries (``calibrate --out``): the command line's settings are
    one-off, never saved, whatever the set loaded under the command
    (:func:`carried_tables`) carries.

    Parameters
    ----------
    path : str, pathlib.Path or None
        The file (None: none, as a preset: no table).

    Returns
    -------
    tuple of (str, object, str)
        (setting, value, source) triples
        (:func:`~feeddrive.parameters.components.solver_table`), empty without a table.

    Raises
    ------
    ParameterError
        As :func:`feeddrive.engine.options.file_settings`.
    """
    if path is None:
        return ()
    settings = opt.file_settings(path)
    return solver_table(settings, f"[solver] in {path}") if settings else ()


def solver_options(cli: dict[str, tuple[Any, str]], params_file: str | None = None, *,
                   tables: list[FileTable] | None = None) -> Any:
    """The options of a command's runs: the defaults, under its files' ``[solver]`` tables,
    under the command line (:func:`feeddrive.engine.options.layered`); refused when a
    value is out of range or ``--accuracy`` comes with a tolerance in one setting.

    Parameters
    ----------
    cli : dict
        ``{name: (value, option)}`` of the command line (value None: not given).
    params_file : str or None, default None
        A parameter file (``--params``) whose table is layered under the command line.
    tables : list of FileTable or None, default None
        The command's tables, lowest first (:func:`command_tables`), over ``params_file``'s.

    Returns
    -------
    SolverOptions
        The merged options, each setting's source recorded.

    Raises
    ------
    ParameterError
        For a refused value, ``--accuracy`` with a tolerance in one setting, or a sweep
        configuration's tolerances over its parameter file's ``accuracy``
        (:func:`feeddrive.parameters.components.solver_over`: one table cannot carry both).
    """
    files = list(tables or [])
    if params_file:
        files.insert(0, FileTable(params_file, opt.file_settings(params_file), carrier=True))
    layers: list[tuple[str, dict[str, Any]]] = [(t.source, t.settings) for t in files]
    layers.append(("command line", cli))
    options = opt.layered(layers)
    _merged(files)  # as a set carries them: refused where one table cannot hold them
    return options


def _merged(files: list[FileTable]) -> tuple[tuple[str, Any, str], ...]:
    """The files' tables merged, each over the ones before it
    (:func:`~feeddrive.parameters.components.solver_over`)."""
    merged: tuple[tuple[str, Any, str], ...] = ()
    for t in files:
        merged = solver_over(merged, solver_table(t.settings, t.source))
    return merged


def carried_tables(options: Any, tables: list[FileTable]) -> dict[str | Path, Any]:
    """The ``[solver]`` settings the sets of a command's files carry
    (:func:`feeddrive.parameters.toml_io.tables_applied`): each setting the files' tables
    give as merged (:func:`~feeddrive.parameters.components.solver_over`: a configuration's
    ``accuracy`` replaces its parameter file's tolerances), at its value in ``options`` (the
    command line's where it gives one, a value equal to the default included); the tables'
    tolerances that the command line's ``--accuracy`` replaced are left out and that accuracy
    carried instead.  A tolerance the command line gives over a table's ``accuracy`` is not
    carried (one table cannot hold both): the options' record holds it, as any explicit
    tolerance, and a worker takes it from there.  The set loaded from a carrier
    file carries them; a sweep configuration's own file, nothing more (its table is in them).

    A worker process reads the set from its TOML and the options from a record without
    their sources (:meth:`feeddrive.SolverOptions.from_record`): the set's settings layered
    under them then give the command's options again, where the files' own tables would let
    a file's ``accuracy = 0.01`` take back an ``--accuracy 1``.

    Parameters
    ----------
    options : SolverOptions
        The command's options (:func:`solver_options`).
    tables : list of FileTable
        The command's tables (:func:`command_tables`).

    Returns
    -------
    dict
        File → (setting, value, source) triples.
    """
    # the tables as merged: a tolerance of a parameter file that a sweep configuration's
    # accuracy replaced is not given (carried at the command line's value beside that
    # accuracy it made one table hold both, and `sweep --rtol` was refused)
    given = {name for name, _, _ in _merged(tables)}
    carried: list[tuple[str, Any, str]] = []
    from_cli = options.source("accuracy").startswith("--")
    for name in opt.SETTINGS:
        if name not in given:
            continue
        value = getattr(options, name)
        if name in SOLVER_TOLERANCES and value is None:
            continue  # replaced by a higher setting's accuracy (carried below)
        carried.append((name, value, options.source(name)))
    if from_cli and any(n in given for n in (*SOLVER_TOLERANCES, "accuracy")) and \
            all(n != "accuracy" for n, _, _ in carried):
        carried.append(("accuracy", options.accuracy, options.source("accuracy")))
    carried = [(n, v, s if s not in (opt.DEFAULT_SOURCE, opt.API_SOURCE) else "command line")
               for n, v, s in carried]
    triples = solver_table(carried, "") if carried else ()
    out: dict[str | Path, Any] = {t.path: triples if t.carrier else () for t in tables}
    return out
