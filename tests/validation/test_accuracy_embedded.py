"""Issue 35 item 3: the embedded global-error estimate (:mod:`feeddrive.solvers.global_error`),
carried along the one integration — ``simulate(..., error_estimate="embedded")``, and a creep
search's trials on request (``error_estimate="embedded"``; a search's default is the deciding
trials' shadow since 2026-12-06: test_accuracy_shadow_trials.py).

Checked against truths feeddrive did not make: the frictionless step responses' exact solution
(the hand-written matrix exponential of ``reference/linear_model.py``, as in
test_accuracy_convergence.py) and the smooth LuGre runs' scipy Radau references
(``reference/make_accuracy_reference.py``, as in test_accuracy_friction.py).

What it reaches (measured 2026-12-05, table speed, estimate over true error; every case in
``test_the_ratio_stated_beside_the_number_is_the_measured_one``): on the frictionless steps
0.16–0.20 at the defaults (``modal``, ``dopri5-dense``, ``auto``; ``rodas4`` 0.64–0.81),
0.55–0.71 at ``accuracy`` 0.01 (``rodas4`` 4–5); on the smooth LuGre runs with ``modal`` at
the defaults 6.3 (CDFS 2 mm/s) and 186 (DDFS 0.5/16 mm/s), 595 with ``dopri5-dense``, 9–70
with ``rodas4``; on the stick-slip runs with Radau references (``reference/cases.py``,
``RADAU_CASES``; measured 2026-12-06) 2.2–259, ``rodas4`` 10–356
(``test_the_stated_ratio_covers_stick_slip_runs``); on the trials that decide the
``reproduce`` report's critical speeds and band edges 6.1–702 (CDFS) and 1.3e4 (DDFS) with
``modal`` at the defaults, up to 6.5e4 (``modal``) and 1.6e5 (``rodas4``) over the accuracies
(``test_the_stated_ratio_covers_the_reports_deciding_trials``; the range stated until then,
600, did not hold there).  Not the factor 3 of the shadow estimate (test_error_estimate.py).
The causes, separated (benchmarks/embedded_estimate_causes.py, benchmarks/README.md; docs/model.md):

1. the 5-ms grid: the CDFS table mode (1276 rad/s) turns 6.4 rad in an interval, and the local
   errors summed over it cancel — carried step by step the same local errors give 1.6× (CDFS)
   and 1.9× (DDFS) the true error, on the grid 0.17× and 0.16× (the frictionless
   underestimate);
2. the Jacobian taken at rest and kept 500 steps through the start: on the LuGre runs alone
   the difference between 6.6× and 0.73× (CDFS), 188× and 3.5× (DDFS) (the LuGre
   overestimate);
3. the embedded lower-order solution's local error carried instead of the propagated
   solution's: 1.6–1.9× at the defaults, 5× at ``accuracy`` 0.01 (RODAS4's 3rd-order: up to
   60×); with the propagated solution's true local errors the carried estimate is 0.98–1.01×;
4. the dense output's interpolation error between the steps: 12–14 % of the true error at the
   1-ms outputs — not a cause that matters here.

Curing 1 and 2 (commit 2b26ba4, reverted in the next) gave 0.72–60× (``modal`` at the defaults
0.73–3.5×) at ×1.26–2.63 the searches' CPU, against the 10 % allowed; 3 needs more evaluations
of the right-hand side.  So the strict xfail stays.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

ROOT = Path(__file__).resolve().parents[2]
for folder in (ROOT, Path(__file__).resolve().parent):
    if str(folder) not in sys.path:
        sys.path.insert(0, str(folder))

from reference.cases import DECIDING, RADAU_CASES, Case  # noqa: E402
from reference.cases import trial_profile as _trial_profile  # noqa: E402
from reference.make_radau_reference import (  # noqa: E402
    deciding_reference as stored_deciding_reference,
)
from reference.scipy_model import STATE_NAMES  # noqa: E402
from test_accuracy_convergence import (  # noqa: E402
    DURATION,
    NUT_SPEED,
    augmented_matrix,
    equivalent_stiffness,
    exact_response,
    frictionless,
)
from test_accuracy_friction import reference  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.analysis.critical import (  # noqa: E402
    CreepTrial,
    CriticalSpeed,
    creep_trial,
    format_integration_error,
)
from feeddrive.analysis.cycle_verdict import VerdictRule  # noqa: E402
from feeddrive.engine.simulate import Simulation  # noqa: E402
from feeddrive.solvers import global_error, switching  # noqa: E402


def embedded(system: fd.DriveSystem, profile: fd.ConstantSpeed, duration: float,
             options: fd.SolverOptions | None = None) -> fd.Result:
    return Simulation(system, profile, options, embedded_estimate=True).run(duration)


def ratio(r: fd.Result, truth: np.ndarray) -> float:
    """The run's embedded table-speed estimate over its largest distance to ``truth`` [m/s] on
    the output grid."""
    true = float(np.max(np.abs(r["table_speed"] - truth)))
    estimate = r.solver_stats["embedded_error_estimate"]["signals"]["table_speed"]["absolute"]
    return float(estimate / true)


def step_ratio(method: str, drive: str, accuracy: float = 1.0) -> float:
    """Embedded table-speed estimate over the true error, 1 mm/s velocity step."""
    params = frictionless()
    nut = NUT_SPEED if drive == "ddfs" else 0.0
    profile = fd.ConstantSpeed(table_speed=1e-3, nut_speed=nut, ramp_time=0.0)
    A = augmented_matrix(params, drive, 1e-3, nut, equivalent_stiffness(params, 0.4))
    r = embedded(fd.DriveSystem(params, drive, 0.4), profile, DURATION,
                 fd.SolverOptions(method=method, accuracy=accuracy, output_interval=1e-3))
    exact = exact_response(A, r.time)[:, STATE_NAMES.index("table_speed")]
    return ratio(r, exact)


def lugre_ratio(name: str, method: str = "modal", accuracy: float = 1.0) -> float:
    """Embedded table-speed estimate over the distance to the Radau reference, smooth LuGre
    run ``name`` (``reference/make_accuracy_reference.py``)."""
    ref = reference(name)
    system = fd.DriveSystem(fd.preset("wang2021"), str(ref["drive"]), 0.4)
    profile = fd.ConstantSpeed(float(ref["table_speed_command"]),
                               float(ref["nut_speed_command"]))
    r = embedded(system, profile, float(ref["time"][-1]),
                 fd.SolverOptions(method=method, accuracy=accuracy))
    np.testing.assert_allclose(r.time, ref["time"], rtol=0, atol=1e-12)
    return ratio(r, ref["table_speed"])


@pytest.mark.parametrize("accuracy", [1.0, 0.1, 0.01])
@pytest.mark.parametrize("method", ["modal", "dopri5-dense", "rodas4", "auto"])
def test_the_ratio_stated_beside_the_number_is_the_measured_one(method: str,
                                                               accuracy: float) -> None:
    # what format_integration_error writes beside a critical speed (MEASURED_RATIO) covers
    # every case measured here, so the label says what the number is worth
    low, high = global_error.MEASURED_RATIO
    ratios = [step_ratio(method, drive, accuracy) for drive in ("cdfs", "ddfs")]
    ratios += [lugre_ratio(name, method, accuracy) for name in ("cdfs_2p0", "ddfs_0p5_vn16")]
    assert all(low <= r <= high for r in ratios), ratios


def creep_ratio(case: Case, method: str, accuracy: float) -> float:
    """Embedded table-speed estimate over the distance to the Radau reference of a stick-slip
    run (``tests/data/radau_<case>.npz``: rtol 1e-10, ``reference/make_radau_reference.py``)."""
    ref = np.load(ROOT / "tests" / "data" / f"radau_{case.name}.npz")
    r = embedded(fd.DriveSystem(case.parameters(), case.drive, 0.4), case.profile(),
                 case.duration, fd.SolverOptions(method=method, accuracy=accuracy,
                                                 output_interval=1e-3))
    np.testing.assert_allclose(r.time, ref["time"], rtol=0, atol=1e-12)
    return ratio(r, ref["table_speed"])


@pytest.mark.parametrize("accuracy", [1.0, 0.1, 0.01])
@pytest.mark.parametrize("method", ["modal", "dopri5-dense", "rodas4", "auto"])
def test_the_stated_ratio_covers_stick_slip_runs(method: str, accuracy: float) -> None:
    # the trials that decide a critical speed are stick-slip ones: the range written beside
    # it covers them too (measured 2026-12-06: 2.2-259, rodas4 10-356; at accuracy 0.01 the
    # reference's own rtol 1e-10 is part of the "true" error, so those ratios are low)
    low, high = global_error.MEASURED_RATIO
    ratios = [creep_ratio(case, method, accuracy) for case in RADAU_CASES]
    assert all(low <= r <= high for r in ratios), ratios


def deciding_reference(trial: tuple[str, float, float, float]) -> np.ndarray:
    """Table speed [m/s] of a deciding trial by scipy's Radau on the plain-Python model, on the
    1-ms grid, at :data:`reference.cases.DECIDING_SETTINGS` — stored
    (tests/data/radau_deciding_trials.npz, ``reference/make_radau_reference.py deciding``:
    computed here they cost 180 s of one worker on a slow host)."""
    return stored_deciding_reference(trial)


def deciding_ratio(trial: tuple[str, float, float, float], method: str,
                   accuracy: float) -> float:
    """Embedded table-speed estimate over the true error of a deciding trial as the search runs
    it (``creep_trial``'s profile and run)."""
    drive, speed, nut, duration = trial
    system = fd.DriveSystem(fd.preset("wang2021"), drive, 0.4)
    r = embedded(system, _trial_profile(speed, nut), duration,
                 fd.SolverOptions(method=method, accuracy=accuracy))
    return ratio(r, deciding_reference(trial))


@pytest.mark.slow
@pytest.mark.parametrize("accuracy", [1.0, 0.1, 0.01])
@pytest.mark.parametrize("method", ["modal", "dopri5-dense", "rodas4", "auto"])
def test_the_stated_ratio_covers_the_reports_deciding_trials(method: str,
                                                             accuracy: float) -> None:
    # the range written beside the report's critical speeds holds for the trials that decide
    # them (measured 2026-12-06, modal at the defaults: CDFS 6.1 at 1.0 mm/s, 54 at 1.42, 702
    # at 1.55 — above the 600 stated until then —, 265 at 1.56; DDFS 1.3e4; the widest 1.6e5,
    # rodas4 at 1.42)
    low, high = global_error.MEASURED_RATIO
    ratios = [deciding_ratio(trial, method, accuracy) for trial in DECIDING]
    assert all(low <= r <= high for r in ratios), ratios


@pytest.mark.parametrize(("drive", "speed", "nut"), [("cdfs", 2e-3, 0.0),
                                                      ("ddfs", 0.5e-3, 16e-3)])
def test_a_run_is_bit_identical_with_the_estimate(drive: str, speed: float,
                                                   nut: float) -> None:
    system = fd.DriveSystem(fd.preset("wang2021"), drive, 0.4)
    profile = fd.ConstantSpeed(speed, nut)
    plain = Simulation(system, profile).run(1.0)
    carried = embedded(system, profile, 1.0)
    for name in STATE_NAMES:
        assert np.array_equal(plain[name], carried[name]), name
    a, b = plain.solver_stats, carried.solver_stats
    assert (a["steps"], a["rejected_steps"]) == (b["steps"], b["rejected_steps"])
    assert "embedded_error_estimate" not in a
    # the estimate's own Jacobians: counted, and only those
    assert b["rhs_evaluations"] > a["rhs_evaluations"]


def test_the_exponential_is_scipys() -> None:
    # a stiff, badly scaled matrix (states in m, m/s and A): scaled by those units
    rng = np.random.default_rng(7)
    scale = np.array([1e-10, 1e-8, 1e-6, 1e-10])
    B = rng.normal(size=(4, 4)) * 50.0 - np.diag([2e3, 10.0, 5e4, 1.0])
    J = B * scale[:, None] / scale[None, :]
    Phi, W1, W2 = (np.zeros((4, 4)) for _ in range(3))
    global_error.exponential(J, 5e-3, Phi, W1, W2, scale)
    expected = scipy.linalg.expm(5e-3 * J)
    scaled = (Phi - expected) * scale[None, :] / scale[:, None]
    assert np.max(np.abs(scaled)) <= 1e-6 * max(1.0, np.max(np.abs(
        expected * scale[None, :] / scale[:, None])))


def test_advance_sums_within_an_interval_and_carries_at_its_end() -> None:
    n, H = 2, global_error.INTERVAL
    Phi = np.array([[0.5, 0.0], [1.0, 2.0]])
    memory = switching.new_memory(n, error_estimate=True)
    at = switching.MEMORY_SCALARS + n + n * n
    memory[at:at + n] = [1.0, -1.0]  # E
    w = np.zeros(n)
    global_error.advance(0.2 * H, 0.6 * H, Phi, memory, at, H, w, np.array([0.1, 0.2]))
    assert memory[at:at + n].tolist() == [1.0, -1.0]  # inside the interval: summed only
    assert memory[at + 2 * n:at + 3 * n].tolist() == [0.1, 0.2]
    global_error.advance(0.6 * H, 2.5 * H, Phi, memory, at, H, w, np.array([0.3, 0.0]))
    first = Phi @ np.array([1.4, -0.8])  # at H: E + Σδ carried
    np.testing.assert_allclose(memory[at:at + n], Phi @ first, rtol=1e-15)  # and at 2H
    assert memory[at + 2 * n:at + 3 * n].tolist() == [0.0, 0.0]
    E, largest = switching.error_estimate(memory, n)  # type: ignore[misc]
    np.testing.assert_allclose(largest, np.maximum([1.1, 0.8], np.abs(Phi @ first)))
    assert switching.error_estimate(switching.new_memory(n), n) is None


@pytest.mark.parametrize("method", ["modal", "rodas4"])
@pytest.mark.parametrize("drive", ["cdfs", "ddfs"])
def test_the_estimate_is_within_a_factor_10_of_the_exact_step_response(method: str,
                                                                       drive: str) -> None:
    # measured 2026-12-05: modal 0.16 (CDFS), 0.20 (DDFS); rodas4 0.81, 0.64
    assert 0.1 <= step_ratio(method, drive) <= 10.0


@pytest.mark.xfail(strict=True, reason="the embedded estimate misses the factor 3 of the "
                   "shadow estimate: 0.16 of the true error here, the 5-ms grid's phase loss "
                   "(see the module)")
def test_the_estimate_is_within_a_factor_3_like_the_shadow() -> None:
    assert 1 / 3 <= step_ratio("modal", "cdfs") <= 3


@pytest.mark.parametrize("name", ["cdfs_2p0", "ddfs_0p5_vn16"])
def test_with_friction_on_it_is_above_the_true_error(name: str) -> None:
    # measured with modal at the defaults: 6.3× (CDFS), 186× (DDFS) the Radau distance
    assert 1.0 < lugre_ratio(name) <= 1e3


def test_a_creep_trial_carries_it_and_the_search_states_it() -> None:
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    rule = VerdictRule(initial_duration=6.0, max_duration=12.0)
    plain = creep_trial(system, 2e-3, rule=rule)
    carried = creep_trial(system, 2e-3, rule=rule, error_estimate="embedded")
    assert plain.speed_error is None and "speed_error_mm_s" not in plain.to_dict()
    assert carried.kind == plain.kind and carried.ripple_ratio == plain.ripple_ratio
    assert carried.speed_error is not None and 0.0 < carried.speed_error < 1e-3 * 2e-3
    assert carried.to_dict()["speed_error_mm_s"] == pytest.approx(1e3 * carried.speed_error)
    below = CreepTrial(speed=1.5e-3, kind="stick-slip", ripple_ratio=1.0, stick_fraction=0.5,
                       stick_slip_frequency=1.0, speed_error=3e-8)
    search = CriticalSpeed(drive="cdfs", table_position=0.4, nut_speed=0.0, start="rest",
                           critical_speed=2e-3, status="found", resolution=1e-5,
                           speed_range=(1e-3, 3e-3), trials=(below, carried),
                           error_estimate="embedded")
    assert search.speed_error == max(3e-8, carried.speed_error)
    stored = search.to_dict()
    assert stored["speed_error_mm_s"] == pytest.approx(1e3 * search.speed_error)
    assert stored["speed_error_method"] == "embedded"
    # what the number is: an estimate (never "≤", it is no bound) with its measured ratio
    low, high = global_error.MEASURED_RATIO
    label = format_integration_error(stored)
    assert label == (f" [integration error estimated {stored['speed_error_mm_s']:.1e} mm/s "
                     f"(embedded estimate: {low:.2g}–{high:,.0f}× the true error)]".replace(
                         ",", " "))
    assert "≤" not in label and "<" not in label
    assert format_integration_error({"critical_speed_mm_s": 1.56}) == ""
    # a search whose deciding trial carried none states none
    bare = CriticalSpeed(**{**search.__dict__, "trials": (plain, below)})
    assert bare.speed_error is None and "speed_error_mm_s" not in bare.to_dict()
    assert math.isfinite(carried.speed_error)


def test_simulate_states_it_in_the_summary_and_refuses_what_it_cannot() -> None:
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    r = fd.simulate(system, fd.ConstantSpeed(2e-3), 0.5, error_estimate="embedded")
    entry = r.solver_stats["error_estimate"]
    assert entry["method"] == r.solver_stats["embedded_error_estimate"]["method"]
    # how it was made and what it is worth, from the estimator's own constants
    low, high = global_error.MEASURED_RATIO
    assert f"summed per {1e3 * global_error.INTERVAL:g}-ms interval" in entry["method"]
    assert f"J taken every {global_error.REFRESH_STEPS} steps" in entry["method"]
    assert f"{low:g}–{high:,.0f}× the true error".replace(",", " ") in entry["method"]
    assert set(entry["signals"]) == set(STATE_NAMES)
    speed = entry["signals"]["table_speed"]
    assert speed["relative"] == pytest.approx(speed["absolute"] / np.ptp(r["table_speed"]))
    assert r.dataset["table_speed"].attrs["integration_error_estimate"] == speed["absolute"]
    with pytest.raises(fd.parameters.ParameterError, match="error_estimate.*dense-output"):
        fd.simulate(system, fd.ConstantSpeed(2e-3), 0.1,
                    options=fd.SolverOptions(method="dopri5"), error_estimate="embedded")
    with pytest.raises(fd.parameters.ParameterError, match="error_estimate.*'embedded'"):
        fd.simulate(system, fd.ConstantSpeed(2e-3), 0.1, error_estimate="cheap")
