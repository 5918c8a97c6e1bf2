"""Generalized Maxwell-slip friction (Al-Bender, Lampaert & Swevers, IEEE TAC 50 (2005)
1883–1887): pre-sliding hysteresis against the paper's closed form, steady curve, analytic
linearisation, parameter files, and a drive simulated with it (issue 19, GMS acceptance)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import feeddrive as fd
from feeddrive.model.friction import friction_law
from feeddrive.model.friction.gms import GMSParameters
from feeddrive.model.friction.lugre_parameters import FrictionBranch, LuGreParameters
from feeddrive.parameters import ParameterError

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "gms_guide.toml"
BRANCH = FrictionBranch(coulomb_force=10.0, static_force=20.0, stribeck_velocity=1e-3,
                        viscous_coefficient=50.0)
K = (1.0e6, 2.0e5, 5.0e4)  # N/m
ALPHA = (0.2, 0.3, 0.5)


def site(margin: float = 0.0, attraction: float = 1e5) -> GMSParameters:
    return GMSParameters(positive=BRANCH, negative=BRANCH, attraction=attraction,
                         element_stiffness=K, element_weight=ALPHA, slip_margin=margin)


def presliding(params: GMSParameters, speed: float, amplitude: float, method: str = "RK45"
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Force along a slow triangle x: 0 → +amplitude → −amplitude (speed [m/s]), integrated
    by scipy's ``method`` at the same tolerances and step limit whatever the method."""
    law = friction_law("gms")
    P = law.pack(params)
    t_turn = amplitude / speed

    def v_of(t: float) -> float:
        return speed if t < t_turn else -speed

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        return law.evaluate(v_of(t), y, params, P)[1]

    t = np.concatenate([np.linspace(0, t_turn, 201), np.linspace(t_turn, 3 * t_turn, 401)[1:]])
    y = np.zeros((t.size, len(K)))
    for j, (a, b) in enumerate(((0.0, t_turn), (t_turn, 3 * t_turn))):
        seg = (t >= a) & (t <= b)
        y0 = np.zeros(len(K)) if j == 0 else y[np.searchsorted(t, t_turn)]
        sol = solve_ivp(rhs, (a, b), y0, t_eval=t[seg], method=method, rtol=1e-10,
                        atol=1e-16, max_step=(b - a) / 2000)
        y[seg] = sol.y.T
    x = np.where(t <= t_turn, speed * t, amplitude - speed * (t - t_turn))
    force = np.array([law.evaluate(v_of(ti), yi, params, P)[0] - 50.0 * v_of(ti)
                      for ti, yi in zip(t, y, strict=True)])
    return x, force, t <= t_turn


def closed_form(x: np.ndarray, loading: np.ndarray, amplitude: float, slip_force: float
                ) -> np.ndarray:
    """Al-Bender et al. 2005 Sect. II: elastoplastic elements in parallel — the virgin curve
    Σ min(k_i x, α_i F_s) and, after the reversal at x_r, Masing's rule
    F_r − Σ min(k_i (x_r − x), 2 α_i F_s)."""
    k, w = np.asarray(K), np.asarray(ALPHA) * slip_force
    virgin = np.minimum(np.outer(x, k), w).sum(axis=1)
    f_r = np.minimum(k * amplitude, w).sum()
    reverse = f_r - np.minimum(np.outer(amplitude - x, k), 2 * w).sum(axis=1)
    return np.where(loading, virgin, reverse)


def test_presliding_hysteresis_follows_the_closed_form():
    """Slow triangle of ±100 µm at 1 µm/s: two elements saturate, one does not; the force
    equals the elastoplastic closed form (s(v) = F_s to 5e-7 at this speed)."""
    amplitude = 1e-4
    x, force, loading = presliding(site(margin=0.0), 1e-6, amplitude)
    expected = closed_form(x, loading, amplitude, 20.0)
    assert np.max(np.abs(force - expected)) < 1e-4 * 20.0
    # the curve is really hysteretic: at x = 0 on the way back the force is negative
    back = ~loading
    assert np.interp(0.0, x[back][::-1], force[back][::-1]) < -1.0


def test_the_slip_margin_bounds_the_deviation_from_the_closed_form():
    """A slip margin makes the elements' ODE stiff: explicit RK45 needed ~30 s of steps for
    it; LSODA (stiff-aware, same rtol/atol/max_step) gives the same forces to 2e-9 N
    (measured against RK45 once, 2026-12-02), far below the 2e-2 N bound checked here."""
    amplitude = 1e-4
    x, force, loading = presliding(site(margin=1e-3), 1e-6, amplitude, method="LSODA")
    expected = closed_form(x, loading, amplitude, 20.0)
    assert np.max(np.abs(force - expected)) <= 1e-3 * 20.0


def test_steady_force_is_the_stribeck_curve():
    gms = friction_law("gms")
    lugre_site = LuGreParameters(positive=BRANCH, negative=BRANCH, bristle_stiffness=1e6,
                                 bristle_damping=0.0)
    v = np.array([-5e-3, -1e-3, -1e-5, 1e-5, 3e-4, 1e-3, 5e-3])
    assert np.allclose(gms.steady_force(v, site(margin=1e-3)),
                       friction_law("lugre").steady_force(v, lugre_site), rtol=1e-12)


@pytest.mark.parametrize("v", [-2e-3, 5e-4, 3e-3])
def test_linearisation_matches_the_slip_branch(v):
    """The analytic linearisation against central differences of the kernel taken inside
    the slip region (the steady state lies there with the default margin)."""
    p = site(margin=1e-3)
    gms = friction_law("gms")
    lin = gms.linearise(v, p)
    x0 = gms.steady_state(v, p)
    P = gms.pack(p)
    n = x0.size
    A = np.empty((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = 1e-7 * abs(x0[j])
        A[:, j] = (gms.evaluate(v, x0 + e, p, P)[1] - gms.evaluate(v, x0 - e, p, P)[1]) / (
            2 * e[j])
    dv = 1e-7 * abs(v)
    B = (gms.evaluate(v + dv, x0, p, P)[1] - gms.evaluate(v - dv, x0, p, P)[1]) / (2 * dv)
    D = (gms.evaluate(v + dv, x0, p, P)[0] - gms.evaluate(v - dv, x0, p, P)[0]) / (2 * dv)
    assert np.allclose(lin.A, A, rtol=1e-5)
    assert np.allclose(lin.B, B, rtol=1e-5)
    assert np.allclose(lin.C, np.asarray(K))
    assert lin.D == pytest.approx(D, rel=1e-5)


def test_a_drive_with_a_gms_guide_simulates():
    """``[friction.guide] law = "gms"`` in a file that extends wang2021: the CDFS follows
    2 mm/s, and the model names the element parameters."""
    params = fd.load(EXAMPLE)
    assert isinstance(params.friction.guide, GMSParameters)
    assert params.friction.screw == fd.preset("wang2021").friction.screw
    system = fd.DriveSystem(params, "cdfs", 0.4)
    result = fd.simulate(system, fd.ConstantSpeed(2e-3), 3.0)
    m = result.creep_metrics()
    assert m.mean_speed == pytest.approx(2e-3, rel=0.01)
    assert [n for n in result.dataset.data_vars if n.startswith("guide_element")] == [
        f"guide_element{i}" for i in range(4)]
    model = system.model(fd.ConstantSpeed(2e-3))
    assert model.parameter("friction.guide.element_stiffness[1]") == 1.2e5
    assert model.parameter("friction.guide.attraction") == params.friction.guide.attraction


def test_switching_law_class_in_an_extends_file_replaces_the_parent_table(tmp_path):
    """A law with parameters of its own replaces the parent's site table; a law sharing
    LuGre's parameters (dahl) still changes only what the file gives."""
    dahl = tmp_path / "dahl.toml"
    dahl.write_text('extends = "wang2021"\n[friction.guide]\nlaw = "dahl"\n')
    loaded = fd.load(dahl).friction.guide
    assert loaded.law == "dahl"
    assert loaded.positive == fd.preset("wang2021").friction.guide.positive
    child = tmp_path / "child.toml"
    child.write_text(f'extends = "{EXAMPLE}"\nname = "again"\n')
    assert isinstance(fd.load(child).friction.guide, GMSParameters)


@pytest.mark.parametrize("change, field", [
    ("element_weight = [0.5, 0.2, 0.2, 0.2]", "friction.guide.element_weight"),
    ("element_weight = [0.5, 0.5]", "friction.guide.element_weight"),
    ("bristle_stiffness = 1e6", "friction.guide.bristle_stiffness"),
])
def test_bad_gms_sites_are_refused_with_the_field(tmp_path, change, field):
    text = EXAMPLE.read_text().replace("element_weight = [0.1, 0.2, 0.3, 0.4]", change) \
        if "weight" in change else EXAMPLE.read_text().replace(
            'law = "gms"', f'law = "gms"\n{change}')
    path = tmp_path / "bad.toml"
    path.write_text(text.replace('extends = "wang2021"', 'extends = "wang2021"'))
    with pytest.raises(ParameterError) as err:
        fd.load(path)
    assert err.value.field == field


def test_lugre_only_analyses_refuse_a_gms_site():
    params = fd.load(EXAMPLE).replace_path("controller.compensation.mode", "feedforward")
    with pytest.raises(ParameterError, match="friction compensation works with "
                                             "LuGreParameters sites"):
        fd.DriveSystem(params, "cdfs", 0.4).model(fd.ConstantSpeed(1e-3))
