"""The model names the solver templates call, defined once.

The solvers never import a model: their templates (the one driver of
:mod:`feeddrive.solvers.driver`, the steps of :mod:`feeddrive.solvers.steps`, the Jacobian
kernels of :mod:`feeddrive.solvers.rodas4`) are compiled once, in the shared drivers' module
(:mod:`feeddrive.solvers.shared`), where ``rhs``, ``sample_update``, ``N_AUX`` and ``N_HELD``
become the arguments each model passes (and into the FMU's module, where they are that
model's own).  These placeholders only make the template modules
importable and checkable on their own; calling one raises.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Sequence
from typing import Any

N_AUX = 0  # the model's number of auxiliary signals
N_HELD = 1  # the model's number of held (sampled) values


def rhs(*args: Any) -> None:  # pragma: no cover - replaced in the generated module
    """Placeholder for the assembled model's right-hand side
    ``rhs(t, y, held, P, T, dy, aux)``.

    The generated module replaces it; calling it raises.

    Parameters
    ----------
    *args : object
        The model function's arguments.

    Raises
    ------
    NotImplementedError
        Always.
    """
    raise NotImplementedError("placeholder: the assembled model's right-hand side")


def sample_update(*args: Any) -> None:  # pragma: no cover - replaced in the generated module
    """Placeholder for the assembled model's sampled-controller update
    ``sample_update(t, y, held, P, T, tick)``.

    The generated module replaces it; calling it raises.

    Parameters
    ----------
    *args : object
        The model function's arguments.

    Raises
    ------
    NotImplementedError
        Always.
    """
    raise NotImplementedError("placeholder: the assembled model's sampled-controller update")


def renamed_templates(templates: Sequence[Callable[..., Any]], prefix: str) -> list[str]:
    """The text of ``templates`` (functions named ``<name>_template``) as the shared drivers'
    module holds it: each renamed ``<prefix><name>``, its calls of the others renamed too, and
    marked ``@kernel``.

    Parameters
    ----------
    templates : sequence of callable
        The template functions.
    prefix : str
        The prefix of their names in the module (``"_r4_"``, ``"_ev_"``).

    Returns
    -------
    list of str
        Python sources, one per template.
    """
    out = []
    for fn in templates:
        name = fn.__name__.removesuffix("_template")
        src = inspect.getsource(fn).replace(f"def {fn.__name__}(", f"def {prefix}{name}(", 1)
        for other in templates:
            short = other.__name__.removesuffix("_template")
            src = src.replace(f"{other.__name__}(", f"{prefix}{short}(")
        out.append("@kernel\n" + src)
    return out
