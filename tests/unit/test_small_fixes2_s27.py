"""Three more small fixes (session 27).

1. A speed given to a profile (``feeddrive.model.reference``) and one given to an analysis
   (``feeddrive.analysis``) were checked by two copies of one rule, which had drifted: a
   profile refused a str or None as "expected a finite speed" where an analysis said
   "expected a number", gave no "the API takes m/s" hint for 1000 m/s, and let an int beyond
   any float (``ConstantSpeed(10**400)``) out as a bare OverflowError.  One check now serves
   both (``feeddrive.parameters.validation.check_speed``).
2. The Nyquist plot of ``feeddrive loops --plot-kind nyquist`` gave each loop's phase margin
   in its legend and never its gain margin; it now gives both, in the Bode legend's words.
3. The step-down's fine staircase between two coarse speeds whose gap is not a whole number of
   fine steps (the first gap of a staircase from ``creep --high 1.537``) did not end on the
   coarse speed below: half a step or more short it stepped past it, below the gap it refines
   (1.527, then 1.517 mm/s under the coarse 1.52), less than half it stopped above it (1.521,
   never 1.52).  It now ends on it, the last step shorter (``protocol.fine_staircase``), and
   the protocol line says so; the protocol's own staircase (whole gaps) is unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.analysis import critical, protocol  # noqa: E402
from feeddrive.analysis.critical import CreepTrial  # noqa: E402
from feeddrive.analysis.cycle_verdict import VerdictRule  # noqa: E402
from feeddrive.analysis.linear import loop_analysis  # noqa: E402
from feeddrive.cli import creep_cmd  # noqa: E402
from feeddrive.parameters import ParameterError  # noqa: E402
from feeddrive.plots.linear import _bode, _nyquist  # noqa: E402

MM = 1e-3
CDFS = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)

# ------------------------------------------------------------------ 1. one speed check


def _refusal(make: Any) -> tuple[str, str]:
    with pytest.raises(ParameterError) as err:
        make()
    return err.value.field, err.value.message


@pytest.mark.parametrize("speed", ["0.001", None, True, pytest.param(10 ** 400, id="10**400"),
                                   math.nan, -math.inf, 1e3, -1e3, 1e300])
def test_a_profile_and_an_analysis_refuse_a_speed_in_the_same_words(speed: object) -> None:
    """The profile's copy said "expected a finite speed" to a str (the analysis: "expected a
    number"), gave no mm/s hint for 1000 m/s and raised OverflowError for 10**400."""
    profile = _refusal(lambda: fd.ConstantSpeed(1e-3, nut_speed=speed))
    analysis = _refusal(lambda: fd.Target("cdfs", 1.56e-3, nut_speed=speed))
    assert (profile[0], analysis[0]) == ("profile.nut_speed", "target.nut_speed")
    assert profile[1] == analysis[1]


def test_an_int_beyond_any_float_is_refused_naming_the_field() -> None:
    """``ConstantSpeed(10**400)`` ended in ``OverflowError: int too large to convert to
    float`` from ``math.isfinite``."""
    assert _refusal(lambda: fd.ConstantSpeed(10 ** 400)) == (
        "profile.table_speed", "expected a finite speed [m/s]")
    assert _refusal(lambda: fd.trapezoid(10 ** 400, 2.0)) == (
        "table_speed", "expected a finite speed [m/s]")


def test_a_speed_too_large_in_m_s_but_not_in_mm_s_says_the_api_takes_m_s() -> None:
    field, message = _refusal(lambda: fd.ConstantSpeed(1.5e3))
    assert field == "profile.table_speed"
    assert message == ("expected |speed| ≤ 100 [m/s] (no feed drive is faster); the API "
                       "takes m/s: 1500 mm/s is 1.5")


# ------------------------------------------------------------------ 2. the Nyquist legend


def _legend(fig: Any) -> dict[str, str]:
    (legend,) = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    return {t.get_text().split(",")[0]: t.get_text() for t in legend.get_texts()}


def test_the_nyquist_legend_gives_both_margins_as_the_bode_legend() -> None:
    """The frictionless wang2021 CDFS loops at 1.5 mm/s: the screw position loop's gain margin
    is 2.59 dB (docs/linear.md item 6, python-control's 2.589 dB); the velocity loop's phase
    never crosses −180°, an infinite gain margin.  Old: "screw position loop, PM 89.7°"."""
    analysis = loop_analysis(CDFS, 1.5e-3, frictionless=True, points=40)
    nyquist, bode = _legend(_nyquist(analysis)), _legend(_bode(analysis))
    assert nyquist["screw position loop"].endswith(", GM 2.6 dB"), nyquist
    assert ", PM 89.7° at 1.36 Hz" in nyquist["screw position loop"], nyquist
    assert nyquist["screw velocity loop"].endswith(", GM ∞ dB"), nyquist
    for name in ("screw position loop", "screw velocity loop"):
        assert nyquist[name] == bode[name]


# ------------------------------------------------------------------ 3. the fine staircase


def _kind(speed: float, edge: float) -> str:
    return "oscillation" if speed < edge else "smooth"


@pytest.fixture
def walks(monkeypatch: pytest.MonkeyPatch) -> tuple[list[list[float]], list[float]]:
    """Every staircase closed-form (creeping below the edge, smooth above: history plays no
    part), as in tests/unit/test_search_grid_s26.py; the speeds of each walk, in order, and
    the edge [m/s] (set by the test)."""
    walked: list[list[float]] = []
    edge = [1.555 * MM]

    def walk_down(system: object, speeds: Sequence[float], *, stop_after: int | None = None,
                  **kwargs: Any) -> tuple[list[CreepTrial], float]:
        trials: list[CreepTrial] = []
        walked.append([])
        for v in speeds:
            walked[-1].append(float(v))
            trials.append(CreepTrial(speed=float(v), kind=_kind(float(v), edge[0]),
                                     ripple_ratio=0.0, stick_fraction=0.0,
                                     stick_slip_frequency=None, min_ratio=1.0, duration=1.0))
            if (stop_after is not None and len(trials) > stop_after + 1
                    and trials[-1].kind != trials[stop_after].kind):
                break
        return trials, 0.0

    monkeypatch.setattr(critical, "walk_down", walk_down)
    return walked, edge


@pytest.mark.parametrize(("high", "fine"), [
    (1.537, [1.527, 1.52]),  # old: 1.527, 1.517 — past the coarse 1.52, below the gap
    (1.531, [1.521, 1.52]),  # old: 1.521 — never the coarse 1.52
    (1.605, [1.595, 1.585, 1.575, 1.565, 1.555, 1.545, 1.535, 1.525, 1.52]),  # old: no 1.52
])
def test_the_fine_staircase_ends_on_the_coarse_speed_below(
        walks: tuple[list[list[float]], list[float]], high: float, fine: list[float]) -> None:
    """A staircase from ``high`` to 0.02 mm/s (coarse 0.1 mm/s: its first gap to 1.52 mm/s
    is no whole number of 0.01-mm/s steps) on a drive that creeps below 1.5205 mm/s: the
    change of kind is in the first gap, and its fine staircase walks it down to 1.52 mm/s in
    0.01-mm/s steps, the last one shorter."""
    walked, edge = walks
    edge[0] = 1.5205 * MM
    res = fd.critical_speed_stepdown(CDFS, start_speed=high * MM, lowest_speed=0.02 * MM)
    coarse, fine_walk = walked
    assert coarse[:2] == pytest.approx([high * MM, 1.52 * MM], abs=1e-15)
    assert fine_walk[0] == pytest.approx(high * MM, abs=1e-15)  # the coarse history first
    assert fine_walk[1:] == pytest.approx([v * MM for v in fine], abs=1e-15)
    assert min(fine_walk) == pytest.approx(1.52 * MM, abs=1e-15)  # never below the gap
    assert res.status == "found"
    assert res.critical_speed == pytest.approx(fine[-2] * MM, abs=1e-15)


def _old_fine(upper: float, lower: float, step: float) -> np.ndarray:
    """The fine staircase as critical_speed_stepdown built it before (session 27)."""
    return np.round(np.arange(upper - step, lower - step / 2, -step), 12)


@pytest.mark.parametrize(("low", "high"), [
    protocol.SPEED_RANGE,  # `reproduce`, `creep` at its defaults
    (0.05 * MM, 3.0 * MM),  # critical_speed_stepdown's own defaults
])
def test_the_default_staircases_are_unchanged(low: float, high: float) -> None:
    """Every gap of the protocol's staircases is a whole number of 0.01-mm/s steps: each fine
    staircase is the very speeds it was, so `reproduce`'s stored results do not change."""
    coarse = protocol.speed_grid(low, high, protocol.STAIRCASE_COARSE_STEP)[::-1]
    for upper, lower in zip(coarse[:-1], coarse[1:], strict=True):
        new = protocol.fine_staircase(float(upper), float(lower), protocol.RESOLUTION)
        assert np.array_equal(new, _old_fine(float(upper), float(lower), protocol.RESOLUTION))
    # Wang2021 Sect. 6: 0.01 mm/s at a time, down to the coarse speed below
    np.testing.assert_allclose(
        1e3 * protocol.fine_staircase(1.62 * MM, 1.52 * MM, protocol.RESOLUTION),
        np.arange(161, 151, -1) / 100, rtol=0, atol=1e-12)


def test_the_default_stepdown_walks_the_speeds_it_walked(
        walks: tuple[list[list[float]], list[float]]) -> None:
    """`reproduce`'s step-down (the protocol's range, steps and resolution) visits the same
    speeds, coarse and fine, in the same order, as with the old fine staircase."""
    walked, _ = walks
    lo, hi = protocol.SPEED_RANGE
    fd.critical_speed_stepdown(CDFS, start_speed=hi, lowest_speed=lo, step=protocol.RESOLUTION,
                               coarse_step=protocol.STAIRCASE_COARSE_STEP)
    coarse = protocol.speed_grid(lo, hi, protocol.STAIRCASE_COARSE_STEP)[::-1]
    i = int(np.flatnonzero(coarse < 1.555 * MM)[0]) - 1  # the last smooth coarse speed
    old = [*coarse[:i + 1], *_old_fine(coarse[i], coarse[i + 1], protocol.RESOLUTION)]
    stop = next(k for k, v in enumerate(old) if v < 1.555 * MM) + 1
    assert walked == [coarse.tolist(), old[:stop]]


def test_the_protocol_line_states_the_fine_staircases_shorter_last_step() -> None:
    """`creep --high 1.605`: the line said the fine staircase was 0.01-mm/s steps; within the
    first (0.085-mm/s) coarse step its last is 0.005 mm/s."""
    text = creep_cmd.protocol_text("running", (0.02 * MM, 1.605 * MM), 0.0, VerdictRule())
    assert text.startswith(
        "step-down on a running table: staircase from 1.605 mm/s in 0.1-mm/s steps, the first "
        "0.085 mm/s, then 0.01-mm/s steps from the last smooth one, the last 0.005 mm/s within "
        "the first (down to 0.02 mm/s), each step held"), text
    one = protocol.describe("running", speed_range=(1.52 * MM, 1.605 * MM))
    assert "in one 0.085-mm/s step, then 0.01-mm/s steps from the last smooth one, the last " \
           "0.005 mm/s within it (down to 1.52 mm/s)" in one, one


@pytest.mark.parametrize("high", [1.61, 3.02, 1.525])
def test_a_line_of_whole_fine_steps_reads_as_before(high: float) -> None:
    """Whole fine steps (1.61 → 1.52, 3.02 → 2.92), or one step no longer than a fine one
    (1.525 → 1.52), add nothing."""
    text = protocol.describe("running", speed_range=(0.02 * MM, high * MM))
    assert "from the last smooth one (down to 0.02 mm/s)" in text, text
    assert protocol.describe("running") == (
        "step-down on a running table: staircase from 3.02 mm/s in 0.1-mm/s steps, then "
        "0.01-mm/s steps from the last smooth one (down to 0.02 mm/s)")
