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


def test_a_failed_streamed_run_leaves_no_empty_file_to_block_a_retry(tmp_path) -> None:
    """A streamed run that failed in its first chunk left a 0-byte file, and the retry was
    refused ("exists; pass --force"); the file is removed and the message says so."""
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    out = tmp_path / "run.csv"
    with pytest.raises(SimulationError, match=f"{out} not written"):
        fd.simulate(system, fd.ConstantSpeed(2e-3), 30.0, output=out,
                    options=fd.SolverOptions(max_steps=3000))
    assert not out.exists()


def test_a_failed_error_estimate_says_which_run_failed_and_keeps_the_run() -> None:
    """The 10× tighter second run of ``error_estimate=True`` needs more steps than the run:
    at a max_steps between the two the run finished, the second run did not, and the message
    said only "maximum number of steps reached" — now it names the second run and the
    finished run is handed over with the error."""
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    alone = fd.simulate(system, fd.ConstantSpeed(2e-3), 2.0)
    steps = alone.solver_stats["steps"]
    with pytest.raises(SimulationError, match="^error estimate: the second run") as err:
        fd.simulate(system, fd.ConstantSpeed(2e-3), 2.0, error_estimate=True,
                    options=fd.SolverOptions(max_steps=steps + 10))
    kept = err.value.result  # type: ignore[attr-defined]
    assert kept.solver_stats["steps"] == steps
    assert (kept["table_speed"] == alone["table_speed"]).all()
