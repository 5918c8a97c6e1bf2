"""The circular test's numbers against its stated choices (issue 37 item 4): "a number a user
reads must not depend on an arbitrary choice unless the choice is stated beside it and a test
shows the number is stable to it".  The choices (docs/acceptance-tests.md): samples beyond
10 % of R are no part of the test (``OFF_CIRCLE``), an inferred circle is fitted to the
samples within 1 % of R (``ON_CIRCLE``), the spike is searched within 45° after a reversal
against the 45° before it (``SPIKE_WINDOW``), its region is left out of the fit to 2 % of its
peak (``SPIKE_TAIL``), and each run's lead-in and lead-out arc is the settling rule's
(``circular_run.settling_lead``: the feed ramp, then until the slowest closed-loop mode has
decayed to ``SETTLE_FRACTION``, 0.1 %).

The trace is the comparison's circle (``feeddrive compensate --compare``): an XY table of two
``wang2021-drive`` CDFS axes, R = 5 mm, F = 5 mm/s, 0.5 m/s² ramps; its reversal spikes are
about 50 µm, 1 % of R (measured: G(b) 69.67 µm, spikes 53.1–53.7 µm)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from feeddrive.analysis import circular as C
from feeddrive.analysis import compensation_compare as cc
from feeddrive.analysis.circular_run import (
    SETTLE_FRACTION,
    CircularRunTrace,
    run_circular_test,
    settling_lead,
)
from feeddrive.machine import Machine, MachineAxis, load_machine
from feeddrive.parameters import preset

DOC = " ".join((Path(__file__).resolve().parents[2] / "docs" / "acceptance-tests.md")
               .read_text(encoding="utf-8").split())
DRIVE = preset("wang2021-drive")
XY = Machine(name="xy", axes=(MachineAxis("x", DRIVE, "cdfs", 0.4),
                              MachineAxis("y", DRIVE, "cdfs", 0.4)))


def _run(lead_deg: float | None) -> CircularRunTrace:
    return run_circular_test(XY, radius=cc.CIRCLE_RADIUS, feed=cc.CIRCLE_FEED,
                             acceleration=cc.CIRCLE_ACCELERATION,
                             lead_arc=None if lead_deg is None else math.radians(lead_deg))


@pytest.fixture(scope="module")
def run() -> CircularRunTrace:
    return _run(None)  # the settling rule's lead arc


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
    fit absorbs part of it as backlash (measured at 60°: 41.0 instead of 53.7 µm) — why 45° is
    the largest window, not a tuning."""
    wide = _again(run, monkeypatch, "SPIKE_WINDOW", math.radians(60.0))
    assert np.max(wide[1:]) < 0.85 * np.max(_numbers(run.test)[1:])


def test_doubling_the_rules_lead_arc_moves_g_and_the_spikes_by_under_1_percent(run) -> None:
    """The settling rule's lead arc (221.6° here: the slowest mode, 5.44 Hz at 1.79 1/s, down
    to 0.1 %) against twice it: G(b) within 0.5 % (measured 0.05 %), the eight spikes within
    1.5 % (measured 0.8 %, the first reversal of each run)."""
    lead = run.lead_in
    assert lead is not None and not lead.given
    longer = _numbers(run_circular_test(XY, radius=cc.CIRCLE_RADIUS, feed=cc.CIRCLE_FEED,
                                        acceleration=cc.CIRCLE_ACCELERATION,
                                        lead_arc=2.0 * lead.arc).test)
    base = _numbers(run.test)
    assert longer[0] == pytest.approx(base[0], rel=0.005)
    assert longer[1:] == pytest.approx(base[1:], rel=0.015)
    # the docs quote this run's figures
    row = (f"| the comparison's, R = 5 mm, F = 5 mm/s | {math.degrees(lead.arc):.1f}° | "
           f"{base[0] * 1e6:.2f} µm | {longer[0] * 1e6:.2f} µm")
    assert row in DOC, row


def test_a_45_degree_lead_arc_is_too_short_for_this_loop(run) -> None:
    """The lead-in transient has not decayed 45° in: G(b) over 20 % higher (measured 91.2
    against 69.7 µm) — why the lead arc follows the loop's slowest mode, not a fixed angle."""
    short = _numbers(_run(45.0).test)
    assert short[0] > 1.2 * run.test.bidirectional_circular_deviation


def test_the_rule_makes_the_xy_tables_g_stable_to_doubling_the_lead() -> None:
    """The docs' example (`feeddrive circular --radius 50 --feed 5000`, the xy-table): the
    rule's 372.9° gives G(b) 104.78 µm and twice it 104.79 µm (within 0.5 %; the spikes
    within 1 %); a fixed 90° lead arc gave 522 µm, mostly the start transient."""
    xy = load_machine("xy-table")
    feed = 5000.0 / 6e4
    lead = settling_lead(xy, ("x", "y"), radius=0.05, feed=feed, acceleration=1.0)
    assert math.degrees(lead.arc) == pytest.approx(372.9, abs=0.05)
    runs = [run_circular_test(xy, radius=0.05, feed=feed, lead_arc=k * lead.arc)
            for k in (1.0, 2.0)]
    base, longer = (_numbers(r.test) for r in runs)
    # the docs' note on G(b) below a run's G (each run's span about its own least-squares
    # circle): its figure is this run's (the note said 0.0003–0.007 µm, measured elsewhere;
    # an outside check, 2026-12-07, found 0.65 µm here)
    t = runs[0].test
    ccw = t.circular_deviation["CCW"]
    assert t.bidirectional_circular_deviation is not None
    below = ccw - t.bidirectional_circular_deviation
    assert below > 0
    note = (f"by {below * 1e6:.2f} µm on the `xy-table` at R = 50 mm, F = 5000 mm/min "
            f"(G(CCW) {ccw * 1e6:.2f} µm, G(b) {t.bidirectional_circular_deviation * 1e6:.2f}")
    assert note in " ".join(DOC.split()), note
    assert longer[0] == pytest.approx(base[0], rel=0.005)
    assert longer[1:] == pytest.approx(base[1:], rel=0.01)
    row = (f"| `xy-table`, R = 50 mm, F = 5000 mm/min | {math.degrees(lead.arc):.1f}° | "
           f"{base[0] * 1e6:.1f} µm | {longer[0] * 1e6:.1f} µm")
    assert row in DOC, row
    assert f"{SETTLE_FRACTION * 100:g} % of its start (`SETTLE_FRACTION`)" in DOC
    assert f"σ = {lead.decay_rate:.2f} 1/s ({lead.frequency:.2f} Hz)" in DOC
    assert base[0] < 0.3 * _numbers(run_circular_test(xy, radius=0.05, feed=feed,
                                                      lead_arc=math.radians(90.0)).test)[0]


def test_the_rule_rests_on_the_rightmost_pole() -> None:
    """The arc is (F²/2a + F·ln(1/ε)/σ)/R with σ the decay rate of the axes' rightmost pole
    at the feed (feeddrive.analysis.linear.rightmost_pole)."""
    from feeddrive.analysis.linear import rightmost_pole
    from feeddrive.engine.simulate import DriveSystem

    xy = load_machine("xy-table")
    feed = 5000.0 / 6e4
    ax = xy.axis("x")
    real, frequency = rightmost_pole(DriveSystem(ax.parameters, ax.drive, ax.table_position),
                                     feed)
    lead = settling_lead(xy, ("x", "y"), radius=0.05, feed=feed, acceleration=1.0)
    assert lead.decay_rate == pytest.approx(-real) and lead.frequency == pytest.approx(frequency)
    want = (feed ** 2 / 2.0 + feed * math.log(1.0 / SETTLE_FRACTION) / -real) / 0.05
    assert lead.arc == pytest.approx(want, rel=1e-12)
