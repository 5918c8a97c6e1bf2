"""Parts of a drive model given as parameter sections of their own (``[acceleration_feedforward]``
…): each module registers its section class (registry group ``feeddrive.sections``); a class
with ``declare_part(b, axes) -> axes`` and ``emit_part(b)`` is assembled into the model, and
its ``schedule()`` — (field, period [s]) pairs — joins the breakpoint grid of the sampled
loops.  See docs/extending.md."""

from typing import Any


def axis_index(label: str, axis: str, axes: list[Any]) -> int:
    """The index of the controller axis a part acts on: ``axis``, or the drive's first.

    Parameters
    ----------
    label : str
        The part's section name (``reversal_feedforward``, …).
    axis : str
        The axis it names; "" = the drive's first.
    axes : list of Axis
        The mechanism's controller axes.

    Returns
    -------
    int
        The axis' index in ``axes``.

    Raises
    ------
    ParameterError
        ``<label>.axis`` naming no axis of the drive.
    """
    from ...parameters import ParameterError

    names = [ax.name for ax in axes]
    target = axis or names[0]
    if target not in names:
        raise ParameterError(f"{label}.axis", axis, f"expected one of {', '.join(names)}")
    return names.index(target)


def added_feedforward(ax: Any, current: str) -> str:
    """The axis' current feed-forward with ``current`` added (another part's: both add).

    Parameters
    ----------
    ax : Axis
        The controller axis.
    current : str
        The code of the part's current [A].

    Returns
    -------
    str
        The code of the axis' whole feed-forward current.
    """
    before = ax.current_feedforward
    return f"({before} + {current})" if before else current
