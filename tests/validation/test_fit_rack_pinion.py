"""A rack-and-pinion-like rig record fitted from force and speed (issue 36 item 5 and its
Acceptance): gear ratio 1 (a direct drive), one fast move 0 → 0.66 m/s → 0 in 0.54 s (half a
sine of speed), the drive force measured by a load cell and the table speed measured.

The record is made by the plain-Python reference model (reference/scipy_model.py, its rack
and pinion written from the equations of feeddrive.model.mechanisms.rack_pinion) integrated
by scipy's Radau (rtol 1e-9), not by feeddrive; it is written as a MATLAB file and read with
``--map`` roles.  The four guide-friction values are fitted from the set with F_c ×1/1.2,
σ2 ×1/0.8 and F_s ×1/1.1 off the truth.  Acceptance: F_s and v_s reported not determined (the
move crosses the Stribeck region in a few milliseconds at each end), F_c and the viscous
coefficient determined with intervals that cover the generating values.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.io import savemat

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.make_radau_reference import radau_states  # noqa: E402
from reference.scipy_model import ReferenceModel  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.analysis.fit import fit_drive  # noqa: E402
from feeddrive.analysis.rig_record import parse_map, read_rig_record  # noqa: E402
from feeddrive.engine.simulate import DriveSystem  # noqa: E402
from feeddrive.model.reference import SineSpeed  # noqa: E402

MOVE = SineSpeed(0.66, 0.0, frequency=1.0 / 1.08)  # 0 → 0.66 m/s at 0.27 s → 0 at 0.54 s
DURATION = 0.54  # [s]
FACTORS = {"coulomb_force": 1.2, "viscous_coefficient": 0.8, "static_force": 1.1,
           "stribeck_velocity": 1.0}
FORCE_NOISE = 1.0  # [N], load cell
SPEED_NOISE = 1e-4  # [m/s]


def direct_drive() -> fd.DriveParameters:
    """``rack-pinion-example`` at gear ratio 1, its velocity loop retuned as the preset tunes
    it (30 Hz on the inertia at the motor, integral corner 3 Hz) for the larger table
    inertia a direct drive reflects."""
    p = fd.preset("rack-pinion-example").replace_path("rack_pinion.gear_ratio", 1.0)
    rp = p.section("rack_pinion")
    H = rp.pinion_radius / rp.gear_ratio
    inertia = (rp.motor.inertia + rp.gearbox_inertia + rp.pinion_inertia
               + p.table.mass * H ** 2)
    kv = 2 * math.pi * 30.0 * inertia / rp.motor.torque_constant
    return (p.replace_path("controller.velocity_gain", kv)
            .replace_path("controller.velocity_integral_gain", kv * 2 * math.pi * 3.0))


def test_reference_rack_pinion_equals_the_engine_at_random_states() -> None:
    """The reference's rack and pinion against the engine's compiled right-hand side at
    gear ratios 1 and 10, random states around the move (both friction sites sliding and
    at rest); a changed mesh damping changes it (so the comparison could fail)."""
    for params in (direct_drive(), fd.preset("rack-pinion-example")):
        engine = DriveSystem(params, "rack-pinion", 0.4).model(MOVE)
        ref = ReferenceModel(params, "rack-pinion", 0.4, MOVE)
        assert ref.state_names == engine.state_names
        rng = np.random.default_rng(36)
        H = ref.H
        moved = ReferenceModel(params.replace_path("rack_pinion.mesh_damping", 2100.0),
                               "rack-pinion", 0.4, MOVE)
        changed = 0
        for _ in range(200):
            t = float(rng.uniform(0.0, DURATION))
            y = np.zeros(ref.n_state)
            x, v = rng.normal(0.0, 0.01), rng.normal(0.0, 0.3) * (rng.random() > 0.15)
            y[:4] = ((x + rng.normal(0.0, 1e-6)) / H,
                     (v + rng.normal(0.0, 1e-3)) / H * (rng.random() > 0.15), x, v)
            for j, name in enumerate(ref.state_names[4:], start=4):
                y[j] = (rng.uniform(-2e-5, 2e-5) if name.endswith("bristle") else
                        rng.normal(0.0, 1e-3) if name.endswith("velocity_integral") else
                        rng.normal(0.0, 1e-2) if name.endswith("current_integral") else
                        rng.normal(0.0, 2.0))
            dy = np.empty(ref.n_state)
            engine.module.rhs(t, y, np.zeros(engine.n_held), engine.P, engine.T, dy,
                              np.zeros(len(engine.aux)))
            expected = ref(t, y)
            np.testing.assert_allclose(dy, expected, rtol=1e-9, atol=1e-9)
            changed += not np.allclose(moved(t, y), expected, rtol=1e-6, atol=0.0)
        assert changed > 100


@pytest.fixture(scope="module")
def fitted(tmp_path_factory: pytest.TempPathFactory):
    base = direct_drive()
    truth, values = base, {}
    for name, factor in FACTORS.items():
        path = f"friction.guide.positive.{name}"
        values[path] = getattr(base.friction.guide.positive, name) * factor
        truth = truth.replace_path(path, values[path])
    t, y, _ = radau_states(truth, "rack-pinion", MOVE, DURATION, 1e-9, 1e-2)
    names = ReferenceModel(truth, "rack-pinion", 0.4, MOVE).state_names
    rp = truth.section("rack_pinion")
    force = y[names.index("motor_current")] * rp.motor.torque_constant * rp.gear_ratio \
        / rp.pinion_radius  # the drive force at the rack [N]
    rng = np.random.default_rng(5)
    path = tmp_path_factory.mktemp("rack") / "move.mat"
    savemat(path, {"t": t[:, None], "vref": (0.66 * np.sin(2 * np.pi * t / 1.08))[:, None],
                   "v": (y[names.index("table_speed")]
                         + SPEED_NOISE * rng.standard_normal(t.size))[:, None],
                   "F": (force + FORCE_NOISE * rng.standard_normal(t.size))[:, None]})
    record = read_rig_record(path, parse_map(["time=t speed_reference=vref speed=v force=F"]),
                             base, drive="rack-pinion")
    return fit_drive(base, [record.experiment], list(values), drive="rack-pinion"), values


@pytest.mark.slow
def test_rack_pinion_move_fitted_from_force_and_speed(fitted) -> None:
    result, values = fitted
    assert result.inadequate is None
    est = {e.path.rsplit(".", 1)[1]: e for e in result.estimates}
    for name in ("coulomb_force", "viscous_coefficient"):
        e = est[name]
        assert e.determined, (name, e.issue)
        assert e.low <= values[e.path] <= e.high, (name, e.low, e.high, values[e.path])
    for name in ("static_force", "stribeck_velocity"):
        e = est[name]
        assert not e.determined, name
        # the F_s–v_s valley is nonlinear: the linear interval is replaced by a profile one
        # (F_s's linear interval was "determined" and excluded the truth before the
        # linearity check), unbounded on one side, and it holds the truth (F_s's lower end
        # was 30.3 N against 24.75 N while a value the set refuses, F_s < F_c, counted as a
        # rise of the likelihood: now the last admissible value, 17.8 N ≈ F_c)
        assert e.interval == "profile"
        assert not (math.isfinite(e.low) and math.isfinite(e.high)), (name, e.low, e.high)
        assert e.low <= values[e.path] <= e.high, (name, e.low, e.high, values[e.path])


@pytest.mark.slow
def test_the_intervals_do_not_hinge_on_the_integrator(fitted) -> None:
    """At the default accuracy the signals' integration error is far below the noise
    (0.008× measured) and the estimates do not move with a ten times tighter integrator, but
    the standard errors do: F_s's and v_s's Jacobian columns are of the integration error's
    size there (their standard errors grew 72–1 274× at accuracy 0.1, measured 2026-12-05
    under RODAS4 and RODAS5P) and F_c's interval with them (a credible one at one setting and
    not at the other counts as an infinite change).  The fit tightens until the standard
    errors hold within ``STDERR_SHIFT`` (F_c's interval then [17.596, 17.852] N under both
    methods, as the fit at accuracy 0.01 gives it; that it covers the truth is the test
    above)."""
    from feeddrive.analysis import fit as fitmod

    result, values = fitted
    check = result.integration
    assert check is not None and check.met
    first, last = check.history[0], check.history[-1]
    assert first["accuracy"] == 1.0 and first["worst_ratio"] <= fitmod.ERROR_TO_NOISE
    assert first["estimate_shift_stderr"] <= fitmod.ESTIMATE_SHIFT
    # the same decisions for any limit from half to five times STDERR_SHIFT (measured: a
    # change of interval kind, inf, at accuracy 1; 1.3 % (RODAS5P) and 2.3 % (RODAS4) at 0.1)
    assert first["stderr_shift"] > 5 * fitmod.STDERR_SHIFT
    assert check.steps >= 1 and last["stderr_shift"] <= 0.5 * fitmod.STDERR_SHIFT
