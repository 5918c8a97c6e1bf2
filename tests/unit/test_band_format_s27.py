"""Session 27: one text for infinite margins and for band edges cut by the scan.

* `feeddrive loops` printed "—" for the wang2021 screw velocity loop's gain margin, which is
  infinite (its phase never crosses −180°: :data:`feeddrive.units.INFINITE_WHEN_ABSENT`),
  the mark of a missing value; "—" stays for a value that does not exist.
* `feeddrive compensate`, the report's linear section, its answer box and its compensation
  table printed a band whose edge is only the scan's end as if it were an edge found, while
  `feeddrive stability` marked it ≤ / ≥; `plot_band` showed no difference either.
* The sweep map's cells printed "–" for an infinite value and for a missing one alike.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import xarray as xr  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from typer.testing import CliRunner  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.analysis.linear import StabilityBand, loop_analysis, stability_band  # noqa: E402
from feeddrive.cli import app  # noqa: E402
from feeddrive.plots.layout import clipped_artists, covered_data  # noqa: E402
from feeddrive.sweep.quantities import stored_value  # noqa: E402

PARAMS = fd.preset("wang2021")
CDFS = fd.DriveSystem(PARAMS, "cdfs", 0.4)
#: wang2021-literal's CDFS slides unstably at every speed of the default scan, 0.01–5 mm/s
#: (tests/unit/test_report_answer.py): both edges of its band are the scan's ends
LITERAL = fd.preset("wang2021-literal")


def _cut_band() -> StabilityBand:
    """The wang2021 CDFS band 0.172–1.399 mm/s scanned to 1 mm/s only: its upper edge is the
    scan's end (tests/unit/test_linear_honesty_s26.py)."""
    return stability_band(CDFS, high=1e-3, points=12)


def _row(band: StabilityBand, case: str) -> dict[str, Any]:
    """A compensation-study row with ``band`` stored as feeddrive.analysis.compensation's
    ``evaluate`` stores it (edges in mm/s, no flags)."""
    return {"case": case, "drive": "cdfs", "compensation": "none",
            "linear_unstable_bands_mm_s": [[1e3 * lo, 1e3 * hi] for lo, hi in band.intervals],
            "tracking_speed_mm_s": 1.0, "verdict_at_tracking_speed": "stick-slip",
            "speed_ripple_ratio": 1.0, "following_error_rms_um": 1.0,
            "following_error_peak_um": 2.0}


# ---------------------------------------------------------------- infinite gain margin


def test_loops_prints_an_infinite_gain_margin_as_infinity() -> None:
    """The wang2021 screw velocity loop has no phase crossover (none up to 50 kHz:
    feeddrive.sweep.quantities); its position loop's margin is python-control's 2.589 dB
    (docs/linear.md).  JSON keeps null, which the sweep store reads back as +inf."""
    runner = CliRunner()
    res = runner.invoke(app, ["loops"])
    assert res.exit_code == 0, res.output
    lines = [" ".join(line.split()) for line in res.stdout.splitlines() if "gain margin" in line]
    (velocity,) = [line for line in lines if line.startswith("screw velocity loop")]
    (position,) = [line for line in lines if line.startswith("screw position loop")]
    assert "gain margin ∞ dB" in velocity and "gain margin 2.59 dB" in position
    assert "—" not in velocity + position
    res = runner.invoke(app, ["loops", "--json"])
    assert res.exit_code == 0, res.output
    loops = {lp["loop"]: lp for lp in json.loads(res.stdout)["loops"]}
    assert loops["screw velocity loop"]["gain_margin_db"] is None
    assert stored_value("screw_velocity_loop_gain_margin_db", None) == math.inf


def test_a_missing_value_keeps_the_dash_and_the_gain_margin_is_infinite(
        capsys: pytest.CaptureFixture[str]) -> None:
    """A loop without gain crossover has no crossover, phase margin or bandwidth ("—"); a loop
    without phase crossover has an infinite gain margin ("∞")."""
    from feeddrive.cli._loops_text import print_loops

    data = {"least_damped_mode": {"frequency_hz": 5.0, "damping_ratio": 0.1},
            "friction": "without friction", "notes": [], "poles": [],
            "loops": [{"loop": "screw velocity loop", "gain_margin_db": None,
                       "phase_margin_deg": None, "crossover_hz": None,
                       "closed_loop_bandwidth_hz": None}]}
    print_loops("CDFS", "x", 1.5, False, data)
    line = " ".join(capsys.readouterr().out.split()).split("screw velocity loop")[1]
    assert line == " crossover — phase margin — gain margin ∞ dB bandwidth —"
    from feeddrive.analysis.linear import margin_text

    assert margin_text("crossover_hz", None, unit="Hz") == "—"
    assert margin_text("gain_margin_db", 2.5894, unit="dB") == "2.59 dB"


def test_the_loops_repr_says_infinite_gain_margin() -> None:
    velocity = loop_analysis(CDFS, 1.5e-3, frictionless=True).loops[1]
    assert velocity.gain_margin_db is None
    assert "GM ∞ dB" in repr(velocity) and "GM —" not in repr(velocity)


# ---------------------------------------------------------------- band edges at the scan's end


def test_stored_bands_know_their_cut_edges_as_the_band_does() -> None:
    """The compensation rows keep the edges alone: an edge equal to the scan's end is that
    end, the same verdict as StabilityBand.edges_at_scan_ends, at either end and at none."""
    from feeddrive.analysis.linear import stored_band_cuts

    literal = stability_band(fd.DriveSystem(LITERAL, "cdfs", 0.4), points=12)
    inside = stability_band(CDFS, points=12)
    cut = _cut_band()
    for band, scan in ((literal, None), (inside, None), (cut, (1e-5, 1e-3))):
        stored = _row(band, "x")["linear_unstable_bands_mm_s"]
        found = stored_band_cuts(stored) if scan is None else stored_band_cuts(stored, scan)
        assert found == band.edges_at_scan_ends
    assert literal.edges_at_scan_ends == [(True, True)]
    assert inside.edges_at_scan_ends == [(False, False)]


def test_compensate_marks_a_band_cut_by_the_scan(capsys: pytest.CaptureFixture[str]) -> None:
    """`feeddrive compensate` printed 0.010–5.000 for a band over the whole scan."""
    from feeddrive.cli.compensate_cmd import _show_study

    literal = stability_band(fd.DriveSystem(LITERAL, "cdfs", 0.4), points=12)
    inside = stability_band(CDFS, points=12)
    rows = [_row(literal, "literal"), _row(inside, "shipped")]
    _show_study(rows, "wang2021", 400.0, 1.0, "dopri5", False, False)
    out = " ".join(capsys.readouterr().out.split())
    assert "linear band ≤ 0.010–≥ 5.000 mm/s" in out
    (lo, hi), = inside.intervals  # edges found: unmarked
    assert f"linear band {1e3 * lo:.3f}–{1e3 * hi:.3f} mm/s" in out


def test_the_reports_compensation_table_marks_a_cut_band() -> None:
    from feeddrive.reproduce.beyond_section import compensation_rows

    literal = stability_band(fd.DriveSystem(LITERAL, "cdfs", 0.4), points=12)
    table = compensation_rows({"rows": [_row(literal, "literal"),
                                        _row(stability_band(CDFS, points=12), "shipped")]})
    assert [r["linear creep band [mm/s]"] for r in table] == ["≤ 0.01–≥ 5.00", "0.17–1.40"]


def test_the_reports_linear_section_and_answer_mark_a_cut_band() -> None:
    """The report's linear section printed wang2021-literal's CDFS band as 0.010–5.000 mm/s;
    the shipped set's (0.172–1.399, the edges found) is unchanged."""
    from feeddrive.reproduce.answer_section import mechanism_sentence
    from feeddrive.reproduce.linear_section import cdfs_linear, linear_rows

    cdfs = cdfs_linear(LITERAL)
    _, rows = linear_rows(LITERAL, {}, cdfs=cdfs)
    value = next(r["value"] for r in rows if r["item"].startswith("CDFS: linearly unstable"))
    assert value.startswith("≤ 0.010–≥ 5.000 mm/s (")
    assert "linearly unstable at ≤ 0.01–≥ 5.00 mm/s;" in mechanism_sentence(cdfs)
    shipped = cdfs_linear(PARAMS)
    assert mechanism_sentence(shipped).endswith("linearly unstable at 0.17–1.40 mm/s.")


def test_band_text_and_the_stability_command_share_the_marks() -> None:
    band = _cut_band()
    assert band.edge_texts() == [("0.172", "≥ 1.000")]
    assert band.text(2, "mm/s") == "0.17–≥ 1.00 mm/s"
    assert "unstable 0.172–≥ 1.000 mm/s" in repr(band)


# ---------------------------------------------------------------- plot_band


def _saved(draw: Callable[[], object]) -> Figure:
    """The figure ``draw()`` saves, taken as it is saved (its artists, not its image)."""
    captured: dict[str, Figure] = {}
    original = Figure.savefig

    def keep(self: Figure, *args: Any, **kwargs: Any) -> None:
        captured["fig"] = self
        original(self, *args, **kwargs)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(Figure, "savefig", keep)
        draw()
    return captured["fig"]


def _plotted(band: StabilityBand, tmp_path: Path) -> Figure:
    """plot_band's figure."""
    from feeddrive.plots.linear import plot_band

    return _saved(lambda: plot_band(band, tmp_path / "band.png"))


def _dashed_at(fig: Figure, x: float) -> list[Any]:
    ax = fig.axes[0]
    return [ln for ln in ax.get_lines() if ln.get_linestyle() == "--"
            and np.allclose(ln.get_xdata(), x)]


def _legend_texts(fig: Figure) -> list[str]:
    legends = [*fig.legends, *(ax.get_legend() for ax in fig.axes)]
    return [t.get_text() for lg in legends if lg is not None for t in lg.get_texts()]


def test_plot_band_marks_an_edge_that_is_the_scans_end(tmp_path: Path) -> None:
    """A dashed edge at the scan's end 1 mm/s with an arrow pointing on out of the scan, and
    the legend saying the band continues beyond it; the lower edge (0.172 mm/s, found) is not
    marked, nor is either edge of the band scanned whole."""
    fig = _plotted(_cut_band(), tmp_path)
    assert len(_dashed_at(fig, 1.0)) == 1
    assert not any(ln.get_linestyle() == "--" and np.allclose(ln.get_xdata(), 0.172, atol=1e-3)
                   for ln in fig.axes[0].get_lines())
    assert any("continues beyond the scan" in t for t in _legend_texts(fig))
    arrows = [a for a in fig.axes[0].texts if getattr(a, "arrow_patch", None) is not None]
    assert len(arrows) == 1 and arrows[0].xy[0] == pytest.approx(1.0)
    assert covered_data(fig) == [] and clipped_artists(fig) == []
    plt.close(fig)
    # a band inside the scan: both edges found, no mark
    fig = _plotted(stability_band(CDFS, points=12), tmp_path)
    assert not any(ln.get_linestyle() == "--" for ln in fig.axes[0].get_lines())
    assert not any("continues beyond" in t for t in _legend_texts(fig))
    plt.close(fig)


# ---------------------------------------------------------------- maps: ∞ is not missing


def _margin_dataset() -> xr.Dataset:
    """A loop-margins grid sweep as feeddrive.sweep.export builds it: one infinite gain
    margin (no phase crossover), one NaN (the point is not computed), the rest finite."""
    gm = np.array([[2.6, math.inf], [math.nan, 3.1]])
    coords = {"table_position": ("table_position", np.array([0.2, 0.6]), {"units": "m"}),
              "controller.velocity_gain": ("controller.velocity_gain", np.array([36.0, 45.0]),
                                           {"units": "A s/rad"})}
    dims = ("table_position", "controller.velocity_gain")
    return xr.Dataset({"screw_velocity_loop_gain_margin_db": (dims, gm, {"units": "dB"})},
                      coords=coords, attrs={"sweep": "m", "quantity": "loop-margins",
                                            "design": "grid"})


def test_map_cells_tell_infinite_from_missing(tmp_path: Path) -> None:
    from feeddrive.sweep import plot_map

    fig = _saved(lambda: plot_map(_margin_dataset(), "table_position",
                                  "controller.velocity_gain", tmp_path / "map.png",
                                  value="screw_velocity_loop_gain_margin_db"))
    cells = sorted(t.get_text() for t in fig.axes[0].texts)
    assert cells == sorted(["2.6", "∞", "–", "3.1"])
    plt.close(fig)


def test_map_statistics_count_infinite_values_apart() -> None:
    from feeddrive.cli.sweep_cmd import _stats_text
    from feeddrive.sweep import percentiles

    stats = percentiles(_margin_dataset(), "screw_velocity_loop_gain_margin_db")
    assert (stats["points"], stats["finite"], stats["infinite"]) == (4, 2, 1)
    assert _stats_text(stats).endswith("(2 of 4 points finite, 1 infinite)")
    all_inf = _margin_dataset().copy(deep=True)
    all_inf["screw_velocity_loop_gain_margin_db"][:] = math.inf
    text = _stats_text(percentiles(all_inf, "screw_velocity_loop_gain_margin_db"))
    assert text.endswith("no finite value among 4 points (4 infinite)")
