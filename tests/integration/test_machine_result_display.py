"""A machine's run shows itself in a notebook (an outside check, 2026-12-07): its Result's
repr, HTML and plot raised KeyError 'table_speed_reference' (its axes' signals are prefixed,
``x.table_speed``), so a notebook cell echoing it — or a circular test's trace holding it —
failed; its summary blamed "a replay" driving the table open-loop."""

from __future__ import annotations

import pytest

import feeddrive as fd
import feeddrive.machine as machine
from feeddrive.parameters import ParameterError


@pytest.fixture(scope="module")
def run() -> fd.Result:
    return machine.simulate_machine(machine.load_machine("xy-table"),
                                    machine.Circle(feed=0.01, acceleration=0.5, radius=0.005),
                                    0.3)


def test_its_repr_and_html_name_the_machine_and_its_axes(run: fd.Result) -> None:
    text = repr(run)
    assert text.startswith("<feeddrive.Result machine xy-table: Circle(") and "axes x, y" in text
    assert f"{run.time.size} samples" in text
    html = run._repr_html_()
    assert "machine xy-table" in html and "x.table_speed" in html


def test_it_plots_each_axis_and_the_contour_error(run: fd.Result) -> None:
    fig = run.plot()
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels == ["x speed [mm/s]", "y speed [mm/s]", "contour error [µm]"]
    assert len(fig.axes[0].lines[0].get_xdata()) == run.time.size


def test_its_summary_says_where_a_machines_summary_is(run: fd.Result) -> None:
    with pytest.raises(ParameterError, match=r"a machine's run \(axes x, y\).*machine_summary"):
        run.summary()


def test_a_negative_command_keeps_its_sign_in_the_title() -> None:
    r = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4), fd.ConstantSpeed(-2e-3),
                    0.1)
    assert "constant -2 mm/s" in repr(r)
