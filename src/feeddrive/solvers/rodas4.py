"""RODAS4: a stiffly accurate Rosenbrock method of order 4 with an order-3 embedded solution and
a continuous (dense) output of order 3.

Source of the coefficients: E. Hairer and G. Wanner, *Solving Ordinary Differential Equations II.
Stiff and Differential-Algebraic Problems*, 2nd ed., Springer (1996), Sect. IV.7 (Table 7.2 and
the text around it), as distributed in their Fortran code ``rodas.f`` (subroutine ``ROCOE``,
``METH = 1``; the dense-output coefficients ``D21 … D35`` of the same subroutine).

One step from (t, y) with step h, J = ∂f/∂y and f_t = ∂f/∂t at (t, y), solves for
u_1 … u_6 (Hairer & Wanner's form IV.7 (7.25), the increments are ``u_i``)::

    (I/(γh) − J) u_i = f(t + c_i h, y + Σ_{j<i} a_ij u_j) + Σ_{j<i} (c_ij/h) u_j + γ_i h f_t

with c_5 = c_6 = 1, γ_5 = γ_6 = 0, a_6j = a_5j for j < 5, a_65 = 1.  The method is stiffly
accurate: y_1 = y + Σ_{j<6} a_6j u_j + u_6, and the embedded solution is the stage-6 argument,
so u_6 is the error estimate.  Dense output on θ = (t* − t)/h ∈ [0, 1]::

    y(θ) = (1 − θ)·y_0 + θ·(y_1 + (1 − θ)·(q_1 + θ·q_2)),  q_1 = Σ d_2j u_j,  q_2 = Σ d_3j u_j.

The Jacobian is taken by forward differences of the model's compiled right-hand side, grouped
(Curtis, Powell & Reid, J. Inst. Maths Applics 13 (1974) 117–119): the structural pattern of
∂f/∂(y, t) comes from the parts' declarations (:mod:`feeddrive.model.sparsity`), columns no row
shares are coloured alike, and each colour costs one call — 8 instead of 16 for the wang2021
DDFS (:func:`fd_jacobian_template`; a full pattern with one column per colour is the plain
Jacobian, used by the tests as the reference).  The linear systems are solved by a small LU
factorisation with partial pivoting written for the 10–20 states of a feed drive
(:func:`lu_factor`, :func:`lu_solve`): numba's ``numpy.linalg`` has no separate factor and
solve, so each stage would refactor — about 4× slower per step at 15 states (measured in
``benchmarks/README.md``).

The coefficients are the tableau :data:`feeddrive.solvers.tableaux.RODAS4`; the step itself is
the one Rosenbrock step of :mod:`feeddrive.solvers.steps` written for that tableau.  This file
holds the model-free kernels (LU, Jacobian, frozen states, spectral radius), compiled beside
the step in the shared drivers' module (see :mod:`feeddrive.solvers.shared`).
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel
from .placeholders import renamed_templates, rhs
from .tableaux import RODAS4

ORDER = 4  # of the main solution; the embedded solution is of order 3
EMBEDDED_ORDER = 3

# Hairer & Wanner, rodas.f, ROCOE, METH = 1 (RODAS4): the numbers are the tableau
# feeddrive.solvers.tableaux.RODAS4; these names are kept for the tests and the docs
R4_GAMMA = RODAS4.gamma
R4_C2, R4_C3, R4_C4 = RODAS4.c[1:4]
R4_D1, R4_D2, R4_D3, R4_D4 = RODAS4.d[:4]
(R4_A21,), (R4_A31, R4_A32), (R4_A41, R4_A42, R4_A43) = RODAS4.a[1:4]
R4_A51, R4_A52, R4_A53, R4_A54 = RODAS4.a[4]
(R4_C21,), (R4_C31, R4_C32), (R4_C41, R4_C42, R4_C43) = RODAS4.cc[1:4]
R4_C51, R4_C52, R4_C53, R4_C54 = RODAS4.cc[4]
R4_C61, R4_C62, R4_C63, R4_C64, R4_C65 = RODAS4.cc[5]
R4_H21, R4_H22, R4_H23, R4_H24, R4_H25 = RODAS4.dense[0]
R4_H31, R4_H32, R4_H33, R4_H34, R4_H35 = RODAS4.dense[1]

TABLEAU = tuple(name for name in dir() if name.startswith("R4_"))

@kernel
def lu_factor(M: np.ndarray, piv: np.ndarray) -> bool:
    """In-place LU factorisation with partial pivoting (rows swapped whole, as LAPACK getrf).
    Returns False if a pivot is exactly zero.

    Parameters
    ----------
    M : numpy.ndarray
        The square matrix, overwritten by its LU factors [SI].
    piv : numpy.ndarray of int
        Output: the row permutation.

    Returns
    -------
    bool
        True, or False for an exactly zero pivot (singular matrix).
    """
    n = M.shape[0]
    for k in range(n):
        p = k
        amax = abs(M[k, k])
        for i in range(k + 1, n):
            if abs(M[i, k]) > amax:
                amax = abs(M[i, k])
                p = i
        piv[k] = p
        if amax == 0.0:
            return False
        if p != k:
            for j in range(n):
                tmp = M[k, j]
                M[k, j] = M[p, j]
                M[p, j] = tmp
        inv = 1.0 / M[k, k]
        for i in range(k + 1, n):
            m = M[i, k] * inv
            M[i, k] = m
            if m != 0.0:
                for j in range(k + 1, n):
                    M[i, j] -= m * M[k, j]
    return True


@kernel
def lu_solve(M: np.ndarray, piv: np.ndarray, b: np.ndarray) -> None:
    """Solve (LU) x = b in place after :func:`lu_factor`.

    Each x_i takes its terms in the order of the reference BLAS ``dtrsv`` (Netlib; what
    LAPACK's ``getrs`` asks of it): the forward substitution with j rising, the back
    substitution with j falling, so that the term of x_{i+1}, the one just found, comes last
    and each row's sum is under way before it (until 2026-12-06 the back substitution took j
    rising, the newest term first: every row's sum waited for it, and the division closing
    the row before; 6–7 % of a DDFS run, benchmarks/README.md).

    The factors' exact zeros are skipped (a drive's LU keeps a third to two thirds of its
    off-diagonal entries zero), so the serial sums of the back substitution grow shorter
    (benchmarks/README.md, "LU solves").  Subtracting the product of a zero and a finite
    number leaves a sum as it was, bit for bit, but for the sign of an exact zero (−0 − (−0)
    is +0); a NaN or infinite entry of b no longer reaches the rows whose factor entry is 0
    (it stays in its own row, where the step's error test sees it).

    Parameters
    ----------
    M : numpy.ndarray
        LU factors from :func:`lu_factor` [SI].
    piv : numpy.ndarray of int
        Their row permutation.
    b : numpy.ndarray
        Right-hand side, overwritten by the solution [SI].
    """
    n = M.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
    for j in range(n):  # by columns: each b[i] takes its terms in the row order, j rising
        bj = b[j]
        for i in range(j + 1, n):
            if M[i, j] != 0.0:
                b[i] -= M[i, j] * bj
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(n - 1, i, -1):
            if M[i, j] != 0.0:
                s -= M[i, j] * b[j]
        b[i] = s / M[i, i]


def fd_jacobian_template(t: float, y: np.ndarray, f0: np.ndarray, held: np.ndarray,
                         P: np.ndarray, T: np.ndarray, atol: np.ndarray, J: np.ndarray,
                         ft: np.ndarray, yp: np.ndarray,
                         fp: np.ndarray, aux: np.ndarray, live: np.ndarray, S: np.ndarray,
                         colour: np.ndarray) -> int:
    """J = ∂f/∂y and ft = ∂f/∂t by grouped forward differences; f0 = f(t, y).

    ``S[i, j]`` (n × (n + 1), column n for t) says whether f_i may depend on y_j; ``colour[j]``
    is the group of column j: the columns of one group are perturbed together, one
    right-hand-side call per group, and each difference goes to the entries S marks in its
    column — exact when no row depends on two columns of a group (structurally orthogonal,
    :func:`feeddrive.model.sparsity.colour_columns`).  A full pattern with one group per
    column is the plain one-column-per-call Jacobian.  Columns of states not ``live`` (see
    :func:`frozen_states`) are 0 and not differenced; a group left without a live column costs
    no call.  Returns the number of right-hand-side evaluations, negated if a state taken as
    frozen has a derivative or a sensitivity (then nothing is to be trusted).

    Parameters
    ----------
    t : float
        Time [s].
    y : numpy.ndarray
        State [SI, per state].
    f0 : numpy.ndarray
        f(t, y), evaluated by the caller [SI per second, per state].
    held : numpy.ndarray
        Held controller values [SI, per value].
    P : numpy.ndarray
        Packed parameter vector [SI, per slot].
    T : numpy.ndarray
        Packed tables [SI].
    atol : numpy.ndarray
        Absolute tolerance per state, scales the differences [SI, per state].
    J : numpy.ndarray
        Output: ∂f/∂y [1/s, per pair].
    ft : numpy.ndarray
        Output: ∂f/∂t [SI per second², per state].
    yp, fp, aux : numpy.ndarray
        Work space [SI].
    live : numpy.ndarray of bool
        States that are not frozen.
    S : numpy.ndarray of int
        Sparsity pattern, (n, n + 1).
    colour : numpy.ndarray of int
        Column groups.

    Returns
    -------
    int
        Right-hand-side evaluations; negative when a frozen state moved.

    References
    ----------
    .. [1] A. R. Curtis, M. J. D. Powell, J. K. Reid, "On the estimation of sparse Jacobian
       matrices", J. Inst. Math. Appl. 13 (1974) 117–119.
    """
    n = y.size
    n_groups = 0
    for j in range(n + 1):
        n_groups = max(n_groups, colour[j] + 1)
        if j < n:
            yp[j] = y[j]
            for i in range(n):
                J[i, j] = 0.0
    for i in range(n):
        ft[i] = 0.0
    calls = 0
    frozen_ok = True
    for i in range(n):
        if not live[i] and f0[i] != 0.0:
            frozen_ok = False
    dt = 1.4901161193847656e-08 * max(abs(t), 1e-3)
    for g in range(n_groups):
        used = colour[n] == g
        for j in range(n):
            if colour[j] == g and live[j]:
                yp[j] = y[j] + 1.4901161193847656e-08 * max(abs(y[j]), 1e3 * atol[j])
                used = True
        if not used:
            continue
        rhs(t + dt if colour[n] == g else t, yp, held, P, T, fp, aux)
        calls += 1
        for j in range(n):
            if colour[j] == g and live[j]:
                d = yp[j] - y[j]  # the increment actually represented
                for i in range(n):
                    if S[i, j]:
                        J[i, j] = (fp[i] - f0[i]) / d
                yp[j] = y[j]
        if colour[n] == g:
            for i in range(n):
                if S[i, n]:
                    ft[i] = (fp[i] - f0[i]) / dt
        # a state taken as frozen must still have a zero derivative and a zero row
        for i in range(n):
            if not live[i] and fp[i] != f0[i]:
                frozen_ok = False
    return calls if frozen_ok else -calls


def frozen_states_template(J: np.ndarray, f0: np.ndarray, live: np.ndarray) -> int:
    """Mark states whose derivative is 0 and whose Jacobian row is 0 as not live; returns the
    number of live states.

    If a state's derivative vanishes identically (the nut states of a CDFS with the nut
    locked, a loop integral whose gain is 0), every Rosenbrock stage gives it a zero increment
    whatever its Jacobian column holds, so that column need not be differenced.  Whether the
    derivative is still 0 is checked at every stage (the Rosenbrock step of
    :mod:`feeddrive.solvers.steps` reports a
    violation and the caller goes back to the full Jacobian).

    Parameters
    ----------
    J : numpy.ndarray
        Jacobian ∂f/∂y [1/s, per pair].
    f0 : numpy.ndarray
        f(t, y) [SI per second, per state].
    live : numpy.ndarray of bool
        Output: which states are live.

    Returns
    -------
    int
        Number of live states.
    """
    n = f0.size
    count = 0
    for i in range(n):
        zero = f0[i] == 0.0
        if zero:
            for j in range(n):
                if J[i, j] != 0.0:
                    zero = False
                    break
        live[i] = not zero
        if live[i]:
            count += 1
    return count


def spectral_radius_template(J: np.ndarray, scale: np.ndarray, v: np.ndarray,
                             w: np.ndarray, iterations: int) -> float:
    """Estimate of the largest |eigenvalue| of J [1/s] by power iteration in the norm weighted
    by ``scale`` (the absolute tolerances): the geometric mean of the growth factors over the
    second half of the iterations, which also converges for a dominant complex pair.

    Parameters
    ----------
    J : numpy.ndarray
        Jacobian ∂f/∂y [1/s, per pair].
    scale : numpy.ndarray
        Weights of the norm, the absolute tolerances [SI, per state].
    v, w : numpy.ndarray
        Work space [-].
    iterations : int
        Power iterations.

    Returns
    -------
    float
        The estimate [1/s].
    """
    n = J.shape[0]
    for i in range(n):
        v[i] = scale[i] * (1.0 + 0.1 * ((i * 7) % 5))
    log_sum = 0.0
    counted = 0
    for k in range(iterations):
        nv = 0.0
        for i in range(n):
            s = 0.0
            for j in range(n):
                s += J[i, j] * v[j]
            w[i] = s
            nv += (s / scale[i]) ** 2
        nv = math.sqrt(nv)
        n_old = 0.0
        for i in range(n):
            n_old += (v[i] / scale[i]) ** 2
        n_old = math.sqrt(n_old)
        if nv == 0.0 or n_old == 0.0 or not math.isfinite(nv):
            return 0.0 if nv == 0.0 else math.inf
        if k >= iterations // 2:
            log_sum += math.log(nv / n_old)
            counted += 1
        for i in range(n):
            v[i] = w[i] / nv
    return math.exp(log_sum / counted) if counted else 0.0


_TEMPLATES = (fd_jacobian_template, frozen_states_template, spectral_radius_template)


def template_sources() -> list[str]:
    """Text placed in the shared drivers' module (:mod:`feeddrive.solvers.shared`): the LU
    kernels and the Jacobian, frozen-state and spectral-radius templates, renamed
    ``_r4_<name>`` (the ``rhs`` they call is the model's, passed in).

    Returns
    -------
    list of str
        Python sources.
    """
    return (["from feeddrive.solvers.rodas4 import lu_factor, lu_solve"]
            + renamed_templates(_TEMPLATES, "_r4_"))
