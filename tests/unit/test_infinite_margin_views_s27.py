"""Session 27, the views `feeddrive loops` left: an infinite gain margin (the loop's phase
never crosses −180°: :data:`feeddrive.units.INFINITE_WHEN_ABSENT`, None in the analysis) was

* sent by the explorer's server as a bare null, the same as a value the loop has not (no gain
  crossover), so the page could only print "—" (the page itself: tests/integration/
  test_explore_infinite_margin_s27.py);
* left out of `feeddrive loops --plot`'s Bode legend;
* printed "none (no crossing)" by the gallery's linear-analysis example.

The wang2021 CDFS screw velocity loop has no phase crossover (none up to 50 kHz:
feeddrive.sweep.quantities); its position loop's gain margin, frictionless at 1.5 mm/s, is
python-control's 2.589 dB (docs/linear.md).
"""

from __future__ import annotations

import contextlib
import io
import json
import runpy
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.analysis.linear import loop_analysis  # noqa: E402
from feeddrive.explore.compute import run_linear  # noqa: E402
from feeddrive.explore.settings import check  # noqa: E402
from feeddrive.plots.linear import _bode  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
CDFS = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)


def test_the_explorer_names_the_infinite_values_it_sends_as_null() -> None:
    res = run_linear(check({"drive": "cdfs", "table_speed": "1.5"}), lambda *args: None)
    json.dumps(res, allow_nan=False)  # still plain JSON: null, never Infinity
    for key in ("loops", "bode"):
        loops = {lp["loop"]: lp for lp in res[key]}
        velocity, position = loops["screw velocity loop"], loops["screw position loop"]
        assert velocity["gain_margin_db"] is None and velocity["crossover_hz"] is not None
        assert velocity["infinite"] == ["gain_margin_db"], key
        assert position["gain_margin_db"] is not None and position["infinite"] == [], key


def test_a_value_the_loop_has_not_stays_a_plain_null() -> None:
    """No gain crossover: no crossover, phase margin or bandwidth (null, "—" on the page); the
    gain margin is still infinite, as `feeddrive loops` prints it
    (tests/unit/test_band_format_s27.py)."""
    from feeddrive.explore.compute import loop_json

    values = {"loop": "screw velocity loop", "gain_margin_db": None, "phase_margin_deg": None,
              "crossover_hz": None, "closed_loop_bandwidth_hz": None}
    sent = loop_json(values)
    assert sent == {**values, "infinite": ["gain_margin_db"]}
    finite = loop_json({**values, "gain_margin_db": 2.589})
    assert finite["infinite"] == [] and finite["gain_margin_db"] == 2.589


def test_the_bode_legend_gives_an_infinite_gain_margin() -> None:
    fig = _bode(loop_analysis(CDFS, 1.5e-3, frictionless=True, points=40))
    (legend,) = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    labels = {t.get_text().split(",")[0]: t.get_text() for t in legend.get_texts()}
    assert labels["screw velocity loop"].endswith(", GM ∞ dB"), labels
    assert labels["screw position loop"].endswith(", GM 2.6 dB"), labels


def test_the_gallery_example_prints_an_infinite_gain_margin() -> None:
    out = io.StringIO()
    try:
        with contextlib.redirect_stdout(out):
            runpy.run_path(str(ROOT / "docs" / "examples" / "plot_05_linear_analysis.py"),
                           run_name="__main__")
    finally:
        plt.close("all")
    lines = {line.split(":")[0]: line for line in out.getvalue().splitlines()}
    assert lines["screw velocity loop"].startswith(
        "screw velocity loop: gain margin ∞ dB, phase margin 16.8 deg"), lines
    assert lines["screw position loop"].startswith(
        "screw position loop: gain margin 2.6 dB"), lines
    assert "none" not in out.getvalue()
