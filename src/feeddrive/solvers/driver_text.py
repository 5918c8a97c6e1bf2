"""The driver's text: the transforms that make each build's source from the one driver.

:mod:`feeddrive.solvers.driver` holds the numerical driver —
:func:`~feeddrive.solvers.driver.driver_template` and its pieces
(:data:`~feeddrive.solvers.driver.PIECES`), written once in the restricted Python of the
kernels.  This module reads their text (``inspect``, ``ast``) and makes from it what each
build compiles, the same operations on the same numbers (the results bit-identical):

* :func:`specialise` folds a use's constant flags into the template (``LAND``, ``DENSE``,
  ``COMM``; ``mode`` and ``adaptive`` where the use fixes them), drops the branches they make
  unreachable and folds the locals left with one constant value; :func:`source` so makes each
  use of :data:`feeddrive.solvers.driver.USES`, and :func:`define` defines a text as a
  function of the driver's module (the C translator reads it);
* :func:`numba_text` makes a text numba's: a piece of more than :data:`NUMBA_ARGS` parameters
  takes its later ones as one tuple, a row written from an array is copied element by element;
* :func:`lower_outputs` makes a driver write its outputs and statistics into its caller's
  arrays (the C build's drivers, numba's of :data:`feeddrive.solvers.driver.NUMBA_NRT_FREE`);
* :func:`piece_source` and :func:`template_sources` give the pieces' text as the shared
  drivers' module (:mod:`feeddrive.solvers.shared`) holds them.

It reads the driver's module, its template and pieces by name; the driver's module never
imports this one.
"""

from __future__ import annotations

import ast
import functools
import inspect
import linecache
import operator
import textwrap
from collections.abc import Mapping, Sequence
from typing import Any

from . import driver, steps

# ---------------------------------------------------------------- specialisation
_COMPARE: dict[type, Any] = {ast.Eq: operator.eq, ast.NotEq: operator.ne, ast.Lt: operator.lt,
                             ast.LtE: operator.le, ast.Gt: operator.gt, ast.GtE: operator.ge,
                             ast.Is: operator.is_, ast.IsNot: operator.is_not}
_ARITHMETIC: dict[type, Any] = {ast.Add: operator.add, ast.Sub: operator.sub,
                               ast.Mod: operator.mod}


class _Fold(ast.NodeTransformer):
    """Names of ``consts`` replaced by their values; ``+``, ``-``, ``%`` of constants,
    comparisons, ``not``, ``and``/``or``,
    conditional expressions, ``if`` and ``while`` on constants folded (the unreachable
    branches dropped)."""

    def __init__(self, consts: Mapping[str, Any]) -> None:
        self.consts = consts

    def visit_Name(self, node: ast.Name) -> ast.expr:
        if isinstance(node.ctx, ast.Load) and node.id in self.consts:
            return ast.copy_location(ast.Constant(self.consts[node.id]), node)
        return node

    def visit_Compare(self, node: ast.Compare) -> ast.expr:
        self.generic_visit(node)
        operands = [node.left, *node.comparators]
        if not all(isinstance(o, ast.Constant) for o in operands):
            return node
        result = True
        for op, a, b in zip(node.ops, operands, operands[1:], strict=False):
            assert isinstance(a, ast.Constant) and isinstance(b, ast.Constant)
            result = result and bool(_COMPARE[type(op)](a.value, b.value))
        return ast.copy_location(ast.Constant(result), node)

    def visit_BinOp(self, node: ast.BinOp) -> ast.expr:
        self.generic_visit(node)
        if (isinstance(node.left, ast.Constant) and isinstance(node.right, ast.Constant)
                and type(node.op) in _ARITHMETIC):
            value = _ARITHMETIC[type(node.op)](node.left.value, node.right.value)
            return ast.copy_location(ast.Constant(value), node)
        return node

    def visit_UnaryOp(self, node: ast.UnaryOp) -> ast.expr:
        self.generic_visit(node)
        if isinstance(node.op, ast.Not) and isinstance(node.operand, ast.Constant):
            return ast.copy_location(ast.Constant(not node.operand.value), node)
        return node

    def visit_BoolOp(self, node: ast.BoolOp) -> ast.expr:
        self.generic_visit(node)
        decisive = isinstance(node.op, ast.Or)  # the value that decides the whole
        kept: list[ast.expr] = []
        for value in node.values:
            if isinstance(value, ast.Constant):
                if bool(value.value) == decisive and not any(
                        isinstance(n, ast.Call) for k in kept for n in ast.walk(k)):
                    return ast.copy_location(ast.Constant(decisive), node)
                if bool(value.value) != decisive:
                    continue  # no effect on the result
            kept.append(value)
        if not kept:
            return ast.copy_location(ast.Constant(not decisive), node)
        if len(kept) == 1:
            return kept[0]
        node.values = kept
        return node

    def visit_IfExp(self, node: ast.IfExp) -> ast.expr:
        self.generic_visit(node)
        if isinstance(node.test, ast.Constant):
            return node.body if node.test.value else node.orelse
        return node

    def visit_If(self, node: ast.If) -> Any:
        self.generic_visit(node)
        if isinstance(node.test, ast.Constant):
            return (node.body if node.test.value else node.orelse) or None
        if not node.body:
            node.body = [ast.Pass()]
        return node

    def visit_While(self, node: ast.While) -> Any:
        self.generic_visit(node)
        if isinstance(node.test, ast.Constant) and not node.test.value:
            return node.orelse or None
        return node

    def generic_visit(self, node: ast.AST) -> ast.AST:
        super().generic_visit(node)
        for field in ("body", "orelse"):
            block = getattr(node, field, None)
            if not isinstance(block, list):
                continue
            for k, stmt in enumerate(block):  # what follows a return is unreachable
                if isinstance(stmt, ast.Return):
                    del block[k + 1:]
                    break
            if field == "body" and not block and not isinstance(node, ast.Module):
                block.append(ast.Pass())  # a block emptied by the folding
        return node


_PURE_CALLS = {"int", "float", "min", "max", "abs"}


def _pure(node: ast.AST) -> bool:
    """No call in ``node`` but numpy constructors and arithmetic builtins."""
    for n in ast.walk(node):
        if isinstance(n, ast.Call):
            f = n.func
            if not ((isinstance(f, ast.Name) and f.id in _PURE_CALLS)
                    or (isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name)
                        and f.value.id == "np")):
                return False
    return True


def _scan(fn: ast.FunctionDef) -> tuple[dict[str, bool], set[str]]:
    """(the locals of ``fn`` every assignment of which stores one and the same bool constant,
    e.g. ``stiff`` where the method is DOPRI5 throughout; the locals never read whose every
    store is a plain or augmented assignment of a value without side effects — what the
    folding left of a flag's variables), in one walk."""
    params = {a.arg for a in fn.args.args}
    values: dict[str, set[Any]] = {}
    other: set[str] = set(params)  # stored otherwise than as one bool constant
    read: set[str] = set()
    removable: dict[str, bool] = {}
    for node in ast.walk(fn):
        if isinstance(node, ast.Name):
            if isinstance(node.ctx, ast.Load):
                read.add(node.id)
            continue
        if not isinstance(node, (ast.Assign, ast.AugAssign, ast.AnnAssign, ast.For)):
            continue
        targets = node.targets if isinstance(node, ast.Assign) else [node.target]
        name = targets[0].id if len(targets) == 1 and isinstance(targets[0], ast.Name) else None
        simple = (name is not None and isinstance(node, (ast.Assign, ast.AugAssign))
                  and _pure(node.value))
        if (name is not None and isinstance(node, ast.Assign)
                and isinstance(node.value, ast.Constant) and isinstance(node.value.value, bool)):
            values.setdefault(name, set()).add(node.value.value)
        else:
            for tgt in targets:
                other.update(n.id for n in ast.walk(tgt) if isinstance(n, ast.Name))
        for tgt in targets:
            for n in ast.walk(tgt):
                if isinstance(n, ast.Name):
                    removable[n.id] = removable.get(n.id, True) and simple
    constant = {name: next(iter(vals)) for name, vals in values.items()
                if len(vals) == 1 and name not in other}
    dead = {name for name, ok in removable.items()
            if ok and name not in read and name not in params}
    return constant, dead


class _DropAssign(ast.NodeTransformer):
    def __init__(self, names: set[str]) -> None:
        self.names = names

    def visit_Assign(self, node: ast.Assign) -> Any:
        if (len(node.targets) == 1 and isinstance(node.targets[0], ast.Name)
                and node.targets[0].id in self.names):
            return None
        return node

    def visit_AugAssign(self, node: ast.AugAssign) -> Any:
        if isinstance(node.target, ast.Name) and node.target.id in self.names:
            return None
        return node


@functools.cache
def _text_of(template: Any) -> str:
    """The source of ``template``, read once per process (``inspect`` tokenises the file)."""
    return textwrap.dedent(inspect.getsource(template))


def specialise(template: Any, name: str, params: Sequence[str], constants: Mapping[str, Any],
               doc: str, returns: str | None = None) -> str:
    """The text of ``template`` specialised: named ``name``, taking ``params`` (a subset of
    the template's parameters, in the caller's order), every name of ``constants`` replaced by
    its value and folded, the branches so made unreachable removed, and the locals left with one
    constant bool value folded as well (repeated until nothing changes).

    Parameters
    ----------
    template : function
        The template (:func:`feeddrive.solvers.driver.driver_template`).
    name : str
        The specialisation's function name.
    params : sequence of str
        Its parameters, in order.
    constants : mapping of str to object
        Flags and parameters fixed by the use, by name.
    doc : str
        Its docstring.
    returns : str, optional
        Its return annotation (none by default).

    Returns
    -------
    str
        Python source of the specialised function.

    Raises
    ------
    ValueError
        A parameter the template does not have, or one the specialisation still reads but
        neither takes nor assigns.
    """
    tree = ast.parse(_text_of(template))
    fn = tree.body[0]
    assert isinstance(fn, ast.FunctionDef)
    by_name = {a.arg: a for a in fn.args.args}
    unknown = [p for p in params if p not in by_name]
    if unknown:
        raise ValueError(f"{name}: {unknown} are not parameters of {fn.name}")
    fn.name = name
    fn.args.args = [by_name[p] for p in params]
    fn.body[0] = ast.Expr(ast.Constant(doc))  # the template's docstring
    fn.returns = None if returns is None else ast.Name(returns, ast.Load())
    consts = dict(constants)
    while True:
        tree = _Fold(consts).visit(tree)
        fn = tree.body[0]
        assert isinstance(fn, ast.FunctionDef)
        folded, dead = _scan(fn)
        if not folded and not dead:
            break
        tree = _DropAssign(set(folded) | dead).visit(tree)
        consts = folded
    assigned = {n.id for n in ast.walk(fn) if isinstance(n, ast.Name)
                and isinstance(n.ctx, ast.Store)}
    dropped = {a for a in by_name if a not in params and a not in assigned}
    read = {n.id for n in ast.walk(fn) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}
    if read & dropped:
        raise ValueError(f"{name}: reads {sorted(read & dropped)}, neither parameters nor "
                         "assigned")
    return ast.unparse(tree) + "\n"


_COUNTER = [0]


def define(source: str, name: str) -> Any:
    """The function ``name`` defined by ``source`` in the namespace of
    :mod:`feeddrive.solvers.driver` (its constants, placeholders and pieces) and as a function
    of that module (the C translator names its C functions after the module), its text
    registered with :mod:`linecache` so that :mod:`inspect` (the C translator) reads it.

    Parameters
    ----------
    source : str
        Python source defining ``name``.
    name : str
        The function's name.

    Returns
    -------
    function
        The function.
    """
    _COUNTER[0] += 1
    filename = f"<{driver.__name__}:{name}:{_COUNTER[0]}>"
    linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)
    namespace = dict(vars(driver))
    exec(compile(source, filename, "exec"), namespace)  # noqa: S102 - our own text
    fn = namespace[name]
    fn.__module__ = driver.__name__
    return fn


_FLAGS = ("LAND", "DENSE", "COMM")
_MODES = {name: getattr(driver, name)
          for name in ("MODE_DOPRI5", "MODE_RODAS4", "MODE_AUTO", "MODE_MODAL", "ROSENBROCK_5")}


@functools.cache
def source(use: str, inline: bool = True) -> str:
    """The text of the driver specialised for ``use`` (a key of
    :data:`feeddrive.solvers.driver.USES`), with the explicit step written in
    (:func:`feeddrive.solvers.steps.inline_steps`) unless ``inline`` is false (the C
    translation calls the step functions).  With ``inline``, numba's text (:func:`numba_text`),
    and for the uses of :data:`feeddrive.solvers.driver.NUMBA_NRT_FREE` the outputs and
    statistics written into the caller's arrays (:func:`lower_outputs`) and the caller's copy
    of ``y0`` advanced.

    Specialising costs ≈ 50 ms; a process does it only when it builds the shared drivers'
    module (:mod:`feeddrive.solvers.shared`, kept in the compile cache's folder) or an FMU.

    Parameters
    ----------
    use : str
        ``"integrate"``, ``"integrate_dense"`` or ``"advance"``.
    inline : bool, default True
        Write the step, error and controller functions into the text.

    Returns
    -------
    str
        Python source of the function ``use``.
    """
    if use not in driver.USES:
        raise KeyError(f"{use!r}: not a use of the driver ({', '.join(driver.USES)})")
    params, fixed, doc = driver.USES[use]
    constants = {**{flag: False for flag in _FLAGS}, **_MODES, **fixed}
    text = specialise(driver.driver_template, use, params, constants, doc,
                      "int" if use == "advance" else None)
    if not inline:
        return text
    text = numba_text(steps.inline_steps(text))
    if use in driver.NUMBA_NRT_FREE:  # its outputs, statistics and state in its caller's arrays
        tree, _ = lower_outputs(text)
        text = ast.unparse(ast.fix_missing_locations(_CallersCopy().visit(tree))) + "\n"
    return text


# ---------------------------------------------------------------- numba's text
#: numba's inliner (``inline="always"``) takes a call of at most this many positional
#: arguments, the model's (:data:`feeddrive.solvers.shared.MODEL_NAMES`) it adds among them:
#: CPython passes more (above 30) as ``*args`` (``CALL_FUNCTION_EX``), which it refuses
NUMBA_ARGS = 28
#: in numba's text a piece of more parameters than :data:`NUMBA_ARGS` takes those from this
#: one on as one tuple, ``bundle`` (:func:`numba_text`)
BUNDLE_FROM = 20
BUNDLE = "bundle"
_COLUMN = "j_col"  # the loop index of a row copied element by element (numba_text)


@functools.cache
def bundled_pieces() -> frozenset[str]:
    """The pieces numba's text passes their later arguments as one tuple (:func:`numba_text`):
    those of more than :data:`NUMBA_ARGS` parameters.

    Returns
    -------
    frozenset of str
        Their names.
    """
    out = set()
    for name in driver.PIECES:
        fn = ast.parse(_text_of(getattr(driver, name))).body[0]
        assert isinstance(fn, ast.FunctionDef)
        if len(fn.args.args) > NUMBA_ARGS:
            out.add(name)
    return frozenset(out)


class _NumbaText(ast.NodeTransformer):
    """numba's text of a driver or a piece (:func:`numba_text`)."""

    def __init__(self, bundled: frozenset[str]) -> None:
        self.bundled = bundled

    def visit_FunctionDef(self, node: ast.FunctionDef) -> ast.FunctionDef:
        self.generic_visit(node)
        if node.name in self.bundled:  # its later parameters one tuple, unpacked first
            later = node.args.args[BUNDLE_FROM:]
            node.args.args = [*node.args.args[:BUNDLE_FROM], ast.arg(BUNDLE)]
            unpack = ast.Assign([ast.Tuple([ast.Name(a.arg, ast.Store()) for a in later],
                                           ast.Store())], ast.Name(BUNDLE, ast.Load()))
            doc = ast.get_docstring(node, clean=False) is not None
            node.body.insert(1 if doc else 0, unpack)
        return node

    def visit_Call(self, node: ast.Call) -> ast.Call:
        self.generic_visit(node)
        if isinstance(node.func, ast.Name) and node.func.id in self.bundled:
            node.args = [*node.args[:BUNDLE_FROM],
                         ast.Tuple(node.args[BUNDLE_FROM:], ast.Load())]
        return node

    def visit_Assign(self, node: ast.Assign) -> ast.stmt:
        self.generic_visit(node)
        target = node.targets[0]
        if (len(node.targets) == 1 and isinstance(target, ast.Subscript)
                and isinstance(target.slice, ast.Tuple) and len(target.slice.elts) == 2
                and ast.unparse(target.slice.elts[1]) == ":"
                and isinstance(node.value, ast.Name)):  # out[i, :] = v, element by element
            row, source = target.slice.elts[0], node.value.id
            copy = ast.parse(f"for {_COLUMN} in range({source}.size):\n"
                             f"    {ast.unparse(target.value)}[{ast.unparse(row)}, {_COLUMN}] = "
                             f"{source}[{_COLUMN}]").body[0]
            return ast.copy_location(copy, node)
        return node


def numba_text(text: str) -> str:
    """A driver's or a piece's text as numba compiles it: a piece of more than
    :data:`NUMBA_ARGS` parameters takes those from :data:`BUNDLE_FROM` on as one tuple
    (``bundle``, unpacked first) and is called so — numba's inliner refuses a call CPython
    makes with ``*args`` —, and a row written from an array (``out[i, :] = v``) is copied
    element by element (numba's slice assignment may copy its source first: an allocation,
    which a driver compiled without numba's runtime cannot make).  The same operations on the
    same numbers: the results are bit-identical.

    Parameters
    ----------
    text : str
        Python source.

    Returns
    -------
    str
        The source as numba's text has it.
    """
    tree = _NumbaText(bundled_pieces()).visit(ast.parse(text))
    return ast.unparse(ast.fix_missing_locations(tree)) + "\n"


class _CallersCopy(ast.NodeTransformer):
    """``y = y0.copy()`` → ``y = y0``: a driver compiled without numba's runtime advances the
    state its caller copied (:data:`feeddrive.solvers.driver.NUMBA_NRT_FREE`)."""

    def visit_Assign(self, node: ast.Assign) -> ast.Assign:
        if ast.unparse(node) == "y = y0.copy()":
            node.value = ast.Name("y0", ast.Load())
        return node


# ---------------------------------------------------------------- the drivers' outputs lowered
#: the drivers' output arrays → the caller's buffers the lowered text writes
#: (:func:`lower_outputs`: the C build's drivers, numba's)
OUTPUTS = {"t_out": "t_buf", "y_out": "y_buf", "aux_out": "aux_buf"}
STATS = "stats"  # the statistics array the driver's text makes
STATS_OUT = "stats_out"  # the caller's array the lowered text writes them into


class _Lower(ast.NodeTransformer):
    """A driver's text writing its outputs into its caller's buffers (:func:`lower_outputs`);
    a text not of the expected form raises ``error``."""

    def __init__(self, error: type[Exception]) -> None:
        self.error = error
        self.n_stats = 0
        self.count: ast.expr | None = None

    def visit_Assign(self, node: ast.Assign) -> Any:
        tgt = node.targets[0] if len(node.targets) == 1 else None
        if isinstance(tgt, ast.Name) and tgt.id in OUTPUTS:
            return None  # the caller's buffer
        if isinstance(tgt, ast.Name) and tgt.id == STATS:
            value = node.value
            if not (isinstance(value, ast.Call) and ast.unparse(value.func) == "np.array"
                    and len(value.args) == 1 and isinstance(value.args[0], ast.List)):
                raise self.error(f"{ast.unparse(node)!r}: the driver's statistics are "
                                 "not an np.array([...]) (lowered_source needs updating)")
            items = value.args[0].elts
            self.n_stats = len(items)
            # one statement, as numba's np.array([...]): stats_out[0], ... = a, ...
            return ast.Assign([ast.Tuple([ast.Subscript(ast.Name(STATS_OUT, ast.Load()),
                                                        ast.Constant(k), ast.Store())
                                          for k in range(len(items))], ast.Store())],
                              ast.Tuple(items, ast.Load()), lineno=node.lineno)
        self.generic_visit(node)
        return node

    def visit_Name(self, node: ast.Name) -> ast.Name:
        if node.id in OUTPUTS:
            return ast.copy_location(ast.Name(OUTPUTS[node.id], node.ctx), node)
        return node

    def visit_If(self, node: ast.If) -> Any:
        self.generic_visit(node)
        empty = all(isinstance(s, ast.Pass) for s in node.body + node.orelse)
        if empty and not any(isinstance(n, ast.Call) for n in ast.walk(node.test)
                             if not (isinstance(n, ast.Call) and isinstance(n.func, ast.Name)
                                     and n.func.id in ("min", "max", "int", "float"))):
            return None  # the choice between the caller's buffers and new arrays
        if not node.body:
            node.body = [ast.Pass()]
        return node

    def visit_Return(self, node: ast.Return) -> Any:
        value = node.value
        if value is None or (isinstance(value, ast.Constant) and value.value is None):
            return node
        first = value.elts[0] if isinstance(value, ast.Tuple) and value.elts else None
        if not (isinstance(first, ast.Subscript) and isinstance(first.slice, ast.Slice)
                and first.slice.lower is None and first.slice.upper is not None
                and isinstance(first.value, ast.Name) and first.value.id == "t_out"):
            raise self.error(f"{ast.unparse(node)!r}: the driver's result is not "
                             "(t_out[:count], ...) (lowered_source needs updating)")
        self.count = first.slice.upper
        return ast.copy_location(ast.Return(first.slice.upper), node)

    def generic_visit(self, node: ast.AST) -> ast.AST:
        super().generic_visit(node)
        for name in ("body", "orelse"):
            block = getattr(node, name, None)
            if (name == "body" and isinstance(block, list) and not block
                    and not isinstance(node, ast.Module)):
                block.append(ast.Pass())
        return node


def _array_arg(name: str) -> ast.arg:
    return ast.arg(arg=name, annotation=ast.Attribute(ast.Name("np", ast.Load()), "ndarray",
                                                      ast.Load()))


def lower_outputs(text: str, error: type[Exception] = ValueError) -> tuple[ast.Module, int]:
    """A driver's function text (:func:`source`) lowered to write into its caller's arrays:
    its outputs into ``t_buf``, ``y_buf``, ``aux_buf`` (added as parameters where the use has
    none), its statistics into ``stats_out`` (a last parameter), its result the number of
    outputs written — what the C build's drivers take and give
    (:func:`feeddrive.backends.c_engine.lowered_source`), and numba's drivers, compiled
    without numba's runtime (:data:`feeddrive.solvers.driver.NUMBA_NRT_FREE`), which cannot
    return a view of an array.

    Parameters
    ----------
    text : str
        The driver's function text.
    error : type, default ValueError
        Raised where the text's outputs, statistics or result are not of the expected form.

    Returns
    -------
    tree : ast.Module
        The lowered text.
    n_stats : int
        The length of the statistics.
    """
    tree = ast.parse(text)
    fn = tree.body[0]
    assert isinstance(fn, ast.FunctionDef)
    have = {a.arg for a in fn.args.args}
    fn.args.args += [_array_arg(b) for b in OUTPUTS.values() if b not in have]
    fn.args.args.append(_array_arg(STATS_OUT))
    fn.returns = None
    lower = _Lower(error)
    tree = ast.fix_missing_locations(lower.visit(tree))
    if lower.count is None or not lower.n_stats:
        raise error(f"{fn.name}: no statistics or result found in the driver's text "
                    "(lowered_source needs updating)")
    return tree, lower.n_stats


@functools.cache
def piece_source(name: str, inline: bool = True) -> str:
    """The text of the driver's piece ``name`` (:data:`feeddrive.solvers.driver.PIECES`), with
    the explicit step's functions written in (:func:`feeddrive.solvers.steps.inline_steps`)
    unless ``inline`` is false (the C translation calls them).

    Parameters
    ----------
    name : str
        A piece.
    inline : bool, default True
        Write the step, error and controller functions into the text (and make it numba's:
        :func:`numba_text`).

    Returns
    -------
    str
        Python source of the function ``name``.
    """
    if name not in driver.PIECES:
        raise KeyError(f"{name!r}: not a piece of the driver ({', '.join(driver.PIECES)})")
    text = _text_of(getattr(driver, name))
    return numba_text(steps.inline_steps(text)) if inline else text


def template_sources() -> list[str]:
    """Text placed in the shared drivers' module before the drivers: the pieces they call
    (:data:`feeddrive.solvers.driver.PIECES`), which numba inlines into them (``inline="always"``).

    Returns
    -------
    list of str
        Python sources.
    """
    return ["from feeddrive._jit import inline_kernel",
            f"from feeddrive.solvers.driver import ({', '.join(driver.STATUS_NAMES)})",
            "from feeddrive.solvers.schedule import next_instant",
            "from feeddrive.solvers.driver import (POWER_ITERATIONS, MEMORY_SCALARS, "
            "MODAL_SWITCH_GAIN, RODAS4_COST, NONSTIFF_HRHO, NONSTIFF_STEPS, MODAL_RETRY, "
            "STIFF_HLAMBDA, STIFF_STEPS, MODAL_EVERY, DOPRI5_STABILITY, R4_EXPONENT, "
            "R5_EXPONENT, R4_STAGES, R5_STAGES)",
            "from feeddrive.solvers.global_error import INTERVAL as GE_INTERVAL, "
            "REFRESH_STEPS as GE_REFRESH, advance as ge_advance, exponential as ge_exponential",
            "from feeddrive.solvers.modes import step_cap as modal_step_cap, "
            "ZETA_LIGHT as MODAL_ZETA_LIGHT, H_LAMBDA as MODAL_H_LAMBDA, "
            "REFRESH as MODAL_REFRESH, jacobian_moved as modal_jacobian_moved",
            *("@inline_kernel\n" + piece_source(name) for name in driver.PIECES)]
