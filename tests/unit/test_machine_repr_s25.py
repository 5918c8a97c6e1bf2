"""A circular test's runs show themselves as machine runs (an outside check, 2026-12-07):
``repr(trace)``, ``repr(trace.results["CCW"])`` raised KeyError 'table_speed_reference'
(a run following given references lacked the attributes that mark a machine's run), its
``plot()`` raised KeyError 'table_speed', its ``summary()`` blamed "a replay"; the trace's
and the test's reprs ran to thousands of characters of arrays."""

from __future__ import annotations

import re

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.analysis.circular_run import CircularRunTrace, run_circular_test
from feeddrive.machine import (
    MachineProfile,
    MachineSystem,
    Together,
    load_machine,
    simulate_machine,
)
from feeddrive.model.reference import SampledSpeed
from feeddrive.parameters import ParameterError


@pytest.fixture(scope="module")
def trace() -> CircularRunTrace:
    return run_circular_test(load_machine("xy-table"), radius=0.01, feed=2000 / 6e4)


def test_a_circular_runs_repr_and_html_name_the_machine_and_its_path(
        trace: CircularRunTrace) -> None:
    run = trace.results["CCW"]
    text = repr(run)
    assert re.match(r"<feeddrive\.Result machine xy-table: Circle\(length=[\d.]+ m, "
                    # after the dash the axes' parameter set (it was the machine's name
                    # again until the machine's attrs named it apart, session 26)
                    r"feed=0\.0333+ m/s\), axes x, y, [\d.]+ s — wang2021; \d+ samples>$",
                    text), text
    assert run._dataset is None  # said from the run's own attributes: no Dataset built
    html = run._repr_html_()
    assert "machine xy-table" in html and "x.table_speed" in html


def test_a_circular_run_plots_each_axis(trace: CircularRunTrace) -> None:
    run = trace.results["CW"]
    fig = run.plot()
    assert [ax.get_ylabel() for ax in fig.axes] == ["x speed [mm/s]", "y speed [mm/s]"]
    assert len(fig.axes[0].lines[0].get_xdata()) == run.time.size


def test_a_circular_runs_summary_says_it_is_a_machines_run(trace: CircularRunTrace) -> None:
    with pytest.raises(ParameterError, match=r"^profile = .*a machine's run \(axes x, y\): "
                                             r".*machine_summary") as err:
        trace.results["CCW"].summary()
    assert "replay" not in str(err.value) and "\n" not in str(err.value)


def test_the_trace_the_test_and_a_run_have_one_line_reprs(trace: CircularRunTrace) -> None:
    gb = trace.test.bidirectional_circular_deviation
    assert gb is not None
    assert repr(trace) == (f"<feeddrive CircularRunTrace xy-table x,y R 10 mm, feed 2000 "
                           f"mm/min: G(b) {gb * 1e6:.4g} µm>")
    assert re.match(r"<feeddrive CircularTest R 10 mm, runs CCW,CW, feed [\d.]+ mm/min: "
                    r"G\(b\) [\d.]+ µm>$", repr(trace.test)), repr(trace.test)
    assert re.match(r"<feeddrive CircularRun CCW: \d+ samples, [\d.]+ … [\d.]+ s>$",
                    repr(trace.test.runs[0])), repr(trace.test.runs[0])


def test_a_together_run_shows_as_a_machine_run() -> None:
    run = simulate_machine(load_machine("xy-table"),
                           Together(feed=0.01, acceleration=0.5, axes=("x", "y"),
                                    distance=0.001), 0.05)
    assert repr(run).startswith("<feeddrive.Result machine xy-table: Together(length=0.001 m")
    assert [ax.get_ylabel() for ax in run.plot().axes] == ["x speed [mm/s]", "y speed [mm/s]"]


def test_a_machine_simulated_from_given_references_shows_as_a_machine_run() -> None:
    machine = load_machine("xy-table")
    t = np.linspace(0.0, 0.05, 51)
    profile = MachineProfile.common(machine, SampledSpeed(time=t, table_speed=np.full_like(
        t, 2e-3)))
    run = fd.simulate(MachineSystem(machine), profile, 0.05)  # type: ignore[arg-type]
    assert repr(run).startswith("<feeddrive.Result machine xy-table: MachineProfile(0.05 s), "
                                "axes x, y,")
