"""A diverging run stops early as ``unstable`` (issue 21, item 2).

Guard: with ``controller.position_gain = 400`` 1/s (50× the shipped 8) the CDFS loop diverges
within 0.3 s; a 3-s run took 20.9 M steps and 25 s and reported 2.3 m of following error.
Now the run stops when a speed state passes DIVERGENCE_SPEED_RATIO × the reference speed,
within at most twice the right-hand-side calls of a normal 3-s run (counts, not time).
"""

from __future__ import annotations

import numpy as np
import pytest

import feeddrive
from feeddrive.analysis.critical import creep_trial
from feeddrive.analysis.verdict_words import UNSTABLE
from feeddrive.engine.simulate import (
    DIVERGENCE_SPEED_RATIO,
    DriveSystem,
    Simulation,
    SolverOptions,
    divergence_bounds,
    simulate,
)
from feeddrive.model.reference import ConstantSpeed

COMMAND = 1e-3  # [m/s]


def _system(gain: float) -> DriveSystem:
    return DriveSystem(feeddrive.preset("wang2021").replace_path("controller.position_gain",
                                                                  gain), "cdfs", 0.4)


@pytest.mark.parametrize("method", ["dopri5", "auto", "modal"])
def test_diverging_run_stops_early_as_unstable(method: str) -> None:
    options = SolverOptions(method=method)
    profile = ConstantSpeed(COMMAND, 0.0, ramp_time=0.1)
    normal = simulate(_system(8.0), profile, 3.0, options=options)
    assert "diverged" not in normal.solver_stats
    assert normal.time[-1] == pytest.approx(3.0)
    wild = simulate(_system(400.0), profile, 3.0, options=options)
    stats = wild.solver_stats
    assert stats["diverged"] and 0.1 < stats["diverged_at_s"] < 1.0
    assert wild.time[-1] == pytest.approx(stats["diverged_at_s"])
    assert stats["rhs_evaluations"] <= 2 * normal.solver_stats["rhs_evaluations"]
    # the last sample is where the speed left its bound, and the verdict says so
    assert abs(wild["table_speed"][-1]) > DIVERGENCE_SPEED_RATIO * COMMAND
    assert np.all(np.isfinite(wild["table_speed"]))
    summary = wild.summary()
    assert summary["verdict"] == "unstable"


def test_diverged_run_continued_stays_diverged_and_trial_says_unstable() -> None:
    system, profile = _system(400.0), ConstantSpeed(COMMAND, 0.0, ramp_time=0.1)
    sim = Simulation(system, profile, SolverOptions(method="dopri5"))
    first = sim.run(2.0)
    again = sim.run(4.0)
    assert np.array_equal(first.time, again.time)
    trial = creep_trial(system, COMMAND, options=SolverOptions(method="dopri5"))
    assert trial.kind == UNSTABLE and trial.duration < 1.0 and not trial.creeping


def test_bounds_follow_the_command_nut_and_initial_speeds() -> None:
    params = feeddrive.preset("wang2021")
    profile = ConstantSpeed(0.5e-3, 16e-3)
    system = DriveSystem(params, "ddfs", 0.4)
    model = system.model(profile)
    bound = divergence_bounds(system, profile, model)
    table = model.index("table_speed")
    assert bound[table] == pytest.approx(DIVERGENCE_SPEED_RATIO * 16.5e-3)
    assert np.isinf(bound[model.index("table_position")])
    kicked = DriveSystem(params, "ddfs", 0.4, initial_state={"table_speed": 0.1})
    assert divergence_bounds(kicked, profile, model)[table] == pytest.approx(
        DIVERGENCE_SPEED_RATIO * 0.1)


def test_a_diverging_staircase_marks_its_steps_unstable() -> None:
    from feeddrive.analysis.critical import walk_down
    trials, simulated = walk_down(_system(400.0), [3e-3, 2e-3, 1e-3])
    assert [t.kind for t in trials] == [UNSTABLE] * 3
    assert simulated == pytest.approx(36.0)  # one run of three 12-s steps, stopped early
