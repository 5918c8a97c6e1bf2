"""Translate the package's restricted-Python numba kernels to C99 (``ast`` based).

The kernels are written in a small subset of Python (scalars, flat arrays, loops, calls of
other kernels); this module turns a list of such functions, and every kernel they call,
transitively, into one C text.  It is the mechanism of the C backend
(:mod:`feeddrive.backends.c_backend`, docs/c-backend.md): one source of every equation, two
compilers.  Anything outside the subset raises :class:`TranslationError` naming the function,
file, line and construct; nothing is translated by guess.

The subset (checked against docs/c-backend.md by the tests):

* types: ``float`` → ``double``, ``int`` → ``long``, ``bool`` → ``int``; array parameters
  (``np.ndarray``) → ``double *`` (``const`` unless the function or a callee writes them),
  other element types and 2-D arrays by ``param_types`` / ``shapes``; local arrays from
  ``np.empty`` / ``np.zeros`` / ``np.ones`` (fixed size from constants, else a C99 VLA);
  local variable types inferred from their assignments (an int variable that is ever given a
  float becomes ``double``, as numba unifies them);
* statements: assignment (also ``a, b = f(...)`` and ``a, b = x, y``), augmented assignment,
  ``if``/``elif``/``else``, ``for i in range(...)`` (constant step), ``while``, ``break``,
  ``continue``, ``return``, ``pass``, expression calls, docstrings;
* expressions: ``+ - * / // % **``, comparisons (chained too), ``and``/``or``/``not``,
  ``a if c else b``, subscripts ``a[i]`` / ``M[i, j]``, ``a.size``, ``M.shape[k]``,
  module constants (inlined with ``repr`` precision), the functions of :data:`MATH`,
  :data:`NUMPY` and :data:`BUILTINS`, calls of other kernels (tuple results as small structs).

Python semantics kept: ``/`` is always float division; ``//`` and ``%`` follow Python on
negative operands (helpers ``fd_floordiv_*``, ``fd_mod_*``, CPython's algorithm); ``round``
is round-half-even; ``int()`` truncates; ``min``/``max`` return the first extreme operand as
Python does (NaN handling included); ``math.floor``/``ceil``/``trunc`` return an integer as
in numba; ``range`` bounds are evaluated once and the loop variable keeps Python's last value.
"""

from __future__ import annotations

import ast
import builtins
import inspect
import math
import textwrap
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["BUILTINS", "MATH", "NUMPY", "HELPERS", "CFunction", "TranslationError",
           "translate_kernels"]


class TranslationError(ValueError):
    """A kernel uses a construct outside the C backend's subset."""


# ---- scalar types: "bool" < "long" < "double"; arrays as Arr
_RANK = {"bool": 0, "long": 1, "double": 2}
_C_SCALAR = {"bool": "int", "long": "long", "double": "double"}
_C_ELEM = {"double": "double", "long": "long", "bool": "unsigned char"}


@dataclass(frozen=True)
class Arr:
    """The C type of an array argument.

    Parameters
    ----------
    elem : str
        Element type: ``"double"``, ``"long"`` or ``"bool"``.
    ndim : int, default 1
        Number of dimensions.
    """

    elem: str
    ndim: int = 1


@dataclass(frozen=True)
class Tup:
    """A tuple result of a kernel, returned in C as a struct ``fd_tuple_<codes>``.

    Parameters
    ----------
    items : tuple of str
        The C type of each element, in order.
    """

    items: tuple[str, ...]

    @property
    def cname(self) -> str:
        """The struct's C name, ``fd_tuple_`` followed by each element type's first letter."""
        return "fd_tuple_" + "".join(t[0] for t in self.items)


def _unify(a: str | None, b: str | None) -> str | None:
    if a is None:
        return b
    if b is None:
        return a
    return a if _RANK[a] >= _RANK[b] else b


#: math-module functions: name → (C function, number of arguments, result type)
MATH: dict[str, tuple[str, int, str]] = {
    **{f: (f, 1, "double") for f in ("exp", "log", "log10", "log1p", "expm1", "sqrt", "sin",
                                    "cos", "tan", "asin", "acos", "atan", "sinh", "cosh",
                                    "tanh", "fabs", "erf", "erfc")},
    "atan2": ("atan2", 2, "double"), "pow": ("pow", 2, "double"),
    "hypot": ("hypot", 2, "double"), "copysign": ("copysign", 2, "double"),
    "fmod": ("fmod", 2, "double"),
    "floor": ("floor", 1, "long"), "ceil": ("ceil", 1, "long"), "trunc": ("trunc", 1, "long"),
    "isfinite": ("isfinite", 1, "bool"), "isnan": ("isnan", 1, "bool"),
    "isinf": ("isinf", 1, "bool"),
}
#: numpy scalar functions: name → (C function, number of arguments, result type)
NUMPY: dict[str, tuple[str, int, str]] = {
    **{f: (f, 1, "double") for f in ("exp", "log", "log10", "log1p", "expm1", "sqrt", "sin",
                                    "cos", "tan", "sinh", "cosh", "tanh", "fabs", "floor",
                                    "ceil", "trunc")},
    "abs": ("fabs", 1, "double"), "absolute": ("fabs", 1, "double"),
    "arcsin": ("asin", 1, "double"), "arccos": ("acos", 1, "double"),
    "arctan": ("atan", 1, "double"), "arctan2": ("atan2", 2, "double"),
    "hypot": ("hypot", 2, "double"), "copysign": ("copysign", 2, "double"),
    "power": ("pow", 2, "double"), "sign": ("fd_sign", 1, "double"),
    "isfinite": ("isfinite", 1, "bool"), "isnan": ("isnan", 1, "bool"),
    "isinf": ("isinf", 1, "bool"),
}
#: Python built-ins with a C meaning
BUILTINS = ("abs", "min", "max", "float", "int", "bool", "round", "len", "range")
#: constants of math / numpy by attribute name
_CONSTANTS = {"pi": math.pi, "e": math.e, "tau": math.tau, "inf": math.inf, "nan": math.nan}
#: local-array constructors (numpy)
ARRAY_CONSTRUCTORS = ("empty", "zeros", "ones")
#: a dimension given so in ``shapes`` is known only at run time: the function takes it as a
#: hidden ``long`` parameter ``<array>_n<k>`` after the array, and callers pass their own
DYNAMIC = "?"

HELPERS = r"""
#ifndef FD_TRANSLATE_HELPERS
#define FD_TRANSLATE_HELPERS
/* Python semantics of //, %, round, min, max and numpy.sign (feeddrive.backends.c_translate) */
static inline long fd_mod_l(long a, long b) {
    long r = a % b;
    if (r != 0 && ((r < 0) != (b < 0))) r += b;
    return r;
}
static inline long fd_floordiv_l(long a, long b) {
    long q = a / b;
    if ((a % b != 0) && ((a < 0) != (b < 0))) q -= 1;
    return q;
}
static inline double fd_mod_d(double a, double b) {
    double m = fmod(a, b);
    if (m != 0.0) {
        if ((b < 0.0) != (m < 0.0)) m += b;
    } else {
        m = copysign(0.0, b);
    }
    return m;
}
static inline double fd_floordiv_d(double a, double b) {
    double m = fmod(a, b);
    double d = (a - m) / b;
    double q;
    if (m != 0.0) {
        if ((b < 0.0) != (m < 0.0)) d -= 1.0;
    }
    if (d != 0.0) {
        q = floor(d);
        if (d - q > 0.5) q += 1.0;
    } else {
        q = copysign(0.0, a / b);
    }
    return q;
}
static inline long fd_round(double x) { return (long)rint(x); }
static inline double fd_min_d(double a, double b) { return (b < a) ? b : a; }
static inline double fd_max_d(double a, double b) { return (b > a) ? b : a; }
static inline long fd_min_l(long a, long b) { return (b < a) ? b : a; }
static inline long fd_max_l(long a, long b) { return (b > a) ? b : a; }
static inline double fd_sign(double x)
{
    return x > 0.0 ? 1.0 : (x < 0.0 ? -1.0 : (x == 0.0 ? 0.0 : x));
}
#endif
"""

_C_RESERVED = frozenset("""auto break case char const continue default do double else enum extern
float for goto if inline int long register restrict return short signed sizeof static struct
switch typedef union unsigned void volatile while _Bool _Complex _Imaginary main
exp log log10 log1p expm1 sqrt sin cos tan asin acos atan atan2 sinh cosh tanh fabs floor ceil
trunc pow hypot copysign fmod erf erfc rint isfinite isnan isinf abs labs memset memcpy malloc
free NAN HUGE_VAL INFINITY y0 y1 yn j0 j1 jn log2 exp2 cbrt lgamma tgamma fmin fmax fma round
lround nearbyint remainder signbit fpclassify isgreater isless nan""".split())


def _literal(value: Any) -> tuple[str, str]:
    """C literal and type of a Python/numpy number."""
    if isinstance(value, (bool, np.bool_)):
        return ("1" if value else "0"), "bool"
    if isinstance(value, (int, np.integer)):
        v = int(value)
        if not -(2 ** 63) < v < 2 ** 63:
            raise TypeError(f"integer {v} does not fit a 64-bit long")
        return (f"{v}L" if not -(2 ** 31) < v < 2 ** 31 else str(v)), "long"
    if isinstance(value, (float, np.floating)):
        x = float(value)
        if math.isnan(x):
            return "NAN", "double"
        if math.isinf(x):
            return ("HUGE_VAL" if x > 0 else "(-HUGE_VAL)"), "double"
        text = repr(x)
        if not any(c in text for c in ".en"):
            text += ".0"
        return (f"({text})" if x < 0 else text), "double"
    raise TypeError(f"{type(value).__name__} is not a number")


def _mangle(fn: Callable[..., Any]) -> str:
    mod = (getattr(fn, "__module__", None) or "local").replace(".", "_")
    return f"fdk_{mod}__{fn.__qualname__.replace('.', '_').replace('<', '').replace('>', '')}"


def _py_function(obj: Any) -> Callable[..., Any] | None:
    """The Python function behind a numba dispatcher (``.py_func``) or a plain function."""
    inner = getattr(obj, "py_func", obj)
    return inner if inspect.isfunction(inner) else None


@dataclass
class _Signature:
    """What a caller needs of a translated function."""

    cname: str
    params: list[tuple[str, str | Arr]]
    returns: str | Tup | None
    written: set[str]
    shapes: dict[str, tuple[str, ...]]
    #: array parameter → its dimensions given as ``"?"`` in ``shapes``, passed as hidden
    #: ``long`` parameters after it (the caller's sizes of its argument)
    dynamic: dict[str, tuple[int, ...]] = field(default_factory=dict)


@dataclass
class _Unit:
    """One translation: every function once, in dependency order."""

    constants: Mapping[str, Any]
    bindings: Mapping[str, Any]
    shapes: Mapping[str, Sequence[str | int]]
    param_types: Mapping[str, Any]
    done: dict[Any, _Signature] = field(default_factory=dict)
    active: list[Any] = field(default_factory=list)
    chunks: list[str] = field(default_factory=list)
    prototypes: list[str] = field(default_factory=list)
    tuples: dict[str, Tup] = field(default_factory=dict)
    #: a hidden first parameter of every function of the translation, passed on by every
    #: call between them: (its C declaration, its C name), e.g. ``("const fd_model *",
    #: "fd_m")`` — what the C expressions of ``constants``, ``shapes`` and ``bindings`` may
    #: refer to (a driver compiled once for every model, the model reached through it)
    context: tuple[str, str] | None = None
    #: C statements at the start of every function's body (with ``context``: the values read
    #: through it into constants, e.g. ``const long fd_n_state = fd_m->n_state;``)
    prologue: str = ""

    def function(self, fn: Callable[..., Any], cname: str | None = None,
                 exported: bool = False) -> _Signature:
        key = fn
        if key in self.done:
            return self.done[key]
        if key in self.active:
            chain = " → ".join(f.__qualname__ for f in self.active)
            raise TranslationError(f"{fn.__qualname__}: recursion is outside the C backend's "
                                   f"subset (call chain {chain})")
        self.active.append(key)
        try:
            tr = _Function(self, fn, cname or _mangle(fn), exported)
            sig = tr.translate()
        finally:
            self.active.pop()
        self.done[key] = sig
        return sig


@dataclass(frozen=True)
class CFunction:
    """A C function a kernel calls by a bound name (``bindings`` of :func:`translate_kernels`).

    Parameters
    ----------
    name
        Its C name.
    returns
        Result type: "double", "long", "bool", or None for void.
    writes
        Positions of the array arguments it writes (None: all — then the caller's arrays lose
        ``const``).
    """

    name: str
    returns: str | None = None
    writes: tuple[int, ...] | None = None


class _Unknown(Exception):
    """A local's type is not known yet (type inference iterates)."""


class _Function:
    """Translation of one Python function."""

    def __init__(self, unit: _Unit, fn: Callable[..., Any], cname: str, exported: bool):
        self.unit = unit
        self.fn = fn
        self.cname = cname
        self.exported = exported
        self.name = fn.__qualname__
        try:
            lines, self.first_line = inspect.getsourcelines(fn)
            self.file = inspect.getsourcefile(fn) or "?"
        except (OSError, TypeError) as exc:
            raise TranslationError(f"{self.name}: source not available ({exc})") from None
        tree = ast.parse(textwrap.dedent("".join(lines)))
        node = tree.body[0]
        if not isinstance(node, ast.FunctionDef):
            raise TranslationError(f"{self.name}: not a plain function definition")
        self.node = node
        self.globals: dict[str, Any] = dict(getattr(fn, "__globals__", {}))
        self.locals: dict[str, str | Arr] = {}
        self.array_decl: dict[str, tuple[str, ...]] = {}  # local array -> C shape expressions
        self.fixed_arrays: set[str] = set()
        self.loop_vars: set[str] = set()
        self.written: set[str] = set()
        self.tmp = 0
        self.inferring = False
        self.returns: str | Tup | None = None
        self.cond_depth = 0
        self.calls_with_writes = 0
        self.calls_total = 0
        self.stmt_writes: set[str] = set()  # arrays written by calls in this statement
        self.stmt_reads: set[str] = set()  # arrays whose elements this statement reads

    # ---- errors
    def error(self, node: ast.AST | None, what: str, *, missing: bool = False
              ) -> TranslationError:
        """The error naming function, file, line and construct; ``missing``: the construct is
        in the subset but the translation lacks information (a type, a size)."""
        line = self.first_line + getattr(node, "lineno", 1) - 1
        if missing:
            return TranslationError(f"{self.name} ({self.file}:{line}): {what}")
        return TranslationError(f"{self.name} ({self.file}:{line}): {what} is outside the C "
                                f"backend's subset (docs/c-backend.md)")

    # ---- signature
    def _param_type(self, arg: ast.arg) -> str | Arr:
        name = arg.arg
        spec = self.unit.param_types.get(f"{self.fn.__name__}.{name}",
                                         self.unit.param_types.get(name))
        if spec is None and arg.annotation is not None:
            spec = ast.unparse(arg.annotation)
        if spec is None:
            raise self.error(arg, f"parameter {name!r} has no type (annotate it, or pass "
                                  f"param_types)", missing=True)
        spec = str(spec).replace(" ", "")
        scalars = {"float": "double", "double": "double", "int": "long", "long": "long",
                   "bool": "bool"}
        if spec in scalars:
            return scalars[spec]
        elems = {"np.ndarray": "double", "numpy.ndarray": "double", "double*": "double",
                 "long*": "long", "int64*": "long", "bool*": "bool", "uint8*": "bool"}
        if spec in elems:
            ndim = len(self.unit.shapes.get(name, (None,)))
            return Arr(elems[spec], ndim)
        raise self.error(arg, f"parameter type {spec!r} of {name!r}")

    def _return_type(self) -> str | Tup | None:
        ann = self.node.returns
        if ann is None:
            return "infer"
        text = ast.unparse(ann).replace(" ", "")
        if text == "None":
            return None
        scalars = {"float": "double", "int": "long", "bool": "bool"}
        if text in scalars:
            return scalars[text]
        if text.startswith(("tuple[", "Tuple[")) and text.endswith("]"):
            items = text[text.index("[") + 1:-1].split(",")
            if all(i in scalars for i in items):
                return Tup(tuple(scalars[i] for i in items))
        raise self.error(ann, f"return annotation {text!r}")

    # ---- name resolution
    def resolve(self, name: str, node: ast.AST) -> Any:
        """The Python object a global name stands for."""
        if name in self.unit.constants:
            return self.unit.constants[name]
        if name in self.unit.bindings:
            return self.unit.bindings[name]
        if name in self.globals:
            return self.globals[name]
        if hasattr(builtins, name):
            return getattr(builtins, name)
        raise self.error(node, f"name {name!r} (not a local, parameter, constant or kernel)")

    # ---- expressions
    def expr(self, node: ast.expr, test: bool = False) -> tuple[str, Any]:
        method = getattr(self, "e_" + type(node).__name__, None)
        if method is None:
            raise self.error(node, f"expression {type(node).__name__} "
                                   f"({ast.unparse(node)!r})")
        return method(node, test) if type(node).__name__ in ("BoolOp", "UnaryOp") \
            else method(node)

    def scalar(self, node: ast.expr, test: bool = False) -> tuple[str, str]:
        code, t = self.expr(node, test)
        if not isinstance(t, str):
            raise self.error(node, f"{ast.unparse(node)!r} used as a number")
        return code, t

    def e_Constant(self, node: ast.Constant) -> tuple[str, Any]:
        try:
            return _literal(node.value)
        except TypeError:
            raise self.error(node, f"constant {node.value!r}") from None

    def e_Name(self, node: ast.Name) -> tuple[str, Any]:
        name = node.id
        if name in self.locals:
            return self.cvar(name), self.locals[name]
        if name in self.array_decl:
            return self.cvar(name), self.locals[name]
        if self.inferring and name in self.assigned:
            raise _Unknown(name)
        value = self.resolve(name, node)
        if isinstance(value, str) and name in self.unit.constants:
            return f"({value})", "long"  # a C expression given by the caller (a size)
        try:
            return _literal(value)
        except TypeError:
            raise self.error(node, f"name {name!r} ({type(value).__name__}) used as a value"
                             ) from None

    def cvar(self, name: str) -> str:
        return name + "_" if name in _C_RESERVED or name.startswith("fd") else name

    def e_Attribute(self, node: ast.Attribute) -> tuple[str, Any]:
        if isinstance(node.value, ast.Name):
            base = node.value.id
            if base in self.locals and isinstance(self.locals[base], Arr):
                if node.attr == "size":
                    shape = self.shape_of(base, node)
                    return "(" + " * ".join(f"({s})" for s in shape) + ")", "long"
                raise self.error(node, f"array attribute .{node.attr}")
            obj = self.resolve(base, node)
            if obj is math or obj is np:
                if node.attr in _CONSTANTS:
                    return _literal(_CONSTANTS[node.attr])
                raise self.error(node, f"{base}.{node.attr} used as a value")
            if inspect.ismodule(obj):
                value = getattr(obj, node.attr, None)
                try:
                    return _literal(value)
                except TypeError:
                    pass
        raise self.error(node, f"attribute {ast.unparse(node)!r}")

    def shape_of(self, name: str, node: ast.AST) -> tuple[str, ...]:
        if name in self.array_decl:
            return self.array_decl[name]
        local = self.locals.get(name)
        if self.inferring and isinstance(local, Arr) and name not in self.params:
            return ("1",) * local.ndim  # a local array not declared yet: any size types alike
        shape = self.unit.shapes.get(name)
        if shape is None:
            raise self.error(node, f"the size of array {name!r} is not known (pass "
                                   f"shapes={{{name!r}: (...)}} with C expressions)",
                             missing=True)
        if name in getattr(self, "params", ()) or name not in self.locals:
            return tuple(self.size_param(name, k) if str(d) == DYNAMIC else str(d)
                         for k, d in enumerate(shape))
        return tuple(str(s) for s in shape)

    def size_param(self, name: str, k: int) -> str:
        """The C name of the hidden parameter holding dimension ``k`` of array parameter
        ``name`` (a ``"?"`` of ``shapes``)."""
        return f"{self.cvar(name)}_n{k}"

    def e_Subscript(self, node: ast.Subscript) -> tuple[str, Any]:
        # M.shape[k]
        if (isinstance(node.value, ast.Attribute) and node.value.attr == "shape"
                and isinstance(node.value.value, ast.Name)):
            base = node.value.value.id
            if not isinstance(self.locals.get(base), Arr):
                raise self.error(node, f"{ast.unparse(node)!r} of a non-array")
            if not (isinstance(node.slice, ast.Constant) and isinstance(node.slice.value, int)):
                raise self.error(node, "a non-constant shape index")
            shape = self.shape_of(base, node)
            k = node.slice.value
            if not 0 <= k < len(shape):
                raise self.error(node, f"shape index {k} of a {len(shape)}-D array")
            return f"({shape[k]})", "long"
        # f(...)[k] of a tuple-returning kernel
        if isinstance(node.value, ast.Call):
            code, t = self.expr(node.value)
            if isinstance(t, Tup):
                if not (isinstance(node.slice, ast.Constant) and isinstance(node.slice.value, int)
                        and 0 <= node.slice.value < len(t.items)):
                    raise self.error(node, "a tuple index that is not a constant in range")
                return f"{code}.v{node.slice.value}", t.items[node.slice.value]
            raise self.error(node, "subscript of a call that returns no tuple")
        if not isinstance(node.value, ast.Name):
            raise self.error(node, f"subscript of {ast.unparse(node.value)!r}")
        base = node.value.id
        t = self.locals.get(base)
        if not isinstance(t, Arr):
            if self.inferring and base in self.assigned:
                raise _Unknown(base)
            raise self.error(node, f"subscript of non-array {base!r}")
        idx = node.slice
        parts = list(idx.elts) if isinstance(idx, ast.Tuple) else [idx]
        if len(parts) != t.ndim:
            raise self.error(node, f"{len(parts)} indices of a {t.ndim}-D array {base!r} (a 2-D "
                                   f"parameter needs its shape in shapes=)")
        codes = []
        for p in parts:
            if isinstance(p, ast.Slice):
                raise self.error(node, f"slice {ast.unparse(node)!r}")
            if isinstance(p, ast.UnaryOp) and isinstance(p.op, ast.USub):
                raise self.error(node, f"negative index {ast.unparse(node)!r} (no wrap-around "
                                       f"in C)")
            c, it = self.scalar(p)
            if it == "double":
                raise self.error(node, f"float index {ast.unparse(p)!r}")
            codes.append(c)
        self.stmt_reads.add(base)
        if t.ndim == 1:
            return f"{self.cvar(base)}[{codes[0]}]", t.elem
        shape = self.shape_of(base, node)
        return f"{self.cvar(base)}[({codes[0]}) * ({shape[1]}) + ({codes[1]})]", t.elem

    def e_BinOp(self, node: ast.BinOp) -> tuple[str, Any]:
        a, ta = self.scalar(node.left)
        b, tb = self.scalar(node.right)
        ints = _RANK[ta] <= 1 and _RANK[tb] <= 1
        op = type(node.op)
        if op in (ast.Add, ast.Sub, ast.Mult):
            sym = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*"}[op]
            return f"({a} {sym} {b})", ("long" if ints else "double")
        if op is ast.Div:
            return f"({self.dbl(a, ta)} / {self.dbl(b, tb)})", "double"
        if op is ast.FloorDiv:
            return ((f"fd_floordiv_l({a}, {b})", "long") if ints
                    else (f"fd_floordiv_d({self.dbl(a, ta)}, {self.dbl(b, tb)})", "double"))
        if op is ast.Mod:
            return ((f"fd_mod_l({a}, {b})", "long") if ints
                    else (f"fd_mod_d({self.dbl(a, ta)}, {self.dbl(b, tb)})", "double"))
        if op is ast.Pow:
            if ints:
                raise self.error(node, f"integer power {ast.unparse(node)!r} (write a float "
                                       f"base)")
            return f"pow({self.dbl(a, ta)}, {self.dbl(b, tb)})", "double"
        raise self.error(node, f"operator {type(node.op).__name__}")

    @staticmethod
    def dbl(code: str, t: str) -> str:
        return code if t == "double" else f"(double)({code})"

    def e_UnaryOp(self, node: ast.UnaryOp, test: bool = False) -> tuple[str, Any]:
        if isinstance(node.op, ast.Not):
            a, _ = self.scalar(node.operand, test=True)
            return f"(!{a})", "bool"
        a, t = self.scalar(node.operand)
        if isinstance(node.op, ast.USub):
            return f"(-{a})", ("long" if t == "bool" else t)
        if isinstance(node.op, ast.UAdd):
            return a, ("long" if t == "bool" else t)
        raise self.error(node, f"operator {type(node.op).__name__}")

    def e_BoolOp(self, node: ast.BoolOp, test: bool = False) -> tuple[str, Any]:
        sym = " && " if isinstance(node.op, ast.And) else " || "
        parts = []
        for i, v in enumerate(node.values):
            if i:
                self.cond_depth += 1
            try:
                c, t = self.scalar(v, test=True)
            finally:
                if i:
                    self.cond_depth -= 1
            if t != "bool" and not test:
                raise self.error(node, f"{'and' if sym == ' && ' else 'or'} on a non-boolean "
                                       f"value used as a number ({ast.unparse(v)!r})")
            parts.append(c)
        return "(" + sym.join(parts) + ")", "bool"

    def e_Compare(self, node: ast.Compare) -> tuple[str, Any]:
        syms = {ast.Eq: "==", ast.NotEq: "!=", ast.Lt: "<", ast.LtE: "<=", ast.Gt: ">",
                ast.GtE: ">="}
        operands = [node.left, *node.comparators]
        if len(operands) > 2:
            for mid in operands[1:-1]:
                if any(isinstance(n, ast.Call) for n in ast.walk(mid)):
                    raise self.error(node, "a chained comparison with a call in the middle")
        for op in node.ops:
            if type(op) not in syms:
                raise self.error(node, f"comparison {type(op).__name__}")
        codes = [self.scalar(o)[0] for o in operands]
        parts = []
        for i, op in enumerate(node.ops):
            parts.append(f"({codes[i]} {syms[type(op)]} {codes[i + 1]})")
        return ("(" + " && ".join(parts) + ")" if len(parts) > 1 else parts[0]), "bool"

    def e_IfExp(self, node: ast.IfExp) -> tuple[str, Any]:
        c, _ = self.scalar(node.test, test=True)
        self.cond_depth += 1
        try:
            a, ta = self.scalar(node.body)
            b, tb = self.scalar(node.orelse)
        finally:
            self.cond_depth -= 1
        return f"({c} ? {a} : {b})", _unify(ta, tb)

    def e_Call(self, node: ast.Call) -> tuple[str, Any]:
        if node.keywords:
            raise self.error(node, f"keyword arguments in {ast.unparse(node)!r}")
        if any(isinstance(a, ast.Starred) for a in node.args):
            raise self.error(node, "a starred argument")
        func = node.func
        if isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name):
            mod = self.resolve(func.value.id, func) if func.value.id not in self.locals else None
            table = MATH if mod is math else NUMPY if mod is np else None
            if table is not None:
                if func.attr not in table:
                    raise self.error(node, f"function {func.value.id}.{func.attr}")
                cfun, nargs, rtype = table[func.attr]
                if len(node.args) != nargs:
                    raise self.error(node, f"{func.value.id}.{func.attr} with "
                                           f"{len(node.args)} arguments")
                args = [self.dbl(*self.scalar(a)) for a in node.args]
                code = f"{cfun}({', '.join(args)})"
                if rtype == "long":
                    code = f"(long){code}"
                elif rtype == "bool":
                    code = f"({code} != 0)"
                return code, rtype
            if inspect.ismodule(mod):
                target = getattr(mod, func.attr, None)
                if _py_function(target) is not None:
                    return self.kernel_call(node, target)
            raise self.error(node, f"call of {ast.unparse(func)!r}")
        if not isinstance(func, ast.Name):
            raise self.error(node, f"call of {ast.unparse(func)!r}")
        if func.id in self.locals:
            raise self.error(node, f"call of local {func.id!r}")
        target = self.resolve(func.id, func)
        if isinstance(target, str):  # a C function bound by name
            target = CFunction(target)
        if isinstance(target, tuple) and len(target) == 2 and isinstance(target[0], str):
            target = CFunction(target[0], target[1])
        if isinstance(target, CFunction):
            return self.external_call(node, target)
        if target is getattr(builtins, func.id, None) and func.id in BUILTINS:
            return self.builtin_call(node, func.id)
        if _py_function(target) is not None:
            return self.kernel_call(node, target)
        raise self.error(node, f"call of {func.id!r} ({type(target).__name__})")

    def builtin_call(self, node: ast.Call, name: str) -> tuple[str, Any]:
        args = node.args
        if name == "range":
            raise self.error(node, "range() outside a for loop")
        if name == "len":
            if len(args) == 1 and isinstance(args[0], ast.Name) \
                    and isinstance(self.locals.get(args[0].id), Arr):
                return f"({self.shape_of(args[0].id, node)[0]})", "long"
            raise self.error(node, "len() of a non-array")
        if name in ("min", "max"):
            if len(args) < 2:
                raise self.error(node, f"{name}() of fewer than two numbers")
            vals = [self.scalar(a) for a in args]
            t = "long" if all(_RANK[v[1]] <= 1 for v in vals) else "double"
            code = vals[0][0] if t == "long" else self.dbl(*vals[0])
            for c, ct in vals[1:]:
                code = f"fd_{name}_{t[0]}({code}, {c if t == 'long' else self.dbl(c, ct)})"
            return code, t
        if len(args) != 1:
            raise self.error(node, f"{name}() with {len(args)} arguments")
        a, t = self.scalar(args[0], test=(name == "bool"))
        if name == "abs":
            return (f"fabs({a})", "double") if t == "double" else (f"labs({a})", "long")
        if name == "float":
            return self.dbl(a, t), "double"
        if name == "int":
            return (f"((long)({a}))", "long") if t == "double" else (a, "long")
        if name == "bool":
            return f"({a} != 0)", "bool"
        if name == "round":
            return (f"fd_round({a})", "long") if t == "double" else (a, "long")
        raise self.error(node, f"built-in {name}()")

    def array_type(self, arg: ast.expr) -> Arr | None:
        """The type of ``arg`` as an array argument (a name, a row ``M[i]``, ``a if c else
        b``), None if it is not one."""
        if isinstance(arg, ast.Name):
            t = self.locals.get(arg.id)
            return t if isinstance(t, Arr) else None
        if (isinstance(arg, ast.Subscript) and isinstance(arg.value, ast.Name)
                and not isinstance(arg.slice, (ast.Tuple, ast.Slice))):
            t = self.locals.get(arg.value.id)
            return Arr(t.elem, 1) if isinstance(t, Arr) and t.ndim == 2 else None
        if isinstance(arg, ast.IfExp):
            return self.array_type(arg.body)
        return None

    def array_argument(self, node: ast.Call, arg: ast.expr, pname: str, ptype: Arr
                       ) -> tuple[str, list[str], tuple[str, ...]]:
        """(C code, the arrays it refers to, its C shape) of an argument for array parameter
        ``pname``: an array name, a row ``M[i]`` of a 2-D array (a pointer into it), or
        ``a if c else b`` of two such (one pointer or the other)."""
        if isinstance(arg, ast.IfExp):
            c, _ = self.scalar(arg.test, test=True)
            a, na, sa = self.array_argument(node, arg.body, pname, ptype)
            b, nb, sb = self.array_argument(node, arg.orelse, pname, ptype)
            if sa != sb:
                raise self.error(node, f"{ast.unparse(arg)!r}: arrays of different sizes")
            return f"({c} ? {a} : {b})", na + nb, sa
        if (isinstance(arg, ast.Subscript) and isinstance(arg.value, ast.Name)
                and not isinstance(arg.slice, (ast.Tuple, ast.Slice))
                and isinstance(self.locals.get(arg.value.id), Arr)):
            at = self.locals[arg.value.id]
            assert isinstance(at, Arr)
            if at.ndim != 2 or ptype != Arr(at.elem, 1):
                raise self.error(node, f"argument {ast.unparse(arg)!r} for array parameter "
                                       f"{pname!r} (a row of a 2-D array of its element type)")
            if isinstance(arg.slice, ast.UnaryOp) and isinstance(arg.slice.op, ast.USub):
                raise self.error(node, f"negative index {ast.unparse(arg)!r} (no wrap-around "
                                       f"in C)")
            i, it = self.scalar(arg.slice)
            if it == "double":
                raise self.error(node, f"float index {ast.unparse(arg.slice)!r}")
            shape = self.shape_of(arg.value.id, node)
            return (f"({self.cvar(arg.value.id)} + ({i}) * ({shape[1]}))", [arg.value.id],
                    (shape[1],))
        if not (isinstance(arg, ast.Name) and isinstance(self.locals.get(arg.id), Arr)):
            if self.inferring and isinstance(arg, ast.Name) and arg.id in self.assigned:
                raise _Unknown(arg.id)
            raise self.error(node, f"argument {ast.unparse(arg)!r} for array "
                                   f"parameter {pname!r} (pass an array name)")
        at = self.locals[arg.id]
        assert isinstance(at, Arr)
        if at != ptype:
            raise self.error(node, f"array {arg.id!r} ({at.elem}, {at.ndim}-D) passed "
                                   f"for {pname!r} ({ptype.elem}, {ptype.ndim}-D)")
        try:
            shape = self.shape_of(arg.id, node)
        except TranslationError:
            shape = ()
        return self.cvar(arg.id), [arg.id], shape

    def call_args(self, node: ast.Call, params: list[tuple[str, str | Arr]],
                  written: set[str] | None,
                  dynamic: Mapping[str, tuple[int, ...]] | None = None) -> list[str]:
        if len(node.args) != len(params):
            raise self.error(node, f"call with {len(node.args)} arguments of a function of "
                                   f"{len(params)}")
        out = []
        dynamic = dynamic or {}
        for arg, (pname, ptype) in zip(node.args, params, strict=True):
            if isinstance(ptype, Arr):
                code, names, shape = self.array_argument(node, arg, pname, ptype)
                if written is None or pname in written:
                    self.written.update(names)
                    self.stmt_writes.update(names)
                out.append(code)
                for k in dynamic.get(pname, ()):
                    if len(shape) <= k:
                        raise self.error(node, f"the size of {ast.unparse(arg)!r} is not known "
                                               f"(pass shapes=)", missing=True)
                    out.append(f"(long)({shape[k]})")
            else:
                c, t = self.scalar(arg)
                out.append(f"({_C_SCALAR[ptype]})({c})" if t != ptype else c)
        return out

    def kernel_call(self, node: ast.Call, target: Any) -> tuple[str, Any]:
        fn = _py_function(target)
        assert fn is not None
        sig = self.unit.function(fn)
        args = self.call_args(node, sig.params, sig.written, sig.dynamic)
        if self.unit.context is not None:
            args.insert(0, self.unit.context[1])
        self.calls_total += 1
        if sig.written:
            self.calls_with_writes += 1
        if isinstance(sig.returns, Tup):
            self.unit.tuples[sig.returns.cname] = sig.returns
        return f"{sig.cname}({', '.join(args)})", sig.returns

    def external_call(self, node: ast.Call, target: CFunction) -> tuple[str, Any]:
        params: list[tuple[str, str | Arr]] = []
        for i, arg in enumerate(node.args):
            at = self.array_type(arg)
            params.append((f"arg{i}", at if at is not None else self.scalar(arg)[1]))
        written = None if target.writes is None else {f"arg{i}" for i in target.writes}
        args = self.call_args(node, params, written)
        self.calls_total += 1
        if written is None or written:
            self.calls_with_writes += 1
        if target.returns not in (None, "double", "long", "bool"):
            raise TranslationError(f"binding {target.name}: result type {target.returns!r}")
        return f"{target.name}({', '.join(args)})", target.returns

    # ---- type inference of locals
    def infer(self) -> None:
        self.assigned: set[str] = set()
        for n in ast.walk(self.node):
            targets: list[ast.expr] = []
            if isinstance(n, ast.Assign):
                targets = n.targets
            elif isinstance(n, (ast.AugAssign, ast.For)):
                targets = [n.target]
            for tgt in targets:
                for t in (tgt.elts if isinstance(tgt, ast.Tuple) else [tgt]):
                    if isinstance(t, ast.Name):
                        self.assigned.add(t.id)
        self.assigned -= set(self.params)
        self.inferring = True
        for _ in range(50):
            changed = False
            for n in ast.walk(self.node):
                for name, t in self.assignment_types(n):
                    old = self.locals.get(name)
                    if isinstance(t, Arr) or isinstance(old, Arr):
                        if old is not None and old != t:
                            raise self.error(n, f"local {name!r} rebound as another kind")
                        new: Any = t
                    else:
                        new = _unify(old if isinstance(old, str) else None, t)
                    if name in self.params and new != old:
                        raise self.error(n, f"parameter {name!r} ({old}) assigned a {t} value "
                                            f"(declare it so, or use a local)")
                    if new != old:
                        self.locals[name] = new
                        changed = True
            if not changed:
                break
        self.inferring = False
        missing = self.assigned - set(self.locals)
        if missing:
            raise self.error(self.node, f"locals whose type cannot be inferred "
                                        f"({', '.join(sorted(missing))})")

    def assignment_types(self, n: ast.AST) -> list[tuple[str, Any]]:
        try:
            if isinstance(n, ast.For) and isinstance(n.target, ast.Name):
                return [(n.target.id, "long")]
            if isinstance(n, ast.AugAssign) and isinstance(n.target, ast.Name):
                fake = ast.BinOp(left=ast.Name(id=n.target.id, ctx=ast.Load()), op=n.op,
                                 right=n.value)
                ast.copy_location(fake, n)
                if n.target.id not in self.locals:
                    return []
                return [(n.target.id, self.expr(fake)[1])]
            if isinstance(n, ast.Assign) and len(n.targets) > 1:  # a = b = value
                t = self.expr(n.value)[1]
                return [(e.id, t) for e in n.targets if isinstance(e, ast.Name)]
            if not isinstance(n, ast.Assign) or len(n.targets) != 1:
                return []
            tgt = n.targets[0]
            if isinstance(tgt, ast.Name):
                arr = self.array_constructor(n.value)
                if arr is not None:
                    return [(tgt.id, arr[0])]
                t = self.expr(n.value)[1]
                return [(tgt.id, t)]
            if isinstance(tgt, ast.Tuple):
                if isinstance(n.value, ast.Tuple):
                    return [(e.id, self.expr(v)[1]) for e, v in zip(tgt.elts, n.value.elts,
                                                                    strict=False)
                            if isinstance(e, ast.Name)]
                t = self.expr(n.value)[1]
                if isinstance(t, Tup):
                    return [(e.id, it) for e, it in zip(tgt.elts, t.items, strict=False)
                            if isinstance(e, ast.Name)]
        except _Unknown:
            return []
        return []

    def array_constructor(self, value: ast.expr) -> tuple[Arr, tuple[str, ...], str] | None:
        """(type, C shape, constructor) of ``np.empty/zeros/ones(shape[, dtype])``, or of
        ``a.copy()`` of an array ``a`` (constructor ``"copy:a"``)."""
        if (isinstance(value, ast.Call) and isinstance(value.func, ast.Attribute)
                and value.func.attr == "copy" and isinstance(value.func.value, ast.Name)
                and isinstance(self.locals.get(value.func.value.id), Arr)):
            if value.args or value.keywords:
                raise self.error(value, f"{ast.unparse(value)!r} with arguments")
            src = value.func.value.id
            at = self.locals[src]
            assert isinstance(at, Arr)
            return at, self.shape_of(src, value), f"copy:{src}"
        if not (isinstance(value, ast.Call) and isinstance(value.func, ast.Attribute)
                and isinstance(value.func.value, ast.Name)
                and value.func.attr in ARRAY_CONSTRUCTORS
                and self.resolve(value.func.value.id, value) is np):
            return None
        if len(value.args) != 1:
            raise self.error(value, f"np.{value.func.attr} with {len(value.args)} arguments")
        elem = "double"
        for kw in value.keywords:
            if kw.arg != "dtype":
                raise self.error(value, f"np.{value.func.attr}({kw.arg}=...)")
            dt = ast.unparse(kw.value).replace("numpy.", "np.")
            kinds = {"np.float64": "double", "float": "double", "np.int64": "long",
                     "int": "long", "np.bool_": "bool", "bool": "bool", "np.uint8": "bool"}
            if dt not in kinds:
                raise self.error(value, f"dtype {dt}")
            elem = kinds[dt]
        shape_node = value.args[0]
        dims = list(shape_node.elts) if isinstance(shape_node, ast.Tuple) else [shape_node]
        if len(dims) not in (1, 2):
            raise self.error(value, f"a {len(dims)}-D local array")
        shape = []
        for d in dims:
            c, t = self.scalar(d)
            if t == "double":
                raise self.error(value, "a float array size")
            shape.append(c)
        return Arr(elem, len(dims)), tuple(shape), value.func.attr

    # ---- statements
    def block(self, body: list[ast.stmt], level: int) -> list[str]:
        out: list[str] = []
        for s in body:
            out += self.stmt(s, level)
        return out

    def reset_order(self) -> None:
        self.calls_total = 0
        self.calls_with_writes = 0
        self.stmt_writes = set()
        self.stmt_reads = set()

    def check_order(self, node: ast.AST) -> None:
        """Refuse what C evaluates in an unspecified order but Python left to right: two calls
        of which one writes an array, or an array element read beside a call that writes
        that array."""
        if self.calls_with_writes and self.calls_total > 1:
            raise self.error(node, "a statement with two calls of which one writes an array "
                                   "(C leaves their order open: split the statement)")
        both = self.stmt_writes & self.stmt_reads
        if both:
            raise self.error(node, f"a statement that reads array {sorted(both)[0]!r} beside "
                                   f"a call that writes it (C leaves their order open: split "
                                   f"the statement)")
        self.reset_order()

    def stmt(self, s: ast.stmt, level: int) -> list[str]:
        pad = "    " * level
        self.reset_order()
        method = getattr(self, "s_" + type(s).__name__, None)
        if method is None:
            raise self.error(s, f"statement {type(s).__name__}")
        lines = method(s, level, pad)
        if not isinstance(s, (ast.If, ast.While, ast.For)):  # those check their heads
            self.check_order(s)
        return lines

    def s_Expr(self, s: ast.Expr, level: int, pad: str) -> list[str]:
        if isinstance(s.value, ast.Constant) and isinstance(s.value.value, str):
            return []  # docstring
        if not isinstance(s.value, ast.Call):
            raise self.error(s, f"expression statement {ast.unparse(s)!r}")
        code, t = self.expr(s.value)
        return [f"{pad}{code};" if t is None else f"{pad}(void){code};"]

    def s_Pass(self, s: ast.Pass, level: int, pad: str) -> list[str]:
        return [f"{pad};"]

    def s_Break(self, s: ast.Break, level: int, pad: str) -> list[str]:
        return [f"{pad}break;"]

    def s_Continue(self, s: ast.Continue, level: int, pad: str) -> list[str]:
        return [f"{pad}continue;"]

    def store(self, tgt: ast.expr) -> tuple[str, Any]:
        """An assignment target: its element is written, not read (for :meth:`check_order`;
        reads in its index count)."""
        before = set(self.stmt_reads)
        code, t = self.target(tgt)
        if isinstance(tgt, ast.Subscript) and isinstance(tgt.value, ast.Name) \
                and tgt.value.id not in before:
            self.stmt_reads.discard(tgt.value.id)
        return code, t

    def target(self, tgt: ast.expr) -> tuple[str, Any]:
        if isinstance(tgt, ast.Name):
            if tgt.id not in self.locals:
                raise self.error(tgt, f"assigning {tgt.id!r}, whose type is not known (a "
                                      f"global, or a local first set by an augmented "
                                      f"assignment)")
            if tgt.id in self.params and isinstance(self.locals[tgt.id], Arr):
                raise self.error(tgt, f"rebinding array parameter {tgt.id!r}")
            return self.cvar(tgt.id), self.locals[tgt.id]
        if isinstance(tgt, ast.Subscript) and isinstance(tgt.value, ast.Name):
            code, t = self.e_Subscript(tgt)
            self.written.add(tgt.value.id)
            return code, t
        raise self.error(tgt, f"assignment target {ast.unparse(tgt)!r}")

    def s_Assign(self, s: ast.Assign, level: int, pad: str) -> list[str]:
        if len(s.targets) != 1:
            return self.chained(s, pad)
        tgt = s.targets[0]
        if isinstance(tgt, ast.Name):
            arr = self.array_constructor(s.value)
            if arr is not None:
                return self.local_array(s, tgt.id, arr, pad)
            if isinstance(self.locals.get(tgt.id), Arr):
                raise self.error(s, f"rebinding array {tgt.id!r}")
        if isinstance(tgt, ast.Tuple):
            names = tgt.elts
            if not all(isinstance(e, (ast.Name, ast.Subscript)) for e in names):
                raise self.error(s, "a nested tuple target")
            if isinstance(s.value, ast.Tuple):
                if len(s.value.elts) != len(names):
                    raise self.error(s, "unpacking of unequal length")
                lines = [f"{pad}{{"]
                temps = []
                for v in s.value.elts:
                    c, t = self.scalar(v)
                    self.tmp += 1
                    temps.append(f"fd_t{self.tmp}")
                    lines.append(f"{pad}    {_C_SCALAR[t]} {temps[-1]} = {c};")
                for e, tmp in zip(names, temps, strict=True):
                    lines.append(f"{pad}    {self.store(e)[0]} = {tmp};")
                return lines + [f"{pad}}}"]
            code, t = self.expr(s.value)
            if not isinstance(t, Tup) or len(t.items) != len(names):
                raise self.error(s, f"unpacking of {ast.unparse(s.value)!r}")
            self.tmp += 1
            tmp = f"fd_t{self.tmp}"
            lines = [f"{pad}{{", f"{pad}    {t.cname} {tmp} = {code};"]
            for i, e in enumerate(names):
                lines.append(f"{pad}    {self.store(e)[0]} = {tmp}.v{i};")
            return lines + [f"{pad}}}"]
        row = self.row_store(s, tgt, pad)
        if row is not None:
            return row
        code, t = self.expr(s.value)
        if not isinstance(t, str):
            raise self.error(s, f"assigning {ast.unparse(s.value)!r} (not a number)")
        lhs, lt = self.store(tgt)
        if lt == "long" and t == "double":
            raise self.error(s, f"a float stored in integer {ast.unparse(tgt)!r}")
        return [f"{pad}{lhs} = {code};"]

    def chained(self, s: ast.Assign, pad: str) -> list[str]:
        """``a = b = ... = value`` of a number: the value once, then each target from left to
        right (Python's order)."""
        if not all(isinstance(t, ast.Name) for t in s.targets):
            raise self.error(s, "a chained assignment to anything but names")
        code, t = self.scalar(s.value)
        self.tmp += 1
        tmp = f"fd_t{self.tmp}"
        lines = [f"{pad}{{", f"{pad}    {_C_SCALAR[t]} {tmp} = {code};"]
        for tgt in s.targets:
            lhs, lt = self.store(tgt)
            if lt == "long" and t == "double":
                raise self.error(s, f"a float stored in integer {ast.unparse(tgt)!r}")
            lines.append(f"{pad}    {lhs} = {tmp};")
        return lines + [f"{pad}}}"]

    def row_store(self, s: ast.Assign, tgt: ast.expr, pad: str) -> list[str] | None:
        """``M[i, :] = v``: row i of a 2-D array given the elements of a 1-D array of its
        length (a loop over the row); None for any other assignment."""
        if not (isinstance(tgt, ast.Subscript) and isinstance(tgt.value, ast.Name)
                and isinstance(tgt.slice, ast.Tuple) and len(tgt.slice.elts) == 2
                and isinstance(tgt.slice.elts[1], ast.Slice)):
            return None
        whole = tgt.slice.elts[1]
        assert isinstance(whole, ast.Slice)
        base, value = tgt.value.id, s.value
        bt = self.locals.get(base)
        if (whole.lower is not None or whole.upper is not None or whole.step is not None
                or not isinstance(bt, Arr) or bt.ndim != 2 or not isinstance(value, ast.Name)
                or self.locals.get(value.id) != Arr(bt.elem, 1)):
            raise self.error(s, f"slice {ast.unparse(tgt)!r} (only M[i, :] = v, v a 1-D "
                                f"array of M's element type)")
        if isinstance(tgt.slice.elts[0], ast.UnaryOp) \
                and isinstance(tgt.slice.elts[0].op, ast.USub):
            raise self.error(s, f"negative index {ast.unparse(tgt)!r} (no wrap-around in C)")
        i, it = self.scalar(tgt.slice.elts[0])
        if it == "double":
            raise self.error(s, f"float index {ast.unparse(tgt.slice.elts[0])!r}")
        shape = self.shape_of(base, s)
        self.written.add(base)
        self.stmt_reads.add(value.id)
        self.tmp += 1
        j = f"fd_i{self.tmp}"
        m = self.cvar(base)
        return [f"{pad}for (long {j} = 0; {j} < ({shape[1]}); ++{j}) "
                f"{m}[({i}) * ({shape[1]}) + {j}] = {self.cvar(value.id)}[{j}];"]

    def local_array(self, s: ast.Assign, name: str, arr: tuple[Arr, tuple[str, ...], str],
                    pad: str) -> list[str]:
        t, shape, kind = arr
        count = " * ".join(f"({d})" for d in shape)
        fixed = True
        try:
            ints = [eval(d, {"__builtins__": {}}) for d in shape]  # literal sizes only
            fixed = all(isinstance(v, int) for v in ints)
        except Exception:
            fixed = False
        lines = []
        elem = _C_ELEM[t.elem]
        if fixed:
            self.fixed_arrays.add(name)
            self.array_decl[name] = tuple(str(max(1, v)) for v in ints)
        else:
            if name in self.array_decl:
                raise self.error(s, f"variable-size local array {name!r} created twice")
            self.array_decl[name] = shape
            lines.append(f"{pad}{elem} {self.cvar(name)}[{count}];")
        n = " * ".join(f"({d})" for d in self.array_decl[name])
        if kind.startswith("copy:"):
            src = kind.removeprefix("copy:")
            self.stmt_reads.add(src)
            self.tmp += 1
            i = f"fd_i{self.tmp}"
            lines.append(f"{pad}for (long {i} = 0; {i} < {n}; ++{i}) {self.cvar(name)}[{i}] = "
                         f"{self.cvar(src)}[{i}];")
        elif kind in ("zeros", "ones"):
            self.tmp += 1
            i = f"fd_i{self.tmp}"
            one = {"double": "1.0", "long": "1", "bool": "1"}[t.elem] if kind == "ones" else "0"
            lines.append(f"{pad}for (long {i} = 0; {i} < {n}; ++{i}) {self.cvar(name)}[{i}] = "
                         f"{one};")
        return lines

    def s_AugAssign(self, s: ast.AugAssign, level: int, pad: str) -> list[str]:
        lhs, lt = self.target(s.target)
        if not isinstance(lt, str):
            raise self.error(s, "augmented assignment of an array")
        fake = ast.BinOp(left=s.target, op=s.op, right=s.value)
        ast.copy_location(fake, s)
        if isinstance(s.target, ast.Subscript):
            fake.left = ast.Subscript(value=s.target.value, slice=s.target.slice, ctx=ast.Load())
        code, t = self.scalar(fake)
        if lt == "long" and t == "double":
            raise self.error(s, f"a float stored in integer {ast.unparse(s.target)!r}")
        op = type(s.op)
        if op in (ast.Add, ast.Sub, ast.Mult):
            rhs, _ = self.scalar(s.value)
            sym = {ast.Add: "+=", ast.Sub: "-=", ast.Mult: "*="}[op]
            return [f"{pad}{lhs} {sym} {rhs};"]
        return [f"{pad}{lhs} = {code};"]

    def s_If(self, s: ast.If, level: int, pad: str) -> list[str]:
        c, _ = self.scalar(s.test, test=True)
        self.check_order(s)
        lines = [f"{pad}if ({c}) {{"]
        lines += self.block(s.body, level + 1)
        orelse = s.orelse
        while len(orelse) == 1 and isinstance(orelse[0], ast.If):
            self.reset_order()
            c, _ = self.scalar(orelse[0].test, test=True)
            self.check_order(orelse[0])
            lines.append(f"{pad}}} else if ({c}) {{")
            lines += self.block(orelse[0].body, level + 1)
            orelse = orelse[0].orelse
        if orelse:
            lines.append(f"{pad}}} else {{")
            lines += self.block(orelse, level + 1)
        return lines + [f"{pad}}}"]

    def s_While(self, s: ast.While, level: int, pad: str) -> list[str]:
        if s.orelse:
            raise self.error(s, "while ... else")
        c, _ = self.scalar(s.test, test=True)
        self.check_order(s)
        return [f"{pad}while ({c}) {{", *self.block(s.body, level + 1), f"{pad}}}"]

    def s_For(self, s: ast.For, level: int, pad: str) -> list[str]:
        if s.orelse:
            raise self.error(s, "for ... else")
        if not isinstance(s.target, ast.Name):
            raise self.error(s, "a for loop over a tuple target")
        it = s.iter
        if not (isinstance(it, ast.Call) and isinstance(it.func, ast.Name)
                and it.func.id == "range" and self.resolve("range", it) is range
                and not it.keywords and 1 <= len(it.args) <= 3):
            raise self.error(s, f"a for loop over {ast.unparse(it)!r} (only range())")
        bounds = []
        for a in it.args:
            c, t = self.scalar(a)
            if t == "double":
                raise self.error(s, f"a float range bound {ast.unparse(a)!r}")
            bounds.append(c)
        start, stop = ("0", bounds[0]) if len(bounds) == 1 else (bounds[0], bounds[1])
        step = 1
        if len(it.args) == 3:
            node = it.args[2]
            value: Any = None
            if isinstance(node, ast.Constant):
                value = node.value
            elif isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub) \
                    and isinstance(node.operand, ast.Constant) \
                    and isinstance(node.operand.value, int):
                value = -node.operand.value
            if not isinstance(value, int) or value == 0:
                raise self.error(s, "a range step that is not a non-zero integer constant")
            step = value
        self.check_order(s)
        self.tmp += 1
        i, e = f"fd_i{self.tmp}", f"fd_e{self.tmp}"
        var = self.cvar(s.target.id)
        if self.locals.get(s.target.id) != "long":
            raise self.error(s, f"loop variable {s.target.id!r} also holds a float")
        cmp = "<" if step > 0 else ">"
        inc = "++" + i if step == 1 else f"{i} += {step}"
        head = f"{pad}for (long {i} = {start}, {e} = {stop}; {i} {cmp} {e}; {inc}) {{"
        return [head, f"{pad}    {var} = {i};", *self.block(s.body, level + 1), f"{pad}}}"]

    def s_Return(self, s: ast.Return, level: int, pad: str) -> list[str]:
        if s.value is None:
            if self.returns is not None:
                raise self.error(s, "a bare return in a function returning a value")
            return [f"{pad}return;"]
        if isinstance(s.value, ast.Tuple):
            if not isinstance(self.returns, Tup) or len(self.returns.items) != len(s.value.elts):
                raise self.error(s, "a tuple return not matching the function's result")
            vals = [self.scalar(v)[0] for v in s.value.elts]
            self.unit.tuples[self.returns.cname] = self.returns
            self.tmp += 1
            r = f"fd_r{self.tmp}"
            lines = [f"{pad}{{", f"{pad}    {self.returns.cname} {r};"]
            lines += [f"{pad}    {r}.v{k} = {v};" for k, v in enumerate(vals)]
            return lines + [f"{pad}    return {r};", f"{pad}}}"]
        code, t = self.expr(s.value)
        if isinstance(self.returns, Tup):
            if t != self.returns:
                raise self.error(s, "a return not matching the function's tuple result")
            return [f"{pad}return {code};"]
        if self.returns is None or not isinstance(t, str):
            raise self.error(s, "returning a value from a function without a result")
        if self.returns == "long" and t == "double":
            raise self.error(s, "a float returned from a function declared int")
        return [f"{pad}return {code};"]

    def infer_return(self) -> str | Tup | None:
        result: Any = None
        for n in ast.walk(self.node):
            if isinstance(n, ast.Return) and n.value is not None:
                if isinstance(n.value, ast.Tuple):
                    t: Any = Tup(tuple(self.scalar(v)[1] for v in n.value.elts))
                else:
                    t = self.expr(n.value)[1]
                if isinstance(t, Arr):
                    raise self.error(n, "returning an array")
                if result is None:
                    result = t
                elif isinstance(result, str) and isinstance(t, str):
                    result = _unify(result, t)
                elif result != t:
                    raise self.error(n, "returns of different kinds")
        return result

    # ---- the whole function
    def translate(self) -> _Signature:
        a = self.node.args
        if a.vararg or a.kwarg or a.kwonlyargs or a.defaults or a.posonlyargs:
            raise self.error(self.node, "default, keyword-only or variable arguments")
        self.params = [arg.arg for arg in a.args]
        ptypes = {arg.arg: self._param_type(arg) for arg in a.args}
        dynamic = {name: tuple(k for k, d in enumerate(self.unit.shapes.get(name, ()))
                               if str(d) == DYNAMIC)
                   for name in self.params if isinstance(ptypes[name], Arr)}
        dynamic = {name: dims for name, dims in dynamic.items() if dims}
        self.locals.update(ptypes)
        declared = self._return_type()
        self.infer()
        self.returns = self.infer_return() if declared == "infer" else declared
        body = self.block(self.node.body, 1)
        if isinstance(self.returns, Tup):
            self.unit.tuples[self.returns.cname] = self.returns
        # the written set decides const-ness; callers' own writes were added during the body
        params_c = []
        hidden: list[str] = []
        for name in self.params:
            t = ptypes[name]
            if isinstance(t, Arr):
                const = "" if name in self.written else "const "
                params_c.append(f"{const}{_C_ELEM[t.elem]} *{self.cvar(name)}")
                for k in dynamic.get(name, ()):
                    hidden.append(self.size_param(name, k))
                    params_c.append(f"long {hidden[-1]}")
            else:
                params_c.append(f"{_C_SCALAR[t]} {self.cvar(name)}")
        if self.unit.context is not None:
            params_c.insert(0, f"{self.unit.context[0]}{self.unit.context[1]}")
            hidden.append(self.unit.context[1])
        ret = ("void" if self.returns is None else self.returns.cname
               if isinstance(self.returns, Tup) else _C_SCALAR[self.returns])
        head = (f"{'' if self.exported else 'static '}{ret} {self.cname}"
                f"({', '.join(params_c) or 'void'})")
        decls = [f"    {line}" for line in self.unit.prologue.splitlines() if line.strip()]
        for name, t in self.locals.items():
            if name in self.params:
                continue
            if isinstance(t, Arr):
                if name in self.fixed_arrays:
                    dims = self.array_decl[name]
                    n = 1
                    for d in dims:
                        n *= int(d)
                    decls.append(f"    {_C_ELEM[t.elem]} {self.cvar(name)}[{n}];")
                continue
            zero = "0.0" if t == "double" else "0"
            decls.append(f"    {_C_SCALAR[t]} {self.cvar(name)} = {zero};")
        # Python lets a parameter or local go unused; C's -Wunused-* would stop the build
        loaded = {n.id for n in ast.walk(self.node)
                  if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}
        loaded |= {n.value.id for n in ast.walk(self.node) if isinstance(n, ast.Subscript)
                   and isinstance(n.value, ast.Name)}
        decls += [f"    (void){self.cvar(name)};" for name in self.locals
                  if name not in loaded]
        decls += [f"    (void){name};" for name in hidden]
        guard = f"FDK_DEF_{self.cname}"
        self.unit.prototypes.append(f"#ifndef {guard}\n{head};\n#endif")
        self.unit.chunks.append(
            f"#ifndef {guard}\n#define {guard}\n/* {self.fn.__module__}.{self.name}, line "
            f"{self.first_line} */"
            f"\n{head}\n{{\n" + "\n".join(decls + body) + "\n}\n#endif")
        return _Signature(self.cname, [(n, ptypes[n]) for n in self.params], self.returns,
                          {n for n in self.params if n in self.written},
                          {n: self.shape_of(n, self.node) for n in self.params
                           if isinstance(ptypes[n], Arr) and n in self.unit.shapes}, dynamic)


def _structs(tuples: Mapping[str, Tup]) -> str:
    out = []
    for name, t in sorted(tuples.items()):
        fields = " ".join(f"{_C_SCALAR[x]} v{i};" for i, x in enumerate(t.items))
        out.append(f"#ifndef FD_STRUCT_{name}\n#define FD_STRUCT_{name}\n"
                   f"typedef struct {{ {fields} }} {name};\n#endif")
    return "\n".join(out)


def translate_kernels(functions: Iterable[Any], constants: Mapping[str, Any] | None = None, *,
                      bindings: Mapping[str, Any] | None = None,
                      shapes: Mapping[str, Sequence[str | int]] | None = None,
                      param_types: Mapping[str, str] | None = None,
                      names: Mapping[str, str] | None = None,
                      context: tuple[str, str] | None = None, prologue: str = "") -> str:
    """C99 text of ``functions`` and of every kernel they call, transitively.

    Parameters
    ----------
    functions
        Python functions or numba dispatchers (``.py_func`` is read) in the restricted subset
        (module docstring, docs/c-backend.md).  Each becomes an exported (non-``static``) C
        function named ``names[fn.__name__]`` or ``fd_<name>``; every kernel they call becomes a
        ``static`` function with a mangled name (``fdk_<module>__<name>``), each translated once,
        in dependency order.
    constants
        Values that override the functions' module globals by name: a number is inlined (floats
        with ``repr`` precision); a string is a C expression inlined as an integer (e.g.
        ``{"N_AUX": "FD_N_AUX"}`` for the solver templates' placeholders).  Module-level
        numbers the functions read (tableau coefficients, parameter offsets) are inlined
        without being listed here.
    bindings
        Global names of called functions replaced by another Python function (translated too)
        or by a C function: a :class:`CFunction` (name, result type, positions of the arrays
        it writes), or just its name (void, assumed to write every array it receives), e.g.
        ``{"rhs": CFunction("fd_rhs", None, (2, 8, 9))}``.
    shapes
        C expressions of array sizes by parameter name, e.g. ``{"y": ["FD_N_STATE"],
        "J": ["FD_N_STATE", "FD_N_STATE"]}``: needed for ``a.size``, ``M.shape[k]``, ``len``
        and 2-D indexing (row-major, the row stride is the second entry).  One mapping serves
        every function of the translation.
    param_types
        Types of unannotated or non-double parameters by ``"name"`` or ``"function.name"``:
        "float", "int", "bool", "double*", "long*", "bool*" (1-byte elements, numpy
        ``bool_``/``uint8``).
    names
        Exported C names by Python function name (default ``fd_<name>``).
    context
        A hidden first parameter of every translated function, exported ones included, which
        every call between them passes on: (C declaration, C name), e.g.
        ``("const fd_model *", "fd_m")``.  The C expressions of ``constants``, ``shapes``
        and ``bindings`` may refer to it (``"fd_m->n_state"``, a binding ``"fd_m->rhs"``):
        then the text does not depend on the sizes or functions it reaches through it.
    prologue
        C statements put at the start of every translated function's body, one a line (with
        ``context``: what is read through it once per call, e.g.
        ``const long fd_n_state = fd_m->n_state; (void)fd_n_state;``).

    Returns
    -------
    str
        C99 source needing only ``<math.h>``, ``<string.h>`` and ``<stdlib.h>`` (included):
        the Python-semantics helpers, tuple structs, prototypes and definitions.  Every part is
        guarded by ``#ifndef`` so two translations can be concatenated into one file.

    Raises
    ------
    TranslationError
        A construct outside the subset, naming the function, file, line and construct.
    """
    unit = _Unit(constants=dict(constants or {}), bindings=dict(bindings or {}),
                 shapes=dict(shapes or {}), param_types=dict(param_types or {}),
                 context=context, prologue=prologue)
    names = dict(names or {})
    for obj in functions:
        fn = _py_function(obj)
        if fn is None:
            raise TranslationError(f"{obj!r}: not a Python function or numba kernel")
        unit.function(fn, names.get(fn.__name__, f"fd_{fn.__name__}"), exported=True)
    return c_text(unit)


def c_text(unit: _Unit) -> str:
    """The C source of one translation: headers, helpers, tuple structs, prototypes, functions.

    Parameters
    ----------
    unit : _Unit
        The translation (every function once, in dependency order).

    Returns
    -------
    str
        The C text.
    """
    parts = ["#include <math.h>", "#include <string.h>", "#include <stdlib.h>", HELPERS,
             _structs(unit.tuples), "\n".join(unit.prototypes), "\n\n".join(unit.chunks)]
    return "\n".join(p for p in parts if p) + "\n"
