"""Shared CLI plumbing: the Typer app, error reporting, unit conversion at the edge."""

from __future__ import annotations

import contextlib
import functools
import json
import os
import sys
from collections.abc import Callable, Iterator
from typing import Annotated, Any, TypeVar

import typer
from rich.console import Console

from .. import registry, units
from ..io.outputs import shown
from ..parameters import DriveParameters, ParameterError, load, preset
from ._usage import OneLineGroup

app = typer.Typer(
    cls=OneLineGroup,  # usage errors in one `error:` line (docs/outputs.md)
    no_args_is_help=True,
    add_completion=True,  # feeddrive --install-completion [bash|zsh|fish|powershell]
    rich_markup_mode=None,  # Rich markup would eat the units: "[mm/s]" (issue 12 item 1)
    help="feeddrive: low-speed simulation and analysis of ball-screw feed drives (Wang2021).",
)
#: the width rich lays tables out in when the output is not a terminal (a pipe, a file, a CI
#: log): wide enough that nothing is folded; plain text is never wrapped there (soft wrap)
PIPED_WIDTH = 1000


def _console(*, stderr: bool = False) -> Console:
    """A console that wraps for a terminal only: piped output is hard-wrapped at 80 columns
    otherwise, mid-phrase (issue 41 item 6)."""
    stream = sys.stderr if stderr else sys.stdout
    piped = not (hasattr(stream, "isatty") and stream.isatty())
    return Console(stderr=stderr, soft_wrap=piped, width=PIPED_WIDTH if piped else None)


console = _console()
err_console = _console(stderr=True)

F = TypeVar("F", bound=Callable[..., Any])

# unit conversion at the edge: the CLI speaks mm, mm/s and N/µm
MM, MM_PER_S, N_PER_UM = units.MM, units.MM_PER_S, units.N_PER_UM


#: exit status of a refused input or output destination (checked before any work)
EXIT_REFUSED = 2
#: exit status of work that could not finish: simulation failure, out of memory, I/O error
EXIT_FAILED = 1
#: exit status of a simulation that finished but diverged (verdict "unstable"); its summary
#: and outputs are still written
EXIT_UNSTABLE = 3

# the arguments that name files, in the order they are named in a message
_FILE_ARGUMENTS = ("config", "store", "file", "fragments", "params_file", "static", "out", "output",
                   "plot")
#: the arguments that name a command's inputs, which none of its outputs may replace
_INPUT_ARGUMENTS = ("traces", "file", "fragments", "config", "store", "fit_file",
                    "params_file", "profile_file", "static")
#: an output option that names a folder (``reproduce --out``)
FOLDER = "folder"
#: an output option that names a store a rerun resumes from: an existing one is reopened,
#: not replaced (``--store``)
STORE = "store"
_OUTPUTS = "feeddrive_outputs"


def outputs(**declared: tuple[str, ...] | str) -> Callable[[F], F]:
    """Declare a command's output options: the one output check (issue 39 item 4).

    :func:`user_errors` checks every declared option that is given before the command's body
    runs (:func:`~feeddrive.io.outputs.check_output_file`, or ``check_output_dir`` for a
    folder): its format, its length (and that of the temporary name it is written under),
    its folder, that it is no input of the command (:data:`_INPUT_ARGUMENTS`) and not the file
    of an output declared before it, an existing file only with ``--force``, that it can be
    written.

    Parameters
    ----------
    **declared : tuple of str or str
        Parameter name → the extensions it takes (``PLOT_FORMATS``), :data:`FOLDER` or
        :data:`STORE`; the option is ``--`` and the name (``_`` as ``-``).

    Returns
    -------
    callable
        The decorator; it records the declaration on the command function.
    """
    def declare(fn: F) -> F:
        fn.__dict__[_OUTPUTS] = dict(declared)
        return fn

    return declare


def declared_outputs(fn: Callable[..., Any]) -> dict[str, tuple[str, ...] | str]:
    """A command's output options as :func:`outputs` declared them, by option (``--plot``).

    Parameters
    ----------
    fn : callable
        The command function (or a wrapper of it: the declaration travels with
        ``functools.wraps``).

    Returns
    -------
    dict of str to (tuple of str or str)
        Option → formats, :data:`FOLDER` or :data:`STORE`.
    """
    return {f"--{name.replace('_', '-')}": kind
            for name, kind in getattr(fn, _OUTPUTS, {}).items()}


def _check_outputs(fn: Callable[..., Any], kwargs: dict[str, Any]) -> None:
    from ..io.outputs import OutputError, check_output_dir, check_output_file, is_same_file

    declared = getattr(fn, _OUTPUTS, {})
    inputs: list[Any] = []
    for name in _INPUT_ARGUMENTS:
        value = kwargs.get(name)
        if name not in declared and value is not None:
            inputs.extend(value if isinstance(value, list | tuple) else [value])
    written: dict[str, Any] = {}  # the outputs checked so far, by option
    for name, kind in declared.items():
        value = kwargs.get(name)
        if value is None:
            continue
        option = f"--{name.replace('_', '-')}"
        for other, path in written.items():  # two outputs of one run, one file
            if is_same_file(value, path):
                raise OutputError(f"{option} {shown(value)}: the same file as {other}; "
                                  "expected a file of its own")
        written[option] = value
        if kind == FOLDER:
            check_output_dir(value, option=option)
        elif kind == STORE:
            check_output_file(value, option=option, inputs=inputs, force=True, formats=None)
            from ..sweep.store import check_existing_store

            check_existing_store(value, option)  # before the work that would fill it
        else:
            check_output_file(value, option=option, inputs=inputs,
                              force=bool(kwargs.get("force", False)), formats=kind)


#: the longest a command's plain progress goes without a line when its output is not a
#: terminal [s] (issue 41 item 6: `reproduce` piped printed nothing for minutes)
PROGRESS_EVERY = 5.0


class PlainProgress:
    """Progress as plain lines, for output that is not a terminal (rich's live bar draws
    nothing there): a line at each change of stage and, while the work goes on without one,
    every :data:`PROGRESS_EVERY` seconds — ``reproduce: CDFS critical speed 3/14 (42 s)``.

    Parameters
    ----------
    what : str
        The command, first word of each line.
    say : callable
        Prints one line.
    every : float, optional
        The longest interval without a line [s].
    """

    def __init__(self, what: str, say: Callable[[str], None],
                 every: float | None = None) -> None:
        import threading
        import time

        self.what, self.say = what, say
        self.every = PROGRESS_EVERY if every is None else every
        self._clock = time.monotonic
        self._start = self._last = self._clock()
        self._state = ("starting", 0, 0)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._beat, name="feeddrive-progress",
                                        daemon=True)

    def _line(self) -> None:
        label, done, total = self._state
        count = f" {done}/{total}" if total else ""
        self.say(f"{self.what}: {label}{count} ({self._clock() - self._start:.0f} s)")
        self._last = self._clock()

    def _beat(self) -> None:
        while not self._stop.wait(max(0.0, self.every - (self._clock() - self._last))):
            with self._lock:
                if self._clock() - self._last >= self.every:
                    self._line()

    def update(self, label: str, done: int, total: int) -> None:
        """A new state of the work: printed when its stage changed, else at the next beat.

        Parameters
        ----------
        label : str
            The stage.
        done, total : int
            Work done of the stage's total (0 total: not counted).
        """
        with self._lock:
            changed = label != self._state[0]
            self._state = (label, done, total)
            if changed:
                self._line()

    def __enter__(self) -> PlainProgress:
        with self._lock:
            self._line()  # "starting": the command is at work from its first second
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()


def _one_line(text: str) -> str:
    """The message on one line: control characters (a newline in a file name) escaped."""
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii")
                   for c in text)


def _files_of(kwargs: dict[str, Any]) -> str:
    names: list[str] = []
    for key in _FILE_ARGUMENTS:
        value = kwargs.get(key)
        if isinstance(value, str | os.PathLike):
            names.append(os.fspath(value))
        elif isinstance(value, list | tuple):
            names.extend(os.fspath(v) for v in value)
    return ", ".join(shown(n) for n in names)


@contextlib.contextmanager
def run_outcome(bar: Any) -> Iterator[None]:
    """Around a run shown by :func:`progress_bar` (``bar`` None with ``--json``): a failed run
    ends the command with its one-line error (exit 1), an interrupted one with where it
    stopped (exit 130); the bar is stopped either way.  A drive's ``simulate`` and a
    machine's.

    Parameters
    ----------
    bar : rich.progress.Progress or None
        The run's bar.

    Yields
    ------
    None
        While the run goes on.
    """
    from ..engine.simulate import SimulationError, SimulationInterrupted

    try:
        yield
    except SimulationError as err:
        # the engine's advice names Python's field beside a table's and the option; a
        # command's user is told the last two
        message = str(err).replace("options.max_steps, ", "").replace(
            "options.max_steps", "--max-steps")
        err_console.print(f"error: {message}", markup=False, highlight=False, soft_wrap=True)
        raise typer.Exit(code=1) from None
    except SimulationInterrupted as stop:
        _stop_bar(bar)
        err_console.print(f"interrupted: {stop}", markup=False, highlight=False,
                          soft_wrap=True)
        raise interrupted() from None
    finally:
        _stop_bar(bar)


def _stop_bar(bar: Any) -> None:
    """Stop a :func:`progress_bar` that was started (rich writes a line end when it stops
    one, started or not: off a terminal that was a blank line on stderr)."""
    if bar is not None and bar.live.is_started:
        bar.stop()


def interrupted() -> typer.Exit:
    """The exit of a command stopped by Ctrl-C, once its message is printed: quick.

    The objects alive now are moved out of the garbage collector's reach (``gc.freeze``):
    the interpreter's exit then skips a last collection over numba's object graph, which took
    1.4–1.7 s of a Ctrl-C's time (measured: 0.2 s with the freeze).  Everything the command
    keeps is written and closed before this is called.
    """
    import gc

    sys.stdout.flush()
    sys.stderr.flush()
    gc.freeze()
    from ..exit_codes import INTERRUPTED

    return typer.Exit(code=INTERRUPTED)


def _fail(message: str, code: int) -> typer.Exit:
    err_console.print(f"error: {_one_line(message)}", markup=False, highlight=False,
                      soft_wrap=True)
    return typer.Exit(code=code)


def save_output(result: Any, output: str, *,
                what: str = "the run finished: its summary is printed"
                ) -> tuple[str | None, str | None]:
    """Write a finished run's ``--output``: ``(the file, None)``, or ``(None, why not)`` as
    one line naming the file, what failed and that nothing was written, so that the command
    still prints the run's summary (and writes its --plot) before it fails with it.

    A writer's failure after the run ended it with the run lost: scipy's ``MatWriteError``
    as a traceback, a full disk with the summary unprinted (an outside check, 2026-12-07).

    Parameters
    ----------
    result : Result
        The run.
    output : str
        The file (``.nc``, ``.mat``: written whole after the run).
    what : str, default "the run finished: its summary is printed"
        What the user still has, said in the line.

    Returns
    -------
    tuple of (str or None, str or None)
        The file written, or None and the line saying why not.
    """
    from ..io.outputs import shown
    from ..parameters import ParameterError

    try:
        return str(result.save(output)), None
    except ParameterError as err:  # the writer's own refusal (a .mat past its format's limit)
        why = err.message
    except OSError as err:  # a full disk, a file-size limit
        why = err.strerror or str(err)
    except MemoryError:
        why = "out of memory while writing it"
    except Exception as err:  # noqa: BLE001  (a writer library's own error: said, not raised)
        why = f"{type(err).__name__}: {err}"
    return None, f"{shown(output)}: {why}; not written ({what})"


#: the CSV reading options, one definition for every command that reads a record (analyze,
#: identify static/dynamic, fit, validate: docs/measured-data.md "Common file rules")
SepOption = Annotated[str | None, typer.Option(
    "--sep", help="Column separator of the CSV (default: detected; 'tab', 'space' accepted).")]
DecimalOption = Annotated[str, typer.Option("--decimal", help="Decimal mark of the CSV: . or ,")]
TimeUnitOption = Annotated[str | None, typer.Option("--time-unit",
                                                    help="Unit of the time column: s "
                                                    "(default) or ms.")]


#: the API's fields the CLI takes as options, field → (option, the option's unit, the factor
#: from the field's unit to it): a refusal of one is shown as the option the user typed, in its
#: unit (issue 41 item 7: ``--nut-speed 16`` on the CDFS was answered "nut_speed = 0.016";
#: ``--drive bogus`` "drive = 'bogus'").  The one table: a field is shown as its option by a
#: command that takes that option only.
_EDGE_FIELDS: dict[str, tuple[str, str, float]] = {
    "nut_speed": ("--nut-speed", "mm/s", 1.0 / MM_PER_S),
    "drive": ("--drive", "", 1.0),
    "duration": ("--duration", "s", 1.0),
    "ramp_time": ("--ramp-time", "s", 1.0),
    "error_estimate": ("--error-estimate", "", 1.0),
    "target.critical_speed": ("--target", "mm/s", 1.0 / MM_PER_S),
    "dwell": ("--dwell", "s", 1.0),
    "start_speed": ("--high", "mm/s", 1.0 / MM_PER_S),  # creep's step-down starts at --high
}


def _refusal(err: ValueError | FileNotFoundError, kwargs: dict[str, Any] | None = None) -> str:
    """The one-line message of a refused input, an API field (:data:`_EDGE_FIELDS`) as the
    option of the command (its parameters ``kwargs``) that the user typed."""
    edge = _EDGE_FIELDS.get(getattr(err, "field", ""))
    if edge is None or getattr(err, "source", None) or not isinstance(err, ParameterError):
        return str(err)
    option, unit, factor = edge
    if option[2:].replace("-", "_") not in (kwargs or {}):  # not this command's option
        return str(err)
    value = err.value
    if isinstance(value, bool):  # a flag: named, not valued
        return f"{option}: {err.message}"
    if isinstance(value, int | float) and unit:
        return f"{option} = {value * factor:g} [{unit}]: {err.message}"
    return str(ParameterError(option, value, err.message))


def _from_ctrl_c(err: BaseException) -> bool:
    """Whether ``err`` is a Ctrl-C in disguise: numba reports a ``KeyboardInterrupt`` raised
    while compiled code calls back into Python as a ``SystemError`` caused by it."""
    seen: set[int] = set()
    cause: BaseException | None = err
    while cause is not None and id(cause) not in seen:
        if isinstance(cause, KeyboardInterrupt):
            return True
        seen.add(id(cause))
        cause = cause.__cause__ or (None if cause.__suppress_context__ else cause.__context__)
    return False


def _stopped() -> typer.Exit:
    err_console.print("interrupted (Ctrl-C)", markup=False, highlight=False, soft_wrap=True)
    return interrupted()


def user_errors(fn: F) -> F:
    """Turn every expected failure into a one-line message on stderr, never a traceback.

    The output options declared with :func:`outputs` are checked first, before any work.
    Refused input or output destination: exit status 2.  Work that could not finish
    (simulation failure, out of memory, nesting too deep, an I/O error): exit status 1.
    The message names the file involved.  A Ctrl-C that the command does not report itself is
    one line and exit status 130 (Typer ended such a command with 130 and no word).
    """

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            _check_outputs(fn, kwargs)
            return fn(*args, **kwargs)
        except (ParameterError, ValueError, FileNotFoundError) as err:
            raise _fail(_refusal(err, kwargs), EXIT_REFUSED) from None
        except OSError as err:
            # without a file name: a write of the command's files (a full disk while writing
            # the output, io.outputs.write_bytes) — none given, nothing to name (it was
            # labelled "output" where no output was written)
            where = shown(os.fspath(err.filename)) if err.filename is not None else \
                _files_of(kwargs)
            why = err.strerror or str(err)
            raise _fail(f"{where}: {why}" if where else why, EXIT_FAILED) from None
        except MemoryError:
            files = _files_of(kwargs)
            raise _fail(f"{files + ': ' if files else ''}out of memory; the input or the "
                        "requested output is too large", EXIT_FAILED) from None
        except RecursionError:
            files = _files_of(kwargs)
            raise _fail(f"{files + ': ' if files else ''}nested too deeply to process",
                        EXIT_REFUSED) from None
        except KeyboardInterrupt:
            raise _stopped() from None
        except Exception as err:
            if not isinstance(err, typer.Exit) and _from_ctrl_c(err):
                raise _stopped() from None
            # SimulationError and sqlite3.Error, checked without importing either at start-up
            simulate = sys.modules.get("feeddrive.engine.simulate")
            if simulate is not None and isinstance(err, simulate.SimulationError):
                raise _fail(f"simulation failed: {err}", EXIT_FAILED) from None
            runner = sys.modules.get("feeddrive.reproduce.runner")  # a pool worker died
            if runner is not None and isinstance(err, runner.WorkerLost):
                raise _fail(str(err), EXIT_FAILED) from None
            builds = sys.modules.get("feeddrive.solvers.builds")  # neither C nor numba
            if builds is not None and isinstance(err, builds.NoEngine):
                raise _fail(str(err), EXIT_FAILED) from None
            c_cache = sys.modules.get("feeddrive.backends.c_cache")  # the C build not made
            if c_cache is not None and isinstance(err, c_cache.CompilerNotFound):
                raise _fail(str(err), EXIT_FAILED) from None
            if c_cache is not None and isinstance(err, c_cache.CompileError):
                raise _fail(f"{err}; {c_cache.COMPILE_FAILED_ADVICE}", EXIT_FAILED) from None
            sqlite3 = sys.modules.get("sqlite3")
            if sqlite3 is not None and isinstance(err, sqlite3.Error):
                files = _files_of(kwargs)
                raise _fail(f"{files + ': ' if files else ''}database error (SQLite: {err})",
                            EXIT_FAILED) from None
            raise

    return wrapper  # type: ignore[return-value]


#: the ``--preset`` help of the commands that take any drive: the default set of each drive
#: (:func:`default_preset`; tests/integration/test_cli_new_user3.py checks it against the
#: topologies' ``example_preset``, which --help does not import)
PRESET_HELP = ("Named parameter set (default wang2021; the drive's example set for the other "
               "topologies: linear-motor-example for --drive linear-motor, "
               "rack-pinion-example for --drive rack-pinion).")


def default_preset(drive: str | None) -> str:
    """The set a command uses for ``drive`` when none is named: the topology's own example
    (``Mechanism.example_preset``), ``wang2021`` for the paper's drives."""
    topology = registry.table(registry.MECHANISMS).get(drive or "")
    return str(getattr(topology, "example_preset", "wang2021"))


def refuse_beside_machine(given: tuple[tuple[str, object, object], ...],
                          why: str = "its axes are set in the machine file") -> None:
    """Refuse, in one line naming the option, a drive's option given with ``--machine``.

    Parameters
    ----------
    given : tuple of (str, object, object)
        Each option's name, its value and its default (an option at its default was not
        given).
    why : str, default "its axes are set in the machine file"
        What the machine sets instead, said after "not with --machine".

    Raises
    ------
    ParameterError
        For the first option whose value is not its default.
    """
    refuse_unused(given, f"not with --machine ({why})")


def refuse_unused(given: tuple[tuple[str, object, object], ...], why: str) -> None:
    """Refuse, in one line naming the option, an option the run would not use (given beside
    another that makes it meaningless): it was dropped without a word.

    Parameters
    ----------
    given : tuple of (str, object, object)
        Each option's name, its value and its default (an option at its default was not
        given).
    why : str
        Why it is not used, the message after the option and its value.

    Raises
    ------
    ParameterError
        For the first option whose value is not its default.
    """
    for option, value, default in given:
        if value != default:
            raise ParameterError(option, value, why)


def resolve_parameters(preset_name: str | None, params_file: str | None,
                       drive: str | None = None) -> DriveParameters:
    """The parameter set named by ``--preset`` or loaded from ``--params`` (not both); by
    default ``wang2021``, or the drive's example set (``linear-motor-example``)."""
    if preset_name and params_file:
        raise ParameterError("--params", params_file, "give either --preset or --params, not both")
    if params_file:
        return load(params_file)
    return preset(preset_name or default_preset(drive))


def print_json(data: Any) -> None:
    sys.stdout.write(json.dumps(data, indent=2, allow_nan=False) + "\n")


def progress_bar(duration: float, again: str | None = None,
                 label: Callable[[float, float], str] | None = None,
                 ) -> tuple[Any, Callable[[float, float], None]]:
    """The progress bar on stderr of a run without ``--json`` (whose JSON is all it prints:
    no bar, and rich.progress is not imported), and the callback that moves it: a drive's
    ``simulate`` and a machine's.

    Parameters
    ----------
    duration : float
        The run's simulated time [s].
    again : str, optional
        What a second pass over the same time is (``--error-estimate``'s run with tighter
        tolerances): when the reported time goes back, the bar starts again under this label.
    label : callable, optional
        ``label(t, t_end)`` → the bar's description at each report (a circular test's "CCW
        run" / "CW run"); default "simulating".

    Returns
    -------
    tuple
        The ``rich`` progress bar (stop it when the run ends) and ``advance(t, t_end)``.
    """
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    bar = Progress(TextColumn("{task.description}"), BarColumn(),
                   TextColumn("{task.fields[t]}"), TimeRemainingColumn(), console=err_console,
                   transient=True)
    task = bar.add_task("simulating", total=duration, t="")
    last = [0.0]

    def advance(t: float, t_end: float) -> None:
        # only long runs (chunked) report progress; off a terminal the bar is kept but not
        # started (a transient bar draws nothing there, and its stop wrote a blank line)
        if not bar.live.is_started and err_console.is_terminal:
            bar.start()
        if again is not None and t < last[0]:  # the second pass
            bar.reset(task, total=duration, description=again)
        last[0] = t
        bar.update(task, completed=t, total=t_end, t=f"{t:.4g} / {t_end:.4g} s",
                   description=None if label is None else label(t, t_end))

    return bar, advance
