"""Open-loop replay (feeddrive.model.replay, issue 36 item 5): a measured current, torque,
force or motor speed drives the compiled model as data in T, the loops bypassed.

The truths are the plain-Python reference model (reference/scipy_model.py) integrated by
scipy's Radau piecewise over the record's samples (reference/replay_truth.py), not feeddrive.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.analysis.fit import Experiment, FitError, fit_drive
from feeddrive.engine.simulate import DriveSystem, SolverOptions, simulate
from feeddrive.model.replay import (
    REPLAYS,
    CurrentReplay,
    ForceReplay,
    MotorSpeedReplay,
    TorqueReplay,
)
from feeddrive.parameters import ParameterError

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.replay_truth import force_driven, speed_driven  # noqa: E402

TIGHT = SolverOptions(accuracy=1e-4)


def _push(t: np.ndarray) -> np.ndarray:
    """A force that keeps the linear-motor table sliding forward at a varying speed [N]."""
    f = 14.7 + 20.0 + 25.0 * np.sin(2 * np.pi * 1.5 * t)
    return np.where(t < 0.02, f * t / 0.02, f)


@pytest.fixture(scope="module")
def linear() -> DriveSystem:
    return DriveSystem(fd.preset("linear-motor-example"), "linear-motor")


@pytest.fixture(scope="module")
def rack() -> DriveSystem:
    return DriveSystem(fd.preset("rack-pinion-example"), "rack-pinion")


def _at(result: object, name: str, t: np.ndarray) -> np.ndarray:
    return np.interp(t, result.time, result[name])  # type: ignore[attr-defined]


def test_force_replay_matches_an_independent_radau_truth(linear: DriveSystem) -> None:
    # irregular sample steps (0.7 … 1.3 ms, on a 0.1-ms output grid so that every sample is
    # an output instant): the table's breakpoints are the record's own instants
    rng = np.random.default_rng(3)
    t = np.concatenate([[0], np.cumsum(rng.integers(7, 14, 400))]) * 1e-4
    force = _push(t)
    truth, _ = force_driven(linear.parameters, t, force)
    run = simulate(linear, ForceReplay(t, force, speed_scale=0.5), float(t[-1]),
                   options=SolverOptions(accuracy=1e-4, output_interval=1e-4))
    x = _at(run, "table_position", t)
    assert truth["table_position"][-1] > 0.05  # it moved: 0.4 s of sliding
    # measured: 5.5e-13 m at accuracy 1e-4 (7.3e-10 at the default accuracy 1, 2026-12-06;
    # 1.7e-7 at either with 1-ms outputs: the interpolation, docs/fitting.md)
    assert np.max(np.abs(x - truth["table_position"])) < 1e-9
    assert np.allclose(_at(run, "replay_input", t), force, atol=1e-9)
    assert np.allclose(_at(run, "drive_force", t), force, atol=1e-9)


def test_current_torque_and_force_replays_are_one_drive(linear: DriveSystem,
                                                        rack: DriveSystem) -> None:
    t = np.arange(301) * 1e-3
    force = _push(t)
    k_f = linear.parameters.linear_motor.force_constant
    runs = [simulate(linear, r, 0.3, options=TIGHT) for r in (
        ForceReplay(t, force, speed_scale=0.5), CurrentReplay(t, force / k_f, speed_scale=0.5))]
    assert np.allclose(runs[0]["table_position"], runs[1]["table_position"], rtol=0,
                       atol=1e-12)
    H = rack.parameters.section("rack_pinion").transmission_ratio
    runs = [simulate(rack, r, 0.3, options=TIGHT) for r in (
        ForceReplay(t, 2 * force, speed_scale=0.5), TorqueReplay(t, 2 * force * H,
                                                                 speed_scale=0.5))]
    assert runs[0]["table_position"][-1] > 1e-3
    assert np.allclose(runs[0]["table_position"], runs[1]["table_position"], rtol=0,
                       atol=1e-12)


def test_speed_replay_matches_an_independent_radau_truth(rack: DriveSystem) -> None:
    H = rack.parameters.section("rack_pinion").transmission_ratio
    t = np.arange(201) * 1e-3
    w = 0.2 * np.sin(np.pi * t / 0.2) ** 2 / H
    truth, signals = speed_driven(rack.parameters, t, w)
    run = simulate(rack, MotorSpeedReplay(t, w, speed_scale=0.3), 0.2, options=TIGHT)
    # the table follows the imposed motor through the mesh; its position to 1e-9 m
    assert np.max(np.abs(_at(run, "table_position", t) - truth["table_position"])) < 1e-9
    # the mesh force, 40 N peak, to 0.1 % of it (k_m = 2e8 N/m magnifies 1e-12 m)
    peak = float(np.max(np.abs(signals["drive_force"])))
    assert peak > 10.0
    assert np.max(np.abs(_at(run, "drive_force", t) - signals["drive_force"])) < 1e-3 * peak
    # the imposed state keeps its start value, the imposed speed is the replay_input output
    assert np.all(run["motor_speed"] == 0.0)
    assert np.allclose(_at(run, "replay_input", t), w, atol=1e-9)


def test_replay_data_reaches_the_compiled_model_through_T(linear: DriveSystem) -> None:
    t = np.arange(11) * 1e-2
    one = linear.model(ForceReplay(t, np.full(11, 20.0)))
    two = linear.model(ForceReplay(t, np.linspace(0, 50, 11)))
    assert "replay_value(t, P" in one.source and "T)" in one.source
    assert one.module is two.module  # same structure: one compiled module, data in T
    assert not np.array_equal(one.T, two.T)


def test_interpolation_is_piecewise_linear_between_irregular_samples(
        linear: DriveSystem) -> None:
    from feeddrive.model.replay import replay_value

    t = np.array([0.0, 0.01, 0.013, 0.05, 0.2])
    v = np.array([0.0, 10.0, -5.0, 7.0, 7.5])
    model = linear.model(ForceReplay(t, v))
    o = model.parameter_names.index("profile[0]")
    probe = np.array([0.0, 0.004, 0.01, 0.0115, 0.03, 0.199, 0.2, 0.3])
    got = [replay_value(float(x), model.P, o, model.T) for x in probe]
    assert np.allclose(got, np.interp(probe, t, v), atol=1e-12)


@pytest.mark.parametrize(("drive", "preset", "replay", "words"), [
    ("ddfs", "wang2021", ForceReplay, "2 motors (screw, nut): no single force path"),
    ("ddfs", "wang2021", CurrentReplay, "no single current path"),
    ("linear-motor", "linear-motor-example", MotorSpeedReplay, "no motor shaft apart"),
])
def test_a_drive_without_the_path_is_refused_in_one_line(drive: str, preset: str,
                                                         replay: type, words: str) -> None:
    system = DriveSystem(fd.preset(preset), drive)
    t = np.arange(5) * 1e-3
    with pytest.raises(ParameterError) as err:
        system.model(replay(t, np.ones(5)))
    assert words in str(err.value) and "\n" not in str(err.value)


def test_torque_off_and_bad_samples_are_refused() -> None:
    p = fd.preset("linear-motor-example").replace_path("controller.mode", "torque_off")
    t = np.arange(5) * 1e-3
    with pytest.raises(ParameterError, match="controller.mode"):
        DriveSystem(p, "linear-motor").model(ForceReplay(t, np.ones(5)))
    system = DriveSystem(fd.preset("linear-motor-example"), "linear-motor")
    with pytest.raises(ParameterError, match="replay.time"):
        system.model(ForceReplay(t[::-1], np.ones(5)))
    with pytest.raises(ParameterError, match="replay.force"):
        system.model(ForceReplay(t, np.array([1.0, np.nan, 1.0, 1.0, 1.0])))


def _experiment(role: str, signals: dict[str, np.ndarray], n: int = 50) -> Experiment:
    t = np.arange(n) * 1e-3
    return Experiment(source="rec", time=t, signals=signals, reference_time=t,
                      table_speed=np.full(n, 0.1), input=role, input_value=np.ones(n))


@pytest.mark.parametrize(("drive", "preset", "role", "signal", "words"), [
    ("ddfs", "wang2021", "force", "table_position", "no single force path"),
    ("linear-motor", "linear-motor-example", "speed", "table_position", "no motor shaft"),
    ("linear-motor", "linear-motor-example", "current", "motor_current",
     "--input current drives motor_current; it cannot also be a fitted signal"),
    ("rack-pinion", "rack-pinion-example", "voltage", "table_position",
     "--input 'voltage': expected one of current, torque, force, speed"),
])
def test_fit_refuses_a_replay_before_any_simulation(monkeypatch: pytest.MonkeyPatch,
                                                    drive: str, preset: str, role: str,
                                                    signal: str, words: str) -> None:
    import feeddrive.analysis.fit as fit

    def boom(*_a: object, **_k: object) -> None:
        raise AssertionError("simulated")

    monkeypatch.setattr(fit, "simulate_experiment", boom)
    e = _experiment(role, {signal: np.linspace(0, 1e-3, 50)})
    with pytest.raises(FitError) as err:
        fit_drive(fd.preset(preset), [e], ["table.mass"], drive=drive)
    assert words in str(err.value) and "\n" not in str(err.value)


def test_fit_refuses_a_loop_gain_of_a_replay(monkeypatch: pytest.MonkeyPatch) -> None:
    import feeddrive.analysis.fit as fit

    monkeypatch.setattr(fit, "simulate_experiment", None)  # any simulation would fail
    e = _experiment("force", {"table_position": np.linspace(0, 1e-3, 50)})
    with pytest.raises(FitError, match="controller.velocity_gain: has no effect .*"
                                       "open-loop replay"):
        fit_drive(fd.preset("linear-motor-example"), [e], ["controller.velocity_gain"],
                  drive="linear-motor")


def test_every_role_is_registered() -> None:
    assert set(REPLAYS) == {"current", "torque", "force", "speed"}
