"""Which derivative can depend on which state: the structural Jacobian pattern of a generated
right-hand side, and a column colouring for a grouped finite-difference Jacobian.

:func:`jacobian_pattern` runs a small dataflow (taint) analysis over the ``rhs`` source the
parts emitted (:mod:`feeddrive.model.codegen`).  Every local variable, ``aux[k]`` and ``dy[i]``
carries the set of columns it may depend on — state indices, and ``n`` for t:

* ``y[j]`` → {j}; ``t`` → {n}; ``held``, ``P``, ``T``, the loop-period flags and constants →
  nothing (they are the same in every call of one Jacobian);
* an operator, a conditional expression or a call of a kernel the parts imported
  (:meth:`Builder.use`, pure by the package's convention) → the union of its operands;
* an assignment inside an ``if`` also takes the condition's set, and the two branches are
  merged by union (the flags and ``P`` are run-time values: both branches count);
* a *local-state kernel* (declared by its part with :meth:`Builder.local_kernel`: the friction
  laws, the LuGre observer) reads only ``y[k : k + m]`` of the array it is given (``k`` the
  argument after ``y``) and writes exactly ``dy[k : k + m]``;
* the whole ``y`` given to any other call → every column; ``aux[k]`` read before it is written
  → every column (its value would be left over from another call).

Anything else — a loop, a call of an unknown function, ``dy`` or ``aux`` passed whole, an index
that is not a constant — makes the analysis give up: every entry is then structurally
non-zero.  The pattern can only be too large, never too small (tested against dense
finite-difference Jacobians in ``tests/unit/test_jacobian_pattern.py``).
"""

from __future__ import annotations

import ast
import functools

import numpy as np

Taint = frozenset[int]
_NONE: Taint = frozenset()
_FREE = frozenset(("held", "P", "T", "n_pos", "n_vel", "n_cur", "math", "np"))
_PURE_BUILTINS = frozenset(("abs", "min", "max", "int", "float", "bool"))


class _Unknown(Exception):
    """A construct the analysis does not model."""


class _Flow:
    def __init__(self, n: int, pure: frozenset[str], local: dict[str, int]) -> None:
        self.n = n
        self.all: Taint = frozenset(range(n + 1))
        self.pure = pure
        self.local = local
        self.env: dict[str, Taint] = {}
        self.dy: dict[int, Taint] = {}
        self.aux: dict[int, Taint] = {}

    # ---- expressions
    def expr(self, node: ast.expr, ctx: Taint) -> Taint:
        if isinstance(node, ast.Constant):
            return _NONE
        if isinstance(node, ast.Name):
            return self._name(node.id)
        if isinstance(node, ast.Subscript):
            return self._subscript(node, ctx)
        if isinstance(node, ast.Call):
            return self._call(node, ctx)
        if isinstance(node, ast.BinOp):
            return self.expr(node.left, ctx) | self.expr(node.right, ctx)
        if isinstance(node, ast.UnaryOp):
            return self.expr(node.operand, ctx)
        if isinstance(node, (ast.BoolOp, ast.Tuple)):
            parts = node.values if isinstance(node, ast.BoolOp) else node.elts
            return frozenset().union(*(self.expr(v, ctx) for v in parts))
        if isinstance(node, ast.Compare):
            return frozenset().union(*(self.expr(v, ctx) for v in [node.left, *node.comparators]))
        if isinstance(node, ast.IfExp):
            return (self.expr(node.test, ctx) | self.expr(node.body, ctx)
                    | self.expr(node.orelse, ctx))
        raise _Unknown(ast.dump(node))

    def _name(self, name: str) -> Taint:
        if name == "t":
            return frozenset((self.n,))
        if name == "y":
            return self.all
        if name in _FREE:
            return _NONE
        if name in self.env:
            return self.env[name]
        raise _Unknown(name)

    def _subscript(self, node: ast.Subscript, ctx: Taint) -> Taint:
        base = node.value.id if isinstance(node.value, ast.Name) else None
        index = _constant_index(node.slice)
        if base == "y":
            return frozenset((index,)) if index is not None else self.all
        if base in ("dy", "aux"):
            if index is None:
                raise _Unknown(ast.dump(node))
            store = self.dy if base == "dy" else self.aux
            return store.get(index, self.all)
        return self.expr(node.value, ctx) | self.expr(node.slice, ctx)

    def _call(self, node: ast.Call, ctx: Taint) -> Taint:
        if node.keywords:
            raise _Unknown(ast.dump(node))
        fn = node.func
        if isinstance(fn, ast.Name) and fn.id in self.local:
            return self._local_call(node, fn.id, ctx)
        pure = (isinstance(fn, ast.Name) and (fn.id in self.pure or fn.id in _PURE_BUILTINS)
                or isinstance(fn, ast.Attribute) and isinstance(fn.value, ast.Name)
                and fn.value.id in ("math", "np"))
        if not pure:
            raise _Unknown(ast.dump(fn))
        for a in node.args:
            if isinstance(a, ast.Name) and a.id in ("dy", "aux"):
                raise _Unknown(f"{a.id} passed to {ast.dump(fn)}")
        return frozenset().union(*(self.expr(a, ctx) for a in node.args))

    def _local_call(self, node: ast.Call, name: str, ctx: Taint) -> Taint:
        """A kernel reading y[k : k + m] and writing dy[k : k + m] (k: the argument after y)."""
        args = node.args
        where = [i for i, a in enumerate(args) if isinstance(a, ast.Name) and a.id == "y"]
        if len(where) != 1 or where[0] + 1 >= len(args):
            raise _Unknown(f"{name}: no y, k arguments")
        k = _constant_index(args[where[0] + 1])
        if k is None:
            raise _Unknown(f"{name}: state offset not a constant")
        m = self.local[name]
        taint = frozenset(range(k, k + m))
        for i, a in enumerate(args):
            if i in (where[0], where[0] + 1) or isinstance(a, ast.Name) and a.id == "dy":
                continue
            if isinstance(a, ast.Name) and a.id == "aux":
                raise _Unknown(f"aux passed to {name}")
            taint |= self.expr(a, ctx)
        for i in range(k, k + m):
            self.dy[i] = taint | ctx
        return taint

    # ---- statements
    def block(self, body: list[ast.stmt], ctx: Taint) -> None:
        for st in body:
            self.stmt(st, ctx)

    def stmt(self, st: ast.stmt, ctx: Taint) -> None:
        if isinstance(st, ast.Assign):
            value = self.expr(st.value, ctx) | ctx
            for target in st.targets:
                self._assign(target, value)
        elif isinstance(st, ast.AugAssign):
            self._assign(st.target, self.expr(st.value, ctx) | self.expr(st.target, ctx) | ctx)
        elif isinstance(st, ast.If):
            inner = ctx | self.expr(st.test, ctx)
            before = self._copy()
            self.block(st.body, inner)
            after_body = self._copy()
            self._restore(before)
            self.block(st.orelse, inner)
            self._merge(after_body)
        elif isinstance(st, ast.Expr):
            self.expr(st.value, ctx)
        elif not isinstance(st, ast.Pass):
            raise _Unknown(ast.dump(st))

    def _assign(self, target: ast.expr, value: Taint) -> None:
        if isinstance(target, ast.Name):
            self.env[target.id] = value
        elif isinstance(target, ast.Tuple):
            for el in target.elts:
                self._assign(el, value)
        elif (isinstance(target, ast.Subscript) and isinstance(target.value, ast.Name)
              and target.value.id in ("dy", "aux")
              and (index := _constant_index(target.slice)) is not None):
            (self.dy if target.value.id == "dy" else self.aux)[index] = value
        else:
            raise _Unknown(ast.dump(target))

    def _copy(self) -> tuple[dict[str, Taint], dict[int, Taint], dict[int, Taint]]:
        return dict(self.env), dict(self.dy), dict(self.aux)

    def _restore(self, state: tuple[dict[str, Taint], dict[int, Taint], dict[int, Taint]]
                 ) -> None:
        self.env, self.dy, self.aux = dict(state[0]), dict(state[1]), dict(state[2])

    def _merge(self, other: tuple[dict[str, Taint], dict[int, Taint], dict[int, Taint]]
               ) -> None:
        """Union with the state after the other branch.  An entry set in one branch only:
        locals keep the value (reading it unset would not compile), ``dy`` keeps it (an
        unwritten derivative is no function of this call's state), ``aux`` becomes every
        column (the other path reads a value left over from another call)."""
        env, dy, aux = other
        for key in env.keys() | self.env.keys():
            self.env[key] = env.get(key, _NONE) | self.env.get(key, _NONE)
        for i in dy.keys() | self.dy.keys():
            self.dy[i] = dy.get(i, _NONE) | self.dy.get(i, _NONE)
        for i in aux.keys() | self.aux.keys():
            self.aux[i] = aux.get(i, self.all) | self.aux.get(i, self.all)


def _constant_index(node: ast.expr) -> int | None:
    if isinstance(node, ast.Constant) and type(node.value) is int:
        return node.value
    return None


@functools.lru_cache(maxsize=64)
def _pattern(rhs_source: str, n: int, pure: frozenset[str],
             local: tuple[tuple[str, int], ...]) -> np.ndarray:
    S = np.zeros((n, n + 1), dtype=np.uint8)
    flow = _Flow(n, pure, dict(local))
    try:
        fn = ast.parse(rhs_source).body[0]
        if not isinstance(fn, ast.FunctionDef):
            raise _Unknown("not a function")
        flow.block(fn.body, _NONE)
    except _Unknown:
        S[:] = 1
        return S
    for i, taint in flow.dy.items():
        if not 0 <= i < n:
            S[:] = 1  # an index outside the state vector: give up
            return S
        S[i, sorted(taint)] = 1
    return S


def jacobian_pattern(rhs_source: str, n_states: int, pure: frozenset[str],
                     local: dict[str, int]) -> np.ndarray:
    """Boolean pattern (uint8, n × (n + 1)) of ∂dy[i]/∂y[j] (last column: ∂/∂t) of the
    function ``rhs_source``; ``pure``: names of side-effect-free kernels, ``local``: local-state
    kernels and their number of states."""
    S = _pattern(rhs_source, n_states, frozenset(pure), tuple(sorted(local.items())))
    return S.copy()


def colour_columns(S: np.ndarray) -> np.ndarray:
    """Greedy largest-first colouring of the columns of ``S``: two columns share a colour only
    if no row has both.  Returns the colour (group number, from 0) of every column."""
    B = np.asarray(S, dtype=bool)
    conflict = (B.T.astype(np.int64) @ B.astype(np.int64)) > 0
    ncol = B.shape[1]
    order = sorted(range(ncol), key=lambda j: (-int(conflict[j].sum()), j))
    colour = np.full(ncol, -1, dtype=np.int64)
    for j in order:
        used = {int(colour[k]) for k in range(ncol) if conflict[j, k] and k != j}
        c = 0
        while c in used:
            c += 1
        colour[j] = c
    return colour
