"""The integrator settings every simulating command takes: ``--rtol``, the absolute
tolerances, ``--accuracy``, ``--rosenbrock`` (:mod:`feeddrive.engine.options`), layered over a
parameter file's ``[solver]`` table."""

from __future__ import annotations

import functools
import inspect
import math
from collections.abc import Callable
from typing import Any, TypeVar

import typer

from ..engine import options as opt
from ..parameters import ParameterError

F = TypeVar("F", bound=Callable[..., Any])

#: the states whose error rtol does not weigh, in words: the kinds outside feeddrive.model.
#: codegen's RELATIVE_KINDS (the model is not imported for --help;
#: tests/integration/test_cli_simulate_s18.py checks these words against it)
RTOL_WEIGHS_NOT = "positions, angles, loop integrals and friction deflections"


#: the absolute tolerances the command line takes in engineering units, as its other lengths
#: and speeds: field → (unit, SI per unit); a parameter file's ``[solver]`` table and the API
#: take SI (an outside check, 2026-12-06: ``--speed-tolerance 0.001`` was 1 mm/s)
CLI_UNITS = {"position_tolerance": ("mm", 1e-3), "speed_tolerance": ("mm/s", 1e-3)}


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
            "naming the time reached.")


#: (parameter, option, help) of the settings added to a command; the numbers are the engine's
#: (feeddrive.engine.options)
OPTIONS = (
    ("rtol", "--rtol", f"Relative tolerance of the integrator [-] (default "
     f"{opt.DEFAULT_RTOL:g} × --accuracy; {opt.MIN_RELATIVE:g} … {opt.MAX_RTOL:g}). It weighs "
     f"only speeds and currents ({RTOL_WEIGHS_NOT} have absolute tolerances only), and at the "
     f"defaults a speed's absolute tolerance ({opt.SPEED_FRACTION:g} × the speed scale) is "
     f"{opt.SPEED_FRACTION / opt.DEFAULT_RTOL:g}× rtol × the commanded speed: --rtol alone "
     "barely changes a run; --accuracy tightens every tolerance."),
    ("position_tolerance", "--position-tolerance",
     f"Absolute tolerance of positions [mm] (default: scaled with the run, "
     f"{opt.POSITION_TIME:g} s × the speed scale, × --accuracy; docs/model.md; "
     f"{_range('position_tolerance')})."),
    ("speed_tolerance", "--speed-tolerance",
     f"Absolute tolerance of speeds [mm/s] (default: {opt.SPEED_FRACTION:g} × the speed "
     f"scale × --accuracy; {_range('speed_tolerance')})."),
    ("current_tolerance", "--current-tolerance",
     f"Absolute tolerance of currents [A] (default: {opt.CURRENT_FRACTION:g} × the current "
     f"limit, or × 1 A, × --accuracy; {_range('current_tolerance')})."),
    ("accuracy", "--accuracy",
     f"Factor on every default tolerance [-] (0.1: ten times tighter; "
     f"{opt.MIN_RELATIVE / opt.DEFAULT_RTOL:g} … {opt.MAX_ACCURACY:g}); not with an explicit "
     "tolerance."),
    ("rosenbrock", "--rosenbrock",
     f"The Rosenbrock method of modal and auto where the run is stiff: "
     f"{' or '.join(opt.ROSENBROCKS)} (default {opt.DEFAULT_ROSENBROCK}; docs/model.md)."),
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
            options = solver_options(cli, kwargs.get("params_file"))
            with opt.using(options):
                return fn(*args, solver=options, **kwargs)

        wrapper.__signature__ = sig.replace(  # type: ignore[attr-defined]
            parameters=[*kept, *added])
        return wrapper  # type: ignore[return-value]

    return decorate


#: Add the integrator settings (:data:`OPTIONS`) to a command.  Before the command's body runs,
#: the settings are merged over the ``[solver]`` table of its ``--params`` file
#: (:func:`solver_options`) and checked (a bad value is refused before any work); the body runs
#: with them in force (:func:`feeddrive.engine.options.using`: every run it starts takes them,
#: in this process and in the workers of a sweep, fit or prediction), and receives them as its
#: parameter ``solver``.
accuracy_options = _settings_options(OPTIONS)
#: the same without ``--rosenbrock``: ``export fmu`` (the FMU's embedded solver is DOPRI5)
tolerance_options = _settings_options(tuple(o for o in OPTIONS if o[0] not in _TEXT))


def solver_options(cli: dict[str, tuple[Any, str]], params_file: str | None = None) -> Any:
    """The options of a command's runs: the defaults, under a parameter file's ``[solver]``
    table, under the command line (:func:`feeddrive.engine.options.layered`); refused when a
    value is out of range or ``--accuracy`` comes with a tolerance in one setting.

    Parameters
    ----------
    cli : dict
        ``{name: (value, option)}`` of the command line (value None: not given).
    params_file : str or None, default None
        The parameter file given with ``--params``.

    Returns
    -------
    SolverOptions
        The merged options, each setting's source recorded.
    """
    layers: list[tuple[str, dict[str, Any]]] = []
    if params_file:
        layers.append((f"[solver] in {params_file}", opt.file_settings(params_file)))
    layers.append(("command line", cli))
    return opt.layered(layers)
