"""`feeddrive analyze --circular` / `--positioning` and `feeddrive positioning` (issue 37).

The CLI prints what the API computes: the same numbers from the file as from the arrays
written to it, refusals in one line with exit status 2 before any work, and help texts that
name the options' units.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from feeddrive.analysis.circular import circular_test
from feeddrive.analysis.circular_run import SETTLE_FRACTION
from feeddrive.cli import app

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "unit"))
from test_circular import CENTRE, R, trace  # noqa: E402

runner = CliRunner()


def invoke(*args: str):  # type: ignore[no-untyped-def]
    return runner.invoke(app, list(args), env={"COLUMNS": "200"})


@pytest.fixture()
def circle_csv(tmp_path: Path) -> tuple[Path, tuple[np.ndarray, ...]]:
    t, x, y = trace(squareness=10e-6, spike=5e-6, scale=(3e-6 / R, 0.0))
    path = tmp_path / "circle.csv"
    np.savetxt(path, np.column_stack([t, x * 1e3, y * 1e3]), delimiter=",",
               header="time [s],x [mm],y [mm]", comments="", fmt="%.17g")
    return path, (t, x, y)


def test_analyze_circular_gives_the_api_numbers(circle_csv, tmp_path: Path) -> None:
    path, (t, x, y) = circle_csv
    plot = tmp_path / "polar.png"
    r = invoke("analyze", "--circular", str(path), "--radius", f"{R * 1e3:g}", "--centre",
               f"{CENTRE[0] * 1e3:g},{CENTRE[1] * 1e3:g}", "--json", "--plot", str(plot))
    assert r.exit_code == 0, r.output
    got = json.loads(r.stdout)
    want = circular_test(t, x, y, radius=R, centre=CENTRE).to_dict()
    for key in ("squareness_um_per_m", "scale_mismatch_um", "servo_mismatch_ms",
                "bidirectional_circular_deviation_um", "mean_radius_deviation_um",
                "radial_deviation_max_um"):
        assert got[key] == pytest.approx(want[key], abs=1e-9), key
    assert got["squareness_um_per_m"] == pytest.approx(10.0, abs=0.1)
    assert [s["height_um"] for s in got["reversal_spikes"]] == pytest.approx(
        [s["height_um"] for s in want["reversal_spikes"]], abs=1e-9)
    assert plot.stat().st_size > 0


def test_analyze_circular_text_states_what_it_inferred(circle_csv) -> None:
    path, _ = circle_csv
    r = invoke("analyze", "--circular", str(path))
    assert r.exit_code == 0, r.output
    assert "centre (" in r.stdout and "inferred: the least-squares centre" in r.stdout
    assert "radius" in r.stdout and "inferred" in r.stdout
    assert "runs CCW, CW, feed 1000" in r.stdout  # mm/min, along the inferred radius
    for label in ("G(CCW)", "G(CW)", "G(b)", "mean radius deviation", "radial deviation F",
                  "squareness", "scale mismatch", "servo mismatch", "backlash X",
                  "lateral play X", "reversal spike CCW at 0°"):
        assert label in r.stdout, label


def test_analyze_circular_refuses_a_record_without_x_y(tmp_path: Path) -> None:
    path = tmp_path / "trace.csv"
    path.write_text("time,position\n" + "".join(f"{k},{k}\n" for k in range(20)))
    r = invoke("analyze", "--circular", str(path))
    assert r.exit_code == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "no x column" in lines[0] and "trace.csv, line 1" in lines[0]


def test_analyze_circular_refuses_bad_options(circle_csv) -> None:
    path, _ = circle_csv
    for args, word in ((("--radius", "-1"), "--radius"), (("--centre", "1;2"), "--centre"),
                       (("--pitch", "0"), "--pitch"), (("--radius", "500"), "radius")):
        r = invoke("analyze", "--circular", str(path), *args)
        assert r.exit_code == 2, args
        assert len(r.stderr.strip().splitlines()) == 1 and word in r.stderr, r.stderr


def test_analyze_help_names_the_acceptance_options_with_units() -> None:
    shown = " ".join(invoke("analyze", "--help").stdout.split())
    for text in ("--circular", "--positioning", "nominal radius [mm]", "nominal centre X,Y [mm]",
                 "the screw's lead [mm]", "deviation magnification [-]"):
        assert text in shown, text


FRICTIONLESS = """extends = "wang2021"
[friction.screw]
law = "none"
[friction.nut]
law = "none"
[friction.guide]
law = "none"
"""


def test_positioning_output_analysed_gives_the_same_metrics(tmp_path: Path) -> None:
    params = tmp_path / "frictionless.toml"
    params.write_text(FRICTIONLESS)
    record, chart = tmp_path / "record.csv", tmp_path / "chart.png"
    r = invoke("positioning", "--params", str(params), "--count", "3", "--span", "100,120",
               "--dwell", "0.5", "--overshoot", "1", "--output", str(record), "--plot",
               str(chart), "--json")
    assert r.exit_code == 0, r.output
    run = json.loads(r.stdout)
    assert [t["target_mm"] for t in run["targets"]] == pytest.approx([100, 110, 120])
    assert 0.0 <= run["reading_motion_um"] < 1e3  # how far from rest the readings were
    a = invoke("analyze", "--positioning", str(record), "--json")
    assert a.exit_code == 0, a.output
    again = json.loads(a.stdout)
    assert set(run["axis"]) == set(again["axis"]) and len(run["axis"]) == 12
    for key, value in run["axis"].items():
        assert again["axis"][key] == pytest.approx(value, abs=1e-9), key  # µm
    for mine, theirs in zip(run["targets"], again["targets"], strict=True):
        for key, value in mine.items():
            assert theirs[key] == pytest.approx(value, abs=1e-9), key
    assert chart.stat().st_size > 0
    text = invoke("analyze", "--positioning", str(record)).stdout
    for symbol in ("A ", "A↑", "A↓", "R ", "R↑", "R↓", "B ", "B̄", "E ", "E↑", "E↓", "M "):
        assert f"  {symbol}" in text, symbol


@pytest.mark.parametrize(("args", "words"), [
    (("--targets", "100,110", "--cycles", "4"), "--cycles = 4: expected at least 5"),
    (("--targets", "100,900"), "--targets = '100,900': the test reaches 98 … 902 mm"),
    (("--targets", "100,110", "--feed", "2000", "--params", "SLOW"), "speed limit"),
    (("--count", "1", "--span", "1,2"), "--count = 1"),
    (("--targets", "100,110", "--cycle", "zigzag"), "--cycle = 'zigzag'"),
])
def test_positioning_refuses_bad_requests_in_one_line(tmp_path: Path, monkeypatch,
                                                      args: tuple[str, ...], words: str) -> None:
    import feeddrive.engine.simulate as engine

    def no_run(*a: object, **k: object) -> None:
        raise AssertionError("simulated a refused request")

    monkeypatch.setattr(engine, "simulate", no_run)
    slow = tmp_path / "slow.toml"
    slow.write_text('extends = "wang2021"\n[controller]\nvoltage_limit = 300.0\n')
    r = invoke("positioning", *[str(slow) if a == "SLOW" else a for a in args])
    assert r.exit_code == 2, r.output
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], r.stderr


def test_analyze_positioning_refuses_an_unequal_record(tmp_path: Path) -> None:
    path = tmp_path / "record.csv"
    head = "target [mm],direction,cycle,position [mm]\n"
    rows = [f"{p},{d},{j},{p}" for p in (100, 110, 120) for d in (1, -1) for j in range(5)]
    path.write_text(head + "\n".join(rows[:-1]) + "\n")
    r = invoke("analyze", "--positioning", str(path))
    assert r.exit_code == 2
    assert "approached 4 times in the negative direction" in r.stderr
    rows = [f"{p},{d},{j},{p}" for p in (100, 110, 120) for d in (1, -1) for j in range(4)]
    path.write_text(head + "\n".join(rows) + "\n")
    r = invoke("analyze", "--positioning", str(path))
    assert r.exit_code == 2 and "cycles = 4: expected at least 5" in r.stderr, r.stderr


def test_positioning_help_names_units_and_the_standard() -> None:
    shown = " ".join(invoke("positioning", "--help").stdout.split())
    for text in ("Target positions on the axis [mm]", "ISO 230-2: at least 5",
                 "Speed of the moves [mm/s]", "[mm/s²]", "Rest at each stop [s]",
                 "axis reverses [mm]", "linear (the standard cycle) or pilgrim",
                 "analyze --positioning reads it"):
        assert text in shown, text


@pytest.mark.parametrize(("args", "words"), [
    (("--circular", "{csv}", "--smoothing", "5"),
     "--smoothing = 5.0: applies to the creep analysis, not to --circular"),
    (("{csv}", "--radius", "50"), "--radius = 50.0: applies to --circular, not to the creep"),
    (("--positioning", "{csv}", "--time-unit", "ms"),
     "--time-unit = 'ms': applies to the creep analysis or --circular, not to --positioning"),
    (("--circular", "--positioning", "{csv}"), "expected one of --circular, --positioning"),
])
def test_analyze_refuses_an_option_of_another_analysis(circle_csv, args: tuple[str, ...],
                                                       words: str) -> None:
    path, _ = circle_csv
    r = invoke("analyze", *[str(path) if a == "{csv}" else a for a in args])
    assert r.exit_code == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], r.stderr


def test_circular_output_analysed_gives_the_same_metrics(tmp_path: Path) -> None:
    """Issue 37 acceptance: `feeddrive circular --output` read back by `analyze --circular`
    gives the command's numbers to 1e-9 (µm, µm/m, ms)."""
    trace_file, polar = tmp_path / "circle.csv", tmp_path / "polar.png"
    r = invoke("circular", "--radius", "50", "--feed", "5000", "--output", str(trace_file),
               "--plot", str(polar), "--json")
    assert r.exit_code == 0, r.output
    run = json.loads(r.stdout)
    assert run["runs"] == ["CCW", "CW"] and run["axes"] == ["x", "y"]
    assert run["centre_mm"] == [400.0, 400.0]  # the xy-table's axes start at 0.4 m
    a = invoke("analyze", "--circular", str(trace_file), "--radius", "50", "--centre",
               "400,400", "--json")
    assert a.exit_code == 0, a.output
    again = json.loads(a.stdout)
    for key in ("bidirectional_circular_deviation_um", "mean_radius_deviation_um",
                "radial_deviation_max_um", "radial_deviation_min_um", "squareness_um_per_m",
                "scale_mismatch_um", "servo_mismatch_ms", "residual_rms_um", "feed_mm_min"):
        assert again[key] == pytest.approx(run[key], abs=1e-9), key
    for key in ("circular_deviation_um", "radius_deviation_um", "backlash_um",
                "lateral_play_um"):
        assert set(again[key]) == set(run[key]), key
        for name, value in run[key].items():
            assert again[key][name] == pytest.approx(value, abs=1e-9), (key, name)
    assert len(run["reversal_spikes"]) == 8
    for mine, theirs in zip(run["reversal_spikes"], again["reversal_spikes"], strict=True):
        assert theirs["height_um"] == pytest.approx(mine["height_um"], abs=1e-9)
    assert polar.stat().st_size > 0
    assert trace_file.read_text().splitlines()[1] == (
        "# nominal circle: --radius 50.0 --centre 400.0,400.0")
    # the lead arc is the settling rule's, stated beside the numbers
    from feeddrive.analysis.circular_run import settling_lead
    from feeddrive.machine import load_machine

    rule = settling_lead(load_machine("xy-table"), ("x", "y"), radius=0.05, feed=5000 / 6e4,
                         acceleration=1.0)
    assert run["lead_in"]["given"] is False
    # (the CLI's feed 5000·1e-3/60 m/s differs from 5000/6e4 in the last bit; the
    # linearisation's differences carry that to ~1e-9)
    assert run["lead_in"]["lead_arc_deg"] == pytest.approx(math.degrees(rule.arc), rel=1e-6)
    assert run["lead_in"]["rule_lead_arc_deg"] == run["lead_in"]["lead_arc_deg"]
    assert rule.describe() in trace_file.read_text().splitlines()[0]


def test_circular_states_a_given_lead_arc_beside_the_rules() -> None:
    """`--lead-arc` overrides the settling rule; the summary says so and names the rule's
    arc (issue 37: a number must not depend on an unstated choice)."""
    r = invoke("circular", "--radius", "50", "--feed", "5000", "--lead-arc", "90")
    assert r.exit_code == 0, r.output
    line = next(x for x in r.stdout.splitlines() if "lead arcs" in x)
    assert "lead arcs 90° as given (the settling rule's 372.9°" in line, line


@pytest.mark.parametrize(("args", "words"), [
    (("--radius", "500"), "--radius = 500.0: axis x would run -100 … 900 mm about its centre "
     "400 mm; expected within its travel 0 … 800 mm (x.screw.length)"),
    (("--feed", "2e5", "--machine", "SLOW"), "--feed = 200000.0: expected ≤ 95493 mm/min, "
     "axis x's speed limit"),
    (("--axes", "x,z"), "--axes = 'z': no such axis"),
    (("--axes", "x"), "--axes = 'x': expected two different axis names"),
    (("--feed", "50000", "--acceleration", "10", "--lead-arc", "90"),
     "--lead-arc = 90.0: the feed ramp"),
    (("--lead-arc", "-5"), "--lead-arc = -5.0: expected a value > 0, ≤ 360 [°]"),
    (("--radius", "0"), "--radius = 0.0: expected a value > 0, ≤ 10000 [mm]"),
    # an outside check, 2026-12-07: a "duration", SI under contour.acceleration, taken
    (("--lead-arc", "1e300"), "--lead-arc = 1e+300: expected a value > 0, ≤ 360 [°]"),
    (("--acceleration", "1e300"), "--acceleration = 1e+300: expected a value > 0, ≤ 1e+06 "
     "[mm/s²]"),
    (("--pitch", "1e300"), "--pitch = 1e+300: expected a value > 0, ≤ 10000 [mm]"),
    (("--nut-speed", "100"), "--nut-speed = 100.0: no axis of the test drives its nut"),
])
def test_circular_refuses_bad_requests_in_one_line(tmp_path: Path, monkeypatch,
                                                   args: tuple[str, ...], words: str) -> None:
    import feeddrive.engine.simulate as engine

    def no_run(*a: object, **k: object) -> None:
        raise AssertionError("simulated a refused request")

    monkeypatch.setattr(engine, "simulate", no_run)
    slow = tmp_path / "slow.toml"  # 300 V / 0.15 V s/rad × 5 mm/2π = 1591.5 mm/s = 95493 mm/min
    slow.write_text('extends = "xy-table"\n[axes.x]\nextends = "wang2021"\n'
                    '[axes.x.controller]\nvoltage_limit = 300.0\n')
    r = invoke("circular", *[str(slow) if a == "SLOW" else a for a in args])
    assert r.exit_code == 2, r.output
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], r.stderr


def test_circular_refuses_a_loop_with_no_settling_lead_in(tmp_path: Path) -> None:
    """The settling rule needs a decaying mode (tests/unit/test_circular_run.py): refused in
    one line, exit status 2, the option to give named."""
    hunting = tmp_path / "hunting.toml"
    hunting.write_text('extends = "xy-table"\n[axes.x]\nextends = "wang2021"\n'
                       '[axes.x.controller]\nvelocity_integral_gain = 15000.0\n')
    r = invoke("circular", "--machine", str(hunting))
    assert r.exit_code == 2, r.output
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: --lead-arc: axis x's closed "
                                                   "loop at the feed 1000 mm/min"), r.stderr
    assert lines[0].endswith("does not decay; no lead-in lets it settle; expected the lead "
                             "arc given")


def test_circular_help_names_units() -> None:
    shown = " ".join(invoke("circular", "--help").stdout.split())
    for text in ("Circle radius R [mm]", "Path feed F [mm/min]", "[mm/s²]",
                 "lead-out arc of each run [°]", "the screw's lead [mm]",
                 f"has decayed to {SETTLE_FRACTION * 100:g} %",
                 "Nut speed of the DDFS axes [mm/s]",
                 "analyze --circular reads it", "ISO 230-4"):
        assert text in shown, text
