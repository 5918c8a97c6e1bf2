"""`feeddrive creep`'s integration-error estimate: which one a search makes
(``--error-estimate``), its one ``integration_error`` entry in the JSON, and why a search
made none."""

from __future__ import annotations

from typing import Any

from ..engine.error_estimate import RATIOS, SHADOW_FACTOR, ratio_text

__all__ = ["ESTIMATES", "ESTIMATE_HELP", "NOT_ASKED", "NOT_ESTIMATED", "RIPPLE_REASON",
           "STEPDOWN_REASON", "estimate_asked", "integration_error", "no_estimate_reason",
           "not_estimated", "shadow_impossible_reason"]

#: how the JSON starts a line that says no integration error was estimated, and the text
NOT_ESTIMATED = "Integration error: not estimated — "
#: why a search made no integration-error estimate, when it is not the settings
STEPDOWN_REASON = ("the step-down search (one continuous run on a running table) makes no "
                   "estimate")
RIPPLE_REASON = "the ripple-threshold search makes no estimate"


def shadow_impossible_reason() -> str:
    """Why the search from rest can make no integration-error estimate at these settings
    (``feeddrive.analysis.critical.shadow_possible`` is False): the setting that a run
    ten times tighter would take below its floor, as the user gave it
    (:func:`feeddrive.engine.error_estimate.tightening_refused`).

    Returns
    -------
    str
        The reason.
    """
    from ..engine.error_estimate import tightening_refused
    from ..engine.options import MIN_RELATIVE, current

    why = tightening_refused(current())
    if why is None:  # (not reached: shadow_possible said no)
        return (f"a run {SHADOW_FACTOR:g}× tighter than these settings would ask for less "
                f"than {MIN_RELATIVE:g} relative (double precision's reach)")
    return f"{why.split(': give a looser')[0]} (double precision's reach)"


def not_estimated(reason: str | None = None) -> dict[str, Any]:
    """The ``integration_error`` entry of a search that made no estimate, and its line.

    Parameters
    ----------
    reason : str, optional
        Why; by default the settings' (:func:`shadow_impossible_reason`).

    Returns
    -------
    dict
        ``estimated`` (False), ``reason`` and ``text`` (the line ``creep`` prints).
    """
    why = shadow_impossible_reason() if reason is None else reason
    return {"estimated": False, "reason": why, "text": NOT_ESTIMATED + why}


def integration_error(searches: list[dict[str, Any]], reason: str) -> dict[str, Any]:
    """The one ``integration_error`` entry of ``creep --json``: the largest estimate over the
    searches (``speed_error_mm_s`` of :meth:`~feeddrive.analysis.critical.CriticalSpeed.to_dict`)
    with how it was made and the measured range of its ratio to the true error, or why there
    is none.

    Parameters
    ----------
    searches : list of dict
        The searches as ``CriticalSpeed.to_dict`` gives them.
    reason : str
        Why there is no estimate when no search carries one.

    Returns
    -------
    dict
        ``estimated``, ``method``, ``speed_error_mm_s`` [mm/s], ``ratio_to_true_error``
        [-], ``tighter_by`` [-] (the shadow's), ``text`` (as the search's line writes it);
        or :func:`not_estimated`.
    """
    from ..analysis.critical import format_integration_error

    made = [s for s in searches if s.get("speed_error_mm_s") is not None]
    if not made:
        return not_estimated(reason)
    worst = max(made, key=lambda s: s["speed_error_mm_s"])
    # an entry stored without its method is an embedded one (format_integration_error)
    method = worst.get("speed_error_method") or "embedded"
    return {"estimated": True, "method": method, "speed_error_mm_s": worst["speed_error_mm_s"],
            "ratio_to_true_error": list(RATIOS[method]),
            **({"tighter_by": SHADOW_FACTOR} if method == "shadow" else {}),
            "text": format_integration_error(worst).strip(" []")}


#: ``--error-estimate``'s help, its numbers the estimators' own
ESTIMATE_HELP = (
    "The search from rest's integration-error estimate: shadow (its deciding trials run again "
    f"with every tolerance {SHADOW_FACTOR:g}× tighter; {ratio_text(RATIOS['shadow'])}× the "
    "true error where measured), embedded (carried along every trial, no second run; "
    f"{ratio_text(RATIOS['embedded'])}× the true error where measured), or none.")
#: ``--error-estimate``'s choices → ``critical_speed_from_rest``'s ``error_estimate``
# (shadow as True: the call reproduce makes, tests/validation/test_report_new_user.py)
ESTIMATES: dict[str, str | bool] = {"shadow": True, "embedded": "embedded", "none": False}
#: why there is none when none was asked for
NOT_ASKED = "not asked for (--error-estimate none)"


def estimate_asked(choice: str, shadow_possible: bool) -> str | bool:
    """The search's ``error_estimate`` from ``--error-estimate`` (refused if not a choice):
    no shadow where the settings leave no run 10× tighter (the search then says why)."""
    from ..parameters import ParameterError

    if choice not in ESTIMATES:
        raise ParameterError("--error-estimate", choice,
                             f"expected one of {', '.join(ESTIMATES)}")
    if choice == "shadow" and not shadow_possible:
        return False
    return ESTIMATES[choice]


def no_estimate_reason(method: str, estimate: str | bool, choice: str = "shadow") -> str:
    """Why ``creep``'s searches carry no estimate when none does."""
    if method == "stepdown":
        return STEPDOWN_REASON
    if choice == "none":
        return NOT_ASKED
    if not estimate:
        return shadow_impossible_reason()
    return (f"the deciding trials could not be compared with their runs {SHADOW_FACTOR:g}× "
            "tighter (a run diverged)")
