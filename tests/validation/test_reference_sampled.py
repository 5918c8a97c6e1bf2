"""Sampled (zero-order-hold) control: the engine's sampled loops against the reference.

The reference (``reference/sampled.py`` on ``reference/scipy_model.py``) integrates the plant
with ``scipy.integrate.solve_ivp`` (DOP853, rtol 1e-10) between sample instants and updates
the held loop outputs at each instant in the engine's order — position loop every n_pos base
periods, velocity loop with the quantised-difference speed measurement, current loop —
written from the loop equations (Wang2021 Sect. 2.1; Åström & Wittenmark, Computer-Controlled
Systems, 1997, Ch. 7), not from the engine's kernels.  The engine runs at tight tolerances.

Runs are short (50 ms: 400 current-loop instants) on ``wang2021`` with Wang2021-like digital
loops (position 1 ms, velocity 0.5 ms, current 0.125 ms), with and without encoder/grating
quantisation, and on the linear-motor example.  States and held loop outputs must agree to
TOL of each trace's largest value; the comparison is shown to detect halving
``velocity_integral_gain`` or ``current_integral_gain`` in only one of the two (before this
test, halving the sampled integral gains changed results and no test noticed: issue 8).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.sampled import quantise, simulate_sampled  # noqa: E402
from reference.scipy_model import ReferenceModel, sampling_grid  # noqa: E402

import feeddrive  # noqa: E402
from feeddrive.engine.simulate import DriveSystem, SolverOptions, sampling, simulate  # noqa: E402
from feeddrive.model.reference import ConstantSpeed  # noqa: E402

TOL = 1e-7  # of each trace's largest value; the agreement achieved is ≤ 3e-10
DURATION = 0.05
TIGHT = SolverOptions(rtol=1e-10, position_tolerance=1e-15, speed_tolerance=1e-13,
                      current_tolerance=1e-11)

SAMPLED = {"controller.position_period": 1e-3, "controller.velocity_period": 5e-4,
           "controller.current_period": 1.25e-4}
QUANTISED = {"controller.encoder_counts": 10000.0, "controller.grating_resolution": 1e-7}


@dataclass(frozen=True)
class Case:
    changes: dict[str, Any]
    drive: str = "ddfs"
    preset: str = "wang2021"
    nut_speed: float = 16e-3

    def parameters(self, **extra: Any) -> feeddrive.DriveParameters:
        p = feeddrive.preset(self.preset)
        for path, value in (self.changes | extra).items():
            p = p.replace_path(path, value)
        return p

    def profile(self) -> ConstantSpeed:
        return ConstantSpeed(2e-3, self.nut_speed, ramp_time=0.02)


CASES = {
    "ddfs-sampled": Case(SAMPLED),
    "ddfs-sampled-quantised": Case(SAMPLED | QUANTISED),
    # the screw's speed from the grating and the nut's encoder; loops driven into their limits
    "cdfs-table-feedback-quantised-saturating": Case(
        SAMPLED | {"controller.velocity_feedback": "table", "controller.encoder_counts": 4096.0,
                   "controller.grating_resolution": 5e-8, "controller.current_limit": 0.28,
                   "controller.voltage_limit": 0.55}, drive="cdfs", nut_speed=0.0),
    # sampled position and velocity loops, continuous current loop
    "ddfs-continuous-current-quantised": Case(SAMPLED | QUANTISED | {
        "controller.current_period": 0.0}),
    # sampled current loop under continuous position and velocity loops
    "ddfs-sampled-current-only": Case({"controller.current_period": 1.25e-4}),
    "linear-motor-sampled-quantised": Case(SAMPLED | {"controller.grating_resolution": 1e-7},
                                           drive="linear-motor",
                                           preset="linear-motor-example", nut_speed=0.0),
}


def _engine(case: Case, params: feeddrive.DriveParameters) -> Any:
    return simulate(DriveSystem(params, case.drive, 0.4), case.profile(), DURATION,
                    options=TIGHT)


def _reference(case: Case, params: feeddrive.DriveParameters
               ) -> tuple[ReferenceModel, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    model = ReferenceModel(params, case.drive, 0.4, case.profile())
    t, y, outputs = simulate_sampled(model, DURATION)
    return model, t, y, outputs


def _worst(result: Any, model: ReferenceModel, y: np.ndarray,
           outputs: dict[str, np.ndarray]) -> dict[str, float]:
    """Largest difference of every state and held output, relative to its largest value."""
    out = {}
    for j, name in enumerate(model.state_names):
        scale = np.max(np.abs(y[:, j]))
        diff = np.max(np.abs(np.asarray(result[name]) - y[:, j]))
        out[name] = diff / scale if scale > 0.0 else diff
    for name, trace in outputs.items():
        scale = np.max(np.abs(trace))
        diff = np.max(np.abs(np.asarray(result[name]) - trace))
        out[name] = diff / scale if scale > 0.0 else diff
    return out


@pytest.mark.parametrize("name", sorted(CASES))
def test_engine_sampled_loops_follow_the_zero_order_hold_reference(name: str) -> None:
    case = CASES[name]
    params = case.parameters()
    result = _engine(case, params)
    model, t, y, outputs = _reference(case, params)
    np.testing.assert_allclose(np.asarray(result.time), t, rtol=0, atol=1e-12)
    assert outputs  # some loop is sampled
    worst = _worst(result, model, y, outputs)
    bad = {k: v for k, v in worst.items() if v > TOL}
    assert not bad, bad
    # the run moves, and sampling (and quantisation) change it by far more than TOL (the
    # continuous and unquantised runs by the engine: the loops' saturation with stick makes a
    # tight continuous scipy run slow)
    table_speed = y[:, model.state_names.index("table_speed")]
    assert np.max(np.abs(table_speed)) > 1e-4
    continuous = case.parameters(**{"controller.position_period": 0.0,
                                    "controller.velocity_period": 0.0,
                                    "controller.current_period": 0.0,
                                    "controller.encoder_counts": 0.0,
                                    "controller.grating_resolution": 0.0})
    for other in (continuous, case.parameters(**{"controller.encoder_counts": 0.0,
                                                 "controller.grating_resolution": 0.0})):
        if other == params:
            continue
        other_speed = np.asarray(_engine(case, other)["table_speed"])
        assert np.max(np.abs(other_speed - table_speed)) > 1e3 * TOL * np.max(
            np.abs(table_speed))


def test_saturating_case_saturates_both_sampled_loops() -> None:
    """The saturating case exercises the sampled anti-windup of both PI loops."""
    case = CASES["cdfs-table-feedback-quantised-saturating"]
    _, _, _, outputs = _reference(case, case.parameters())
    c = case.parameters().controller
    for name, limit in (("screw_current_command", c.current_limit),
                        ("screw_voltage", c.voltage_limit)):
        at_limit = np.mean(np.abs(outputs[name]) >= limit)
        assert 0.02 < at_limit < 0.98, (name, at_limit)


@pytest.mark.parametrize("quantised", [False, True], ids=["ideal", "quantised"])
@pytest.mark.parametrize("gain", ["velocity_integral_gain", "current_integral_gain"])
@pytest.mark.parametrize("halved_in", ["engine", "reference"])
def test_halving_a_sampled_integral_gain_on_one_side_only_is_detected(
        gain: str, quantised: bool, halved_in: str) -> None:
    case = CASES["ddfs-sampled-quantised" if quantised else "ddfs-sampled"]
    params = case.parameters()
    halved = params.replace_path(f"controller.{gain}", getattr(params.controller, gain) / 2)
    assert getattr(halved.controller, gain) > 0.0
    result = _engine(case, halved if halved_in == "engine" else params)
    model, _, y, outputs = _reference(case, params if halved_in == "engine" else halved)
    worst = _worst(result, model, y, outputs)
    # far beyond the tolerance of the agreement test, in the table's motion itself
    assert worst["table_speed"] > 1e4 * TOL, worst["table_speed"]
    assert worst["screw_current"] > 1e4 * TOL, worst["screw_current"]


@pytest.mark.parametrize("periods", [(1e-3, 5e-4, 1.25e-4), (0.0, 0.0, 2.5e-4),
                                     (2e-3, 0.0, 5e-4), (0.0, 0.0, 0.0)])
def test_reference_sample_grid_is_the_engines(periods: tuple[float, float, float]) -> None:
    p = feeddrive.preset("wang2021")
    for name, value in zip(("position", "velocity", "current"), periods, strict=True):
        p = p.replace_path(f"controller.{name}_period", value)
    mine, engine = sampling_grid(p, 1e-3), sampling(p, 1e-3)
    assert (mine.base, mine.n_pos, mine.n_vel, mine.n_cur, mine.out_every) == (
        engine.base, *(engine.step(f"controller.{loop}_period")
                       for loop in ("position", "velocity", "current")), engine.out_every)


def test_quantise_is_a_floor_count() -> None:
    """An incremental count truncates toward −∞ (a negative position reads one count low)."""
    assert quantise(2.5e-7, 1e-7) == pytest.approx(2e-7, rel=1e-12)
    assert quantise(-2.5e-7, 1e-7) == pytest.approx(-3e-7, rel=1e-12)
    assert quantise(0.123, 0.0) == 0.123
