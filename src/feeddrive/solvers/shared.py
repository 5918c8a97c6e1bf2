"""The solver drivers compiled once for every model, the model's functions passed to them.

The drivers (:mod:`feeddrive.solvers.driver` specialised as ``integrate`` and
``integrate_dense``, the steps of :mod:`feeddrive.solvers.steps`, the Jacobian kernels of
:mod:`feeddrive.solvers.rodas4` and ``auxiliary``) are written as templates that call the
model's ``rhs`` and ``sample_update`` and read its sizes ``N_AUX``, ``N_HELD``.  Pasted into
every generated model module, they were compiled again for each model (≈ 14 CPU s a model,
most of a cold ``reproduce``: issue 21 item 3).  Here they are placed once in a generated
module of their own, each function that reads a model name (directly or through a function
it calls) taking those names as its first arguments; a model passes its ``rhs`` and
``sample_update`` as *first-class functions* (numba ``cfunc``\\ s of :func:`signatures`,
called through their address) and its sizes.  numba compiles
the drivers once per signature — the same for every model — and caches them on disk; a new
model compiles only its own two functions.

Nothing is rounded differently: numba compiles without fast-math, so a call through an
address computes what the inlined call did, bit for bit (tested against recorded
trajectories, ``tests/validation/test_engine_v1_regression.py``).
"""

from __future__ import annotations

import ast
import functools
import threading
from pathlib import Path
from types import ModuleType
from typing import Any

from .._jit import (
    cache_dir,
    compile_lock,
    first_class,
    import_generated,
    numba_started,
)


def signatures() -> tuple[Any, Any]:
    """The numba signatures of the first-class functions (numba started).

    Returns
    -------
    tuple
        ``rhs(t, y, held, P, T, dy, aux)``'s and ``sample_update(t, y, held, P, T, tick)``'s.
    """
    from numba import types

    array = types.float64[::1]
    return (types.void(types.float64, array, array, array, array, array, array),
            types.void(types.float64, array, array, array, array, types.int64[::1]))

#: the names a template reads from its model, in the order they are passed
MODEL_NAMES = ("rhs", "sample_update", "N_STATE", "N_AUX", "N_HELD", "N_CLOCK")
#: the drivers a model calls (the other functions of the module are theirs)
ENTRY_POINTS = ("integrate", "integrate_dense", "auxiliary")


@functools.cache
def solver_sources() -> list[str]:
    """The integrator templates, as they read in a model's module: the one driver of
    :mod:`feeddrive.solvers.driver` specialised as ``integrate`` (DOPRI5 landing on every
    breakpoint, as in engine v1) and ``integrate_dense`` (dense output, DOPRI5 ⇄ RODAS4),
    beside the steps and Jacobian kernels they call and ``auxiliary``.

    Read and specialised with ``inspect`` and ``ast`` (≈ 0.1 s): only when the shared
    drivers' module is not in the compile cache's folder yet (:func:`module_source`).

    Returns
    -------
    list of str
        Python sources of the solver functions.
    """
    from . import dopri5, driver_text, evaluate, rodas4, steps, switching

    return (steps.template_sources() + rodas4.template_sources()
            + driver_text.template_sources() + dopri5.template_sources()
            + switching.template_sources()
            + evaluate.template_sources())


def model_arguments(source: str) -> tuple[str, dict[str, tuple[str, ...]]]:
    """``source`` (solver templates reading the model names of :data:`MODEL_NAMES` as
    globals) rewritten so that each function reading one — directly or through a function of
    ``source`` it calls — takes them as its first parameters, and passes them on.

    Parameters
    ----------
    source : str
        Python source of the templates.

    Returns
    -------
    text : str
        The rewritten source.
    added : dict of str to tuple of str
        Function name → the model names it now takes first, in :data:`MODEL_NAMES` order.
    """
    tree = ast.parse(source)
    functions = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}
    reads: dict[str, set[str]] = {}
    calls: dict[str, set[str]] = {}
    for name, fn in functions.items():
        names = {n.id for n in ast.walk(fn) if isinstance(n, ast.Name)}
        reads[name] = names & set(MODEL_NAMES)
        calls[name] = {n.func.id for n in ast.walk(fn) if isinstance(n, ast.Call)
                       and isinstance(n.func, ast.Name) and n.func.id in functions}
    changed = True
    while changed:  # what a function reads through the functions it calls
        changed = False
        for name in functions:
            more = set().union(*(reads[c] for c in calls[name])) - reads[name] if calls[name] \
                else set()
            if more:
                reads[name] |= more
                changed = True
    added = {name: tuple(m for m in MODEL_NAMES if m in reads[name]) for name in functions}
    for name, fn in functions.items():
        fn.args.args[:0] = [ast.arg(arg=m) for m in added[name]]
        for node in ast.walk(fn):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                    and added.get(node.func.id)):
                node.args[:0] = [ast.Name(id=m, ctx=ast.Load()) for m in added[node.func.id]]
    return ast.unparse(ast.fix_missing_locations(tree)), {n: a for n, a in added.items() if a}


_HEADER = ('"""Generated by feeddrive.solvers.shared: the solver drivers of every model.  '
           'Do not edit."""\n')
_TRAILER = "# the end of the shared drivers\n"  # a whole file ends so


def module_source(path: Path) -> str:
    """The text of the shared drivers' module: the file at ``path`` if it is one, else
    rewritten from the templates (:func:`model_arguments`), with the table
    ``MODEL_ARGUMENTS`` (function → the model names it takes first).

    The text is a function of the solver templates alone, which name the compile cache's
    folder (:data:`feeddrive._jit.SOURCE_DIGEST`), so a file there is the text; rewriting the
    templates costs a fresh process ≈ 0.1 s (issue 21 item 4).  A damaged file is not used.

    Parameters
    ----------
    path : pathlib.Path
        Where the module is kept.

    Returns
    -------
    str
        Python source.
    """
    try:  # written whole (atomically) or not at all: a file with both ends is the text
        source = path.read_text(encoding="utf-8")
        if (source.startswith(_HEADER) and source.endswith(_TRAILER)
                and "\nMODEL_ARGUMENTS = " in source):
            return source
    except (OSError, ValueError):
        pass
    text, added = model_arguments("\n\n\n".join(solver_sources()))
    return (_HEADER + "import math\nimport numpy as np\nfrom feeddrive._jit import kernel\n\n"
            f"MODEL_ARGUMENTS = {added!r}\n\n\n" + text + "\n" + _TRAILER)


_FIRST_USE = threading.Lock()  # threads of one process (the explorer's jobs) build things once
_DRY_RUN = threading.local()  # set inside prepared_models(): stop at the first driver call


class ModelPrepared(BaseException):  # noqa: N818 (a signal, not an error)
    """Raised at a model's first driver call inside :func:`prepared_models`, once its
    first-class functions are compiled (a ``BaseException``: no ``except Exception`` of the
    code on the way swallows it)."""


class prepared_models:  # noqa: N801 (a context manager, read as a phrase)
    """Inside it, a model's first call of a shared driver compiles (or loads) the model's
    first-class functions and raises :class:`ModelPrepared` instead of running the driver.

    What it is for: a cold ``feeddrive reproduce`` compiles the drivers in one worker for
    ≈ 20 CPU s, while the other has nothing to do but wait for them; run through the study's
    tasks inside this, the other compiles every model those tasks build meanwhile
    (:func:`feeddrive.reproduce.runner.prepare_models`).
    """

    def __enter__(self) -> prepared_models:
        _DRY_RUN.on = True
        return self

    def __exit__(self, *exc: object) -> bool:
        _DRY_RUN.on = False
        return exc[0] is ModelPrepared


def preparing() -> bool:
    """Whether this thread runs inside :class:`prepared_models`.

    Returns
    -------
    bool
        True inside it.
    """
    return bool(getattr(_DRY_RUN, "on", False))


def drivers_on_disk() -> bool:
    """Whether the compile cache holds the dense-output driver (``integrate_dense``): false on
    a cold cache, until the first process that needs it has compiled it.

    Returns
    -------
    bool
        True when its index file is in the cache folder.
    """
    return any(Path(cache_dir()).glob("shared_*/drivers.integrate_dense-*.nbi"))


@functools.cache
def _module() -> tuple[ModuleType, dict[str, tuple[str, ...]]]:
    """The shared drivers' module (imported once per process) and each function's model
    arguments."""
    with _FIRST_USE:
        source = module_source(Path(cache_dir()) / "shared" / "drivers.py")
        module = import_generated("shared", "drivers", source)
    return module, module.MODEL_ARGUMENTS


class Bound:
    """One model's functions bound to the shared drivers (:meth:`function`: ``integrate``,
    ``integrate_dense``, ``auxiliary`` … take the arguments of the templates they are, without
    the model's).

    The model's first-class ``rhs`` and ``sample_update`` are compiled (or loaded from the
    cache) at the first driver call, a shared driver at its first call in the process; each
    first compilation holds a file lock so that two processes needing it compile it once
    (:func:`feeddrive._jit.compile_lock`).

    Parameters
    ----------
    rhs, sample_update : numba dispatcher
        The model's kernels.
    sizes : dict of str to int
        ``N_STATE``, ``N_AUX``, ``N_HELD``, ``N_CLOCK``.
    path : str
        The model module's file (beside which its compile lock is kept).
    """

    def __init__(self, rhs: Any, sample_update: Any, sizes: dict[str, int], path: str) -> None:
        self._kernels = (rhs, sample_update)
        self._sizes = sizes
        self._path = path
        self._values: dict[str, Any] | None = None
        self._entries: dict[str, tuple[Any, list[Any]]] = {}  # name → (entry point, model's)

    def _model_values(self) -> dict[str, Any]:
        if self._values is None:
            rhs, update = self._kernels
            with _FIRST_USE, compile_lock(self._path, "first_class"):
                if self._values is not None:  # another thread was first
                    return self._values
                rhs_signature, sample_signature = signatures() if numba_started() \
                    else (None, None)
                self._values = {"rhs": first_class(rhs.py_func, rhs_signature, "rhs_fc"),
                                "sample_update": first_class(update.py_func, sample_signature,
                                                             "sample_update_fc"),
                                **self._sizes}
        return self._values

    def _call(self, name: str, args: tuple[Any, ...]) -> Any:
        module, added = _module()
        fn = getattr(module, name)
        values = self._model_values()
        if getattr(_DRY_RUN, "on", False):
            raise ModelPrepared(name)
        head = [values[m] for m in added.get(name, ())]
        if not numba_started():  # plain Python (cold callers; the engine runs in C)
            return fn(*head, *args)
        if not fn.signatures:  # the first call in this process: compiled or loaded once
            with compile_lock(module.__file__ or name, name):
                return fn(*head, *args)
        return fn(*head, *args)

    def function(self, name: str) -> Any:
        """Any function of the shared drivers' module (a step, ``_r4_fd_jacobian`` …) with
        this model's arguments put first: called with the template's own arguments.

        Parameters
        ----------
        name : str
            The function's name in the templates.

        Returns
        -------
        callable
            The function bound to this model.

        Raises
        ------
        AttributeError
            When the templates define no such function.
        """
        if name not in ENTRY_POINTS:  # (an entry point is there: no import at binding time)
            module, _ = _module()
            if not callable(getattr(module, name, None)) or name.startswith("__"):
                raise AttributeError(f"the solver drivers define no function {name!r}")

        def bound(*args: Any) -> Any:
            return self._call(name, args)

        bound.__name__ = bound.__qualname__ = name
        return bound

    def compiled(self, name: str) -> Any:
        """:meth:`function`, calling after its first call the compiled code directly, without
        numba's per-call typing of the arguments (≈ 10–15 µs of a ≈ 20-µs call): for callers
        that make thousands of calls with arguments of fixed types — float64 scalars and
        C-contiguous float64 or integer arrays, always the same — such as the linearisations
        (:mod:`feeddrive.analysis.linear`).  The types are not checked after the first call.

        Parameters
        ----------
        name : str
            The function's name in the templates.

        Returns
        -------
        callable
            The function bound to this model.
        """
        first = self.function(name)
        entries = self._entries

        def call(*args: Any) -> Any:
            got = entries.get(name)
            if got is not None and not getattr(_DRY_RUN, "on", False):
                return got[0](*got[1], *args)
            out = first(*args)
            if not numba_started():
                return out
            module, added = _module()
            overloads = getattr(module, name).overloads
            if len(overloads) == 1:  # one signature: its compiled entry point
                values = self._model_values()
                entries[name] = (next(iter(overloads.values())).entry_point,
                                 [values[m] for m in added.get(name, ())])
            return out

        call.__name__ = call.__qualname__ = name
        return call


def binding_source() -> str:
    """The lines closing a generated model module: its ``rhs``, ``sample_update`` and sizes
    bound to the shared drivers (``integrate``, ``integrate_dense``, ``auxiliary``; any other
    function of theirs, ``module._r4_fd_jacobian`` say, through the module's ``__getattr__``,
    and without per-call typing through ``module.compiled(name)``, :meth:`Bound.compiled`).

    Returns
    -------
    str
        Python source.
    """
    sizes = ", ".join(f"{m!r}: {m}" for m in MODEL_NAMES[2:])
    return ("from feeddrive.solvers.shared import Bound as _Bound\n"
            f"_bound = _Bound(rhs, sample_update, {{{sizes}}}, __file__)\n"
            + "".join(f"{name} = _bound.function({name!r})\n" for name in ENTRY_POINTS)
            + "compiled = _bound.compiled\n"
            + "__getattr__ = _bound.function\n")
