"""The last two speed checks worded their own way now call the shared one (session 27).

1. ``trace_input.check_command``, behind the public ``creep_metrics``, ``steady_window``,
   ``trace_verdict`` and ``trace.hold_settled``, raised a bare ValueError of its own wording
   for a NaN, infinite, zero or non-numeric ``command_speed``, and took 1e9 m/s.  It is now
   ``feeddrive.parameters.validation.check_speed(sign="nonzero")``: a ParameterError (still a
   ValueError) naming ``command_speed``, the value and [m/s], with the bound
   ``units.LARGEST_SPEED``.
2. ``synthetic_experiment`` refused a speed above ``LARGEST_SPEED`` in words of its own and
   a NaN or a str as ``profile.table_speed``, a field its caller never wrote; it now names
   ``speed`` in the shared words (either sign and 0 still taken, as the profile takes them).
   ``analyze_trace``, which hands these functions a command it takes from the record (the
   position's slope, a command column), refuses one beyond the bound naming ``position`` or
   ``command`` (a position in µm given as m was analysed at 1000 m/s).
3. ``fmu.solver_starts`` (NaN tolerances for a NaN speed, TypeError for a str) and
   ``compensation.default_cases`` (a NaN nut speed taken into a case, "Unknown format code"
   for a str) checked no speed; both now call the shared check.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.analysis.compensation import default_cases
from feeddrive.analysis.creep_window import creep_metrics, steady_window
from feeddrive.analysis.cycle_verdict import trace_verdict
from feeddrive.analysis.fit import synthetic_experiment
from feeddrive.analysis.trace import analyze_trace, hold_settled
from feeddrive.fmu import solver_starts
from feeddrive.parameters import ParameterError
from feeddrive.parameters.validation import check_speed

# a speed oscillating ±80 % about 1 mm/s at 2 Hz (creep_metrics' docstring example)
T = np.linspace(0.0, 4.0, 4001)
V = 1e-3 * (1.0 + 0.8 * np.sin(2 * np.pi * 2.0 * T))

BAD = [math.nan, math.inf, -math.inf, "0.001", True, None, 0.0, 0, 1e9, -1e9, 500.0]

TRACE_FUNCTIONS: dict[str, Callable[[object], object]] = {
    "creep_metrics": lambda vc: creep_metrics(T, V, vc),  # type: ignore[arg-type]
    "steady_window": lambda vc: steady_window(T, V, vc),  # type: ignore[arg-type]
    "trace_verdict": lambda vc: trace_verdict(T, V, vc),  # type: ignore[arg-type]
    "hold_settled": lambda vc: hold_settled(T, V, vc, "smooth"),  # type: ignore[arg-type]
}


def _refusal(make: Callable[[], object]) -> ParameterError:
    with pytest.raises(ParameterError) as err:
        make()
    assert "\n" not in str(err.value)
    return err.value


def _shared(name: str, value: object, sign: str) -> str:
    return str(_refusal(lambda: check_speed(name, value, sign=sign)))


# ------------------------------------------------------------------ 1. the command speed


@pytest.mark.parametrize("function", sorted(TRACE_FUNCTIONS))
@pytest.mark.parametrize("speed", BAD)
def test_a_bad_command_speed_is_a_parameter_error_in_the_shared_words(function: str,
                                                                       speed: object) -> None:
    """Was a bare ValueError ("command_speed = nan: expected a finite, non-zero speed");
    1e9 m/s was taken as a command."""
    err = _refusal(lambda: TRACE_FUNCTIONS[function](speed))
    assert err.field == "command_speed"
    assert "[m/s]" in err.message
    assert str(err) == _shared("command_speed", speed, "nonzero")


@pytest.mark.parametrize("function", sorted(TRACE_FUNCTIONS))
def test_a_bad_command_speed_is_still_caught_as_a_value_error(function: str) -> None:
    with pytest.raises(ValueError, match=r"^command_speed = nan: expected a finite, non-zero "
                                         r"speed \[m/s\]$"):
        TRACE_FUNCTIONS[function](math.nan)


def test_a_command_above_the_bound_names_it() -> None:
    assert _refusal(lambda: creep_metrics(T, V, 1e9)).message == \
        "expected |speed| ≤ 100 [m/s] (no feed drive is faster)"  # units.LARGEST_SPEED


@pytest.mark.parametrize("speed", [1e-3, np.float64(1e-3), -1e-3])
def test_a_command_within_the_bound_is_taken_with_either_sign(speed: float) -> None:
    sign = float(np.sign(speed))
    assert creep_metrics(T, sign * V, speed, frequency=False).verdict == "creeping"
    assert trace_verdict(T, sign * V, speed).kind == trace_verdict(T, V, 1e-3).kind


# the same trace as a position [m] (analyze_trace's docstring example)
X = 1e-3 * T - 0.8e-3 / (2 * np.pi * 2.0) * np.cos(2 * np.pi * 2.0 * T)


def test_analyze_trace_names_the_position_when_its_slope_is_no_feed_speed() -> None:
    """A position in µm given as m: analysed as "creeping" at a command of 995 m/s before;
    with the bounded command check it would blame ``command_speed``, which was not given."""
    err = _refusal(lambda: analyze_trace(T, 1e6 * X))
    assert err.field == "position"
    assert re.match(r"segment \d\.\d{3}–4\.000 s moves at 1000 m/s", err.message), err.message
    assert err.message.endswith("m/s, faster than any feed drive (|speed| ≤ 100 m/s): "
                                "expected a position in m [m]")


def test_analyze_trace_names_a_command_column_beyond_the_bound() -> None:
    err = _refusal(lambda: analyze_trace(T, X, command=np.full(T.size, 500.0)))
    assert err.field == "command"
    assert err.message.endswith("moves at 500 m/s, faster than any feed drive (|speed| ≤ "
                                "100 m/s): expected a command speed in m/s [m/s]")


def test_analyze_trace_still_estimates_a_feed_speed_from_the_position() -> None:
    segment = analyze_trace(T, X).segments[0]
    assert (segment.command_from, segment.metrics.verdict) == ("estimated", "creeping")
    assert segment.command_speed == pytest.approx(1e-3, rel=0.01)


# ------------------------------------------------------------------ 2. synthetic_experiment


@pytest.mark.parametrize("speed", [math.nan, math.inf, -math.inf, "0.001", None, 1e9, -500.0])
def test_synthetic_experiment_names_speed_in_the_shared_words(speed: object) -> None:
    """NaN and a str were refused as ``profile.table_speed``; inf and 1e9 as "expected a
    speed of at most 100 m/s in magnitude"."""
    err = _refusal(lambda: synthetic_experiment(fd.preset("wang2021"), speed, 0.3))  # type: ignore[arg-type]
    assert err.field == "speed"
    assert "[m/s]" in err.message
    assert str(err) == _shared("speed", speed, "any")


# ------------------------------------------------------------------ 3. the other public ones


@pytest.mark.parametrize("speed", [math.nan, math.inf, "0.001", None, 1e9])
@pytest.mark.parametrize("field", ["table_speed", "nut_speed"])
def test_solver_starts_refuses_a_bad_start_speed(field: str, speed: object) -> None:
    """``fmu.solver_starts`` returned NaN tolerances for a NaN speed and took 1e9 m/s; a str
    failed in ``abs()`` with a bare TypeError."""
    speeds = {"table_speed": 1e-3, "nut_speed": 0.0} | {field: speed}
    err = _refusal(lambda: solver_starts(fd.preset("wang2021"), **speeds))  # type: ignore[arg-type]
    assert err.field == field
    assert "[m/s]" in err.message
    assert str(err) == _shared(field, speed, "any")


def test_solver_starts_still_takes_zero_and_either_sign() -> None:
    p = fd.preset("wang2021")
    assert solver_starts(p, 0.0, 0.0) == solver_starts(p, -0.0, 0.0)
    assert solver_starts(p, -2e-3, 5e-3) == solver_starts(p, 2e-3, -5e-3)


@pytest.mark.parametrize("speed", [math.nan, math.inf, "0.001", None, 1e9])
def test_default_cases_refuses_a_bad_nut_speed(speed: object) -> None:
    """``default_cases(nut_speed=nan)`` made a case that failed only when run (naming
    ``profile.nut_speed``); a str ended in "Unknown format code 'g'"; 1e9 was taken."""
    err = _refusal(lambda: default_cases(nut_speed=speed))  # type: ignore[arg-type]
    assert err.field == "nut_speed"
    assert "[m/s]" in err.message
    assert str(err) == _shared("nut_speed", speed, "any")


def test_default_cases_still_takes_a_nut_speed() -> None:
    assert default_cases(nut_speed=-16e-3)[-1].nut_speed == -16e-3
