"""The analysis API's arguments refused before any work, naming the argument, in the API's own
unit (m/s), and its results printed in one line (an outside audit, 2026-12-07).

A speed range given in mm/s blamed a ``coarse_step`` nobody set, a resolution was shown
in mm/s and multiplied, three speeds were taken as a range, a dict where SolverOptions go
raised an AttributeError from inside; ``linearize`` at 1e300 m/s printed LAPACK's complaints;
``run_positioning_test`` built a profile of 10⁵ cycles for minutes and never returned from
1e300; ``calibrate`` took a target in mm/s and bisected for 26 s.  Every test here stops the
work it must not reach (a trial, a profile, a simulation) so that the code before the fix
fails at once instead of running."""

from __future__ import annotations

import re

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.analysis import calibrate as calibration
from feeddrive.analysis import critical
from feeddrive.analysis.calibrate import Calibration, Target, Unknown, calibrate
from feeddrive.analysis.critical import CreepTrial, CriticalSpeed
from feeddrive.analysis.positioning_run import run_positioning_test
from feeddrive.parameters import ParameterError

KI = "controller.velocity_integral_gain"


@pytest.fixture(scope="module")
def system() -> fd.DriveSystem:
    return fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)


@pytest.fixture
def no_work(monkeypatch: pytest.MonkeyPatch) -> None:
    """A trial, a staircase, a positioning profile or a simulation reached fails the test."""
    import feeddrive.engine.simulate as engine
    import feeddrive.model.positioning_profile as positioning_profile

    def refused(*args: object, **kwargs: object) -> None:
        raise AssertionError("work started on a request that should have been refused")

    monkeypatch.setattr(critical, "_run_trial", refused)
    monkeypatch.setattr(critical, "walk_down", refused)
    monkeypatch.setattr(calibration, "creep_trial", refused)
    monkeypatch.setattr(positioning_profile, "stops_profile", refused)
    monkeypatch.setattr(engine, "simulate", refused)


def refusal(field: str, pattern: str) -> tuple[type[ParameterError], str]:
    return ParameterError, "^" + re.escape(field) + pattern


# ------------------------------------------------------------ 1: the critical-speed searches


def test_a_speed_range_in_mm_s_is_refused_as_the_range_and_says_the_api_takes_m_s(
        system: fd.DriveSystem, no_work: None) -> None:
    with pytest.raises(ParameterError, match=r"^speed_range = \(0\.02, 3\.0\): expected "
                                             r"high − low ≤ 0\.4 \[m/s\]") as err:
        fd.critical_speed_from_rest(system, speed_range=(0.02, 3.0))
    assert err.value.field == "speed_range"
    assert str(err.value).endswith("the API takes m/s: 3 mm/s is 0.003")


def test_a_range_above_the_axis_speed_limit_is_refused_with_the_limit(no_work: None) -> None:
    drive = fd.DriveSystem(fd.preset("wang2021-drive"), "cdfs", 0.4)  # 300 V: 1.59 m/s
    with pytest.raises(ParameterError, match=r"^speed_range = \(0\.02, 3\.0\): expected "
                                             r"speeds ≤ 1\.59155 \[m/s\] \(the screw motor"):
        fd.critical_speed_from_rest(drive, speed_range=(0.02, 3.0))


def test_the_resolution_is_shown_as_given_in_m_s(system: fd.DriveSystem, no_work: None) -> None:
    with pytest.raises(ParameterError, match=r"^resolution = 1e-300: expected ≥ 1e-07 \[m/s\]"):
        fd.critical_speed_from_rest(system, resolution=1e-300)


@pytest.mark.parametrize(("speed_range", "field", "says"), [
    ((1e-5, 1e-4, 1e-3), "speed_range", r" = \(1e-05, 0\.0001, 0\.001\): expected a pair "
                                        r"\(low, high\) of speeds \[m/s\]"),
    (1e-3, "speed_range", r" = 0\.001: expected a pair \(low, high\) of speeds \[m/s\]"),
    (("a", "b"), "speed_range[0]", r" = 'a': expected a number \[m/s\]"),
    ((2e-3, 1e-3), "speed_range", r" = \(0\.002, 0\.001\): expected low < high \[m/s\]"),
    ((float("nan"), 1e-3), "speed_range[0]", r" = nan: expected a finite speed > 0 \[m/s\]"),
])
def test_a_speed_range_that_is_not_a_range_is_refused_naming_it(
        system: fd.DriveSystem, no_work: None, speed_range: object, field: str,
        says: str) -> None:
    with pytest.raises(ParameterError, match="^" + re.escape(field) + says) as err:
        fd.critical_speed_from_rest(system, speed_range=speed_range)  # type: ignore[arg-type]
    assert err.value.field == field


@pytest.mark.parametrize(("kwargs", "says"), [
    ({"options": {}}, r"^options = 'dict': expected SolverOptions, e\.g\. SolverOptions"),
    ({"rule": "x"}, r"^rule = 'str': expected a VerdictRule or None"),
    ({"progress": 3}, r"^progress = 'int': expected None or a callable"),
    ({"coarse_step": "0.2"}, r"^coarse_step = '0\.2': expected a number \[m/s\]"),
    ({"nut_speed": float("inf")}, r"^nut_speed = inf: expected a finite speed \[m/s\]"),
])
def test_arguments_of_the_wrong_kind_are_refused_before_a_trial(
        system: fd.DriveSystem, no_work: None, kwargs: dict[str, object], says: str) -> None:
    with pytest.raises(ParameterError, match=says):
        fd.critical_speed_from_rest(system, **kwargs)  # type: ignore[arg-type]


def test_a_parameter_set_where_the_system_goes_is_named(system: fd.DriveSystem,
                                                        no_work: None) -> None:
    with pytest.raises(ParameterError, match=r"^system = 'DriveParameters': expected a "
                                             r"DriveSystem"):
        fd.critical_speed_from_rest(system.parameters)  # type: ignore[arg-type]


def test_the_stepdown_names_its_start_speed(system: fd.DriveSystem, no_work: None) -> None:
    with pytest.raises(ParameterError, match=r"^start_speed = 3\.0: expected start_speed − "
                                             r"lowest_speed ≤ 0\.2 \[m/s\]"):
        fd.critical_speed_stepdown(system, start_speed=3.0)
    with pytest.raises(ParameterError, match=r"^start_speed = 1e-05: expected > lowest_speed "
                                             r"= 5e-05 \[m/s\]"):
        fd.critical_speed_stepdown(system, start_speed=1e-5)


# ------------------------------------------------------------------- 2: the linear analysis


def test_the_stability_scan_refuses_in_m_s(system: fd.DriveSystem) -> None:
    with pytest.raises(ParameterError, match=r"^low = 0\.005: expected < high = 1e-05 "
                                             r"\[m/s\]$"):
        fd.stability_band(system, low=5e-3, high=1e-5)
    drive = fd.DriveSystem(fd.preset("wang2021-drive"), "cdfs", 0.4)
    with pytest.raises(ParameterError, match=r"^high = 5\.0: expected \|speed\| ≤ 1\.59155 "
                                             r"\[m/s\] \(the screw motor") as err:
        fd.stability_band(drive, high=5.0, points=2)
    assert str(err.value).endswith("the API takes m/s: 5 mm/s is 0.005")


def test_linearize_refuses_a_speed_beyond_any_drive_before_any_linear_algebra(
        system: fd.DriveSystem, capfd: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(ParameterError, match=r"^table_speed = 1e\+300: expected \|speed\| ≤ "
                                             r"100 \[m/s\] \(no feed drive is faster\)$"):
        fd.linearize(system, 1e300)
    assert "DLASCL" not in capfd.readouterr().out


@pytest.mark.parametrize("frequencies", [["a"], [1.0, np.inf], [[1.0, 2.0]]])
def test_frequencies_that_are_not_frequencies_are_named(system: fd.DriveSystem,
                                                        frequencies: object) -> None:
    with pytest.raises(ParameterError, match=r"^frequency_hz = .*: expected a sequence of 1 … "
                                             r"1000000 finite, positive frequencies \[Hz\]$"):
        fd.frequency_response(system, "tracking", frequency_hz=frequencies)  # type: ignore


# ----------------------------------------------------------------- 3: the positioning test


@pytest.mark.parametrize(("cycles", "says"), [
    # ≤ 4165: the 20 000 s the reference holds less the warm-up pass (session 26)
    (10**5, r" = 100000: expected ≤ 4165 \[-\]: 2 targets × 100000 cycles × 2 directions and "
            r"1 warm-up pass last at least 4\.8e\+05 s"),
    (1e300, r" = 1e\+300: expected ≤ 4165 \[-\]"),
    (float("nan"), r" = nan: expected a whole number ≥ 5 of approaches"),
    (None, r" = None: expected a whole number ≥ 5 of approaches"),
    (5.5, r" = 5\.5: expected a whole number ≥ 5 of approaches"),
], ids=["1e5", "1e300", "nan", "None", "5.5"])
def test_cycles_are_refused_before_the_profile_is_built(no_work: None, cycles: object,
                                                        says: str) -> None:
    with pytest.raises(ParameterError, match=r"^cycles" + says) as err:
        run_positioning_test(fd.preset("wang2021"), "cdfs", [0.1, 0.2],
                             cycles=cycles)  # type: ignore[arg-type]
    assert err.value.field == "cycles"


def test_a_dwell_too_long_for_the_reference_names_the_dwell(no_work: None) -> None:
    with pytest.raises(ParameterError, match=r"^dwell = 10000\.0: expected a shorter dwell "
                                             r"\[s\], or fewer targets: .*longer than the "
                                             r"20000 s its reference holds"):
        run_positioning_test(fd.preset("wang2021"), "cdfs", [0.1, 0.2], dwell=1e4)


@pytest.mark.parametrize(("params", "kwargs", "says"), [
    ("wang2021", {}, r"^params = 'wang2021': expected a DriveParameters"),
    (None, {"feed": "0.01"}, r"^feed = '0\.01': expected a number > 0 \[m/s\]"),
    (None, {"options": {}}, r"^options = 'dict': expected SolverOptions"),
])
def test_positioning_arguments_of_the_wrong_kind_are_named(no_work: None, params: object,
                                                           kwargs: dict[str, object],
                                                           says: str) -> None:
    with pytest.raises(ParameterError, match=says):
        run_positioning_test(params or fd.preset("wang2021"), "cdfs",  # type: ignore[arg-type]
                             [0.1, 0.2], **kwargs)  # type: ignore[arg-type]


def test_a_positioning_run_prints_in_one_line() -> None:
    run = run_positioning_test(fd.preset("wang2021"), "cdfs", [0.1, 0.11], feed=0.01,
                               acceleration=0.2, dwell=0.5, overshoot=1e-3)
    text = repr(run)
    assert "\n" not in text and len(text) <= 400, text
    assert text.startswith("<feeddrive PositioningRun cdfs, 2 targets 100…110 mm, 5 cycles "
                           "linear, feed 10 mm/s, dwell 0.5 s: ")
    assert f"B {run.test.reversal * 1e6:.3g} µm" in text
    assert f"R {run.test.repeatability * 1e6:.3g} µm" in text


# ------------------------------------------------------------------------ 4: calibration


@pytest.mark.parametrize(("make", "field", "says"), [
    (lambda: Target("cdfs", float("nan")), "target.critical_speed",
     r" = nan: expected a finite speed > 0 \[m/s\]"),
    (lambda: Target("cdfs", -1.01e-3), "target.critical_speed",
     r" = -0\.00101: expected a finite speed > 0 \[m/s\]"),
    (lambda: Unknown("table.mass", 10, 1), "unknown.high",
     r" = 1: expected > unknown\.low = 10 \[SI unit of table\.mass\]"),
    (lambda: Unknown(KI, "1", "10"), "unknown.low",
     r" = '1': expected a finite number > 0 .*\[SI unit of controller\."),
])
def test_targets_and_unknowns_are_refused_when_made(make: object, field: str,
                                                    says: str) -> None:
    with pytest.raises(ParameterError, match="^" + re.escape(field) + says) as err:
        make()  # type: ignore[operator]
    assert err.value.field == field


def test_a_target_in_mm_s_is_refused_before_any_trial(no_work: None) -> None:
    with pytest.raises(ParameterError, match=r"^target\.critical_speed = 1\.56: expected "
                                             r"0\.06 … 3 mm/s \(6e-05 … 0\.003 m/s\)") as err:
        calibrate(fd.preset("wang2021"), Target("cdfs", 1.56), Unknown(KI, 1e3, 1e4))
    assert str(err.value).endswith("the API takes m/s: 1.56 mm/s is 0.00156")


@pytest.mark.parametrize(("args", "says"), [
    (("wang2021", Target("cdfs", 1.56e-3), Unknown(KI, 1e3, 1e4)),
     r"^params = 'wang2021': expected a DriveParameters"),
    ((None, "1.56e-3", Unknown(KI, 1e3, 1e4)), r"^target = '1\.56e-3': expected a Target"),
    ((None, Target("cdfs", 1.56e-3), Unknown("controller.bogus", 1e3, 1e4)),
     r"^unknown\.path = 'controller\.bogus': unknown field"),
])
def test_calibrate_names_an_argument_of_the_wrong_kind(no_work: None, args: tuple[object, ...],
                                                       says: str) -> None:
    params, target, unknown = args
    with pytest.raises(ParameterError, match=says):
        calibrate(params or fd.preset("wang2021"), target, unknown)  # type: ignore[arg-type]


def test_a_bracket_that_does_not_cross_the_switch_is_named(
        monkeypatch: pytest.MonkeyPatch) -> None:
    def creeping(system: object, speed: float, **kwargs: object) -> CreepTrial:
        return CreepTrial(speed=speed, kind="stick-slip", ripple_ratio=1.0, stick_fraction=0.5,
                          stick_slip_frequency=1.0)

    monkeypatch.setattr(calibration, "creep_trial", creeping)
    with pytest.raises(ParameterError, match=r"^unknown = .*: the creep verdict at 0\.00155 m/s "
                                             r"\(1\.55 mm/s\) is the same \(creeping\) at both "
                                             r"ends"):
        calibrate(fd.preset("wang2021"), Target("cdfs", 1.56e-3), Unknown(KI, 1e3, 1e4))


def test_a_calibration_prints_in_one_line_and_says_when_it_missed() -> None:
    achieved = CriticalSpeed(drive="cdfs", table_position=0.4, nut_speed=0.0, start="rest",
                             critical_speed=None, status="above-range", resolution=1e-5,
                             speed_range=(0.05e-3, 3.0e-3))
    cal = Calibration(parameters=fd.preset("wang2021"), unknown=Unknown(KI, 1e3, 1e4),
                      value=8896.49, target=Target("cdfs", 1.56e-3), achieved=achieved,
                      evaluations=12, interval=(8800.0, 8990.0))
    text = repr(cal)
    assert "\n" not in text and len(text) <= 400, text
    assert text.startswith(f"<feeddrive Calibration {KI} = 8896.49 (interval 8800…8990) → cdfs "
                           "critical speed > 3.00 mm/s (creeps at every tested speed), target "
                           "1.56 mm/s: NOT reached, see .reason()")


def test_the_command_line_shows_the_target_and_the_search_range_in_mm_s() -> None:
    """`calibrate --target 5` and `creep --high 5000` were refused in the API's m/s, the
    latter with "the API takes m/s" though the option is in mm/s (session 25)."""
    from typer.testing import CliRunner

    from feeddrive.cli import app

    res = CliRunner().invoke(app, ["calibrate", "--target", "5"])
    assert res.exit_code == 2
    assert res.output.strip().splitlines()[-1].startswith(
        "error: --target = 5 [mm/s]: expected 0.06 … 3 mm/s")
    res = CliRunner().invoke(app, ["creep", "--high", "5000"])
    assert res.exit_code == 2
    line = res.output.strip().splitlines()[-1]
    assert line.startswith("error: --high = 5000.0: expected ≤ --low + 200 = 200.02 [mm/s]")
    assert "API" not in line


def test_positioning_names_its_dwell_option() -> None:
    """`positioning --dwell 1e9` was refused as `dwell = 1000000000.0` (session 25)."""
    from typer.testing import CliRunner

    from feeddrive.cli import app

    res = CliRunner().invoke(app, ["positioning", "--targets", "100,110", "--dwell", "1e9"])
    assert res.exit_code == 2
    assert res.output.strip().splitlines()[-1].startswith("error: --dwell = 1e+09 [s]: ")
