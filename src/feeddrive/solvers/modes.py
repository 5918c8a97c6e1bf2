"""Which oscillatory modes a Rosenbrock step must resolve: the step cap of the ``modal``
method (:mod:`feeddrive.solvers.switching`, ``MODE_MODAL``).

An L-stable one-step method with stability function R damps a linear mode y' = λy with
|R(hλ)| < |e^{hλ}| (Hairer & Wanner, *Solving ODEs II*, 2nd ed., Springer 1996, Sect. IV.3:
A- and L-stability, the order star of R).  On the imaginary axis RODAS4's |R(iy)| falls from
1 − 6e-9 at y = 0.2 to 0.999937 at y = 1, 0.9954 at y = 2.5 and 0.715 at y = 10: a step of
h|λ| = 10 adds a numerical damping ratio ζ_num = −ln|R(iy)|/y ≈ 0.034 to every mode.  A table
mode that grows slowly (the ``wang2021-literal`` CDFS at 0.2 mm/s: λ = 3.0 ± 1268i 1/s,
ζ = −0.0024) is then damped instead, and while its amplitude is below the tolerances the error
estimate never sees it: the run settles "smooth" where the exact solution creeps.

The cure used here: from the Jacobian the Rosenbrock step already needs, the eigenvalues
(LAPACK ``zgeev`` through numba; states with a zero derivative and a zero Jacobian row
contribute a zero eigenvalue and are left out), and for every complex eigenvalue whose
damping ratio ζ = −Re λ/|λ| is below :data:`ZETA_LIGHT` — lightly damped, undamped or growing
— the step is capped at h|λ| ≤ :data:`H_LAMBDA` (ζ_num ≤ 1.3e-5 there: a mode growing
with ζ = −1e-4 still grows).  The explicit DOPRI5 steps are capped alike: on the imaginary axis
DOPRI5's |R(iy)| exceeds 1 for 1 < y < 3.3, so at its stability limit it amplifies a lightly
damped mode into a false instability (|ζ_num| ≤ 3.1e-5 below y = 1).  Stiff *decaying*
components (real eigenvalues, heavily damped pairs) do not cap the step: there the L-stable
step is what makes the method fast.  The idea of telling the two apart from the spectrum is
Shampine's (L. F. Shampine, "Stiffness and nonstiff differential equation solvers, II:
detecting stiffness with Runge–Kutta methods",
ACM TOMS 3 (1977) 44–53) and Hairer–Wanner's ``dopri5.f`` stiffness test, which estimates
h|λ| of the dominant mode only; the eigen-decomposition gives every mode with its damping.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel

ZETA_LIGHT = 0.02  # modes with a damping ratio below this are resolved
H_LAMBDA = 0.7  # the cap: h·|λ| of each such mode (RODAS4's ζ_num(0.7) = 1.25e-5)
# the eigenvalues are recomputed when a row of the Jacobian moved by more than this fraction
# of its largest entry since the last analysis (jacobian_moved)
REFRESH = 0.05


@kernel
def step_cap(J: np.ndarray, live: np.ndarray, zeta_light: float, h_lambda: float) -> float:
    """The largest step [s] that resolves every lightly damped mode of J (see the module):
    min over eigenvalues λ with Im λ ≠ 0 and −Re λ/|λ| < ``zeta_light`` of ``h_lambda``/|λ|;
    inf if there is none (or J is not finite)."""
    n = J.shape[0]
    m = 0
    for i in range(n):
        if live[i]:
            m += 1
    if m == 0:
        return math.inf
    A = np.empty((m, m), dtype=np.complex128)
    r = 0
    for i in range(n):
        if not live[i]:
            continue
        c = 0
        for j in range(n):
            if not live[j]:
                continue
            if not math.isfinite(J[i, j]):
                return math.inf
            A[r, c] = J[i, j]
            c += 1
        r += 1
    ev = np.linalg.eigvals(A)
    cap = math.inf
    for k in range(m):
        a = abs(ev[k])
        if a == 0.0 or abs(ev[k].imag) <= 1e-9 * a:
            continue
        if -ev[k].real / a < zeta_light:
            cap = min(cap, h_lambda / a)
    return cap


@kernel
def jacobian_moved(J: np.ndarray, J_ref: np.ndarray, refresh: float) -> bool:
    """Whether a row of J differs from that of ``J_ref`` by more than ``refresh`` of the row's
    largest entry (max-norm, row by row; the rows of a drive's Jacobian differ in scale by
    orders of magnitude, and an eigenvalue moves by about the size of the change)."""
    n = J.shape[0]
    for i in range(n):
        row = 0.0
        d = 0.0
        for j in range(n):
            row = max(row, abs(J_ref[i, j]))
            d = max(d, abs(J[i, j] - J_ref[i, j]))
        if d > refresh * row:
            return True
    return False
