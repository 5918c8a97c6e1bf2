"""A circular test at a low feed, where the path sticks and slips back at the quadrants.

At 100 mm/min on a 50-mm circle the ``xy-table``'s path turns back by ≈ 2e-4° (0.2 µm along
the path) some 27 times per run; the evaluation took only stretches whose angle never turned
back, so it found no full revolution and ``feeddrive circular --feed 100`` failed (an outside
check, 2026-12-07), though that is the test a machine-tool engineer runs to see low-speed
friction.  A run now ends only where the angle turns back by more than the reversal angle
(``circular.REVERSAL``, 1°; docs/acceptance-tests.md), the smaller turns back are counted in a
note, and the quantities do not depend on that angle between the largest stick-slip turn back
and the lead arcs (checked here from 0.01° to 10°).

The closed-form traces are built in the test: a circle with a known radial deviation
a·cos 4θ (outside the ballbar error model, so it stays in the residual: G = 2a) whose angle
dips back by a known amount at known samples.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from feeddrive.analysis import circular as C
from feeddrive.analysis.circular_run import run_circular_test
from feeddrive.cli import app
from feeddrive.io.acceptance import read_xy_trace
from feeddrive.machine import machine_from_dict

R = 0.05  # [m]
A = 5e-6  # radial deviation amplitude [m]: G = 2A
BACK = math.radians(2e-4)  # each stick-slip turn back [rad]
EVERY = 400  # samples between turns back
N = 40_000  # samples per run (0.009° apart)


def _trace(back: float = BACK, every: int = EVERY) -> tuple[np.ndarray, ...]:
    """A CCW run then a CW run of 400° each, the path at every ``every``-th sample held
    for three samples ``back`` behind where it was (stuck, then slipped back)."""
    lead = math.radians(20.0)
    ccw = np.linspace(-lead, 2 * math.pi + lead, N)
    dip = np.zeros(N)
    for k in range(every // 2, N - 3, every):
        dip[k:k + 3] = ccw[k:k + 3] - (ccw[k - 1] - back)
    theta = np.concatenate([ccw - dip, (ccw - dip)[::-1]])
    r = R + A * np.cos(4 * theta)
    t = np.arange(theta.size) * 1e-3
    return t, r * np.cos(theta), r * np.sin(theta), dip


def test_stick_slip_stays_in_its_run_and_is_counted() -> None:
    t, x, y, dip = _trace()
    test = C.circular_test(t, x, y, radius=R, centre=(0.0, 0.0))
    assert [r.direction for r in test.runs] == ["CCW", "CW"]
    for run in test.runs:
        # each run is its middle 360°, however the dips fall (the net travel)
        assert abs(run.angle[-1] - run.angle[0]) == pytest.approx(2 * math.pi, abs=2e-4)
        g = test.circular_deviation[run.direction]
        assert g == pytest.approx(2 * A, rel=1e-3)  # the closed form's 2a
    # the dips inside each run's kept samples: counted, the largest given
    inside = sum(1 for k in range(EVERY // 2, N - 3, EVERY)
                 if test.runs[0].time[0] < k * 1e-3 <= test.runs[0].time[-1])
    note = next(n for n in test.notes if n.startswith("CCW: the path turned back"))
    assert f"turned back {inside} times" in note
    largest = float(re.search(r"by at most ([0-9.e-]+)°", note).group(1))
    assert largest == pytest.approx(math.degrees(BACK), rel=1e-2)
    # the feed is the net travel over the time: a dip is travelled twice but advances nothing
    assert test.feed == pytest.approx(R * (2 * math.pi + math.radians(40)) / (N - 1) / 1e-3,
                                      rel=1e-3)


def test_a_record_that_may_never_turn_back_has_no_run() -> None:
    """The old rule (a run ends at any turn back) is the reversal angle made tiny: no run."""
    t, x, y, _ = _trace()
    with pytest.raises(ValueError, match="no full revolution"):
        C.circular_test(t, x, y, radius=R, centre=(0.0, 0.0), reversal=BACK / 2)


@pytest.mark.parametrize("degrees", [0.01, 1.0, 10.0])
def test_quantities_do_not_depend_on_the_reversal_angle(degrees: float) -> None:
    t, x, y, _ = _trace()
    base = C.circular_test(t, x, y, radius=R, centre=(0.0, 0.0))
    other = C.circular_test(t, x, y, radius=R, centre=(0.0, 0.0),
                            reversal=math.radians(degrees))
    assert other.to_dict() | {"notes": []} == base.to_dict() | {"notes": []}


def test_a_turn_back_beyond_the_reversal_angle_ends_a_run() -> None:
    """200° CCW, 2° back, 200° CCW: two stretches with the default 1° (no full revolution),
    one run of 398° net with a 5° reversal angle."""
    a = np.concatenate([np.linspace(0, math.radians(200), 5000),
                        np.linspace(math.radians(200), math.radians(198), 50),
                        np.linspace(math.radians(198), math.radians(398), 5000)])
    t = np.arange(a.size) * 1e-3
    with pytest.raises(ValueError, match="no full revolution"):
        C.circular_test(t, R * np.cos(a), R * np.sin(a), radius=R, centre=(0.0, 0.0))
    test = C.circular_test(t, R * np.cos(a), R * np.sin(a), radius=R, centre=(0.0, 0.0),
                           reversal=math.radians(5.0))
    assert [r.direction for r in test.runs] == ["CCW"]


@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan, 2 * math.pi, 1e300])
def test_a_bad_reversal_angle_is_refused(bad: float) -> None:
    t, x, y, _ = _trace()
    with pytest.raises(C.ParameterError, match="reversal"):
        C.circular_test(t, x, y, radius=R, centre=(0.0, 0.0), reversal=bad)


# ---- the simulated machine at 100 mm/min ------------------------------------------------

XY = machine_from_dict({"extends": "xy-table"})
FEED = 100.0 / 60e3  # 100 mm/min [m/s]


@pytest.fixture(scope="module")
def slow() -> object:
    return run_circular_test(XY, radius=R, feed=FEED, acceleration=1.0)


def test_the_xy_table_at_100_mm_per_min_is_evaluated(slow: object) -> None:
    test = slow.test  # type: ignore[attr-defined]
    assert [r.direction for r in test.runs] == ["CCW", "CW"]
    notes = [n for n in test.notes if "turned back" in n]
    assert len(notes) == 2  # both runs stick and slip back
    for note in notes:
        count = int(re.search(r"turned back (\d+) times", note).group(1))
        largest = float(re.search(r"by at most ([0-9.e-]+)°", note).group(1))
        assert count > 0
        assert largest < 0.01  # far below the 1° that ends a run
    # the stick-slip shows as reversal spikes far above the servo's lag (tens of µm)
    assert max(abs(s.height) for s in test.spikes) > 10e-6
    # with turns back disallowed, the old failure
    with pytest.raises(ValueError, match="no full revolution"):
        C.circular_test(slow.time, slow.x, slow.y, radius=R,  # type: ignore[attr-defined]
                        centre=slow.centre, reversal=math.radians(1e-5))  # type: ignore


@pytest.mark.parametrize("degrees", [0.01, 10.0])
def test_the_slow_runs_numbers_do_not_depend_on_the_reversal_angle(slow: object,
                                                                   degrees: float) -> None:
    s = slow  # type: ignore[assignment]
    other = C.circular_test(s.time, s.x, s.y, radius=R,  # type: ignore[attr-defined]
                            centre=s.centre,  # type: ignore[attr-defined]
                            reversal=math.radians(degrees))
    assert other.to_dict() | {"notes": []} == s.test.to_dict() | {  # type: ignore
        "notes": []}


def test_cli_keeps_the_trace_when_it_cannot_be_evaluated(tmp_path: Path) -> None:
    """The runs are finished work: ``--output`` writes their trace even when the reversal
    angle leaves no full revolution (the trace was lost before)."""
    out = tmp_path / "trace.csv"
    res = CliRunner().invoke(app, ["circular", "--feed", "100", "--reversal-angle", "1e-5",
                                   "--output", str(out)])
    assert res.exit_code == 1, res.output
    assert "did not turn 360°" in res.output
    assert "--reversal-angle" in res.output or "reversal angle" in res.output
    trace = read_xy_trace(str(out))  # as analyze --circular reads it
    assert trace.time.size > 1000
    assert trace.time[-1] > 2 * (2 * math.pi * R / FEED)  # both runs, whole


@pytest.mark.parametrize("bad", ["0", "-1", "360", "nan"])
def test_cli_refuses_a_bad_reversal_angle(bad: str) -> None:
    for argv in (["circular", "--reversal-angle", bad],
                 ["analyze", "--circular", "missing.csv", "--reversal-angle", bad]):
        res = CliRunner().invoke(app, argv)
        assert res.exit_code != 0
        assert "--reversal-angle" in res.output and "[°]" in res.output, res.output


# ---- reversal spikes that do not stand out (the audit's finding, 2026-12-07) --------------

def _circle_with(delta: object) -> C.CircularTest:
    """A CCW and a CW run of 400° whose radial deviation is ``delta(theta, sign)`` [m]."""
    lead = math.radians(20.0)
    a = np.linspace(-lead, 2 * math.pi + lead, 20_000)
    theta = np.concatenate([a, a[::-1]])
    sign = np.concatenate([np.ones(a.size), -np.ones(a.size)])
    r = R + delta(theta, sign)  # type: ignore[operator]
    t = np.arange(theta.size) * 1e-3
    return C.circular_test(t, r * np.cos(theta), r * np.sin(theta), radius=R,
                           centre=(0.0, 0.0))


def _after_reversal(theta: np.ndarray, sign: np.ndarray) -> np.ndarray:
    """Travel past the last axis reversal (0°, 90°, 180°, 270°) in the direction of motion."""
    return np.mod(theta * sign, math.pi / 2)


def test_a_transient_after_each_reversal_stands_out() -> None:
    """h·exp(−travel/2°) after each reversal: eight spikes of h, each standing out."""
    h = 8e-6
    test = _circle_with(lambda th, sg: h * np.exp(-_after_reversal(th, sg) / math.radians(2)))
    assert len(test.spikes) == 8
    for s in test.spikes:
        assert s.stands_out
        assert s.height == pytest.approx(h, rel=0.05)
    assert not any("do not stand out" in n for n in test.notes)


def test_an_oscillation_between_reversals_is_not_passed_off_as_spikes() -> None:
    """A sustained oscillation, 37 periods per revolution, of 10 µm: every "spike" is one of
    its peaks, said in a note and beside each spike, none flagged as standing out."""
    test = _circle_with(lambda th, sg: 10e-6 * np.sin(37 * th))
    assert not any(s.stands_out for s in test.spikes)
    note = next(n for n in test.notes if "do not stand out" in n)
    assert note.startswith("8 of 8 reversal spikes")
    text = "\n".join(C.describe(test))
    assert text.count("does not stand out") == 8
    assert all(d["stands_out"] is False for d in test.to_dict()["reversal_spikes"])


def test_the_slow_runs_spikes_are_said_not_to_stand_out(slow: object) -> None:
    """At 100 mm/min the path oscillates between the reversals as much as after them."""
    test = slow.test  # type: ignore[attr-defined]
    assert not any(s.stands_out for s in test.spikes)
    assert any("do not stand out" in n for n in test.notes)


# ---- what the commands say (the audit's findings, 2026-12-07) ------------------------------

def test_too_small_a_reversal_angle_is_named_as_the_cause(tmp_path: Path) -> None:
    """`analyze --circular` blamed --centre and the columns when the reversal angle was below
    the stick-slip turns back."""
    t, x, y, _ = _trace()
    with pytest.raises(ValueError, match="reversal angle") as err:
        C.circular_test(t, x, y, radius=R, centre=(0.0, 0.0), reversal=BACK / 2)
    assert "--centre" not in str(err.value)
    back = float(re.search(r"up to ([0-9.e-]+)°", str(err.value)).group(1))
    assert back == pytest.approx(math.degrees(BACK), rel=1e-2)


def test_the_printed_analyze_command_keeps_every_digit_of_the_radius(tmp_path: Path) -> None:
    out = tmp_path / "odd.csv"
    res = CliRunner().invoke(app, ["circular", "--radius", "12.3456789", "--feed", "2000",
                                   "--output", str(out)])
    assert res.exit_code == 0, res.output
    hint = re.search(r"\(feeddrive (analyze --circular .*)\)", res.output).group(1)
    assert "--radius 12.3456789 " in hint
    circ = next(line for line in res.output.splitlines() if "circular deviation G(CCW)" in line)
    again = CliRunner().invoke(app, hint.split())
    assert again.exit_code == 0, again.output
    assert circ in again.output  # the same G(CCW), every printed digit


def test_a_feed_too_low_for_the_reference_table_names_the_feed() -> None:
    res = CliRunner().invoke(app, ["circular", "--feed", "20", "--radius", "25",
                                   "--lead-arc", "30"])
    assert res.exit_code == 2
    assert "--feed = 20.0" in res.output and "mm/min" in res.output
    assert "contour.duration" not in res.output


def test_a_given_lead_arc_is_not_asked_for_again() -> None:
    """With the lead arc given, the settling rule's refusal is a note without its advice to
    give one."""
    from feeddrive.analysis.circular_run import _lead_in

    lead = _lead_in(XY, ("x", "y"), 0.005, 50 / 60e3, 1.0, 0.0, math.radians(30))
    assert lead.given and lead.notes
    assert "does not decay" in lead.notes[0]
    assert "expected the lead arc given" not in lead.notes[0]


def test_the_polar_plot_labels_only_spikes_that_stand_out() -> None:
    from feeddrive.plots.acceptance import circular_figure

    h = 8e-6
    spiky = _circle_with(lambda th, sg: h * np.exp(-_after_reversal(th, sg) / math.radians(2)))
    waves = _circle_with(lambda th, sg: 10e-6 * np.sin(37 * th))
    for test, labelled in ((spiky, 8), (waves, 0)):
        ax = circular_figure(test).axes[0]
        assert sum("µm" in t.get_text() for t in ax.texts) == labelled
        assert ("8 reversal spikes not labelled" in ax.get_title()) == (labelled == 0)


def test_the_progress_bar_says_which_run_it_is_on() -> None:
    """One bar over both runs (run_circular_test's progress), labelled by the run: the first
    half of the time is the CCW run's (the runs are equally long)."""
    from feeddrive.cli._common import progress_bar

    bar, advance = progress_bar(1.0, label=lambda t, end: "CCW run" if t <= end / 2
                                else "CW run")
    task = bar.tasks[0]
    advance(10.0, 100.0)
    assert task.description == "CCW run"
    advance(60.0, 100.0)
    assert task.description == "CW run" and task.completed == 60.0
    plain, go = progress_bar(1.0)
    go(5.0, 10.0)
    assert plain.tasks[0].description == "simulating"  # no label: as before
