"""LuGre friction (feeddrive.model.friction.stribeck): properties of the model and of the
exact bristle step.

Reference formulas are written out here, independently of the package, from Wang2021
Eq. (11): F = σ0 z + σ1 ż + σ2 v, ż = v − σ0|v| z / G(v), G(v) = F_c + (F_s − F_c)e^{−(v/v_s)²}.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from feeddrive import friction, preset
from feeddrive.parameters import LuGreParameters

PARAMS = preset("wang2021")
SITES: dict[str, LuGreParameters] = {
    "screw": PARAMS.friction.screw,
    "nut": PARAMS.friction.nut,
    "guide": PARAMS.friction.guide,
}

site_names = st.sampled_from(sorted(SITES))
magnitudes = st.floats(min_value=-6.0, max_value=-1.5).map(lambda e: 10.0**e)  # 1 µm/s … 32 mm/s
signs = st.sampled_from([1.0, -1.0])
velocities = st.tuples(magnitudes, signs).map(lambda t: t[0] * t[1])


def stribeck(v: float, site: LuGreParameters) -> float:
    """G(v) = σ0 g(v) [N], Wang2021 Eq. (11), branch chosen by the sign of v."""
    b = site.positive if v >= 0 else site.negative
    return b.coulomb_force + (b.static_force - b.coulomb_force) * math.exp(
        -((v / b.stribeck_velocity) ** 2))


def relaxation_rate(v: float, site: LuGreParameters) -> float:
    """λ = σ0|v|/G(v) [1/s]: ż = v − λz at constant v."""
    return site.bristle_stiffness * abs(v) / stribeck(v, site)


# ------------------------------------------------------------------ steady state


@settings(max_examples=150, deadline=None)
@given(site=site_names, v=velocities, z_frac=st.floats(-1.0, 1.0))
def test_steady_lugre_force_equals_stribeck_curve(site: str, v: float, z_frac: float) -> None:
    p = SITES[site]
    b = p.positive if v >= 0 else p.negative
    z0 = z_frac * friction.bristle_bound(p)
    # integrate the bristle ODE at constant v for 60 time constants: z reaches z_ss
    z = friction.bristle_step(z0, v, 60.0 / relaxation_rate(v, p), p)
    curve = math.copysign(stribeck(v, p), v) + b.viscous_coefficient * v
    assert float(friction.friction_force(v, z, p)) == pytest.approx(curve, rel=1e-9)
    assert float(friction.steady_friction(v, p)) == pytest.approx(curve, rel=1e-12)


def test_steady_friction_is_odd_only_through_the_branches() -> None:
    """Table 1 has different + and − branches: the steady curve is not an odd function."""
    p = SITES["screw"]
    v = 1e-3
    assert float(friction.steady_friction(v, p)) != pytest.approx(
        -float(friction.steady_friction(-v, p)), rel=1e-3)
    assert float(friction.steady_friction(-v, p)) == pytest.approx(
        -(stribeck(-v, p) + p.negative.viscous_coefficient * v), rel=1e-12)


# ------------------------------------------------------------------ bristle bound


@settings(max_examples=150, deadline=None)
@given(
    site=site_names,
    z_frac=st.floats(-1.0, 1.0),
    steps=st.lists(
        st.tuples(
            st.one_of(velocities, st.just(0.0)),
            st.floats(min_value=-7.0, max_value=0.0).map(lambda e: 10.0**e),
        ),
        min_size=1, max_size=40,
    ),
)
def test_bristle_state_stays_within_bound(site: str, z_frac: float,
                                          steps: list[tuple[float, float]]) -> None:
    p = SITES[site]
    bound = friction.bristle_bound(p)
    assert bound == pytest.approx(
        max(p.positive.static_force, p.negative.static_force) / p.bristle_stiffness, rel=1e-15)
    z = z_frac * bound
    for v, h in steps:
        z = friction.bristle_step(z, v, h, p)
        assert math.isfinite(z)
        assert abs(z) <= bound * (1.0 + 1e-12)


# ------------------------------------------------------------------ dissipation


def cycle_work(p: LuGreParameters, amplitude: float, omega: float, cycles: int,
               steps_per_cycle: int) -> float:
    """∫F·v dt [J] over whole periods of v(t) = A sin(ωt), starting from z = 0.

    The velocity is held at each step's midpoint value (an admissible input in its own
    right), z is advanced with the exact step, and the work of each step is integrated
    exactly: with v held, ∫z dt = (v h − Δz)/λ because ż = v − λz.
    """
    period = 2.0 * math.pi / omega
    h = period / steps_per_cycle
    n = cycles * steps_per_cycle
    v = amplitude * np.sin(omega * (np.arange(n) + 0.5) * h)
    z = np.empty(n + 1)
    z[0] = 0.0
    for k in range(n):
        z[k + 1] = friction.bristle_step(z[k], v[k], h, p)
    dz = np.diff(z)
    s2 = np.where(v >= 0, p.positive.viscous_coefficient, p.negative.viscous_coefficient)
    lam = np.array([relaxation_rate(x, p) for x in v])
    int_z = (v * h - dz) / lam
    int_force = p.bristle_stiffness * int_z + p.bristle_damping * dz + s2 * v * h
    return float(np.sum(v * int_force))


@settings(max_examples=40, deadline=None)
@given(
    site=site_names,
    amplitude=st.floats(min_value=-6.0, max_value=-2.0).map(lambda e: 10.0**e),
    omega=st.floats(min_value=0.0, max_value=3.0).map(lambda e: 10.0**e),
    cycles=st.integers(1, 3),
)
def test_friction_never_adds_energy_over_a_closed_cycle(site: str, amplitude: float,
                                                        omega: float, cycles: int) -> None:
    """Starting from z = 0 the stored bristle energy σ0z²/2 can only have grown, so a
    dissipative model must absorb work: ∮F·v dt > 0 (holds here even for the guide, whose
    passivity margin is negative: that margin is only a sufficient condition)."""
    p = SITES[site]
    work = cycle_work(p, amplitude, omega, cycles, steps_per_cycle=800)
    # lower bound: the viscous part alone, σ2 A² π/ω per cycle, minus a small tolerance
    viscous = min(p.positive.viscous_coefficient, p.negative.viscous_coefficient)
    assert work > 0.5 * viscous * amplitude**2 * math.pi / omega * cycles


def test_cycle_work_detects_an_energy_source() -> None:
    """The check above can fail: a negative viscous coefficient adds energy."""
    p = SITES["nut"]
    # bypass validation on purpose: an active "friction" with σ2 < 0
    bad_branch = object.__new__(type(p.positive))
    for name, value in vars(p.positive).items():
        object.__setattr__(bad_branch, name, value)
    object.__setattr__(bad_branch, "viscous_coefficient", -1e6)
    bad = object.__new__(type(p))
    for name, value in vars(p).items():
        object.__setattr__(bad, name, value)
    object.__setattr__(bad, "positive", bad_branch)
    object.__setattr__(bad, "negative", bad_branch)
    assert cycle_work(bad, 1e-3, 10.0, 1, 800) < 0.0


# ------------------------------------------------------------------ exact step vs ODE


@pytest.mark.parametrize("site", sorted(SITES))
@pytest.mark.parametrize("v", [2e-5, -2e-5, 1.2e-3, -1.2e-3, 2e-2, -2e-2])
@pytest.mark.parametrize("step", [1e-4, 5e-3])
@pytest.mark.parametrize("z_frac", [-1.0, 0.3])
def test_exact_bristle_step_equals_fine_integration(site: str, v: float, step: float,
                                                    z_frac: float) -> None:
    p = SITES[site]
    z0 = z_frac * friction.bristle_bound(p)

    def rhs(_t: float, z: np.ndarray) -> np.ndarray:
        return v - p.bristle_stiffness * abs(v) * z / stribeck(v, p)

    ref = solve_ivp(rhs, (0.0, step), [z0], method="Radau", rtol=1e-12,
                    atol=1e-12 * friction.bristle_bound(p))
    assert ref.success
    exact = friction.bristle_step(z0, v, step, p)
    assert exact == pytest.approx(ref.y[0, -1], abs=1e-9 * friction.bristle_bound(p))
    # the package's own rate function agrees with the reference right-hand side
    assert float(friction.bristle_rate(v, z0, p)) == pytest.approx(rhs(0.0, np.array(z0)),
                                                                   rel=1e-12)


# ------------------------------------------------------------------ v = 0


@pytest.mark.parametrize("site", sorted(SITES))
@pytest.mark.parametrize("z_frac", [-1.0, 0.0, 0.5])
@pytest.mark.parametrize("zero", [0.0, -0.0])
def test_safe_at_zero_speed(site: str, z_frac: float, zero: float) -> None:
    p = SITES[site]
    z = z_frac * friction.bristle_bound(p)
    assert float(friction.bristle_rate(zero, z, p)) == 0.0
    assert float(friction.friction_force(zero, z, p)) == pytest.approx(
        p.bristle_stiffness * z, abs=1e-12)
    assert friction.bristle_step(z, zero, 1e-3, p) == z
    assert float(friction.steady_friction(zero, p)) == 0.0
    assert float(friction.stribeck_magnitude(zero, p)) == p.positive.static_force
    v = np.array([-1e-3, zero, 1e-3])
    for out in (friction.friction_force(v, z, p), friction.bristle_rate(v, z, p),
                friction.steady_friction(v, p), friction.stribeck_magnitude(v, p)):
        assert np.all(np.isfinite(out))
