"""Which build of the engine runs a model's drivers: C where a compiler is found, else numba.

The drivers (:mod:`feeddrive.solvers.driver`) exist in two builds from one text: numba's
(:mod:`feeddrive.solvers.shared`) and the C build (:mod:`feeddrive.backends.c_engine`, a
plug-in of the group :data:`feeddrive.registry.ENGINES`: the core does not import the code
generators).  :func:`driver` picks one per call:

* ``FEEDDRIVE_ENGINE=numba``: numba;
* ``FEEDDRIVE_ENGINE=c``: C, an error without a compiler;
* unset (or ``auto``): C where a compiler is found; else numba, said once per process in one
  line on standard error (:data:`feeddrive.backends.c_cache.NO_COMPILER`).  A model whose
  kernels fall outside the C subset (a friction law or part written outside the package
  without type annotations) runs in numba, said once per model structure.

numba is an optional install (``pip install 'feeddrive[numba]'``,
:data:`feeddrive._jit.HAVE_NUMBA`), imported only when its build runs
(:func:`feeddrive._jit.start_numba`).  Without it the C build runs everything per step, and
where it cannot — no C compiler, ``FEEDDRIVE_ENGINE=numba``, or a model outside the C subset —
:class:`NoEngine` says in one line how to get either build (:data:`NO_ENGINE`).

Both give the same results (the regression corpus, docs/c-backend.md "The engine build").
"""

from __future__ import annotations

import os
import shlex
import shutil
from typing import TYPE_CHECKING, Any

from .. import _jit, registry
from .._jit import HAVE_NUMBA

if TYPE_CHECKING:
    from ..model.assemble import Model

#: the environment variable that forces a build
ENGINE_ENV = "FEEDDRIVE_ENGINE"
#: its values: "auto" (the default), "c" and "numba"
CHOICES = ("auto", "c", "numba")
#: set by the parent of a pool for its workers (:func:`feeddrive._workers.
#: single_threaded_children`): the parent has said what
#: :data:`~feeddrive.backends.c_cache.NO_COMPILER` says (:func:`announce`), so that a sweep's
#: workers do not each say it again
SAID_ENV = "FEEDDRIVE_BUILD_SAID"
#: what is said when neither build can run: no C compiler and numba not installed
NO_ENGINE = ("no C compiler found and numba is not installed; install a C compiler "
             "(Debian: apt-get install gcc; macOS: xcode-select --install; or set CC) or "
             "install numba: pip install 'feeddrive[numba]'")


def cc_problem(cc: str) -> str | None:
    """What is wrong with ``$CC`` = ``cc``, or None when it names an executable: one wording,
    which :func:`feeddrive.backends.c_cache.find_compiler`'s refusal, the note said while numba
    runs and :func:`no_engine_text` all use (here, as the core may not import the backends).

    Parameters
    ----------
    cc : str
        The variable's value.

    Returns
    -------
    str or None
        ``CC = "gcc '-O2" is not a command line (no closing quotation): …``, ``CC =
        '/x/cc': '/x/cc' is not an executable file``, ``… is not an executable on PATH``.
    """
    try:
        cmd = shlex.split(cc)
    except ValueError as err:  # an unbalanced quote
        return (f"CC = {cc!r} is not a command line ({str(err).lower()}): expected a C "
                "compiler and its options, quoted as in a shell (CC='gcc -O2')")
    if cmd and shutil.which(cmd[0]) is not None:
        return None
    program = cmd[0] if cmd else ""
    where = "file" if os.sep in program or (os.altsep or os.sep) in program else "on PATH"
    return f"CC = {cc!r}: {program!r} is not an executable {where}"


def cc_trouble(cc: str) -> str:
    """What is wrong with ``$CC`` when it gives no compiler, to start a line
    (:func:`cc_problem`).

    Parameters
    ----------
    cc : str
        The variable's value.

    Returns
    -------
    str
        ``CC = '…': '…' is not an executable on PATH``, ``CC = '…' is not a command line (…)``.
    """
    return cc_problem(cc) or f"CC = {cc!r} gives no compiler"


def no_engine_text(numba: str = "is not installed") -> str:
    """:data:`NO_ENGINE`, or, where ``$CC`` is set but gives no compiler, that
    (:func:`cc_trouble`).

    Parameters
    ----------
    numba : str, default "is not installed"
        What is wrong with numba.

    Returns
    -------
    str
        One line.
    """
    cc = os.environ.get("CC", "").strip()
    if not cc:
        return NO_ENGINE.replace("numba is not installed", f"numba {numba}")
    return (f"{cc_trouble(cc)} and numba {numba}; set CC to a C compiler "
            "(or unset it to use cc, gcc or clang from PATH), or install numba: "
            "pip install 'feeddrive[numba]'")


def announce() -> None:
    """Say in the parent of a pool of workers what each worker would say once about the build
    (no C compiler: the numba build runs, :data:`~feeddrive.backends.c_cache.NO_COMPILER`),
    so that it is said once (the workers are told it was said:
    :data:`~feeddrive.backends.c_cache.SAID_ENV`).  numba is not started here."""
    try:
        choice = chosen()
    except ValueError:  # refused where a model is run
        return
    engine = registry.table(registry.ENGINES).get("c")
    if choice == "auto" and HAVE_NUMBA and engine is not None:
        engine.available()


class NoEngine(RuntimeError):
    """Neither build can run a model: no C compiler (or a model outside the C subset) and numba
    not installed.  The message is one line saying how to get either."""


def chosen() -> str:
    """The build ``FEEDDRIVE_ENGINE`` asks for.

    Returns
    -------
    str
        ``"auto"``, ``"c"`` or ``"numba"``.

    Raises
    ------
    ValueError
        One line naming the variable, its value and the choices.
    """
    raw = os.environ.get(ENGINE_ENV, "")
    value = raw.strip().lower() or "auto"
    if value not in CHOICES:
        raise ValueError(f"{ENGINE_ENV} = {raw!r}: expected one of {', '.join(CHOICES)} "
                         "(unset: auto, C where a compiler is found)")
    return value


def engine_name() -> str:
    """The build that runs the drivers in this process now: ``"c"`` or ``"numba"``.

    Returns
    -------
    str
        The build's name.

    Raises
    ------
    NoEngine
        Without numba: no C compiler found, or ``FEEDDRIVE_ENGINE=numba``.
    """
    choice = chosen()
    if choice == "numba":
        if not HAVE_NUMBA:
            raise NoEngine(f"{ENGINE_ENV} = 'numba' but numba is not installed: "
                           "pip install 'feeddrive[numba]', or unset it to use C")
        return "numba"
    engine = registry.table(registry.ENGINES).get("c")
    if not HAVE_NUMBA:
        try:
            if engine is not None and engine.available(required=True):
                return "c"
        except RuntimeError:  # CompilerNotFound (the core does not import the backends)
            pass
        raise NoEngine((f"{ENGINE_ENV} = 'c': " if choice == "c" else "") + no_engine_text())
    if choice == "c":
        if engine is None or not engine.available(required=True):
            return "numba"
        return "c"
    if engine is not None and engine.available(quiet=True):
        return "c"
    # no compiler: numba, if it imports (found is not enough: a hidden or broken numba)
    _numba_build()
    if engine is not None:
        engine.available()  # said once per process, in one line (NO_COMPILER)
    return "numba"


def driver(model: Model, use: str) -> Any:
    """``model``'s driver ``use`` (``"integrate"`` or ``"integrate_dense"``) in the build of
    :func:`engine_name`, taking the arguments of the driver's text
    (:data:`feeddrive.solvers.driver.USES`) and returning ``(t_out, y_out, aux_out, stats,
    held)``; the outputs are written into the buffers passed where the use takes them
    (``integrate_dense``: its caller passes them large enough).

    Parameters
    ----------
    model : Model
        The assembled model.
    use : str
        The driver.

    Returns
    -------
    callable
        The driver.
    """
    if not _in_c(model):
        _numba_build()
        from . import driver as template

        run = getattr(model.module, use)
        return _into_buffers(model, run, use) if use in template.NUMBA_NRT_FREE else run
    return registry.table(registry.ENGINES)["c"].driver(model, use)


def _into_buffers(model: Model, run: Any, use: str) -> Any:
    """numba's driver ``use`` compiled without its runtime
    (:data:`feeddrive.solvers.driver.NUMBA_NRT_FREE`: its outputs written into buffers passed
    — new ones where the use takes none —, its statistics into an array passed last, the
    state it advances ``y0`` itself, the number of outputs its result), taking and returning
    what the others do."""
    import numpy as np

    from . import driver as template

    names = template.USES[use][0]
    at = {name: names.index(name) for name in ("y0", "held", "t_end", "base", "start")}
    own = "t_buf" not in names  # the buffers made here (as the C build's caller does)
    n_stats = template.N_STATS[use]
    n_state, n_aux = len(model.states), len(model.aux)

    def call(*args: Any) -> tuple[np.ndarray, ...]:
        values = list(args)
        values[at["y0"]] = args[at["y0"]].copy()  # the driver's state, advanced in place
        if own:
            n_break = int(round(args[at["t_end"]] / args[at["base"]]))
            n_out = max(0, (n_break - args[at["start"]]) // args[names.index("out_every")] + 1)
            buffers = (np.empty(n_out), np.empty((n_out, n_state)), np.empty((n_out, n_aux)))
            values += buffers
        else:
            buffers = tuple(args[names.index(b)] for b in ("t_buf", "y_buf", "aux_buf"))
        stats = np.zeros(n_stats)
        count = run(*values, stats)
        t_buf, y_buf, aux_buf = buffers
        return (t_buf[:count], y_buf[:count], aux_buf[:min(count, aux_buf.shape[0])], stats,
                args[at["held"]])

    return call


def _numba_build() -> None:
    """Start the numba build (:func:`feeddrive._jit.start_numba`, once per process): numba is
    imported only where its build runs.

    Raises
    ------
    NoEngine
        numba is found but does not import (hidden, or broken): one line saying how to get
        either build.
    """
    try:
        _jit.start_numba()
    except ImportError as err:
        why = f"does not import ({str(err).splitlines()[0] if str(err) else type(err).__name__})"
        engine = registry.table(registry.ENGINES).get("c")
        if chosen() == "numba" and engine is not None and engine.available(quiet=True):
            raise NoEngine(f"{ENGINE_ENV} = 'numba': numba {why}; unset {ENGINE_ENV} to use "
                           "the C build") from None
        raise NoEngine((f"{ENGINE_ENV} = 'numba': " if chosen() == "numba" else "")
                       + no_engine_text(why)) from None


def engine_of(model: Model) -> str:
    """The build that runs ``model``'s drivers: ``"c"`` or ``"numba"``.

    Parameters
    ----------
    model : Model
        The assembled model.

    Returns
    -------
    str
        The build's name.
    """
    return "c" if _in_c(model) else "numba"


def _in_c(model: Model) -> bool:
    """Whether the C build runs ``model``: :func:`engine_name` is C and the model's kernels
    translate (else numba runs it, said once; an error with ``FEEDDRIVE_ENGINE=c``)."""
    if engine_name() != "c":
        return False
    if not HAVE_NUMBA:
        try:
            return bool(registry.table(registry.ENGINES)["c"].translates(model, required=True))
        except ValueError as err:  # TranslationError: outside the C subset
            raise NoEngine(f"{str(err).splitlines()[0]}; this model needs the numba build: "
                           "pip install 'feeddrive[numba]'") from None
    return bool(registry.table(registry.ENGINES)["c"].translates(model,
                                                                required=chosen() == "c"))


def compiled(model: Model, name: str) -> Any:
    """``model``'s function ``name`` of the shared drivers' module (``_ev_rates``,
    ``_ev_central_columns``, ``_r4_fd_jacobian``, ``auxiliary`` …) in the build of
    :func:`engine_name`, taking and returning what ``model.module.compiled(name)`` does; a
    function the C build does not hold is numba's.

    Parameters
    ----------
    model : Model
        The assembled model.
    name : str
        The function.

    Returns
    -------
    callable
        The function.
    """
    if _in_c(model):
        fn = registry.table(registry.ENGINES)["c"].function(model, name)
        if fn is not None:
            return fn
    else:
        _numba_build()
    return model.module.compiled(name)
