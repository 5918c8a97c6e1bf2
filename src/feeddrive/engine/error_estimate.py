"""The global integration error of a run, estimated and stated beside its result.

Every method here keeps its global error proportional to its tolerances: measured on the
frictionless step responses of the CDFS and DDFS against their exact (matrix-exponential)
response, each decade of ``accuracy`` lowers the error 9–11× for the dense-output methods
(tests/validation/test_accuracy_convergence.py; benchmarks/results/bench_accuracy.md).  So the
run is repeated with every tolerance ten times tighter (the *shadow*), and the difference of
the two on the output grid estimates the error of the run itself: with errors e and e/10 of
the same shape the difference is 0.9 e, with unrelated shapes √1.01 e — within 10 % either
way, a factor 3 at worst where proportionality holds only roughly (stick–slip: the error is
the drift of the slip instants, which a tighter run shortens in proportion too).  The cost is
the shadow run: 1.6–2.5× the run (steps ∝ tolerance^(−1/5) for DOPRI5, ^(−1/4) for RODAS4).
Tolerance proportionality and running at two tolerances: Hairer, Nørsett & Wanner [1]_;
global error estimation with one-step methods: Shampine [2]_.

References
----------
.. [1] E. Hairer, S. P. Nørsett, G. Wanner, Solving Ordinary Differential Equations I, 2nd ed.,
   Springer, 1993, Sect. II.4 ("tolerance proportionality", and global error estimation by
   running at two tolerances).
.. [2] L. F. Shampine, "Global error estimation with one-step methods", Comput. Math. Appl.
   12A (1986) 885–894.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ..parameters import ParameterError
from ..solvers.global_error import INTERVAL as _INTERVAL
from ..solvers.global_error import MEASURED_RATIO as _RATIO
from ..solvers.global_error import REFRESH_STEPS as _REFRESH
from . import options as opt

if TYPE_CHECKING:
    from .options import SolverOptions
    from .result import Result

__all__ = ["ESTIMATES", "RATIOS", "RUN_RATIO", "RUN_RATIO_ACCURACY", "SHADOW_FACTOR",
           "SHADOW_RATIO", "embedded_entry", "estimate_kind", "ratio_text", "signal_errors",
           "summary_entry", "tightened", "tightening_refused"]

#: the shadow run's tolerances: this many times tighter
SHADOW_FACTOR = 10.0
#: what the shadow estimate is worth where a critical speed is written with it: the measured
#: range of its ratio to the true table-speed error on the trials that decide the
#: ``reproduce`` report's critical speeds and band edges (``wang2021`` at mid-screw: CDFS
#: 1.0, 1.42, 1.55 mm/s for 12 s and 1.56 mm/s for 24 s, DDFS 0.02 mm/s at v_n = 16 mm/s,
#: against scipy's Radau at rtol 1e-13, ``reference/cases.py``'s ``DECIDING_SETTINGS``,
#: stored in tests/data/radau_deciding_trials.npz) at ``accuracy`` 1 and 0.1, and on three
#: stick-slip runs
#: (``reference/cases.py``, against their stored Radau references) at ``accuracy`` 1;
#: measured 2026-12-06: 0.91–1.0 (0.85–1.0 against the rtol-1e-11 references used before,
#: one of which was 1.2e-10 m/s off on another CPU) and 0.89–1.1 (against a Radau at rtol
#: 1e-12, the stick-slip runs 0.83–1.0 at ``accuracy`` 1 … 0.01); checked by
#: tests/validation/test_accuracy_shadow_trials.py
SHADOW_RATIO = (0.8, 1.2)
#: what a run's shadow estimate is worth (``simulate(..., error_estimate=True)``,
#: ``simulate --error-estimate``): the measured range of its ratio to the true error, rounded
#: outward — measured 2026-12-06 0.58–1.29 on the frictionless step responses against their
#: exact solution (tests/validation/test_error_estimate.py: every method, CDFS and DDFS at
#: 0.1, 1 and 10 mm/s, ``accuracy`` 1 and 0.01, table position and speed and screw current;
#: the ends the DDFS's table position and screw current) and 0.85–1.02 on the smooth LuGre
#: runs against scipy's Radau (tests/validation/test_accuracy_friction.py, every method,
#: ``accuracy`` 1 and 0.1); both tests check their ratios inside it
RUN_RATIO = (0.5, 1.5)
#: the ``accuracy`` range over which :data:`RUN_RATIO` was measured (the tests above); a run
#: outside it gets a note beside the ratio (an outside check measured 1.6× on one signal of a
#: CDFS run at ``accuracy`` 100)
RUN_RATIO_ACCURACY = (0.01, 1.0)
#: how the estimate was made, as a result states it
METHOD_TEXT = (f"difference to a run with every tolerance {SHADOW_FACTOR:g}× tighter "
               "(tolerance proportionality; feeddrive.engine.error_estimate)")
#: the ways an integration error is estimated (``error_estimate`` of ``simulate`` and of the
#: creep searches): True is the first
ESTIMATES = ("shadow", "embedded")


def ratio_text(ratio: tuple[float, float]) -> str:
    """A measured range of an estimate over the true error as it is written beside the number:
    two significant digits, thousands spaced (``"0.15–200 000"``, ``"0.8–1.2"``).

    Parameters
    ----------
    ratio : tuple of float
        The lowest and highest ratio [-].

    Returns
    -------
    str
        The range.
    """
    return "–".join(f"{r:.2g}" if r < 1e3 else f"{r:,.0f}".replace(",", " ") for r in ratio)


#: the measured range of each estimate's ratio to the true error, by kind (:data:`ESTIMATES`):
#: what is written beside an estimate wherever it is shown
RATIOS = {"shadow": SHADOW_RATIO, "embedded": _RATIO}

EMBEDDED_TEXT = (f"the accepted steps' local error estimates summed per {1e3 * _INTERVAL:g}-ms "
                 f"interval and carried by exp(H J), J taken every {_REFRESH} steps "
                 f"(feeddrive.solvers.global_error); {ratio_text(_RATIO)}× the true error "
                 "where measured")


def estimate_kind(error_estimate: bool | str | None) -> str | None:
    """``error_estimate`` as one of :data:`ESTIMATES` (True: ``"shadow"``), or None for none;
    anything else refused in one line.

    Parameters
    ----------
    error_estimate : bool, str or None
        False or None, True, ``"shadow"`` or ``"embedded"``.

    Returns
    -------
    str or None
        ``"shadow"``, ``"embedded"`` or None.

    Raises
    ------
    ParameterError
        For any other value.
    """
    from ..parameters.validation import is_flag

    if error_estimate is None or is_flag(error_estimate) and not error_estimate:
        return None
    if is_flag(error_estimate):  # np.True_ too (it was refused as no boolean)
        return ESTIMATES[0]
    if isinstance(error_estimate, str) and error_estimate in ESTIMATES:
        return error_estimate
    raise ParameterError("error_estimate", error_estimate,
                         "expected False, True or 'shadow' (a second run ten times tighter) "
                         "or 'embedded' (carried along the run)")


#: a tightened value this close (relative) below its floor is the floor, rounded in the division
_ROUNDING = 1e-9


def tightening_refused(options: SolverOptions, factor: float = SHADOW_FACTOR) -> str | None:
    """Why ``options`` cannot be made ``factor`` times tighter, or None when they can: the
    one rule of :func:`tightened` (the error estimate's shadow run, the fit's tightening)
    and of :func:`feeddrive.analysis.critical.shadow_possible` (a creep search's estimate).

    A tightened setting may not fall below its floor (:func:`feeddrive.engine.options.floor`:
    ``MIN_RELATIVE`` for ``rtol``, ``MIN_ABSOLUTE`` for an absolute tolerance,
    ``MIN_ACCURACY`` for ``accuracy``, which carries the default tolerances): the run's own
    settings are then at double precision's reach.  The reason names the setting as the user
    gave it (:meth:`~feeddrive.SolverOptions.setting_text`: the command line's
    option in its units, a file's setting, the API's field).

    Parameters
    ----------
    options : SolverOptions
        The run's options.
    factor : float, default SHADOW_FACTOR
        How much tighter [-].

    Returns
    -------
    str or None
        ``"needs a run 10× tighter than position tolerance 1e-21 mm, below 1e-21 mm: give a
        looser --position-tolerance to estimate its error"``, or None.
    """
    for name, value in _tightened_values(options, factor).items():
        low = opt.floor(name)
        if value < low * (1.0 - _ROUNDING):  # (1e-16 A ÷ 10 is 9.999999999999999e-18)
            return (f"needs a run {factor:g}× tighter than {options.setting_text(name)}, "
                    f"below {options.setting_value(name, low)}: give a looser "
                    f"{options.setting_place(name)} to estimate its error")
    return None


def _tightened_values(options: SolverOptions, factor: float) -> dict[str, float]:
    """The settings :func:`tightened` changes and their new values: each explicit tolerance
    ÷ ``factor``, and ``accuracy`` ÷ ``factor`` where it acts (a default tolerance, or the
    step caps of ``dopri5``: :attr:`~feeddrive.engine.options.SolverOptions.accuracy_acts`)."""
    changes: dict[str, float] = {}
    for name, _, _ in opt.TOLERANCES:
        value = getattr(options, name)
        if value is not None:
            changes[name] = value / factor
    if options.accuracy_acts:
        changes["accuracy"] = options.accuracy / factor
    return changes


def tightened(options: SolverOptions, factor: float = SHADOW_FACTOR) -> SolverOptions:
    """``options`` with every tolerance ``factor`` times tighter: the explicit ones divided,
    the defaults through ``accuracy`` (which also tightens ``dopri5``'s step caps, and so is
    divided under ``dopri5`` even with every tolerance explicit), as docs/model.md's rule
    scales them.  Each tightened setting keeps naming where it came from
    (:meth:`~feeddrive.SolverOptions.tightened_source`: ``"--rtol ÷ 10"``).

    Parameters
    ----------
    options : SolverOptions
        The run's options.
    factor : float, default SHADOW_FACTOR
        How much tighter [-].

    Returns
    -------
    SolverOptions
        The shadow run's options.

    Raises
    ------
    ParameterError
        When a tightened setting would fall below its floor (:func:`tightening_refused`: the
        run's own settings are then at double precision's reach, no estimate is possible).
    """
    refused = tightening_refused(options, factor)
    if refused is not None:
        raise ParameterError("error_estimate", True, refused)
    # a value at its floor but for the division's rounding taken as the floor
    changes: dict[str, Any] = {name: max(value, opt.floor(name))
                               for name, value in _tightened_values(options, factor).items()}
    # each tightened setting named as derived from its own source: the accuracy apart from
    # the run's explicit tolerances (which it divides), not the two in one setting that
    # SolverOptions refuses
    origin = dict(options.origin)
    origin.update({name: options.tightened_source(name, factor) for name in changes})
    return replace(options, **changes, origin=tuple(sorted(origin.items())))


def signal_errors(result: Result, shadow: Result) -> dict[str, dict[str, float]]:
    """Per signal of ``result``, the largest difference to ``shadow`` on the common output
    grid, absolute and relative to the signal's range (its peak-to-peak; its largest |value|
    when constant).

    Parameters
    ----------
    result, shadow : Result
        The run and its shadow (same output instants).

    Returns
    -------
    dict
        ``{signal: {"absolute": [SI], "relative": [-]}}``.
    """
    if result.time.shape != shadow.time.shape or not np.array_equal(result.time, shadow.time):
        raise ValueError("the shadow run's output instants differ from the run's")
    out: dict[str, dict[str, float]] = {}
    for name in result.signal_names():
        a, b = np.asarray(result[name], dtype=float), np.asarray(shadow[name], dtype=float)
        diff = float(np.max(np.abs(a - b))) if a.size else 0.0
        out[name] = _entry(diff, a)
    return out


def _entry(error: float, signal: np.ndarray) -> dict[str, float]:
    """``error`` absolute and relative to ``signal``'s range (its peak-to-peak; its largest
    |value| when constant; 0 relative for a signal that is 0 throughout)."""
    span = float(np.ptp(signal)) if signal.size else 0.0
    if span == 0.0:
        span = float(np.max(np.abs(signal))) if signal.size else 0.0
    return {"absolute": error, "relative": error / span if span > 0.0 else 0.0}


def _largest(errors: dict[str, dict[str, float]]) -> dict[str, Any]:
    worst = max(errors.items(), key=lambda kv: kv[1]["relative"]) if errors else ("", {})
    return {"signal": worst[0],
            "relative": worst[1].get("relative", 0.0) if worst[1] else 0.0}


def embedded_entry(names: list[str], largest: np.ndarray,
                   states: np.ndarray | None = None) -> dict[str, Any]:
    """The embedded estimate (:mod:`feeddrive.solvers.global_error`) as a run's
    ``solver_stats["embedded_error_estimate"]`` holds it: per state, the largest propagated
    error over the run, absolute and (with ``states``) relative to the state's range on the
    output grid.

    Parameters
    ----------
    names : list of str
        The model's state names.
    largest : numpy.ndarray
        The largest |E| over the run per state [SI, per state].
    states : numpy.ndarray, optional
        The run's states on its output grid, (samples, states) [SI]: without them (a creep
        trial reads its table speed's absolute error only) no ``relative`` entries — the
        ranges of a long run's states cost more than the estimate.

    Returns
    -------
    dict
        ``kind`` ("embedded"), ``ratio_to_true_error`` (the measured range of the estimate
        over the true error), ``method`` (how), ``signals`` (``{state: {"absolute": [SI],
        "relative": [-]}}``), ``largest_relative`` (signal and value; with ``states``).
    """
    how = {"kind": "embedded", "ratio_to_true_error": list(RATIOS["embedded"]),
           "method": EMBEDDED_TEXT}
    if states is None:
        return {**how, "signals": {name: {"absolute": float(largest[k])}
                                   for k, name in enumerate(names)}}
    signals = {name: _entry(float(largest[k]), np.asarray(states[:, k], dtype=float))
               for k, name in enumerate(names)}
    return {**how, "signals": signals, "largest_relative": _largest(signals)}


def summary_entry(errors: dict[str, dict[str, float]], options: SolverOptions,
                  shadow: SolverOptions, shadow_stats: dict[str, Any]) -> dict[str, Any]:
    """The estimate as a run's ``solver_stats["error_estimate"]`` holds it.

    Parameters
    ----------
    errors : dict
        :func:`signal_errors`.
    options, shadow : SolverOptions
        The run's and the shadow's options.
    shadow_stats : dict
        The shadow run's solver statistics.

    Returns
    -------
    dict
        ``kind`` ("shadow"), ``ratio_to_true_error`` (:data:`RUN_RATIO`),
        ``ratio_measured_at_accuracy`` (:data:`RUN_RATIO_ACCURACY`; ``ratio_note`` for a run
        outside it), ``method`` (how), ``shadow`` (its tolerances and cost), ``signals`` (per
        signal), ``largest_relative`` (signal and value).
    """
    low, high = RUN_RATIO_ACCURACY
    note = {} if low <= options.accuracy <= high else {
        "ratio_note": f"the ratio was measured at accuracy {low:g}–{high:g}; this run's "
                      f"accuracy {options.accuracy:g} is outside that range"}
    return {"kind": "shadow", "ratio_to_true_error": list(RUN_RATIO),
            "ratio_measured_at_accuracy": list(RUN_RATIO_ACCURACY), **note,
            "method": METHOD_TEXT,
            "shadow": {"accuracy": shadow.accuracy, "rtol": shadow_stats.get("rtol"),
                       "steps": shadow_stats.get("steps"),
                       "rhs_evaluations": shadow_stats.get("rhs_evaluations")},
            "signals": errors,
            "largest_relative": _largest(errors)}
