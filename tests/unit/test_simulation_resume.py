"""A staircase run continued from the checkpoint of an earlier run with the same beginning
(`Simulation.resume`, what the step-down search does when it lengthens one step) is
bit-identical to the run from rest: states, samples and solver counters."""

from __future__ import annotations

import numpy as np

import feeddrive as fd
from feeddrive.engine.simulate import DriveSystem, Simulation, simulate
from feeddrive.model.reference import _staircase

SPEEDS = np.array([1.6e-3, 1.45e-3, 1.4e-3])


def test_a_resumed_staircase_equals_the_run_from_rest() -> None:
    system = DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    first, _ = _staircase(SPEEDS, [12.0, 12.0, 12.0], 0.0, 0.0)
    longer, _ = _staircase(SPEEDS, [12.0, 24.0, 12.0], 0.0, 0.0)  # step 1 held longer
    before = Simulation(system, first)
    before.keep_checkpoints()
    before.run(float(first.time[-1]))
    again = Simulation(system, longer)
    again.keep_checkpoints()
    at = again.resume(before)
    # the profiles part at 24 s (the old end of step 1): resumed from the chunk end before
    assert at == 20.0
    resumed = again.run(float(longer.time[-1]))
    fresh = simulate(system, longer, float(longer.time[-1]))
    assert np.array_equal(resumed.time, fresh.time)
    for name in ("table_speed", "table_position", "screw_speed", "screw_current"):
        assert np.array_equal(resumed[name], fresh[name]), name
    for key in ("steps", "rejected_steps", "rhs_evaluations"):
        assert resumed.solver_stats[key] == fresh.solver_stats[key]


def test_nothing_is_resumed_from_another_system_or_a_profile_that_differs_at_once() -> None:
    params = fd.preset("wang2021")
    system = DriveSystem(params, "cdfs", 0.4)
    first, _ = _staircase(SPEEDS, [12.0, 12.0, 12.0], 0.0, 0.0)
    before = Simulation(system, first)
    before.keep_checkpoints()
    before.run(float(first.time[-1]))
    other = Simulation(DriveSystem(params, "cdfs", 0.3), first)
    assert other.resumable_from(before) == 0.0
    lower, _ = _staircase(SPEEDS * 0.9, [12.0, 12.0, 12.0], 0.0, 0.0)
    assert Simulation(system, lower).resumable_from(before) == 0.0


def test_a_continued_runs_states_are_joined_column_by_column_when_read() -> None:
    """A run continued past two DENSE_CHUNK ends keeps its states as parts
    (``Run.defer_states``); each state read is the one-shot run's, bit for bit, and so is the
    whole Dataset."""
    from feeddrive.engine.simulate import DENSE_CHUNK

    system = DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    profile = fd.ConstantSpeed(1.2e-3, ramp_time=0.1)
    sim = Simulation(system, profile)
    sim.run(6.0)
    continued = sim.run(2.5 * DENSE_CHUNK)
    fresh = simulate(system, profile, 2.5 * DENSE_CHUNK)
    run = continued._run
    assert run is not None and run._state_parts is not None and len(run._state_parts) == 3
    assert not run._state_columns  # nothing joined before a signal is read
    assert np.array_equal(continued["table_speed"], fresh["table_speed"])
    assert list(run._state_columns) == [[s.name for s in run.model.states].index(
        "table_speed")]  # that column alone
    for name in fresh.signal_names():
        assert np.array_equal(continued[name], fresh[name]), name
    # the auxiliary signals (continuous loops: computed from every state) joined the parts
    # once, and the states are read from that array since
    assert run._state_parts is None and run.y.shape == (fresh.time.size, len(run.model.states))
    assert continued.dataset.equals(fresh.dataset)


def test_a_finished_run_and_its_simulation_are_freed_without_the_cyclic_collector() -> None:
    """No reference cycle between a Simulation, its chunks and its Result: with the cyclic
    garbage collector off, dropping the last references frees them (a step-down search keeps
    ≈ 20 staircase runs; in cycles their output arrays waited for Python's next cyclic
    collection, 621 MB at the running CDFS search's peak against 255 MB freed at once)."""
    import gc
    import weakref

    system = DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    first, _ = _staircase(SPEEDS, [12.0, 12.0, 12.0], 0.0, 0.0)
    longer, _ = _staircase(SPEEDS, [12.0, 24.0, 12.0], 0.0, 0.0)
    was_enabled = gc.isenabled()
    gc.collect()
    gc.disable()
    try:
        before = Simulation(system, first)
        before.keep_checkpoints()
        r1 = before.run(float(first.time[-1]))
        again = Simulation(system, longer)
        again.keep_checkpoints()
        assert again.resume(before) == 20.0
        r2 = again.run(float(longer.time[-1]))
        for r in (r1, r2):  # a state, and the auxiliary signals evaluated when read
            for name in ("table_speed", "guide_friction"):
                assert np.all(np.isfinite(r[name])), name
        probes = [weakref.ref(x) for x in (before, again, r1, r2, r1.time, r2.time)]
        del before, again, r1, r2, r
        assert [p() for p in probes] == [None] * len(probes)
    finally:
        if was_enabled:
            gc.enable()
