"""`feeddrive analyze --circular` / `--positioning` and `feeddrive positioning` (issue 37).

The CLI prints what the API computes: the same numbers from the file as from the arrays
written to it, refusals in one line with exit status 2 before any work, and help texts that
name the options' units.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from feeddrive.analysis.circular import circular_test
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
