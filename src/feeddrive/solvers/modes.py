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
(:func:`real_eigenvalues`; states with a zero derivative and a zero Jacobian row contribute a
zero eigenvalue and are left out), and for every complex eigenvalue whose damping ratio ζ = −Re
λ/|λ| is below :data:`ZETA_LIGHT` — lightly damped, undamped or growing — the step is capped at
h|λ| ≤ :data:`H_LAMBDA` (RODAS4's ζ_num ≤ 4.4e-7 there, RODAS5P's ≤ 7.8e-9, DOPRI5's ≤ 1.3e-6: a
mode growing with ζ = −1e-5 still grows, and a mode decaying with ζ = 3e-4 decays within 0.5 %
of its rate). The cap was 0.7 (ζ_num 1.25e-5 and 2.2e-5) until the verdict corpus
(benchmarks/bench_verdicts.py) found a trial it decided wrongly: the ball–nut share 0.2 DDFS at
0.48 mm/s, whose 5.4-Hz oscillation decays with ζ ≈ 3.2e-4 and enters the ±2 % band just before
the 240-s limit: at 0.7 the extra numerical damping (4–7 % of its rate) called it "smooth" at
239.3 s; Radau at rtol 1e-10, ``dopri5`` and the cap 0.35 say "undecided". The explicit DOPRI5
steps are capped alike: on the imaginary axis DOPRI5's |R(iy)| exceeds 1 for 1 < y < 3.3, so at
its stability limit it amplifies a lightly damped mode into a false instability. Stiff
*decaying* components (real eigenvalues, heavily damped pairs) do not cap the step: there the
L-stable step is what makes the method fast. The idea of telling the two apart from the spectrum
is Shampine's (L. F. Shampine, "Stiffness and nonstiff differential equation solvers, II:
detecting stiffness with Runge–Kutta methods", ACM TOMS 3 (1977) 44–53) and Hairer–Wanner's
``dopri5.f`` stiffness test, which estimates h|λ| of the dominant mode only; the
eigen-decomposition gives every mode with its damping.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel

ZETA_LIGHT = 0.02  # modes with a damping ratio below this are resolved
H_LAMBDA = 0.35  # the cap: h·|λ| of each such mode (RODAS4's ζ_num(0.35) = 4.4e-7)
# the eigenvalues are recomputed when a row of the Jacobian moved by more than this fraction
# of its largest entry since the last analysis (jacobian_moved)
REFRESH = 0.05


@kernel
def real_eigenvalues(A: np.ndarray, wr: np.ndarray, wi: np.ndarray) -> bool:
    """The eigenvalues of a real n × n matrix, in real arithmetic.

    Balancing (Parlett & Reinsch), reduction to Hessenberg form by stabilised elementary
    similarity transformations and the Francis double-shift QR iteration — EISPACK's
    ``balanc``, ``elmhes`` and ``hqr`` [1]_, in the 1-based form of [2]_.  Complex pairs come
    as conjugates (wi[k] < 0 first).

    Parameters
    ----------
    A : numpy.ndarray
        (n + 1) × (n + 1) array whose A[1:, 1:] holds the matrix (row and column 0 unused);
        overwritten [1/s].
    wr : numpy.ndarray
        Length n + 1: receives the real parts in wr[1:] [1/s].
    wi : numpy.ndarray
        Length n + 1: receives the imaginary parts in wi[1:] [rad/s].

    Returns
    -------
    bool
        False if an eigenvalue took more than 30 iterations (then wr, wi are incomplete).

    References
    ----------
    .. [1] J. H. Wilkinson, C. Reinsch, *Handbook for Automatic Computation II: Linear
       Algebra*, Springer 1971, contributions II/11, II/13, II/14.
    .. [2] W. H. Press et al., *Numerical Recipes*, 2nd ed., Sect. 11.5–11.6.
    """
    n = A.shape[0] - 1
    # balance (Parlett & Reinsch; NR balanc)
    radix = 2.0
    sqrdx = radix * radix
    done = False
    while not done:
        done = True
        for i in range(1, n + 1):
            r = 0.0
            c = 0.0
            for j in range(1, n + 1):
                if j != i:
                    c += abs(A[j, i])
                    r += abs(A[i, j])
            if c != 0.0 and r != 0.0:
                g = r / radix
                f = 1.0
                s = c + r
                while c < g:
                    f *= radix
                    c *= sqrdx
                g = r * radix
                while c > g:
                    f /= radix
                    c /= sqrdx
                if (c + r) / f < 0.95 * s:
                    done = False
                    g = 1.0 / f
                    for j in range(1, n + 1):
                        A[i, j] *= g
                    for j in range(1, n + 1):
                        A[j, i] *= f
    # Hessenberg form by stabilised elementary similarity transformations (NR elmhes)
    for m in range(2, n):
        x = 0.0
        i = m
        for j in range(m, n + 1):
            if abs(A[j, m - 1]) > abs(x):
                x = A[j, m - 1]
                i = j
        if i != m:
            for j in range(m - 1, n + 1):
                tmp = A[i, j]
                A[i, j] = A[m, j]
                A[m, j] = tmp
            for j in range(1, n + 1):
                tmp = A[j, i]
                A[j, i] = A[j, m]
                A[j, m] = tmp
        if x != 0.0:
            for i in range(m + 1, n + 1):
                y = A[i, m - 1]
                if y != 0.0:
                    y /= x
                    A[i, m - 1] = y
                    for j in range(m, n + 1):
                        A[i, j] -= y * A[m, j]
                    for j in range(1, n + 1):
                        A[j, m] += y * A[j, i]
    for i in range(3, n + 1):
        for j in range(1, i - 1):
            A[i, j] = 0.0
    # Francis double-shift QR (NR hqr)
    anorm = 0.0
    for i in range(1, n + 1):
        for j in range(max(i - 1, 1), n + 1):
            anorm += abs(A[i, j])
    nn = n
    t = 0.0
    p = q = r = s = w = x = y = z = 0.0
    while nn >= 1:
        its = 0
        while True:
            l = nn
            while l >= 2:
                s = abs(A[l - 1, l - 1]) + abs(A[l, l])
                if s == 0.0:
                    s = anorm
                if abs(A[l, l - 1]) + s == s:
                    A[l, l - 1] = 0.0
                    break
                l -= 1
            if l < 1:
                l = 1
            x = A[nn, nn]
            if l == nn:
                wr[nn] = x + t
                wi[nn] = 0.0
                nn -= 1
                break
            y = A[nn - 1, nn - 1]
            w = A[nn, nn - 1] * A[nn - 1, nn]
            if l == nn - 1:
                p = 0.5 * (y - x)
                q = p * p + w
                z = math.sqrt(abs(q))
                x += t
                if q >= 0.0:
                    z = p + (z if p >= 0.0 else -z)
                    wr[nn - 1] = x + z
                    wr[nn] = x + z
                    if z != 0.0:
                        wr[nn] = x - w / z
                    wi[nn - 1] = 0.0
                    wi[nn] = 0.0
                else:
                    wr[nn - 1] = x + p
                    wr[nn] = x + p
                    wi[nn - 1] = -z
                    wi[nn] = z
                nn -= 2
                break
            if its == 30:
                return False
            if its == 10 or its == 20:
                t += x
                for i in range(1, nn + 1):
                    A[i, i] -= x
                s = abs(A[nn, nn - 1]) + abs(A[nn - 1, nn - 2])
                x = 0.75 * s
                y = x
                w = -0.4375 * s * s
            its += 1
            m = nn - 2
            while m >= l:
                z = A[m, m]
                r = x - z
                s = y - z
                p = (r * s - w) / A[m + 1, m] + A[m, m + 1]
                q = A[m + 1, m + 1] - z - r - s
                r = A[m + 2, m + 1]
                s = abs(p) + abs(q) + abs(r)
                p /= s
                q /= s
                r /= s
                if m == l:
                    break
                u = abs(A[m, m - 1]) * (abs(q) + abs(r))
                v = abs(p) * (abs(A[m - 1, m - 1]) + abs(z) + abs(A[m + 1, m + 1]))
                if u + v == v:
                    break
                m -= 1
            for i in range(m + 2, nn + 1):
                A[i, i - 2] = 0.0
                if i != m + 2:
                    A[i, i - 3] = 0.0
            for k in range(m, nn):
                if k != m:
                    p = A[k, k - 1]
                    q = A[k + 1, k - 1]
                    r = 0.0
                    if k != nn - 1:
                        r = A[k + 2, k - 1]
                    x = abs(p) + abs(q) + abs(r)
                    if x != 0.0:
                        p /= x
                        q /= x
                        r /= x
                s = math.sqrt(p * p + q * q + r * r)
                if p < 0.0:
                    s = -s
                if s != 0.0:
                    if k == m:
                        if l != m:
                            A[k, k - 1] = -A[k, k - 1]
                    else:
                        A[k, k - 1] = -s * x
                    p += s
                    x = p / s
                    y = q / s
                    z = r / s
                    q /= p
                    r /= p
                    for j in range(k, nn + 1):
                        p = A[k, j] + q * A[k + 1, j]
                        if k != nn - 1:
                            p += r * A[k + 2, j]
                            A[k + 2, j] -= p * z
                        A[k + 1, j] -= p * y
                        A[k, j] -= p * x
                    mmin = nn if nn < k + 3 else k + 3
                    for i in range(l, mmin + 1):
                        p = x * A[i, k] + y * A[i, k + 1]
                        if k != nn - 1:
                            p += z * A[i, k + 2]
                            A[i, k + 2] -= p * r
                        A[i, k + 1] -= p * q
                        A[i, k] -= p
    return True


@kernel
def step_cap_real(J: np.ndarray, live: np.ndarray, zeta_light: float, h_lambda: float
                  ) -> float:
    """:func:`step_cap` in real arithmetic alone: NaN where the QR iteration of
    :func:`real_eigenvalues` does not converge (no LAPACK; the C build of the driver calls
    this, docs/c-backend.md).

    Parameters
    ----------
    J : numpy.ndarray
        n × n Jacobian of the right-hand side [1/s].
    live : numpy.ndarray
        n flags: the states that take part [-].
    zeta_light : float
        Damping ratio below which a mode counts as lightly damped [-].
    h_lambda : float
        Largest h·|λ| allowed on such a mode [-].

    Returns
    -------
    float
        The step cap [s]; inf if there is no such mode (or J is not finite); NaN if the
        eigenvalues did not converge.
    """
    n = J.shape[0]
    m = 0
    for i in range(n):
        if live[i]:
            m += 1
    if m == 0:
        return math.inf
    A = np.zeros((m + 1, m + 1))
    if not _live_block(J, live, A):
        return math.inf
    wr = np.zeros(m + 1)
    wi = np.zeros(m + 1)
    if not real_eigenvalues(A, wr, wi):
        return math.nan
    return _light_cap(wr, wi, m, zeta_light, h_lambda)


@kernel
def _live_block(J: np.ndarray, live: np.ndarray, A: np.ndarray) -> bool:
    """A[1:, 1:] = J's rows and columns of the live states; False if one is not finite."""
    n = J.shape[0]
    r = 1
    for i in range(n):
        if not live[i]:
            continue
        c = 1
        for j in range(n):
            if not live[j]:
                continue
            if not math.isfinite(J[i, j]):
                return False
            A[r, c] = J[i, j]
            c += 1
        r += 1
    return True


@kernel
def _light_cap(wr: np.ndarray, wi: np.ndarray, m: int, zeta_light: float, h_lambda: float
               ) -> float:
    """The smallest h_lambda/|λ| over the lightly damped eigenvalues wr[1:] + i·wi[1:]."""
    cap = math.inf
    for k in range(1, m + 1):
        a = math.hypot(wr[k], wi[k])
        if a == 0.0 or abs(wi[k]) <= 1e-9 * a:
            continue
        if -wr[k] / a < zeta_light:
            cap = min(cap, h_lambda / a)
    return cap


@kernel
def step_cap(J: np.ndarray, live: np.ndarray, zeta_light: float, h_lambda: float) -> float:
    """The largest step that resolves every lightly damped mode of J (see the module).

    The minimum over eigenvalues λ with Im λ ≠ 0 and −Re λ/|λ| < ``zeta_light`` of
    ``h_lambda``/|λ|.  The eigenvalues in real arithmetic (:func:`real_eigenvalues`, ≈ 5×
    faster than LAPACK's complex ``zgeev`` on these sizes, :func:`step_cap_real`); should that
    not converge, by ``zgeev``.

    Parameters
    ----------
    J : numpy.ndarray
        n × n Jacobian of the right-hand side [1/s].
    live : numpy.ndarray
        n flags: the states that take part (held or frozen states are left out) [-].
    zeta_light : float
        Damping ratio below which a mode counts as lightly damped [-].
    h_lambda : float
        Largest h·|λ| allowed on such a mode [-].

    Returns
    -------
    float
        The step cap [s]; inf if there is no such mode (or J is not finite).
    """
    cap = step_cap_real(J, live, zeta_light, h_lambda)
    if not math.isnan(cap):
        return cap
    m = 0
    for i in range(J.shape[0]):
        if live[i]:
            m += 1
    A = np.zeros((m + 1, m + 1))
    _live_block(J, live, A)
    Z = np.empty((m, m), dtype=np.complex128)
    for i in range(m):
        for j in range(m):
            Z[i, j] = A[i + 1, j + 1]
    ev = np.linalg.eigvals(Z)
    wr = np.zeros(m + 1)
    wi = np.zeros(m + 1)
    for k in range(m):
        wr[k + 1] = ev[k].real
        wi[k + 1] = ev[k].imag
    return _light_cap(wr, wi, m, zeta_light, h_lambda)


@kernel
def jacobian_moved(J: np.ndarray, J_ref: np.ndarray, refresh: float) -> bool:
    """Whether the Jacobian has moved enough since the last eigen-analysis to redo it.

    Max-norm, row by row: the rows of a drive's Jacobian differ in scale by orders of
    magnitude, and an eigenvalue moves by about the size of the change.

    Parameters
    ----------
    J : numpy.ndarray
        The current n × n Jacobian [1/s].
    J_ref : numpy.ndarray
        The Jacobian of the last eigen-analysis [1/s].
    refresh : float
        Relative change of a row (to the row's largest entry) that counts as moved [-].

    Returns
    -------
    bool
        True if some row of J differs from that of ``J_ref`` by more than ``refresh`` of the
        row's largest entry.
    """
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
