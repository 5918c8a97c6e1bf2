"""Issue 35 item 3 inside the creep search and ``reproduce``: the integration error written
beside a critical speed is the *shadow* estimate of the trials that decide it — each run again
with every tolerance ``SHADOW_FACTOR`` times tighter once the search is done
(:func:`feeddrive.analysis.critical.critical_speed_from_rest`, ``error_estimate=True``).

Checked against truths feeddrive did not make: scipy's Radau on the plain-Python model
(``reference/make_radau_reference.py``) for the trials that decide the ``reproduce`` report's
critical speeds and band edges, and the stored Radau references of three stick-slip runs
(``reference/cases.py``). Measured 2026-12-06: the shadow over the true table-speed error
0.85–1.0 on the deciding trials at ``accuracy`` 1 and 0.1 (0.91–1.0 against the tighter
references of ``reference.cases.DECIDING_SETTINGS``, session 21: the DDFS trial's
reference had been 1.2e-10 m/s off on another CPU, four times the run's error), 0.89–1.1 on the
stick-slip runs at ``accuracy`` 1 (whose stored references, rtol 1e-10, carry up to 9e-10 m/s
themselves: against a Radau at rtol 1e-12 the shadow is 0.83–1.0 at ``accuracy`` 1 … 0.01) —
the embedded estimate it replaced there was 6.1–13 000× (test_accuracy_embedded.py). What the
estimate costs a search is measured, not tested (benchmarks/README.md).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
for folder in (ROOT, Path(__file__).resolve().parent):
    if str(folder) not in sys.path:
        sys.path.insert(0, str(folder))

from reference.cases import RADAU_CASES  # noqa: E402
from test_accuracy_embedded import DECIDING, _trial_profile, deciding_reference  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.analysis.critical import (  # noqa: E402
    creep_trial,
    critical_speed_from_rest,
    deciding_trials,
    format_integration_error,
)
from feeddrive.engine.error_estimate import SHADOW_FACTOR, SHADOW_RATIO, tightened  # noqa: E402
from feeddrive.engine.simulate import Simulation  # noqa: E402
from feeddrive.parameters import ParameterError  # noqa: E402


@pytest.mark.slow
@pytest.mark.parametrize("accuracy", [1.0, 0.1])
@pytest.mark.parametrize("trial", DECIDING, ids=[f"{t[0]}-{t[1]}" for t in DECIDING])
def test_the_shadow_of_a_deciding_trial_is_within_its_stated_range(
        trial: tuple[str, float, float, float], accuracy: float) -> None:
    drive, speed, nut, duration = trial
    system = fd.DriveSystem(fd.preset("wang2021"), drive, 0.4)
    options = fd.SolverOptions(accuracy=accuracy)
    judged = creep_trial(system, speed * 1e-3, nut_speed=nut * 1e-3, options=options,
                         error_estimate=True)
    assert judged.duration == duration  # the trial the report's search decides on
    run = Simulation(system, _trial_profile(speed, nut), options).run(duration)
    true = float(np.max(np.abs(run["table_speed"] - deciding_reference(trial))))
    low, high = SHADOW_RATIO
    assert judged.speed_error is not None
    assert low <= judged.speed_error / true <= high, judged.speed_error / true


@pytest.mark.parametrize("case", RADAU_CASES, ids=[c.name for c in RADAU_CASES])
def test_the_shadow_of_a_stick_slip_run_is_within_its_stated_range(case: object) -> None:
    ref = np.load(ROOT / "tests" / "data" / f"radau_{case.name}.npz")  # type: ignore[attr-defined]
    r = fd.simulate(fd.DriveSystem(case.parameters(), case.drive, 0.4),  # type: ignore[attr-defined]
                    case.profile(), case.duration,  # type: ignore[attr-defined]
                    options=fd.SolverOptions(output_interval=1e-3), error_estimate=True)
    true = float(np.max(np.abs(r["table_speed"] - ref["table_speed"])))
    shadow = r.solver_stats["error_estimate"]["signals"]["table_speed"]["absolute"]
    low, high = SHADOW_RATIO
    assert low <= shadow / true <= high, shadow / true


def test_a_search_estimates_its_deciding_trials_by_their_shadow() -> None:
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    found = critical_speed_from_rest(system, speed_range=(1.50e-3, 1.60e-3), coarse_step=5e-5,
                                     error_estimate=True)
    plain = critical_speed_from_rest(system, speed_range=(1.50e-3, 1.60e-3), coarse_step=5e-5)
    assert [(t.speed, t.kind, t.duration) for t in found.trials] == [
        (t.speed, t.kind, t.duration) for t in plain.trials]  # the runs are the same
    deciding = deciding_trials(found.trials)
    assert [t.kind for t in deciding] == ["oscillation", "smooth"]
    for t in found.trials:  # the deciding ones estimated, the others not
        assert (t.speed_error is not None) == (t in deciding)
    # each deciding trial's estimate, computed here from the two runs
    default = fd.SolverOptions()
    for t in deciding:
        profile = fd.ConstantSpeed(t.speed, 0.0, ramp_time=0.1)
        a = Simulation(system, profile, default).run(t.duration)["table_speed"]
        b = Simulation(system, profile, tightened(default)).run(t.duration)["table_speed"]
        assert t.speed_error == float(np.max(np.abs(a - b)))
    assert found.speed_error == max(t.speed_error for t in deciding)  # type: ignore[type-var]
    stored = found.to_dict()
    assert stored["speed_error_method"] == "shadow"
    low, high = SHADOW_RATIO
    assert format_integration_error(stored) == (
        f" [integration error estimated {stored['speed_error_mm_s']:.1e} mm/s (difference to "
        f"the deciding trials run {SHADOW_FACTOR:g}× tighter: {low:.2g}–{high:.2g}× the true "
        "error)]")
    assert "speed_error_method" not in plain.to_dict()
    # the embedded estimate is still there on request, carried by every trial
    carried = critical_speed_from_rest(system, speed_range=(1.50e-3, 1.60e-3),
                                       coarse_step=5e-5, error_estimate="embedded")
    assert all(t.speed_error is not None for t in carried.trials)
    assert carried.to_dict()["speed_error_method"] == "embedded"


def test_a_search_below_its_range_estimates_its_lowest_trial() -> None:
    system = fd.DriveSystem(fd.preset("wang2021"), "ddfs", 0.4)
    found = critical_speed_from_rest(system, nut_speed=16e-3, speed_range=(2e-5, 4.2e-4),
                                     error_estimate=True)
    assert found.status == "below-range"
    assert [t.speed_error is not None for t in found.trials] == [True] + [False] * (
        len(found.trials) - 1)


def test_an_estimate_it_cannot_make_is_refused_before_any_trial() -> None:
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    with pytest.raises(ParameterError, match="error_estimate"):
        critical_speed_from_rest(system, error_estimate="twice")
    # a run already at double precision's reach has no tighter shadow
    with pytest.raises(ParameterError, match="error_estimate.*tighter"):
        critical_speed_from_rest(system, options=fd.SolverOptions(rtol=5e-14),
                                 error_estimate=True)


def test_creep_at_double_precisions_reach_searches_without_an_estimate_and_says_so() -> None:
    """``--rtol`` 5e-14 is a valid setting (1e-14 … 0.1) that leaves no run 10× tighter: the
    search runs, states no integration error, and says why (text and JSON)."""
    from typer.testing import CliRunner

    from feeddrive.analysis.critical import shadow_possible
    from feeddrive.cli import app

    assert shadow_possible() and not shadow_possible(fd.SolverOptions(rtol=5e-14))
    args = ["creep", "--drive", "cdfs", "--method", "bisect", "--low", "2.9", "--high",
            "3.02", "--rtol", "5e-14"]
    res = CliRunner().invoke(app, args, terminal_width=400)
    assert res.exit_code == 0, res.output
    assert "[integration error estimated" not in res.output
    assert ("Integration error: not estimated — needs a run 10× tighter than rtol 5e-14, "
            "below 1e-14 (double precision's reach)") in res.output
    res = CliRunner().invoke(app, [*args, "--json"])
    assert res.exit_code == 0, res.output
    import json

    out = json.loads(res.output)
    assert out["integration_error"]["estimated"] is False
    assert out["integration_error"]["text"].startswith("Integration error: not estimated")
    assert "speed_error_mm_s" not in out["searches"][0]
    # at the defaults the estimate is made and no such line is printed
    res = CliRunner().invoke(app, args[:-2], terminal_width=400)
    assert res.exit_code == 0 and "not estimated" not in res.output


def test_the_help_and_the_docs_state_the_shadow_as_the_code_makes_it() -> None:
    """``creep --help`` and docs/model.md name the factor the shadow is tighter by and the
    range written beside the number, as the code has them."""
    from typer.testing import CliRunner

    from feeddrive.cli import app

    help_text = " ".join(CliRunner().invoke(app, ["creep", "--help"],
                                            terminal_width=200).output.split())
    assert f"every tolerance {SHADOW_FACTOR:g}× tighter" in help_text
    docs = " ".join((ROOT / "docs" / "model.md").read_text(encoding="utf-8").split())
    low, high = SHADOW_RATIO
    assert f"`feeddrive.engine.error_estimate.SHADOW_RATIO`, {low:.2g}–{high:.2g}" in docs
    assert f"the deciding trials run {SHADOW_FACTOR:g}× tighter: {low:.2g}–{high:.2g}×" in docs


def test_a_stored_reference_made_otherwise_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    """The deciding trials' stored Radau references are read only at the settings and
    parameters they were made with (else: regenerate, the message says how)."""
    import reference.make_radau_reference as maker

    trial = DECIDING[-1]
    assert maker.deciding_reference(trial).shape == (int(round(trial[3] / 1e-3)) + 1,)
    monkeypatch.setattr(maker, "DECIDING_SETTINGS", (1e-12, 1e-6))
    with pytest.raises(RuntimeError, match="make_radau_reference.py deciding"):
        maker.deciding_reference(trial)
    monkeypatch.undo()
    real = fd.preset
    monkeypatch.setattr(fd, "preset", lambda name: real(name).replace_path("table.mass", 21.0))
    with pytest.raises(RuntimeError, match="other parameters"):
        maker.deciding_reference(trial)
