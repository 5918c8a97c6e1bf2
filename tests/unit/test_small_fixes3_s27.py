"""Two more small fixes (session 27).

1. Two copies of the speed check remained after ``feeddrive.parameters.validation.
   check_speed`` became the one the profiles and the analyses call, each worded its own way:
   ``analyze_trace(command_speed=…)`` refused a str as "expected a finite, non-zero speed"
   (the analyses: "expected a number") and said "the API takes m/s" to every speed above
   ``LARGEST_SPEED``, 1e9 m/s too (no mm/s figure); the FMU's start speeds
   (``export_fmu(table_speed=…, nut_speed=…)``, ``fmu.model.InputReference``) took 500 m/s
   and failed on a str with a bare TypeError.  Both now call the shared check.
2. ``protocol.describe`` stated the protocol's own step-down steps (0.1 / 0.01 mm/s) whatever
   steps a search ran (``critical_speed_stepdown(coarse_step=…, step=…)``, a sweep's
   ``[quantity]`` with ``start = "running"``) and the protocol's bisection resolution from
   rest; it now states the steps given, from the grids the search runs
   (``protocol.speed_grid``, ``protocol.fine_staircase``), with the shorter last fine step in
   every coarse step when the fine step does not divide the coarse one.  The default sentences
   (``reproduce``'s report prints them) are unchanged.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from feeddrive.analysis import protocol
from feeddrive.analysis.trace import analyze_trace
from feeddrive.fmu.model import InputReference
from feeddrive.parameters import ParameterError
from feeddrive.parameters.validation import check_speed
from feeddrive.sweep.quantities import QuantitySettings

MM = 1e-3

# ------------------------------------------------------------------ 1. the speed check

# a trace whose speed oscillates ±80 % about 1 mm/s (analyze_trace's docstring example)
T = np.linspace(0.0, 2.0, 2001)
X = 1e-3 * T - 0.8e-3 / (2 * np.pi * 2.0) * np.cos(2 * np.pi * 2.0 * T)


def _refusal(make: object) -> ParameterError:
    with pytest.raises(ParameterError) as err:
        make()  # type: ignore[operator]
    assert "\n" not in str(err.value)
    return err.value


def _shared(name: str, value: object, sign: str) -> str:
    return str(_refusal(lambda: check_speed(name, value, sign=sign)))


@pytest.mark.parametrize("speed", ["0.001", True, math.nan, -math.inf, 0.0, 500.0, -1e9])
def test_the_trace_command_speed_is_refused_in_the_shared_words(speed: object) -> None:
    """analyze_trace said "expected a finite, non-zero speed" to a str and "the API takes m/s"
    to 1e9 m/s; it now says what every analysis says."""
    err = _refusal(lambda: analyze_trace(T, X, command_speed=speed))
    assert str(err) == _shared("command_speed", speed, "nonzero")


def test_the_trace_command_speed_hints_mm_s_only_where_it_fits() -> None:
    """500 m/s read as mm/s is 0.5 m/s, a feed speed: the hint says so; 1e9 m/s is no
    mm/s figure (1e6 m/s), and no longer told "the API takes m/s"."""
    assert _refusal(lambda: analyze_trace(T, X, command_speed=500.0)).message.endswith(
        "; the API takes m/s: 500 mm/s is 0.5")
    assert "mm/s" not in _refusal(lambda: analyze_trace(T, X, command_speed=1e9)).message
    assert "the API takes" not in _refusal(
        lambda: analyze_trace(T, X, command_speed=-1e9)).message


def test_the_trace_command_speed_still_takes_a_speed_within_the_bound() -> None:
    a = analyze_trace(T, X, command_speed=-1e-3)
    assert a.segments[0].command_speed == -1e-3  # a negative command is a command


@pytest.mark.parametrize("field", ["table_speed", "nut_speed"])
@pytest.mark.parametrize("speed", [500.0, -1e9, "0.001", None])
def test_the_fmu_start_speeds_are_refused_in_the_shared_words(field: str,
                                                              speed: object) -> None:
    """500 m/s was written into the FMU as its start speed; a str failed with TypeError."""
    err = _refusal(lambda: InputReference(**{field: speed}).encode())  # type: ignore[arg-type]
    assert err.field == field
    assert str(err) == _shared(field, speed, "any")


def test_the_fmu_start_speeds_keep_their_finite_wording_and_take_any_sign() -> None:
    assert str(_refusal(lambda: InputReference(math.inf).encode())) == \
        "table_speed = inf: expected a finite speed [m/s]"  # as before
    _, table = InputReference(-2e-3, 5e-3).encode()
    assert (table[1, 0], table[3, 0]) == (-2e-3, 5e-3)


# ------------------------------------------------------------------ 2. the protocol line


def test_the_default_sentences_are_byte_identical() -> None:
    """reproduce's report prints describe('rest') and describe('running'): unchanged."""
    assert protocol.describe("rest") == (
        "from rest: trials of 12 s doubled up to 240 s until decided, scan 0.02–3.02 mm/s in "
        "0.2-mm/s steps, then bisection to 0.01 mm/s")
    assert protocol.describe("running") == (
        "step-down on a running table: staircase from 3.02 mm/s in 0.1-mm/s steps, then "
        "0.01-mm/s steps from the last smooth one (down to 0.02 mm/s)")
    assert protocol.describe("running", holds=True) == (
        "step-down on a running table: staircase from 3.02 mm/s in 0.1-mm/s steps, then "
        "0.01-mm/s steps from the last smooth one (down to 0.02 mm/s), each step held 12 s "
        "doubled up to 240 s until decided")
    # the protocol's own steps given explicitly read the same
    assert protocol.describe("running", coarse_step=protocol.STAIRCASE_COARSE_STEP,
                             resolution=protocol.RESOLUTION) == protocol.describe("running")
    assert protocol.describe("rest", coarse_step=protocol.COARSE_STEP,
                             resolution=protocol.RESOLUTION) == protocol.describe("rest")


def _gaps(upper: float, lower: float, step: float) -> list[float]:
    """The fine staircase's steps between two coarse speeds [mm/s] (protocol.fine_staircase,
    the grid critical_speed_stepdown runs)."""
    fine = np.concatenate([[upper], protocol.fine_staircase(upper, lower, step)])
    return [round(g, 9) for g in -1e3 * np.diff(fine)]


def test_a_stepdown_with_other_steps_states_them() -> None:
    """critical_speed_stepdown(coarse_step=0.25 mm/s, step=0.02 mm/s) on 1–2 mm/s: the line
    said 0.1-mm/s then 0.01-mm/s steps.  0.02 does not divide 0.25: each fine staircase
    ends on a 0.01-mm/s step."""
    lo, hi, coarse, fine = 1.0 * MM, 2.0 * MM, 0.25 * MM, 0.02 * MM
    grid = protocol.speed_grid(lo, hi, coarse)
    assert set(np.round(1e3 * np.diff(grid), 9)) == {0.25}
    assert _gaps(float(grid[-1]), float(grid[-2]), fine) == [0.02] * 12 + [0.01]
    assert protocol.describe("running", speed_range=(lo, hi), coarse_step=coarse,
                             resolution=fine) == (
        "step-down on a running table: staircase from 2 mm/s in 0.25-mm/s steps, then "
        "0.02-mm/s steps from the last smooth one, the last 0.01 mm/s within each coarse "
        "step (down to 1 mm/s)")


def test_a_shorter_first_coarse_step_is_stated_apart() -> None:
    """1–2.1 mm/s in 0.25-mm/s steps starts with a 0.1-mm/s step, five whole 0.02-mm/s fine
    steps, while each whole coarse step ends on 0.01 mm/s; 1.605 mm/s with 0.03-mm/s fine
    steps ends its first (0.085-mm/s) coarse step on 0.025 mm/s."""
    lo, hi = 1.0 * MM, 2.1 * MM
    grid = protocol.speed_grid(lo, hi, 0.25 * MM)
    assert _gaps(float(grid[-1]), float(grid[-2]), 0.02 * MM) == [0.02] * 5
    text = protocol.describe("running", speed_range=(lo, hi), coarse_step=0.25 * MM,
                             resolution=0.02 * MM)
    assert ("staircase from 2.1 mm/s in 0.25-mm/s steps, the first 0.1 mm/s, then 0.02-mm/s "
            "steps from the last smooth one, the last 0.01 mm/s within each coarse step but "
            "the first (down to 1 mm/s)") in text, text
    grid = protocol.speed_grid(0.02 * MM, 1.605 * MM, protocol.STAIRCASE_COARSE_STEP)
    assert _gaps(float(grid[-1]), float(grid[-2]), 0.03 * MM) == [0.03, 0.03, 0.025]
    assert _gaps(float(grid[-2]), float(grid[-3]), 0.03 * MM) == [0.03, 0.03, 0.03, 0.01]
    text = protocol.describe("running", speed_range=(0.02 * MM, 1.605 * MM),
                             resolution=0.03 * MM)
    assert ("in 0.1-mm/s steps, the first 0.085 mm/s, then 0.03-mm/s steps from the last "
            "smooth one, the last 0.01 mm/s within each coarse step but the first, 0.025 mm/s "
            "within that one (down to 0.02 mm/s)") in text, text


def test_one_whole_coarse_step_says_within_it() -> None:
    text = protocol.describe("running", speed_range=(1.0 * MM, 1.25 * MM),
                             coarse_step=0.25 * MM, resolution=0.02 * MM)
    assert text.endswith("in 0.25-mm/s steps, then 0.02-mm/s steps from the last smooth one, "
                         "the last 0.01 mm/s within it (down to 1 mm/s)"), text


def test_a_sweeps_running_quantity_is_stated_with_its_steps() -> None:
    """A sweep's [quantity] start = "running", coarse_step = 0.2, resolution = 0.05 [mm/s]
    runs critical_speed_stepdown(coarse_step=q.coarse_step, step=q.resolution): the line
    states those, not 0.1 / 0.01 mm/s."""
    q = QuantitySettings.parse({"start": "running", "low": 0.5, "high": 2.5,
                                "coarse_step": 0.2, "resolution": 0.05})
    text = protocol.describe("running", speed_range=(q.low, q.high),
                             coarse_step=q.search_coarse_step, resolution=q.resolution)
    assert text == ("step-down on a running table: staircase from 2.5 mm/s in 0.2-mm/s steps, "
                    "then 0.05-mm/s steps from the last smooth one (down to 0.5 mm/s)")


def test_the_rest_line_states_the_resolution_given() -> None:
    """critical_speed_from_rest(resolution=0.005 mm/s): the line said bisection to 0.01."""
    assert protocol.describe("rest", resolution=0.005 * MM).endswith(
        "then bisection to 0.005 mm/s")
