"""Reference and load inputs of the linear model, named frequency responses, the one pole rule
and honest operating points (issue 23, items 1, 3, 4)."""

from __future__ import annotations

import json
import math

import control as ct
import numpy as np
import pytest

import feeddrive as fd
from feeddrive.analysis.linear import (
    MARGINAL,
    classify_poles,
    frequency_response,
    linearize,
    loop_analysis,
)
from feeddrive.model.disturbances import TorqueRipple
from feeddrive.model.mechanisms.ball_screw_stiffness import equivalent_stiffness
from feeddrive.parameters import ParameterError

W = fd.preset("wang2021")
CDFS = fd.DriveSystem(W, "cdfs", 0.4)
V = 1.5e-3  # [m/s] operating point of the frictionless loops (as docs/linear.md)


def _cdfs_from_equations(params: fd.DriveParameters, k_eq: float, *,
                         open_position_loop: bool = False) -> ct.InputOutputSystem:
    """The wang2021 CDFS closed loop built from its physical equations with python-control,
    independent of the engine and of ``linearize``'s matrices (frictionless): screw shaft
    J θ̈ = K_t i − H F_d, table m ẍ = F_d − F_load with F_d = k_eq (Hθ − x) + c (Hθ̇ − ẋ),
    armature L i̇ = u − R i − K_e θ̇; current PI, velocity PI on table-equivalent speed
    (H·(ω_c − θ̇)), position P with speed feed-forward: ω_c = (K_pp (r − x) + v_r)/H.
    Inputs r [m], v_r [m/s], F_load [N], i_d [A] (added to the current command); outputs
    x [m], i [A].  ``open_position_loop``: the
    transfer ω_c → x instead (the position loop broken at its output)."""
    s, c = params.screw, params.controller
    H = s.transmission_ratio
    J = params.screw_motor.inertia + s.shaft_inertia
    m, cax = params.table.mass, params.stiffness.axial_damping
    kt, ke = params.screw_motor.torque_constant, params.screw_motor.back_emf_constant
    L, R = params.screw_motor.inductance, params.screw_motor.resistance
    # states θ, ω, x, v, i; inputs u, F_load; outputs i, ω, x
    A = np.array([
        [0, 1, 0, 0, 0],
        [-H * k_eq * H / J, -H * cax * H / J, H * k_eq / J, H * cax / J, kt / J],
        [0, 0, 0, 1, 0],
        [k_eq * H / m, cax * H / m, -k_eq / m, -cax / m, 0],
        [0, -ke / L, 0, 0, -R / L],
    ])
    B = np.array([[0, 0], [0, 0], [0, 0], [0, -1 / m], [1 / L, 0]])
    C = np.array([[0, 0, 0, 0, 1], [0, 1, 0, 0, 0], [0, 0, 1, 0, 0]])
    plant = ct.ss(A, B, C, np.zeros((3, 2)), inputs=["u", "F"], outputs=["i", "w", "x"])
    ci = ct.tf([c.current_gain, c.current_integral_gain], [1, 0], inputs="ei", outputs="u")
    si = ct.summing_junction(inputs=["ic", "id", "-i"], output="ei")
    cv = ct.tf([H * c.velocity_gain, H * c.velocity_integral_gain], [1, 0], inputs="ew",
               outputs="ic")
    sw = ct.summing_junction(inputs=["wc", "-w"], output="ew")
    if open_position_loop:
        return ct.interconnect([plant, ci, si, cv, sw], inputs=["wc"], outputs=["x"],
                               check_unused=False, add_unused=False)
    ep = ct.summing_junction(inputs=["r", "-x"], output="ex")
    cp = ct.ss([], [], [], [[c.position_gain / H, 1.0 / H]], inputs=["ex", "vr"],
               outputs="wc")
    return ct.interconnect([plant, ci, si, cv, sw, ep, cp], inputs=["r", "vr", "F", "id"],
                           outputs=["x", "i"])


def test_position_loop_margins_match_python_control() -> None:
    """The gain margin is read at the −180° crossing (before issue 23 it was read at −360°:
    76 dB instead of python-control's 3 dB, the 5.5-Hz velocity-loop resonance)."""
    la = loop_analysis(CDFS, V, frictionless=True)  # the default grid: margins located exactly
    lin = la.linear
    k_eq = equivalent_stiffness(W, 0.4 + lin.operating_point["table_position"])
    c, H = W.controller, W.screw.transmission_ratio
    ref = _cdfs_from_equations(W, k_eq, open_position_loop=True) * (c.position_gain / H)
    gm, pm, _, _, w_gain_crossover, _ = ct.stability_margins(ref)
    pos = {lp.name: lp for lp in la.loops}["screw position loop"]
    assert pos.gain_margin_db == pytest.approx(20 * math.log10(gm), abs=0.05)
    assert pos.phase_margin_deg == pytest.approx(pm, abs=0.1)
    assert pos.crossover_hz == pytest.approx(w_gain_crossover / (2 * math.pi), rel=1e-3)


def test_to_control_has_reference_and_load_inputs_named_as_the_simulation() -> None:
    lin = linearize(CDFS, V, frictionless=True)
    sys = lin.to_control()
    for name in ("table_position_reference", "table_speed_reference", "load_force"):
        assert name in sys.input_labels
    for name in ("table_position", "following_error", "screw_current", "screw_motor_torque"):
        assert name in sys.output_labels
    # the simulation's signals carry the same names
    result = fd.simulate(CDFS, fd.ConstantSpeed(1e-3), 0.3)
    for name in ("table_position_reference", "table_speed_reference", "following_error",
                 "screw_current"):
        assert name in result.dataset
    ddfs = linearize(fd.DriveSystem(W, "ddfs", 0.4), V, 16e-3, frictionless=True)
    assert "nut_speed_reference" in ddfs.inputs and "nut_position_reference" in ddfs.inputs
    assert "nut_speed_reference" not in lin.inputs  # the CDFS holds its nut


def test_frequency_responses_match_a_python_control_interconnection() -> None:
    """Tracking, dynamic compliance, disturbance sensitivity and the current a load needs,
    CDFS, frictionless,
    0.1–500 Hz: within 0.05 dB and 0.5° of the interconnection built from the equations."""
    lin = linearize(CDFS, V, frictionless=True)
    k_eq = equivalent_stiffness(W, 0.4 + lin.operating_point["table_position"])
    ref = _cdfs_from_equations(W, k_eq)
    f = np.logspace(-1, np.log10(500.0), 120)
    s = 2j * np.pi * f
    g = ref(s)  # (outputs, inputs, frequencies)
    cases = {
        "tracking": g[0, 0] + s * g[0, 1],  # position reference with its speed feed-forward
        "dynamic_compliance": g[0, 2],
        "disturbance_sensitivity": g[0, 3],
    }
    for name, want in cases.items():
        got = frequency_response(lin, name, frequency_hz=f).response
        assert np.max(np.abs(20 * np.log10(np.abs(got) / np.abs(want)))) < 0.05, name
        dphase = (np.degrees(np.angle(got / want)) + 180.0) % 360.0 - 180.0
        assert np.max(np.abs(dphase)) < 0.5, name
    got = frequency_response(lin, "load_force", "screw_current", f).response
    assert np.max(np.abs(20 * np.log10(np.abs(got) / np.abs(g[1, 2])))) < 0.05
    kt = W.screw_motor.torque_constant
    torque = frequency_response(lin, "load_force", "screw_motor_torque", f).response
    np.testing.assert_allclose(torque, kt * got, rtol=1e-6)
    err = frequency_response(lin, "following_error", frequency_hz=f).response
    np.testing.assert_allclose(err, 1.0 - frequency_response(lin, "tracking",
                                                             frequency_hz=f).response,
                               atol=1e-6)


def _static_compliance(p: fd.DriveParameters) -> float:
    """docs/linear.md: with the velocity-loop integral zero (and a current loop with integral
    action, K_v not placed), a load F holds the table back by C₀·F, C₀ = H / (K_t·K_vp·K_pp)
    on the table-speed basis (H² / (…) on the motor basis): the current H·F/K_t the screw must
    carry is K_vp·H·ω_c, and ω_c = K_pp·Δx / H."""
    c, H = p.controller, p.screw.transmission_ratio
    basis = 1.0 if c.velocity_gain_basis == "table" else H
    return H * basis / (p.screw_motor.torque_constant * c.velocity_gain * c.position_gain)


def test_dynamic_compliance_tends_to_the_static_compliance_without_the_integral() -> None:
    p = W.replace_path("controller.velocity_integral_gain", 0.0)
    r = frequency_response(fd.DriveSystem(p, "cdfs", 0.4), "dynamic_compliance",
                           frequency_hz=np.array([1e-3, 1e-2]), table_speed=V)
    c0 = _static_compliance(p)
    assert c0 == pytest.approx(4.019e-6, rel=1e-3)  # 4.02 µm/N, i.e. 0.249 N/µm
    assert r.magnitude[0] == pytest.approx(c0, rel=1e-4)
    # the load pushes the table back: the phase is 180°
    assert abs((r.phase_deg[0] % 360.0) - 180.0) < 0.5
    assert r.unit == "m/N"


def test_dynamic_compliance_falls_to_zero_at_dc_with_the_integral() -> None:
    """With the velocity-loop integral on, |X/F| ≈ ω·(H/(K_t·K_vi) + 1/K_eq)/K_pp at low
    frequency (docs/linear.md: the integral drives the velocity error to zero, so the motor
    speed follows ω_c = K_pp·Δx/H and the current H·F/K_t takes K_vi·H·∫ω_c; the screw's
    deflection F/K_eq enters through the motor-speed feedback): +20 dB/decade to zero."""
    p = W
    c, H = p.controller, p.screw.transmission_ratio
    lin = linearize(CDFS, V, frictionless=True)
    k_eq = equivalent_stiffness(W, 0.4 + lin.operating_point["table_position"])
    slope = (H / (p.screw_motor.torque_constant * c.velocity_integral_gain) + 1.0 / k_eq) \
        / c.position_gain
    f = np.array([1e-4, 1e-3, 1e-2])
    r = frequency_response(lin, "dynamic_compliance", frequency_hz=f)
    w = 2 * np.pi * f
    np.testing.assert_allclose(r.magnitude / w, slope, rtol=2e-3)
    # one decade up, 20 dB up
    assert np.diff(r.magnitude_db) == pytest.approx([20.0, 20.0], abs=0.01)
    assert abs(((r.phase_deg[0] + 90.0) + 180.0) % 360.0 - 180.0) < 0.5  # −jω·slope


def test_named_loop_gains_equal_loop_analysis() -> None:
    la = loop_analysis(CDFS, V, frictionless=True, f_min=1.0, f_max=100.0, points=30)
    loops = {lp.name: lp for lp in la.loops}
    for name, key in (("screw_position_loop", "screw position loop"),
                      ("screw_velocity_loop", "screw velocity loop")):
        r = frequency_response(CDFS, name, frequency_hz=loops[key].frequency_hz, table_speed=V)
        np.testing.assert_allclose(r.magnitude_db, loops[key].magnitude_db, atol=1e-9)


def test_frequency_response_refuses_unknown_names_in_one_line() -> None:
    lin = linearize(CDFS, V, frictionless=True)
    with pytest.raises(ParameterError, match="input.*expected one of.*tracking"):
        frequency_response(lin, "table_force", "table_position")
    with pytest.raises(ParameterError, match="output.*expected one of.*table_position"):
        frequency_response(lin, "load_force", "table_acceleration")
    with pytest.raises(ParameterError, match="loop gain needs the DriveSystem"):
        frequency_response(lin, "screw_velocity_loop")


# ---------------------------------------------------------------- the one pole rule


def test_rigid_body_poles_are_listed_as_such_without_a_damping_ratio() -> None:
    """Issue 23 acceptance: `loops --drive ddfs --with-friction` lists its free motion (the
    common rotation of screw and nut under a hollow motor on a speed loop) as rigid-body."""
    la = loop_analysis(fd.DriveSystem(W, "ddfs", 0.4), V, 16e-3, frictionless=False)
    poles = la.as_dict()["poles"]
    rigid = [p for p in poles if p["kind"] == "rigid-body"]
    assert len(rigid) == 1
    assert "damping_ratio" not in rigid[0] and "frequency_hz" not in rigid[0]
    assert all("damping_ratio" in p for p in poles if p["kind"] != "rigid-body")
    assert not la.dominant().rigid_body
    json.dumps(la.as_dict(), allow_nan=False)


def test_the_rule_keeps_a_genuinely_unstable_real_pole() -> None:
    fast = -1e4
    ev = np.array([3e-10, fast, -2.0 + 30j, -2.0 - 30j, 0.5])
    poles = classify_poles(ev)
    kinds = {(p.real, p.rigid_body) for p in poles}
    assert (3e-10, True) in kinds  # below MARGINAL × 1e4 = 1e-3 1/s
    assert (0.5, False) in kinds  # unstable, shown as it is
    assert 0.5 > MARGINAL * abs(fast)


# ---------------------------------------------------------------- honest operating points


def test_free_angles_stay_at_their_start_and_do_not_drift() -> None:
    """docs/linear.md: directions no equation holds stay at their start.  Before issue 23 the
    DDFS nut angle ended ≈ 10³ rad away (rounding noise walked Levenberg–Marquardt along the
    singular direction)."""
    ddfs = fd.DriveSystem(W, "ddfs", 0.4)
    vn = 16e-3
    H = W.screw.transmission_ratio
    ops = [linearize(ddfs, V, vn).operating_point for _ in range(2)]
    assert ops[0] == ops[1]
    # the start (t = 1 s): θ_n = v_n·t/H, θ_s = (v + v_n)·t/H; the screw–nut twist the
    # deflection needs splits evenly, and their common rotation — the free direction — stays
    d_nut = ops[0]["nut_angle"] - vn / H
    d_screw = ops[0]["screw_angle"] - (V + vn) / H
    assert abs(d_nut) < 1e-3  # [rad] a deflection of the screw, not a drift of 10³ rad
    assert abs(d_nut + d_screw) < 1e-9


def test_a_set_with_torque_ripple_is_linearised_on_its_averaged_model_with_a_warning() -> None:
    rippled = W.replace_path("disturbances.screw_motor_ripple", TorqueRipple(
        orders=(6.0,), amplitudes=(0.01,), phases=(0.0,)))
    lin = linearize(fd.DriveSystem(rippled, "cdfs", 0.4), V)
    plain = linearize(CDFS, V)
    assert lin.notes and "averaged model" in lin.notes[0] and "torque ripple" in lin.notes[0]
    np.testing.assert_allclose(np.sort_complex(lin.poles()), np.sort_complex(plain.poles()),
                               rtol=1e-9, atol=1e-9)
    assert not plain.notes
    la = loop_analysis(fd.DriveSystem(rippled, "cdfs", 0.4), V)
    assert la.as_dict()["notes"] == list(lin.notes)
    assert math.isfinite(la.dominant().frequency_hz)


# ---------------------------------------------------------------- the package's top level


def test_linear_analysis_is_reachable_from_the_top_level_and_dir_lists_public_names() -> None:
    from feeddrive import linear

    for name in ("linearize", "loop_analysis", "stability_band", "frequency_response"):
        assert getattr(fd, name) is getattr(linear, name)
    names = dir(fd)
    for private in ("Any", "annotations", "importlib", "sys", "types", "TYPE_CHECKING"):
        assert private not in names
    assert all(not n.startswith("_") or n == "__version__" for n in names)
    assert set(fd.__all__) <= set(names)
    assert callable(fd.simulate) and callable(fd.preset)  # existing names keep working


def test_the_compliance_numbers_in_the_docs_are_the_code_s() -> None:
    """docs/linear.md states C₀ and the low-frequency slope for wang2021."""
    import re
    from pathlib import Path

    text = (Path(__file__).parents[2] / "docs" / "linear.md").read_text(encoding="utf-8")
    c0 = float(re.search(r"C₀ = ([0-9.]+) µm/N", text).group(1))  # type: ignore[union-attr]
    assert c0 * 1e-6 == pytest.approx(_static_compliance(W.replace_path(
        "controller.velocity_integral_gain", 0.0)), rel=1e-3)
    slope = float(re.search(r"= ([0-9.]+e-8) m s/N", text).group(1))  # type: ignore[union-attr]
    lin = linearize(CDFS, V, frictionless=True)
    r = frequency_response(lin, "dynamic_compliance", frequency_hz=np.array([1e-3]))
    assert r.magnitude[0] / (2 * np.pi * 1e-3) == pytest.approx(slope, rel=2e-3)
