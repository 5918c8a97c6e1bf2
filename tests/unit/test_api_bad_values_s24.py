"""API arguments an outside check found unchecked (2026-12-07): each is now a ParameterError
naming the argument, the value and the range, before any work — a tolerance of 0 no longer
loops for ever, a coarse frequency grid no longer gives margins read between its points."""

from __future__ import annotations

import math

import pytest

import feeddrive as fd
from feeddrive.analysis.linear import MIN_POINTS_PER_DECADE
from feeddrive.parameters import ParameterError

SYSTEM = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)


@pytest.mark.parametrize("tolerance", [0.0, -1e-6, math.nan, math.inf])
def test_a_band_edge_tolerance_that_never_stops_or_stops_at_once_is_refused(
        tolerance: float) -> None:
    """0 never returned (the bisection's `while b - a > tolerance`); NaN returned the band
    0.135–3.029 mm/s for the true 0.172–1.399."""
    for call in (fd.stability_band, fd.linear.upper_band_edge):
        with pytest.raises(ParameterError, match="expected a finite speed > 0") as err:
            call(SYSTEM, points=5, tolerance=tolerance)
        assert err.value.field == "tolerance"


@pytest.mark.parametrize("tolerance", [0.0, -0.01, math.nan, 2.0])
def test_a_calibration_tolerance_that_never_stops_is_refused(tolerance: float) -> None:
    with pytest.raises(ParameterError) as err:
        fd.calibrate(fd.preset("wang2021"), fd.Target("cdfs", 1.56e-3),
                     fd.Unknown("controller.velocity_integral_gain", 1000.0, 5000.0),
                     relative_tolerance=tolerance)
    assert err.value.field == "relative_tolerance"


@pytest.mark.parametrize(("kwargs", "field"), [
    ({"points": 0}, "points"), ({"points": 10.5}, "points"), ({"points": 3}, "points"),
    ({"f_min": 0.0}, "f_min"), ({"f_min": math.nan}, "f_min"), ({"f_max": math.inf}, "f_max"),
    ({"f_min": 100.0, "f_max": 1.0}, "f_max"),
])
def test_a_loop_analysis_grid_that_cannot_give_margins_is_refused(kwargs: dict,
                                                                  field: str) -> None:
    """points=0 was numpy's IndexError, 10.5 its TypeError, f_min=0 five RuntimeWarnings and
    no margins, 3 points a 65.5-dB gain margin for the true 2.59 dB."""
    with pytest.raises(ParameterError) as err:
        fd.loop_analysis(SYSTEM, **kwargs)
    assert err.value.field == field


def _control_loop(lin: object, inp: str, out: str) -> tuple[object, object]:
    """L = 1/S − 1 and T = 1 − S as python-control systems, S the transfer the loop's
    disturbance input sees (the linear model's matrices; the margins' extraction is what is
    checked, by python-control's own ``margin`` and ``bandwidth``)."""
    import control as ct
    import numpy as np

    i, o = lin.inputs.index(inp), lin.outputs.index(out)  # type: ignore[attr-defined]
    A, B = lin.A, lin.B[:, [i]]  # type: ignore[attr-defined]
    C, D = lin.C[[o]], lin.D[[o]][:, [i]]  # type: ignore[attr-defined]
    d = float(D[0, 0])
    s_inverse = ct.ss(A - B @ C / d, B / d, -C / d, np.array([[1.0 / d]]))
    return s_inverse - 1, 1 - ct.ss(A, B, C, D)


@pytest.mark.parametrize("points", [None, "fewest"])
def test_the_margins_are_python_controls_whatever_the_grid(points: str | None) -> None:
    """The margins and bandwidth are located between the grid's points: at the default 400
    and at the fewest allowed they equal python-control's ``margin`` and ``bandwidth`` of the
    same transfers (interpolated on the grid, the position loop's gain margin read 3.02 dB on
    400 points, 4.32 on 150: python-control's is 2.589)."""
    import control as ct
    import numpy as np

    fewest = math.ceil(MIN_POINTS_PER_DECADE * math.log10(500.0 / 0.5))
    result = fd.loop_analysis(SYSTEM, **({} if points is None else {"points": fewest}))
    position, velocity = result.loops
    lin = result.linear
    L, T = _control_loop(lin, "screw_speed_command_disturbance", "screw_speed_command")
    gm, pm, wcg, wcp = ct.margin(L)
    assert position.gain_margin_db == pytest.approx(20 * np.log10(gm), rel=1e-6)
    assert position.phase_margin_deg == pytest.approx(pm, rel=1e-6)
    assert position.crossover_hz == pytest.approx(wcp / (2 * np.pi), rel=1e-6)
    assert position.bandwidth_hz == pytest.approx(ct.bandwidth(T) / (2 * np.pi), rel=1e-6)
    assert 2.5 < position.gain_margin_db < 2.7  # measured: 2.589 dB at 5.57 Hz
    # the velocity loop (position loop opened): its phase margin and crossover
    from dataclasses import replace

    from feeddrive.analysis.linear import linearize

    open_position = replace(SYSTEM, parameters=SYSTEM.parameters.replace_path(
        "controller.position_gain", 0.0))
    L, T = _control_loop(linearize(open_position, 1e-3, 0.0, frictionless=True),
                         "screw_current_command_disturbance", "screw_current_command")
    gm, pm, wcg, wcp = ct.margin(L)
    assert velocity.phase_margin_deg == pytest.approx(pm, rel=1e-6)
    assert velocity.crossover_hz == pytest.approx(wcp / (2 * np.pi), rel=1e-6)
    # T's DC gain is infinite to python-control (the open position loop leaves the table
    # free: A is singular), so its bandwidth() is NaN; the −3 dB point of its own response
    # (|T| → 1 as f → 0; T evaluated by python-control, the root by scipy's brentq) instead
    from scipy.optimize import brentq

    def below_3_db(f: float) -> float:
        return 20 * np.log10(abs(complex(T(2j * np.pi * f)))) + 3.0

    assert velocity.bandwidth_hz == pytest.approx(brentq(below_3_db, 1.0, 100.0, xtol=1e-12),
                                                  rel=1e-6)
    # (no gain margin: no −180° crossing above the crossover; python-control's margin takes
    # the crossing near DC, where the free table's integrator turns the phase)


@pytest.mark.parametrize("interval", [0.0, -1e-3, math.nan])
def test_a_built_profiles_interval_is_checked(interval: float) -> None:
    """interval=0 was a ZeroDivisionError, −1e-3 an empty profile, NaN blamed the duration."""
    for build in (lambda: fd.trapezoid(1e-3, 2.0, interval=interval),
                  lambda: fd.stepdown(2e-3, 1e-3, step=5e-4, interval=interval)):
        with pytest.raises(ParameterError) as err:
            build()
        assert err.value.field == "interval"


def test_one_path_given_as_text_is_refused_naming_the_argument() -> None:
    """fit_drive(free="a.b") said "--free: _ given twice" (its letters read as paths), and
    sensitivity(patterns="a.b") "--parameters = ['c', 'o', 'n', …]: matches no numeric
    parameter" (an outside check, 2026-12-07)."""
    from feeddrive.analysis.fit import FitError, fit_drive
    from feeddrive.analysis.sensitivity import sensitivity

    with pytest.raises(FitError, match=r"free = 'controller.velocity_gain': expected a list"):
        fit_drive(fd.preset("wang2021"), [object()], "controller.velocity_gain")  # type: ignore[list-item, arg-type]
    with pytest.raises(ParameterError, match=r"patterns = 'controller.velocity_gain'"):
        sensitivity(fd.preset("wang2021"), patterns="controller.velocity_gain", in_process=True)


def test_sensitivity_refuses_a_position_in_the_metres_it_was_given() -> None:
    """0.9 m was reported as "table_position = 900.0 … the configuration's positions are in
    mm" (the sweep it builds takes mm)."""
    from feeddrive.analysis.sensitivity import sensitivity

    with pytest.raises(ParameterError, match=r"table_position = 0.9: expected 0 < a < 0.8 \[m\]"):
        sensitivity(fd.preset("wang2021"), table_position=0.9,
                    patterns=["controller.velocity_gain"], in_process=True)


@pytest.mark.parametrize(("loop", "broken"), [("screw_position_loop", "speed"),
                                              ("screw_velocity_loop", "current")])
def test_a_loop_gain_names_the_signals_it_is_broken_at(loop: str, broken: str) -> None:
    """The loop gain's input and output were "screw_velocity_command_disturbance" /
    "screw_velocity_command", no signals of the model (an outside check, 2026-12-07): they
    are where loop_analysis breaks the loop, and taken back as a pair they give the
    sensitivity S of which the gain is 1/S − 1."""
    from dataclasses import replace

    import numpy as np

    fr = fd.frequency_response(SYSTEM, loop, frequency_hz=np.array([1.0, 5.0]))
    assert (fr.input, fr.output) == (f"screw_{broken}_command_disturbance",
                                     f"screw_{broken}_command")
    system = SYSTEM if broken == "speed" else replace(
        SYSTEM, parameters=SYSTEM.parameters.replace_path("controller.position_gain", 0.0))
    s = fd.frequency_response(system, fr.input, fr.output, frequency_hz=fr.frequency_hz)
    np.testing.assert_allclose(fr.response, 1.0 / s.response - 1.0, rtol=1e-12)


def test_a_dask_cluster_serves_its_http_on_a_free_loopback_port(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """With ``dashboard_address=None`` the scheduler's HTTP server (health, metrics) took
    0.0.0.0:8787, and a second cluster at once printed distributed's "Port 8787 is already in
    use" beside a command's one line (a Ctrl-C test beside another Dask run, 2026-12-07)."""
    import distributed

    from feeddrive.sweep.executors import executor

    seen: dict[str, object] = {}

    class Stop(Exception):
        pass

    def cluster(**kwargs: object) -> None:
        seen.update(kwargs)
        raise Stop

    monkeypatch.setattr(distributed, "LocalCluster", cluster)
    with pytest.raises(Stop), executor(dask_workers=1):
        pass
    assert seen["dashboard_address"] == "127.0.0.1:0"
