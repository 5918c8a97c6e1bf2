"""Right-hand-side evaluations for the linearisations, as templates of the shared drivers
(:mod:`feeddrive.solvers.shared`): a model's rates at one state, and the central differences
of its state Jacobian column by column, each one compiled call through the model's
first-class ``rhs``.

:mod:`feeddrive.analysis.linear` evaluated the model's own ``rhs`` kernel from Python: that
compiled every linearised model's right-hand side a second time beside its first-class
function (≈ 1–2 CPU s a structure on a cold cache, five structures in ``reproduce``), and a
state matrix cost ≈ 20 calls from Python.  The arithmetic here is that of the Python code it
replaces, operation for operation (``y[k] ± h``, ``(f₊ − f₋)/(2h)``), so the numbers are the
same to the bit.
"""

from __future__ import annotations

import numpy as np

from .placeholders import renamed_templates, rhs


def rates_template(t: float, y: np.ndarray, held: np.ndarray, P: np.ndarray, T: np.ndarray,
                   dy: np.ndarray, aux: np.ndarray) -> None:
    """dy = f(t, y) and the auxiliary signals, by the model's ``rhs``.

    Parameters
    ----------
    t : float
        Time [s].
    y : numpy.ndarray
        State [SI, per state].
    held : numpy.ndarray
        Held controller values [SI, per value].
    P : numpy.ndarray
        Packed parameter vector [SI, per slot].
    T : numpy.ndarray
        Packed tables [SI].
    dy : numpy.ndarray
        Output: the rates [SI per second, per state].
    aux : numpy.ndarray
        Output: the auxiliary signals [SI, per signal].
    """
    rhs(t, y, held, P, T, dy, aux)  # the model's, passed in (shared.model_arguments)


def central_columns_template(t: float, y: np.ndarray, held: np.ndarray, P: np.ndarray,
                             T: np.ndarray, columns: np.ndarray, steps: np.ndarray,
                             rows: np.ndarray, A: np.ndarray, yp: np.ndarray, dp: np.ndarray,
                             dm: np.ndarray, aux: np.ndarray) -> None:
    """A[r, j] = (f_rows[r](y + h_j e_k) − f_rows[r](y − h_j e_k)) / (2 h_j), k = columns[j].

    Parameters
    ----------
    t : float
        Time [s].
    y : numpy.ndarray
        State [SI, per state].
    held, P, T : numpy.ndarray
        Held values, packed parameters and tables [SI].
    columns : numpy.ndarray of int
        The states differenced, one column of ``A`` each.
    steps : numpy.ndarray
        Their steps h [SI, per column].
    rows : numpy.ndarray of int
        The rates kept, one row of ``A`` each.
    A : numpy.ndarray
        Output, (rows, columns) [1/s, per pair].
    yp, dp, dm, aux : numpy.ndarray
        Work space [SI].
    """
    for i in range(y.size):
        yp[i] = y[i]
    for j in range(columns.size):
        k = columns[j]
        h = steps[j]
        yp[k] = y[k] + h
        rhs(t, yp, held, P, T, dp, aux)
        yp[k] = y[k] - h
        rhs(t, yp, held, P, T, dm, aux)
        yp[k] = y[k]
        for r in range(rows.size):
            A[r, j] = (dp[rows[r]] - dm[rows[r]]) / (2 * h)


_TEMPLATES = (rates_template, central_columns_template)


def template_sources() -> list[str]:
    """The templates as they read in the shared drivers' module, renamed ``_ev_<name>``.

    Returns
    -------
    list of str
        Python sources.
    """
    return renamed_templates(_TEMPLATES, "_ev_")
