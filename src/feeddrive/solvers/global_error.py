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
  error of the embedded solution, not of the run: an estimate, not a bound, 0.15–200 000×
  the run's true error (:data:`MEASURED_RATIO`; measured against exact and independent
  references in tests/validation/test_accuracy_embedded.py; stated in docs/model.md).
* The propagation runs on a fixed grid of :data:`INTERVAL`: the local errors of the steps
  within one interval are summed, and at each grid instant E ← Φ (E + Σδ) with Φ = exp(H J),
  the exact propagator of the linearised error equation over H for the Jacobian J
  (:func:`exponential`: scaling and squaring of a Taylor polynomial [4]_).  J is the step's own on
  a RODAS4 step, else taken by the grouped differences of the Rosenbrock steps; Φ is formed
  again every :data:`REFRESH_STEPS` accepted steps.  Whatever J, Φ is stable where the
  linearisation is: a Jacobian that has gone stale (a start-up ramp, a friction site's
  stiction) cannot make the estimate blow up, as the method's own propagator R(hJ) can when
  h·λ(J) leaves its stability region.  Summing within an interval shifts an oscillatory
  error's phase by up to H|λ| (not its amplitude) and leaves out the decay of a component
  that decays within H.

Why it misses the true error (measured 2026-12-05; benchmarks/embedded_estimate_causes.py,
tests/validation/test_accuracy_embedded.py, docs/model.md): (1) the grid — H|λ| is 6.4 rad for
the CDFS table mode, the local errors summed in an interval cancel, and the estimate is
0.16–0.20× the true error on the frictionless steps (carried step by step: 1.6–1.9×); (2) the
Jacobian taken at rest and kept through the start: 6.3–595× on the smooth LuGre runs (looked
at adaptively: 0.73–3.5×); (3) the lower-order solution's local error: 1.6–5× (RODAS4 up to
60×).  Curing (1) and (2) needs at least one n × n product with a vector per step, ×1.26–2.63
the creep searches' CPU (commit 2b26ba4, reverted): over the 10 % allowed, so not done.

What the driver keeps, in its memory between calls
(:func:`feeddrive.solvers.switching.new_memory`): E, the largest |E + Σδ| so far and Σδ, per
state.

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

#: the propagation grid [s]: the local errors within one interval are summed and carried on
#: by exp(H J) at its end (the CDFS table mode, 1276 rad/s, turns 6.4 rad in it: cause (1) of
#: the module's underestimate; at 1 ms it would turn 1.3 rad, at five times the matrix-vector
#: products)
INTERVAL = 5e-3
#: accepted steps between two propagators exp(H J) (a Jacobian costs a call of the
#: right-hand side per column group, 8 for a 15-state drive, the exponential ≈ 15 matrix
#: products: together ≈ 3 % of 100 DOPRI5 steps)
REFRESH_STEPS = 500
#: what the estimate is worth: the measured range of its ratio to the true table-speed error
#: over the cases of tests/validation/test_accuracy_embedded.py (which checks each lies in it:
#: frictionless CDFS/DDFS 1-mm/s steps against the matrix exponential, smooth LuGre CDFS 2 mm/s
#: and DDFS 0.5/16 mm/s and three stick-slip runs against scipy's Radau, and the trials that
#: decide the ``reproduce`` report's critical speeds and bands — CDFS 1.0, 1.42, 1.55 mm/s
#: for 12 s, 1.56 mm/s for 24 s, DDFS 0.02 mm/s at v_n = 16 mm/s, ``wang2021`` at mid-screw —
#: against Radau; methods modal,
#: dopri5-dense, rodas4, auto at accuracy 1, 0.1, 0.01; measured 2026-12-05/06: 0.155 on the
#: frictionless steps to 1.6e5 on the band-edge trial at 1.42 mm/s, the largest 6.5e4 with
#: ``modal``; 600 until the deciding trials were measured, and the one at 1.55 mm/s gave 702),
#: written beside the number wherever it is shown
#: (``feeddrive.analysis.critical.format_integration_error``)
MEASURED_RATIO = (0.15, 2.0e5)
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
def _product(Phi_a: np.ndarray, Phi: np.ndarray, Phi_b: np.ndarray) -> None:
    """Phi_b = Phi_a Phi (n × n), each entry summed over m rising as the plain triple loop
    sums it, the rows of Phi added to Phi_b's row i in turn and a zero Phi_a[i, m] skipped: a
    sum that starts at +0 and takes a zero's product (of finite numbers) stays what it was,
    so Phi_b is the plain loop's bit for bit, at the cost of Phi_a's nonzeros (a drive's scaled
    Jacobian keeps 14–22 % of its entries; the squarings' Φ fewer zeros).  (The parameters
    are named as the C backend knows their shapes.)"""
    n = Phi_a.shape[0]
    for i in range(n):
        for j in range(n):
            Phi_b[i, j] = 0.0
        for m in range(n):
            a = Phi_a[i, m]
            if a != 0.0:
                for j in range(n):
                    Phi_b[i, j] += a * Phi[m, j]


@kernel
def advance(t: float, t_new: float, Phi: np.ndarray, memory: np.ndarray, at: int,
            H: float, w: np.ndarray, d: np.ndarray) -> None:
    """After an accepted step [t, t_new] with local error ``d``: Σδ += d, then at each
    instant k·H of the propagation grid passed, E ← Φ (E + Σδ) and Σδ ← 0; the largest
    |E + Σδ| updated.  The memory holds E at ``at``, the largest |E + Σδ| at ``at + n``, Σδ
    at ``at + 2n`` [SI, per state].

    Parameters
    ----------
    t, t_new : float
        The step's start and end [s].
    Phi : numpy.ndarray
        exp(H J) (:func:`exponential`) [-].
    memory : numpy.ndarray
        The driver's memory [SI, per state].
    at : int
        Where E starts in ``memory``.
    H : float
        The interval [s].
    w : numpy.ndarray
        Work space, length n [SI, per state].
    d : numpy.ndarray
        The step's local error (:func:`keep_local`) [SI, per state].
    """
    n = w.size
    for i in range(n):
        memory[at + 2 * n + i] += d[i]
    passed = int(math.floor(t_new / H)) - int(math.floor(t / H))
    for _ in range(passed):
        for j in range(n):
            w[j] = memory[at + j] + memory[at + 2 * n + j]
            memory[at + 2 * n + j] = 0.0
        for i in range(n):
            v = 0.0
            for j in range(n):
                v += Phi[i, j] * w[j]
            memory[at + i] = v
    for i in range(n):
        memory[at + n + i] = max(memory[at + n + i],
                                 abs(memory[at + i] + memory[at + 2 * n + i]))
