"""The leftovers of session 29's bad-input sweeps, each settled by a decision:

1. the API's flag arguments take ``bool`` and ``np.bool_`` and refuse anything else
   (``frictionless="yes"`` was taken as True, ``frequency=None`` as False; a parameter
   set's flags refused ``np.bool_``, which ``SampledSpeed.hold`` took);
2. a ``LoadProfile`` shorter than the run: its last force is held (the model's documented
   behaviour, and what a ramp-and-hold record means); the summary now says so;
3. ``Target("xdfs", …)``: its drive is checked when made, as ``DriveSystem`` checks it;
4. ``DriveParameters.section`` refuses a name that is not a string, instead of "unhashable
   type" or None;
6. ``SolverOptions(origin=…)`` (the API holds a default against a [solver] table with it)
   refuses what is not pairs (setting, source) naming its fields.

5 (a sweep's ``linear_points`` without the linear band) is in
tests/integration/test_cli_bad_input3_s29.py.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.parameters import ParameterError


@pytest.fixture(scope="module")
def params() -> fd.DriveParameters:
    return fd.preset("wang2021")


@pytest.fixture(scope="module")
def system(params: fd.DriveParameters) -> fd.DriveSystem:
    return fd.DriveSystem(params, "cdfs", 0.4)


# --------------------------------------------------------------------- 1: flag arguments

def _trace() -> tuple[np.ndarray, np.ndarray]:
    t = np.linspace(0.0, 10.0, 2001)
    return t, np.full(t.size, 1e-3)


def _flag_call(case: str, params: fd.DriveParameters, system: fd.DriveSystem,
               value: object) -> Callable[[], Any]:
    """The call of one public function with ``value`` for its flag argument."""
    from feeddrive.analysis.compensation import compensation_study
    from feeddrive.analysis.fit import fit_drive
    from feeddrive.analysis.fragments import friction_fragment
    from feeddrive.analysis.sensitivity import sensitivity
    from feeddrive.analysis.trace import analyze_trace

    t, v = _trace()
    calls: dict[str, Callable[[], Any]] = {
        "linearize": lambda: fd.linearize(system, frictionless=value),
        "loop_analysis": lambda: fd.loop_analysis(system, frictionless=value),
        "frequency_response": lambda: fd.frequency_response(system, "tracking",
                                                            frictionless=value),
        "creep_metrics": lambda: fd.creep_metrics(t, v, 1e-3, frequency=value),
        "Simulation": lambda: fd.Simulation(system, fd.ConstantSpeed(1e-3),
                                            embedded_estimate=value),
        "SolverOptions": lambda: fd.SolverOptions(locate_reversals=value),
        "SampledSpeed": lambda: fd.SampledSpeed(t, v, hold=value),
        "simulate": lambda: fd.simulate(system, fd.ConstantSpeed(1e-3), 0.05,
                                        error_estimate=value),
        "fit_drive": lambda: fit_drive(params, [], ["friction.screw.coulomb_force"],
                                       accuracy_check=value),
        "compensation_study": lambda: compensation_study(params, [], search=value),
        "friction_fragment": lambda: friction_fragment("screw",
                                                       include_undetermined=value),
        "analyze_trace": lambda: analyze_trace(t, 1e-3 * t, segment=value),
        "sensitivity": lambda: sensitivity(params, in_process=value),
    }
    return calls[case]


_FLAGS = {"linearize": "frictionless", "loop_analysis": "frictionless",
          "frequency_response": "frictionless", "creep_metrics": "frequency",
          "Simulation": "embedded_estimate", "SolverOptions": "options.locate_reversals",
          "SampledSpeed": "profile.hold", "simulate": "error_estimate",
          "fit_drive": "accuracy_check", "compensation_study": "search",
          "friction_fragment": "include_undetermined", "analyze_trace": "segment",
          "sensitivity": "in_process"}


@pytest.mark.parametrize("value", ["yes", 1, 0.0])
@pytest.mark.parametrize("case", sorted(_FLAGS))
def test_a_flag_argument_refuses_what_is_no_boolean(params: fd.DriveParameters,
                                                   system: fd.DriveSystem, case: str,
                                                   value: object) -> None:
    """``linearize(..., frictionless="yes")`` linearised without friction, ``creep_metrics(...,
    frequency="yes")`` looked for a frequency, ``sensitivity(in_process="no")`` ran in this
    process: every flag took anything truthy or falsy."""
    says = f"^{re.escape(_FLAGS[case])} = {re.escape(repr(value))}: expected "
    with pytest.raises(ParameterError, match=says):
        _flag_call(case, params, system, value)()


def test_a_flag_argument_takes_numpy_booleans(params: fd.DriveParameters,
                                              system: fd.DriveSystem) -> None:
    """np.bool_ (what ``x > 0`` of an array gives) is a boolean everywhere: a parameter
    set's flag refused it ("expected true or false"), ``error_estimate=np.True_`` was
    refused, while ``SampledSpeed(hold=np.True_)`` took it; each is read as a plain bool."""
    from feeddrive.engine.error_estimate import estimate_kind

    assert fd.linearize(system, frictionless=np.True_).frictionless is True
    assert fd.SolverOptions(sample_steps=np.True_).sample_steps is True
    changed = params.replace_path("controller.velocity_feedforward", np.False_)
    assert changed.controller.velocity_feedforward is False
    assert estimate_kind(np.True_) == "shadow" and estimate_kind(np.False_) is None
    t, v = _trace()
    assert fd.creep_metrics(t, v, 1e-3, frequency=np.False_).stick_slip_frequency is None
    with pytest.raises(ParameterError, match=r"^controller\.velocity_feedforward = 'yes': "
                                             r"expected true or false$"):
        params.replace_path("controller.velocity_feedforward", "yes")


# ---------------------------------------------------- 2: a load record shorter than the run

def _loaded_run(force_end: float, duration: float) -> fd.Result:
    t = np.linspace(0.0, 0.1, 11)
    load = fd.LoadProfile(t, force_end * t / 0.1)
    system = fd.DriveSystem(fd.preset("linear-motor-example"), "linear-motor", load=load)
    return fd.simulate(system, fd.ConstantSpeed(1e-3, ramp_time=0.0), duration)


def test_a_run_longer_than_its_load_record_says_the_last_force_is_held() -> None:
    """A LoadProfile shorter than the run was taken without a word; the model holds its last
    force to the run's end (a ramp-and-hold load is meant so: kept, not refused), and the
    summary now says so, in the numbers the run used (saved and read back too)."""
    import xarray as xr

    result = _loaded_run(10.0, 0.3)
    assert result["load_force"][-1] == pytest.approx(10.0)  # held, not dropped to 0
    says = [w for w in result.summary()["warnings"] if w.startswith("the load record")]
    assert says == ["the load record ends at 0.1 s, before the run's end 0.3 s: its last "
                    "force 10 N is held to the end (LoadProfile holds its last value; end "
                    "the record at 0 N for no load after it, or run only as long as the "
                    "record)"]
    reread = fd.Result(xr.Dataset(attrs=dict(result.dataset.attrs),
                                  data_vars=dict(result.dataset.data_vars)))
    assert says[0] in reread.summary()["warnings"]


@pytest.mark.parametrize(("force_end", "duration"), [(10.0, 0.1), (0.0, 0.3)])
def test_a_load_record_as_long_as_the_run_or_ending_at_zero_says_nothing(
        force_end: float, duration: float) -> None:
    warnings = _loaded_run(force_end, duration).summary()["warnings"]
    assert not [w for w in warnings if "load record" in w]


# ----------------------------------------------------------- 3: a Target's drive, when made

def test_a_target_refuses_an_unknown_drive_when_made() -> None:
    """``Target("xdfs", …)`` was taken and refused only by ``calibrate``; it is checked when
    made, as ``DriveSystem`` checks its drive, in the same words."""
    with pytest.raises(ParameterError, match=r"^target\.drive = 'xdfs': expected one of "
                                             r"cdfs, ddfs, .* \(did you mean 'ddfs'\?\)$"):
        fd.Target("xdfs", 1.56e-3)
    assert fd.Target("ddfs", 1.56e-3).drive == "ddfs"


# ------------------------------------------------------ 4: DriveParameters.section's name

@pytest.mark.parametrize(("name", "shown"), [(["x"], r"\['x'\]"), (3, "3"), (None, "None")])
def test_a_section_name_that_is_no_string_is_refused(params: fd.DriveParameters,
                                                    name: object, shown: str) -> None:
    """``P.section(['x'])`` was "unhashable type: 'list'", ``P.section(3)`` returned None, as
    for a section the set does not give."""
    with pytest.raises(ParameterError, match=rf"^name = {shown}: expected a section's name "
                                             r"\(str\), e\.g\. one of acceleration_feedforward, "
                                             r"backlash, .*, table$"):
        params.section(name)  # type: ignore[arg-type]
    assert params.section("backlash") is None  # registered, not given: absent
    assert params.section("screw") is params.screw


# ---------------------------------------------------------- 6: SolverOptions.origin's type

@pytest.mark.parametrize(("origin", "field", "says"), [
    (3, "options.origin = 3", "expected pairs (setting, source) of text"),
    ("accuracy", "options.origin = 'accuracy'", "expected pairs (setting, source) of text"),
    ((("accuracy", 3),), "options.origin[0] = ('accuracy', 3)",
     "expected pairs (setting, source) of text"),
    ((("acuracy", "API"),), "options.origin[0] = ('acuracy', 'API')",
     "expected a setting of SolverOptions, one of method, "),
])
def test_solver_options_refuse_an_origin_that_is_no_pairs(origin: object, field: str,
                                                         says: str) -> None:
    """``origin`` is the API's (``SolverOptions(accuracy=1.0, origin=(("accuracy", "API"),))``
    holds a default against a set's [solver] table): ``origin=3`` was "'int' object is not
    iterable", a misspelt setting's source was kept and never asked for."""
    with pytest.raises(ParameterError, match="^" + re.escape(f"{field}: {says}")):
        fd.SolverOptions(accuracy=1.0, origin=origin)  # type: ignore[arg-type]


def test_solver_options_take_an_origin_as_pairs_or_a_mapping() -> None:
    for origin in ([("accuracy", "API")], {"accuracy": "API"}, (("accuracy", "API"),)):
        options = fd.SolverOptions(accuracy=1.0, origin=origin)  # type: ignore[arg-type]
        assert options.origin == (("accuracy", "API"),)
        assert options.source("accuracy") == "API"


def test_the_machine_api_flags_refuse_what_is_not_a_bool() -> None:
    """The machine's flag arguments, left out by the sweep (its scope was ``feeddrive``'s
    ``__all__`` and the analyses): ``"yes"`` was read as true, ``0`` as counter-clockwise."""
    from feeddrive.machine import load_machine
    from feeddrive.machine.contour import Circle
    from feeddrive.machine.linear import axis_loops, linearize_machine

    machine = load_machine("xy-table")
    with pytest.raises(ParameterError, match=r"^frictionless = 'yes': expected True or False$"):
        linearize_machine(machine, frictionless="yes")  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=r"^frictionless = 1: expected True or False$"):
        axis_loops(machine, frictionless=1)  # type: ignore[arg-type]
    with pytest.raises(ParameterError,
                       match=r"^contour\.clockwise = 0: expected True or False$"):
        Circle(feed=0.01, acceleration=1.0, radius=0.01, clockwise=0)  # type: ignore[arg-type]
    assert Circle(feed=0.01, acceleration=1.0, radius=0.01, clockwise=np.True_).clockwise is True
