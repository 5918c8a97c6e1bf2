"""A failed integration says what to do about its own cause (an outside check, 2026-12-06: a
step-size underflow, from a tolerance of 5e-324 A, advised raising --max-steps)."""

from __future__ import annotations

import pytest

import feeddrive as fd
from feeddrive.engine import simulate as simulate_module
from feeddrive.engine.simulate import FAILURE_ADVICE, SimulationError
from feeddrive.solvers import dopri5


def test_every_failure_status_has_its_own_advice() -> None:
    failures = {dopri5.STATUS_MAX_STEPS, dopri5.STATUS_STEP_UNDERFLOW, dopri5.STATUS_NON_FINITE}
    assert set(FAILURE_ADVICE) == failures
    assert len(set(FAILURE_ADVICE.values())) == len(failures)
    assert "--max-steps" in FAILURE_ADVICE[dopri5.STATUS_MAX_STEPS]
    assert "--max-steps" not in FAILURE_ADVICE[dopri5.STATUS_STEP_UNDERFLOW]
    assert "--max-steps" not in FAILURE_ADVICE[dopri5.STATUS_NON_FINITE]


def test_a_run_out_of_steps_says_so_and_how_to_go_on() -> None:
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    with pytest.raises(SimulationError) as err:
        fd.simulate(system, fd.ConstantSpeed(2e-3), 0.2, options=fd.SolverOptions(max_steps=50))
    text = str(err.value)
    assert dopri5.STATUS_MESSAGES[dopri5.STATUS_MAX_STEPS] in text
    assert text.endswith(FAILURE_ADVICE[dopri5.STATUS_MAX_STEPS])


def test_a_step_size_underflow_does_not_advise_more_steps(monkeypatch) -> None:
    """The driver's status as the run ends is what picks the advice: a run made to end with
    an underflow (the chunk's stats rewritten) says to loosen the tolerances."""
    original = simulate_module._Chunks._call

    def underflow(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        t, yy, aa, stats = original(self, *args, **kwargs)
        stats = stats.copy()
        stats[0] = dopri5.STATUS_STEP_UNDERFLOW
        return t, yy, aa, stats

    monkeypatch.setattr(simulate_module._Chunks, "_call", underflow)
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    with pytest.raises(SimulationError) as err:
        fd.simulate(system, fd.ConstantSpeed(2e-3), 0.2)
    text = str(err.value)
    assert dopri5.STATUS_MESSAGES[dopri5.STATUS_STEP_UNDERFLOW] in text
    assert "--max-steps" not in text and "--accuracy" in text
