"""Long runs (issue 9 item 3): chunked integration is bit-identical to one integrator call,
streams to a file without keeping the run, reports progress, and stops on Ctrl-C with what
was computed."""

from __future__ import annotations

import importlib

import numpy as np
import pandas as pd
import pytest

import feeddrive as fd
from feeddrive.engine.simulate import Simulation, SimulationInterrupted, SolverOptions, sampling
from feeddrive.model.reference import ConstantSpeed
from feeddrive.solvers import dopri5

W = fd.preset("wang2021")
sim_mod = importlib.import_module("feeddrive.engine.simulate")


def _one_call(system: fd.DriveSystem, profile: ConstantSpeed, duration: float) -> np.ndarray:
    model = system.model(profile)
    options = SolverOptions()
    grid = sampling(system.parameters, options.output_interval)
    sim = Simulation(system, profile, options)  # the run's resolved tolerances
    atol, rel = sim.atol, sim.rel
    _, y, _, stats, _ = dopri5.integrate(
        model, system.initial_vector(model), duration, grid.out_every, grid.base,
        grid.schedule, sim.tolerances.rtol, atol, rel, 1e-6, grid.base, 1, options.max_steps,
        switch_rows=sim.switch_rows)
    assert int(stats[0]) == 0
    return y


@pytest.mark.parametrize("sampled", [False, True])
def test_chunked_run_is_bit_identical_to_one_call(sampled: bool, monkeypatch) -> None:
    params = W
    if sampled:
        params = (W.replace_path("controller.position_period", 1e-3)
                  .replace_path("controller.velocity_period", 5e-4)
                  .replace_path("controller.current_period", 1.25e-4)
                  .replace_path("controller.encoder_counts", 10000.0))
    system = fd.DriveSystem(params, "cdfs", 0.4)
    profile = ConstantSpeed(1.2e-3)
    monkeypatch.setattr(sim_mod, "FIRST_CHUNK", 0.3)
    monkeypatch.setattr(sim_mod, "CHUNK_WALL_TIME", 1e-4)  # many small chunks
    seen: list[float] = []
    # dopri5's wall-time chunks (the dense-output methods chunk at DENSE_CHUNK: tested below)
    r = fd.simulate(system, profile, 3.0, progress=lambda t, end: seen.append(t),
                    options=fd.SolverOptions(method="dopri5"))
    assert len(seen) > 5 and seen[-1] == pytest.approx(3.0)
    y = _one_call(system, profile, 3.0)
    states = np.column_stack([r[name] for name in system.model(profile).state_names])
    np.testing.assert_array_equal(states, y)
    assert np.all(np.diff(r.time) > 0)


@pytest.mark.parametrize("sampled", [False, True])
def test_continued_simulation_is_bit_identical_to_a_run_from_rest(sampled: bool) -> None:
    """Simulation.run(12) then .run(24) continues the first run; the 24-s Result equals
    simulate(..., 24) sample for sample (the creep verdict lengthens trials this way)."""
    params = W
    if sampled:
        params = (W.replace_path("controller.position_period", 1e-3)
                  .replace_path("controller.velocity_period", 5e-4)
                  .replace_path("controller.encoder_counts", 10000.0))
    system = fd.DriveSystem(params, "cdfs", 0.4)
    profile = ConstantSpeed(1.2e-3, ramp_time=0.1)
    # dopri5 continues from any instant; the dense-output methods (the default) from the
    # multiples of DENSE_CHUNK (their own tests)
    explicit = fd.SolverOptions(method="dopri5")
    sim = fd.Simulation(system, profile, explicit)
    short = sim.run(3.0)
    evaluations = short.solver_stats["rhs_evaluations"]
    long = sim.run(6.0)
    ref = fd.simulate(system, profile, 6.0, options=explicit)
    for name in ("table_speed", "table_position", "screw_current"):
        np.testing.assert_array_equal(long[name], ref[name])
    np.testing.assert_array_equal(long.time, ref.time)
    np.testing.assert_array_equal(short["table_speed"], long["table_speed"][:short.time.size])
    # continued, not repeated: the second call cost only the extra 3 s (a resumed chunk
    # evaluates the right-hand side once more at its first point)
    assert 0 <= long.solver_stats["rhs_evaluations"] - ref.solver_stats["rhs_evaluations"] <= 2
    assert evaluations < long.solver_stats["rhs_evaluations"] < 3 * evaluations
    # a shorter run than the last starts again from rest
    np.testing.assert_array_equal(sim.run(3.0)["table_speed"], short["table_speed"])


def test_streamed_run_writes_every_sample_and_keeps_only_the_end(tmp_path, monkeypatch) -> None:
    monkeypatch.setattr(sim_mod, "FIRST_CHUNK", 0.5)
    monkeypatch.setattr(sim_mod, "KEEP_STREAMED", 1.0)
    monkeypatch.setattr(sim_mod, "CHUNK_WALL_TIME", 1e-4)
    out = tmp_path / "run.parquet"
    # dopri5's small chunks (a dense-output run of 4 s is one chunk: DENSE_CHUNK = 10 s)
    r = fd.simulate(fd.DriveSystem(W, "cdfs", 0.4), ConstantSpeed(2e-3), 4.0, output=out,
                    options=fd.SolverOptions(method="dopri5"))
    frame = pd.read_parquet(out)
    assert len(frame) == 4001 and frame["time"].iloc[-1] == pytest.approx(4.0)
    assert np.all(np.diff(frame["time"].to_numpy()) > 0)
    assert r.time[0] > 2.0 and r.time[-1] == pytest.approx(4.0)  # only the end is kept
    np.testing.assert_allclose(frame["table_speed"].to_numpy()[-r.time.size:],
                               1e3 * r["table_speed"], rtol=1e-12)


def test_ctrl_c_between_chunks_keeps_what_was_computed(tmp_path, monkeypatch) -> None:
    monkeypatch.setattr(sim_mod, "FIRST_CHUNK", 0.5)
    calls = []

    def interrupt(t: float, end: float) -> None:
        calls.append(t)
        if len(calls) == 2:
            raise KeyboardInterrupt

    out = tmp_path / "run.csv"
    with pytest.raises(SimulationInterrupted) as info:
        fd.simulate(fd.DriveSystem(W, "cdfs", 0.4), ConstantSpeed(2e-3), 60.0, output=out,
                    progress=interrupt)
    stop = info.value
    assert 0 < stop.t_reached < 60.0 and stop.output == str(out)
    assert stop.result is not None and stop.result.time[-1] == pytest.approx(stop.t_reached)
    written = pd.read_csv(out, comment="#")
    assert written["time [s]"].iloc[-1] == pytest.approx(stop.t_reached)


def test_auxiliary_signals_evaluated_when_read_equal_the_recorded_ones() -> None:
    """Issue 9 item 2: with continuous loops the dense-output run records states only; the
    auxiliary signals computed on first read equal those the integrator would have recorded."""
    from feeddrive.solvers import switching

    system = fd.DriveSystem(W, "ddfs", 0.4)
    profile = ConstantSpeed(0.5e-3, 16e-3)
    options = SolverOptions(method="auto")
    r = fd.simulate(system, profile, 2.0, options=options)
    assert r.solver_stats["output_rhs_evaluations"] == 0  # nothing evaluated for the record
    model = system.model(profile)
    grid = sampling(W, options.output_interval)
    sim = Simulation(system, profile, options)  # the run's resolved tolerances
    atol, rel = sim.atol, sim.rel
    t, y, aux, _, _ = switching.integrate(
        model, system.initial_vector(model), 2.0, grid.out_every, grid.base, grid.schedule,
        sim.tolerances.rtol, atol, rel, 1e-6, np.inf, 1, options.max_steps,
        options.driver_mode[0],
        sim_mod.profile_breakpoints(profile, 2.0, grid.base), want_aux=True,
        switch_rows=sim.switch_rows)
    np.testing.assert_array_equal(r.time, t)
    for k, sig in enumerate(model.aux):
        np.testing.assert_array_equal(r[sig.name], aux[:, k], err_msg=sig.name)


@pytest.mark.parametrize(("drive", "nut_speed", "sampled"),
                         [("cdfs", 0.0, False), ("ddfs", 16e-3, False), ("cdfs", 0.0, True)])
def test_continued_dense_run_is_bit_identical_to_a_run_from_rest(
        drive: str, nut_speed: float, sampled: bool) -> None:
    """method "auto": a 12-s run continued to 24 s equals a 24-s run from rest sample for
    sample (both end their calls at the multiples of DENSE_CHUNK, where the driver's state is
    carried over: step size, method, switching counters, frozen states)."""
    params = W
    if sampled:
        params = (W.replace_path("controller.position_period", 1e-3)
                  .replace_path("controller.velocity_period", 5e-4))
    system = fd.DriveSystem(params, drive, 0.4)
    profile = ConstantSpeed(1.2e-3 if drive == "cdfs" else 0.5e-3, nut_speed, ramp_time=0.1)
    options = SolverOptions(method="auto")
    sim = fd.Simulation(system, profile, options)
    short = sim.run(12.0)
    long = sim.run(24.0)
    ref = fd.simulate(system, profile, 24.0, options=options)
    np.testing.assert_array_equal(long.time, ref.time)
    for name in ("table_speed", "table_position", "screw_current"):
        np.testing.assert_array_equal(long[name], ref[name])
    # up to the last multiple of DENSE_CHUNK the short run is the long one's start
    n = int(round(sim_mod.DENSE_CHUNK / 1e-3)) + 1
    np.testing.assert_array_equal(short["table_speed"][:n], ref["table_speed"][:n])
    if sampled:  # 12 s is a sample instant, a step end in every run: the whole short run
        np.testing.assert_array_equal(short["table_speed"], ref["table_speed"][:12001])
    assert long.solver_stats["method_switches"] == ref.solver_stats["method_switches"]


def test_dense_run_streams_reports_progress_and_stops_on_ctrl_c(tmp_path, monkeypatch) -> None:
    """method "auto" streams to a file chunk by chunk, keeps only the end, reports progress
    after each DENSE_CHUNK, and Ctrl-C between chunks keeps what was computed."""
    monkeypatch.setattr(sim_mod, "DENSE_CHUNK", 1.0)
    monkeypatch.setattr(sim_mod, "KEEP_STREAMED", 1.0)
    system = fd.DriveSystem(W, "ddfs", 0.4)
    profile = ConstantSpeed(0.5e-3, 16e-3)
    options = SolverOptions(method="auto")
    seen: list[float] = []
    out = tmp_path / "run.parquet"
    r = fd.simulate(system, profile, 4.5, options=options, output=out,
                    progress=lambda t, end: seen.append(t))
    assert seen == pytest.approx([1.0, 2.0, 3.0, 4.0, 4.5])
    whole = fd.simulate(system, profile, 4.5, options=options)
    frame = pd.read_parquet(out)
    np.testing.assert_array_equal(frame["time"].to_numpy(), whole.time)
    np.testing.assert_allclose(frame["table_speed"].to_numpy(),
                               1e3 * whole["table_speed"], rtol=1e-12)
    assert r.time[0] > 2.0 and r.time[-1] == pytest.approx(4.5)  # only the end is kept

    def interrupt(t: float, end: float) -> None:
        if t >= 2.0:
            raise KeyboardInterrupt

    with pytest.raises(SimulationInterrupted) as info:
        fd.simulate(system, profile, 4.5, options=options, output=tmp_path / "cut.csv",
                    progress=interrupt)
    assert info.value.t_reached == pytest.approx(2.0)
    assert pd.read_csv(tmp_path / "cut.csv", comment="#")["time [s]"].iloc[-1] == pytest.approx(2.0)
    partial = info.value.result
    assert partial is not None and partial.time[-1] == pytest.approx(2.0)
    for sig in system.model(profile).aux:  # evaluated on reading, one per sample
        assert partial[sig.name].shape == partial.time.shape, sig.name


def test_docs_state_the_dense_chunk_length() -> None:
    """docs/model.md tells users where dense-output runs end their calls."""
    from pathlib import Path

    text = " ".join((Path(__file__).resolve().parents[2] / "docs" / "model.md")
                    .read_text(encoding="utf-8").split())
    assert f"multiples of {sim_mod.DENSE_CHUNK:g} s (`simulate.DENSE_CHUNK`)" in text
