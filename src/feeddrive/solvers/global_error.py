"""The embedded global-error estimate: carried along inside the one integration.

The global error E(t) = y_num(t) − y(t) of a one-step method obeys, to first order, the
linearised error equation: each accepted step adds its local error δ_n, and what was there
before is carried by the variational equation E' = J E (Hairer, Nørsett & Wanner [1]_, Sect.
II.3, "Lady Windermere's fan", and Sect. II.12 on estimating the global error by integrating
it along; Shampine [2]_; Dormand, Duckers & Prince [3]_ integrate the same equation with a third
formula of the Runge–Kutta family).  Here:

* δ_n is the step's own embedded error estimate — DOPRI5's h·Σ e_j k_j, RODAS4's u_6: the
  local error of the *lower-order* solution of each pair.  The run propagates the higher-order
  one (local extrapolation), whose local error is smaller, so the sum estimates the global
  error of the embedded solution, not of the run: an overestimate by a factor that grows as
  the steps resolve the solution better (1.6–1.9 on the frictionless steps at the defaults,
  5 at ``accuracy`` 0.01; RODAS4's 3rd-order embedded solution 3–60).
* Each step carries E exactly to the last instant g of a grid of H = h_J/:data:`SUBDIVISION`
  (h_J the step the Jacobian was looked at) before its end, E ← exp(mHJ) E (the
  :data:`POWERS` propagators exp(2^k H J) that m's binary digits select, formed by
  :func:`exponential`, scaling and squaring of a Taylor polynomial [4]_), then adds δ_n.  So a
  local error is carried at most H out of phase.  On a fixed 5-ms grid with the local errors of
  an interval summed (before), the CDFS table mode (1276 rad/s) turned 6.4 rad per interval,
  the sum cancelled, and the estimate was 0.16× the true error.
* J is the step's own on a RODAS4 step, the ``modal`` method's newest after each of its
  eigen-analyses, else taken by the grouped differences of the Rosenbrock steps; it is looked
  at every 8–:data:`CHECK_STEPS` accepted steps (halved when it had moved, doubled when not)
  and whenever the step size doubled or halved, and the propagators are formed again when it
  moved by :data:`MOVED` (:func:`feeddrive.solvers.modes.jacobian_moved`).  A Jacobian taken
  at rest and kept for 500 steps through the start (before) made the smooth LuGre DDFS's
  estimate 188× the true error.  Whatever J, exp(HJ) is stable where the linearisation is (the
  method's own propagator R(hJ) with a stale Jacobian is not).

Measured against exact and independent references (tests/validation/test_accuracy_embedded.py,
docs/model.md): 0.72–60× the true error (:data:`MEASURED_RATIO`).  It costs at least one
n × n product with a vector per step: ×1.3 (DDFS) to ×2.6 (CDFS) the CPU of the creep searches
(benchmarks/bench_error_estimate.py): over the issue's 10 %.

What the driver keeps, in its memory between calls
(:func:`feeddrive.solvers.switching.new_memory`): E and the largest |E| so far per state, the
grid instant g and the interval H.

Limits: the held values of sampled loops are not states, so a sampled controller's feedback
on the error is not propagated (with continuous loops it is: their integrators are states);
the auxiliary signals get no estimate (they are functions of the states the estimate covers).

References
----------
.. [1] E. Hairer, S. P. Nørsett, G. Wanner, Solving Ordinary Differential Equations I, 2nd
   ed., Springer, 1993, Sect. II.3 and II.12.
.. [2] L. F. Shampine, "Global error estimation with one-step methods", Comput. Math. Appl.
   12A (1986) 885–894.
.. [3] J. R. Dormand, R. R. Duckers, P. J. Prince, "Global error estimation with Runge–Kutta
   methods", IMA J. Numer. Anal. 4 (1984) 169–184.
.. [4] N. J. Higham, "The scaling and squaring method for the matrix exponential revisited",
   SIAM J. Matrix Anal. Appl. 26 (2005) 1179–1193.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel

#: the longest propagation interval H [s]
INTERVAL = 5e-3
#: the propagation interval H is the step the Jacobian was taken at over this: a local error
#: is added at the last grid instant before its step's end, so it is carried at most H out of
#: phase: ≤ 3.3/SUBDIVISION rad for the modes an explicit step resolves (DOPRI5's stability
#: limit h|λ| ≤ 3.3) and ≤ 0.35/SUBDIVISION for the lightly damped modes a ``modal``
#: Rosenbrock step is capped on (``feeddrive.solvers.modes.H_LAMBDA``); on a fixed 5-ms grid the
#: CDFS table mode (1276 rad/s) turned 6.4 rad, the summed local errors cancelled and the
#: estimate was 0.16× the true error
SUBDIVISION = 4
#: the propagators cover steps up to SPAN times the step they were formed at (a longer step
#: forms them again)
SPAN = 16.0
#: the most propagators exp(2^k H J) kept (k < POWERS)
POWERS = 12
#: accepted steps between two looks at the Jacobian (the step's own on a Rosenbrock step, the
#: ``modal`` method's newest, else one taken by the grouped differences of the Rosenbrock steps:
#: a call of the right-hand side per column group, 8 for a 15-state drive, ≈ 3 % of 50 DOPRI5
#: steps); also looked at whenever the ``modal`` method analyses a new one
CHECK_STEPS = 64
CHECK_MIN = 8
#: the propagators are formed again when a row of the Jacobian looked at differs from the one
#: they were formed from by more than this fraction of the row's largest entry (the ``modal``
#: method's own test, ``feeddrive.solvers.modes.jacobian_moved``, looser than its 5 %: an
#: estimate within a factor 3 needs the propagator to tens of per cent, the step cap's
#: eigenvalues to a few); a Jacobian taken at rest and kept through the start (every 500 steps
#: until then) made the smooth LuGre DDFS's estimate 188× the true error
MOVED = 0.25
#: what the estimate is worth: the measured range of its ratio to the true table-speed error
#: over the cases of tests/validation/test_accuracy_embedded.py (which checks each lies in it:
#: frictionless CDFS/DDFS 1-mm/s steps against the matrix exponential, smooth LuGre CDFS 2 mm/s
#: and DDFS 0.5/16 mm/s against scipy's Radau; methods modal, dopri5-dense, rodas4, auto at
#: accuracy 1, 0.1, 0.01; measured 2026-12-05: 0.72–60.5, rodas4 at accuracy 0.01 the top),
#: written beside the number wherever it is shown
#: (``feeddrive.analysis.critical.format_integration_error``)
MEASURED_RATIO = (0.7, 61.0)
#: the Taylor degree of the exponential after scaling ‖A/2^s‖₁ ≤ 1/2 (remainder ≤ 2e-7
#: relative: an estimate needs no more)
TAYLOR_DEGREE = 6


@kernel
def keep_local(e: np.ndarray, d: np.ndarray) -> None:
    """Keep the accepted step's local error estimate ``e`` in ``d`` (the dense output reuses
    ``e``; the step may still be thrown away at a switching surface it crossed).

    Parameters
    ----------
    e : numpy.ndarray
        The step's error estimate [SI, per state].
    d : numpy.ndarray
        Receives it [SI, per state].
    """
    for i in range(e.size):
        d[i] = e[i]


@kernel
def copy(J: np.ndarray, M: np.ndarray) -> None:
    """M ← J (n × n).

    Parameters
    ----------
    J : numpy.ndarray
        The matrix copied [any].
    M : numpy.ndarray
        Receives it [any].
    """
    n = J.shape[0]
    for i in range(n):
        for j in range(n):
            M[i, j] = J[i, j]


@kernel
def _product(Phi_a: np.ndarray, Phi: np.ndarray, Phi_b: np.ndarray) -> None:
    """Phi_b ← Phi_a Phi (n × n), row by row (the inner loop along a row of each).

    Parameters
    ----------
    Phi_a, Phi : numpy.ndarray
        The factors [-].
    Phi_b : numpy.ndarray
        Receives the product [-].
    """
    n = Phi.shape[0]
    for i in range(n):
        for j in range(n):
            Phi_b[i, j] = 0.0
        for m in range(n):
            a = Phi_a[i, m]
            for j in range(n):
                Phi_b[i, j] += a * Phi[m, j]


@kernel
def exponential(J: np.ndarray, H: float, Phi: np.ndarray, Phi_a: np.ndarray,
                Phi_b: np.ndarray, scale: np.ndarray) -> None:
    """Phi = exp(H J) = D exp(H D⁻¹ J D) D⁻¹ with D = diag(``scale``) (the states' units
    differ by orders of magnitude: the scaled matrix's norm is near its spectral radius): A =
    H D⁻¹ J D / 2^s with ‖A‖₁ ≤ 1/2, the Taylor polynomial of degree :data:`TAYLOR_DEGREE`
    (Horner), squared s times (Higham 2005, the module's reference 4).

    Parameters
    ----------
    J : numpy.ndarray
        The Jacobian (n × n) [1/s].
    H : float
        The interval [s].
    Phi : numpy.ndarray
        Receives exp(H J) (n × n) [-].
    Phi_a, Phi_b : numpy.ndarray
        Work space (n × n) [-].
    scale : numpy.ndarray
        The states' scales D, e.g. their absolute tolerances [SI, per state].
    """
    n = J.shape[0]
    norm = 0.0
    for j in range(n):
        col = 0.0
        for i in range(n):
            col += abs(J[i, j]) * scale[j] / scale[i]
        norm = max(norm, col)
    norm *= H
    s = 0
    factor = H
    if math.isfinite(norm):
        while norm > 0.5:
            norm *= 0.5
            factor *= 0.5
            s += 1
    for i in range(n):
        for j in range(n):
            Phi_a[i, j] = factor * J[i, j] * scale[j] / scale[i]
            Phi[i, j] = 0.0
        Phi[i, i] = 1.0
    for k in range(TAYLOR_DEGREE, 0, -1):  # Phi ← I + A Phi / k
        _product(Phi_a, Phi, Phi_b)
        for i in range(n):
            for j in range(n):
                Phi[i, j] = Phi_b[i, j] / k
            Phi[i, i] += 1.0
    for _ in range(s):
        _product(Phi, Phi, Phi_b)
        for i in range(n):
            for j in range(n):
                Phi[i, j] = Phi_b[i, j]
    for i in range(n):
        for j in range(n):
            Phi[i, j] *= scale[i] / scale[j]


@kernel
def propagators(J: np.ndarray, h: float, Phi_k: np.ndarray, Phi: np.ndarray,
                Phi_a: np.ndarray, Phi_b: np.ndarray, scale: np.ndarray, memory: np.ndarray,
                at: int) -> int:
    """For the Jacobian ``J`` taken at a step ``h``: the interval H = min(:data:`INTERVAL`,
    h/:data:`SUBDIVISION`), kept in the memory at ``at + 2n + 1``, and the propagators
    exp(2^k H J), k < K, transposed (so that :func:`advance` runs along rows), in the rows
    k·n … (k + 1)·n − 1 of ``Phi_k`` (:func:`exponential` with D = diag(``scale``), then
    squared), K the fewest (≤ :data:`POWERS`) with 2^(K−1) H ≥ :data:`SPAN` h.

    Parameters
    ----------
    J : numpy.ndarray
        The Jacobian (n × n) [1/s].
    h : float
        The step it was taken at [s].
    Phi_k : numpy.ndarray
        Receives the propagators (POWERS·n × n) [-].
    Phi, Phi_a, Phi_b : numpy.ndarray
        Work space (n × n) [-].
    scale : numpy.ndarray
        The states' scales D, e.g. their absolute tolerances [SI, per state].
    memory : numpy.ndarray
        The driver's memory (:func:`advance`) [SI, per state].
    at : int
        Where E starts in ``memory``.

    Returns
    -------
    int
        K, the propagators formed.
    """
    n = J.shape[0]
    H = min(INTERVAL, h / SUBDIVISION)
    memory[at + 2 * n + 1] = H
    exponential(J, H, Phi, Phi_a, Phi_b, scale)
    for i in range(n):
        for j in range(n):
            Phi_k[i, j] = Phi[j, i]
    K = 1
    span = H
    while K < POWERS and span < SPAN * h:
        K += 1
        span *= 2.0
    for k in range(1, K):  # (Φ²)ᵀ = (Φᵀ)²
        for i in range(n):
            for j in range(n):
                Phi_k[k * n + i, j] = 0.0
            for m in range(n):
                a = Phi_k[(k - 1) * n + i, m]
                for j in range(n):
                    Phi_k[k * n + i, j] += a * Phi_k[(k - 1) * n + m, j]
    return K


@kernel
def advance(t_new: float, Phi_k: np.ndarray, K: int, memory: np.ndarray, at: int,
            w: np.ndarray, d: np.ndarray) -> None:
    """After an accepted step ending at ``t_new`` with local error ``d``: E, the error at the
    grid instant g, is carried to the last grid instant g + mH ≤ ``t_new`` by exp(mHJ) (the
    propagators of :func:`propagators` that m's binary digits select), then E ← E + d, and
    the largest |E| updated.  The memory holds E at ``at``, the largest |E| at ``at + n``, g
    at ``at + 2n`` and H at ``at + 2n + 1`` [SI, per state; s].

    Parameters
    ----------
    t_new : float
        The step's end [s].
    Phi_k : numpy.ndarray
        The propagators (:func:`propagators`) [-].
    K : int
        How many (:func:`propagators`).
    memory : numpy.ndarray
        The driver's memory [SI, per state].
    at : int
        Where E starts in ``memory``.
    w : numpy.ndarray
        Work space, length n [SI, per state].
    d : numpy.ndarray
        The step's local error (:func:`keep_local`) [SI, per state].
    """
    n = w.size
    H = memory[at + 2 * n + 1]
    passed = int(math.floor((t_new - memory[at + 2 * n]) / H))
    if passed > 0:
        memory[at + 2 * n] += passed * H
        k = 0
        while passed > 0:
            top = k >= K - 1
            if top or passed % 2 == 1:
                row = (K - 1 if top else k) * n
                for j in range(n):  # E ← Φ E, Φᵀ stored: along its rows
                    w[j] = memory[at + j]
                    memory[at + j] = 0.0
                for j in range(n):
                    e = w[j]
                    for i in range(n):
                        memory[at + i] += Phi_k[row + j, i] * e
                passed -= 1 if top else 0
            if not top:
                passed = passed // 2
                k += 1
    for i in range(n):
        memory[at + i] += d[i]
        memory[at + n + i] = max(memory[at + n + i], abs(memory[at + i]))
