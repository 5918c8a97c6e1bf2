"""The circular test's numbers against its stated choices (issue 37 item 4): "a number a user
reads must not depend on an arbitrary choice unless the choice is stated beside it and a test
shows the number is stable to it".  The choices (docs/acceptance-tests.md): samples beyond
10 % of R are no part of the test (``OFF_CIRCLE``), an inferred circle is fitted to the
samples within 1 % of R (``ON_CIRCLE``), the spike is searched within 45° after a reversal
against the 45° before it (``SPIKE_WINDOW``), its region is left out of the fit to 2 % of its
peak (``SPIKE_TAIL``), and each run has a 90° lead-in and lead-out arc.

The trace is the comparison's circle (``feeddrive compensate --compare``): an XY table of two
``wang2021-drive`` CDFS axes, R = 5 mm, F = 5 mm/s, 0.5 m/s² ramps; its reversal spikes are
about 50 µm, 1 % of R (measured: G(b) 69.55 µm, spikes 49.4–53.4 µm)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from feeddrive.analysis import circular as C
from feeddrive.analysis import compensation_compare as cc
from feeddrive.analysis.circular_run import CircularRunTrace, run_circular_test
from feeddrive.machine import Machine, MachineAxis
from feeddrive.parameters import preset

DRIVE = preset("wang2021-drive")
XY = Machine(name="xy", axes=(MachineAxis("x", DRIVE, "cdfs", 0.4),
                              MachineAxis("y", DRIVE, "cdfs", 0.4)))


def _run(lead_deg: float) -> CircularRunTrace:
    return run_circular_test(XY, radius=cc.CIRCLE_RADIUS, feed=cc.CIRCLE_FEED,
                             acceleration=cc.CIRCLE_ACCELERATION,
                             lead_arc=math.radians(lead_deg))


@pytest.fixture(scope="module")
def run() -> CircularRunTrace:
    return _run(90.0)


def _numbers(test: C.CircularTest) -> np.ndarray:
    return np.array([test.bidirectional_circular_deviation, *(s.height for s in test.spikes)])


def _again(run: CircularRunTrace, monkeypatch: pytest.MonkeyPatch, name: str, value: float,
           *, nominal: bool = True) -> np.ndarray:
    monkeypatch.setattr(C, name, value)
    test = C.circular_test(run.time, run.x, run.y, radius=cc.CIRCLE_RADIUS if nominal else None,
                           centre=run.test.centre if nominal else None)
    return _numbers(test)


def test_the_spikes_are_about_one_percent_of_the_radius(run) -> None:
    """The case is the one that matters: a deviation near 1 % of R, where a 1 % exclusion of
    the lead-in cut the spikes' peaks (46.2 µm read before issue 37 item 4)."""
    heights = _numbers(run.test)[1:]
    assert np.all(heights > 0.009 * cc.CIRCLE_RADIUS) and len(heights) == 8


@pytest.mark.parametrize("value", [0.05, 0.2])
def test_the_off_circle_exclusion_changes_nothing(run, monkeypatch, value) -> None:
    assert _again(run, monkeypatch, "OFF_CIRCLE", value) == pytest.approx(
        _numbers(run.test), rel=1e-12)


def test_the_inferred_circles_fit_band_moves_g_and_the_spikes_by_under_0_1_percent(
        run, monkeypatch) -> None:
    base = _again(run, monkeypatch, "ON_CIRCLE", 0.01, nominal=False)
    for value in (0.005, 0.02):
        assert _again(run, monkeypatch, "ON_CIRCLE", value, nominal=False) == pytest.approx(
            base, rel=1e-3)


@pytest.mark.parametrize(("name", "value"), [("SPIKE_WINDOW", math.radians(30.0)),
                                             ("SPIKE_TAIL", 0.01), ("SPIKE_TAIL", 0.04)])
def test_the_spike_windows_move_the_spikes_by_under_1_percent(run, monkeypatch, name,
                                                              value) -> None:
    assert _again(run, monkeypatch, name, value) == pytest.approx(_numbers(run.test),
                                                                  rel=0.01)


def test_a_spike_window_over_45_degrees_overlaps_the_previous_reversal(run,
                                                                       monkeypatch) -> None:
    """Reversals are 90° apart: the window after one reversal and the one before the next
    overlap beyond 45°, the previous spike then hides the next from the exclusion, and the
    fit absorbs part of it as backlash (measured at 60°: 40.6 instead of 53.4 µm) — why 45° is
    the largest window, not a tuning."""
    wide = _again(run, monkeypatch, "SPIKE_WINDOW", math.radians(60.0))
    assert np.max(wide[1:]) < 0.85 * np.max(_numbers(run.test)[1:])


def test_a_longer_lead_arc_moves_g_by_under_1_percent_and_the_later_spikes_by_under_1_percent(
        run) -> None:
    """90° against 135°: G(b) within 1 % (measured 0.3 %); the first reversal of each run
    (45° into the measured revolution) still carries the lead-in transient of the
    set's least-damped servo mode (5.5 Hz, −1.2 … −1.8 1/s): within 8 % (measured 7.3 %); the
    other six spikes within 1 % (measured 0.8 %)."""
    longer = _numbers(_run(135.0).test)
    base = _numbers(run.test)
    assert longer[0] == pytest.approx(base[0], rel=0.01)
    # each run's measured revolution starts at 45°: the CCW run reverses first at 90°, the
    # CW run at 0° (index 0 of the numbers is G(b))
    first = [1 + k for k, s in enumerate(run.test.spikes)
             if (s.direction, s.angle) in (("CCW", 90.0), ("CW", 0.0))]
    assert len(first) == 2
    later = [k for k in range(1, 9) if k not in first]
    assert longer[later] == pytest.approx(base[later], rel=0.01)
    assert longer[first] == pytest.approx(base[first], rel=0.08)


def test_a_45_degree_lead_arc_is_too_short_for_this_loop(run) -> None:
    """The lead-in transient has not decayed 45° in: G(b) 31 % higher (measured 91.2 against
    69.5 µm) — the lead arc is stated beside the numbers, and 90° is the shortest this loop
    needs at this feed."""
    short = _numbers(_run(45.0).test)
    assert short[0] > 1.2 * run.test.bidirectional_circular_deviation
