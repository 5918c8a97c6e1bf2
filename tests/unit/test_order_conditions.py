"""Tableaux check their own order conditions when built (issue 42 item 3): the shipped ones
pass, and every single coefficient of DOPRI5 (with its embedded pair and continuous extension)
and of RODAS4 and RODAS5P (with their dense outputs), moved by 1e-9, is refused by name.
The Rosenbrock conditions come from the trees; written out for order ≤ 4 they are checked here
against Hairer & Wanner II, Table 7.1's rows, computed in the test from the standard form."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from feeddrive.solvers import tableaux
from feeddrive.solvers.order_conditions import (
    OrderConditionError,
    check_explicit,
    check_rosenbrock,
    trees,
)
from feeddrive.solvers.tableaux import BS3, DOPRI5, RODAS3, RODAS4, RODAS5P

EPS = 1e-9


def test_rooted_trees_are_counted_as_in_oeis_a000081() -> None:
    # the number of rooted trees with n nodes: 1, 1, 2, 4, 9, 20, 48 (OEIS A000081)
    assert [len(trees(n)) for n in range(1, 8)] == [1, 1, 2, 4, 9, 20, 48]


def test_every_shipped_tableau_meets_its_conditions() -> None:
    for tab in tableaux.EXPLICIT.values():
        check_explicit(tab)
    for rtab in tableaux.ROSENBROCK.values():
        check_rosenbrock(rtab)
    assert {t.name for t in (DOPRI5, BS3, RODAS4, RODAS3, RODAS5P)} == {
        *tableaux.EXPLICIT, *tableaux.ROSENBROCK}


def _moved(value: Any, path: tuple[int, ...]) -> Any:
    """``value`` (a float or nested tuples of floats) with the entry at ``path`` moved by EPS."""
    if not path:
        return value + EPS
    k, rest = path[0], path[1:]
    return (*value[:k], _moved(value[k], rest), *value[k + 1:])


def _entries(value: Any, path: tuple[int, ...] = ()) -> list[tuple[int, ...]]:
    if isinstance(value, tuple):
        return [p for k, v in enumerate(value) for p in _entries(v, (*path, k))]
    return [path]


def _perturbations(tab: Any, fields: tuple[str, ...]) -> list[tuple[str, tuple[int, ...]]]:
    return [(f, p) for f in fields for p in _entries(getattr(tab, f))]


@pytest.mark.parametrize("field", ["c", "a", "b", "e", "dense"])
def test_each_coefficient_of_dopri5_moved_is_refused(field: str) -> None:
    cases = _perturbations(DOPRI5, (field,))
    assert cases
    for name, path in cases:
        with pytest.raises(OrderConditionError, match=r"^dp5: .*stated order is wrong"):
            dataclasses.replace(DOPRI5, **{name: _moved(getattr(DOPRI5, name), path)})


def test_a_weight_moved_keeping_the_sum_fails_a_higher_order_condition() -> None:
    b = list(DOPRI5.b)
    b[2] += EPS
    b[3] -= EPS  # Σ b_i = 1 still holds; Σ b_i c_i = 1/2 does not
    with pytest.raises(OrderConditionError, match=r"solution: Σ b_i Φ_i\(t\) for tree 1 of "
                                                  r"order 2"):
        dataclasses.replace(DOPRI5, b=tuple(b))


@pytest.mark.parametrize("tab", [RODAS4, RODAS5P], ids=["rodas4", "rodas5p"])
@pytest.mark.parametrize("field", ["gamma", "c", "a", "cc", "d", "dense"])
def test_each_coefficient_of_a_rosenbrock_method_moved_is_refused(tab: Any, field: str) -> None:
    cases = _perturbations(tab, (field,))
    assert cases
    s = len(tab.c)
    for name, path in cases:
        value = _moved(getattr(tab, name), path)
        if name == "dense" and path[1] == s - 1:
            # RODAS5P's rows reach the last increment u_S, the error estimate: O(h^(q+2)) =
            # O(h^5), beyond the dense output's order 4, so no condition sees its weight and a
            # wrong one lowers no order: accepted, and stated here
            assert tab is RODAS5P
            dataclasses.replace(tab, **{name: value})
            continue
        if name == "a" and path[0] >= s - 3:
            if path[1] >= len(tab.a[s - 3]):
                continue  # the stiffly accurate 1.0s, checked by the step's shape rule
            # the last rows of a stiffly accurate method move together (RODAS4: two, RODAS5P:
            # three share a_6)
            for row in range(s - 3, s):
                if row != path[0] and tab.a[row][:len(tab.a[s - 3])] == tab.a[path[0]][
                        :len(tab.a[s - 3])] and path[1] < len(tab.a[row]):
                    value = _moved(value, (row, path[1]))
        with pytest.raises(OrderConditionError, match=rf"^{tab.name}: .*stated order is wrong"):
            dataclasses.replace(tab, **{name: value})


def _table_7_1(tab: Any) -> list[tuple[float, float]]:
    """Hairer & Wanner II, Table 7.1's eight conditions (order ≤ 4) as (left, right), written
    out in the test from the standard form (7.26), independently of the trees."""
    s, g = len(tab.c), tab.gamma
    cc = np.zeros((s, s))
    a = np.zeros((s, s))
    for i in range(s):
        cc[i, :i] = tab.cc[i]
        a[i, :i] = tab.a[i]
    gam = np.linalg.inv(np.eye(s) / g - cc)
    alpha = a @ gam
    beta = alpha + gam - np.diag(np.diag(gam))
    m = np.zeros(s)
    m[:s - 1] = tab.a[-1]
    m[s - 1] = 1.0
    b = m @ gam
    al, bp = alpha.sum(axis=1), beta.sum(axis=1)
    return [(b.sum(), 1.0), (b @ bp, 0.5 - g), (b @ al ** 2, 1 / 3),
            (b @ beta @ bp, 1 / 6 - g + g ** 2), (b @ al ** 3, 1 / 4),
            ((b * al) @ alpha @ bp, 1 / 8 - g / 3), (b @ beta @ al ** 2, 1 / 12 - g / 3),
            (b @ beta @ beta @ bp, 1 / 24 - g / 2 + 1.5 * g ** 2 - g ** 3)]


@pytest.mark.parametrize("tab", [RODAS4, RODAS5P], ids=["rodas4", "rodas5p"])
def test_the_trees_give_table_7_1_for_order_4(tab: Any) -> None:
    # the tree rule passes both; Table 7.1 written out holds for both too (to 1e-13)
    for left, right in _table_7_1(tab):
        assert abs(left - right) < 1e-13
    # a moved γ breaks Table 7.1 and the tree rule alike
    with pytest.raises(OrderConditionError):
        dataclasses.replace(tab, gamma=tab.gamma + 1e-6)
    assert max(abs(lf - r) for lf, r in _table_7_1(
        type("T", (), {"c": tab.c, "a": tab.a, "cc": tab.cc, "gamma": tab.gamma + 1e-6})
    )) > 1e-9


def test_a_method_of_too_high_an_order_is_not_claimed() -> None:
    with pytest.raises(OrderConditionError, match=r"^rodas4: solution: .* of order 5 "):
        dataclasses.replace(RODAS4, order=5)
    with pytest.raises(OrderConditionError, match=r"^rodas5p: solution: .* of order 6 "):
        dataclasses.replace(RODAS5P, order=6)
    with pytest.raises(OrderConditionError, match=r"^rodas5p: embedded solution: .* order 5 "):
        dataclasses.replace(RODAS5P, embedded_order=5)
    with pytest.raises(OrderConditionError, match=r"^bs3: solution: .* of order 4 "):
        dataclasses.replace(BS3, order=5)  # a 3rd-order pair claimed as 5th: fails at 4


def test_the_sums_are_correctly_rounded_on_every_machine() -> None:
    # the check sums without BLAS or LAPACK (the module's description): a product rounded
    # once, the sum correctly rounded — the same bits wherever it runs, which a BLAS dot
    # (fused multiply-adds or not, by CPU) is not
    from fractions import Fraction

    from feeddrive.solvers.order_conditions import _dot, _inverse_lower

    rng = np.random.default_rng(7)
    for _ in range(50):
        u, v = rng.normal(size=8) * 10.0 ** rng.integers(-8, 8, 8), rng.normal(size=8)
        exact = sum(Fraction(float(Fraction(x) * Fraction(y))) for x, y in zip(u, v, strict=True))
        assert _dot(u, v) == float(exact)
    low = np.tril(rng.normal(size=(8, 8))) + 4.0 * np.eye(8)
    inv = _inverse_lower(low)
    assert np.all(np.triu(inv, 1) == 0.0)
    assert np.max(np.abs(low @ inv - np.eye(8))) < 1e-14
