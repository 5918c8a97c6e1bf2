"""Arguments of the fit, the trace analysis and their results an outside check found
unchecked or unreadable (2026-12-07): each is now a ParameterError naming the argument, the
value and the unit before any simulation, and the results print in a line or a few.

No test here simulates a drive for longer than 0.3 s: a fit is refused before its first
simulation (``simulate_experiment`` is replaced by one that fails the test)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import feeddrive as fd
import feeddrive.analysis.fit as fitmod
from feeddrive.analysis.fit import (
    Experiment,
    FitResult,
    ParameterEstimate,
    fit_drive,
    synthetic_experiment,
)
from feeddrive.analysis.positioning import positioning_test
from feeddrive.analysis.static_fit import fit_static
from feeddrive.analysis.trace import analyze_trace, estimate_speed
from feeddrive.parameters import ParameterError

P = fd.preset("wang2021")
KI = "controller.velocity_integral_gain"


@pytest.fixture
def no_simulation(monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse(task: object) -> dict[str, object]:
        raise AssertionError("a simulation ran")

    monkeypatch.setattr(fitmod, "simulate_experiment", refuse)


def _record(**changes: object) -> Experiment:
    t = np.arange(0.0, 1.0, 1e-3)
    v = np.full(t.size, 1e-3)
    fields: dict[str, object] = {
        "source": "x.csv", "time": t, "signals": {"table_position": v * t},
        "reference_time": t, "table_speed": v, "noise": {"table_position": 1e-8}}
    fields.update(changes)
    return Experiment(**fields)  # type: ignore[arg-type]


def _refused(err: pytest.ExceptionInfo[ParameterError], field: str, message: str) -> None:
    assert err.value.field == field
    assert re.match(message, err.value.message), err.value.message
    assert "\n" not in str(err.value)


# ------------------------------------------------------------------ synthetic_experiment


@pytest.mark.parametrize(("kwargs", "field", "message"), [
    ({"current_noise": -0.01}, "current_noise", r"expected a finite number ≥ 0 \[-"),
    ({"current_noise": math.nan}, "current_noise", r"expected a finite number ≥ 0 \[-"),
    ({"current_noise": math.inf}, "current_noise", r"expected a finite number ≥ 0 \[-"),
    ({"position_quantum": -1e-6}, "position_quantum", r"expected a finite number ≥ 0 \[m\]"),
    ({"position_quantum": math.nan}, "position_quantum", r"expected a finite number ≥ 0 \[m\]"),
    ({"seed": -1}, "seed", r"expected a whole number ≥ 0 \[-\]"),
    ({"seed": 1.5}, "seed", r"expected a whole number ≥ 0 \[-\]"),
    ({"record_start": 10.0}, "record_start", r"expected a start before the record's end, "
                                             r"0 ≤ record_start < duration = 0.3 \[s\]"),
    ({"record_start": 0.2999}, "record_start", r"expected a start at least 8 samples before "
                                               r"the end"),
])
def test_synthetic_experiment_refuses_bad_noise_seed_and_start(kwargs: dict, field: str,
                                                               message: str) -> None:
    """-0.01 and a quantum of -1 µm were accepted (the quantum silently ignored), NaN made the
    whole current NaN, seed -1 was numpy's "expected non-negative integer", a start past the
    end an empty record that the fit took to `IndexError: index -1`."""
    with pytest.raises(ParameterError) as err:
        synthetic_experiment(P, 1e-3, 0.3, **kwargs)
    _refused(err, field, message)


# ------------------------------------------------------------------ Experiment


@pytest.mark.parametrize(("changes", "field", "message"), [
    ({"signals": {"screw_current": np.r_[np.ones(3), np.full(997, np.nan)]}},
     "signals.screw_current", r"expected finite samples \[A\]; index 3 of 1000 is not"),
    ({"signals": {"table_position": np.full(1000, np.nan)}},
     "signals.table_position", r"expected finite samples \[m\]; index 0 of 1000"),
    ({"table_speed": np.r_[np.full(999, 1e-3), np.inf]},
     "table_speed", r"expected finite samples \[m/s\]; index 999"),
    ({"signals": {"bogus": np.ones(1000)}}, "signals.bogus",
     r"expected a measurable signal, one of table_position, table_speed, screw_current"),
    ({"signals": {"table_position": np.ones(999)}}, "signals.table_position",
     r"expected 1000 samples, one per sample time \[m\]; it has 999"),
    ({"time": np.zeros(0), "signals": {}}, "time", r"expected at least 2 sample times \[s\]"),
])
def test_an_experiment_refuses_samples_a_fit_cannot_use(changes: dict, field: str,
                                                        message: str) -> None:
    """An all-NaN current was fitted to "stderr inf, no effect on the simulated traces (zero
    Jacobian column)" with the NaN never named; an unknown signal was `KeyError: 'bogus'`."""
    with pytest.raises(ParameterError) as err:
        _record(**changes)
    _refused(err, field, message)
    assert err.value.source == "x.csv"


# ------------------------------------------------------------------ fit_drive


@pytest.mark.parametrize(("call", "field", "message"), [
    (lambda: fit_drive("wang2021", [_record()], [KI]),  # type: ignore[arg-type]
     "base", r"expected DriveParameters, e\.g\. fd\.preset\(\"wang2021\"\)"),
    (lambda: fit_drive(P, [_record()], [KI], bounds={KI: 5}),  # type: ignore[dict-item]
     f"bounds.{KI}", r"expected a \(low, high\) pair, low < high \[A/m"),
    (lambda: fit_drive(P, [_record()], [KI], bounds={KI: (1e4, 1.0)}),
     f"bounds.{KI}", r"expected a \(low, high\) pair, low < high \[A/m"),
    (lambda: fit_drive(P, [_record()], [KI], bounds={"table.mass": (1.0, 2.0)}),
     "bounds.table.mass", r"expected the path of a free parameter"),
    (lambda: fit_drive(P, [_record(noise={})], [KI]),
     "experiments[0].noise.table_position", r"expected the noise σ of every fitted signal \[m\]"),
    (lambda: fit_drive(P, [_record(noise={"table_position": math.nan})], [KI]),
     "experiments[0].noise.table_position", r"expected a finite noise σ > 0 \[m\]"),
    (lambda: fit_drive(P, [_record(signals={})], [KI]),
     "experiments[0].signals", r"expected at least one measured signal"),
])
def test_fit_drive_refuses_bad_arguments_before_simulating(no_simulation: None, call: object,
                                                           field: str, message: str) -> None:
    """A preset's name said "'controller' is not a field of the parameter set", bounds of 5
    "cannot unpack non-iterable int", a missing noise σ `KeyError`, a NaN one a NaN fit."""
    with pytest.raises(ParameterError) as err:
        call()  # type: ignore[operator]
    _refused(err, field, message)


def test_fit_drive_refuses_a_sample_made_nan_after_the_record(no_simulation: None) -> None:
    record = _record(signals={"table_position": np.linspace(0.0, 1e-3, 1000)})
    record.signals["table_position"][5] = np.nan
    with pytest.raises(ParameterError) as err:
        fit_drive(P, [record], [KI])
    _refused(err, "signals.table_position", r"expected finite samples \[m\]; index 5 of 1000")


# ------------------------------------------------------------------ analyze_trace


T = np.linspace(0.0, 2.0, 2001)
X = 1e-3 * T - 0.8e-3 / (2 * np.pi * 2.0) * np.cos(2 * np.pi * 2.0 * T)


@pytest.mark.parametrize(("kwargs", "field", "message"), [
    ({"smoothing_time": 0.0}, "smoothing_time", r"expected a finite time > 0 \[s\]"),
    ({"smoothing_time": 1e300}, "smoothing_time",
     r"expected a window not longer than the trace, at most 2.001 s \[s\]"),
    ({"window": 2.5}, "window", r"expected an odd whole number of samples > polyorder "
                                r"\[samples\]"),
    ({"thresholds": {"stick_level": 0.1}}, "thresholds", r"expected a CreepThresholds"),
    # the shared speed check's wording (validation.check_speed), as the analyses and profiles
    ({"command_speed": 1000.0}, "command_speed", r"expected \|speed\| ≤ 100 \[m/s\]"),
    ({"min_step": -1.0}, "min_step", r"expected a finite value > 0 \[m/s\]"),
])
def test_analyze_trace_refuses_bad_settings(kwargs: dict, field: str, message: str) -> None:
    """0 s was taken as the default window while -1 was refused; 1e300 s printed a
    300-digit window; 2.5 samples was scipy's TypeError; a dict of thresholds "'dict' object
    has no attribute 'stick_level'"; 1000 m/s was judged."""
    kwargs = {"command_speed": 1e-3, **kwargs}
    with pytest.raises(ParameterError) as err:
        analyze_trace(T, X, **kwargs)
    _refused(err, field, message)
    assert len(str(err.value)) < 400


@pytest.mark.parametrize("polyorder", [-1, 0, 1.5])
def test_estimate_speed_refuses_an_order_with_no_derivative(polyorder: object) -> None:
    """-1 was scipy's "expected deg >= 0"; 0 a speed of zero everywhere."""
    with pytest.raises(ParameterError) as err:
        estimate_speed(T, X, polyorder=polyorder)  # type: ignore[arg-type]
    _refused(err, "polyorder", r"expected a whole number ≥ 1 .*\[-\]")


def test_a_command_in_mm_s_given_as_m_s_is_noted() -> None:
    """1 m/s given for a 1-mm/s trace was "creeping" without a word."""
    t = np.linspace(0.0, 1.0, 1001)
    result = analyze_trace(t, 1e-3 * t, command_speed=1.0)
    assert any("the API takes m/s" in note and "1000×" in note for note in result.notes)
    right = analyze_trace(t, 1e-3 * t, command_speed=1e-3)
    assert not any("the API takes m/s" in note for note in right.notes)


# ------------------------------------------------------------------ reprs


def _short(text: str, cls: str, *words: str) -> None:
    assert text.startswith(f"<feeddrive.{cls}") and text.endswith(">"), text
    assert len(text) <= 220 and "array(" not in text, text
    for word in words:
        assert word in text, text


def test_an_experiment_prints_in_a_line() -> None:
    _short(repr(_record()), "Experiment", "'x.csv'", "1000 samples", "table_position",
           "1 mm/s")
    assert "\n" not in repr(_record())


def test_a_fit_result_prints_one_line_per_estimate() -> None:
    """It printed 3552 characters, down to the residual autocorrelations."""
    est = ParameterEstimate(path=KI, unit="A/m", start=4000.0, value=3925.29, stderr=0.021,
                            low=3925.25, high=3925.33, interval="linear", determined=True)
    result = FitResult(parameters=P, base_name="wang2021", drive="cdfs", table_position=0.4,
                       sources=("x.csv",), estimates=(est,), covariance=np.eye(1),
                       correlation=np.eye(1), condition_number=1.0,
                       singular_values=np.ones(1), poorly_determined=(), residuals=(),
                       residual_ok=True, cost=0.5, dof=999, evaluations=12, confidence=0.95,
                       experiments=(_record(),), simulated=({"table_position": np.zeros(1000)},))
    lines = repr(result).splitlines()
    assert len(lines) == 3 and lines[0].startswith("<feeddrive.FitResult cdfs of 'wang2021'")
    assert lines[1].strip() == f"{KI} = 3925.29 ± 0.021 A/m"
    assert len(repr(result)) <= 300


def test_trace_static_and_positioning_results_print_in_a_line() -> None:
    _short(repr(analyze_trace(T, X, command_speed=1e-3, source="run.csv")), "TraceAnalysis",
           "'run.csv'", "2001 samples", "1 mm/s creeping")
    v = np.array([0.1, 0.3, 1.0, 3.0, 10.0, 30.0]) * 1e-3
    force = 30.0 + 15.0 * np.exp(-(v / 2e-3) ** 2) + 800.0 * v
    rng = np.random.default_rng(0)
    static = fit_static(np.r_[v, -v], np.r_[force, -force] * (1 + 0.01 * rng.standard_normal(12)),
                        source="tests.csv")
    _short(repr(static), "StaticFit", "'tests.csv'", "+ F_c", "− F_c", "mm/s")
    p = np.linspace(0.0, 0.4, 11)
    iso = positioning_test(p, np.full((11, 5), -2e-6), np.full((11, 5), 2e-6))
    _short(repr(iso), "PositioningTest", "11 targets", "5 approaches", "B 4,", "M 0 µm")
