"""The Python API's bad-input sweep of session 29, as a notebook user hits it: each case ended
in a traceback from inside numpy, pathlib or dataclasses, was taken without a word (a complex
trace cast to its real part, ``duration=True`` run for 1 s, a window's third value dropped),
or refused a number it should take (``np.float32``) in words that say it is not one.  Each is
now taken, or refused in one line naming the argument, the value and what was expected."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.parameters import ParameterError


@pytest.fixture(scope="module")
def params() -> fd.DriveParameters:
    return fd.preset("wang2021")


# ------------------------------------------------------------ NumPy's scalars are numbers

@pytest.mark.parametrize("value", [np.float32(45.0), np.int64(45), np.float64(45.0)])
def test_a_parameter_takes_numpy_scalars_as_floats(params: fd.DriveParameters,
                                                   value: object) -> None:
    """np.float32(45) and np.int64(45) were "controller.velocity_gain = np.float32(45.0):
    expected a number [A s/m]" (np.float64, a float subclass, was taken)."""
    changed = params.replace_path("controller.velocity_gain", value)
    assert type(changed.controller.velocity_gain) is float
    assert changed.controller.velocity_gain == 45.0


@pytest.mark.parametrize("value", [np.array(45.0), True, 45 + 0j, "45"])
def test_a_parameter_still_refuses_what_is_no_number(params: fd.DriveParameters,
                                                     value: object) -> None:
    with pytest.raises(ParameterError, match=r"^controller\.velocity_gain = .*: expected a "
                                             r"number \[A s/m\]$"):
        params.replace_path("controller.velocity_gain", value)


def test_solver_options_take_numpy_scalars_as_plain_numbers() -> None:
    """np.float32(1e-3) was "options.output_interval = np.float32(0.001): expected a finite
    value > 0 [s]" (a finite value > 0), np.int64 "max_steps … expected a whole number"."""
    options = fd.SolverOptions(rtol=np.float32(1e-6), output_interval=np.float64(2e-3),
                               max_step=np.float32(1e-3), max_steps=np.int64(1000))
    assert type(options.rtol) is float and options.rtol == pytest.approx(1e-6)
    assert type(options.max_step) is float and type(options.max_steps) is int
    assert options.max_steps == 1000
    with pytest.raises(ParameterError, match=r"^options\.output_interval = True: expected a "
                                             r"finite value > 0 \[s\]$"):
        fd.SolverOptions(output_interval=True)


@pytest.mark.parametrize("check", ["thresholds", "f_min", "tolerance", "reversal"])
def test_the_analyses_take_numpy_scalars(check: str) -> None:
    """Each was refused as "expected a finite number ≥ 0 [-]", "… frequency > 0 [Hz]", "…
    speed > 0 [m/s]" and "a turn-back angle > 0 and < 2π [rad]" for an np.float32."""
    from feeddrive.analysis import circular, linear

    if check == "thresholds":
        th = fd.CreepThresholds(stick_level=np.float32(0.25))
        assert type(th.stick_level) is float and th.stick_level == 0.25
    elif check == "f_min":
        linear._check_frequencies(np.float32(1.0), np.float64(100.0), np.int64(400))
    elif check == "tolerance":
        linear._check_tolerance(np.float32(1e-6))
    else:
        a = np.linspace(0.0, 2 * np.pi, 721)
        res = circular.circular_test(a, 0.01 * np.cos(a), 0.01 * np.sin(a), radius=0.01,
                                     centre=(0.0, 0.0), reversal=np.float32(0.01))
        assert "CCW" in res.circular_deviation
        with pytest.raises(ParameterError, match=r"^reversal = True: expected a turn-back"):
            circular.circular_test(a, 0.01 * np.cos(a), 0.01 * np.sin(a), radius=0.01,
                                   centre=(0.0, 0.0), reversal=True)


@pytest.mark.parametrize(("run", "says"), [
    ({"duration": True}, r"^duration = True: expected a finite time > 0 \[s\]$"),
    ({"output": 3}, r"^output = 3: expected None or a file name \(str or pathlib\.Path\) "
                    r"ending in \.parquet or \.csv$"),
    ({"progress": 3}, r"^progress = 'int': expected None or a callable progress\(t, t_end\)"),
])
def test_a_run_refuses_a_bool_duration_a_number_output_or_progress(
        params: fd.DriveParameters, monkeypatch: pytest.MonkeyPatch, run: dict[str, Any],
        says: str) -> None:
    """``duration=True`` ran for 1 s; ``output=3`` was os.fspath's TypeError and
    ``progress=3`` "'int' object is not callable", after the first chunk had run."""
    from feeddrive.engine import simulate as engine

    def no_run(*_a: Any, **_k: Any) -> Any:
        raise AssertionError("the run started although its input was refused")

    monkeypatch.setattr(engine, "_advance", no_run)
    sim = fd.Simulation(fd.DriveSystem(params, "ddfs", 0.4), fd.ConstantSpeed(1e-3))
    with pytest.raises(ParameterError, match=says):
        sim.run(**{"duration": 0.05, **run})


def test_an_initial_state_of_true_is_refused(params: fd.DriveParameters) -> None:
    """``initial_state={"table_speed": True}`` started the table at 1 m/s."""
    with pytest.raises(ParameterError, match=r"^initial_state\.table_speed = True: expected "
                                             r"a finite number in the state's SI unit$"):
        fd.DriveSystem(params, "ddfs", 0.4, initial_state={"table_speed": True})
    system = fd.DriveSystem(params, "ddfs", 0.4, initial_state={"table_speed": np.float32(0)})
    assert system.initial_state["table_speed"] == 0


# -------------------------------------------------- arrays of what is not a real number

def _trace() -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(200) * 1e-3
    return t, 1e-3 * (1.0 + 0.5 * np.sin(2 * np.pi * 10 * t))


def _refuse_array(case: str) -> None:
    t, v = _trace()
    if case == "creep_metrics complex":
        fd.creep_metrics(t, v + 0j, 1e-3)
    elif case == "creep_metrics bool":
        fd.creep_metrics(t, v > 1e-3, 1e-3)
    elif case == "creep_metrics text":
        fd.creep_metrics(["a"] * t.size, v, 1e-3)
    elif case == "SampledSpeed complex":
        fd.SampledSpeed(t, v + 0j)
    elif case == "LoadProfile complex":
        fd.LoadProfile(t, np.zeros(t.size) + 1j)
    elif case == "circular_test complex":
        from feeddrive.analysis.circular import circular_test

        a = np.linspace(0.0, 2 * np.pi, 361)
        circular_test(a, 0.01 * np.cos(a) + 0j, 0.01 * np.sin(a), radius=0.01,
                      centre=(0.0, 0.0))
    elif case == "positioning_test text":
        from feeddrive.analysis.positioning import positioning_test

        positioning_test("abc", np.zeros((3, 5)), np.zeros((3, 5)))
    else:
        system = fd.DriveSystem(fd.preset("wang2021"), "ddfs", 0.4)
        fd.frequency_response(system, "table_position_reference", "table_position",
                              frequency_hz=np.array([1.0, 2.0 + 1.0j]))


@pytest.mark.parametrize(("case", "says"), [
    ("creep_metrics complex", r"^speed\[0\] = \(0\.001\+0j\): expected real numbers \[m/s\]$"),
    ("creep_metrics bool", r"^speed\[0\] = (True|False): expected real numbers \[m/s\]$"),
    ("creep_metrics text", r"^time\[0\] = 'a': expected real numbers \[s\]$"),
    ("SampledSpeed complex", r"^profile\.table_speed\[0\] = \(0\.001\+0j\): expected real "
                             r"numbers \[m/s\]$"),
    ("LoadProfile complex", r"^load\.force\[0\] = 1j: expected real numbers \[N\]$"),
    ("circular_test complex", r"^x\[0\] = \(0\.01\+0j\): expected real numbers \[m\]$"),
    ("positioning_test text", r"^targets = 'abc': expected real numbers \[m\]$"),
    ("frequency_response complex", r"^frequency_hz = array\(\[1\.\+0\.j, 2\.\+1\.j\]\): expected "
                                   r"a sequence of 1 … 1000000 finite, positive frequencies "
                                   r"\[Hz\]$"),
])
def test_an_array_of_what_is_no_real_number_is_refused_naming_the_value(case: str,
                                                                         says: str) -> None:
    """Complex values were cast to their real part with only numpy's ComplexWarning,
    booleans to 0 and 1 m/s (judged "unstable"), and text failed as numpy's "could not
    convert string to float: 'a'", naming no argument."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ComplexWarning on the way
        with pytest.raises(ParameterError, match=says):
            _refuse_array(case)


def test_arrays_of_numbers_of_any_kind_are_still_taken() -> None:
    import pandas as pd

    t, v = _trace()
    m = fd.creep_metrics(pd.Series(t), list(v), np.float32(1e-3))
    assert m.verdict == fd.creep_metrics(t, v, 1e-3).verdict
    profile = fd.SampledSpeed(np.arange(5) * 1e-3, np.array([0, 1, 1, 1, 1], dtype=np.int8))
    assert profile.table_speed.dtype == np.int8  # kept as given; read as floats
    fd.SampledSpeed(t, np.array([*v], dtype=object))


def test_a_reversed_circular_record_is_refused() -> None:
    """A record given last sample first was measured "runs CCW, feed -376.991 mm/min"."""
    from feeddrive.analysis.circular import circular_test

    a = np.linspace(0.0, 2 * np.pi, 361)
    t = np.linspace(0.0, 10.0, a.size)
    with pytest.raises(ParameterError, match=r"^time\[1\] = 9\.97\d*: expected increasing "
                                             r"sample times \[s\] \(time\[0\] = 10\.0\)$"):
        circular_test(t[::-1], 0.01 * np.cos(a), 0.01 * np.sin(a), radius=0.01,
                      centre=(0.0, 0.0))


@pytest.mark.parametrize(("kw", "says"), [
    ({"radius": "a"}, r"^radius = 'a': expected a radius > 0 \[m\]$"),
    ({"centre": 3}, r"^centre = 3: expected two finite coordinates \[m\]$"),
    ({"centre": ("a", "b")}, r"^centre = \('a', 'b'\): expected two finite coordinates \[m\]$"),
    ({"pitch": "1"}, r"^pitch = '1': expected a period > 0 \[m\]$"),
])
def test_circular_test_names_a_radius_centre_or_pitch_of_the_wrong_kind(
        kw: dict[str, Any], says: str) -> None:
    """Python's TypeError: "must be real number, not str", "object of type 'int' has no
    len()"."""
    from feeddrive.analysis.circular import circular_test

    a = np.linspace(0.0, 2 * np.pi, 361)
    args: dict[str, Any] = {"radius": 0.01, "centre": (0.0, 0.0), **kw}
    with pytest.raises(ParameterError, match=says):
        circular_test(a, 0.01 * np.cos(a), 0.01 * np.sin(a), **args)
    assert circular_test(a, 0.01 * np.cos(a), 0.01 * np.sin(a), radius=0.01,
                         centre=np.array([0.0, 0.0])).circular_deviation


def test_frequency_response_names_a_system_of_the_wrong_kind(
        params: fd.DriveParameters) -> None:
    """``frequency_response(params, "tracking")`` was a bare AssertionError."""
    for system in (params, 3):
        with pytest.raises(ParameterError, match=rf"^system = '{type(system).__name__}': "
                                                 r"expected a DriveSystem, e\.g\."):
            fd.frequency_response(system, "tracking")  # type: ignore[arg-type]


@pytest.mark.parametrize("window", [(0.1, 0.2, 0.3), "ab", np.array([0.1, 0.2, 0.3])])
def test_a_window_of_three_values_is_refused(window: object) -> None:
    """``window=(0.1, 0.2, 0.3)`` was taken as (0.1, 0.2), the third dropped."""
    t, v = _trace()
    with pytest.raises(ParameterError, match=r"^window = .*: expected \(start, end\) \[s\]$"):
        fd.creep_metrics(t, v, 1e-3, window=window)  # type: ignore[arg-type]
    assert fd.creep_metrics(t, v, 1e-3, window=np.array([0.05, 0.15])).window_end == 0.15


# ---------------------------------------------------------------- paths, names and kinds

@pytest.mark.parametrize("path", [None, 3])
def test_load_and_save_name_a_path_that_is_not_one(tmp_path: Path, path: object) -> None:
    """os.fspath's TypeError: "expected str, bytes or os.PathLike object, not int"."""
    import xarray as xr

    with pytest.raises(ParameterError, match=rf"^path = {path}: expected a TOML file's path "
                                             r"\(str or pathlib\.Path\); a preset by its "
                                             r"name is feeddrive\.preset\(name\)$"):
        fd.load(path)  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=rf"^path = {path}: expected a file name \(str "
                                             r"or pathlib\.Path\) ending in \.csv, \.parquet, "
                                             r"\.nc, \.mat$"):
        fd.Result(xr.Dataset({"x": ("time", [0.0])})).save(path)  # type: ignore[arg-type]


def test_result_refuses_what_is_no_dataset() -> None:
    """``Result("run.nc")`` was made, then failed at first use: "'str' object has no
    attribute 'attrs'"."""
    with pytest.raises(ParameterError, match=r"^dataset = 'str': expected an xarray\.Dataset "
                                             r"of a run"):
        fd.Result("run.nc")  # type: ignore[arg-type]


def test_a_misspelt_signal_is_named_with_the_closest(params: fd.DriveParameters) -> None:
    """``result["tabel_speed"]`` listed the 30 signals without pointing at one, and
    ``result[["table_speed"]]`` was "unhashable type: 'list'"."""
    import xarray as xr

    ds = xr.Dataset({"table_speed": ("time", [0.0, 1.0]), "nut_speed": ("time", [0.0, 0.0])},
                    coords={"time": [0.0, 1.0]})
    result = fd.Result(ds)
    with pytest.raises(KeyError, match=r"'tabel_speed': no such signal in this run; its "
                                       r"signals: table_speed, nut_speed \(did you mean "
                                       r"'table_speed'\?\)"):
        result["tabel_speed"]
    with pytest.raises(KeyError, match=r"\['table_speed'\]: no such signal in this run"):
        result[["table_speed"]]  # type: ignore[index]


def test_with_values_names_a_misspelt_field(params: fd.DriveParameters) -> None:
    """The dataclass's TypeError: "Controller.__init__() got an unexpected keyword argument
    'velocity_gian'" (the docstring promised a ParameterError)."""
    with pytest.raises(ParameterError, match=r"^controller\.velocity_gian = 1\.0: unknown "
                                             r"field; expected one of position_gain, .* \(did "
                                             r"you mean 'velocity_gain'\?\)$"):
        params.controller.with_values(velocity_gian=1.0)
    assert params.controller.with_values(velocity_gain=40).velocity_gain == 40.0


def test_replace_path_past_a_value_is_refused(params: fd.DriveParameters) -> None:
    """dataclasses' TypeError: "must be called with a dataclass type or instance"."""
    with pytest.raises(ParameterError, match=r"^controller\.velocity_gain\.x = 1\.0: unknown "
                                             r"field 'x': velocity_gain is a value, not a "
                                             r"section$"):
        params.replace_path("controller.velocity_gain.x", 1.0)


def test_preset_names_a_name_of_the_wrong_kind() -> None:
    """``preset(["wang2021"])`` was "unhashable type: 'list'"."""
    with pytest.raises(ParameterError, match=r"^preset = \['wang2021'\]: unknown preset; "
                                             r"expected one of .*wang2021"):
        fd.preset(["wang2021"])  # type: ignore[arg-type]


def test_a_stepdown_names_a_nut_speed_the_drive_does_not_follow_as_given(
        params: fd.DriveParameters, monkeypatch: pytest.MonkeyPatch) -> None:
    """On the CDFS, ``nut_speed=1e-3`` was refused by the first trial as "nut_speed =
    9.999999999999999e-06" (the staircase's ramped first sample)."""
    from feeddrive.analysis import critical

    def no_run(*_a: Any, **_k: Any) -> Any:
        raise AssertionError("a trial started although the input was refused")

    monkeypatch.setattr(critical, "walk_down", no_run)
    with pytest.raises(ParameterError, match=r"^nut_speed = 0\.001: the CDFS holds the hollow "
                                             r"motor; expected 0"):
        fd.critical_speed_stepdown(fd.DriveSystem(params, "cdfs", 0.4), nut_speed=1e-3)
