"""The zero crossings of a friction site's sliding speed are located and made step ends of
the dense-output driver (issue 35 item 2: the DDFS's table reverses eight times in its start
transient, and a step across the guide friction's kink at v = 0 kept the error from falling
with the tolerance; feeddrive.solvers.events)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.engine.simulate import Simulation, switching_rows
from feeddrive.solvers.events import THETA_MIN, first_crossing

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data"


def test_the_rows_are_the_sliding_speeds_of_the_acting_sites() -> None:
    H = fd.preset("wang2021").screw.lead / (2 * np.pi)
    ddfs = Simulation(fd.DriveSystem(fd.preset("wang2021"), "ddfs", 0.4),
                      fd.ConstantSpeed(0.5e-3, 16e-3))
    names = ddfs.model.state_names
    W = switching_rows(ddfs.model, ddfs.P)
    expected = np.zeros((3, len(names)))
    expected[0, names.index("screw_speed")] = H  # screw site: H·ω_s
    expected[1, names.index("nut_speed")] = H  # nut site: H·ω_n
    expected[2, names.index("table_speed")] = 1.0  # guide: v_t
    np.testing.assert_allclose(W, expected, rtol=1e-12, atol=0)
    # the CDFS's held nut does not act: no row for it
    cdfs = Simulation(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4),
                      fd.ConstantSpeed(1e-3))
    assert switching_rows(cdfs.model, cdfs.P).shape == (2, len(names))


@pytest.mark.parametrize("lead", [5e-3, 10e-3])
def test_the_rows_kept_for_a_structure_follow_its_numbers_not_its_profile(lead: float) -> None:
    """2026-12-06: the rows of a model are kept between runs that differ by their profile
    only (a search's trials: 15 of the 17 evaluations saved per run), and checked by the two
    that are made every time.  Each run's rows are still the closed-form sliding speeds (H =
    lead/2π): after another profile's run, for every kind of profile, and with another lead,
    which must not take the rows kept for the first."""
    from feeddrive.engine import simulate as sim_module

    params = fd.preset("wang2021").replace_path("screw.lead", lead)
    system = fd.DriveSystem(params, "ddfs", 0.4)
    H = lead / (2 * np.pi)
    profiles = [fd.ConstantSpeed(0.5e-3, 16e-3), fd.ConstantSpeed(2e-3, 8e-3, ramp_time=0.5),
                fd.SineSpeed(1e-3, 16e-3, frequency=0.5),
                fd.SampledSpeed(np.linspace(0.0, 1.0, 11), np.full(11, 1e-3),
                                np.full(11, 16e-3))]
    for profile in profiles:
        sim = Simulation(system, profile)
        names = sim.model.state_names
        expected = np.zeros((3, len(names)))
        expected[0, names.index("screw_speed")] = H
        expected[1, names.index("nut_speed")] = H
        expected[2, names.index("table_speed")] = 1.0
        np.testing.assert_allclose(sim.switch_rows, expected, rtol=1e-12, atol=0)
        np.testing.assert_allclose(switching_rows(sim.model, sim.P), expected, rtol=1e-12,
                                   atol=0)
    assert len(sim_module._SWITCH_ROWS) >= 1


def test_a_law_without_a_kink_gives_no_row() -> None:
    p = fd.preset("wang2021")
    for site in ("screw", "nut", "guide"):
        p = p.replace_path(f"friction.{site}.law", "stribeck")  # tanh-smoothed: no kink
    sim = Simulation(fd.DriveSystem(p, "ddfs", 0.4), fd.ConstantSpeed(0.5e-3, 16e-3))
    assert switching_rows(sim.model, sim.P).shape[0] == 0


def test_first_crossing_finds_the_root_on_the_continuous_extension() -> None:
    # DOPRI5's extension with q2 = q3 = e = 0 is y + θ·q1: g = 1 − 4θ crosses at θ = 0.25
    y, y_new = np.array([1.0, 5.0]), np.array([-3.0, 5.0])
    q1, zero = y_new - y, np.zeros(2)
    W = np.array([[1.0, 0.0]])
    th = first_crossing(W, y, y_new, q1, zero, zero, zero, False)[0]
    assert th == pytest.approx(0.25, abs=1e-12)
    # a quadratic extension: y(θ) = y + θ(q1 + (1 − θ) q2) with g = 1 − 3θ + (1 − θ)θ·q2
    q2 = np.array([2.0, 0.0])
    y_new = np.array([-2.0, 5.0])
    th = first_crossing(W, y, y_new, y_new - y, q2, zero, zero, False)[0]
    # root of 1 − 3θ + 2θ(1 − θ) = 1 − θ − 2θ²: θ = 0.5
    assert th == pytest.approx(0.5, abs=1e-12)
    # no sign change, or one within THETA_MIN of an end: none
    assert first_crossing(W, y, np.array([0.5, 5.0]), np.array([-0.5, 0.0]), zero, zero,
                          zero, False)[0] == -1.0
    y_end = np.array([-THETA_MIN / 10, 0.0])
    assert first_crossing(W, np.array([1.0, 0.0]), y_end, y_end - np.array([1.0, 0.0]),
                          zero, zero, zero, False)[0] == -1.0


def test_the_ddfs_start_lands_on_every_reversal_of_the_reference() -> None:
    """The engine lands on every reversal of the table speed of the Radau reference
    (reference/make_accuracy_reference.py): eight, after a start from zero speed (a start,
    not a crossing); the screw and nut never reverse.  A crossing located from a large step
    may take a second landing close to it (counted when another step came between), at most
    one per reversal.  Measured 2026-12-05: ``modal`` 12 (10 before its switch back to DOPRI5
    weighed the methods' costs), ``auto`` 12, ``rodas4`` 11, ``dopri5-dense`` 11."""
    with np.load(DATA / "accuracy_ddfs_0p5_vn16.npz") as f:
        t, v = f["time"], f["table_speed"]
    k = np.flatnonzero(v[1:-1] * v[2:] < 0.0) + 1  # sign changes after the start
    reversals = t[k] - v[k] / (v[k + 1] - v[k]) * (t[k + 1] - t[k])
    assert reversals.size == 8
    r = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "ddfs", 0.4),
                    fd.ConstantSpeed(0.5e-3, 16e-3), float(t[-1]))
    assert reversals.size <= r.solver_stats["switch_crossings"] <= 2 * reversals.size


def test_a_speed_dithering_about_zero_does_not_stall_the_run() -> None:
    """The bug this guards: the torque-ripple DDFS at 0.05 mm/s (hollow motor 30 mm/s; a
    trial of reproduce's forced study) sticks, its table speed dithering about zero, and a
    crossing located closer to t than t's resolution was landed on without advancing t —
    the driver looped for good.  Measured with the guard: 51 190 steps, 741 crossings (48 039
    steps without crossing location)."""
    system = fd.DriveSystem(fd.preset("wang2021-ripple"), "ddfs", 0.4)
    r = fd.simulate(system, fd.ConstantSpeed(0.05e-3, 30e-3), 12.0,
                    options=fd.SolverOptions(max_steps=200_000))
    assert r.time[-1] == pytest.approx(12.0)
    assert r.solver_stats["switch_crossings"] > 100
    assert r.solver_stats["steps"] < 70_000


def test_a_gms_site_declares_its_reversals() -> None:
    """GMS switches every slipping element to sticking at v = 0 (its rate jumps to 0) and
    changes its direction branch there: it declares ``kink_at_zero_speed``, its guide gives
    the table speed as a row, and the GMS-guide DDFS at 0.5 mm/s (hollow motor 16 mm/s),
    whose table reverses in its start transient, lands on every reversal (measured: 12 on the
    1-ms output grid, 12 crossings).  The bug this guards: the law did not declare it and its
    first state has no fixed name (``element0`` … per site), so the guide had no row and
    every step crossed the reversals."""
    from feeddrive.model.friction import friction_law

    assert friction_law("gms").kink_at_zero_speed
    assert friction_law("gms").first_state == "element0"
    system = fd.DriveSystem(fd.load(ROOT / "examples" / "gms_guide.toml"), "ddfs", 0.4)
    profile = fd.ConstantSpeed(0.5e-3, 16e-3)
    sim = Simulation(system, profile)
    names = sim.model.state_names
    W = switching_rows(sim.model, sim.P)
    assert W.shape == (3, len(names))
    guide = np.zeros(len(names))
    guide[names.index("table_speed")] = 1.0
    np.testing.assert_allclose(W[2], guide, rtol=1e-12, atol=0)
    r = fd.simulate(system, profile, 1.0)
    v = np.asarray(r["table_speed"])
    reversals = int(np.sum(v[1:-1] * v[2:] < 0.0))  # after the start from rest
    assert reversals >= 8
    assert reversals <= r.solver_stats["switch_crossings"] <= reversals + 2


def test_dopri5_locates_the_ddfs_reversals_on_its_steps_extension() -> None:
    """The bug this guards: ``dopri5`` (every output instant a step end) stepped across the
    guide friction's kink at the DDFS table's eight reversals, its table position error
    against the Radau reference (reference/make_accuracy_reference.py) then 2.6e-8 of the
    stroke at accuracy 1 and 5.5e-10 at 0.001.  Located on each step's continuous extension
    (as the dense driver does) it is 9.7e-11 at accuracy 1 (measured); with
    ``locate_reversals=False`` the v1 steps come back."""
    with np.load(DATA / "accuracy_ddfs_0p5_vn16.npz") as f:
        t, x = f["time"], f["table_position"]
    system = fd.DriveSystem(fd.preset("wang2021"), "ddfs", 0.4)
    errors = {}
    for locate in (True, False):
        r = fd.simulate(system, fd.ConstantSpeed(0.5e-3, 16e-3), float(t[-1]),
                        options=fd.SolverOptions(method="dopri5", locate_reversals=locate))
        errors[locate] = float(np.max(np.abs(r["table_position"] - x))) / float(np.ptp(x))
    assert errors[True] <= 2e-10, errors
    assert errors[False] >= 100 * errors[True], errors


def test_the_dopri5_step_cap_follows_the_accuracy() -> None:
    """1 ms × accuracy^(1/5): where the cap binds DOPRI5's global error goes as h⁵, so it
    falls ten times per decade of accuracy as where the tolerances bind (with the fixed 1-ms
    cap the CDFS's table speed error fell 4.2× in the second decade); 1 ms exactly at
    accuracy 1 (the v1 engine); an explicit max_step as given; dense methods uncapped."""
    assert fd.SolverOptions(method="dopri5").largest_step == 1e-3
    for accuracy in (0.1, 0.001, 10.0):
        cap = fd.SolverOptions(method="dopri5", accuracy=accuracy).largest_step
        assert cap == pytest.approx(1e-3 * accuracy ** 0.2, rel=1e-12)
    assert fd.SolverOptions(method="dopri5", accuracy=0.1, max_step=2e-3).largest_step == 2e-3
    assert fd.SolverOptions(method="dopri5-dense", accuracy=0.1).largest_step == np.inf
    assert fd.SolverOptions(method="dopri5-fixed", accuracy=0.1).largest_step == 1e-3
    sim = Simulation(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4),
                     fd.ConstantSpeed(2e-3),
                     fd.SolverOptions(method="dopri5", accuracy=0.01))
    from feeddrive.engine.simulate import _Chunks

    assert _Chunks(sim, want_aux=False).h_max == pytest.approx(1e-3 * 0.01 ** 0.2, rel=1e-12)


@pytest.mark.parametrize("value", ["yes", 1, None])
def test_locate_reversals_must_be_true_or_false(value: object) -> None:
    with pytest.raises(fd.ParameterError, match=r"options\.locate_reversals.*True or False"):
        fd.SolverOptions(locate_reversals=value)  # type: ignore[arg-type]


def test_the_kept_rows_key_a_record_by_its_digest_not_its_samples(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A record's samples live in ``T`` (an 8-kHz, 100-s record: 26 MB), and the kept rows
    (64 of them) were keyed by ``T``'s bytes: a fit of such a record held a copy per
    parameter point.  The key is now a digest, of fixed size, and still tells apart another
    parameter value and another structure; another record (the profile's table, as its
    numbers in ``P``) shares the key since 2026-12-08 — a fit's records at one parameter
    point were each a miss — and its rows are the ones computed afresh."""
    import sys

    from feeddrive.engine import simulate as sim_module
    from feeddrive.model.assemble import assemble

    params = fd.preset("wang2021")
    t = np.linspace(0.0, 10.0, 200_001)  # 6.4 MB of table
    v = 1e-3 * np.minimum(t / 0.1, 1.0)
    model = assemble(params, "cdfs", 0.4, "locked", fd.SampledSpeed(t, v))
    key = sim_module._rows_key(model, model.P, model.T)
    assert model.T.nbytes > 6_000_000
    assert sum(sys.getsizeof(part) for part in key) < 2_000
    other_record = assemble(params, "cdfs", 0.4, "locked", fd.SampledSpeed(t, 1.01 * v))
    other_mass = assemble(params.replace_path("table.mass", 30.0), "cdfs", 0.4, "locked",
                          fd.SampledSpeed(t, v))
    ddfs = assemble(params, "ddfs", 0.4, "locked", fd.SampledSpeed(t, v, np.full(t.size, 16e-3)))
    keys = {key, sim_module._rows_key(other_mass, other_mass.P, other_mass.T),
            sim_module._rows_key(ddfs, ddfs.P, ddfs.T)}
    assert len(keys) == 3
    assert sim_module._rows_key(model, model.P.copy(), model.T.copy()) == key
    assert sim_module._rows_key(other_record, other_record.P, other_record.T) == key
    # a table elsewhere in T still tells apart: change a value outside the profile's table
    o = model.parameter_names.index("profile[0]")
    to, columns = int(model.P[o + 5]), int(model.P[o + 6])
    assert to + 4 * columns <= model.T.size
    if to > 0 or to + 4 * columns < model.T.size:
        outside = model.T.copy()
        outside[0 if to > 0 else -1] += 1.0
        assert sim_module._rows_key(model, model.P, outside) != key
    # the rows kept for one record are those the other's own evaluation gives
    from feeddrive._kept import Kept

    monkeypatch.setattr(sim_module, "_SWITCH_ROWS", Kept(64))
    fresh = sim_module.switching_rows(other_record, other_record.P)
    monkeypatch.setattr(sim_module, "_SWITCH_ROWS", Kept(64))
    sim_module.switching_rows(model, model.P)
    assert len(sim_module._SWITCH_ROWS) == 1
    np.testing.assert_array_equal(sim_module.switching_rows(other_record, other_record.P),
                                  fresh)
    assert len(sim_module._SWITCH_ROWS) == 1 and fresh.shape[0] >= 1  # shared, not a miss
