"""Issue 35 item 2 with friction on: every method converges with ``accuracy`` against scipy
Radau on the plain-Python model (``reference/make_accuracy_reference.py``: rtol 1e-11,
absolute tolerances 1e-4 × the former fixed defaults, checked against a second run at rtol
1e-12 — what the comparison can resolve), and a stick–slip run converges on its slip instants
and period against the creeping Radau references (``reference/make_radau_reference.py``).

Smooth LuGre runs of the shipped ``wang2021`` set (table at mid-screw, 0.1-s start ramp, 3 s):
the CDFS at 2.0 mm/s and the DDFS at 0.5 mm/s with the hollow motor at 16 mm/s.
"""

from __future__ import annotations

import sys
from functools import cache
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.cases import RADAU_CASES  # noqa: E402

import feeddrive as fd  # noqa: E402

DATA = ROOT / "tests" / "data"
ACCURACIES = (1.0, 0.1, 0.01, 0.001)
METHODS = ("modal", "auto", "rodas4", "dopri5-dense", "dopri5")
SMOOTH = ("cdfs_2p0", "ddfs_0p5_vn16")
#: a comparison resolves errors down to this multiple of the reference's own (its distance
#: to the check run)
RESOLVED = 3.0


@cache
def reference(name: str) -> dict[str, np.ndarray]:
    with np.load(DATA / f"accuracy_{name}.npz") as f:
        return {k: f[k] for k in f.files}


def run(name: str, method: str, accuracy: float, *,
        error_estimate: bool = False, **options: str) -> fd.Result:
    """The run of reference ``name`` with ``method`` at ``accuracy`` (``options``: other
    :class:`~feeddrive.SolverOptions` settings, e.g. ``rosenbrock``)."""
    ref = reference(name)
    system = fd.DriveSystem(fd.preset("wang2021"), str(ref["drive"]), 0.4)
    profile = fd.ConstantSpeed(float(ref["table_speed_command"]),
                               float(ref["nut_speed_command"]))
    return fd.simulate(system, profile, float(ref["time"][-1]),
                       options=fd.SolverOptions(method=method, accuracy=accuracy, **options),
                       error_estimate=error_estimate)


def relative_errors(name: str, r: fd.Result) -> dict[str, float]:
    """Largest error against the reference over the signal's range, and the floor the
    reference resolves (same scale)."""
    ref = reference(name)
    np.testing.assert_allclose(r.time, ref["time"], rtol=0, atol=1e-12)
    out = {}
    for signal in ("table_position", "table_speed"):
        span = float(np.ptp(ref[signal]))
        out[signal] = float(np.max(np.abs(r[signal] - ref[signal]))) / span
        out[f"{signal}_floor"] = RESOLVED * float(ref[f"reference_error_{signal}"]) / span
    return out


def test_the_references_are_the_current_parameter_set() -> None:
    for name in SMOOTH:
        ref = reference(name)
        assert fd.parameters.loads(str(ref["parameters_toml"])) == fd.preset("wang2021")
        assert float(ref["rtol"]) <= 1e-11


#: ``dopri5`` (every output instant a step end) locates the friction reversals on its steps'
#: continuous extension and caps its steps at 1 ms × accuracy^(1/5) (the v1 engine's fixed
#: 1-ms cap and steps across the reversals: ``locate_reversals=False`` at accuracy 1,
#: test_engine_v1_regression).  With the fixed cap the CDFS's table speed fell only 4.2× in the
#: second decade (1.28e-7, 1.20e-8, 2.87e-9: the error where the cap binds is the cap's, deaf
#: to the tolerances).  The DDFS at 0.5/16 mm/s then fell only 4.7× (table speed 1.17e-7 →
#: 2.47e-8) and 4.2× (position 9.7e-11 → 2.3e-11) in the first decade: its largest error was
#: the ring each reversal leaves (t ≈ 0.6 s), at steps bounded by DOPRI5's stability, not by
#: the tolerances (met 12× over there).  Below accuracy 1 each step is now also capped at
#: accuracy^(1/5) × DOPRI5's stability bound 3.3/ρ (ρ: the error-weighted stiffness estimate
#: of the step before; SolverOptions.stability_share), and the DDFS's table speed falls
#: 1.17e-7, 1.92e-8, 3.11e-9, 7.6e-10 (6.1×, 6.2×, the last below the floor), its position
#: 9.7e-11, 1.8e-11, 5.2e-12 (5.3×, then below the floor), at 56 408 right-hand sides at
#: accuracy 0.1 against 58 256 without the cap (fewer rejected steps); the CDFS's table speed
#: 1.28e-7, 6.35e-9, 7.5e-10, 2.2e-10 (measured 2026-12-05).

@pytest.mark.slow
@pytest.mark.parametrize("name", SMOOTH)
@pytest.mark.parametrize("method", METHODS)
def test_smooth_lugre_runs_converge_with_accuracy(method: str, name: str) -> None:
    errs = [relative_errors(name, run(name, method, a)) for a in ACCURACIES]
    for signal in ("table_position", "table_speed"):
        series = [e[signal] for e in errs]
        floor = errs[0][f"{signal}_floor"]
        for a, b in zip(series, series[1:], strict=False):
            assert b <= a / 5.0 or b <= floor, (signal, series, floor)


@pytest.mark.parametrize("name", SMOOTH)
@pytest.mark.parametrize("method", METHODS)
def test_every_method_holds_5e_7_of_the_stroke_at_the_defaults(method: str, name: str) -> None:
    # issue 35 item 4's bound, here over 3 s against the Radau reference
    assert relative_errors(name, run(name, method, 1.0))["table_position"] <= 5e-7


@pytest.mark.slow
@pytest.mark.parametrize("name", SMOOTH)
def test_the_estimate_holds_with_friction_on(name: str) -> None:
    for accuracy in (1.0, 0.1):
        r = run(name, "modal", accuracy, error_estimate=True)
        ref = reference(name)
        for signal in ("table_position", "table_speed"):
            true = float(np.max(np.abs(r[signal] - ref[signal])))
            resolved = RESOLVED * float(ref[f"reference_error_{signal}"])
            estimate = r.solver_stats["error_estimate"]["signals"][signal]["absolute"]
            if true <= resolved:  # below what the reference resolves: only an upper bound
                assert estimate <= 3 * resolved, (signal, accuracy, estimate, resolved)
                continue
            assert 1 / 3 <= estimate / true <= 3, (signal, accuracy, estimate, true)
            low, high = r.solver_stats["error_estimate"]["ratio_to_true_error"]  # as stated
            assert low <= estimate / true <= high, (signal, accuracy, estimate, true)


def slip_instants(t: np.ndarray, v: np.ndarray, level: float) -> np.ndarray:
    """Upward crossings of ``level`` by the table speed (each slip's onset), interpolated."""
    k = np.flatnonzero((v[:-1] < level) & (v[1:] >= level))
    return t[k] + (level - v[k]) / (v[k + 1] - v[k]) * (t[k + 1] - t[k])


@pytest.mark.slow
@pytest.mark.parametrize("case", RADAU_CASES, ids=[c.name for c in RADAU_CASES])
def test_stick_slip_converges_on_its_slip_instants(case: object) -> None:
    from reference.make_radau_reference import stick_slip_figures

    ref = np.load(DATA / f"radau_{case.name}.npz")  # type: ignore[attr-defined]
    window = (float(ref["window"][0]), float(ref["window"][1]))
    level = float(np.mean(ref["table_speed"][ref["time"] >= window[0]]))
    t_ref = slip_instants(ref["time"], ref["table_speed"], level)
    errs, periods = [], []
    for accuracy in (1.0, 0.1, 0.01):
        r = fd.simulate(fd.DriveSystem(case.parameters(), case.drive, 0.4),  # type: ignore[attr-defined]
                        case.profile(), case.duration,  # type: ignore[attr-defined]
                        options=fd.SolverOptions(accuracy=accuracy))
        t = slip_instants(r.time, r["table_speed"], level)
        assert t.size == t_ref.size  # the same slips, none gained or lost
        errs.append(float(np.max(np.abs(t - t_ref))))
        periods.append(abs(stick_slip_figures(r.time, r["table_speed"], window)["period"]
                           - float(ref["period"])))
    # the slip instants converge (≥ 5× per decade, or below 1 µs: the 1-ms grid's
    # interpolation of a slip that rises 1 mm/s in ~0.5 ms resolves no finer)
    for a, b in zip(errs, errs[1:], strict=False):
        assert b <= a / 5.0 or b <= 1e-6, errs
    assert periods[-1] <= periods[0] or periods[-1] <= 1e-7, periods
