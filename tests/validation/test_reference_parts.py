"""The engine's parts against the plain-Python reference model, right-hand side by right-hand side.

For every part of the composable core (issue 8) the assembled model's compiled ``rhs`` is
evaluated at random physically sized states and compared with ``reference/scipy_model.py``
(written independently from Wang2021 Eqs. (2)–(11), the cited friction laws and the parts'
docstrings) to ~1e-9 relative, as ``test_engine_rhs_equals_reference_model_at_random_states``
does for the original drive:

* the friction laws LuGre (Canudas de Wit et al. 1995), smoothed static Stribeck
  (Armstrong-Hélouvry et al. 1994), Dahl (Dahl 1968; Olsson et al. 1998, Eq. (9)) and none,
  at every site and mixed;
* the ball–nut share f = 0.5 and 1 on the DDFS (friction at the relative screw−nut speed);
* motor torque ripple, screw lead error, the table load force (constant and a record);
* ``controller.mode = "torque_off"``;
* the linear-motor direct drive.

Each case also checks that its part really changes the right-hand side (by far more than the
tolerance), so the comparison could fail.
"""

from __future__ import annotations

import sys
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.scipy_model import ReferenceModel  # noqa: E402

import feeddrive  # noqa: E402
from feeddrive.engine.simulate import DriveSystem  # noqa: E402
from feeddrive.model.disturbances import LeadError, TorqueRipple  # noqa: E402
from feeddrive.model.mechanisms.base import start_position  # noqa: E402
from feeddrive.model.reference import ConstantSpeed, SineSpeed  # noqa: E402

TABLE_POSITION = 0.35


def _start(drive: str) -> float:
    """The start position of ``drive``'s runs: ``TABLE_POSITION`` where the model reads it (a
    ball screw's K_eq(a)), else the default, the only one such a drive takes (its model reads
    none: engine and reference are compared from the same start either way)."""
    return start_position(drive, TABLE_POSITION)
RTOL = 1e-9


def _with(params: feeddrive.DriveParameters, changes: dict[str, Any]) -> feeddrive.DriveParameters:
    for path, value in changes.items():
        params = params.replace_path(path, value)
    return params


def _all_sites(law: str) -> dict[str, Any]:
    return {f"friction.{site}.law": law for site in ("screw", "nut", "guide")}


RIPPLE = {"disturbances.screw_motor_ripple": TorqueRipple(orders=(1.0, 6.0, 12.0),
                                                          amplitudes=(0.08, 0.05, 0.02),
                                                          phases=(0.3, -1.1, 2.0)),
          "disturbances.hollow_motor_ripple": TorqueRipple(orders=(2.0, 8.0),
                                                           amplitudes=(0.06, 0.03),
                                                           phases=(0.7, 0.0))}
LEAD = {"disturbances.lead_error": LeadError(orders=(1.0, 3.0), amplitudes=(4e-6, 1.5e-6),
                                             phases=(0.2, -0.9))}


@dataclass(frozen=True)
class Case:
    changes: dict[str, Any]
    drive: str = "ddfs"
    nut_hold: str = "locked"
    preset: str = "wang2021"
    profile: Any = field(default_factory=lambda: ConstantSpeed(0.5e-3, 16e-3, ramp_time=0.3))
    load: Callable[[], Any] | None = None  # builds a LoadProfile
    # the part must change these derivatives, against the same drive with ``base`` changes
    # only (the preset's own parts, by default), at the same states
    affects: tuple[str, ...] = ()
    base: dict[str, Any] = field(default_factory=dict)


def _load_record() -> Any:
    t = np.linspace(0.0, 0.8, 17)
    return feeddrive.LoadProfile(time=t, force=120.0 * np.sin(7.0 * t) + 40.0)


DDFS_SINE = SineSpeed(1e-3, 5e-3, frequency=0.4)
LINEAR = ConstantSpeed(1e-3, ramp_time=0.3)
CDFS = ConstantSpeed(1.5e-3, ramp_time=0.3)

CASES: dict[str, Case] = {
    # friction laws, every site
    "lugre-ddfs": Case(_all_sites("lugre"), affects=("screw_speed", "nut_speed", "table_speed"),
                       base=_all_sites("none")),
    "stribeck-ddfs": Case(_all_sites("stribeck"), affects=("screw_speed", "nut_speed",
                                                           "table_speed"),
                          base=_all_sites("none")),
    "stribeck-ddfs-wide-smoothing": Case(_all_sites("stribeck") | {
        "friction.screw.smoothing_velocity": 2e-4, "friction.guide.smoothing_velocity": 5e-5,
        "friction.nut.smoothing_velocity": 1e-4}, affects=("screw_speed", "table_speed"),
        base=_all_sites("stribeck")),
    "dahl-ddfs": Case(_all_sites("dahl"), profile=DDFS_SINE,
                      affects=("screw_speed", "nut_speed", "table_speed"),
                      base=_all_sites("none")),
    "none-ddfs": Case(_all_sites("none"), affects=("screw_speed", "nut_speed", "table_speed")),
    "none-cdfs": Case(_all_sites("none"), drive="cdfs", profile=CDFS,
                      affects=("screw_speed", "table_speed")),
    "mixed-laws-cdfs-servo": Case({"friction.screw.law": "dahl", "friction.nut.law": "stribeck",
                                   "friction.guide.law": "lugre"}, drive="cdfs",
                                  nut_hold="servo", profile=SineSpeed(2e-3, 0.0, 0.7),
                                  affects=("screw_speed", "nut_speed")),
    "mixed-laws-share-ddfs": Case({"friction.screw.law": "stribeck",
                                   "friction.nut.law": "dahl", "friction.guide.law": "none",
                                   "friction.ball_nut_share": 0.3},
                                  affects=("screw_speed", "nut_speed", "table_speed")),
    # ball–nut share
    "share-0.5-ddfs": Case({"friction.ball_nut_share": 0.5}, affects=("nut_speed",)),
    "share-1-ddfs": Case({"friction.ball_nut_share": 1.0}, profile=DDFS_SINE,
                         affects=("nut_speed",)),
    "share-1-dahl-ddfs": Case({"friction.ball_nut_share": 1.0, "friction.screw.law": "dahl"},
                              affects=("nut_speed",)),
    "share-0.5-cdfs": Case({"friction.ball_nut_share": 0.5}, drive="cdfs", profile=CDFS,
                           affects=("screw_speed",)),
    # disturbances
    "ripple-ddfs": Case(RIPPLE, affects=("screw_speed", "nut_speed")),
    "ripple-cdfs-servo": Case(RIPPLE, drive="cdfs", nut_hold="servo", profile=CDFS,
                              affects=("screw_speed", "nut_speed")),
    "lead-error-ddfs": Case(LEAD, affects=("screw_speed", "nut_speed", "table_speed")),
    "lead-error-cdfs": Case(LEAD, drive="cdfs", profile=CDFS,
                            affects=("screw_speed", "table_speed")),
    "load-constant-ddfs": Case({"disturbances.load_force": 150.0, "disturbances.load_start": 0.5},
                               affects=("table_speed",)),
    "load-record-cdfs": Case({"disturbances.load_force": -60.0}, drive="cdfs", profile=CDFS,
                             load=_load_record, affects=("table_speed",)),
    "all-disturbances-share-ddfs": Case(RIPPLE | LEAD | {"disturbances.load_force": 80.0,
                                                         "friction.ball_nut_share": 0.5},
                                        profile=DDFS_SINE,
                                        affects=("screw_speed", "nut_speed", "table_speed")),
    # motors off
    "torque-off-ddfs": Case({"controller.mode": "torque_off"},
                            affects=("screw_speed", "nut_speed", "screw_current",
                                     "nut_current")),
    "torque-off-cdfs-ripple": Case({"controller.mode": "torque_off"} | RIPPLE, drive="cdfs",
                                   profile=CDFS, affects=("screw_speed", "screw_current")),
    # linear-motor direct drive
    "linear-motor": Case({}, drive="linear-motor", preset="linear-motor-example",
                         profile=LINEAR),
    "linear-motor-sine-saturating": Case({"controller.current_limit": 2.0,
                                          "controller.voltage_limit": 40.0},
                                         drive="linear-motor", preset="linear-motor-example",
                                         profile=SineSpeed(5e-3, frequency=1.3),
                                         affects=("motor_current",)),
    "linear-motor-kv-position-output": Case({"controller.kv_placement": "position_output",
                                             "controller.velocity_command_gain": 1.5},
                                            drive="linear-motor", preset="linear-motor-example",
                                            profile=LINEAR, affects=("motor_current",)),
    "linear-motor-stribeck-load": Case({"friction.guide.law": "stribeck",
                                        "disturbances.load_force": 30.0,
                                        "disturbances.load_start": 0.2},
                                       drive="linear-motor", preset="linear-motor-example",
                                       profile=LINEAR, load=_load_record,
                                       affects=("table_speed",)),
    "linear-motor-dahl-torque-off": Case({"friction.guide.law": "dahl",
                                          "controller.mode": "torque_off"},
                                         drive="linear-motor", preset="linear-motor-example",
                                         profile=LINEAR, affects=("table_speed", "motor_current")),
}


def _random_states(rng: np.random.Generator, times: np.ndarray, model: ReferenceModel,
                   nut: bool) -> np.ndarray:
    """Physically sized random states at ``times``, built by state name.  Half near the
    reference (loops in their linear range), half anywhere within ±50 mm and ±mm/s; some
    speeds exactly 0 and some screw and nut speeds exactly equal (the friction branch points,
    also of the ball–nut contact)."""
    n = times.size
    H = model.H
    refs = np.array([model.reference(float(t)) for t in times])
    near = rng.random(n) < 0.5
    x_t = np.where(near, refs[:, 0] + rng.normal(0.0, 2e-6, n), rng.uniform(-0.05, 0.05, n))
    x_n = np.where(near, refs[:, 2] + rng.normal(0.0, 2e-6, n), rng.uniform(-0.05, 0.05, n))
    spread = np.where(near, 5e-5, 2e-3)
    v_t = refs[:, 1] + spread * rng.normal(0.0, 1.0, n)
    v_n = refs[:, 3] + spread * rng.normal(0.0, 1.0, n) if nut else np.zeros(n)
    v_s = refs[:, 1] + refs[:, 3] + spread * rng.normal(0.0, 1.0, n)
    for v in (v_t, v_n, v_s):
        v[rng.random(n) < 0.15] = 0.0
    if nut:
        same = rng.random(n) < 0.1
        v_s[same] = v_n[same]
    values = {
        "table_position": x_t, "table_speed": v_t,
        "nut_angle": x_n / H if nut else np.zeros(n),
        "nut_speed": v_n / H,
        "screw_speed": v_s / H,
    }
    values["screw_angle"] = (x_t + rng.normal(0.0, 5e-6, n)) / H + values["nut_angle"]
    y = np.zeros((n, len(model.state_names)))
    for j, name in enumerate(model.state_names):
        nut_state = name.startswith("nut_")
        if nut_state and not nut:
            continue  # the held nut: frozen at rest
        if name in values:
            y[:, j] = values[name]
        elif name.endswith("_bristle"):
            y[:, j] = rng.uniform(-1.0, 1.0, n) * (3e-4 if nut_state else 5e-5)
        elif name.endswith("_velocity_integral"):
            y[:, j] = rng.normal(0.0, 1e-3, n)
        elif name.endswith("_current_integral"):
            y[:, j] = rng.normal(0.0, 1e-2, n)
        elif name.endswith("_current"):
            y[:, j] = rng.normal(0.0, 2.0, n)
        else:
            raise AssertionError(f"no random value for state {name}")
    return y


def _models(case: Case, changes: dict[str, Any]) -> tuple[Any, ReferenceModel]:
    params = _with(feeddrive.preset(case.preset), changes)
    load = case.load() if case.load is not None else None
    system = DriveSystem(params, case.drive, _start(case.drive), nut_hold=case.nut_hold,
                         load=load)
    return system.model(case.profile), ReferenceModel(params, case.drive, _start(case.drive),
                                                      case.profile, nut_hold=case.nut_hold,
                                                      load=load)


def _evaluate(case: Case, seed: str
              ) -> tuple[ReferenceModel, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(reference model, times, states, engine dy, reference dy) at 200 random states."""
    engine_model, model = _models(case, case.changes)
    # the reference builds its state list from the parts as the engine does
    assert model.state_names == engine_model.state_names
    nut = case.drive == "ddfs" or (case.drive == "cdfs" and case.nut_hold == "servo")
    rng = np.random.default_rng(zlib.crc32(seed.encode()))
    times = rng.uniform(0.0, 1.0, 200)
    states = _random_states(rng, times, model, nut)
    held = np.zeros(engine_model.n_held)
    aux = np.zeros(len(engine_model.aux))
    engine = np.empty_like(states)
    reference = np.empty_like(states)
    for k, (t, y) in enumerate(zip(times, states, strict=True)):
        dy = np.empty(states.shape[1])
        engine_model.module.rhs(float(t), y, held, engine_model.P, engine_model.T, dy,
                                aux)
        engine[k] = dy
        reference[k] = model(float(t), y)
    return model, times, states, engine, reference


def _assert_close(names: tuple[str, ...], engine: np.ndarray, reference: np.ndarray) -> None:
    """Agreement to RTOL relative to each component's size, or to 1e-3 of its largest value
    over the sample where terms cancel."""
    scale = np.max(np.abs(reference), axis=0)
    for j, name in enumerate(names):
        if scale[j] == 0.0:
            assert np.all(engine[:, j] == 0.0), name
            continue
        diff = np.abs(engine[:, j] - reference[:, j])
        bound = RTOL * np.maximum(np.abs(reference[:, j]), 1e-3 * scale[j])
        worst = int(np.argmax(diff / bound))
        assert diff[worst] <= bound[worst], (name, worst, engine[worst, j], reference[worst, j])


@pytest.mark.parametrize("name", sorted(CASES))
def test_engine_part_rhs_equals_reference_at_random_states(name: str) -> None:
    case = CASES[name]
    model, times, states, engine, reference = _evaluate(case, name)
    names = model.state_names
    _assert_close(names, engine, reference)
    # the sample crosses the friction branch points
    speeds = states[:, names.index("table_speed")]
    assert np.any(speeds < 0) and np.any(speeds > 0) and np.any(speeds == 0.0)
    # and the part matters: without it the derivatives at the same states (matched by name;
    # states the other layout lacks at 0) differ by far more than the tolerance
    if case.affects:
        _, base = _models(case, case.base)
        base_states = np.array([[y[names.index(n)] if n in names else 0.0
                                 for n in base.state_names] for y in states])
        base_dy = np.array([base(float(t), y) for t, y in zip(times, base_states, strict=True)])
        for state in case.affects:
            j, jb = names.index(state), base.state_names.index(state)
            change = np.max(np.abs(reference[:, j] - base_dy[:, jb]))
            assert change > 1e3 * RTOL * np.max(np.abs(reference[:, j])), (state, change)


def test_reference_tracks_engine_state_layout_for_every_law_and_share() -> None:
    """Stateless laws add no state, the screw site goes at f = 1, the ball–nut site comes at
    f > 0; the reference lists its states exactly as the assembled model does."""
    profile = ConstantSpeed(1e-3, 16e-3)
    for law in ("lugre", "stribeck", "dahl", "none"):
        for share in (0.0, 0.4, 1.0):
            params = _with(feeddrive.preset("wang2021"),
                           {"friction.screw.law": law, "friction.nut.law": "dahl",
                            "friction.guide.law": "stribeck",
                            "friction.ball_nut_share": share})
            engine = DriveSystem(params, "ddfs", TABLE_POSITION).model(profile)
            reference = ReferenceModel(params, "ddfs", TABLE_POSITION, profile)
            assert reference.state_names == engine.state_names, (law, share)
            stateful = law in ("lugre", "dahl")
            assert ("screw_bristle" in engine.state_names) == (stateful and share < 1.0)
            assert ("ball_nut_bristle" in engine.state_names) == (stateful and share > 0.0)
    lm = feeddrive.preset("linear-motor-example")
    start = _start("linear-motor")
    engine = DriveSystem(lm, "linear-motor", start).model(ConstantSpeed(1e-3))
    assert ReferenceModel(lm, "linear-motor", start).state_names == engine.state_names


def test_share_one_matches_share_zero_on_the_locked_cdfs_from_equal_bristles() -> None:
    """With the nut held the ball–nut contact slides at the screw speed: moving the whole
    screw friction there changes nothing when both sites start from the same bristle state
    (the FrictionSites docstring: 'with the nut held (CDFS) f has no effect')."""
    rng = np.random.default_rng(8)
    p0 = feeddrive.preset("wang2021")
    p1 = p0.replace_path("friction.ball_nut_share", 1.0)
    m0 = ReferenceModel(p0, "cdfs", TABLE_POSITION, CDFS)
    m1 = ReferenceModel(p1, "cdfs", TABLE_POSITION, CDFS)
    e1 = DriveSystem(p1, "cdfs", TABLE_POSITION).model(CDFS)
    for _ in range(20):
        y0 = np.zeros(len(m0.state_names))
        for k, name in enumerate(m0.state_names):
            if not name.startswith("nut_"):
                y0[k] = rng.normal(0.0, 1e-4)
        y1 = np.array([y0[m0.state_names.index(n.replace("ball_nut_", "screw_"))]
                       for n in m1.state_names])
        t = float(rng.uniform(0.0, 1.0))
        d0, d1 = m0(t, y0), m1(t, y1)
        de = np.empty_like(d1)
        e1.module.rhs(t, y1, np.zeros(e1.n_held), e1.P, e1.T, de,
                      np.zeros(len(e1.aux)))
        for j, name in enumerate(m1.state_names):
            j0 = m0.state_names.index(name.replace("ball_nut_", "screw_"))
            assert d1[j] == pytest.approx(d0[j0], rel=1e-12, abs=1e-12 * max(1.0, abs(d0[j0])))
            assert de[j] == pytest.approx(d1[j], rel=1e-9, abs=1e-9 * max(1.0, abs(d1[j])))


def test_locked_nut_freezes_every_nut_state_including_its_current_integral() -> None:
    """ball_screw.py: 'the nut's states are frozen (nut_hold = "locked")'.  A nonzero start
    state of the held nut (``initial_state``) must stay put.  Guards the bug found by this
    test: the continuous current loop of the held hollow motor kept integrating."""
    params = feeddrive.preset("wang2021")
    engine = DriveSystem(params, "cdfs", TABLE_POSITION).model(CDFS)
    y = np.zeros(len(engine.state_names))
    y[engine.index("nut_current")] = 1.0
    dy = np.empty_like(y)
    engine.module.rhs(0.2, y, np.zeros(engine.n_held), engine.P, engine.T, dy,
                      np.zeros(len(engine.aux)))
    reference = ReferenceModel(params, "cdfs", TABLE_POSITION, CDFS)(0.2, y)
    assert reference[engine.index("nut_current_integral")] == 0.0
    assert dy[engine.index("nut_current_integral")] == 0.0
