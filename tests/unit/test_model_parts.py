"""The composable core through its public API: parts, laws, disturbances, initial state."""

from __future__ import annotations

import math

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.model.disturbances import LeadError, TorqueRipple
from feeddrive.model.friction import FrictionLaw, friction_law, register_friction_law
from feeddrive.model.reference import ConstantSpeed
from feeddrive.parameters import ParameterError, loads
from feeddrive.solvers import builds
from feeddrive.solvers.builds import HAVE_NUMBA

# ---------------------------------------------------------------- a toy law in this file only


@fd.model.kernel
def _toy_viscous_kernel(v, y, k, P, o, dy):  # type: ignore[no-untyped-def]
    """Pure viscous friction F = σ2·v with the branch's σ2 (no state)."""
    return (P[o + 3] if v >= 0.0 else P[o + 7]) * v


class ToyViscous(FrictionLaw):
    name = "toy_viscous"
    kernel = _toy_viscous_kernel


@fd.model.kernel
def _toy_viscous_typed_kernel(v: float, y: np.ndarray, k: int, P: np.ndarray, o: int,
                              dy: np.ndarray) -> float:
    """The same law with type annotations: inside the C subset, so it runs without numba."""
    return (P[o + 3] if v >= 0.0 else P[o + 7]) * v


class ToyViscousTyped(FrictionLaw):
    name = "toy_viscous_typed"
    kernel = _toy_viscous_typed_kernel


needs_numba = pytest.mark.skipif(
    not HAVE_NUMBA, reason="numba is not installed (the optional extra feeddrive[numba]): a "
    "kernel without type annotations runs in the numba build only")


@pytest.mark.parametrize("law", [pytest.param(ToyViscous, marks=needs_numba), ToyViscousTyped],
                         ids=["untyped", "typed"])
def test_a_friction_law_defined_outside_the_package_simulates(law: type[FrictionLaw]) -> None:
    register_friction_law(law())
    params = fd.preset("wang2021").replace_path("friction.guide.law", law.name)
    result = fd.simulate(fd.DriveSystem(params, "cdfs", 0.4), ConstantSpeed(2e-3), 0.5)
    v = result["table_speed"]
    sigma2 = np.where(v >= 0, params.friction.guide.positive.viscous_coefficient,
                      params.friction.guide.negative.viscous_coefficient)
    np.testing.assert_allclose(result["guide_friction"], sigma2 * v, rtol=1e-15, atol=0)
    assert "guide_bristle" not in result.dataset  # a stateless law has no bristle
    assert result["table_position"][-1] > 0.5e-3  # it moved: 2 mm/s for 0.5 s after the ramp


def test_a_law_outside_the_c_subset_runs_in_numba_said_once(
        capfd: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """The toy law's kernel has no type annotations, so the C translator refuses it: the C
    build (the default where a compiler is found) hands that model to numba, says so once in
    one line, and ``FEEDDRIVE_ENGINE=c`` makes it an error naming the kernel."""
    from feeddrive.backends.c_cache import available_compiler
    from feeddrive.backends.c_translate import TranslationError

    if available_compiler() is None:
        pytest.skip("no C compiler: every model runs in numba")
    register_friction_law(ToyViscous())
    params = fd.preset("wang2021").replace_path("friction.guide.law", "toy_viscous")
    system = fd.DriveSystem(params, "cdfs", 0.3)
    monkeypatch.delenv("FEEDDRIVE_ENGINE", raising=False)
    if not HAVE_NUMBA:  # neither build can run it: one line naming the kernel and the extra
        with pytest.raises(builds.NoEngine) as absent:
            fd.simulate(system, ConstantSpeed(2e-3), 0.05)
        message = str(absent.value)
        assert "\n" not in message and "_toy_viscous_kernel" in message
        assert "pip install 'feeddrive[numba]'" in message
        return
    capfd.readouterr()
    first = fd.simulate(system, ConstantSpeed(2e-3), 0.05)
    second = fd.simulate(system, ConstantSpeed(1e-3), 0.05)
    said = [line for line in capfd.readouterr().err.splitlines() if "numba build" in line]
    assert first.solver_stats["engine"] == second.solver_stats["engine"] == "numba"
    assert len(said) <= 1  # once per model structure (an earlier test may have said it)
    assert all("_toy_viscous_kernel" in line for line in said)
    plain = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.3), ConstantSpeed(2e-3),
                        0.05)
    assert plain.solver_stats["engine"] == "c"
    monkeypatch.setenv("FEEDDRIVE_ENGINE", "c")
    with pytest.raises(TranslationError, match="_toy_viscous_kernel"):
        fd.simulate(fd.DriveSystem(params, "cdfs", 0.35), ConstantSpeed(2e-3), 0.05)


def test_unknown_law_is_refused_with_the_field_named() -> None:
    with pytest.raises(ParameterError, match=r"friction\.nut\.law.*unknown friction law"):
        fd.preset("wang2021").replace_path("friction.nut.law", "coulomb-ish")


# ---------------------------------------------------------------- laws behind one interface

SITE = fd.preset("wang2021").friction.screw


@pytest.mark.parametrize("v", [-4e-3, -3e-4, 2e-4, 8.64e-4, 5e-3])
def test_lugre_analytic_linearisation_matches_finite_differences(v: float) -> None:
    law = friction_law("lugre")
    exact = law.linearise(v, SITE)
    numeric = FrictionLaw.linearise(law, v, SITE)
    np.testing.assert_allclose(exact.A, numeric.A, rtol=1e-6)
    np.testing.assert_allclose(exact.B, numeric.B, rtol=1e-5, atol=1e-9)
    np.testing.assert_allclose(exact.C, numeric.C, rtol=1e-6)
    assert exact.D == pytest.approx(numeric.D, rel=1e-5, abs=1e-6)


def test_static_and_lugre_laws_share_the_steady_curve() -> None:
    """Away from v = 0 (|v| ≫ v_ε) the smoothed static law is Table 1's Stribeck curve, the
    LuGre law's steady state (Wang2021 Eq. (11))."""
    v = np.array([-5e-3, -1e-3, -2e-4, 2e-4, 1e-3, 5e-3])
    lugre = friction_law("lugre").steady_force(v, SITE)
    static = friction_law("stribeck").steady_force(v, SITE)
    np.testing.assert_allclose(static, lugre, rtol=1e-12)
    np.testing.assert_allclose(lugre, fd.friction.steady_friction(v, SITE), rtol=1e-12)


def test_dahl_law_steady_force_is_coulomb_plus_viscous() -> None:
    """Dahl (Olsson et al. 1998, Eq. (9), i = 1): steady force F_c·sign(v) + σ2·v."""
    v = np.array([-2e-3, 1e-3])
    expected = [-SITE.negative.coulomb_force + SITE.negative.viscous_coefficient * v[0],
                SITE.positive.coulomb_force + SITE.positive.viscous_coefficient * v[1]]
    np.testing.assert_allclose(friction_law("dahl").steady_force(v, SITE), expected, rtol=1e-12)


def test_no_friction_is_a_law_with_zero_force_and_no_state() -> None:
    params = fd.preset("wang2021")
    for site in ("screw", "nut", "guide"):
        params = params.replace_path(f"friction.{site}.law", "none")
    result = fd.simulate(fd.DriveSystem(params, "ddfs", 0.4), ConstantSpeed(1e-3, 5e-3), 0.3)
    for site in ("screw", "nut", "guide"):
        assert np.all(result[f"{site}_friction"] == 0.0)
        assert f"{site}_bristle" not in result.dataset


# ---------------------------------------------------------------- expressiveness


def test_cdfs_coasts_to_rest_with_torque_off_and_energy_never_rises() -> None:
    """Start at 5 mm/s with the motors disconnected (controller.mode = torque_off), friction
    on: mechanical energy (kinetic + axial spring + LuGre bristle storage ½σ0z²) only falls."""
    w = fd.preset("wang2021").replace_path("controller.mode", "torque_off")
    H = w.screw.transmission_ratio
    system = fd.DriveSystem(w, "cdfs", 0.4,
                            initial_state={"table_speed": 5e-3, "screw_speed": 5e-3 / H})
    profile = ConstantSpeed(0.0)
    # dopri5: every sample a step end (interpolated samples of the dense default wiggle at
    # the tolerance, so their energy need not fall sample by sample to 1e-12)
    ds = fd.simulate(system, profile, 1.5, options=fd.SolverOptions(method="dopri5")).dataset
    model = system.model(profile)
    stretch = H * (ds.screw_angle - ds.nut_angle) - ds.table_position
    energy = (0.5 * model.parameter("screw.J") * ds.screw_speed**2
              + 0.5 * model.parameter("table.mass") * ds.table_speed**2
              + 0.5 * ds.equivalent_stiffness * stretch**2
              + 0.5 * w.friction.screw.bristle_stiffness * ds.screw_bristle**2
              + 0.5 * w.friction.guide.bristle_stiffness * ds.guide_bristle**2).values
    assert energy[0] == pytest.approx(0.5 * (model.parameter("screw.J") / H**2
                                             + model.parameter("table.mass")) * 25e-6)
    assert np.all(np.diff(energy) <= 1e-12 * energy[0])
    assert energy[-1] < 0.01 * energy[0]
    assert abs(ds.table_speed.values[-1]) < 1e-5  # at rest (pre-sliding wobble only)
    assert np.all(ds.screw_current.values == 0.0)


def test_load_force_decelerates_a_free_table_as_newton_says() -> None:
    """Linear motor, torque off, no friction, constant load F from t = 0: v(t) = v0 − F t/m."""
    p = (fd.preset("linear-motor-example").replace_path("controller.mode", "torque_off")
         .replace_path("friction.guide.law", "none")
         .replace_path("disturbances.load_force", 50.0))
    system = fd.DriveSystem(p, "linear-motor", initial_state={"table_speed": 0.01})
    r = fd.simulate(system, ConstantSpeed(0.0), 0.1)
    mass = p.table.mass + p.linear_motor.forcer_mass  # type: ignore[union-attr]
    np.testing.assert_allclose(r["table_speed"], 0.01 - 50.0 * r.time / mass, atol=1e-12)
    assert np.all(r["load_force"] == 50.0)


def test_load_profile_record_is_interpolated() -> None:
    t = np.linspace(0.0, 0.1, 11)
    load = fd.LoadProfile(t, 100.0 * t)
    p = (fd.preset("linear-motor-example").replace_path("controller.mode", "torque_off")
         .replace_path("friction.guide.law", "none"))
    r = fd.simulate(fd.DriveSystem(p, "linear-motor", load=load), ConstantSpeed(0.0), 0.2)
    expected = np.minimum(100.0 * r.time, 10.0)
    np.testing.assert_allclose(r["load_force"], expected, rtol=1e-12, atol=1e-12)


def test_torque_ripple_signal_is_the_declared_harmonic() -> None:
    p = fd.preset("wang2021").replace_path("disturbances.screw_motor_ripple",
                                           TorqueRipple((6.0,), (0.0135,), (0.3,)))
    r = fd.simulate(fd.DriveSystem(p, "cdfs", 0.4), ConstantSpeed(2e-3), 0.5)
    np.testing.assert_allclose(r["screw_ripple_torque"],
                               0.0135 * np.sin(6.0 * r["screw_angle"] + 0.3), atol=1e-15)
    base = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4),
                       ConstantSpeed(2e-3), 0.5)
    assert np.max(np.abs(r["table_speed"] - base["table_speed"])) > 1e-6


def test_lead_error_moves_the_table_by_the_declared_deviation() -> None:
    """Frictionless, rigid-ish CDFS at rest with a lead error: the stretch balance gives a
    table position following δ(θ) — checked through the drive force being zero at rest."""
    p = fd.preset("wang2021").replace_path("disturbances.lead_error",
                                           LeadError((1.0,), (2e-6,), (0.0,)))
    H = p.screw.transmission_ratio
    theta = math.pi / 2  # δ = 2 µm
    for site in ("screw", "nut", "guide"):
        p = p.replace_path(f"friction.{site}.law", "none")
    p = p.replace_path("controller.mode", "torque_off")
    x = H * theta + 2e-6
    system = fd.DriveSystem(p, "cdfs", 0.4, initial_state={"screw_angle": theta,
                                                             "table_position": x})
    r = fd.simulate(system, ConstantSpeed(0.0), 0.01)
    assert np.max(np.abs(r["drive_force"])) < 1e-9
    assert np.max(np.abs(r["table_speed"])) < 1e-15


def test_initial_state_names_are_checked() -> None:
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4,
                            initial_state={"table_velocity": 1e-3})
    with pytest.raises(ParameterError, match="table_velocity.*unknown state.*table_speed"):
        fd.simulate(system, ConstantSpeed(1e-3), 0.1)


def test_zero_gains_run_open_loop() -> None:
    """Every gain zero: no current, the table stays at rest (friction holds it)."""
    p = fd.preset("wang2021")
    for g in ("position_gain", "velocity_gain", "current_gain", "velocity_integral_gain",
              "current_integral_gain"):
        p = p.replace_path(f"controller.{g}", 0.0)
    r = fd.simulate(fd.DriveSystem(p, "cdfs", 0.4), ConstantSpeed(1e-3), 0.2)
    assert np.all(r["screw_current"] == 0.0)
    assert np.all(r["table_position"] == 0.0)


def test_linear_motor_runs_and_tracks() -> None:
    r = fd.simulate(fd.DriveSystem(fd.preset("linear-motor-example"), "linear-motor"),
                    ConstantSpeed(1e-3), 2.0)
    assert set(r.dataset.data_vars) >= {"table_speed", "motor_current", "guide_friction"}
    assert "screw_speed" not in r.dataset
    assert r.summary()["mean_table_speed_mm_s"] == pytest.approx(1.0, rel=0.01)


def test_linear_motor_without_its_section_is_refused() -> None:
    with pytest.raises(ParameterError, match="linear_motor.*needs a \\[linear_motor\\]"):
        fd.DriveSystem(fd.preset("wang2021"), "linear-motor")


def test_ripple_on_a_motor_the_topology_lacks_is_refused() -> None:
    p = fd.preset("linear-motor-example").replace_path("disturbances.hollow_motor_ripple",
                                                       TorqueRipple((6.0,), (0.01,), (0.0,)))
    with pytest.raises(ParameterError, match="hollow_motor_ripple.*no such motor"):
        fd.simulate(fd.DriveSystem(p, "linear-motor"), ConstantSpeed(1e-3), 0.1)


# ---------------------------------------------------------------- one TOML document


def test_partial_file_extends_a_preset() -> None:
    p = loads('extends = "wang2021"\n[stiffness]\nequivalent_stiffness = 21600000.0\n'
              '[friction.screw]\nlaw = "dahl"\n')
    base = fd.preset("wang2021")
    assert p.stiffness.equivalent_stiffness == 2.16e7
    assert p.friction.screw.law == "dahl"
    assert p.friction.screw.bristle_stiffness == base.friction.screw.bristle_stiffness
    assert p.controller == base.controller


def test_file_extends_another_file(tmp_path) -> None:
    (tmp_path / "base.toml").write_text('extends = "wang2021"\n[table]\nmass = 30.0\n')
    (tmp_path / "child.toml").write_text('extends = "base.toml"\n[friction]\n'
                                         'ball_nut_share = 0.5\n')
    p = fd.load(tmp_path / "child.toml")
    assert p.table.mass == 30.0 and p.friction.ball_nut_share == 0.5


def test_parts_round_trip_through_toml() -> None:
    p = (fd.preset("wang2021").replace_path("friction.guide.law", "stribeck")
         .replace_path("disturbances.screw_motor_ripple",
                       TorqueRipple((6.0, 12.0), (0.01, 0.002), (0.0, 1.0))))
    assert loads(fd.parameters.dumps(p)) == p
    lm = fd.preset("linear-motor-example")
    assert loads(fd.parameters.dumps(lm)) == lm


@pytest.mark.parametrize(("text", "match"), [
    ('extends = "wang2021"\n[friction]\nball_nut_share = 1.5\n', "ball_nut_share = 1.5"),
    ('extends = "nope"\n', "extends = 'nope'"),
    ('extends = "wang2021"\n[disturbances.lead_error]\norders = [1.0]\namplitudes = [5.0]\n'
     'phases = [0.0]\n', r"lead_error\.amplitudes\[0\] = 5\.0.*1 µm = 1e-6 m"),
    ('extends = "wang2021"\n[disturbances.screw_motor_ripple]\norders = [6.0, 12.0]\n'
     'amplitudes = [0.01]\nphases = [0.0]\n', "as many entries as orders"),
    ('extends = "wang2021"\n[controller]\nmode = "off"\n', "controller.mode"),
])
def test_bad_part_values_give_one_line_errors(text: str, match: str) -> None:
    with pytest.raises(ParameterError, match=match) as err:
        loads(text)
    assert "\n" not in str(err.value)


def test_hollow_motor_may_have_its_own_loops() -> None:
    """Per-axis loops: `[hollow_controller]` gives the hollow motor its own gains; absent, it
    uses `[controller]` (the same numbers give the same run, bit for bit)."""
    w = fd.preset("wang2021")
    profile = ConstantSpeed(0.5e-3, 16e-3)
    base = fd.simulate(fd.DriveSystem(w, "ddfs", 0.4), profile, 0.5)
    same = fd.simulate(fd.DriveSystem(w.with_values(hollow_controller=w.controller), "ddfs",
                                      0.4), profile, 0.5)
    np.testing.assert_array_equal(base["nut_speed"], same["nut_speed"])
    own = w.with_values(hollow_controller=w.controller.with_values(velocity_gain=20.0))
    other = fd.simulate(fd.DriveSystem(own, "ddfs", 0.4), profile, 0.5)
    assert np.max(np.abs(other["nut_speed"] - base["nut_speed"])) > 0
    model = fd.DriveSystem(own, "ddfs", 0.4).model(profile)
    assert model.parameter("controller.nut.kvp") == 20.0
    assert model.parameter("controller.screw.kvp") == w.controller.velocity_gain
    assert loads(fd.parameters.dumps(own)) == own
