"""Issue 24 item 2: legends and labels covered the data.  feeddrive.plots.layout checks a
figure as matplotlib draws it; these tests show that it catches each fault the issue saw, and
that the figures of `simulate --plot` and `map --plot` have none of them (the reproduction's
figures: tests/validation/test_report_new_user.py)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import xarray as xr  # noqa: E402

from feeddrive.plots.layout import (  # noqa: E402
    clipped_artists,
    covered_data,
    overlapping_texts,
)

T = np.linspace(0.0, 12.0, 6000)
OSCILLATION = 1.55 + 1.2 * np.sin(2 * np.pi * 5.5 * T)  # fills the axes, as Fig. 6a


def test_an_inner_legend_on_an_oscillation_is_caught() -> None:
    fig, ax = plt.subplots()
    ax.plot(T, OSCILLATION, label="table")
    ax.plot(T, np.full_like(T, 1.55), "k--", label="command")
    ax.legend(loc="lower right")
    found = covered_data(fig)
    assert found and "legend" in found[0] and "'table'" in found[0]
    plt.close(fig)


def test_a_boxed_label_on_a_peak_and_a_sparse_segment_are_caught() -> None:
    fig, ax = plt.subplots()
    ax.plot([0.0, 10.0], [0.0, 10.0], label="diagonal")  # two vertices, one long segment
    ax.text(5.0, 5.0, "label on the line", ha="center", va="center",
            bbox={"facecolor": "white"})
    found = covered_data(fig)
    assert found and "label on the line" in found[0] and "'diagonal'" in found[0]
    plt.close(fig)


def test_clipped_legend_and_a_legend_over_the_title_are_caught() -> None:
    fig, ax = plt.subplots(figsize=(3, 3))
    ax.plot([0, 1], [0, 1])
    fig.legend(handles=ax.get_lines(), labels=["a very long legend entry " * 4],
               loc="lower center")
    assert clipped_artists(fig)
    plt.close(fig)
    fig, ax = plt.subplots(layout="constrained")
    ax.plot(T, OSCILLATION, label="table")
    fig.suptitle("a title")
    fig.legend(loc="outside upper center")
    assert any("a title" in s for s in overlapping_texts(fig))
    plt.close(fig)


def test_a_clean_figure_passes() -> None:
    fig, ax = plt.subplots(layout="constrained")
    ax.plot(T, OSCILLATION, label="table")
    fig.legend(loc="outside lower center")
    ax.set_title("title")
    assert covered_data(fig) == [] and clipped_artists(fig) == []
    assert overlapping_texts(fig) == []
    plt.close(fig)


@pytest.mark.parametrize("drive", ["cdfs", "ddfs", "linear-motor"])
def test_simulate_plot_keeps_legends_off_the_traces_and_says_what_ran(drive: str) -> None:
    """Item 2: `simulate --plot` had its legends on the traces and a title without speed or
    profile."""
    import feeddrive as fd
    from feeddrive.plots.result import result_figure

    params = fd.preset("linear-motor-example" if drive == "linear-motor" else "wang2021")
    nut = 16e-3 if drive == "ddfs" else 0.0
    r = fd.simulate(fd.DriveSystem(params, drive, 0.4), fd.ConstantSpeed(1.5e-3, nut), 0.6)
    fig = result_figure(r)
    assert covered_data(fig) == [] and clipped_artists(fig) == []
    assert overlapping_texts(fig) == []
    title = fig.texts[0].get_text()  # the suptitle
    assert "constant 1.5 mm/s" in title and drive.upper() in title
    assert ("position" in title) == (drive != "linear-motor")
    plt.close(fig)


def _map_dataset() -> xr.Dataset:
    """A critical-speed grid sweep as feeddrive.sweep.export builds it (SI units)."""
    pos = np.array([0.2, 0.3, 0.4, 0.5, 0.6])
    gain = np.array([27.0, 36.0, 45.0, 56.0, 72.0])
    crit = 1e-3 * (1.0 + 0.02 * np.arange(5)[:, None] + 0.25 * np.arange(5)[None, :])
    lin = 0.9 * crit
    coords = {"table_position": ("table_position", pos, {"units": "m"}),
              "controller.velocity_gain": ("controller.velocity_gain", gain, {"units": "A s/rad"})}
    dims = ("table_position", "controller.velocity_gain")
    return xr.Dataset(
        {"critical_speed": (dims, crit, {"units": "m/s"}),
         "linear_upper": (dims, lin, {"units": "m/s"}),
         "status": (dims, np.full((5, 5), "found"))},
        coords=coords, attrs={"sweep": "example", "quantity": "critical-speed",
                              "design": "grid"})


def test_map_plot_legend_fits_and_contour_labels_do_not_overlap(tmp_path) -> None:
    """Item 2: the map's bottom legend was cut off on both sides, and the red boundary's
    contour labels were drawn over the black ones."""
    from feeddrive.sweep import maps

    captured = {}
    original = plt.Figure.savefig

    def keep(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        captured["fig"] = self
        return original(self, *args, **kwargs)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(plt.Figure, "savefig", keep)
        maps.plot_map(_map_dataset(), "table_position", "controller.velocity_gain",
                      tmp_path / "map.png")
    fig = captured["fig"]
    assert clipped_artists(fig) == []
    contour_labels = [t for t in overlapping_texts(fig) if "lin" not in t]
    assert contour_labels == []
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert len(labels) == 2 and all(ax.collections for ax in fig.get_axes()[:1])
