"""Accuracy of the compiled engine against independent references.

* friction off: the adaptive engine follows the exact linear response (matrix exponential of
  the hand-derived augmented matrix, ``reference/linear_model.py``);
* creeping runs: ripple amplitude and stick-slip period agree with the scipy Radau
  references (rtol 1e-10) stored in ``tests/data`` by ``reference/make_radau_reference.py``;
* the engine's right-hand side equals the plain-Python model of
  ``reference/scipy_model.py`` at random states, for both drives and many option
  combinations (a cross-check of both implementations).
"""

from __future__ import annotations

import sys
import zlib
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.cases import RADAU_CASES, Case  # noqa: E402
from reference.linear_model import augmented_matrix, exact_response  # noqa: E402
from reference.make_radau_reference import stick_slip_figures  # noqa: E402
from reference.scipy_model import STATE_NAMES, ReferenceModel  # noqa: E402

import feeddrive  # noqa: E402
from feeddrive.engine.simulate import DriveSystem, SolverOptions, simulate  # noqa: E402
from feeddrive.model.mechanisms.ball_screw_stiffness import equivalent_stiffness  # noqa: E402
from feeddrive.model.reference import ConstantSpeed, SineSpeed  # noqa: E402

IX = {name: k for k, name in enumerate(STATE_NAMES)}

DATA = ROOT / "tests" / "data"


# ---------------------------------------------------------------- friction off: exact response

LINEAR_VARIANTS = {
    "literal": {},
    "table-basis": {"controller.velocity_gain_basis": "table"},
    "kv-velocity-error": {"controller.kv_placement": "velocity_error",
                          "controller.velocity_feedback": "table"},
    "kv-position-output": {"controller.velocity_gain_basis": "table",
                           "controller.kv_placement": "position_output"},
    "no-feedforward": {"controller.velocity_feedforward": False,
                       "stiffness.screw_support": "fixed-free"},
}


def _params(changes: dict[str, object], axial_damping: float = 2000.0) -> feeddrive.DriveParameters:
    p = (feeddrive.preset("wang2021-literal")
         .replace_path("stiffness.axial_damping", axial_damping)
         .replace_path("stiffness.position_dependent", False))
    for site in ("screw", "nut", "guide"):
        p = p.replace_path(f"friction.{site}.law", "none")
    for path, value in changes.items():
        p = p.replace_path(path, value)
    return p


def _frictionless_run(params: feeddrive.DriveParameters, drive: str, profile: ConstantSpeed,
                      duration: float, options: SolverOptions) -> tuple[np.ndarray, np.ndarray,
                                                                         np.ndarray]:
    result = simulate(DriveSystem(params, drive, 0.4), profile, duration, options=options)
    y = np.column_stack([result[name] if name in result.dataset else np.zeros(result.time.size)
                         for name in STATE_NAMES])
    return result.time, y, result.solver_stats


@pytest.mark.parametrize("variant", sorted(LINEAR_VARIANTS))
@pytest.mark.parametrize(("drive", "nut_speed"), [("cdfs", 0.0), ("ddfs", 16e-3)])
def test_frictionless_adaptive_engine_matches_exact_linear_response(
        variant: str, drive: str, nut_speed: float) -> None:
    params = _params(LINEAR_VARIANTS[variant])
    profile = ConstantSpeed(table_speed=1.5e-3, nut_speed=nut_speed, ramp_time=0.0)
    A = augmented_matrix(params, drive, 1.5e-3, nut_speed, equivalent_stiffness(params, 0.4))
    tight = SolverOptions(rtol=1e-10, position_tolerance=1e-15, speed_tolerance=1e-13,
                          current_tolerance=1e-11)
    t, y, _ = _frictionless_run(params, drive, profile, 0.2, tight)
    y_exact = exact_response(A, t)
    for name in ("table_position", "table_speed", "screw_speed", "nut_speed", "screw_current"):
        k = STATE_NAMES.index(name)
        scale = np.max(np.abs(y_exact[:, k]))
        if scale == 0.0:
            assert np.all(y[:, k] == 0.0)
            continue
        err = np.max(np.abs(y[:, k] - y_exact[:, k])) / scale
        assert err < 1e-8, (name, err)


def test_frictionless_engine_at_default_tolerances_is_accurate_to_them() -> None:
    """Default tolerances with ``dopri5`` (steps capped at 1 ms): the global error stays within
    a few times the local targets (speed_tolerance = 1e-8 m/s, position_tolerance = 1e-10 m).
    The default method ``modal`` takes uncapped steps and accumulates 2.8e-7 m/s on this case
    (the 200-Hz table mode); its bound is checked at 10× tighter tolerances
    (tests/unit/test_solver_rodas4.py::test_dense_output_follows_the_exact_response…)."""
    params = _params({"controller.velocity_gain_basis": "table"})
    profile = ConstantSpeed(table_speed=1.5e-3, ramp_time=0.0)
    A = augmented_matrix(params, "cdfs", 1.5e-3, 0.0, equivalent_stiffness(params, 0.4))
    t, y, _ = _frictionless_run(params, "cdfs", profile, 0.5, SolverOptions(method="dopri5"))
    y_exact = exact_response(A, t)
    err = np.max(np.abs(y[:, IX['table_speed']] - y_exact[:, IX['table_speed']]))
    assert err < 5e-8, err
    assert np.max(np.abs(y[:, IX['table_position']] - y_exact[:, IX['table_position']])) < 5e-10


# ---------------------------------------------------------------- creeping: Radau references


def _engine_run(case: Case) -> tuple[np.ndarray, np.ndarray]:
    r = simulate(DriveSystem(case.parameters(), case.drive, 0.4), case.profile(), case.duration)
    return r.time, r["table_speed"]


@pytest.mark.parametrize("case", RADAU_CASES, ids=[c.name for c in RADAU_CASES])
def test_engine_matches_radau_reference_ripple_and_period(case: Case) -> None:
    ref = np.load(DATA / f"radau_{case.name}.npz")
    t, v = _engine_run(case)
    np.testing.assert_allclose(t, ref["time"], rtol=0, atol=1e-12)
    window = (float(ref["window"][0]), float(ref["window"][1]))
    figures = stick_slip_figures(t, v, window)
    # the case really creeps: a ripple larger than the command, tens of periods in the window
    assert float(ref["ripple"]) > abs(case.table_speed)
    assert float(ref["cycles"]) >= 20
    assert figures["ripple"] == pytest.approx(float(ref["ripple"]), rel=0.02)
    assert figures["period"] == pytest.approx(float(ref["period"]), rel=0.02)
    assert figures["mean_speed"] == pytest.approx(float(ref["mean_speed"]), rel=0.02)
    # and sample by sample the traces agree far better than that
    assert np.max(np.abs(v - ref["table_speed"])) < 0.002 * float(ref["ripple"])


def test_radau_reference_files_are_the_current_cases() -> None:
    for case in RADAU_CASES:
        ref = np.load(DATA / f"radau_{case.name}.npz")
        assert str(ref["case"]) == repr(case)
        assert float(ref["rtol"]) <= 1e-10
        # the stored text predates fields added later with defaults: compare the parameter
        # sets it describes, not the text
        assert feeddrive.parameters.loads(str(ref["parameters_toml"])) == case.parameters()


# ---------------------------------------------------------------- RHS cross-check

RHS_VARIANTS: dict[str, dict[str, object]] = {
    "literal": {},
    "damped-table": {"stiffness.axial_damping": 3000.0,
                     "controller.velocity_gain_basis": "table"},
    "kv-position-output": {"controller.velocity_gain_basis": "table",
                           "controller.kv_placement": "position_output"},
    "kv-velocity-error-table-feedback": {"controller.kv_placement": "velocity_error",
                                         "controller.velocity_feedback": "table"},
    "pi-loops-saturating": {"controller.velocity_integral_gain": 2000.0,
                            "controller.current_integral_gain": 500.0,
                            "controller.current_limit": 3.0,
                            "controller.voltage_limit": 8.0},
    "no-ff-fixed-free-no-torsion": {"controller.velocity_feedforward": False,
                                    "stiffness.screw_support": "fixed-free",
                                    "stiffness.include_torsion": False,
                                    "stiffness.support_bearing_count": 1.0},
    "fixed-stiffness-override": {"stiffness.equivalent_stiffness": 2.16e7},
    "frozen-stiffness": {"stiffness.position_dependent": False},
    "nut-speed-loop": {"controller.nut_loop": "speed",
                       "controller.velocity_gain_basis": "table"},
}


def _random_states(rng: np.random.Generator, times: np.ndarray, model: ReferenceModel,
                   nut: bool) -> np.ndarray:
    """Physically sized random states at ``times``; some speeds exactly 0 (the friction branch
    point).  Half the samples follow the reference within µm and tens of µm/s (loops in their
    linear range), half are anywhere within ±50 mm and ±mm/s (saturated loops, K_eq far from
    mid-screw)."""
    n = times.size
    H = model.H
    refs = np.array([model.reference(float(t)) for t in times])
    near = rng.random(n) < 0.5
    x_t = np.where(near, refs[:, 0] + rng.normal(0.0, 2e-6, n), rng.uniform(-0.05, 0.05, n))
    x_n = np.where(near, refs[:, 2] + rng.normal(0.0, 2e-6, n), rng.uniform(-0.05, 0.05, n))
    th_n = x_n / H if nut else np.zeros(n)
    y = np.zeros((n, len(STATE_NAMES)))
    y[:, IX['nut_angle']] = th_n
    y[:, IX['screw_angle']] = (x_t + rng.normal(0.0, 5e-6, n)) / H + th_n
    y[:, IX['table_position']] = x_t
    spread = np.where(near, 5e-5, 2e-3)[:, None]
    speeds = refs[:, [1, 3, 1]] + spread * rng.normal(0.0, 1.0, (n, 3))
    speeds[:, 0] += refs[:, 3]
    speeds[rng.random((n, 3)) < 0.15] = 0.0
    y[:, IX['screw_speed']] = speeds[:, 0] / H
    y[:, IX['nut_speed']] = speeds[:, 1] / H if nut else 0.0
    y[:, IX['table_speed']] = speeds[:, 2]
    y[:, IX['screw_bristle']] = rng.uniform(-3e-6, 3e-6, n)
    y[:, IX['nut_bristle']] = rng.uniform(-3e-4, 3e-4, n) if nut else 0.0
    y[:, IX['guide_bristle']] = rng.uniform(-5e-5, 5e-5, n)
    y[:, IX['screw_current']] = rng.normal(0.0, 2.0, n)
    y[:, IX['nut_current']] = rng.normal(0.0, 2.0, n) if nut else 0.0
    y[:, IX['screw_velocity_integral']] = rng.normal(0.0, 1e-3, n)
    y[:, IX['nut_velocity_integral']] = rng.normal(0.0, 1e-3, n) if nut else 0.0
    y[:, IX['screw_current_integral']] = rng.normal(0.0, 1e-2, n)
    y[:, IX['nut_current_integral']] = rng.normal(0.0, 1e-2, n) if nut else 0.0
    return y


DRIVE_SETUPS = {
    # name: (drive, nut_hold, profile)
    "cdfs-locked-constant": ("cdfs", "locked", ConstantSpeed(1.5e-3, ramp_time=0.3)),
    "cdfs-servo-sine": ("cdfs", "servo", SineSpeed(2e-3, 0.0, frequency=0.7)),
    "ddfs-constant": ("ddfs", "locked", ConstantSpeed(0.5e-3, 16e-3, ramp_time=0.3)),
    "ddfs-sine": ("ddfs", "locked", SineSpeed(1e-3, 5e-3, frequency=0.4)),
}


def test_reference_state_order_matches_engine_layout() -> None:
    """The assembled ball-screw model's states are generated from its parts; their order is
    the reference model's (the cross-check below relies on it)."""
    model = DriveSystem(feeddrive.preset("wang2021"), "ddfs", 0.4).model(ConstantSpeed(1e-3))
    assert model.state_names == STATE_NAMES


@pytest.mark.parametrize("variant", sorted(RHS_VARIANTS))
@pytest.mark.parametrize("setup", sorted(DRIVE_SETUPS))
def test_engine_rhs_equals_reference_model_at_random_states(variant: str, setup: str) -> None:
    drive, nut_hold, profile = DRIVE_SETUPS[setup]
    params = feeddrive.preset("wang2021-literal")
    for path, value in RHS_VARIANTS[variant].items():
        params = params.replace_path(path, value)
    engine_model = DriveSystem(params, drive, 0.35, nut_hold=nut_hold).model(profile)
    model = ReferenceModel(params, drive, 0.35, profile, nut_hold=nut_hold)
    nut = drive == "ddfs" or nut_hold == "servo"
    rng = np.random.default_rng(zlib.crc32(f"{variant}/{setup}".encode()))
    times = rng.uniform(0.0, 1.0, 200)
    states = _random_states(rng, times, model, nut)
    held = np.zeros(engine_model.n_held)
    aux = np.zeros(len(engine_model.aux))
    a_names = [a.name for a in engine_model.aux]
    a_icmd, a_u = a_names.index("screw_current_command"), a_names.index("screw_voltage")
    engine = np.empty_like(states)
    reference = np.empty_like(states)
    i_cmd, voltage = [], []
    for k, (t, y) in enumerate(zip(times, states, strict=True)):
        dy = np.empty(len(STATE_NAMES))
        engine_model.module.rhs(float(t), y, held, engine_model.P, engine_model.T, dy,
                                aux)
        engine[k] = dy
        i_cmd.append(aux[a_icmd])
        voltage.append(aux[a_u])
        reference[k] = model(float(t), y)
    # relative to each component's typical size over the sample (terms cancel in places)
    scale = np.max(np.abs(reference), axis=0)
    for j, name in enumerate(STATE_NAMES):
        if scale[j] == 0.0:
            assert np.all(engine[:, j] == 0.0), name
            continue
        diff = np.abs(engine[:, j] - reference[:, j])
        bound = 1e-9 * np.maximum(np.abs(reference[:, j]), 1e-3 * scale[j])
        worst = int(np.argmax(diff / bound))
        assert diff[worst] <= bound[worst], (name, worst, engine[worst, j], reference[worst, j])
    # the sample exercises the nonlinear parts: both friction branches, the branch point,
    # and (where limits are set low) saturated and unsaturated loops
    speeds = states[:, [IX['screw_speed'], IX['nut_speed'], IX['table_speed']]]
    assert np.any(speeds < 0) and np.any(speeds > 0) and np.any(speeds == 0.0)
    c = params.controller
    if c.current_limit < 100.0:
        saturated = np.array([abs(a) >= c.current_limit for a in i_cmd])
        assert 0.1 < saturated.mean() < 0.9
    if c.voltage_limit < 100.0:
        saturated = np.array([abs(a) >= c.voltage_limit for a in voltage])
        assert 0.1 < saturated.mean() < 0.9


def test_reference_stiffness_chain_matches_package_stiffness() -> None:
    """The reference's own Eqs. (2)–(5) against feeddrive.model.mechanisms.ball_screw_stiffness
    at Table 3's positions."""
    params = feeddrive.preset("wang2021-literal")
    for a in (0.2, 0.3, 0.4, 0.5, 0.6):
        model = ReferenceModel(params, "cdfs", a, ConstantSpeed(1e-3))
        assert model.equivalent_stiffness(0.0) == pytest.approx(
            equivalent_stiffness(params, a), rel=1e-12)
