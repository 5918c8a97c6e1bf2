"""The generic steps: one explicit embedded Runge–Kutta step and one Rosenbrock step, written
for any tableau of :mod:`feeddrive.solvers.tableaux`, and the weighted error norm.

A step is written out from its tableau as a function in the restricted Python of the
package's kernels (the loops unrolled over the stages, the coefficients inlined as literals),
then compiled by numba once, in the shared drivers' module (:func:`template_sources`,
:mod:`feeddrive.solvers.shared`; an FMU's module has its own copy next to its ``rhs``), and
translated to C by :mod:`feeddrive.backends.c_translate` for
the FMU (:func:`explicit_step`, :func:`rosenbrock_step` return the Python function).  Writing
it out — instead of looping over the tableau at run time — keeps the step as fast as a
hand-written one (the stage count and every coefficient are compile-time constants) and its
arithmetic that of the hand-written step it replaces, operation for operation:

* explicit stage s: ``yt = y + h·Σ_j a_sj k_j`` (one term: ``h·a·k``), then
  ``k_s = f(t + c_s h, yt)``; the solution ``y_new = y + h·Σ b_j k_j``; with FSAL the
  derivative at (t_new, y_new); zero coefficients are left out;
* the error estimate and the continuous extension's last vector, ``h·Σ w_j k_j`` over the
  stages (:func:`explicit_combination`);
* Rosenbrock stage s (increment form, :class:`~feeddrive.solvers.tableaux.RosenbrockTableau`):
  ``u_s = (I/(γh) − J)⁻¹ (f(t + c_s h, y + Σ a_sj u_j) + d_s h f_t + Σ (c_sj/h) u_j)``, one LU
  factorisation per step; states assumed frozen (``live`` false) are checked to keep a zero
  derivative at every stage.

The right-hand side is called as ``rhs(t, y, held, P, T, dy, aux)``: everything a model needs
is in its vectors (a sampled loop reads its period from ``P``), so a step serves every model.
"""

from __future__ import annotations

import ast
import functools
import inspect
import linecache
import math
import textwrap
from collections.abc import Callable
from typing import Any

import numpy as np

from . import placeholders
from .rodas4 import lu_factor, lu_solve  # noqa: F401 - called by the Rosenbrock step
from .tableaux import DOPRI5, RODAS4, RODAS5P, ExplicitTableau, RosenbrockTableau

# the model arguments of every right-hand-side call between the state and the outputs
RHS_ARGS = "held, P, T"


def error_norm_template(e: np.ndarray, y: np.ndarray, y_new: np.ndarray, rtol: float,
                        atol: np.ndarray, rel_mask: np.ndarray) -> float:
    """RMS of the error estimate ``e`` weighted by atol + rtol·max(|y|, |y_new|) (relative part
    only where ``rel_mask``); a non-finite norm counts as a failed step.

    Parameters
    ----------
    e : numpy.ndarray
        Error estimate of the step [SI, per state].
    y : numpy.ndarray
        State at the start of the step [SI, per state].
    y_new : numpy.ndarray
        State at its end [SI, per state].
    rtol : float
        Relative tolerance [-].
    atol : numpy.ndarray
        Absolute tolerance per state [SI, per state].
    rel_mask : numpy.ndarray
        1 where the relative tolerance applies [-].

    Returns
    -------
    float
        The norm [-]; inf when not finite.

    References
    ----------
    .. [1] E. Hairer, S. P. Nørsett, G. Wanner, Solving Ordinary Differential Equations I,
       2nd ed., Springer, 1993, Sect. II.4, Eq. (4.11).
    """
    n = e.size
    err = 0.0
    for i in range(n):
        scale = atol[i] + rtol * rel_mask[i] * max(abs(y[i]), abs(y_new[i]))
        r = e[i] / scale
        err += r * r
    err = math.sqrt(err / n)
    if not math.isfinite(err):
        err = 1e10
    return err


def pi_factor_template(err: float, err_old: float, alpha: float, beta: float) -> float:
    """The step-size controller of the explicit steps: after an accepted step with error norm
    ``err`` (``err_old``: the previous accepted step's, floored at 1e-4), the next step is
    this factor times the last — Hairer's PI controller 0.9·err^(−α)·err_old^β in [0.2, 5],
    5 after an exact step (Hairer, Nørsett & Wanner, Solving ODEs I, Sect. II.4, and their
    ``dopri5.f``; α = 0.2 − 0.75β, β = 0.04).

    Parameters
    ----------
    err : float
        Error norm of the accepted step [-].
    err_old : float
        That of the previous accepted step [-].
    alpha : float
        Exponent α [-].
    beta : float
        Exponent β [-].

    Returns
    -------
    float
        The step-size factor, in [0.2, 5] [-].

    References
    ----------
    .. [1] E. Hairer, S. P. Nørsett, G. Wanner, Solving Ordinary Differential Equations I,
       2nd ed., Springer, 1993, Sect. II.4, and their ``dopri5.f``.
    """
    fac = 5.0
    if err != 0.0:
        fac = min(5.0, max(0.2, 0.9 * err ** (-alpha) * err_old ** beta))
    return fac


def reject_factor_template(err: float) -> float:
    """The factor of the retry after a rejected explicit step of error norm ``err`` > 1:
    0.9·err^(−1/5), at least 0.2 (``dopri5.f``).

    Parameters
    ----------
    err : float
        Error norm of the rejected step, > 1 [-].

    Returns
    -------
    float
        The step-size factor [-].
    """
    fac = max(0.2, 0.9 * err ** (-0.2))
    return fac


def _num(x: float) -> str:
    return repr(float(x))


def _sum(terms: list[tuple[float, str]]) -> str:
    """``w1 * v1 + w2 * v2 …`` (zero weights left out; a negative weight as a subtraction,
    which IEEE arithmetic makes the same number)."""
    out = ""
    for w, v in terms:
        if w == 0.0:
            continue
        if not out:
            out = f"{_num(w)} * {v}"
        elif w < 0:
            out += f" - {_num(-w)} * {v}"
        else:
            out += f" + {_num(w)} * {v}"
    return out


def _h_times(terms: list[tuple[float, str]]) -> str:
    """``h * w * v`` for one non-zero term, ``h * (Σ w v)`` for more."""
    live = [(w, v) for w, v in terms if w != 0.0]
    if len(live) == 1:
        return f"h * {_num(live[0][0])} * {live[0][1]}"
    return f"h * ({_sum(live)})"


def _at(c: float) -> str:
    if c == 1.0:
        return "t + h"
    return f"t + {_num(c)} * h"


_SCALARS = {"t": "float", "h": "float", "t_new": "float"}


def _signature(name: str, args: str, returns: str) -> str:
    """``def name(a: type, …) -> returns:`` (the C translator reads the annotations)."""
    typed = ", ".join(f"{a}: {_SCALARS.get(a, 'np.ndarray')}"
                      for a in (x.strip() for x in args.split(",")))
    return f"def {name}({typed}) -> {returns}:"


def _stage_names(tab: ExplicitTableau) -> list[str]:
    """k1 … kS and, with FSAL, the new point's stage k(S+1)."""
    return [f"k{s + 1}" for s in range(len(tab.e))]


def explicit_step_source(tab: ExplicitTableau, name: str) -> str:
    """The text of one step of ``tab`` as a function ``name``::

        name(t, h, y, k1, held, P, T, k2, …, kS[, k_new], yt, y_new, aux, t_new)

    ``k1`` = f(t, y) is given; the step leaves y_new, the stages and (FSAL) k_new =
    f(t_new, y_new); ``yt`` keeps the last stage's argument (the stiffness test of
    :mod:`feeddrive.solvers.switching` compares it with y_new).

    Parameters
    ----------
    tab : ExplicitTableau
        The explicit embedded Runge–Kutta pair (:mod:`feeddrive.solvers.tableaux`).
    name : str
        The function's name in the generated text.

    Returns
    -------
    str
        Python source of the function (annotated, for the C translator).

    References
    ----------
    .. [1] E. Hairer, S. P. Nørsett, G. Wanner, Solving Ordinary Differential Equations I,
       2nd ed., Springer, 1993, Sect. II.1 (explicit Runge–Kutta methods), Sect. II.4
       (embedded pairs); DOPRI5: J. R. Dormand, P. J. Prince, J. Comput. Appl. Math. 6 (1980)
       19–26.
    """
    ks = _stage_names(tab)
    S = len(tab.c)
    lines = [_signature(name, f"t, h, y, k1, {RHS_ARGS}, {', '.join(ks[1:])}, yt, y_new, aux, "
                              "t_new", "None"),
             f'    """One {tab.name} step (feeddrive.solvers.tableaux; written by '
             'feeddrive.solvers.steps)."""',
             "    n = y.size"]
    for s in range(1, S):
        comb = _h_times([(a, f"{ks[j]}[i]") for j, a in enumerate(tab.a[s])])
        lines += ["    for i in range(n):",
                  f"        yt[i] = y[i] + {comb}",
                  f"    rhs({_at(tab.c[s])}, yt, {RHS_ARGS}, {ks[s]}, aux)"]
    comb = _h_times([(b, f"{ks[j]}[i]") for j, b in enumerate(tab.b)])
    lines += ["    for i in range(n):", f"        y_new[i] = y[i] + {comb}"]
    if tab.fsal:
        lines.append(f"    rhs(t_new, y_new, {RHS_ARGS}, {ks[-1]}, aux)")
    return "\n".join(lines) + "\n"


def explicit_combination_source(tab: ExplicitTableau, weights: tuple[float, ...],
                                name: str) -> str:
    """``name(h, k1, …, out)``: out = h·Σ w_j k_j over the stages of ``e`` (the error
    estimate with ``tab.e``, the continuous extension's last vector with ``tab.dense``).

    Parameters
    ----------
    tab : ExplicitTableau
        The explicit embedded Runge–Kutta pair (:mod:`feeddrive.solvers.tableaux`).
    weights : tuple of float
        The combination's weights, one per stage [-].
    name : str
        The function's name in the generated text.

    Returns
    -------
    str
        Python source of the function (annotated, for the C translator).
    """
    ks = _stage_names(tab)
    comb = _h_times([(w, f"{k}[i]") for w, k in zip(weights, ks, strict=True)])
    return (_signature(name, f"h, {', '.join(ks)}, out", "None") + "\n"
            f'    """h · Σ w_j k_j of the {tab.name} stages (feeddrive.solvers.steps)."""\n'
            "    for i in range(out.size):\n"
            f"        out[i] = {comb}\n")


def rosenbrock_step_source(tab: RosenbrockTableau, name: str) -> str:
    """The text of one step of the Rosenbrock method ``tab`` as a function ``name``::

        name(t, h, y, f0, J, ft, held, P, T, M, piv, u1, …, uS, yt, fs, y_new, aux, live)

    y_new, the error estimate u_S and the increments u_1 … u_S−1 (dense output).  Returns the
    number of right-hand-side evaluations (S − 1), −1 if the matrix is singular, −2 if a state
    assumed frozen (``live`` false) got a non-zero derivative.

    Parameters
    ----------
    tab : RosenbrockTableau
        The Rosenbrock method (:mod:`feeddrive.solvers.tableaux`).
    name : str
        The function's name in the generated text.

    Returns
    -------
    str
        Python source of the function (annotated, for the C translator).

    References
    ----------
    .. [1] E. Hairer, G. Wanner, Solving Ordinary Differential Equations II, 2nd ed.,
       Springer, 1996, Sect. IV.7.
    """
    S = len(tab.c)
    us = [f"u{s + 1}" for s in range(S)]
    lines = [_signature(name, f"t, h, y, f0, J, ft, {RHS_ARGS}, M, piv, {', '.join(us)}, yt, "
                              "fs, y_new, aux, live", "int"),
             f'    """One {tab.name} step (feeddrive.solvers.tableaux; written by '
             'feeddrive.solvers.steps)."""',
             "    n = y.size",
             f"    g = 1.0 / ({_num(tab.gamma)} * h)",
             "    for i in range(n):",
             "        for j in range(n):",
             "            M[i, j] = -J[i, j]",
             "        M[i, i] += g",
             "    if not lu_factor(M, piv):",
             "        return -1",
             "    ih = 1.0 / h",
             "    frozen_ok = True"]

    def increment(s: int, f: str) -> str:
        out = f
        if tab.d[s] != 0.0:
            out += f" + h * {_num(tab.d[s])} * ft[i]"
        cc = [(c, f"{us[j]}[i]") for j, c in enumerate(tab.cc[s]) if c != 0.0]
        if len(cc) == 1:
            out += f" + {_num(cc[0][0])} * ih * {cc[0][1]}"
        elif cc:
            out += f" + ih * ({_sum(cc)})"
        return out

    lines += ["    for i in range(n):", f"        u1[i] = {increment(0, 'f0[i]')}",
              "    lu_solve(M, piv, u1)"]
    for s in range(1, S):
        if s >= 2 and tuple(tab.a[s]) == (*tab.a[s - 1], 1.0):
            lines += ["    for i in range(n):", f"        yt[i] += {us[s - 1]}[i]"]
        else:
            terms = "".join(f" + {_num(a)} * {us[j]}[i]" if a >= 0
                            else f" - {_num(-a)} * {us[j]}[i]"
                            for j, a in enumerate(tab.a[s]) if a != 0.0)
            lines += ["    for i in range(n):", f"        yt[i] = y[i]{terms}"]
        lines += [f"    rhs({_at(tab.c[s])}, yt, {RHS_ARGS}, fs, aux)",
                  "    for i in range(n):",
                  "        if not live[i] and fs[i] != 0.0:",
                  "            frozen_ok = False",
                  f"        {us[s]}[i] = {increment(s, 'fs[i]')}",
                  f"    lu_solve(M, piv, {us[s]})"]
    lines += ["    for i in range(n):", f"        y_new[i] = yt[i] + {us[-1]}[i]",
              "    if not frozen_ok:", "        return -2", f"    return {S - 1}"]
    return "\n".join(lines) + "\n"


def rosenbrock_dense_source(tab: RosenbrockTableau, name: str) -> str:
    """``name(u1, …, u(S−1) or uS, q1, q2[, q3])``: the dense-output vectors of the step just
    taken (over the increments and rows the tableau's ``dense`` holds).

    Parameters
    ----------
    tab : RosenbrockTableau
        The Rosenbrock method (:mod:`feeddrive.solvers.tableaux`).
    name : str
        The function's name in the generated text.

    Returns
    -------
    str
        Python source of the function (annotated, for the C translator).
    """
    us = [f"u{s + 1}" for s in range(len(tab.dense[0]))]
    qs = [f"q{r + 1}" for r in range(len(tab.dense))]
    body = [f"        {q}[i] = {_sum([(w, f'{u}[i]') for w, u in zip(row, us, strict=True)])}"
            for q, row in zip(qs, tab.dense, strict=True)]
    return (_signature(name, f"{', '.join(us)}, {', '.join(qs)}", "None") + "\n"
            f'    """The {tab.name} dense-output vectors (feeddrive.solvers.steps)."""\n'
            f"    for i in range({us[0]}.size):\n" + "\n".join(body) + "\n")


_COUNTER = [0]


def _define(source: str, name: str, scope: dict[str, Any] | None = None) -> Any:
    """The function ``name`` defined by ``source`` in this module's namespace (``scope``:
    names that replace its globals, e.g. a test's ``rhs``), its text registered with
    :mod:`linecache` so that :mod:`inspect` (numba's cache, the C translator) reads it."""
    _COUNTER[0] += 1
    filename = f"<feeddrive.solvers.steps:{name}:{_COUNTER[0]}>"
    linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)
    namespace = {**globals(), "rhs": placeholders.rhs, **(scope or {})}
    local: dict[str, Any] = {}
    exec(compile(source, filename, "exec"), namespace, local)  # noqa: S102 - our own text
    fn = local[name]
    fn.__module__ = __name__
    return fn


# The Python functions of the project's steps (the C translator and the tests read them);
# their text is what template_sources places in the generated modules.
STEP_NAMES = {"dp5_step": "_dp5_step", "dp5_error": "_dp5_error", "dp5_dense": "_dp5_dense",
              "rodas4_step": "_r4_rodas4_step", "rodas4_dense": "_r4_rodas4_dense",
              "rodas5p_step": "_r5_rodas5p_step", "rodas5p_dense": "_r5_rodas5p_dense"}


@functools.cache
def sources() -> dict[str, str]:
    """The generated text of every step function, by name in the generated modules.

    Returns
    -------
    dict of str to str
        Function name → Python source.
    """
    return {
        "_dp5_step": explicit_step_source(DOPRI5, "_dp5_step"),
        "_dp5_error": explicit_combination_source(DOPRI5, DOPRI5.e, "_dp5_error"),
        "_dp5_dense": explicit_combination_source(DOPRI5, DOPRI5.dense, "_dp5_dense"),
        "_r4_rodas4_step": rosenbrock_step_source(RODAS4, "_r4_rodas4_step"),
        "_r4_rodas4_dense": rosenbrock_dense_source(RODAS4, "_r4_rodas4_dense"),
        "_r5_rodas5p_step": rosenbrock_step_source(RODAS5P, "_r5_rodas5p_step"),
        "_r5_rodas5p_dense": rosenbrock_dense_source(RODAS5P, "_r5_rodas5p_dense"),
    }


@functools.cache
def function(name: str) -> Any:
    """The Python function of the generated step ``name`` (a key of :func:`sources`).

    Parameters
    ----------
    name : str
        A key of :func:`sources`.

    Returns
    -------
    function
        The function.
    """
    return _define(sources()[name], name)


def explicit_step(tab: ExplicitTableau, rhs: Any = None) -> Any:
    """The Python function of one step of ``tab`` (for tests and the C translator), calling
    ``rhs`` (default: the placeholder the generated modules replace).

    Parameters
    ----------
    tab : ExplicitTableau
        The explicit embedded Runge–Kutta pair (:mod:`feeddrive.solvers.tableaux`).
    rhs : callable, optional
        The right-hand side the step calls.

    Returns
    -------
    function
        The step.
    """
    return _define(explicit_step_source(tab, f"_{tab.name}_step"), f"_{tab.name}_step",
                   None if rhs is None else {"rhs": rhs})


def explicit_error(tab: ExplicitTableau) -> Any:
    """The Python function computing ``tab``'s error estimate h·Σ e_j k_j.

    Parameters
    ----------
    tab : ExplicitTableau
        The explicit embedded Runge–Kutta pair (:mod:`feeddrive.solvers.tableaux`).

    Returns
    -------
    function
        The error function.
    """
    return _define(explicit_combination_source(tab, tab.e, f"_{tab.name}_error"),
                   f"_{tab.name}_error")


def rosenbrock_step(tab: RosenbrockTableau, rhs: Any = None) -> Any:
    """The Python function of one step of the Rosenbrock method ``tab``, calling ``rhs``.

    Parameters
    ----------
    tab : RosenbrockTableau
        The Rosenbrock method (:mod:`feeddrive.solvers.tableaux`).
    rhs : callable, optional
        The right-hand side the step calls.

    Returns
    -------
    function
        The step.
    """
    return _define(rosenbrock_step_source(tab, f"_{tab.name}_step"), f"_{tab.name}_step",
                   None if rhs is None else {"rhs": rhs})


_HAND_WRITTEN: dict[str, Any] = {"_error_norm": error_norm_template,
                                  "_pi_factor": pi_factor_template,
                                  "_reject_factor": reject_factor_template}


@functools.cache
def _norm_source(name: str = "_error_norm") -> str:
    fn = _HAND_WRITTEN[name]
    return inspect.getsource(fn).replace(f"def {fn.__name__}(", f"def {name}(", 1)


class _Rename(ast.NodeTransformer):
    """Names replaced by expressions (a function's parameters by a call's arguments)."""

    def __init__(self, names: dict[str, ast.expr]) -> None:
        self.names = names

    def visit_Name(self, node: ast.Name) -> ast.expr:
        return self.names.get(node.id, node)


def renamed_body(name: str, fn: ast.FunctionDef, call: ast.Call,
                 target: ast.expr | None) -> list[ast.stmt]:
    """The statements of ``fn`` (the function ``name``) with its parameters renamed to the
    argument expressions of ``call``, its docstring left out and a final ``return x`` made
    ``target = x``: what a call statement becomes when the function is written in.

    Parameters
    ----------
    name : str
        The function's name (for the messages).
    fn : ast.FunctionDef
        Its definition.
    call : ast.Call
        The call written over.
    target : ast.expr or None
        The call statement's assignment target.

    Returns
    -------
    list of ast.stmt
        The statements.

    Raises
    ------
    ValueError
        Arguments other than one positional per parameter; a returned value with no target.
    """
    params = [a.arg for a in fn.args.args]
    if len(call.args) != len(params) or call.keywords:
        raise ValueError(f"{name}: called with {len(call.args)} positional arguments for "
                         f"{len(params)} parameters")
    rename = _Rename(dict(zip(params, call.args, strict=True)))
    out: list[ast.stmt] = []
    for stmt in fn.body:
        if isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Constant):
            continue  # the docstring
        if isinstance(stmt, ast.Return):
            if target is None or stmt.value is None:
                raise ValueError(f"{name}: a returned value needs an assignment target")
            stmt = ast.Assign(targets=[target], value=stmt.value, lineno=0)
        out.append(rename.visit(stmt))
    return out


def _body(name: str, call: ast.Call, target: ast.expr | None) -> list[str]:
    """The statements of step function ``name`` written in for ``call``
    (:func:`renamed_body`), as text."""
    source = _norm_source(name) if name in _HAND_WRITTEN else sources()[name]
    fn = ast.parse(source).body[0]
    assert isinstance(fn, ast.FunctionDef)
    return [line for stmt in renamed_body(name, fn, call, target)
            for line in ast.unparse(stmt).splitlines()]


def write_in(source: str, names: tuple[str, ...],
             body: Callable[[str, ast.Call, ast.expr | None], list[str]]) -> str:
    """``source`` (a function's text) with every call statement of the functions ``names``
    — ``name(args)`` or ``target = name(args)`` — replaced by ``body(name, call, target)``,
    indented as the statement was.

    Parameters
    ----------
    source : str
        The function's text.
    names : tuple of str
        The functions whose calls are written over.
    body : callable
        The lines that replace a call statement.

    Returns
    -------
    str
        The text with the calls replaced.
    """
    lines = source.splitlines()
    tree = ast.parse(textwrap.dedent(source))
    found: list[tuple[int, int, int, list[str]]] = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.stmt):
            continue
        value, target = None, None
        if isinstance(node, ast.Expr):
            value = node.value
        elif isinstance(node, ast.Assign) and len(node.targets) == 1:
            value, target = node.value, node.targets[0]
        if (isinstance(value, ast.Call) and isinstance(value.func, ast.Name)
                and value.func.id in names):
            assert node.end_lineno is not None
            found.append((node.lineno, node.end_lineno, node.col_offset,
                          body(value.func.id, value, target)))
    for start, end, col, text in sorted(found, reverse=True):
        lines[start - 1:end] = [" " * col + ln for ln in text]
    return "\n".join(lines) + "\n"


INLINED = ("_dp5_step", "_dp5_error", "_dp5_dense", "_error_norm", "_pi_factor",
           "_reject_factor")


def inline_steps(source: str, names: tuple[str, ...] = INLINED) -> str:
    """``source`` (a driver's function text) with every call statement of the written steps
    ``names`` — ``name(args)`` or ``target = name(args)`` — replaced by the step's body with
    its parameters renamed to the arguments: the text numba compiles is then what a
    hand-inlined step was (a call per step, with its array arguments reference-counted, cost
    ~10 % of a DOPRI5 run of a drive: benchmarks/bench_old_new.py).  The C translation keeps
    the calls (:mod:`feeddrive.fmu.solver`): both build the same step text.

    Parameters
    ----------
    source : str
        The driver's function text.
    names : tuple of str, default INLINED
        The step functions to inline.

    Returns
    -------
    str
        The text with the step calls replaced by their bodies.
    """
    return write_in(source, names, _body)


def template_sources() -> list[str]:
    """Text placed in the shared drivers' module (and an FMU's): the error norm and every step
    function
    (the driver's specialisations have the explicit step written into their text,
    :func:`inline_steps`; the FMU's integrator and the Rosenbrock branch call them).

    Returns
    -------
    list of str
        Python sources.
    """

    return (["@kernel\n" + _norm_source(name) for name in _HAND_WRITTEN]
            + ["@kernel\n" + src for src in sources().values()])
