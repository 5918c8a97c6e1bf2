"""Which derivative can depend on which state: the structural Jacobian pattern of an assembled
model, from what its parts declare, and a column colouring for a grouped finite-difference
Jacobian.

Every part's code says what it computes from what, its signals named in braces
(:meth:`feeddrive.model.codegen.Builder.emit` derives the flows from that text): ``dy:<state>``
and ``aux:<signal>`` and its own named values (``f_d``, ``f_screw``, ``ref_x``) written from
``y:<state>``, ``t`` and other written names. Parameters, held (sampled) values and tables are
constants of one Jacobian and are not declared. :func:`declared_pattern` follows these flows to
the states and t every derivative depends on; a name written in several places (the two
branches of a gated site) depends on the union. A declaration that names a state, signal or
value no part writes, or a state whose derivative nobody writes, is refused, so a part cannot
drop out of the pattern silently; the pattern is checked against dense finite-difference
Jacobians of every kind of model in ``tests/unit/test_jacobian_pattern.py`` (an under-estimate
there is a wrong Jacobian).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np


def declared_pattern(states: Sequence[str], aux: Sequence[str],
                     flows: Mapping[str, set[str]]) -> np.ndarray:
    """Boolean pattern (uint8, n × (n + 1)) of ∂dy[i]/∂y[j] (last column: ∂/∂t).

    Parameters
    ----------
    states : sequence of str
        The model's state names, in state-vector order.
    aux : sequence of str
        Its auxiliary signal names.
    flows : mapping
        Written quantity → the quantities it is computed from
        (:attr:`feeddrive.model.codegen.Builder.flows`).

    Returns
    -------
    numpy.ndarray
        ``S[i, j] = 1`` where derivative i may depend on state j (j = n: on t).
    """
    n = len(states)
    index = {name: i for i, name in enumerate(states)}
    signals = set(aux)
    for written, reads in flows.items():
        kind, _, name = written.partition(":")
        if kind == "dy" and name not in index or kind == "aux" and name not in signals:
            raise ValueError(f"flow: {written!r} is no state derivative or signal of the model")
        for r in reads:
            if r.startswith("y:") and r[2:] not in index:
                raise ValueError(f"flow of {written!r}: {r!r} is no state of the model")
            if r != "t" and not r.startswith("y:") and r not in flows:
                raise ValueError(f"flow of {written!r}: reads {r!r}, which no part writes")
    unwritten = [s for s in states if f"dy:{s}" not in flows]
    if unwritten:
        raise ValueError(f"flow: no part declares the derivative of {', '.join(unwritten)}")
    columns: dict[str, set[int]] = {}
    for written in flows:  # fixed point of the union over the declarations
        columns[written] = set()
    changed = True
    while changed:
        changed = False
        for written, reads in flows.items():
            cols = columns[written]
            before = len(cols)
            for r in reads:
                if r == "t":
                    cols.add(n)
                elif r.startswith("y:"):
                    cols.add(index[r[2:]])
                else:
                    cols |= columns[r]
            changed |= len(cols) != before
    S = np.zeros((n, n + 1), dtype=np.uint8)
    for i, name in enumerate(states):
        S[i, sorted(columns[f"dy:{name}"])] = 1
    return S


def colour_columns(S: np.ndarray) -> np.ndarray:
    """Greedy largest-first colouring of the columns of ``S``: two columns share a colour only
    if no row has both.  Returns the colour (group number, from 0) of every column.

    Parameters
    ----------
    S : numpy.ndarray of int
        The sparsity pattern, (n, n + 1): 1 where dy[i] may depend on y[j] (column n: t).

    Returns
    -------
    numpy.ndarray of int
        The group of every column.

    References
    ----------
    .. [1] A. R. Curtis, M. J. D. Powell, J. K. Reid, "On the estimation of sparse Jacobian
       matrices", J. Inst. Math. Appl. 13 (1974) 117–119.
    """
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
