"""Order conditions of the methods in :mod:`feeddrive.solvers.tableaux`, checked when a tableau
is built: a mistyped coefficient raises :class:`OrderConditionError` naming the condition,
instead of silently lowering the method's order.

* Explicit Runge–Kutta: for every rooted tree t with ρ(t) ≤ p nodes, Σ_i b_i Φ_i(t) = 1/γ(t)
  (Butcher's conditions, E. Hairer, S. P. Nørsett and G. Wanner, *Solving Ordinary
  Differential Equations I*, 2nd ed., Springer (1993), Sect. II.2, Theorem 2.13), for the
  solution (order p), the embedded solution (its order; with ``fsal`` over the stages and the
  new point, whose row is b) and the continuous extension (Sect. II.6: Σ_i b_i(θ) Φ_i(t) =
  θ^ρ(t)/γ(t) for ρ(t) ≤ its order, at several θ), and c_i = Σ_j a_ij.
* Rosenbrock: the conditions of Hairer and Wanner, *Solving Ordinary Differential Equations
  II*, 2nd ed., Springer (1996), Sect. IV.7 (its Table 7.1 lists those of order ≤ 4), for every
  rooted tree t with ρ(t) ≤ p nodes: Σ_i b_i Φ_i(t) = 1/γ(t), where Φ links a vertex
  with one son to it by β_ij = α_ij + γ_ij (the diagonal γ included: the Jacobian's term) and a
  vertex with several sons to each by α_ij; in the method's standard form, obtained from the
  increment form (7.25) by Γ = (I/γ − C)^{-1}, α = A Γ, b = m Γ (7.26).  Also c_i = α_i and
  d_i = Σ_j γ_ij (the non-autonomous terms, (7.4')), and for the dense output the same
  conditions up to order p − 1 with b_i(θ) and the right-hand sides θ^ρ(t)/γ(t) (Sect. IV.7,
  "Dense output").  Written out for order ≤ 4 the trees give Table 7.1's rows (e.g.
  Σ b_i β'_i = 1/2 − γ, Σ b_i β_ij β'_j = 1/6 − γ + γ²).

The sums are formed the same on every machine: each product rounded once, the terms added by
``math.fsum`` (correctly rounded), Γ by forward substitution — no BLAS or LAPACK, whose
kernels (fused multiply-adds or not, blocking) differ between CPUs and library versions.  With
``np.linalg.inv`` and ``@``, on an "AMD EPYC" host (2026-12-06), RODAS5's α_7 (the benchmark's
tableau, benchmarks/bench_rosenbrock_order.py) came 1.2e-13 from c_7, past :data:`TOLERANCE`,
where the hosts before had left it within; so summed, 1.6e-14 at most (every tableau's
largest residual: DOPRI5 9.4e-16, RODAS4 8.9e-16, RODAS5P 2.0e-14, RODAS5 1.6e-14).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .tableaux import ExplicitTableau, RosenbrockTableau

__all__ = ["OrderConditionError", "TOLERANCE", "THETAS", "check_explicit", "check_rosenbrock",
           "trees"]

#: largest residual accepted (relative to max(1, |right-hand side|)): the coefficients are
#: rationals or 16-digit decimals rounded to double precision; the tableaux here leave at most
#: 2.0e-15 (RODAS4; DOPRI5 2.5e-16), so a coefficient wrong in its 13th digit or earlier fails
TOLERANCE = 1e-13
#: the points θ of the step at which a continuous extension is checked (more than its degree,
#: so a polynomial identity holding at all of them holds for every θ)
THETAS = (0.1, 0.25, 0.4, 0.5, 0.6, 0.75, 0.9, 1.0)

Tree = tuple["Tree", ...]  # a rooted tree: the sorted tuple of its root's subtrees


class OrderConditionError(ValueError):
    """A tableau's coefficients miss one of its order conditions."""


def _canonical(tree: Tree) -> Tree:
    return tuple(sorted(_canonical(child) for child in tree))


def _grow(tree: Tree) -> set[Tree]:
    """Every tree made by adding one leaf to a node of ``tree``."""
    out = {_canonical((*tree, ()))}
    for k, child in enumerate(tree):
        for grown in _grow(child):
            out.add(_canonical((*tree[:k], grown, *tree[k + 1:])))
    return out


@functools.cache
def trees(order: int) -> tuple[Tree, ...]:
    """The rooted trees with ``order`` nodes (1, 1, 2, 4, 9, 20 … of them).

    Parameters
    ----------
    order : int
        The number of nodes ρ(t), ≥ 1.

    Returns
    -------
    tuple of Tree
        Each tree as the sorted tuple of its root's subtrees (the leaf is ``()``).
    """
    if order == 1:
        return ((),)
    return tuple(sorted({g for t in trees(order - 1) for g in _grow(t)}))


@functools.cache
def _size(tree: Tree) -> int:
    return 1 + sum(_size(child) for child in tree)


@functools.cache
def _density(tree: Tree) -> int:
    """γ(t) = ρ(t) · Π γ(subtrees) (an exact integer)."""
    return _size(tree) * math.prod(_density(child) for child in tree)


def _dot(u: np.ndarray, v: np.ndarray) -> float:
    """Σ u_i v_i, each product rounded once and the sum correctly rounded (``math.fsum``)."""
    return math.fsum(float(x) * float(y) for x, y in zip(u, v, strict=True))


def _mv(m: np.ndarray, v: np.ndarray) -> np.ndarray:
    """M v by :func:`_dot` (the same on every machine, unlike BLAS)."""
    return np.array([_dot(row, v) for row in m])


def _vm(v: np.ndarray, m: np.ndarray) -> np.ndarray:
    """vᵀ M by :func:`_dot`."""
    return _mv(m.T, v)


def _inverse_lower(low: np.ndarray) -> np.ndarray:
    """The inverse of a lower-triangular matrix by forward substitution, column by column."""
    n = low.shape[0]
    inv = np.zeros((n, n))
    for j in range(n):
        inv[j, j] = 1.0 / low[j, j]
        for i in range(j + 1, n):
            inv[i, j] = -_dot(low[i, j:i], inv[j:i, j]) / low[i, i]
    return inv


def _sum(v: np.ndarray) -> float:
    return math.fsum(float(x) for x in v)


def _weights(tree: Tree, a: np.ndarray, memo: dict[Tree, np.ndarray]) -> np.ndarray:
    """Φ(t) over the stages: Π over the subtrees of A Φ(subtree) (ones for the leaf); each
    tree's once per ``memo`` (one per matrix ``a``: the same arithmetic, so the same value)."""
    phi = memo.get(tree)
    if phi is None:
        phi = np.ones(a.shape[0])
        for child in tree:
            phi = phi * _mv(a, _weights(child, a, memo))
        memo[tree] = phi
    return phi


def _fail(name: str, what: str, got: float, want: float) -> None:
    if not abs(got - want) <= TOLERANCE * max(1.0, abs(want)):
        raise OrderConditionError(f"{name}: {what} = {got!r}, expected {want!r} "
                                  "(a coefficient or the stated order is wrong: "
                                  "feeddrive.solvers.order_conditions)")


def _lower(rows: tuple[tuple[float, ...], ...], size: int) -> np.ndarray:
    m = np.zeros((size, size))
    for i, row in enumerate(rows):
        m[i, :len(row)] = row
    return m


def _check_trees(name: str, what: str, weights: np.ndarray,
                 phi: Callable[[Tree], np.ndarray], order: int, theta: float = 1.0) -> None:
    """Σ b_i Φ_i(t) = θ^ρ(t) / γ(t) for every tree up to ``order``, Φ(t) by ``phi`` (the
    method's own stage weights: explicit or Rosenbrock)."""
    for rho in range(1, order + 1):
        for k, tree in enumerate(trees(rho)):
            _fail(name, f"{what}: Σ b_i Φ_i(t) for tree {k + 1} of order {rho}"
                  + ("" if theta == 1.0 else f" at θ = {theta}"),
                  _dot(weights, phi(tree)), theta ** rho / _density(tree))


def check_explicit(tab: ExplicitTableau) -> None:
    """Check an explicit embedded pair's order conditions (the module's description).

    Parameters
    ----------
    tab : ExplicitTableau
        The tableau.

    Raises
    ------
    OrderConditionError
        At the first condition missed, naming it.
    """
    s = len(tab.c)
    n = s + (1 if tab.fsal else 0)
    a = _lower(tab.a, n)
    b = np.zeros(n)
    b[:s] = tab.b
    if tab.fsal:
        a[s, :s] = tab.b  # the stage at the new point (c = 1)
    c = (*tab.c, 1.0) if tab.fsal else tab.c
    for i in range(n):
        _fail(tab.name, f"row sum of a in stage {i + 1} (c_{i + 1})", _sum(a[i]), c[i])
    memo: dict[Tree, np.ndarray] = {}

    def phi(tree: Tree) -> np.ndarray:
        return _weights(tree, a, memo)

    _check_trees(tab.name, "solution", b, phi, tab.order)
    e = np.zeros(n)
    e[:len(tab.e)] = tab.e
    _check_trees(tab.name, "embedded solution", b - e, phi, tab.embedded_order)
    if tab.dense:
        # y(θ) = y0 + θ(q1 + (1−θ)(q2 + θ(q3 + (1−θ) h Σ d_i k_i))) with q1 = h Σ b_i k_i,
        # q2 = h k_1 − q1, q3 = q1 − h k_new − q2 (dopri5.f CONTD5; the driver's dense output)
        first, new, d = np.eye(n)[0], np.eye(n)[s], np.zeros(n)
        d[:len(tab.dense)] = tab.dense
        for th in THETAS:
            w = th * (b + (1 - th) * ((first - b) + th * ((2 * b - first - new)
                                                          + (1 - th) * d)))
            _check_trees(tab.name, "continuous extension", w, phi, tab.order - 1, th)


def _rosenbrock_weights(tree: Tree, alpha: np.ndarray, beta: np.ndarray,
                        memo: dict[Tree, np.ndarray]) -> np.ndarray:
    """Φ(t) of a Rosenbrock method over the stages: a vertex with one son is linked to it by
    β (the diagonal γ included), a vertex with several sons to each by α (ones for the leaf);
    each tree's once per ``memo`` (one per method)."""
    phi = memo.get(tree)
    if phi is None:
        if len(tree) == 1:
            phi = _mv(beta, _rosenbrock_weights(tree[0], alpha, beta, memo))
        else:
            phi = np.ones(alpha.shape[0])
            for child in tree:
                phi = phi * _mv(alpha, _rosenbrock_weights(child, alpha, beta, memo))
        memo[tree] = phi
    return phi


def check_rosenbrock(tab: RosenbrockTableau) -> None:
    """Check a Rosenbrock method's order conditions (the module's description).

    Parameters
    ----------
    tab : RosenbrockTableau
        The tableau (stiffly accurate: y_1 = the last stage argument + u_S, the embedded
        solution the last stage argument).

    Raises
    ------
    OrderConditionError
        At the first condition missed, naming it.
    """
    s, g = len(tab.c), tab.gamma
    gam = _inverse_lower(np.eye(s) / g - _lower(tab.cc, s))
    low = _lower(tab.a, s)
    alpha = np.array([_vm(row, gam) for row in low])
    beta = alpha + gam  # β_ij = α_ij + γ_ij, the diagonal γ_ii = γ included
    for i in range(s):
        _fail(tab.name, f"α_{i + 1} (c_{i + 1})", _sum(alpha[i]), tab.c[i])
        _fail(tab.name, f"Σ_j γ_{i + 1}j (d_{i + 1})", _sum(gam[i]), tab.d[i])
    m = np.zeros(s)
    m[:s - 1] = tab.a[-1]
    m_hat = m.copy()
    m[s - 1] = 1.0

    memo: dict[Tree, np.ndarray] = {}

    def phi(tree: Tree) -> np.ndarray:
        return _rosenbrock_weights(tree, alpha, beta, memo)

    _check_trees(tab.name, "solution", _vm(m, gam), phi, tab.order)
    _check_trees(tab.name, "embedded solution", _vm(m_hat, gam), phi, tab.embedded_order)
    if tab.dense:
        # y(θ) = (1−θ) y0 + θ (y1 + (1−θ)(q1 + θ (q2 + θ q3))), q_r = Σ_j dense[r][j] u_j
        # (q3 = 0 for a method with two rows)
        q = [np.zeros(s) for _ in range(3)]
        for r, row in enumerate(tab.dense):
            q[r][:len(row)] = row
        for th in THETAS:
            w = th * (m + (1 - th) * (q[0] + th * (q[1] + th * q[2])))
            _check_trees(tab.name, "dense output", _vm(w, gam), phi, tab.dense_order, th)
