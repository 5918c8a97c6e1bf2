"""Declared Jacobian pattern vs the text-parsed one it replaced vs finite differences.

For every model of the C-backend agreement test's list (``tests/unit/test_c_backend.py``:
every kind of model the test suite builds) plus the rack-and-pinion drive, its friction laws
and the acceleration feed-forward part, this compares three patterns of ∂f/∂(y, t):

* **declared**: ``Model.jacobian_pattern``, assembled from what each part declares it reads
  and writes (``Builder.flow``, :mod:`feeddrive.model.sparsity`);
* **parsed**: the dataflow analysis of the generated ``rhs`` text that the declarations
  replaced (``model/sparsity.py`` at commit ``OLD``, read with ``git show``);
* **observed**: entries that are non-zero in a plain one-column-per-call finite-difference
  Jacobian at ``N_STATES`` random states (both signs of every speed; sampled models also with
  their loops' flags set).

It prints one line per model (with the time each pattern takes to compute: the old analysis
un-cached, the declared one from ``Model.flows``) and fails (exit 1) where declared ⊉ parsed
or declared ⊉ observed.  Run from the repository root::

    python benchmarks/sparsity_equivalence.py
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import inspect
import subprocess
import sys
import time
import types
from pathlib import Path
from typing import Any

import numpy as np

import feeddrive as fd
from feeddrive.model.assemble import Model
from feeddrive.model.friction import friction_law
from feeddrive.model.reference import ConstantSpeed
from feeddrive.model.sparsity import declared_pattern

ROOT = Path(__file__).resolve().parents[1]
OLD = "ec220f9"  # the last commit with the text-parsing analysis
N_STATES = 30


def _old_sparsity() -> types.ModuleType:
    text = subprocess.run(["git", "show", f"{OLD}:src/feeddrive/model/sparsity.py"],
                          cwd=ROOT, check=True, capture_output=True, text=True).stdout
    module = types.ModuleType("old_sparsity")
    exec(compile(text, "old_sparsity.py", "exec"), module.__dict__)
    return module


def _cases() -> dict[str, Any]:
    spec = importlib.util.spec_from_file_location("c_cases", ROOT / "tests/unit/test_c_backend.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    cases = dict(mod.CASES)
    RP = fd.preset("rack-pinion-example")
    sampled = dict(mod.SAMPLED)

    def ch(p: fd.DriveParameters, changes: dict[str, Any]) -> fd.DriveParameters:
        for path, value in changes.items():
            p = p.replace_path(path, value)
        return p

    from feeddrive.model.parts.acceleration_feedforward import AccelerationFeedforward

    def with_acc(p: fd.DriveParameters) -> fd.DriveParameters:
        part = AccelerationFeedforward(gain=0.02, period=1e-3)
        return dataclasses.replace(p, sections=tuple(sorted(
            (*p.sections, ("acceleration_feedforward", part)))))

    cases.update({
        "rack-pinion": lambda: (fd.DriveSystem(RP, "rack-pinion", 0.4), ConstantSpeed(2e-3)),
        "rack-pinion-dahl-stribeck": lambda: (fd.DriveSystem(ch(RP, {
            "rack_pinion.gearbox_friction.law": "dahl", "friction.guide.law": "stribeck"}),
            "rack-pinion", 0.4), ConstantSpeed(2e-3)),
        "rack-pinion-sampled-quantised": lambda: (
            fd.DriveSystem(ch(RP, sampled | dict(mod.QUANTISED)), "rack-pinion", 0.4),
            ConstantSpeed(2e-3)),
        "acceleration-feedforward-ddfs": lambda: (fd.DriveSystem(with_acc(ch(W, sampled)), "ddfs",
                                                                 0.4),
                                                  ConstantSpeed(2e-3, 16e-3, ramp_time=0.02)),
        "acceleration-feedforward-linear-motor": lambda: (
            fd.DriveSystem(with_acc(ch(fd.preset("linear-motor-example"), sampled)),
                           "linear-motor", 0.4), ConstantSpeed(2e-3)),
    })
    return cases


W = fd.preset("wang2021")


def parsed_pattern(old: types.ModuleType, model: Model, system: fd.DriveSystem) -> np.ndarray:
    """The old analysis on the generated rhs, told the local-state kernels as assembly did
    (each friction law's alias with its state count — the last site's — and the observer)."""
    src = model.source
    start = src.index("def rhs(")
    end = src.index("\n\n\n", start)
    rhs = src[start:end] + "\n"
    aliases = {line.split(" as ")[1].strip() for line in src.splitlines()
               if line.startswith("from ") and " as " in line}
    local: dict[str, int] = {}
    for site, law_name in model.sites:
        law = friction_law(law_name)
        n = sum(1 for s in model.state_names if s.startswith(f"{site}_")
                and s.removeprefix(f"{site}_") in law.state_names
                or s.startswith(f"{site}_element"))
        local[f"_law_{law_name.replace('-', '_')}"] = n
    if "_observer_force" in aliases:
        local["_observer_force"] = 1
    pure = frozenset(aliases | {"_friction_law"})
    old._pattern.cache_clear()
    return old.jacobian_pattern(rhs, len(model.state_names), pure, local)


def _scales(model: Model) -> np.ndarray:
    atol, _ = model.tolerances(1e-3, 1e-3, 1.0)
    for i, name in enumerate(model.state_names):
        if name.endswith(("_bristle", "_friction_observer")):
            atol[i] = 1e-6
        elif "_element" in name:
            atol[i] = 1e-4
    return atol


def _inputs(model: Model, sampled: bool) -> tuple[np.ndarray, tuple[int, ...]]:
    """(P, loop flags) of one right-hand-side call: the sampled parts holding their outputs
    when ``sampled``, else running continuously — by the loop-period flags of the rhs (engine
    v2) or, where the rhs has none, by every clock of the model's schedule at a period > 0
    (or 0)."""
    P = model.P.copy()
    if "n_pos" in inspect.signature(model.module.rhs.py_func).parameters:
        return P, (1, 1, 1) if sampled else (0, 0, 0)
    for _, slot in getattr(model, "clocks", ()):
        P[slot] = 1e-4 if sampled else 0.0
    return P, ()


def observed_pattern(model: Model, seed: int) -> np.ndarray:
    n = len(model.state_names)
    full = np.ones((n, n + 1), dtype=np.uint8)
    colour = np.arange(n + 1)
    rng = np.random.default_rng(seed)
    atol, _ = model.tolerances(1e-9, 1e-8, 1e-6)
    seen = np.zeros((n, n + 1), dtype=bool)
    scale = _scales(model)
    for k in range(N_STATES):
        y = rng.normal(size=n) * scale * rng.choice([0.1, 1.0, 10.0], size=n)
        t = float(rng.uniform(0.0, 2.0))
        P, flags = _inputs(model, sampled=k % 5 == 4)
        held = rng.normal(size=model.n_held) * 0.1
        aux = np.empty(len(model.aux))
        f0 = np.empty(n)
        model.module.rhs(t, y, held, P, model.T, *flags, f0, aux)
        J = np.empty((n, n))
        ft = np.empty(n)
        model.module._r4_fd_jacobian(t, y, f0, held, P, model.T, *flags, atol, J, ft,
                                     np.empty(n), np.empty(n), aux, np.ones(n, dtype=np.bool_),
                                     full, colour)
        seen |= np.column_stack([J, ft]) != 0.0
    return seen.astype(np.uint8)


def main() -> int:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    old = _old_sparsity()
    bad = 0
    print(f"{'model':48s} {'n':>3s} {'declared':>8s} {'parsed':>6s} {'observed':>8s}  "
          f"declared − parsed")
    totals = np.zeros(3, dtype=int)
    times = np.zeros(2)
    for name, case in _cases().items():
        system, profile = case()
        model = system.model(profile)
        D = model.jacobian_pattern.astype(bool)
        t0 = time.perf_counter()
        S = parsed_pattern(old, model, system).astype(bool)
        t1 = time.perf_counter()
        again = declared_pattern(model.state_names, [a.name for a in model.aux],
                                 {w: set(r) for w, r in model.flows})
        t2 = time.perf_counter()
        assert np.array_equal(again, model.jacobian_pattern)
        times += (t1 - t0, t2 - t1)
        O = observed_pattern(model, seed=sum(map(ord, name))).astype(bool)
        extra = [(model.state_names[i], (model.state_names + ("t",))[j])
                 for i, j in np.argwhere(D & ~S)]
        missing = np.argwhere((S | O) & ~D)
        totals += (D.sum(), S.sum(), O.sum())
        print(f"{name:48s} {D.shape[0]:3d} {D.sum():8d} {S.sum():6d} {O.sum():8d}  "
              f"{'; '.join(f'd{a}/d{b}' for a, b in extra) or '—'}")
        if missing.size:
            bad += 1
            names = model.state_names + ("t",)
            print("   NOT DECLARED:", [(names[i], names[j]) for i, j in missing])
    print(f"{'total':48s} {'':3s} {totals[0]:8d} {totals[1]:6d} {totals[2]:8d}")
    print(f"pattern computation, all models: parsed {1e3 * times[0]:.1f} ms, declared "
          f"{1e3 * times[1]:.1f} ms")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
