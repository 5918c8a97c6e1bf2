"""Tableaux check their own order conditions when built (issue 42 item 3): the shipped ones
pass, and every single coefficient of DOPRI5 (with its embedded pair and continuous extension)
and of RODAS4 (with its dense output), moved by 1e-9, is refused by name."""

from __future__ import annotations

import dataclasses
from typing import Any

import pytest

from feeddrive.solvers import tableaux
from feeddrive.solvers.order_conditions import (
    OrderConditionError,
    check_explicit,
    check_rosenbrock,
    trees,
)
from feeddrive.solvers.tableaux import BS3, DOPRI5, RODAS3, RODAS4

EPS = 1e-9


def test_rooted_trees_are_counted_as_in_oeis_a000081() -> None:
    # the number of rooted trees with n nodes: 1, 1, 2, 4, 9, 20, 48 (OEIS A000081)
    assert [len(trees(n)) for n in range(1, 8)] == [1, 1, 2, 4, 9, 20, 48]


def test_every_shipped_tableau_meets_its_conditions() -> None:
    for tab in tableaux.EXPLICIT.values():
        check_explicit(tab)
    for rtab in tableaux.ROSENBROCK.values():
        check_rosenbrock(rtab)
    assert {t.name for t in (DOPRI5, BS3, RODAS4, RODAS3)} == {
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


@pytest.mark.parametrize("field", ["gamma", "c", "a", "cc", "d", "dense"])
def test_each_coefficient_of_rodas4_moved_is_refused(field: str) -> None:
    cases = _perturbations(RODAS4, (field,))
    assert cases
    s = len(RODAS4.c)
    for name, path in cases:
        value = _moved(getattr(RODAS4, name), path)
        if name == "a" and path[0] >= s - 2:
            if path[0] == s - 1 and path[1] == s - 2:
                continue  # the stiffly accurate 1.0, checked by the step's shape rule
            # the last two rows of a stiffly accurate method move together
            other = (s - 1 if path[0] == s - 2 else s - 2, path[1])
            value = _moved(value, other)
        with pytest.raises(OrderConditionError, match=r"^rodas4: .*stated order is wrong"):
            dataclasses.replace(RODAS4, **{name: value})


def test_a_method_of_too_high_an_order_is_not_claimed() -> None:
    with pytest.raises(OrderConditionError, match="order 5: the conditions of order above 4"):
        dataclasses.replace(RODAS4, order=5)
    with pytest.raises(OrderConditionError, match=r"^bs3: solution: .* of order 4 "):
        dataclasses.replace(BS3, order=5)  # a 3rd-order pair claimed as 5th: fails at 4
