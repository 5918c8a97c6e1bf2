"""Profiles and loads an outside check found unchecked (2026-12-07): speeds beyond any feed
drive, a zero sine, builders that failed in numpy's words, a load record checked only at
simulate, a run past the end of a table that still commands a speed, and summaries that
judged an unfinished ramp or a speed in mm/s given as m/s without a word."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.parameters import ParameterError

SYSTEM = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
FAST = r"^expected \|speed\| ≤ 100 \[m/s\] \(no feed drive is faster\)"


@pytest.mark.parametrize(("make", "field"), [
    (lambda: fd.ConstantSpeed(1e6), "profile.table_speed"),
    (lambda: fd.ConstantSpeed(1e300), "profile.table_speed"),
    (lambda: fd.ConstantSpeed(1e-3, nut_speed=-1e3), "profile.nut_speed"),
    (lambda: fd.SineSpeed(1e4), "profile.table_amplitude"),
    (lambda: fd.SineSpeed(1e-3, nut_amplitude=101.0), "profile.nut_amplitude"),
    (lambda: fd.SampledSpeed(np.array([0.0, 0.01]), np.array([0.0, 1e6])),
     "profile.table_speed[1]"),
    (lambda: fd.SampledSpeed(np.array([0.0, 0.01]), np.zeros(2), np.array([-200.0, 0.0])),
     "profile.nut_speed[0]"),
    (lambda: fd.trapezoid(1e3, 2.0), "table_speed"),
    (lambda: fd.stepdown(1e3, 1e-3), "start_speed"),
])
def test_a_speed_beyond_any_feed_drive_is_refused_when_the_profile_is_made(
        make: object, field: str) -> None:
    """ConstantSpeed(1e6) ran and was judged 'creeping'; 1e300 overflowed in numpy."""
    with pytest.raises(ParameterError) as err:
        make()  # type: ignore[operator]
    assert err.value.field == field
    assert re_match(FAST, err.value.message)


def re_match(pattern: str, text: str) -> bool:
    import re

    return re.match(pattern, text) is not None


def test_a_command_of_a_rapid_traverse_is_said_in_the_summary() -> None:
    """ConstantSpeed(2.0) meant as 2 mm/s ran at 2 m/s without a word."""
    s = fd.simulate(SYSTEM, fd.ConstantSpeed(2.0), 0.3).summary()
    said = [w for w in s["warnings"] if w.startswith("the command is")]
    assert said == ["the command is 2 m/s (2000 mm/s, 120 m/min), a rapid traverse, not a "
                    "creep test; the API takes m/s (2 mm/s is 0.002), the command line mm/s"]


def test_a_run_past_the_end_of_a_table_that_still_commands_a_speed_is_refused() -> None:
    """The speed reference held, the position reference froze, the verdict said 'creeping'."""
    moving = fd.SampledSpeed(np.array([0.0, 0.01]), np.array([1e-3, 1e-3]))
    with pytest.raises(ParameterError) as err:
        fd.simulate(SYSTEM, moving, 1.0)
    assert err.value.field == "duration"
    assert re_match(r"^expected ≤ 0\.02 \[s\]: the profile ends at 0\.01 s still commanding "
                    r"table speed 1 mm/s", err.value.message)
    with pytest.raises(ParameterError) as err:  # a continued run too
        fd.Simulation(SYSTEM, moving).run(1.0)
    assert err.value.field == "duration"
    # one sample interval past the end is the output instant after it (a fit's records)
    assert fd.simulate(SYSTEM, moving, 0.02).time[-1] == pytest.approx(0.02)
    # a table that ends at rest holds the table there: a longer run settles
    at_rest = fd.SampledSpeed(np.array([0.0, 0.01, 0.02]), np.array([1e-3, 1e-3, 0.0]))
    assert fd.simulate(SYSTEM, at_rest, 0.1).time[-1] == pytest.approx(0.1)


def test_a_ramp_that_ends_after_the_run_is_said_in_the_summary() -> None:
    """A 10-s ramp in a 1-s run was judged 'smooth' against the 0.1 mm/s it had reached."""
    s = fd.simulate(SYSTEM, fd.ConstantSpeed(1e-3, ramp_time=10.0), 0.5).summary()
    assert any(re_match(r"^the start ramp ends at 10 s, after the run's end 0\.5 s: the "
                        r"verdict is of the ramp, not of the constant command of 1 mm/s "
                        r"\(its reference reaches 0\.05 mm/s\)", w) for w in s["warnings"]), \
        s["warnings"]


def test_a_sine_of_zero_table_amplitude_is_refused_when_made() -> None:
    """It was refused only by the summary, after the run, in a bare ValueError."""
    with pytest.raises(ParameterError) as err:
        fd.SineSpeed(0.0, nut_amplitude=1e-3)
    assert err.value.field == "profile.table_amplitude"
    assert re_match(r"^expected a non-zero amplitude \[m/s\]", err.value.message)


def test_a_sine_of_numpy_numbers_is_summarised_as_a_sine() -> None:
    """Its repr held np.float64(…), which the summary did not read: a creep verdict."""
    profile = fd.SineSpeed(np.float64(2e-3), frequency=np.float64(2.0))
    assert repr(profile) == "SineSpeed(table_amplitude=0.002, nut_amplitude=0.0, frequency=2.0)"
    assert fd.simulate(SYSTEM, profile, 0.6).summary()["profile"] == "sine"


def _csv(tmp: Path) -> Path:
    path = tmp / "p.csv"
    path.write_text("time,table_speed\n0,1\n1,1\n")
    return path


@pytest.mark.parametrize(("make", "field", "unit"), [
    (lambda: fd.trapezoid("1e-3", 2), "table_speed", "m/s"),  # numpy's UFuncTypeError
    (lambda: fd.trapezoid([1e-3, 2e-3], 2), "table_speed", "m/s"),  # a broadcast error
    (lambda: fd.trapezoid(1e-3, "2"), "duration", "s"),  # "ufunc 'isfinite' not supported"
    (lambda: fd.trapezoid(1e-3, 2, nut_speed=math.nan), "nut_speed", "m/s"),
    (lambda: fd.stepdown("3e-3", 1e-3), "start_speed", "m/s"),
    (lambda: fd.stepdown(3e-3, 1e-3, dwell=[4.0]), "dwell", "s"),
    (lambda: fd.stepdown(3e-3, 1e-3, nut_speed="0"), "nut_speed", "m/s"),
    (lambda: fd.SampledSpeed.from_function(lambda t: 1e-3 + 0 * t, 1.0, interval=0),
     "interval", "s"),  # ZeroDivisionError
    (lambda: fd.SampledSpeed.from_function(lambda t: 1e-3 + 0 * t, math.nan),
     "duration", "s"),  # "cannot convert float NaN to integer"
    (lambda: fd.SampledSpeed.from_function(lambda t: 1e-3 + 0 * t, 1e9),
     "duration", "s"),  # MemoryError 72.8 TiB
    (lambda: fd.SampledSpeed.from_function(lambda t: 1e-3 + 0 * t, -1),
     "duration", "s"),  # a shape message naming no argument
    (lambda: fd.SampledSpeed.from_function(1e-3, 1.0), "table_speed", "m/s"),
    (lambda: fd.SampledSpeed.from_function(lambda t: t[:, None], 0.01), "table_speed", "m/s"),
    (lambda: fd.SampledSpeed(np.array([0.0, 1.0]), np.zeros(2), hold="no"), "profile.hold",
     None),  # taken as True
])
def test_a_builder_refuses_a_bad_argument_naming_it(make: object, field: str,
                                                    unit: str | None) -> None:
    with pytest.raises(ParameterError) as err:
        make()  # type: ignore[operator]
    assert err.value.field == field
    if unit is not None:
        assert f"[{unit}]" in err.value.message


def test_from_csv_refuses_a_path_that_is_not_one(tmp_path: Path) -> None:
    from feeddrive.model.reference import from_csv

    with pytest.raises(ParameterError) as err:
        from_csv(123)  # type: ignore[arg-type]
    assert err.value.field == "path"
    with pytest.raises(ParameterError) as err:
        from_csv(_csv(tmp_path), interval="1e-3")  # type: ignore[arg-type]
    assert (err.value.field, err.value.message) == ("interval", "expected a finite value > 0 [s]")


@pytest.mark.parametrize(("time", "force", "field", "message"), [
    ([0.0, 1.0], [math.nan, 1.0], "load.force[0]", r"^expected finite values \[N\]"),
    ([0.0, 1.0], ["a", "b"], "load.force[0]", r"^expected real numbers \[N\]"),  # session 29
    ([0.0, 1.0, 3.0], [0.0, 0.0, 0.0], "load.time", r"^expected a uniform, increasing grid "
                                                     r"starting at 0 \[s\]"),
    ([0.0, 1.0], [0.0, 1e9], "load.force[1]", r"^expected \|force\| ≤ 1e\+06 \[N\]"),
])
def test_a_load_record_is_checked_when_made(time: list, force: list, field: str,
                                            message: str) -> None:
    """A NaN force was refused at simulate in a bare ValueError, strings in numpy's words."""
    with pytest.raises(ParameterError) as err:
        fd.LoadProfile(np.array(time), np.array(force))
    assert err.value.field == field
    assert re_match(message, err.value.message)


@pytest.mark.parametrize("load", [{"time": [0.0, 1.0], "force": [1.0, 1.0]}, 10.0])
def test_a_load_that_is_not_a_load_profile_is_refused_by_the_drive(load: object) -> None:
    """It failed at simulate with "'dict' object has no attribute 'encode'"."""
    with pytest.raises(ParameterError) as err:
        fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4, load=load)  # type: ignore[arg-type]
    assert err.value.field == "load"
    assert re_match(r"^expected a LoadProfile, e\.g\. LoadProfile\(time=…, force=…\) \[s, N\]",
                    err.value.message)


def test_the_cli_ramp_warning_gives_advice_the_command_takes() -> None:
    """`simulate`'s constant profile has a fixed 0.1-s start ramp (its --ramp-time is the
    trapezoid's): the warning's advice is a longer run, not an option that does not act."""
    from typer.testing import CliRunner

    from feeddrive.cli import app

    res = CliRunner().invoke(app, ["simulate", "--table-speed", "1", "--duration", "0.05"])
    assert res.exit_code == 0, res.output
    line = next(ln for ln in res.output.splitlines() if "start ramp ends at 0.1 s" in ln)
    assert "run longer than 0.1 s" in line and "--ramp-time" not in line
