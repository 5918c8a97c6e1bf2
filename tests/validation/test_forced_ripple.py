"""The torque-ripple reading (issue 14): a forced oscillation whose critical speed is defined
by a ripple threshold, reported with the threshold and its sensitivity."""

from __future__ import annotations

import inspect
import math

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.analysis import forced
from feeddrive.analysis.forced import ripple_point, threshold_critical_speed
from feeddrive.model.disturbances import TorqueRipple
from feeddrive.model.reference import ConstantSpeed

RIPPLE = fd.preset("wang2021-ripple")


@pytest.fixture(scope="module")
def ddfs16_searches() -> list[dict]:
    """The DDFS searches at v_n = 16 mm/s, one per threshold of forced.THRESHOLDS (0.5, the
    default, among them): computed once, read by two tests (each ran its own 0.5 search)."""
    system = fd.DriveSystem(RIPPLE, "ddfs", 0.4)
    return [threshold_critical_speed(system, 16e-3, threshold=th) for th in forced.THRESHOLDS]


def test_ripple_reading_meets_the_ddfs_targets_by_the_half_threshold(
        ddfs16_searches: list[dict]) -> None:
    """Issue 14 targets on `wang2021-ripple`, 50 % threshold: DDFS 0.40–0.60 mm/s at v_n = 16
    and 20 mm/s (Wang2021 Fig. 8: 0.50; Sect. 6: 0.52 measured); the CDFS is unchanged."""
    default = inspect.signature(threshold_critical_speed).parameters["threshold"].default
    assert default == 0.5
    d16 = ddfs16_searches[forced.THRESHOLDS.index(default)]
    d20 = threshold_critical_speed(fd.DriveSystem(RIPPLE, "ddfs", 0.4), 20e-3)
    assert 0.40 <= d16["critical_speed_mm_s"] <= 0.60
    assert 0.40 <= d20["critical_speed_mm_s"] <= 0.60
    assert d20["critical_speed_mm_s"] <= d16["critical_speed_mm_s"]
    assert d16["kind"] == "oscillation"  # forced: the table never stops
    c = threshold_critical_speed(fd.DriveSystem(RIPPLE, "cdfs", 0.4), 0.0)
    assert 1.40 <= c["critical_speed_mm_s"] <= 1.72
    # the README's first screen states this number
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    assert (f"{d16['critical_speed_mm_s']:.2f} mm/s only with motor torque ripple added "
            "(`wang2021-ripple`)") in " ".join(readme.split())


def test_threshold_sensitivity_is_monotonic_and_stated(monkeypatch,
                                                      ddfs16_searches: list[dict]) -> None:
    system = fd.DriveSystem(RIPPLE, "ddfs", 0.4)
    values = ddfs16_searches
    speeds = [v["critical_speed_mm_s"] for v in values]
    assert speeds[0] > speeds[1] > speeds[2]  # a stricter threshold, a higher speed
    assert all(f"below {th:g} ×" in v["rule"] for th, v in zip(forced.THRESHOLDS, values,
                                                               strict=True))
    # the searches sharing their ripple runs give the same answers, points and all, with
    # fewer runs than the three searches alone
    runs: list[float] = []
    original = forced.ripple_point

    def counted(*args: object, **kw: object) -> forced.ForcedRipplePoint:
        runs.append(float(args[1]))  # type: ignore[arg-type]
        return original(*args, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(forced, "ripple_point", counted)
    shared = forced.threshold_critical_speeds(system, 16e-3)
    assert shared == values
    assert len(runs) == len(set(runs)) < sum(len(v["points"]) for v in values)


def test_forced_ripple_does_not_depend_on_the_window() -> None:
    """The steady ripple of the 12-s trial equals that of a 24-s trial within 1 %."""
    system = fd.DriveSystem(RIPPLE, "ddfs", 0.4)
    a = ripple_point(system, 0.5e-3, 16e-3, duration=12.0)
    b = ripple_point(system, 0.5e-3, 16e-3, duration=24.0)
    assert a.ripple_ratio == pytest.approx(b.ripple_ratio, rel=0.01)


def test_open_loop_ripple_matches_the_rigid_body_response() -> None:
    """Issue 14 acceptance: one harmonic of torque ripple in an open-loop constant-speed run
    gives the analytically expected table-speed ripple within 2 %.  A linear motor is not
    needed: the CDFS with the motor disconnected (torque_off), friction off, set spinning at
    v0 carries a torque T_r sin(nθ) on the screw; with the screw–table stiffness far above
    the ripple frequency the body is rigid, J_eq v̇/H = T_r sin(nθ), θ ≈ v0 t/H, so the speed
    ripple amplitude is T_r·H/(J_eq·n·ω0), ω0 = v0/H, J_eq = J_s + m_t H²."""
    amp, order, v0 = 0.0135, 6.0, 20e-3
    p = (fd.preset("wang2021").replace_path("controller.mode", "torque_off")
         .replace_path("disturbances.screw_motor_ripple", TorqueRipple((order,), (amp,),
                                                                        (0.0,))))
    for site in ("screw", "nut", "guide"):
        p = p.replace_path(f"friction.{site}.law", "none")
    H = p.screw.transmission_ratio
    system = fd.DriveSystem(p, "cdfs", 0.4, initial_state={"screw_speed": v0 / H,
                                                            "table_speed": v0})
    r = fd.simulate(system, ConstantSpeed(0.0), 1.0)
    model = system.model(ConstantSpeed(0.0))
    j_eq = model.parameter("screw.J") + model.parameter("table.mass") * H**2
    omega0 = v0 / H
    expected = amp * H / (j_eq * order * omega0)  # [m/s] amplitude of the speed ripple
    v = r["table_speed"][r.time > 0.2]
    measured = 0.5 * (np.max(v) - np.min(v))
    assert measured == pytest.approx(expected, rel=0.02)
    assert not math.isnan(measured)


def test_threshold_speed_does_not_depend_on_the_scan_grid() -> None:
    """The answer is the lowest multiple of the resolution that passes, whatever the scan."""
    system = fd.DriveSystem(RIPPLE, "ddfs", 0.4)
    a = threshold_critical_speed(system, 16e-3, speed_range=(0.05e-3, 3.0e-3),
                                 coarse_step=0.2e-3)
    b = threshold_critical_speed(system, 16e-3, speed_range=(0.02e-3, 3.02e-3),
                                 coarse_step=0.13e-3)
    assert a["critical_speed_mm_s"] == b["critical_speed_mm_s"]


def test_creep_cli_ripple_threshold_gives_the_forced_critical_speed() -> None:
    """`feeddrive creep --preset wang2021-ripple --drive ddfs --nut-speed 16 --ripple-threshold
    0.5 --json` (issue 14 acceptance on the ripple reading)."""
    import json

    from typer.testing import CliRunner

    from feeddrive.cli import app

    res = CliRunner().invoke(app, ["creep", "--preset", "wang2021-ripple", "--drive", "ddfs",
                                   "--nut-speed", "16", "--ripple-threshold", "0.5", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert 0.40 <= out["critical_speed_mm_s"] <= 0.60
    assert "0.5 × the command" in out["rule"] and out["kind"] == "oscillation"
