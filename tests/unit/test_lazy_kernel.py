"""A kernel before numba is started (feeddrive._jit.LazyKernel, 2026-12-06): what a caller, the
docs' autodoc, a class attribute and pickle see of it is what they saw of the plain function
(and of numba's dispatcher)."""

from __future__ import annotations

import inspect
import pickle

from feeddrive._jit import LazyKernel


def twice(x: float) -> float:
    """Twice ``x``."""
    return 2.0 * x


twice = LazyKernel(twice, {})  # type: ignore[assignment]  # what the decorator does


def test_called_before_numba_starts_it_runs_its_python_function() -> None:
    assert isinstance(twice, LazyKernel)
    assert twice(1.5) == 3.0 and twice.py_func(1.5) == 3.0
    assert twice.dispatcher is None


def test_it_is_a_routine_with_the_function_s_name_signature_and_docstring() -> None:
    assert inspect.isroutine(twice)  # autodoc documents it as a function
    assert twice.__name__ == "twice" and twice.__doc__ == "Twice ``x``."
    assert str(inspect.signature(twice)) == "(x: 'float') -> 'float'"


def test_as_a_class_attribute_it_binds_as_a_function_does() -> None:
    class Holder:
        method = twice

    bound = Holder().method
    assert inspect.ismethod(bound) and bound.__func__ is twice
    assert Holder.method is twice


def test_it_pickles_by_name_as_a_function_does() -> None:
    assert pickle.loads(pickle.dumps(twice)) is twice


def test_introspection_does_not_start_numba() -> None:
    # an attribute a function lacks (inspect and copy ask for such) is missing, as on a
    # function, and asking for it starts nothing
    assert not hasattr(twice, "__signature__") and not hasattr(twice, "__deepcopy__")
    assert twice.__wrapped__ is twice.py_func and twice.__module__ == __name__
    assert twice.dispatcher is None
