"""Forward-mode derivatives of the package's kernels: the tangent of a kernel, as a kernel.

Source transformation (the tangent mode of algorithmic differentiation [1]_, as tools such as
Tapenade apply it to source code [2]_) of the restricted Python the kernels are written in
(the subset of :mod:`feeddrive.backends.c_translate`, docs/c-backend.md): for a function ``f``
and every kernel it calls, transitively, a function ``f__tangent`` that computes what ``f``
computes and, beside every float value, its directional derivative — for a seed ``ẏ`` of the states
(and of the parameters ``Ṗ``, tables ``Ṫ``), ``dy__d = (∂f/∂y)·ẏ + (∂f/∂P)·Ṗ + …`` exactly, up
to rounding (no step size: the chain rule applied to every operation).  The result is itself a
kernel in the same subset: the C translator turns it into C (the FMU's
``fmi2GetDirectionalDerivative``), and it runs as plain Python too (the tests compare it with
finite differences).  One source of every equation, its derivative generated from it.

Rules.  Each float local and parameter ``x`` gets a tangent ``x__d``; each float array ``a``
(parameters and local arrays) an array ``a__d``; integers, booleans, comparisons and indices
have none.  ``+ - * / **``, ``abs``, ``min``/``max`` (the operand Python returns), ``float``,
the functions of :data:`RULES` and conditional expressions follow the chain rule on the branch
taken (a kink such as ``abs`` at 0 takes the right-hand derivative); ``int``, ``round``,
``floor``, ``ceil`` and ``trunc`` are piecewise constant.  A call of a kernel that returns a
float or writes a float array becomes a call of its tangent, hoisted into a statement of its
own before the one that used it (an argument's call first; a call inside a conditional
expression's branch stays under its condition).  Kernels that return integers and write
nothing (``branch``) are called as they are.

Anything else raises :class:`TangentError` naming the function and construct.

References
----------
.. [1] A. Griewank, A. Walther, *Evaluating Derivatives: Principles and Techniques of
   Algorithmic Differentiation*, 2nd ed., SIAM 2008, Ch. 3 (the forward mode).
.. [2] L. Hascoët, V. Pascual, "The Tapenade automatic differentiation tool", ACM TOMS 39
   (2013) 20 (source transformation of the tangent mode).
"""

from __future__ import annotations

import ast
import builtins
import copy
import inspect
import itertools
import linecache
import math
import textwrap
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["TangentError", "tangent", "TANGENT_SUFFIX", "RULES"]

#: suffix of a tangent function's name and of every tangent variable's
TANGENT_SUFFIX = "__tangent"
_D = "__d"
#: the math module under a name no kernel uses (the tangent rules' cos, sin, …)
_MATH = "_tangent_math"


class TangentError(ValueError):
    """A kernel uses a construct the tangent transformation does not handle."""


def _m(fn: str, *args: ast.expr) -> ast.expr:
    return ast.Call(ast.Attribute(ast.Name(_MATH, ast.Load()), fn, ast.Load()), list(args), [])


def _c(x: float) -> ast.expr:
    return ast.Constant(float(x))


def _bin(a: ast.expr, op: ast.operator, b: ast.expr) -> ast.expr:
    return ast.BinOp(a, op, b)


def _mul(a: ast.expr | None, b: ast.expr | None) -> ast.expr | None:
    if a is None or b is None:
        return None
    return _bin(a, ast.Mult(), b)


def _add(a: ast.expr | None, b: ast.expr | None) -> ast.expr | None:
    if a is None:
        return b
    if b is None:
        return a
    return _bin(a, ast.Add(), b)


def _sub(a: ast.expr | None, b: ast.expr | None) -> ast.expr | None:
    if b is None:
        return a
    if a is None:
        return ast.UnaryOp(ast.USub(), b)
    return _bin(a, ast.Sub(), b)


def _div(a: ast.expr | None, b: ast.expr) -> ast.expr | None:
    return None if a is None else _bin(a, ast.Div(), b)


#: derivative of each one-argument math function at x (AST of f'(x)), applied to x's tangent
#:
#: :meta hide-value:
RULES: dict[str, Callable[[ast.expr], ast.expr]] = {
    "exp": lambda x: _m("exp", x),
    "expm1": lambda x: _m("exp", x),
    "log": lambda x: _bin(_c(1.0), ast.Div(), x),
    "log1p": lambda x: _bin(_c(1.0), ast.Div(), _bin(_c(1.0), ast.Add(), x)),
    "log10": lambda x: _bin(_c(1.0), ast.Div(), _bin(x, ast.Mult(), _c(math.log(10.0)))),
    "sqrt": lambda x: _bin(_c(0.5), ast.Div(), _m("sqrt", x)),
    "sin": lambda x: _m("cos", x),
    "cos": lambda x: ast.UnaryOp(ast.USub(), _m("sin", x)),
    "tan": lambda x: _bin(_c(1.0), ast.Div(), _bin(_m("cos", x), ast.Pow(), _c(2.0))),
    "sinh": lambda x: _m("cosh", x),
    "cosh": lambda x: _m("sinh", x),
    "tanh": lambda x: _bin(_c(1.0), ast.Sub(), _bin(_m("tanh", x), ast.Pow(), _c(2.0))),
    "atan": lambda x: _bin(_c(1.0), ast.Div(), _bin(_c(1.0), ast.Add(), _bin(x, ast.Mult(),
                                                                             x))),
    "asin": lambda x: _bin(_c(1.0), ast.Div(), _m("sqrt", _bin(_c(1.0), ast.Sub(),
                                                               _bin(x, ast.Mult(), x)))),
    "acos": lambda x: ast.UnaryOp(ast.USub(), _bin(_c(1.0), ast.Div(), _m(
        "sqrt", _bin(_c(1.0), ast.Sub(), _bin(x, ast.Mult(), x))))),
    "erf": lambda x: _bin(_c(2.0 / math.sqrt(math.pi)), ast.Mult(),
                          _m("exp", ast.UnaryOp(ast.USub(), _bin(x, ast.Mult(), x)))),
    "erfc": lambda x: _bin(_c(-2.0 / math.sqrt(math.pi)), ast.Mult(),
                           _m("exp", ast.UnaryOp(ast.USub(), _bin(x, ast.Mult(), x)))),
}
_ABS = {"fabs", "abs", "absolute"}
_STEPS = {"floor", "ceil", "trunc", "isfinite", "isnan", "isinf"}  # piecewise constant
_NP_ALIASES = {"arctan": "atan", "arcsin": "asin", "arccos": "acos"}


@dataclass
class _Signature:
    """What a kernel takes and gives, from its annotations (activity aside)."""

    params: list[tuple[str, str]]  # (name, "f" float / "i" integer, bool / "a" float array)
    returns: tuple[str, ...] | None  # kinds of the results ("f" / "i"), None: none
    writes: set[str]  # array parameters it writes (directly or through calls)


@dataclass
class _Info:
    """A kernel's tangent for one activity of its parameters: its name and what a caller
    needs to call it.  Kinds: "f" a float that varies (a tangent beside it), "c" a float
    that does not, "i" an integer, "a" a float array that varies, "ca" one that does not."""

    fn: Callable[..., Any]
    name: str  # the tangent function's name
    params: list[tuple[str, str]]  # (name, kind)
    returns: tuple[str, ...] | None
    needed: bool  # varies: callers call the tangent (else the kernel itself, tangent 0)
    source: str = ""
    obj: Callable[..., Any] | None = None


@dataclass
class _Registry:
    """Every kernel's tangent once per activity, every kernel's signature once."""

    infos: dict[Any, _Info] = field(default_factory=dict)
    signatures: dict[Any, _Signature] = field(default_factory=dict)
    active: list[Any] = field(default_factory=list)


def _py(obj: Any) -> Callable[..., Any] | None:
    inner = getattr(obj, "py_func", obj)
    return inner if inspect.isfunction(inner) else None


def _parse(fn: Callable[..., Any]) -> ast.FunctionDef:
    try:
        lines, _ = inspect.getsourcelines(fn)
    except (OSError, TypeError) as exc:
        raise TangentError(f"{fn.__qualname__}: source not available ({exc})") from None
    node = ast.parse(textwrap.dedent("".join(lines))).body[0]
    if not isinstance(node, ast.FunctionDef):
        raise TangentError(f"{fn.__qualname__}: not a plain function definition")
    return node


def _kind_of_annotation(text: str | None) -> str | None:
    if text is None:
        return None
    text = text.replace(" ", "")
    return {"float": "f", "double": "f", "int": "i", "long": "i", "bool": "i",
            "np.ndarray": "a", "numpy.ndarray": "a", "double*": "a"}.get(text)


def _returns(node: ast.FunctionDef) -> tuple[str, ...] | None:
    if node.returns is None:
        return None
    text = ast.unparse(node.returns).replace(" ", "")
    if text == "None":
        return None
    one = _kind_of_annotation(text)
    if one in ("f", "i"):
        return (one,)
    if text.startswith(("tuple[", "Tuple[")):
        items = [_kind_of_annotation(i) for i in text[text.index("[") + 1:-1].split(",")]
        if all(i in ("f", "i") for i in items):
            return tuple(str(i) for i in items)
    raise TangentError(f"{node.name}: return annotation {text!r}")


class _Transform:
    """The tangent of one function for one activity of its parameters."""

    def __init__(self, reg: _Registry, fn: Callable[..., Any],
                 params: list[tuple[str, str]]) -> None:
        self.reg = reg
        self.fn = fn
        self.node = _parse(fn)
        self.name = fn.__qualname__
        self.globals: dict[str, Any] = dict(getattr(fn, "__globals__", {}))
        self.params = params
        if any(a for a in (self.node.args.vararg, self.node.args.kwarg)) or \
                self.node.args.kwonlyargs or self.node.args.defaults:
            raise TangentError(f"{self.name}: only plain positional parameters")
        self.kind: dict[str, str] = dict(self.params)
        self.returns = _returns(self.node)
        self.globals_needed: set[str] = set()
        self.tmp = itertools.count(1)
        body = self.node.body
        if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
                and isinstance(body[0].value.value, str):
            body = body[1:]
        self.body = body

    # ---- errors and name resolution
    def error(self, node: ast.AST, what: str) -> TangentError:
        line = getattr(node, "lineno", "?")
        return TangentError(f"{self.name} (line {line}): {what} is outside the tangent "
                            "transformation's subset")

    def resolve(self, node: ast.expr) -> Any:
        """The object a call's function expression names (a kernel, math, a builtin)."""
        if isinstance(node, ast.Name):
            if node.id in self.kind:
                raise self.error(node, f"call of local {node.id!r}")
            if node.id in self.globals:
                return self.globals[node.id]
            return getattr(builtins, node.id, None)
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
            mod = self.globals.get(node.value.id)
            if mod is math or mod is np:
                return (mod, node.attr)
            if inspect.ismodule(mod):
                return getattr(mod, node.attr, None)
        raise self.error(node, f"call of {ast.unparse(node)!r}")

    def callee(self, node: ast.Call) -> Callable[..., Any] | None:
        target = self.resolve(node.func)
        return _py(target) if not isinstance(target, tuple) else None

    # ---- type inference: which locals are floats (fixed point over the assignments)
    def kind_of(self, e: ast.expr) -> str | tuple[str, ...] | None:
        if isinstance(e, ast.Constant):
            return "f" if isinstance(e.value, float) else "i"
        if isinstance(e, ast.Name):
            if e.id in self.kind:
                return {"c": "f", "ca": "a"}.get(self.kind[e.id], self.kind[e.id])
            value = self.globals.get(e.id)
            if isinstance(value, bool | int):
                return "i"
            if isinstance(value, float):
                return "f"
            raise self.error(e, f"name {e.id!r}")
        if isinstance(e, ast.Subscript):
            if isinstance(e.value, ast.Call) and isinstance(e.slice, ast.Constant) and \
                    isinstance(e.slice.value, int):
                items = self.kind_of(e.value)  # one result of a kernel's tuple
                return items[e.slice.value] if isinstance(items, tuple) else None
            base = self.kind_of(e.value) if isinstance(e.value, ast.Name) else None
            if base == "a":
                return "f"
            raise self.error(e, f"subscript {ast.unparse(e)!r}")
        if isinstance(e, ast.Attribute):
            if isinstance(e.value, ast.Name) and self.globals.get(e.value.id) in (math, np):
                return "f"
            if e.attr in ("size", "shape"):
                return "i"
            raise self.error(e, f"attribute {ast.unparse(e)!r}")
        if isinstance(e, ast.BinOp):
            a, b = self.kind_of(e.left), self.kind_of(e.right)
            if isinstance(e.op, ast.Div):
                return "f"
            if None in (a, b):
                return None
            return "f" if "f" in (a, b) else "i"
        if isinstance(e, ast.UnaryOp):
            return "i" if isinstance(e.op, ast.Not) else self.kind_of(e.operand)
        if isinstance(e, ast.Compare | ast.BoolOp):
            return "i"
        if isinstance(e, ast.IfExp):
            a, b = self.kind_of(e.body), self.kind_of(e.orelse)
            if a is None or b is None:
                return a if b is None else b
            return "f" if "f" in (a, b) else "i"
        if isinstance(e, ast.Tuple):
            parts = [self.kind_of(x) for x in e.elts]
            return None if None in parts else tuple(str(x) for x in parts)
        if isinstance(e, ast.Call):
            target = self.resolve(e.func)
            if isinstance(target, tuple):
                name = target[1]
                if name in ("floor", "ceil", "trunc", "isfinite", "isnan", "isinf") and \
                        target[0] is math:
                    return "i"
                if name in ("zeros", "empty", "ones"):
                    return "a"
                return "f"
            if target is getattr(builtins, getattr(e.func, "id", ""), None):
                name = e.func.id  # type: ignore[attr-defined]
                if name in ("int", "round", "len", "bool", "range"):
                    return "i"
                if name == "float":
                    return "f"
                kinds = [self.kind_of(a) for a in e.args]
                if None in kinds:
                    return None
                return "f" if "f" in kinds else "i"
            fn = self.callee(e)
            if fn is None:
                raise self.error(e, f"call of {ast.unparse(e.func)!r}")
            returns = _signature_of(self.reg, fn).returns
            if returns is None:
                return None
            return returns[0] if len(returns) == 1 else returns
        raise self.error(e, f"expression {type(e).__name__}")

    def _assignments(self) -> list[tuple[ast.expr, ast.expr]]:
        out = []
        for n in ast.walk(ast.Module(self.body, [])):
            if isinstance(n, ast.Assign):
                for t in n.targets:
                    out.append((t, n.value))
            elif isinstance(n, ast.AugAssign):
                out.append((n.target, ast.BinOp(n.target, n.op, n.value)))
            elif isinstance(n, ast.For):
                out.append((n.target, ast.Constant(0)))
        return out

    def _infer(self) -> None:
        assigns = self._assignments()
        names = {t.id for t, _ in assigns if isinstance(t, ast.Name)}
        names |= {e.id for t, _ in assigns if isinstance(t, ast.Tuple) for e in t.elts
                  if isinstance(e, ast.Name)}
        for _ in range(len(names) + 2):
            changed = False
            for target, value in assigns:
                try:
                    k = self.kind_of(value)
                except TangentError:
                    k = None
                if k is None:
                    continue
                pairs = []
                if isinstance(target, ast.Name):
                    pairs.append((target.id, k))
                elif isinstance(target, ast.Tuple) and isinstance(k, tuple):
                    pairs += [(t.id, kk) for t, kk in zip(target.elts, k, strict=True)
                              if isinstance(t, ast.Name)]
                for name, kk in pairs:
                    if name in dict(self.params) or not isinstance(kk, str):
                        continue
                    old = self.kind.get(name)
                    new = "a" if kk == "a" else ("f" if "f" in (old, kk) else "i")
                    if new != old:
                        self.kind[name] = new
                        changed = True
            if not changed:
                break
        missing = names - set(self.kind)
        if missing:
            raise TangentError(f"{self.name}: cannot tell the type of {sorted(missing)}")

    # ---- expressions: (primal, tangent or None); statements a call needs go to `pre`
    def new_tmp(self) -> str:
        return f"tng_{next(self.tmp)}"

    def d_name(self, name: str) -> ast.expr:
        return ast.Name(name + _D, ast.Load())

    def primal(self, e: ast.expr, pre: list[ast.stmt]) -> ast.expr:
        """An expression whose value only is needed (a condition, an index, an integer)."""
        return self.expr(e, pre, want=False)[0]

    def expr(self, e: ast.expr, pre: list[ast.stmt], want: bool = True
             ) -> tuple[ast.expr, ast.expr | None]:
        if isinstance(e, ast.Constant):
            return e, None
        if isinstance(e, ast.Name):
            k = self.kind.get(e.id)
            return e, (self.d_name(e.id) if k == "f" else None)
        if isinstance(e, ast.Attribute):
            return e, None
        if isinstance(e, ast.Subscript) and isinstance(e.value, ast.Call):
            # one result of a kernel's tuple, f(...)[k]: every result into temporaries
            fn = self.callee(e.value)
            returns = _signature_of(self.reg, fn).returns if fn is not None else None
            pos = e.slice.value if isinstance(e.slice, ast.Constant) else None
            if fn is None or returns is None or not isinstance(pos, int) or \
                    not 0 <= pos < len(returns):
                raise self.error(e, f"subscript {ast.unparse(e)!r}")
            targets = [self.new_tmp() for _ in returns]
            for t, k in zip(targets, returns, strict=True):
                self.kind[t] = k
            self.kernel_call(e.value, fn, pre, targets=targets)
            pick = targets[pos]
            return (ast.Name(pick, ast.Load()),
                    self.d_name(pick) if self.kind[pick] == "f" else None)
        if isinstance(e, ast.Subscript):
            index = self.primal(e.slice, pre)
            base = e.value
            if not isinstance(base, ast.Name) or self.kind.get(base.id) not in ("a", "ca"):
                raise self.error(e, f"subscript {ast.unparse(e)!r}")
            sub = ast.Subscript(base, index, ast.Load())
            if self.kind[base.id] == "ca":
                return sub, None
            return sub, ast.Subscript(self.d_name(base.id), copy.deepcopy(index), ast.Load())
        if isinstance(e, ast.UnaryOp):
            p, d = self.expr(e.operand, pre, want)
            out = ast.UnaryOp(e.op, p)
            if isinstance(e.op, ast.USub):
                return out, (None if d is None else ast.UnaryOp(ast.USub(), d))
            if isinstance(e.op, ast.UAdd):
                return out, d
            return out, None
        if isinstance(e, ast.BinOp):
            return self.binop(e, pre, want)
        if isinstance(e, ast.Compare):
            return ast.Compare(self.primal(e.left, pre), e.ops,
                               [self.primal(c, pre) for c in e.comparators]), None
        if isinstance(e, ast.BoolOp):
            return ast.BoolOp(e.op, [self.primal(v, pre) for v in e.values]), None
        if isinstance(e, ast.IfExp):
            return self.ifexp(e, pre, want)
        if isinstance(e, ast.Call):
            return self.call(e, pre, want)
        if isinstance(e, ast.Tuple):
            raise self.error(e, "a tuple outside an assignment or return")
        raise self.error(e, f"expression {type(e).__name__}")

    def binop(self, e: ast.BinOp, pre: list[ast.stmt], want: bool
              ) -> tuple[ast.expr, ast.expr | None]:
        a, da = self.expr(e.left, pre, want)
        b, db = self.expr(e.right, pre, want)
        p = ast.BinOp(a, e.op, b)
        op = e.op
        if not want:
            return p, None
        if isinstance(op, ast.Add):
            return p, _add(da, db)
        if isinstance(op, ast.Sub):
            return p, _sub(da, db)
        if isinstance(op, ast.Mult):
            return p, _add(_mul(da, b), _mul(a, db))
        if isinstance(op, ast.Div):
            # (a/b)' = a'/b − (a/b)·b'/b
            return p, _sub(_div(da, b), _div(_mul(copy.deepcopy(p), db), b))
        if isinstance(op, ast.Pow):
            if isinstance(e.right, ast.Constant) and isinstance(e.right.value, int | float) \
                    and db is None:
                c = float(e.right.value)
                if da is None:
                    return p, None
                base = _bin(a, ast.Pow(), _c(c - 1.0)) if c != 2.0 else a
                return p, _mul(_mul(_c(c), base), da)
            # (a^b)' = a^b·(b'·log a + b·a'/a)
            inner = _add(_mul(db, _m("log", a)), _div(_mul(b, da), a))
            return p, _mul(copy.deepcopy(p), inner)
        if isinstance(op, ast.FloorDiv):
            return p, None
        if isinstance(op, ast.Mod):
            # a % b = a − floor(a/b)·b: a' − floor(a/b)·b'
            return p, _sub(da, _mul(_m("floor", _bin(a, ast.Div(), b)), db))
        raise self.error(e, f"operator {type(op).__name__}")

    def ifexp(self, e: ast.IfExp, pre: list[ast.stmt], want: bool
              ) -> tuple[ast.expr, ast.expr | None]:
        test = self.primal(e.test, pre)
        pre_b: list[ast.stmt] = []
        pre_o: list[ast.stmt] = []
        b, db = self.expr(e.body, pre_b, want)
        o, do = self.expr(e.orelse, pre_o, want)
        if not pre_b and not pre_o:
            d = None if db is None and do is None else ast.IfExp(
                copy.deepcopy(test), db or _c(0.0), do or _c(0.0))
            return ast.IfExp(test, b, o), d
        # a branch calls a kernel: the call stays under the condition (an if statement)
        tmp = self.new_tmp()
        self.kind[tmp] = "f" if (db is not None or do is not None) else "i"
        body = [*pre_b, _assign(tmp, b)]
        orelse = [*pre_o, _assign(tmp, o)]
        if self.kind[tmp] == "f":
            body.append(_assign(tmp + _D, db or _c(0.0)))
            orelse.append(_assign(tmp + _D, do or _c(0.0)))
        pre.append(ast.If(test, body, orelse))
        return ast.Name(tmp, ast.Load()), (self.d_name(tmp) if self.kind[tmp] == "f" else None)

    def call(self, e: ast.Call, pre: list[ast.stmt], want: bool
             ) -> tuple[ast.expr, ast.expr | None]:
        if e.keywords or any(isinstance(a, ast.Starred) for a in e.args):
            raise self.error(e, "keyword or starred arguments")
        target = self.resolve(e.func)
        if isinstance(target, tuple):  # math.f / np.f
            mod, name = target
            name = _NP_ALIASES.get(name, name)
            args = [self.expr(a, pre, want) for a in e.args]
            p = ast.Call(e.func, [a for a, _ in args], [])
            if name in ("zeros", "empty", "ones"):
                return p, None
            if not want or name in _STEPS:
                return p, None
            (x, dx), *rest = args
            if name in _ABS:
                return p, (None if dx is None else ast.IfExp(
                    ast.Compare(x, [ast.GtE()], [_c(0.0)]), dx, ast.UnaryOp(ast.USub(), dx)))
            if name in RULES and not rest:
                return p, _mul(RULES[name](copy.deepcopy(x)), dx)
            if name == "atan2":
                (yv, dy), (xv, dxv) = args
                den = _add(_mul(xv, xv), _mul(yv, yv))
                assert den is not None
                num = _sub(_mul(xv, dy), _mul(yv, dxv))
                return p, (None if num is None else _bin(num, ast.Div(), den))
            if name == "hypot":
                (u, du), (v, dv) = args
                num = _add(_mul(u, du), _mul(v, dv))
                return p, _div(num, copy.deepcopy(p))
            if name == "copysign":
                (u, du), (v, _) = args
                sign = _bin(_m("copysign", _c(1.0), u), ast.Mult(),
                            _m("copysign", _c(1.0), v))
                return p, _mul(sign, du)
            if name == "pow":
                fake = ast.BinOp(e.args[0], ast.Pow(), e.args[1])
                return self.binop(fake, pre, want)
            raise self.error(e, f"the derivative of {ast.unparse(e.func)}")
        fname = getattr(e.func, "id", None)
        if fname is not None and target is getattr(builtins, fname, None) and fname not in \
                self.globals:
            return self.builtin(e, fname, pre, want)
        fn = self.callee(e)
        if fn is None:
            raise self.error(e, f"call of {ast.unparse(e.func)!r}")
        return self.kernel_call(e, fn, pre)

    def builtin(self, e: ast.Call, name: str, pre: list[ast.stmt], want: bool
                ) -> tuple[ast.expr, ast.expr | None]:
        if name in ("int", "round", "len", "bool"):
            return ast.Call(e.func, [self.primal(a, pre) for a in e.args], []), None
        args = [self.expr(a, pre, want) for a in e.args]
        p = ast.Call(e.func, [a for a, _ in args], [])
        if not want:
            return p, None
        if name == "float":
            return p, args[0][1]
        if name == "abs":
            x, dx = args[0]
            return p, (None if dx is None else ast.IfExp(
                ast.Compare(x, [ast.GtE()], [_c(0.0)]), dx, ast.UnaryOp(ast.USub(), dx)))
        if name in ("min", "max"):
            if len(args) < 2:
                raise self.error(e, f"{name}() of fewer than two numbers")
            # Python returns the first extreme operand: fold left, keeping the tangent of the
            # operand that wins
            cur, dcur = args[0]
            beats = ast.Lt() if name == "min" else ast.Gt()
            for nxt, dnxt in args[1:]:
                if dcur is None and dnxt is None:
                    cur = ast.Call(ast.Name(name, ast.Load()), [cur, nxt], [])
                    continue
                dcur = ast.IfExp(ast.Compare(copy.deepcopy(nxt), [beats], [copy.deepcopy(cur)]),
                                 dnxt or _c(0.0), dcur or _c(0.0))
                cur = ast.Call(ast.Name(name, ast.Load()), [cur, nxt], [])
            return p, dcur
        raise self.error(e, f"built-in {name}()")

    def kernel_call(self, e: ast.Call, fn: Callable[..., Any], pre: list[ast.stmt],
                    targets: list[str] | None = None) -> tuple[ast.expr, ast.expr | None]:
        """A kernel call: its arguments transformed, the kernel's tangent for their activity
        called in a statement of its own (or the kernel itself when nothing of it varies)."""
        sig = _signature_of(self.reg, fn)
        if len(e.args) != len(sig.params):
            raise self.error(e, f"a call with {len(e.args)} arguments of a function of "
                                f"{len(sig.params)}")
        prim: list[ast.expr] = []
        tang: list[ast.expr] = []
        kinds: list[tuple[str, str]] = []
        for a, (pname, k) in zip(e.args, sig.params, strict=True):
            if k == "?":  # unannotated (a machine axis' scope function): as its argument
                known = self.kind.get(a.id) if isinstance(a, ast.Name) else None
                if known is None:
                    raise self.error(e, f"argument {ast.unparse(a)!r} for the unannotated "
                                        f"parameter {pname!r} (pass a name of known type)")
                k = "a" if known in ("a", "ca") else "f" if known in ("f", "c") else "i"
            if k == "a":
                if not isinstance(a, ast.Name) or self.kind.get(a.id) not in ("a", "ca"):
                    raise self.error(e, f"argument {ast.unparse(a)!r} for the array "
                                        f"parameter {pname!r} (pass an array name)")
                prim.append(a)
                kinds.append((pname, self.kind[a.id]))
                if self.kind[a.id] == "a":
                    tang.append(self.d_name(a.id))
            elif k == "f":
                p, d = self.expr(a, pre)
                prim.append(p)
                kinds.append((pname, "c" if d is None else "f"))
                if d is not None:
                    tang.append(d)
            else:
                prim.append(self.primal(a, pre))
                kinds.append((pname, "i"))
        info = _tangent_info(self.reg, fn, dict(kinds))
        returns = sig.returns or ()
        if not info.needed:  # nothing of it varies: the kernel itself, tangent 0
            call = ast.Call(e.func, prim, [])
            if targets is not None:
                pre.append(ast.Assign([ast.Tuple([ast.Name(t, ast.Store()) for t in targets],
                                                 ast.Store())], call, lineno=0))
                for t in targets:
                    if self.kind.get(t) == "f":
                        pre.append(_assign(t + _D, _c(0.0)))
                return ast.Constant(0), None
            return call, None
        call = ast.Call(ast.Name(info.name, ast.Load()), prim + tang, [])
        self.globals_needed.add(info.name)
        if targets is None:
            if len(returns) > 1:
                raise self.error(e, "a call returning a tuple outside a tuple assignment")
            if not returns:
                pre.append(ast.Expr(call))
                return ast.Constant(0), None
            tmp = self.new_tmp()
            self.kind[tmp] = returns[0]
            targets = [tmp]
        if len(targets) != len(returns):
            raise self.error(e, f"{len(targets)} targets for {len(returns)} results")
        names = [*targets, *(t + _D for t, k in zip(targets, returns, strict=True) if k == "f")]
        for t, k in zip(targets, returns, strict=True):
            self.kind.setdefault(t, k)
        store = (ast.Tuple([ast.Name(n, ast.Store()) for n in names], ast.Store())
                 if len(names) > 1 else ast.Name(names[0], ast.Store()))
        pre.append(ast.Assign([store], call, lineno=0))
        t0 = targets[0]
        return ast.Name(t0, ast.Load()), (self.d_name(t0) if returns[0] == "f" else None)

    # ---- statements
    def block(self, body: list[ast.stmt]) -> list[ast.stmt]:
        out: list[ast.stmt] = []
        for s in body:
            out += self.stmt(s)
        return out or [ast.Pass()]

    def stmt(self, s: ast.stmt) -> list[ast.stmt]:
        pre: list[ast.stmt] = []
        if isinstance(s, ast.Assign):
            if len(s.targets) != 1:
                raise self.error(s, "chained assignment")
            return self.assign(s.targets[0], s.value, pre)
        if isinstance(s, ast.AugAssign):
            load = copy.deepcopy(s.target)
            _to_load(load)
            return self.assign(s.target, ast.BinOp(load, s.op, s.value), pre)
        if isinstance(s, ast.If):
            test = self.primal(s.test, pre)
            return [*pre, ast.If(test, self.block(s.body),
                                 self.block(s.orelse) if s.orelse else [])]
        if isinstance(s, ast.For):
            it = s.iter
            if not (isinstance(it, ast.Call) and getattr(it.func, "id", None) == "range"):
                raise self.error(s, "a for loop over anything but range()")
            args = [self.primal(a, pre) for a in it.args]
            return [*pre, ast.For(s.target, ast.Call(it.func, args, []), self.block(s.body),
                                  [], lineno=0)]
        if isinstance(s, ast.While):
            test = self.primal(s.test, pre)
            if pre:
                raise self.error(s, "a kernel call in a while condition")
            return [ast.While(test, self.block(s.body), [])]
        if isinstance(s, ast.Return):
            return self.ret(s, pre)
        if isinstance(s, ast.Expr):
            if isinstance(s.value, ast.Constant):
                return []
            if not isinstance(s.value, ast.Call):
                raise self.error(s, "an expression statement")
            p, _ = self.expr(s.value, pre, want=False)
            if isinstance(p, ast.Call):
                pre.append(ast.Expr(p))
            return pre
        if isinstance(s, ast.Pass | ast.Break | ast.Continue):
            return [s]
        raise self.error(s, f"statement {type(s).__name__}")

    def assign(self, target: ast.expr, value: ast.expr, pre: list[ast.stmt]
               ) -> list[ast.stmt]:
        if isinstance(target, ast.Tuple):
            names = [t.id for t in target.elts if isinstance(t, ast.Name)]
            if len(names) != len(target.elts):
                raise self.error(target, "a tuple target of anything but names")
            if isinstance(value, ast.Call):
                fn = None if isinstance(self.resolve(value.func), tuple) else self.callee(value)
                if fn is None:
                    raise self.error(value, "a tuple result of anything but a kernel")
                self.kernel_call(value, fn, pre, targets=names)
                return pre
            if isinstance(value, ast.Tuple) and len(value.elts) == len(names):
                pairs = [self.expr(v, pre) for v in value.elts]
                out = list(pre)
                dn = [(n, d) for n, (_, d) in zip(names, pairs, strict=True)
                      if self.kind.get(n) == "f"]
                if dn:
                    out.append(ast.Assign(
                        [ast.Tuple([ast.Name(n + _D, ast.Store()) for n, _ in dn], ast.Store())],
                        ast.Tuple([d or _c(0.0) for _, d in dn], ast.Load()), lineno=0))
                out.append(ast.Assign([target], ast.Tuple([p for p, _ in pairs], ast.Load()),
                                      lineno=0))
                return out
            raise self.error(target, "a tuple assignment")
        if isinstance(target, ast.Name):
            k = self.kind.get(target.id)
            if k == "a":  # a local array: its tangent array beside it, of the same shape
                p = self.primal(value, pre)
                return [*pre, ast.Assign([target], p, lineno=0),
                        ast.Assign([ast.Name(target.id + _D, ast.Store())],
                                   copy.deepcopy(p), lineno=0)]
            if k == "f":
                p, d = self.expr(value, pre)
                return [*pre, _assign(target.id + _D, d or _c(0.0)),
                        ast.Assign([target], p, lineno=0)]
            p = self.primal(value, pre)
            return [*pre, ast.Assign([target], p, lineno=0)]
        if isinstance(target, ast.Subscript):
            base = target.value
            if not isinstance(base, ast.Name) or self.kind.get(base.id) != "a":
                raise self.error(target, f"assignment to {ast.unparse(target)!r}")
            index = self.primal(target.slice, pre)
            p, d = self.expr(value, pre)
            return [*pre,
                    ast.Assign([ast.Subscript(self.d_name(base.id), copy.deepcopy(index),
                                              ast.Store())], d or _c(0.0), lineno=0),
                    ast.Assign([ast.Subscript(base, index, ast.Store())], p, lineno=0)]
        raise self.error(target, f"assignment to {type(target).__name__}")

    def ret(self, s: ast.Return, pre: list[ast.stmt]) -> list[ast.stmt]:
        kinds = self.returns
        if kinds is None:
            return [*pre, ast.Return(None)]
        values = s.value.elts if isinstance(s.value, ast.Tuple) else [s.value]
        if s.value is None or len(values) != len(kinds):
            raise self.error(s, "a return that does not match the annotation")
        prim: list[ast.expr] = []
        tang: list[ast.expr] = []
        for v, k in zip(values, kinds, strict=True):
            assert v is not None
            if k == "f":
                p, d = self.expr(v, pre)
                prim.append(p)
                tang.append(d or _c(0.0))
            else:
                prim.append(self.primal(v, pre))
        items = prim + tang
        out = items[0] if len(items) == 1 else ast.Tuple(items, ast.Load())
        return [*pre, ast.Return(out)]

    # ---- the tangent function
    def build(self, info: _Info) -> str:
        body = self.block(self.body)
        args = [ast.arg(n, _annotation(k)) for n, k in self.params]
        args += [ast.arg(n + _D, _annotation(k)) for n, k in self.params if k in ("f", "a")]
        kinds = self.returns
        returns: ast.expr | None = None
        if kinds is not None:
            out = [*kinds, *(k for k in kinds if k == "f")]
            names = ["float" if k == "f" else "int" for k in out]
            returns = ast.parse(names[0] if len(names) == 1 else
                                f"tuple[{', '.join(names)}]", mode="eval").body
        fdef = ast.FunctionDef(info.name, ast.arguments([], args, None, [], [], None, []),
                               body, [], returns, None)
        fdef.type_params = []  # type: ignore[attr-defined,unused-ignore]  # Python ≥ 3.12
        module = ast.Module([fdef], [])
        ast.fix_missing_locations(module)
        return ast.unparse(module) + "\n"


def _annotation(kind: str) -> ast.expr:
    text = {"f": "float", "c": "float", "i": "int", "a": "np.ndarray", "ca": "np.ndarray"}
    return ast.parse(text[kind], mode="eval").body


def _assign(name: str, value: ast.expr) -> ast.stmt:
    return ast.Assign([ast.Name(name, ast.Store())], value, lineno=0)


def _to_load(node: ast.AST) -> None:
    for n in ast.walk(node):
        if hasattr(n, "ctx"):
            n.ctx = ast.Load()


def _writes(reg: _Registry, fn: Callable[..., Any], node: ast.FunctionDef,
            params: list[tuple[str, str]], globals_: Mapping[str, Any]) -> set[str]:
    """The array parameters a function writes, directly or through the kernels it calls."""
    arrays = {n for n, k in params if k in ("a", "?")}  # "?": unannotated (the rhs)
    out: set[str] = set()
    for n in ast.walk(node):
        targets = n.targets if isinstance(n, ast.Assign) else [n.target] if isinstance(
            n, ast.AugAssign) else []
        for t in targets:
            if isinstance(t, ast.Subscript) and isinstance(t.value, ast.Name) and \
                    t.value.id in arrays:
                out.add(t.value.id)
        if isinstance(n, ast.Call):
            f = n.func
            target = None
            if isinstance(f, ast.Name):
                target = globals_.get(f.id)
            elif isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name):
                mod = globals_.get(f.value.id)
                if inspect.ismodule(mod) and mod not in (math, np):
                    target = getattr(mod, f.attr, None)
            callee = _py(target)
            if callee is None:
                continue
            sig = _signature_of(reg, callee)
            for a, (pname, _) in zip(n.args, sig.params, strict=False):
                if pname in sig.writes and isinstance(a, ast.Name) and a.id in arrays:
                    out.add(a.id)
    return out


def _signature_of(reg: _Registry, fn: Callable[..., Any]) -> _Signature:
    """A kernel's parameters, results and the arrays it writes (once per registry)."""
    if fn in reg.signatures:
        return reg.signatures[fn]
    if fn in reg.active:
        raise TangentError(f"{fn.__qualname__}: recursion")
    reg.active.append(fn)
    try:
        node = _parse(fn)
        params = []
        for a in node.args.args:
            k = _kind_of_annotation(ast.unparse(a.annotation) if a.annotation is not None
                                    else None)
            params.append((a.arg, k or "?"))
        sig = _Signature(params, _returns(node), set())
        reg.signatures[fn] = sig
        sig.writes = _writes(reg, fn, node, params, getattr(fn, "__globals__", {}))
    finally:
        reg.active.remove(fn)
    return sig


def _tangent_info(reg: _Registry, fn: Callable[..., Any], kinds: Mapping[str, str]) -> _Info:
    """The tangent of ``fn`` for the activity ``kinds`` of its parameters (made once per
    registry and activity), with the kernels it calls."""
    sig = _signature_of(reg, fn)
    params = []
    for name, k in sig.params:
        kind = kinds.get(name, k)
        if kind == "?":
            raise TangentError(f"{fn.__qualname__}: parameter {name!r} has no type")
        params.append((name, kind))
    key = (fn, tuple(params))
    if key in reg.infos:
        return reg.infos[key]
    varies = {name for name, k in params if k in ("f", "a")}
    writes = sig.writes & varies
    needed = bool(writes) or (sig.returns is not None and "f" in sig.returns and bool(varies))
    # a name from the function and its activity: the same in every translation (the C text
    # of an FMU does not depend on what was exported before), distinct per specialisation
    code = "".join({"f": "v", "c": "c", "i": "i", "a": "V", "ca": "C"}[k] for _, k in params)
    module = fn.__module__.rsplit(".", 1)[-1]
    info = _Info(fn=fn, name=f"{fn.__name__}__{module}{TANGENT_SUFFIX}_{code}",
                 params=params, returns=sig.returns, needed=needed)
    clash = next((i for i in reg.infos.values() if i.name == info.name), None)
    if clash is not None:
        raise TangentError(f"{fn.__qualname__}: its tangent's name {info.name!r} is taken by "
                           f"{clash.fn.__module__}.{clash.fn.__qualname__}'s")
    reg.infos[key] = info
    if needed:
        tr = _Transform(reg, fn, params)
        tr._infer()
        info.source = tr.build(info)
        info.obj = _define(info, fn)
    return info


def _define(info: _Info, fn: Callable[..., Any]) -> Callable[..., Any]:
    """The tangent as a Python function, its source registered so it can be read back (the C
    translator reads kernels' source) and its globals those of ``fn``'s module."""
    filename = f"<{info.name}: tangent of {fn.__module__}.{fn.__qualname__}>"
    linecache.cache[filename] = (len(info.source), None, info.source.splitlines(True), filename)
    namespace = dict(getattr(fn, "__globals__", {}))
    namespace[_MATH] = math
    namespace.setdefault("np", np)
    exec(compile(info.source, filename, "exec"), namespace)  # noqa: S102 - generated kernel
    obj = namespace[info.name]
    obj.__module__ = fn.__module__
    obj._tangent_namespace = namespace
    return obj


def tangent(fn: Any, kinds: Mapping[str, str] | None = None) -> tuple[Callable[..., Any],
                                                                        dict[str, str]]:
    """The tangent of the kernel ``fn`` and of every kernel it calls.

    ``fn__tangent(*params, *tangents)`` takes ``fn``'s parameters, then a tangent for each
    float and float-array parameter, in order (``x__d``), and returns ``fn``'s results
    followed by the tangent of each float result; it writes the tangents of the arrays ``fn``
    writes into their tangent arrays.

    Parameters
    ----------
    fn : function or numba dispatcher
        A kernel in the C backend's subset.
    kinds : mapping of str to str, optional
        Activity of the parameters, overriding their annotations: ``"f"`` a float that varies,
        ``"c"`` one that does not, ``"i"`` an integer, ``"a"`` a float array that varies,
        ``"ca"`` one that does not (the generated ``rhs`` has no annotations: ``t`` ``"c"``,
        ``y`` ``"a"``, …).  Only what varies gets a tangent.

    Returns
    -------
    function
        The tangent, a plain Python function (its source readable by the C translator).
    dict of str to str
        Name of each tangent function made (the kernels' too) → its source.

    Raises
    ------
    TangentError
        For a construct outside the transformation's subset.
    """
    py = _py(fn)
    if py is None:
        raise TangentError(f"{fn!r}: not a Python function or numba kernel")
    reg = _Registry()
    info = _tangent_info(reg, py, dict(kinds or {}))
    if not info.needed:
        raise TangentError(f"{py.__qualname__}: returns no float and writes no array")
    made = {i.name: i for i in reg.infos.values() if i.needed}
    # each tangent calls the others by name: every namespace sees all of them
    for i in made.values():
        assert i.obj is not None
        ns = i.obj._tangent_namespace  # type: ignore[attr-defined]
        for j in made.values():
            ns[j.name] = j.obj
    assert info.obj is not None
    return info.obj, {name: i.source for name, i in made.items()}
