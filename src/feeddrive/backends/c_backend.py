"""The C backend: the assembled model's right-hand side, sampled-controller update and
auxiliary outputs as one standalone C99 file, translated from the same kernels numba compiles.

:func:`c_model_source` reads the generated module of a :class:`~feeddrive.model.assemble.Model`
(its ``rhs`` and ``sample_update``) and translates them and every kernel they call with
:func:`feeddrive.backends.c_translate.translate_kernels` — no equation is written a second time
(docs/c-backend.md explains the mechanism and the subset a kernel must stay in).  The file
needs only ``<math.h>``, ``<string.h>`` and ``<stdlib.h>`` and exports::

    #define FD_N_STATE, FD_N_AUX, FD_N_HELD, FD_N_PARAM, FD_N_TABLE
    #define FD_N_CLOCK
    void fd_rhs(double t, const double *y, double *held, const double *P, const double *T,
                double *dy, double *aux);
    void fd_sample_update(double t, double *y, double *held, const double *P,
                          const double *T, const long *tick);
    void fd_aux(double t, const double *y, double *held, const double *P, const double *T,
                double *aux);
    extern const double fd_parameters[FD_N_PARAM], fd_tables[FD_N_TABLE];  (data=True)
    extern const char *const fd_state_names[FD_N_STATE], *const fd_aux_names[...],
                          *const fd_parameter_names[FD_N_PARAM];

with the arguments of the numba ``model.module.rhs`` / ``sample_update`` (a sampled part reads
its period from ``P``; ``tick``: per clock of the model's sample schedule, the count of its
instant now or −1, :mod:`feeddrive.solvers.schedule`).
:func:`compile_shared` builds a shared library with the system's C compiler and
:func:`load_shared` wraps it with ctypes (used by the tests); :func:`load_cached` does both
through the compiled-object cache (:mod:`feeddrive.backends.c_cache`).
"""

from __future__ import annotations

import ctypes
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .c_cache import CompileError, CompilerNotFound, cached_library, compile_c, find_compiler
from .c_translate import CFunction, TranslationError, _Unit, c_text, translate_kernels

if TYPE_CHECKING:
    from ..model.assemble import Model

__all__ = ["RHS", "SAMPLE_UPDATE", "CFunction", "CLibrary", "CompileError", "CompilerNotFound",
           "SOLVER_SHAPES", "SOLVER_TYPES", "TranslationError",
           "c_model_source", "c_solver_source", "solver_kernels",
           "compile_shared", "find_compiler", "load_cached", "load_shared", "translate_kernels",
           "STRICT_FLAGS"]

#: the warnings the generated C is compiled clean with (tests compile with them)
STRICT_FLAGS = ("-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic")

_GENERATED_TYPES = {
    **{f"rhs.{k}": v for k, v in (("t", "float"), ("y", "double*"), ("held", "double*"),
                                  ("P", "double*"), ("T", "double*"), ("dy", "double*"),
                                  ("aux", "double*"))},
    **{f"sample_update.{k}": v for k, v in (("t", "float"), ("y", "double*"),
                                            ("held", "double*"), ("P", "double*"),
                                            ("T", "double*"), ("tick", "long*"))},
}


def _c_string(text: str) -> str:
    out = text.encode("utf-8").decode("ascii", "backslashreplace")
    return '"' + out.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _c_doubles(values: np.ndarray) -> str:
    items = [repr(float(v)) if np.isfinite(v) else ("NAN" if np.isnan(v) else
                                                   ("HUGE_VAL" if v > 0 else "-HUGE_VAL"))
             for v in np.asarray(values, dtype=float).ravel()]
    lines = []
    for i in range(0, len(items), 6):
        lines.append("    " + ", ".join(items[i:i + 6]) + ",")
    return "\n".join(lines) if lines else "    0.0,"


def c_model_source(model: Model, *, data: bool = True) -> str:
    """One self-contained C99 file of ``model``'s right-hand side, sampled-controller update
    and auxiliary outputs (module docstring for the exported names).

    Parameters
    ----------
    model
        An assembled model (``DriveSystem.model(profile)``); its generated numba module is
        translated, with every kernel it calls.
    data
        Include ``fd_parameters`` and ``fd_tables`` (``model.P`` and ``model.T``, full
        ``repr`` precision).  Without them the host passes its own P and T; a long sampled
        profile's table can be megabytes of C text.

    Returns
    -------
    str
        C99 source.

    Raises
    ------
    TranslationError
        A kernel of the model uses a construct outside the C backend's subset.
    """
    module = model.module
    # a machine's axes run in functions of their own (Builder.scope): _rhs_<axis> and
    # _sample_<axis> take the arguments of rhs and sample_update
    types = dict(_GENERATED_TYPES)
    for name in vars(module):
        for prefix, entry in (("_rhs_", "rhs."), ("_sample_", "sample_update.")):
            if name.startswith(prefix):
                types.update({f"{name}.{k.removeprefix(entry)}": v
                              for k, v in _GENERATED_TYPES.items() if k.startswith(entry)})
    unit = _Unit(constants={}, bindings={}, shapes={}, param_types=types)
    rhs = unit.function(module.rhs.py_func, "fd_model_rhs")
    upd = unit.function(module.sample_update.py_func, "fd_model_sample_update")
    n_state, n_aux, n_held = len(model.states), len(model.aux), int(module.N_HELD)
    n_param, n_table = int(model.P.size), int(model.T.size)
    head = [
        f"/* Generated by feeddrive.backends.c_backend from the kernels of one assembled model "
        f"({model.drive}; {n_state} states).  Do not edit: regenerate. */",
        f"#define FD_N_STATE {n_state}",
        f"#define FD_N_AUX {n_aux}",
        f"#define FD_N_HELD {n_held}",
        f"#define FD_N_CLOCK {int(module.N_CLOCK)}",
        f"#define FD_N_PARAM {n_param}",
        f"#define FD_N_TABLE {n_table}",
    ]
    body = c_text(unit)
    rhs_args = "t, y, held, P, T, dy, aux"
    upd_args = "t, y, held, P, T, tick"
    tail = [
        "void fd_rhs(double t, const double *y, double *held, const double *P, const double *T,"
        "\n            double *dy, double *aux);",
        "void fd_sample_update(double t, double *y, double *held, const double *P,"
        "\n                      const double *T, const long *tick);",
        "void fd_aux(double t, const double *y, double *held, const double *P, const double *T,"
        "\n            double *aux);",
        "",
        "/* dy = f(t, y) and the auxiliary signals; held: the sampled controller's values */",
        "void fd_rhs(double t, const double *y, double *held, const double *P, const double *T,"
        "\n            double *dy, double *aux)\n{\n"
        f"    {rhs.cname}({rhs_args});\n}}",
        "",
        "/* the sampled parts at an instant of the schedule (tick: per clock its count, or -1):"
        " updates held */",
        "void fd_sample_update(double t, double *y, double *held, const double *P,"
        "\n                      const double *T, const long *tick)\n{\n"
        f"    {'(void)y; ' if 'y' not in upd.written else ''}{upd.cname}({upd_args});\n}}",
        "",
        "/* the auxiliary signals alone */",
        "void fd_aux(double t, const double *y, double *held, const double *P, const double *T,"
        "\n            double *aux)\n{\n"
        "    double dy[FD_N_STATE];\n"
        f"    {rhs.cname}(t, y, held, P, T, dy, aux);\n}}",
        "",
        *(["const double fd_parameters[FD_N_PARAM] = {\n" + _c_doubles(model.P) + "\n};",
           "const double fd_tables[FD_N_TABLE] = {\n" + _c_doubles(model.T) + "\n};"]
          if data else []),
        "const char *const fd_state_names[FD_N_STATE] = {\n"
        + ",\n".join("    " + _c_string(n) for n in model.state_names) + "\n};",
        f"const char *const fd_aux_names[{max(1, n_aux)}] = {{\n"
        + (",\n".join("    " + _c_string(a.name) for a in model.aux) or '    ""') + "\n};",
        "const char *const fd_parameter_names[FD_N_PARAM] = {\n"
        + ",\n".join("    " + _c_string(n) for n in model.parameter_names) + "\n};",
    ]
    return "\n".join(head) + "\n" + body + "\n" + "\n".join(tail) + "\n"


#: array sizes of the solver building blocks' parameters, as C expressions of the model file
SOLVER_SHAPES: dict[str, tuple[str, ...]] = {
    **{name: ("FD_N_STATE",) for name in (
        "y", "k1", "k2", "k3", "k4", "k5", "k6", "k7", "yt", "y_new", "e", "atol", "rel_mask",
        "f0", "ft", "yp", "fp", "live", "piv", "b", "u1", "u2", "u3", "u4", "u5", "u6", "fs",
        "q1", "q2", "out", "d", "w", "scale")},
    "J": ("FD_N_STATE", "FD_N_STATE"), "M": ("FD_N_STATE", "FD_N_STATE"),
    # the embedded global-error estimate's (feeddrive.solvers.global_error)
    "Phi": ("FD_N_STATE", "FD_N_STATE"), "Phi_a": ("FD_N_STATE", "FD_N_STATE"),
    "Phi_b": ("FD_N_STATE", "FD_N_STATE"),
    "S": ("FD_N_STATE", "FD_N_STATE + 1"), "colour": ("FD_N_STATE + 1",), "aux": ("FD_N_AUX",),
    "steps": ("FD_N_CLOCK",), "schedule": ("FD_N_CLOCK",), "tick": ("FD_N_CLOCK",),
}
#: ``fd_rhs`` as a translated template calls it (``bindings={"rhs": RHS}``): the arrays at
#: positions 2, 5, 6 (held — non-const in the API —, dy, aux) are written, y, P, T stay const
RHS = CFunction("fd_rhs", None, (2, 5, 6))
#: ``fd_sample_update`` likewise: y (non-const in the API) and held
SAMPLE_UPDATE = CFunction("fd_sample_update", None, (1, 2))
#: element types of the solver building blocks' non-double arrays (numpy ``int64`` / ``bool_``)
SOLVER_TYPES = {"piv": "long*", "live": "bool*", "S": "bool*", "colour": "long*",
                "steps": "long*", "schedule": "long*", "tick": "long*"}


def solver_kernels() -> dict[str, Any]:
    """The project's solver building blocks by exported C name.

    Returns
    -------
    dict
        C name → Python template: one DOPRI5 step, its error estimate and norm, and the
        RODAS4 step with its grouped finite-difference Jacobian, frozen-state test and dense
        output (the steps of :mod:`feeddrive.solvers.steps` written for the tableaux of
        :mod:`feeddrive.solvers.tableaux`; :mod:`feeddrive.solvers.rodas4`).
    """
    from ..solvers import rodas4, steps

    return {"fd_dp5_step": steps.function("_dp5_step"),
            "fd_dp5_error": steps.function("_dp5_error"),
            "fd_error_norm": steps.error_norm_template,
            "fd_fd_jacobian": rodas4.fd_jacobian_template,
            "fd_frozen_states": rodas4.frozen_states_template,
            "fd_rodas4_step": steps.function("_r4_rodas4_step"),
            "fd_rodas4_dense": steps.function("_r4_rodas4_dense")}


def c_solver_source(names: tuple[str, ...] | None = None) -> str:
    """C99 text of the solver building blocks (:func:`solver_kernels`), translated from the
    package's own solver code with ``rhs`` bound to ``fd_rhs``; append it to
    :func:`c_model_source` (it uses that file's ``FD_N_*`` sizes and ``fd_rhs``).

    Parameters
    ----------
    names
        Exported C names to include (default: all of :func:`solver_kernels`).

    Returns
    -------
    str
        C99 source; the exported functions keep the Python templates' argument order, arrays
        as pointers (``const`` where the template only reads them; ``piv`` and ``colour`` are
        ``long *``, ``live`` and ``S`` ``unsigned char *``, ``J``/``M``/``S`` row-major).
    """
    kernels = solver_kernels()
    chosen = tuple(kernels) if names is None else names
    unknown = [n for n in chosen if n not in kernels]
    if unknown:
        raise ValueError(f"names = {unknown}: expected some of {', '.join(kernels)}")
    return translate_kernels([kernels[n] for n in chosen], {"N_AUX": "FD_N_AUX"},
                             bindings={"rhs": RHS}, shapes=SOLVER_SHAPES,
                             param_types=SOLVER_TYPES,
                             names={kernels[n].__name__: n for n in chosen})


def compile_shared(c_text: str, folder: str | os.PathLike[str], *, name: str = "fd_model",
                   strict: bool = True, optimise: str = "-O1") -> Path:
    """Compile ``c_text`` into a shared library ``folder/<name>.so`` (``.dll`` on Windows)
    with a gcc-compatible compiler (gcc, clang, MinGW; :func:`find_compiler`).

    Parameters
    ----------
    c_text
        C99 source (:func:`c_model_source`).
    folder
        Existing or new folder for the ``.c`` file and the library.
    name
        File stem.
    strict
        Compile with :data:`STRICT_FLAGS` (warnings are errors).
    optimise
        Optimisation flag.  ``-ffp-contract=off`` is always passed: a fused multiply-add
        would round differently from numba.

    Returns
    -------
    Path
        The shared library.

    Raises
    ------
    CompilerNotFound
        No C compiler (see :func:`find_compiler`).
    CompileError
        The compiler failed (a RuntimeError; one line with its first error line, its whole
        output in ``output``).
    """
    flags = [*(STRICT_FLAGS if strict else ("-std=c99",)), optimise, "-ffp-contract=off",
             "-fPIC", "-shared"]
    return compile_c({f"{name}.c": c_text}, folder,
                     f"{name}.dll" if os.name == "nt" else f"{name}.so", find_compiler(), flags,
                     ("-lm",))


_DP = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")
_LP = np.ctypeslib.ndpointer(dtype=np.int64, flags="C_CONTIGUOUS")


@dataclass
class CLibrary:
    """A compiled model library (:func:`load_shared`) with numba-like calls.

    Parameters
    ----------
    lib
        The ``ctypes.CDLL`` with argument types declared.
    path
        The shared library's file.
    """

    lib: Any
    path: Path

    def rhs(self, t: float, y: np.ndarray, held: np.ndarray, P: np.ndarray, T: np.ndarray,
            dy: np.ndarray, aux: np.ndarray) -> None:
        """Call the C library's ``fd_rhs``: fill ``dy`` and ``aux`` in place (the numba ``rhs``
        signature).

        Parameters
        ----------
        t : float
            Time [s].
        y : numpy.ndarray
            State vector [SI, per state].
        held : numpy.ndarray
            Values the sampled controller holds [SI, per value].
        P : numpy.ndarray
            Packed parameter vector [SI, per slot].
        T : numpy.ndarray
            Packed tables [SI].
        dy : numpy.ndarray
            Output: state rates [SI per second, per state].
        aux : numpy.ndarray
            Output: auxiliary signals [SI, per signal].
        """
        self.lib.fd_rhs(float(t), y, held, P, T, dy, aux)

    def sample_update(self, t: float, y: np.ndarray, held: np.ndarray, P: np.ndarray,
                      T: np.ndarray, tick: np.ndarray) -> None:
        """Call the C library's ``fd_sample_update``: update ``held`` in place at a sample instant.

        Parameters
        ----------
        t : float
            Time [s].
        y : numpy.ndarray
            State vector [SI, per state].
        held : numpy.ndarray
            Values the sampled controller holds [SI, per value].
        P : numpy.ndarray
            Packed parameter vector [SI, per slot].
        T : numpy.ndarray
            Packed tables [SI].
        tick : numpy.ndarray of int
            Each clock's instant count now, −1 when it has none (int64, one per clock).
        """
        self.lib.fd_sample_update(float(t), y, held, P, T,
                                  np.ascontiguousarray(tick, dtype=np.int64))

    def aux(self, t: float, y: np.ndarray, held: np.ndarray, P: np.ndarray, T: np.ndarray,
            aux: np.ndarray) -> None:
        """Call the C library's ``fd_aux``: fill ``aux`` in place.

        Parameters
        ----------
        t : float
            Time [s].
        y : numpy.ndarray
            State vector [SI, per state].
        held : numpy.ndarray
            Values the sampled controller holds [SI, per value].
        P : numpy.ndarray
            Packed parameter vector [SI, per slot].
        T : numpy.ndarray
            Packed tables [SI].
        aux : numpy.ndarray
            Output: auxiliary signals [SI, per signal].
        """
        self.lib.fd_aux(float(t), y, held, P, T, aux)


def load_shared(path: str | os.PathLike[str]) -> CLibrary:
    """Load a library built by :func:`compile_shared` from :func:`c_model_source`.

    Parameters
    ----------
    path
        The shared library.

    Returns
    -------
    CLibrary
        ``fd_rhs``, ``fd_sample_update`` and ``fd_aux`` with their argument types declared
        (float64 C-contiguous arrays), so a wrong array type raises instead of corrupting
        memory.
    """
    lib = ctypes.CDLL(str(path))
    D = ctypes.c_double
    lib.fd_rhs.argtypes = [D, _DP, _DP, _DP, _DP, _DP, _DP]
    lib.fd_rhs.restype = None
    lib.fd_sample_update.argtypes = [D, _DP, _DP, _DP, _DP, _LP]
    lib.fd_sample_update.restype = None
    lib.fd_aux.argtypes = [D, _DP, _DP, _DP, _DP, _DP]
    lib.fd_aux.restype = None
    return CLibrary(lib=lib, path=Path(path))


def load_cached(c_text: str) -> CLibrary:
    """Load the library of ``c_text`` (:func:`c_model_source`) from the compiled-object cache,
    compiling it there on first use (:func:`feeddrive.backends.c_cache.cached_library`, with
    its default flags).

    Parameters
    ----------
    c_text : str
        C99 source exporting ``fd_rhs``, ``fd_sample_update`` and ``fd_aux``.

    Returns
    -------
    CLibrary
        The loaded library (:func:`load_shared`).

    Raises
    ------
    CompilerNotFound
        Without a C compiler.
    CompileError
        When the compiler fails.
    """
    return load_shared(cached_library(c_text))
