"""The linear analysis says what its numbers are (outside checks, 2026-12-07).

* The velocity loop's closed-loop bandwidth was 8.542 Hz at some table positions and 7.894 Hz
  at others: its model (position loop open, the table free) has a rigid-body pole, so its DC
  gain |T(0)| was a 0/0 left to rounding (+2.02 dB at 300 mm, a singular matrix at 400 mm).
  It is python-control's ``bandwidth`` of the same transfer, the cancelling pole and zero at 0
  removed, at every position.
* ``stability --high 1.0`` printed ``unstable from 0.172 to 1.000 mm/s`` with no note: the
  scan's end presented as the band's edge (the edge is 1.399 mm/s).
* The band's mode frequency was taken at √(lower·upper), said nowhere; it runs 5.38–5.48 Hz
  over the band.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.analysis import linear
from feeddrive.analysis.linear import linearize, loop_analysis, rightmost_pole, stability_band
from feeddrive.cli import app

PARAMS = fd.preset("wang2021")
CDFS = fd.DriveSystem(PARAMS, "cdfs", 0.4)


def _control_bandwidth_hz(position: float) -> float:
    """python-control's ``bandwidth`` of the CDFS velocity loop's T = 1 − S at ``position``
    [m] (position loop open), its cancelling pole and zero at s = 0 removed (``minreal``): the
    raw state space has a singular A, whose DC gain python-control reads as infinite or, at
    300 mm, as the same rounding (+2.02 dB) the loop analysis read."""
    import control as ct

    system = fd.DriveSystem(PARAMS, "cdfs", position)
    open_position = replace(system, parameters=system.parameters.replace_path(
        "controller.position_gain", 0.0))
    lin = linearize(open_position, 1e-3, 0.0, frictionless=True)
    i = lin.inputs.index("screw_current_command_disturbance")
    o = lin.outputs.index("screw_current_command")
    T = ct.ss(lin.A, lin.B[:, [i]], -lin.C[[o]], np.array([[1.0 - lin.D[o, i]]]))
    T = ct.minreal(ct.ss2tf(T), tol=1e-6, verbose=False)
    assert abs(T.dcgain()) == pytest.approx(1.0, abs=1e-6)  # the integrator's |T(0)| = 1
    return float(ct.bandwidth(T)) / (2 * np.pi)


@pytest.mark.parametrize("position", [0.3, 0.39, 0.4])
def test_velocity_loop_bandwidth_is_python_controls_at_every_position(position: float) -> None:
    """300 and 390 mm read 7.894 Hz, 400 mm 8.542 Hz; python-control gives 8.542 at all."""
    system = fd.DriveSystem(PARAMS, "cdfs", position)
    velocity = {lp.name: lp for lp in loop_analysis(system, 1e-3).loops}["screw velocity loop"]
    assert velocity.bandwidth_hz == pytest.approx(_control_bandwidth_hz(position), rel=1e-6)
    assert velocity.bandwidth_hz == pytest.approx(8.5423, abs=1e-3)


@pytest.mark.parametrize("fraction", [1e-4, 1e-8])
def test_velocity_loop_bandwidth_does_not_move_with_where_dc_is_read(
        monkeypatch: pytest.MonkeyPatch, fraction: float) -> None:
    """The DC gain with a rigid-body pole is the limit f → 0, read at DC_LIMIT_FRACTION of the
    slowest other pole: 100 times either way the bandwidth is the same to 1e-6 Hz (printed:
    0.01 Hz; the level moves by ~fraction², 9e-8 dB at 1e-4)."""
    system = fd.DriveSystem(PARAMS, "cdfs", 0.3)
    base = loop_analysis(system, 1e-3).loops[1].bandwidth_hz
    monkeypatch.setattr(linear, "DC_LIMIT_FRACTION", fraction)
    moved = loop_analysis(system, 1e-3).loops[1].bandwidth_hz
    assert base is not None and moved == pytest.approx(base, abs=1e-6)
    assert base == pytest.approx(8.5423, abs=1e-3)


def test_position_loop_bandwidth_unchanged_without_a_rigid_body_pole() -> None:
    """The position loop's model has no rigid-body pole: its DC gain is still read at f = 0,
    and its bandwidth is python-control's on the raw state space."""
    import control as ct

    result = loop_analysis(fd.DriveSystem(PARAMS, "cdfs", 0.3), 1e-3)
    assert linear._dc_frequency(result.linear) == 0.0
    lin = result.linear
    i = lin.inputs.index("screw_speed_command_disturbance")
    o = lin.outputs.index("screw_speed_command")
    T = ct.ss(lin.A, lin.B[:, [i]], -lin.C[[o]], np.array([[1.0 - lin.D[o, i]]]))
    assert result.loops[0].bandwidth_hz == pytest.approx(float(ct.bandwidth(T)) / (2 * np.pi),
                                                         rel=1e-6)


# ---------------------------------------------------------------- the band at the scan's ends


@pytest.mark.parametrize(("low", "high", "ends", "said"), [
    (1e-5, 1e-3, (False, True), r"steady sliding is unstable at the scan's highest speed, "
                                r"1 mm/s: the band's upper edge is above it, not found"),
    (0.2e-3, 5e-3, (True, False), r"steady sliding is unstable at the scan's lowest speed, "
                                  r"0.2 mm/s: the band's lower edge is below it, not found"),
])
def test_a_band_cut_by_the_scan_says_its_edge_is_the_scans_end(
        low: float, high: float, ends: tuple[bool, bool], said: str) -> None:
    """--high 1.0 gave 0.172–1.000 mm/s and notes [] (the edge is 1.399 mm/s)."""
    band = stability_band(CDFS, low=low, high=high, points=12)
    assert band.edges_at_scan_ends == [ends]
    assert any(re_match(said, note) for note in band.notes), band.notes
    d = band.as_dict()
    assert d["unstable_band_edges_at_scan_ends"] == [list(ends)]
    assert d["notes"] == list(band.notes)
    text = repr(band)
    assert ("≥1.000" in text.replace(" ", "")) == ends[1]
    assert ("≤0.200" in text.replace(" ", "")) == ends[0]


def re_match(pattern: str, text: str) -> bool:
    import re

    return re.match(pattern, text) is not None


def test_a_band_inside_the_scan_has_found_edges_and_no_note() -> None:
    band = stability_band(CDFS, points=12)
    assert band.edges_at_scan_ends == [(False, False)]
    assert band.as_dict()["unstable_band_edges_at_scan_ends"] == [[False, False]]
    assert not band.notes


def test_stability_text_marks_the_scans_end() -> None:
    runner = CliRunner()
    res = runner.invoke(app, ["stability", "--high", "1.0", "--points", "12"])
    assert res.exit_code == 0, res.output
    out = " ".join(res.stdout.split())
    assert "unstable from 0.172 to ≥ 1.000 mm/s" in out
    assert "the band's upper edge is above it, not found (scan higher)" in out
    res = runner.invoke(app, ["stability", "--low", "0.2", "--points", "12", "--json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert data["unstable_band_edges_at_scan_ends"] == [[True, False]]
    assert data["unstable_bands_mm_s"][0][0] == pytest.approx(0.2)


# ---------------------------------------------------------------- the mode's frequency


def test_the_mode_frequency_says_where_it_is_taken_and_its_range_over_the_band() -> None:
    """Taken at √(lower·upper) (5.45 Hz at 0.49 mm/s), the rightmost pole's frequency runs
    5.375 Hz at the lower edge to 5.482 near 0.8 mm/s: the range is given, and a fine scan of
    the band finds the same to 0.005 Hz (what is printed)."""
    band = stability_band(CDFS, points=20)
    (lo, hi), = band.intervals
    (speed,) = band.mode_speed
    assert speed == pytest.approx(math.sqrt(lo * hi), rel=1e-12)
    assert band.mode_frequency_hz[0] == rightmost_pole(CDFS, speed)[1]
    d = band.as_dict()
    assert d["unstable_mode_speed_mm_s"] == [pytest.approx(1e3 * speed)]
    (f_lo, f_hi), = band.mode_frequency_range_hz
    assert d["unstable_mode_frequency_range_hz"] == [[f_lo, f_hi]]
    fine = [rightmost_pole(CDFS, float(v))[1]
            for v in np.geomspace(lo + band.tolerance, hi - band.tolerance, 25)]
    assert f_lo == pytest.approx(min(fine), abs=0.005)
    assert f_hi == pytest.approx(max(fine), abs=0.005)
    assert f_lo < band.mode_frequency_hz[0] < f_hi


@pytest.mark.parametrize(("low", "high", "points"), [(0.1e-3, 2e-3, 15), (1e-5, 5e-3, 40)])
def test_the_mode_frequency_and_its_range_do_not_move_with_the_scan(
        low: float, high: float, points: int) -> None:
    """The same band from another range or grid: the same frequency, speed and range, to
    what is printed (0.01 Hz, 0.01 mm/s)."""
    ref = stability_band(CDFS, points=20)
    band = stability_band(CDFS, low=low, high=high, points=points)
    assert band.mode_frequency_hz[0] == pytest.approx(ref.mode_frequency_hz[0], abs=0.005)
    assert band.mode_speed[0] == pytest.approx(ref.mode_speed[0], abs=5e-6)
    for a, b in zip(band.mode_frequency_range_hz[0], ref.mode_frequency_range_hz[0],
                    strict=True):
        assert a == pytest.approx(b, abs=0.005)


def test_stability_text_says_where_the_mode_is_taken() -> None:
    res = CliRunner().invoke(app, ["stability", "--points", "20"])
    assert res.exit_code == 0, res.output
    out = " ".join(res.stdout.split())
    assert ("unstable from 0.172 to 1.399 mm/s (mode 5.45 Hz at 0.49 mm/s, the geometric "
            "middle of the band; 5.38–5.48 Hz at the speeds evaluated in it)") in out
