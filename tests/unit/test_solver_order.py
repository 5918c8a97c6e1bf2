"""Convergence order of the compiled Dormand–Prince integrator on a problem with an exact answer.

With friction off the closed loop is linear time-invariant with an affine input; its exact
response is a matrix exponential of an augmented matrix derived by hand from the equations in
``reference/linear_model.py`` (not from the engine).  The engine runs in fixed-step mode at
several steps; log(error) regressed on log(h) must have slope 5 (Dormand–Prince is order 5).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.linear_model import augmented_matrix, exact_response  # noqa: E402
from reference.scipy_model import STATE_NAMES  # noqa: E402

import feeddrive  # noqa: E402
from feeddrive.engine.simulate import DriveSystem, Simulation, SolverOptions, sampling, simulate  # noqa: E402
from feeddrive.model.mechanisms.ball_screw_stiffness import equivalent_stiffness  # noqa: E402
from feeddrive.model.reference import ConstantSpeed  # noqa: E402
from feeddrive.solvers import dopri5  # noqa: E402

X_T, V_T = STATE_NAMES.index("table_position"), STATE_NAMES.index("table_speed")

BREAK = 1e-3  # s, breakpoint (output) spacing
DURATION = 0.05  # s
# steps that divide the breakpoint spacing; |λ|h ≤ 0.3 for the fastest pole (|λ| ≈ 2.4e3 1/s),
# errors from ~1e-7 down to ~1e-11 of the signal: above round-off, in the asymptotic range
STEPS = BREAK / np.array([8, 10, 12, 16, 20, 25])


def frictionless_params(**changes: object) -> feeddrive.DriveParameters:
    """wang2021-literal with every friction site on the law "none" (no friction)."""
    p = (feeddrive.preset("wang2021-literal")
         .replace_path("stiffness.axial_damping", 2000.0)
         .replace_path("stiffness.position_dependent", False))
    for site in ("screw", "nut", "guide"):
        p = p.replace_path(f"friction.{site}.law", "none")
    for path, value in changes.items():
        p = p.replace_path(path.replace("__", "."), value)
    return p


def run_engine(params: feeddrive.DriveParameters, drive: str, profile: ConstantSpeed,
               duration: float, *, adaptive: int, step: float = 1e-6,
               options: SolverOptions | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(t, y) of the engine (states in the reference model's order); friction is off."""
    options = options or SolverOptions(output_interval=BREAK)
    if not adaptive:
        options = SolverOptions(method="dopri5-fixed", fixed_step=step,
                                output_interval=options.output_interval)
    result = simulate(DriveSystem(params, drive, 0.4), profile, duration, options=options)
    # friction off: the law "none" has no bristle states (NaN columns, not compared)
    y = np.column_stack([result[name] if name in result.dataset
                         else np.full(result.time.size, np.nan) for name in STATE_NAMES])
    return result.time, y


def exact(params: feeddrive.DriveParameters, drive: str, profile: ConstantSpeed,
          times: np.ndarray) -> np.ndarray:
    A = augmented_matrix(params, drive, profile.table_speed, profile.nut_speed,
                         equivalent_stiffness(params, 0.4))
    return exact_response(A, times)


def scaled_error(y: np.ndarray, y_exact: np.ndarray) -> float:
    """Largest error over time and states, each state scaled by its largest magnitude."""
    scale = np.max(np.abs(y_exact), axis=0)
    live = (scale > 0.0) & ~np.isnan(y).any(axis=0)
    return float(np.max(np.abs(y - y_exact)[:, live] / scale[live]))


@pytest.mark.parametrize(("drive", "nut_speed"), [("cdfs", 0.0), ("ddfs", 16e-3)])
def test_dopri5_fixed_step_converges_with_order_5(drive: str, nut_speed: float) -> None:
    params = frictionless_params()
    profile = ConstantSpeed(table_speed=1.5e-3, nut_speed=nut_speed, ramp_time=0.0)
    errors = []
    y_exact = None
    for h in STEPS:
        t, y = run_engine(params, drive, profile, DURATION, adaptive=0, step=float(h))
        if y_exact is None:
            y_exact = exact(params, drive, profile, t)
        errors.append(scaled_error(y, y_exact))
    slope = np.polyfit(np.log(STEPS), np.log(errors), 1)[0]
    assert slope == pytest.approx(dopri5.ORDER, abs=0.3), (slope, errors)


def test_exact_response_is_not_trivial() -> None:
    """Guard the order test: the table really moves and the 200-Hz mode is excited."""
    params = frictionless_params()
    profile = ConstantSpeed(table_speed=1.5e-3, ramp_time=0.0)
    times = np.linspace(0.0, DURATION, 51)
    y = exact(params, "cdfs", profile, times)
    assert y[-1, X_T] == pytest.approx(1.5e-3 * DURATION, rel=0.05)
    assert np.ptp(np.diff(y[:, V_T])) > 0.0


def test_continuous_control_reuses_the_last_stage_at_breakpoints() -> None:
    """With continuous loops the integrator skips the derivative at each breakpoint and reuses
    the step's last stage, evaluated at exactly the breakpoint.  The recorded auxiliary signals
    must then equal a fresh evaluation at the recorded (t, y), bit for bit, and a fixed-step
    run costs 6 evaluations per step plus one at t = 0."""
    from reference.cases import creeping_parameters

    params = creeping_parameters()
    profile = ConstantSpeed(table_speed=1e-3)
    options = SolverOptions()
    system = DriveSystem(params, "cdfs", 0.4)
    model = system.model(profile)
    grid = sampling(params, options.output_interval)
    sim = Simulation(system, profile, options)  # the run's resolved tolerances
    atol, rel = sim.atol, sim.rel
    t, y, aux, stats, held = dopri5.integrate(
        model, system.initial_vector(model), 0.5, grid.out_every, grid.base, grid.schedule,
        sim.tolerances.rtol, atol, rel, 1e-6, grid.base, 1, options.max_steps)
    assert int(stats[3]) == 6 * int(stats[1]) + 1
    fresh = np.empty(len(model.aux))
    dy = np.empty(len(model.states))
    for k in range(0, t.size, 7):
        model.module.rhs(t[k], y[k], held, model.P, model.T, dy, fresh)
        np.testing.assert_array_equal(aux[k], fresh)
