"""The C build of the engine: the one driver of :mod:`feeddrive.solvers.driver`, translated
into one C library for every model (compiled once per machine), and per model structure a
small library of its kernels, which the drivers reach through a table; called by ctypes.

Every method runs through the driver's two specialisations (``integrate``: ``dopri5`` and its
fixed-step variant; ``integrate_dense``: ``modal``, ``auto``, ``rodas4``, ``dopri5-dense`` and
theirs).  Their text (:func:`feeddrive.solvers.driver_text.source` with ``inline=False``) is
read as it is, whatever its authors change, and *lowered* at the boundary between Python and C
alone (:func:`lowered_source`, :func:`feeddrive.solvers.driver_text.lower_outputs`, which
lowers numba's dense driver too): the output arrays the numba breakpoint driver allocates are
the caller's buffers, the statistics array is written into a caller's array and the driver
returns the number of outputs; the drivers, which take their work arrays from their caller
(:func:`feeddrive.solvers.driver.step_space`, ``work_space``), are called by an entry that
makes them.
Everything else — the steps, the RODAS4 Jacobian and linear solves, the
event location, the eigen-analysis of the modal step cap (:mod:`feeddrive.solvers.modes`, in
real arithmetic: no LAPACK) — is translated by :mod:`feeddrive.backends.c_translate` from the
same Python numba compiles.

Two libraries, each compiled through the compiled-object cache
(:mod:`feeddrive.backends.c_cache`, keyed by source hash, compiler, flags and platform):

* the **driver library** (:func:`driver_source`): both drivers and the shared module's other
  functions (:data:`FUNCTIONS`), the same text for every model, so compiled once.  Every one
  of its functions takes the model's table (:data:`MODEL_STRUCT`) as a hidden first parameter
  (the translator's ``context``): the sizes ``FD_N_STATE`` … are read from it — the work
  arrays are C99 variable-length arrays — and the model's right-hand side and sampled update
  are called through its function pointers;
* a **model library** per model structure (:func:`model_source`): the model's kernels
  (:func:`feeddrive.backends.c_backend.c_model_source`, its sizes constants) and its table
  ``fd_model_table``.

Both are loaded with ctypes; each call of an entry of the driver library passes the address of
the model's table first, and ctypes releases the GIL for the call.

The build registers itself as the engine ``"c"`` (:data:`feeddrive.registry.ENGINES`);
:mod:`feeddrive.solvers.builds` chooses between it and numba.

One difference from the numba build is known and cannot be removed without LAPACK: where the
real QR iteration of the eigen-analysis does not converge (:func:`step_cap_real
<feeddrive.solvers.modes.step_cap_real>` returns NaN), numba falls back to LAPACK's ``zgeev``
and the C build goes without the step cap until the next analysis.
"""

from __future__ import annotations

import ast
import contextlib
import ctypes
import functools
import hashlib
import json
import os
import sys
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import registry
from .c_backend import SOLVER_SHAPES, SOLVER_TYPES, CFunction, c_model_source
from .c_cache import (
    LIBRARY_FLAGS,
    CompileError,
    CompilerNotFound,
    available_compiler,
    cached_library,
    find_compiler,
    keep_text,
    kept,
    kept_text,
)
from .c_translate import DYNAMIC, TranslationError, translate_kernels

if TYPE_CHECKING:
    from ..model.assemble import Model

__all__ = ["USES", "CEngine", "driver_source", "lowered_source", "model_source"]

#: the driver's uses the engine calls, by name of the numba function they replace
USES = ("integrate", "integrate_dense")
#: the driver's output arrays → the caller's buffers the C driver writes, and its statistics
#: array → the caller's (:data:`feeddrive.solvers.driver_text.OUTPUTS`, ``STATS``,
#: ``STATS_OUT``, which lower the text: :func:`feeddrive.solvers.driver_text.lower_outputs`;
#: repeated here, the engine importing the driver's text only when it builds)
OUTPUTS = {"t_out": "t_buf", "y_out": "y_buf", "aux_out": "aux_buf"}
STATS = "stats"
STATS_OUT = "stats_out"

#: how the driver library reaches a model: its sizes and its two functions, one table per
#: model library (``fd_model_table``, :func:`model_source`), passed to every entry of the
#: driver library (:func:`driver_source`) as its first argument
MODEL_STRUCT = r"""
#ifndef FD_MODEL_STRUCT
#define FD_MODEL_STRUCT
/* A model as the engine's driver library reaches it (feeddrive.backends.c_engine): its sizes
   and its right-hand side and sampled update (fd_rhs, fd_sample_update of its library). */
typedef void (*fd_rhs_fn)(double t, const double *y, double *held, const double *P,
                          const double *T, double *dy, double *aux);
typedef void (*fd_sample_update_fn)(double t, double *y, double *held, const double *P,
                                    const double *T, const long *tick);
typedef struct fd_model {
    long n_state, n_aux, n_held, n_clock, n_param, n_table;
    fd_rhs_fn rhs;
    fd_sample_update_fn sample_update;
} fd_model;
#endif
"""
#: the hidden first parameter of every function of the driver library (the translator's
#: ``context``), and the sizes read through it where the model library has constants
CONTEXT = ("const fd_model *", "fd_m")
SIZES = {"FD_N_STATE": "n_state", "FD_N_AUX": "n_aux", "FD_N_HELD": "n_held",
         "FD_N_CLOCK": "n_clock", "FD_N_PARAM": "n_param", "FD_N_TABLE": "n_table"}
#: the sizes the drivers use, read from the table once per call of each function into a
#: local constant (``fd_n_state`` …), which the compiler keeps across the model's calls
LOCAL_SIZES = ("FD_N_STATE", "FD_N_AUX", "FD_N_HELD", "FD_N_CLOCK")
PROLOGUE = "\n".join(f"const long fd_{SIZES[m]} = {CONTEXT[1]}->{SIZES[m]}; "
                     f"(void)fd_{SIZES[m]};" for m in LOCAL_SIZES)
#: the model's functions as the driver library calls them (through the table)
RHS = CFunction(f"{CONTEXT[1]}->rhs", None, (2, 5, 6))
SAMPLE_UPDATE = CFunction(f"{CONTEXT[1]}->sample_update", None, (1, 2))
#: the table's name in a model library
TABLE = "fd_model_table"
#: the driver library's flags: :data:`~feeddrive.backends.c_cache.LIBRARY_FLAGS` at ``-O3``.
#: Compiled once per machine, so its 0.5 CPU s more than ``-O2`` is paid once; gcc 12's
#: vectoriser then takes the stage sums over the run-time state count, and the DOPRI5-type
#: runs are 7–10 % faster (RODAS4 as the method ≈ 5 % slower: its LU loops are short);
#: results unchanged (no reassociation without ``-ffast-math``; benchmarks/README.md)
DRIVER_FLAGS = tuple("-O3" if flag == "-O2" else flag for flag in LIBRARY_FLAGS)


class ModelTable(ctypes.Structure):
    """``fd_model`` (:data:`MODEL_STRUCT`) as ctypes reads it: the sizes a model library was
    compiled with, checked against the model before its first run."""

    _fields_ = [*((name, ctypes.c_long) for name in SIZES.values()),
                ("rhs", ctypes.c_void_p), ("sample_update", ctypes.c_void_p)]


def _array_arg(name: str) -> ast.arg:
    return ast.arg(arg=name, annotation=ast.Attribute(ast.Name("np", ast.Load()), "ndarray",
                                                      ast.Load()))


@functools.cache
def lowered_source(use: str) -> tuple[str, int]:
    """The driver specialised for ``use`` (:data:`USES`) as the C build takes it: its outputs
    written into the caller's ``t_buf``, ``y_buf``, ``aux_buf`` (added as parameters where the
    use has none), its statistics into ``stats_out`` (a last parameter), its result the number
    of outputs written.

    Parameters
    ----------
    use : str
        ``"integrate"`` or ``"integrate_dense"``.

    Returns
    -------
    source : str
        Python source of the function ``use``.
    n_stats : int
        The length of the statistics.
    """
    from ..solvers import driver_text

    if use not in USES:
        raise KeyError(f"{use!r}: not a use of the C engine ({', '.join(USES)})")
    tree, n_stats = driver_text.lower_outputs(driver_text.source(use, inline=False),
                                              TranslationError)
    fn = tree.body[0]
    assert isinstance(fn, ast.FunctionDef)
    tree.body = _allocating_entry(fn)
    return ast.unparse(ast.fix_missing_locations(tree)) + "\n", n_stats


class _AuxCount(ast.NodeTransformer):
    def visit_Name(self, node: ast.Name) -> ast.Name:
        return ast.Name("N_AUX", node.ctx) if node.id == "n_aux" else node


def _allocating_entry(fn: ast.FunctionDef) -> list[ast.stmt]:
    """``fn`` and, where it takes the work arrays of
    :func:`feeddrive.solvers.driver.step_space` (and of ``work_space``: the dense driver),
    the entry that makes them as those functions do — on the stack, as C99 arrays — and calls
    it renamed ``<name>_loop``: the C build's caller is C, no array passed through ctypes for
    them."""
    from ..solvers import driver, driver_text

    params = [a.arg for a in fn.args.args]
    made: set[str] = set()
    statements: list[ast.stmt] = []
    for maker in (driver.step_space, driver.work_space):
        work = ast.parse(driver_text._text_of(maker)).body[0]
        assert isinstance(work, ast.FunctionDef)
        result = work.body[-1]
        assert isinstance(result, ast.Return) and isinstance(result.value, ast.Tuple)
        names = {e.id for e in result.value.elts if isinstance(e, ast.Name)}
        if names <= set(params):
            made |= names
            seen = {ast.dump(st) for st in statements}  # n = y0.size once
            statements += [st for st in work.body[1:-1] if ast.dump(st) not in seen]
    if not made:
        return [fn]
    entry = ast.FunctionDef(
        name=fn.name, args=ast.arguments(posonlyargs=[], args=[
            a for a in fn.args.args if a.arg not in made], kwonlyargs=[], kw_defaults=[],
            defaults=[]), decorator_list=[], returns=None,
        body=[ast.Expr(ast.Constant(f"{fn.name}'s entry: its work arrays (feeddrive.solvers."
                                    "driver.step_space, work_space), then the driver.")),
              *(_AuxCount().visit(st) for st in statements),
              ast.Return(ast.Call(ast.Name(f"{fn.name}_loop", ast.Load()),
                                  [ast.Name(p, ast.Load()) for p in params], []))])
    fn.name = f"{fn.name}_loop"
    return [entry, fn]


def _bindings() -> dict[str, Any]:
    from ..solvers import driver, modes, rodas4, steps

    return {"rhs": RHS, "sample_update": SAMPLE_UPDATE,
            **{name: steps.function(name) for name in steps.sources()},
            "_error_norm": steps.error_norm_template,
            "_pi_factor": steps.pi_factor_template,
            "_reject_factor": steps.reject_factor_template,
            "_r4_fd_jacobian": rodas4.fd_jacobian_template,
            "_r4_frozen_states": rodas4.frozen_states_template,
            "_r4_spectral_radius": rodas4.spectral_radius_template,
            "modal_step_cap": modes.step_cap_real,
            **{name: getattr(driver, name) for name in driver.PIECES}}


#: array sizes of the driver and what it calls (``"?"``: passed at run time)
SHAPES: dict[str, tuple[str, ...]] = {
    **SOLVER_SHAPES,
    **{name: ("FD_N_STATE",) for name in ("y0", "bound", "v", "w", "scale", "all_live", "f",
                                          "f_new", "q3")},
    "J_ref": ("FD_N_STATE", "FD_N_STATE"), "held": ("FD_N_HELD",),
    **{name: (DYNAMIC,) for name in ("stops", "memory", "t_buf", STATS_OUT, "wr", "wi")},
    "y_buf": (DYNAMIC, "FD_N_STATE"), "aux_buf": (DYNAMIC, "FD_N_AUX"),
    # the outputs as the driver's pieces take them (feeddrive.solvers.driver.PIECES)
    "t_out": (DYNAMIC,), "y_out": (DYNAMIC, "FD_N_STATE"), "aux_out": (DYNAMIC, "FD_N_AUX"),
    **{name: ("FD_N_STATE", "FD_N_STATE") for name in ("ge_J", "ge_Phi", "ge_A", "ge_B")},
    "ge_w": ("FD_N_STATE",), "ge_d": ("FD_N_STATE",), "ge_aux": ("FD_N_AUX",),
    "switch_rows": (DYNAMIC, "FD_N_STATE"), "W": (DYNAMIC, "FD_N_STATE"),
    "A": (DYNAMIC, DYNAMIC), "row": ("FD_N_STATE",),
}


#: element types of the driver's and its pieces' arrays other than double (and the count
#: ``steps`` of step_attempt, not the schedule's ``steps`` of SOLVER_TYPES)
PARAM_TYPES = {**SOLVER_TYPES, "all_live": "bool*", "step_attempt.steps": "int"}


def _translated(use: str) -> dict[str, Any]:
    from ..solvers import driver_text

    if use == "functions":
        return _functions_unit()
    fn = driver_text.define(lowered_source(use)[0], use)
    text = translate_kernels([fn], {"N_AUX": "FD_N_AUX"}, bindings=_bindings(),
                             shapes=SHAPES, param_types=PARAM_TYPES,
                             names={use: f"fd_{use}"}, context=CONTEXT,
                             prologue=PROLOGUE)
    return {"c": text, "n_stats": lowered_source(use)[1], "params": _c_params(use)}


#: the shared module's functions other than the drivers that the C unit holds too
#: (``model.module.compiled(name)``, :func:`feeddrive.solvers.builds.compiled`): name →
#: (template, exported C name, sizes, element types)
FUNCTIONS: dict[str, tuple[str, str, dict[str, tuple[str, ...]], dict[str, str]]] = {
    "_ev_rates": ("feeddrive.solvers.evaluate:rates_template", "fd_ev_rates",
                  {**SOLVER_SHAPES, "held": ("FD_N_HELD",), "dy": ("FD_N_STATE",)}, {}),
    "_ev_central_columns": (
        "feeddrive.solvers.evaluate:central_columns_template", "fd_ev_central_columns",
        {**SOLVER_SHAPES, "held": ("FD_N_HELD",), "dp": ("FD_N_STATE",),
         "dm": ("FD_N_STATE",), "columns": (DYNAMIC,), "steps": (DYNAMIC,),
         "rows": (DYNAMIC,), "A": (DYNAMIC, DYNAMIC)},
        {"columns": "long*", "rows": "long*", "steps": "double*"}),
    "_r4_fd_jacobian": ("feeddrive.solvers.rodas4:fd_jacobian_template", "fd_r4_fd_jacobian",
                        {**SOLVER_SHAPES, "held": ("FD_N_HELD",)}, dict(SOLVER_TYPES)),
    "auxiliary": ("feeddrive.solvers.dopri5:auxiliary_template", "fd_auxiliary",
                  {"t_out": (DYNAMIC,), "y_out": (DYNAMIC, "FD_N_STATE"),
                   "out": (DYNAMIC, "FD_N_AUX")}, {}),
}


def _template(name: str) -> Any:
    import importlib

    module, attr = FUNCTIONS[name][0].split(":")
    return getattr(importlib.import_module(module), attr)


def _returned_array(fn: ast.FunctionDef) -> str | None:
    """The local array a template allocates and returns (``auxiliary``), if any."""
    last = fn.body[-1]
    if isinstance(last, ast.Return) and isinstance(last.value, ast.Name):
        return last.value.id
    return None


@functools.cache
def _template_result(name: str) -> tuple[str | None, bool]:
    """(the array the template behind ``name`` allocates and returns, or None; whether it
    returns a number)."""
    import inspect
    import textwrap

    template = ast.parse(textwrap.dedent(inspect.getsource(_template(name)))).body[0]
    assert isinstance(template, ast.FunctionDef)
    returns = str(_template(name).__annotations__.get("return")) not in ("None", "")
    return _returned_array(template), returns


def function_source(name: str) -> str:
    """The text of the template behind ``name`` (``FUNCTIONS``), renamed as in the shared
    module; an array it allocates and returns becomes its caller's last argument.

    Parameters
    ----------
    name : str
        A key of ``FUNCTIONS``.

    Returns
    -------
    str
        Python source.
    """
    import inspect
    import textwrap

    fn = ast.parse(textwrap.dedent(inspect.getsource(_template(name)))).body[0]
    assert isinstance(fn, ast.FunctionDef)
    fn.name = name
    result = _returned_array(fn)
    if result is not None:
        fn.body = [st for st in fn.body[:-1] if not (
            isinstance(st, ast.Assign) and len(st.targets) == 1
            and isinstance(st.targets[0], ast.Name) and st.targets[0].id == result)]
        fn.args.args.append(_array_arg(result))
        fn.returns = None
    return ast.unparse(ast.fix_missing_locations(fn)) + "\n"


def _functions_unit() -> dict[str, Any]:
    from ..solvers import driver_text

    texts, params = [], {}
    for name, (_, cname, shapes, types) in FUNCTIONS.items():
        source = function_source(name)
        fn = driver_text.define(source, name)
        fn.__globals__.update(vars(__import__(_template(name).__module__, fromlist=["_"])))
        texts.append(translate_kernels([fn], {"N_AUX": "FD_N_AUX", "N_HELD": "FD_N_HELD"},
                                       bindings={"rhs": RHS}, shapes=shapes,
                                       param_types=types, names={name: cname},
                                       context=CONTEXT, prologue=PROLOGUE))
        node = ast.parse(source).body[0]
        assert isinstance(node, ast.FunctionDef)
        params[name] = _params_of(node, shapes, types)
    return {"c": "\n".join(texts), "n_stats": 0, "params": params}


@functools.cache
def _sources_digest() -> str:
    """The hash of everything the drivers' C text is made from: the solver templates and
    kernels (:data:`feeddrive._jit.SOURCE_DIGEST`) and the translator's own files."""
    from .. import _jit

    digest = hashlib.sha256(_jit.SOURCE_DIGEST.encode())
    here = Path(__file__).resolve().parent
    for name in ("c_translate.py", "c_backend.py", "c_engine.py"):
        digest.update((here / name).read_bytes())
    return digest.hexdigest()[:20]


def _keep(name: str, text: str) -> None:
    """Keep ``text`` as the file ``name`` of the cache with its SHA-256 beside it
    (:func:`~feeddrive.backends.c_cache.keep_text`: the fallback folder when the cache cannot
    be written; each file whole or not at all): what no folder takes is made again by the next
    process."""
    keep_text(name, text)


def _kept_text(name: str) -> str | None:
    """The text of the cache's file ``name`` if it is whole — its SHA-256 the one kept beside
    it (:func:`~feeddrive.backends.c_cache.kept_text`) — marked used; None if it is not there,
    cannot be read, or was cut short or edited (then made again by the caller)."""
    text = kept_text(name)
    if text is not None:
        _FROM_CACHE.add(name)
    return text


#: the texts this process read from the cache (:func:`_kept_text`): a compilation that fails
#: on one is tried again on a fresh translation
_FROM_CACHE: set[str] = set()


@functools.cache
def driver_unit(use: str, again: bool = False) -> dict[str, Any]:
    """The driver ``use`` (:func:`lowered_source`) in C, exported as ``fd_<use>``, with every
    solver function it calls; every function takes the model's table (:data:`MODEL_STRUCT`)
    as its first parameter, reads the model's sizes from it and calls the model's ``fd_rhs``
    and ``fd_sample_update`` through it; with the entry's parameters (the table not among
    them).

    Specialising and translating the driver costs ≈ 0.7 CPU s, the same for every model: the
    result is kept in the C cache's folder under the hash of its sources
    (:func:`_sources_digest`), written whole (a temporary file renamed) or not at all, with its
    SHA-256 beside it: a kept text cut short or edited is translated again.

    Parameters
    ----------
    use : str
        ``"integrate"`` or ``"integrate_dense"`` (or ``"functions"``: :data:`FUNCTIONS`).
    again : bool, default False
        Translated anew and kept in place of the file (whose library did not compile).

    Returns
    -------
    dict
        ``"c"``: the C99 text; ``"n_stats"``: the statistics' length; ``"params"``: the
        entry's parameters as (name, kind) pairs (:func:`_c_params`).
    """
    name = f"driver-{use}-{_sources_digest()}.json"
    try:
        unit = None if again else json.loads(_kept_text(name) or "null")
    except ValueError:  # a damaged file: made again
        unit = None
    if isinstance(unit, dict) and set(unit) == {"c", "n_stats", "params"}:
        if isinstance(unit["params"], dict):
            unit["params"] = {k: [tuple(p) for p in v] for k, v in unit["params"].items()}
        else:
            unit["params"] = [tuple(p) for p in unit["params"]]
        return unit
    unit = _translated(use)
    _keep(name, json.dumps(unit))
    return unit


@functools.cache
def driver_source(again: bool = False) -> str:
    """The driver library's C unit: both drivers and the shared module's other functions
    (:data:`FUNCTIONS`), the same text for every model — compiled once per machine (per
    compiler, flags and platform) through the compiled-object cache.

    A model is reached at run time through its table (:data:`MODEL_STRUCT`), every function's
    first parameter: the sizes (``FD_N_STATE`` … are read from it, the local work arrays are
    C99 variable-length arrays) and the right-hand side and sampled update (called through
    its function pointers).

    Parameters
    ----------
    again : bool, default False
        From units translated anew (``driver_unit``), where the kept ones gave a library
        that failed.

    Returns
    -------
    str
        C99 source.
    """
    sizes = "\n".join(f"#define {macro} fd_{field}" if macro in LOCAL_SIZES else
                      f"#define {macro} ({CONTEXT[1]}->{field})"
                      for macro, field in SIZES.items())
    return ("/* Generated by feeddrive.backends.c_engine: the engine's drivers for every model "
            "(feeddrive.solvers.driver, lowered and translated).  Do not edit: regenerate. */"
            "\n#include <math.h>\n" + MODEL_STRUCT + "/* the model's sizes, read from its "
            "table (every function's first parameter) */\n" + sizes + "\n"
            + "\n".join(driver_unit(use, again)["c"] for use in (*USES, "functions")))


def model_source(model: Model) -> str:
    """The model library's C unit: ``model``'s kernels (parameters and tables passed at run
    time; :func:`feeddrive.backends.c_backend.c_model_source`) and its table
    ``fd_model_table`` (:data:`MODEL_STRUCT`: its sizes, ``fd_rhs``, ``fd_sample_update``),
    which the driver library's entries take.

    Parameters
    ----------
    model : Model
        The assembled model.

    Returns
    -------
    str
        C99 source.
    """
    fields = ", ".join(SIZES)
    return (c_model_source(model, data=False) + MODEL_STRUCT
            + f"/* the model as the driver library (feeddrive.backends.c_engine) reaches it */"
            f"\nconst fd_model {TABLE} = {{{fields}, fd_rhs, fd_sample_update}};\n")


#: the generated modules' names (:func:`feeddrive.model.codegen.compile_module`): a hash of
#: their text, the package's kernels and a registered law's kernel source
_GENERATED = "feeddrive_model_"


def _model_text(model: Model, again: bool = False) -> str:
    """:func:`model_source` of ``model``, kept in the cache folder as
    ``model-<hash>.c`` under a hash of what it is made from: the generated module's name (a
    hash of its text, the package's kernels and a registered law's kernel), the translator's
    sources (:func:`_sources_digest`) and the model's sizes.  Translating costs 30–60 ms per
    model structure and process (≈ 1 CPU s of a warm ``reproduce``); the file is written whole
    (a temporary file renamed) or not at all, with its SHA-256 beside it (a kept text cut
    short or edited is translated again), and a model whose module was not generated by
    :func:`~feeddrive.model.codegen.compile_module` is translated every time.  ``again``:
    translated anew and kept in place of the file (whose library failed: damaged)."""
    name = _model_file(model)
    if name is None:
        return model_source(model)
    text = None if again else _kept_text(name)
    if text is not None:
        return text
    text = model_source(model)
    _keep(name, text)
    return text


def _model_file(model: Model) -> str | None:
    """The name :func:`_model_text` keeps ``model``'s text under, ``model-<hash>.c``; None for
    a model whose module was not generated (its text is not kept)."""
    module = model.module
    name = str(getattr(module, "__name__", ""))
    if not name.startswith(_GENERATED):
        return None
    what = (name, _sources_digest(), model.drive, len(model.states), len(model.aux),
            int(module.N_HELD), int(module.N_CLOCK), int(model.P.size), int(model.T.size))
    return f"model-{hashlib.sha256(repr(what).encode()).hexdigest()[:24]}.c"


#: the file names a compiler's message gives the two libraries' texts (their temporary
#: folder is gone when it is read); a model's kept text is named by its path
DRIVER_FILE, MODEL_FILE = "driver.c", "model.c"


def _library_of(text_of: Callable[[bool], str], symbols: Sequence[str], flags: Sequence[str],
                name: str, shown: Callable[[], str | None], what: str
                ) -> tuple[ctypes.CDLL, str]:
    """The library compiled from ``text_of(False)`` (through the cache), loaded, holding every
    one of ``symbols``, and the text it was compiled from.  Compiled from ``text_of(True)``
    (translated anew, kept in place of a damaged kept text) where the first fails to
    compile; and where the library loaded lacks one of ``symbols`` (a damaged library whose
    digest matches), that library is compiled again, once, from a fresh translation — each
    said in one line on standard error.  ``name``, ``shown``: as :func:`~feeddrive.backends.
    c_cache.cached_library` takes them (``shown()`` the kept text's path, or None); ``what``:
    the kept text, for a note where ``shown()`` gives none."""
    text = text_of(False)
    try:
        path = cached_library(text, flags=flags, name=name, shown=shown())
    except CompileError:
        fresh = text_of(True)  # a kept text damaged?
        if fresh == text:
            raise
        print(f"feeddrive: {shown() or what} did not compile: translated again",
              file=sys.stderr)
        text = fresh
        path = cached_library(text, flags=flags, name=name, shown=shown())
    lib = ctypes.CDLL(str(path))
    missing = _missing(lib, symbols)
    if missing is None:
        return lib, text
    print(f"feeddrive: {path} lacks {missing} (damaged), so it is compiled again",
          file=sys.stderr)
    _unload(lib)  # the same path is loaded again below: dlopen would return this one
    fresh = text_of(True)
    path = cached_library(fresh, flags=flags, name=name, shown=shown(), again=fresh == text)
    lib = ctypes.CDLL(str(path))
    missing = _missing(lib, symbols)
    if missing is not None:
        raise RuntimeError(f"{path}: the C library compiled from a fresh translation lacks "
                           f"{missing} (a defect of the C engine)")
    return lib, fresh


def _missing(lib: ctypes.CDLL, symbols: Sequence[str]) -> str | None:
    """The first of ``symbols`` that ``lib`` does not define, or None."""
    for symbol in symbols:
        try:
            ctypes.c_char.in_dll(lib, symbol)
        except ValueError:
            return symbol
    return None


def _unload(lib: ctypes.CDLL) -> None:
    """Unload ``lib`` (nothing of it in use), so that a library compiled again under its path
    is loaded, not this one."""
    import _ctypes

    close = getattr(_ctypes, "dlclose", None) or getattr(_ctypes, "FreeLibrary", None)
    if close is not None:
        with contextlib.suppress(OSError):
            close(lib._handle)


#: why the C build does not run where a C ``long`` is 32 bits (64-bit Windows): the engine
#: passes numpy's 64-bit integer arrays as ``long *``
LONG_32 = ("the C engine passes 64-bit integers as C long, which has 32 bits on this "
           "platform (64-bit Windows)")
_D = ctypes.POINTER(ctypes.c_double)
_L = ctypes.POINTER(ctypes.c_long)
_B = ctypes.POINTER(ctypes.c_ubyte)
_ELEM = {"double*": (_D, np.float64), "long*": (_L, np.int64), "bool*": (_B, np.bool_)}
_KINDS = {"double*": "f", "long*": "iu", "bool*": "biu"}  # element kinds of that size taken


def _c_params(use: str) -> list[tuple[str, str]]:
    """(name, kind) of the C entry's parameters in order: kind "double", "long", "int" or an
    array type of :data:`_ELEM`, then its run-time sizes as ("name#k", "size")."""
    source, _ = lowered_source(use)
    fn = ast.parse(source).body[0]  # the entry
    assert isinstance(fn, ast.FunctionDef) and fn.name == use
    return _params_of(fn, SHAPES, PARAM_TYPES)


def _params_of(fn: ast.FunctionDef, shapes: dict[str, tuple[str, ...]],
               types: dict[str, str]) -> list[tuple[str, str]]:
    out: list[tuple[str, str]] = []
    for a in fn.args.args:
        spec = (types.get(f"{fn.name}.{a.arg}") or types.get(a.arg)
                or (ast.unparse(a.annotation) if a.annotation else ""))
        if spec in ("np.ndarray", "double*", "long*", "bool*"):
            out.append((a.arg, "double*" if spec == "np.ndarray" else spec))
            out += [(f"{a.arg}#{k}", "size") for k, d in enumerate(shapes.get(a.arg, ()))
                    if d == DYNAMIC]
        else:
            out.append((a.arg, {"float": "double", "int": "long", "bool": "int"}[spec]))
    return out


_ARRAY, _SIZE, _DOUBLE, _INT = range(4)

#: the stack a call may need before it runs on a thread of its own (:func:`stack_need`).  The
#: C build keeps its work arrays on the stack, as C99 variable-length arrays — the Jacobian,
#: the iteration matrix, the modal reference and the eigen-analysis' matrix, ≈ 32 n² bytes
#: for n states, twice that with the embedded error estimate — and a thread's stack is what
#: the platform gives (8 MiB on Linux, less elsewhere and in some hosts): a 34-axis machine
#: (510 states) overflowed it and the process died (an outside check, 2026-12-07)
STACK_OWN_THREAD = 512 * 1024


def stack_need(n_state: int, n_aux: int) -> int:
    """Bytes of stack the work arrays of a call of a model may take: 16 matrices of
    (n + 2)² doubles and 64 vectors, twice what the drivers declare.  Above
    :data:`STACK_OWN_THREAD` the call gets a thread of its own, with this much and 1 MiB more
    (:func:`thread_stack`).

    Parameters
    ----------
    n_state : int
        The model's states n.
    n_aux : int
        Its auxiliary signals.

    Returns
    -------
    int
        Bytes.
    """
    return 8 * (16 * (n_state + 2) ** 2 + 64 * (n_state + n_aux + 2))


def thread_stack(need: int) -> int:
    """The stack of the thread of a call: 1 MiB more than it needs, in whole MiB.

    Parameters
    ----------
    need : int
        Bytes the call's arrays may take (:func:`stack_need`).

    Returns
    -------
    int
        Bytes of stack, a multiple of 1 MiB.
    """
    return -(-(need + (1 << 20)) // (1 << 20)) * (1 << 20)


_STACK_SIZE_LOCK = threading.Lock()  # threading.stack_size is the process's setting


def on_own_stack(fn: Callable[..., Any], args: Sequence[Any], size: int,
                 memory: np.ndarray | None = None) -> Any:
    """``fn(*args)`` on a new thread with ``size`` bytes of stack, the caller waiting.

    The compiled call releases the GIL; Ctrl-C while waiting (KeyboardInterrupt in the
    caller) asks a driver to stop after its step (``memory[-2]``, as
    :meth:`feeddrive.engine.simulate.Simulation.request_stop` does), waits for it to return
    and raises on.  Waiting is on an event, not ``Thread.join``, which an interrupt can leave
    claiming the thread ended (CPython 3.11).

    Parameters
    ----------
    fn : callable
        The call (a ctypes function).
    args : sequence
        Its arguments.
    size : int
        Bytes of stack of the thread (:func:`thread_stack`).
    memory : numpy.ndarray, optional
        A driver's memory, whose ``[-2]`` asks it to stop.

    Returns
    -------
    object
        What ``fn`` returned; what it raised is raised here.
    """
    box: dict[str, Any] = {}
    done = threading.Event()

    def run() -> None:
        try:
            box["value"] = fn(*args)
        except BaseException as err:  # handed to the caller
            box["error"] = err
        finally:
            done.set()

    with _STACK_SIZE_LOCK:
        before = threading.stack_size(size)
        try:
            worker = threading.Thread(target=run, name="feeddrive-c-call", daemon=True)
            worker.start()
        finally:
            threading.stack_size(before)
    try:
        while not done.wait(0.25):
            pass
    except KeyboardInterrupt:
        if memory is not None:
            memory[-2] = 1.0
        done.wait()
        raise
    if "error" in box:
        raise box["error"]
    return box["value"]


class _Entry:
    """One exported function of the driver library for one model, called with numpy arrays:
    the model's table first (its address), then each array passed by its address
    (``c_void_p``; ≈ 3 µs an array, where ``data_as`` costs 5), checked to be C-contiguous
    with elements of the C type's kind and size."""

    def __init__(self, lib: ctypes.CDLL, use: str, table: int, again: bool = False,
                 stack: int = 0) -> None:
        if use in FUNCTIONS:
            self.params = driver_unit("functions", again)["params"][use]
            self.n_stats = 0
            self.fn = getattr(lib, FUNCTIONS[use][1])
        else:
            unit = driver_unit(use, again)
            self.params = unit["params"]
            self.n_stats = unit["n_stats"]
            self.fn = getattr(lib, f"fd_{use}")
        self.fn.restype = ctypes.c_long
        self.table = table
        self.names = [name for name, kind in self.params if kind != "size"]
        where = {name: i for i, name in enumerate(self.names)}
        # a large model's call runs on a thread with the stack it needs (STACK_OWN_THREAD);
        # a driver's memory carries its stop request
        self.stack = thread_stack(stack) if stack > STACK_OWN_THREAD else 0
        self.stop_at = where.get("memory") if use in ("integrate", "integrate_dense") else None
        # (what, which argument, dimension or accepted element type)
        self.plan: list[tuple[int, int, Any]] = []
        argtypes: list[Any] = [ctypes.c_void_p]  # the model's table
        for name, kind in self.params:
            if kind == "size":
                base, k = name.split("#")
                self.plan.append((_SIZE, where[base], int(k)))
                argtypes.append(ctypes.c_long)
            elif kind in _ELEM:
                self.plan.append((_ARRAY, where[name], kind))
                argtypes.append(ctypes.c_void_p)
            elif kind == "double":
                self.plan.append((_DOUBLE, where[name], None))
                argtypes.append(ctypes.c_double)
            else:
                self.plan.append((_INT, where[name], None))
                argtypes.append(ctypes.c_int if kind == "int" else ctypes.c_long)
        self.fn.argtypes = argtypes
        self._accepted: dict[tuple[np.dtype[Any], str], bool] = {}
        self._last: list[tuple[Any, int] | None] = [None] * len(self.names)
        self.keep = use in FUNCTIONS and use != "auxiliary"

    def _check(self, a: Any, kind: str, position: int) -> None:
        key = (a.dtype, kind)
        ok = self._accepted.get(key)
        if ok is None:
            dtype = np.dtype(_ELEM[kind][1])
            ok = self._accepted[key] = a.dtype == dtype or (
                a.dtype.itemsize == dtype.itemsize and a.dtype.kind in _KINDS[kind])
        if not (ok and a.flags.c_contiguous):
            raise TypeError(f"{self.names[position]}: a C-contiguous "
                            f"{np.dtype(_ELEM[kind][1]).name} array is expected, not "
                            f"{a.dtype} {a.shape}")

    def positional(self, args: Sequence[Any]) -> int:
        """Call with the arguments in the order of :attr:`names`.

        With :attr:`keep` (the linearisations' functions, whose arrays are small), the
        array passed last at each position is kept with its address: a caller that passes
        the same arrays call after call (thousands of calls) pays the address and the check
        once.  Kept, an array cannot be freed, so no other array can take its place under
        the same identity.  The drivers and ``auxiliary`` keep nothing (their output arrays
        are the run's, megabytes), their calls being few."""
        out: list[Any] = [self.table]
        last = self._last
        for what, i, extra in self.plan:
            a = args[i]
            if what == _ARRAY:
                seen = last[i]
                if seen is not None and seen[0] is a:
                    out.append(seen[1])
                    continue
                self._check(a, extra, i)
                address = a.ctypes.data
                if self.keep:
                    last[i] = (a, address)
                out.append(address)
            elif what == _SIZE:
                out.append(a.shape[extra])
            elif what == _DOUBLE:
                out.append(float(a))
            else:
                out.append(int(a))
        if self.stack:
            return int(on_own_stack(self.fn, out, self.stack,
                                    None if self.stop_at is None else args[self.stop_at]))
        return int(self.fn(*out))

    def __call__(self, values: dict[str, Any]) -> int:
        return self.positional([values[name] for name in self.names])


class CEngine:
    """The C build: one driver library for every model (:func:`driver_source`) and per model
    structure one library of its kernels (:func:`model_source`); the drivers called with the
    model's table and the arguments, in the order, of the numba ones
    (:mod:`feeddrive.solvers.shared`) and giving the same results."""

    name = "c"

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._driver_lock = threading.Lock()
        self._drivers: ctypes.CDLL | None = None
        self._drivers_again = False  # the driver library is of units translated anew
        self._libraries: dict[str, tuple[ctypes.CDLL, int]] = {}
        self._entries: dict[tuple[int, str], _Entry] = {}
        self._functions: dict[tuple[int, str], Callable[..., Any]] = {}
        self._compiler: dict[tuple[str | None, str | None], bool] = {}
        self._said_long: list[bool] = []

    def available(self, required: bool = False, quiet: bool = False) -> bool:
        """Whether a C compiler is found (without one,
        :data:`~feeddrive.backends.c_cache.NO_COMPILER` is said once per process, unless
        ``quiet``).

        Parameters
        ----------
        required : bool, default False
            ``FEEDDRIVE_ENGINE=c``: no compiler is an error.
        quiet : bool, default False
            Say nothing (the caller says it once it knows the numba build runs).

        Returns
        -------
        bool
            True with a compiler.

        Raises
        ------
        CompilerNotFound
            With ``required`` and no compiler: one line saying how to get one.
        """
        if ctypes.sizeof(ctypes.c_long) != ctypes.sizeof(ctypes.c_int64):
            if required:
                raise CompilerNotFound(f"FEEDDRIVE_ENGINE = 'c': {LONG_32}; unset it to use "
                                       "numba")
            if not quiet and not self._said_long:
                self._said_long.append(True)
                print(f"feeddrive: {LONG_32}, so the numba build is used", file=sys.stderr)
            return False
        where = (os.environ.get("CC"), os.environ.get("PATH"))  # asked once per setting
        if required:
            try:
                find_compiler()
            except CompilerNotFound as err:
                raise CompilerNotFound(f"FEEDDRIVE_ENGINE = 'c': {err}; or unset it to use "
                                       "numba") from None
            return True
        found = self._compiler.get(where)
        if found is None:
            try:
                find_compiler()
                found = True
            except CompilerNotFound:
                found = False
            self._compiler[where] = found
        if not found and not quiet:
            available_compiler()  # says NO_COMPILER, once per process
        return found

    def translates(self, model: Model, required: bool = False) -> bool:
        """Whether ``model``'s kernels are inside the C subset (a friction law or part defined
        outside the package may not be: docs/c-backend.md); if not, numba runs that model,
        said once per model structure in one line on standard error.

        Parameters
        ----------
        model : Model
            The assembled model.
        required : bool, default False
            ``FEEDDRIVE_ENGINE=c``: a kernel outside the subset is an error.

        Returns
        -------
        bool
            True when the C build runs it.

        Raises
        ------
        TranslationError
            With ``required``: the kernel, file, line and construct, in one line.
        """
        module = model.module
        refused = getattr(module, "_fd_c_refused", None)
        if refused is None:
            try:
                self._library(model)
                refused = ""
            except TranslationError as err:
                if required:
                    raise
                refused = str(err).splitlines()[0]
                print(f"feeddrive: this model runs in the numba build ({refused})",
                      file=sys.stderr)
            setattr(module, "_fd_c_refused", refused)  # noqa: B010 (a generated module)
        if refused and required:
            raise TranslationError(refused)
        return not refused

    def _driver_library(self) -> ctypes.CDLL:
        """The driver library (:func:`driver_source`), the same for every model: compiled
        once per machine, loaded once per process; compiled from units translated anew where
        the kept ones do not compile, or give a library without its entries
        (:func:`_library_of`)."""
        lib = self._drivers
        if lib is None:
            with self._driver_lock:
                lib = self._drivers
                if lib is None:
                    def text_of(again: bool) -> str:
                        # anew only if a kept unit was read: else it would be the same text
                        fresh = again and any(n.startswith("driver-") for n in _FROM_CACHE)
                        self._drivers_again = self._drivers_again or fresh
                        return driver_source(fresh)

                    symbols = [*(f"fd_{use}" for use in USES),
                               *(cname for _, cname, _, _ in FUNCTIONS.values())]
                    what = f"the kept driver texts (driver-*-{_sources_digest()}.json)"
                    lib = self._drivers = _library_of(text_of, symbols, DRIVER_FLAGS,
                                                      DRIVER_FILE, lambda: None, what)[0]
        return lib

    def _library(self, model: Model) -> tuple[ctypes.CDLL, int]:
        """``model``'s library (:func:`model_source`) and the address of its table, the
        driver library loaded too; the table's sizes checked against the model's."""
        module = model.module
        found: tuple[ctypes.CDLL, int] | None = getattr(module, "_fd_c_engine", None)
        if found is not None:
            return found
        self._driver_library()
        with self._lock:
            found = getattr(module, "_fd_c_engine", None)
            if found is None:
                text = _model_text(model)
                key = hashlib.sha256(text.encode()).hexdigest()
                found = self._libraries.get(key)
                if found is None:
                    def shown() -> str | None:  # the kept text, whose lines a message counts
                        name = _model_file(model)
                        path = kept(name) if name is not None else None
                        return str(path) if path is not None else None

                    lib, text = _library_of(
                        lambda again: _model_text(model, again=True) if again else text,
                        [TABLE], LIBRARY_FLAGS, MODEL_FILE, shown, "the model's kept text")
                    key = hashlib.sha256(text.encode()).hexdigest()
                    table = ModelTable.in_dll(lib, TABLE)
                    expected = (len(model.states), len(model.aux), int(module.N_HELD),
                                int(module.N_CLOCK))
                    got = (table.n_state, table.n_aux, table.n_held, table.n_clock)
                    if got != expected:
                        raise RuntimeError(f"the C library of this model has the sizes {got} "
                                           f"(states, auxiliary signals, held values, clocks)"
                                           f", not the model's {expected}")
                    found = self._libraries[key] = (lib, ctypes.addressof(table))
                setattr(module, "_fd_c_engine", found)  # noqa: B010 (a generated module)
        return found

    def _entry(self, model: Model, use: str) -> _Entry:
        lib, table = self._library(model)
        key = (id(lib), use)
        entry = self._entries.get(key)
        if entry is None:
            entry = self._entries[key] = _Entry(self._driver_library(), use, table,
                                                self._drivers_again,
                                                stack_need(len(model.states), len(model.aux)))
        return entry

    def function(self, model: Model, name: str) -> Callable[..., Any] | None:
        """The C function ``name`` of ``model`` (a key of ``FUNCTIONS``), taking the
        arguments of ``model.module.compiled(name)`` and returning what it returns; None for
        a function the C unit does not hold.

        Parameters
        ----------
        model : Model
            The assembled model.
        name : str
            A function of the shared drivers' module.

        Returns
        -------
        callable or None
            The function.
        """
        if name not in FUNCTIONS:
            return None
        entry = self._entry(model, name)
        key = (id(entry), name)
        done = self._functions.get(key)
        if done is not None:
            return done
        result, returns = _template_result(name)
        n_aux = len(model.aux)
        positional = entry.positional

        if result is not None:  # auxiliary: the (samples, N_AUX) array it returns
            def call(*args: Any) -> Any:
                out = np.empty((len(args[0]), n_aux))
                positional([*args, out])
                return out
        elif returns:
            def call(*args: Any) -> Any:
                return positional(args)
        else:
            def call(*args: Any) -> Any:
                positional(args)
        self._functions[key] = call
        return call

    def driver(self, model: Model, use: str) -> Callable[..., Any]:
        """The C driver ``use`` of ``model``, taking the numba driver's arguments and
        returning what it returns: ``(t_out, y_out, aux_out, stats, held)``.

        Parameters
        ----------
        model : Model
            The assembled model.
        use : str
            ``"integrate"`` or ``"integrate_dense"``.

        Returns
        -------
        callable
            The driver.
        """
        from ..solvers import driver as template
        from ..solvers import shared

        entry = self._entry(model, use)
        if shared.preparing():  # inside prepared_models: the library built, nothing run
            raise shared.ModelPrepared(use)
        names = template.USES[use][0]
        n_state, n_aux = len(model.states), len(model.aux)

        def call(*args: Any) -> tuple[np.ndarray, ...]:
            values = dict(zip(names, args, strict=True))
            n_break = int(round(values["t_end"] / values["base"]))
            n_out = max(0, (n_break - values["start"]) // values["out_every"] + 1)
            n_aux_out = n_out if values.get("want_aux", True) else 0
            t_buf, y_buf, aux_buf = (values.get(b) for b in OUTPUTS.values())
            if not (t_buf is not None and y_buf is not None and aux_buf is not None
                    and t_buf.shape[0] >= n_out and y_buf.shape[0] >= n_out
                    and y_buf.shape[1] == n_state and aux_buf.shape[0] >= n_aux_out
                    and aux_buf.shape[1] == n_aux):
                t_buf = np.empty(n_out)
                y_buf = np.empty((n_out, n_state))
                aux_buf = np.empty((n_aux_out, n_aux))
            values.update(t_buf=t_buf, y_buf=y_buf, aux_buf=aux_buf)
            stats = np.zeros(entry.n_stats)
            values[STATS_OUT] = stats
            count = entry(values)
            return (t_buf[:count], y_buf[:count], aux_buf[:min(count, aux_buf.shape[0])],
                    stats, values["held"])

        return call


registry.register(registry.ENGINES, CEngine.name, CEngine())
