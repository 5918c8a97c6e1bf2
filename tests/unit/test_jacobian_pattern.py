"""The structural Jacobian pattern the parts declare and the grouped (coloured)
finite-difference Jacobian of RODAS4 (``feeddrive.model.sparsity``,
``rodas4.fd_jacobian_template``).

* the declared pattern covers every numerical non-zero of the plain one-column-per-call
  Jacobian at many random states, for the shipped presets' CDFS, DDFS, linear motor and
  rack-and-pinion drive and for models with the other friction laws, the friction observer
  and the disturbances — an under-estimate (a wrong Jacobian) is caught, as a deliberately
  thinned pattern shows;
* the grouped Jacobian equals the plain one (bit for bit: a row never sees a second column of
  its group, so every difference is computed from the same numbers);
* the groups are fewer than the differenced columns; declarations that name what no part
  writes, or leave a derivative undeclared, are refused.

``benchmarks/sparsity_equivalence.py`` compares the declared pattern with the text-parsing
analysis it replaced, model by model (equal in all 35 model kinds, benchmarks/README.md).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.model.assemble import Model
from feeddrive.model.disturbances import LeadError, TorqueRipple
from feeddrive.model.loops import Compensation
from feeddrive.model.reference import ConstantSpeed
from feeddrive.model.sparsity import colour_columns, declared_pattern

W = fd.preset("wang2021")


def _laws(p: fd.DriveParameters, **laws: str) -> fd.DriveParameters:
    for site, law in laws.items():
        p = p.replace_path(f"friction.{site}.law", law)
    return p


CASES: dict[str, Callable[[], tuple[fd.DriveSystem, ConstantSpeed]]] = {
    "wang2021-ddfs": lambda: (fd.DriveSystem(W, "ddfs", 0.4), ConstantSpeed(0.5e-3, 16e-3)),
    "wang2021-cdfs": lambda: (fd.DriveSystem(W, "cdfs", 0.4), ConstantSpeed(1.2e-3)),
    "linear-motor": lambda: (fd.DriveSystem(fd.preset("linear-motor-example"), "linear-motor",
                                            0.4), ConstantSpeed(2e-3)),
    "rack-pinion": lambda: (fd.DriveSystem(fd.preset("rack-pinion-example"), "rack-pinion",
                                           0.4), ConstantSpeed(2e-3)),
    "dahl-stribeck-ddfs": lambda: (
        fd.DriveSystem(_laws(W, screw="dahl", nut="stribeck", guide="dahl"), "ddfs", 0.3),
        ConstantSpeed(1e-3, 8e-3)),
    "stribeck-dahl-cdfs": lambda: (
        fd.DriveSystem(_laws(W, screw="stribeck", nut="dahl", guide="none"), "cdfs", 0.5),
        ConstantSpeed(1e-3)),
    "observer-ripple-lead": lambda: (
        fd.DriveSystem(W.replace_path("controller.compensation",
                                      Compensation(mode="observer", observer_gain=50.0))
                       .replace_path("disturbances.screw_motor_ripple",
                                     TorqueRipple((6.0,), (0.0135,), (0.3,)))
                       .replace_path("disturbances.lead_error",
                                     LeadError((1.0,), (2e-6,), (0.0,))), "cdfs", 0.4),
        ConstantSpeed(1e-3)),
}


def _parameters(model: Model, sampled: bool) -> np.ndarray:
    """The model's P; ``sampled``: with every clock of its schedule at a period > 0 (the
    right-hand side then reads the held values of the sampled parts)."""
    P = model.P.copy()
    if sampled:
        for _, slot in model.clocks:
            P[slot] = 1e-4
    return P


def _jacobian(model: Model, t: float, y: np.ndarray, S: np.ndarray, colour: np.ndarray,
              live: np.ndarray | None = None, sampled: bool = False,
              ) -> tuple[np.ndarray, int]:
    """([J | ft], calls) of the compiled grouped finite-difference Jacobian."""
    n = y.size
    P = _parameters(model, sampled)
    held = np.zeros(model.n_held)
    aux = np.empty(len(model.aux))
    f0 = np.empty(n)
    model.module.rhs(t, y, held, P, model.T, f0, aux)
    J = np.empty((n, n))
    ft = np.empty(n)
    atol, _ = model.tolerances(1e-9, 1e-8, 1e-6)
    live = np.ones(n, dtype=np.bool_) if live is None else live
    calls = model.module._r4_fd_jacobian(t, y, f0, held, P, model.T, atol, J, ft,
                                         np.empty(n), np.empty(n), aux, live, S, colour)
    return np.column_stack([J, ft]), int(calls)


def dense_jacobian(model: Model, t: float, y: np.ndarray, sampled: bool = False) -> np.ndarray:
    """[∂f/∂y | ∂f/∂t], one right-hand-side call per column (full pattern, one column a
    group)."""
    n = y.size
    full = np.ones((n, n + 1), dtype=np.uint8)
    return _jacobian(model, t, y, full, np.arange(n + 1), sampled=sampled)[0]


def undeclared_entries(S: np.ndarray, J: np.ndarray) -> list[tuple[int, int]]:
    """Entries where the numerical Jacobian is non-zero but the pattern says structurally 0."""
    return [(int(i), int(j)) for i, j in np.argwhere((J != 0.0) & (S == 0))]


def random_states(system: fd.DriveSystem, profile: ConstantSpeed, model: Model, count: int,
                  seed: int) -> list[tuple[float, np.ndarray]]:
    """States from a short run, scaled by random factors in (−2, 2) (both signs of every
    speed: both friction branches) plus noise of 10⁴ absolute tolerances; random times."""
    r = fd.simulate(system, profile, 0.3)
    traj = np.column_stack([r[name] for name in model.state_names])
    atol, _ = model.tolerances(1e-9, 1e-8, 1e-6)
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        k = int(rng.integers(traj.shape[0]))
        y = traj[k] * rng.uniform(-2, 2, traj.shape[1]) + 1e4 * atol * rng.normal(size=atol.size)
        out.append((float(rng.uniform(0.0, 0.3)), y))
    return out


@pytest.mark.parametrize("case", list(CASES))
def test_pattern_covers_the_dense_jacobian_and_groups_reproduce_it(case: str) -> None:
    system, profile = CASES[case]()
    model = system.model(profile)
    S, colour = model.jacobian_pattern, model.jacobian_colours
    n = len(model.state_names)
    assert S.shape == (n, n + 1)
    assert S.sum() < S.size  # the analysis understood the model (else everything is 1)
    seen = np.zeros_like(S, dtype=bool)
    for k, (t, y) in enumerate(random_states(system, profile, model, 30, seed=len(case))):
        sampled = k % 5 == 4  # sampled loops read held values
        dense = dense_jacobian(model, t, y, sampled)
        assert undeclared_entries(S, dense) == [], (case, t, y, sampled)
        seen |= dense != 0.0
        grouped, calls = _jacobian(model, t, y, S, colour, sampled=sampled)
        np.testing.assert_array_equal(grouped, dense)
        assert calls == colour.max() + 1
    # the states exercised the model: most declared entries were seen non-zero
    # the states are not degenerate: a good part of the declared entries were seen non-zero
    # (measured: 57 of 70 in the DDFS, 29 of 64 at the least — the CDFS's held nut)
    assert seen.sum() >= S.sum() / 3, (seen.sum(), S.sum())


def test_a_thinned_pattern_is_caught() -> None:
    """Removing one entry that is numerically non-zero is reported by the helper of the
    coverage test, and the grouped Jacobian with that pattern is then wrong there."""
    system, profile = CASES["wang2021-ddfs"]()
    model = system.model(profile)
    t, y = random_states(system, profile, model, 1, seed=3)[0]
    dense = dense_jacobian(model, t, y)
    S = model.jacobian_pattern.copy()
    i, j = np.argwhere((dense != 0.0) & (S == 1))[7]
    S[i, j] = 0
    assert undeclared_entries(S, dense) == [(int(i), int(j))]
    grouped, _ = _jacobian(model, t, y, S, colour_columns(S))
    assert grouped[i, j] == 0.0 != dense[i, j]


def test_groups_are_fewer_than_live_columns() -> None:
    """Measured (wang2021, table at mid-screw): the DDFS's 15 states and t — 16 columns, one
    call each — fall into 8 groups; the CDFS, whose held nut leaves 10 live columns (9 states
    and t), needs 7 calls."""
    ddfs = fd.DriveSystem(W, "ddfs", 0.4).model(ConstantSpeed(0.5e-3, 16e-3))
    colour = ddfs.jacobian_colours
    assert colour.size == 16
    assert colour.max() + 1 == 8
    cdfs = fd.DriveSystem(W, "cdfs", 0.4).model(ConstantSpeed(1.2e-3))
    n = len(cdfs.state_names)
    y = np.full(n, 1e-4)
    f0 = np.empty(n)
    cdfs.module.rhs(0.2, y, np.zeros(cdfs.n_held), cdfs.P, cdfs.T, f0,
                    np.empty(len(cdfs.aux)))
    dense = dense_jacobian(cdfs, 0.2, y)
    live = np.array([f0[i] != 0.0 or np.any(dense[i] != 0.0) for i in range(n)])
    assert live.sum() == 9
    grouped, calls = _jacobian(cdfs, 0.2, y, cdfs.jacobian_pattern, cdfs.jacobian_colours,
                               live=live)
    assert calls == 7
    np.testing.assert_array_equal(grouped[:, np.append(live, True)],
                                  dense[:, np.append(live, True)])


def test_frozen_state_that_moves_is_reported() -> None:
    """A state taken as frozen whose derivative is not 0 gives a negative call count."""
    model = fd.DriveSystem(W, "ddfs", 0.4).model(ConstantSpeed(0.5e-3, 16e-3))
    n = len(model.state_names)
    live = np.ones(n, dtype=np.bool_)
    live[model.index("nut_speed")] = False
    _, calls = _jacobian(model, 0.2, np.full(n, 1e-4), model.jacobian_pattern,
                         model.jacobian_colours, live=live)
    assert calls < 0


STATES = ("x", "v", "z")


def test_declarations_are_followed_through_named_values() -> None:
    """dy:x ← v; f ← (v, z) and dy:z ← (v, z) (a friction kernel); dy:v ← (f, t, aux:u);
    aux:u ← x; a name written twice (two branches) depends on the union."""
    flows = {"dy:x": {"y:v"}, "f": {"y:v", "y:z"}, "dy:z": {"y:v", "y:z"},
             "aux:u": {"y:x"}, "dy:v": {"f", "t", "aux:u"}, "w": {"y:x"}}
    flows["w"] |= {"y:z"}
    S = declared_pattern(STATES, ("u",), flows)
    np.testing.assert_array_equal(S, np.array([[0, 1, 0, 0], [1, 1, 1, 1], [0, 1, 1, 0]],
                                              dtype=np.uint8))


@pytest.mark.parametrize(("flows", "message"), [
    ({"dy:x": {"g"}, "dy:v": set(), "dy:z": set()}, "reads 'g', which no part writes"),
    ({"dy:x": {"y:q"}, "dy:v": set(), "dy:z": set()}, "'y:q' is no state"),
    ({"dy:x": set(), "dy:v": set()}, "derivative of z"),
    ({"dy:x": set(), "dy:v": set(), "dy:z": set(), "aux:nope": set()}, "no state derivative"),
])
def test_incomplete_declarations_are_refused(flows: dict[str, set[str]], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        declared_pattern(STATES, ("u",), flows)


def test_a_site_whose_speed_reads_a_state_by_index_is_refused(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A mechanism that writes a friction site's speed as ``y[k]`` code instead of naming the
    state in braces would drop the read from the derived flows: refused, naming the read."""
    import dataclasses

    from feeddrive.model.mechanisms.linear_motor import LinearMotorDrive

    plain = LinearMotorDrive.sites
    monkeypatch.setattr(LinearMotorDrive, "sites", lambda self, b: [
        dataclasses.replace(s, speed=b.y("table_speed")) for s in plain(self, b)])
    # a set no other test builds: a built model is kept by its set, drive, start and profile,
    # and this one must be built anew (it took an unused start position, 0.33 m, before
    # session 30 refused one on a linear motor)
    own = fd.preset("linear-motor-example")
    own = own.replace_path("table.mass", own.table.mass * 1.001)
    system = fd.DriveSystem(own, "linear-motor")
    with pytest.raises(ValueError, match=r"f_guide.*reads y\[.*in braces"):
        system.model(ConstantSpeed(1.7e-3))
