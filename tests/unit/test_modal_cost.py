"""Issues 35 (item 4) and 42: what the default ``modal`` method spends on the DDFS, by count.

The default run of benchmarks/bench_engine.py's ``ddfs_0p5_vn16`` scenario (``wang2021`` DDFS
at mid-screw, table 0.5 mm/s, hollow motor 16 mm/s, 10 s), measured 2026-12-05: 3 444 steps
(185 rejected), 2 601 RODAS4 steps, 2 439 Jacobians, 40 010 right-hand sides, 131
eigen-analyses.  Until then every Jacobian also got a spectral-radius estimate (12 dense
power iterations, ≈ 1.5 µs each at 15 states, ≈ 15 % of the run's CPU): 2 439 of them.
``modal`` now takes the spectral radius of the switch back to DOPRI5 with the step cap's
eigen-analysis, from the same reference Jacobian (both redone when a row of J moves by
``modes.REFRESH``), so it makes as many estimates as eigen-analyses; and once the moved test
finds the Jacobian within ``modes.REFRESH`` of that reference it keeps it for up to
``MODAL_EVERY`` RODAS4 steps (fresh after a rejected step and at every event): measured
1 493 Jacobians, 33 715 right-hand sides, 2 831 RODAS4 steps, the same error against the
Radau reference (1.66e-11 m; benchmarks/README.md).
"""

from __future__ import annotations

from statistics import median
from typing import Any

import pytest

import feeddrive as fd
from feeddrive.engine.simulate import DriveSystem, SolverOptions, simulate
from feeddrive.model.reference import ConstantSpeed

# medians over the seven rounding-level perturbations of the ``ddfs_counts`` fixture
# (tests/conftest.py: one run's counts move by up to ±13 %, its steps by up to +40 %), measured
# on the tree before the back substitution took the reference BLAS order (f191cdd,
# 2026-12-06), bounds +10 %: RODAS4 261 Jacobians, 1 175 Rosenbrock steps, 47 197 right-hand
# sides; RODAS5P (the default since 2026-12-05) 466, 897, 20 473.  (Single runs at the
# unperturbed position, 2026-12-05: RODAS4 31 eigen-analyses, 252 Jacobians, 1 166
# Rosenbrock steps of 7 549, 47 197 right-hand sides; RODAS5P 48, 524, 938 of 2 331, 19 914.)
BOUNDS = {"rodas4": (287, 1293, 51917), "rodas5p": (513, 987, 22520)}


@pytest.mark.parametrize("rosenbrock", sorted(BOUNDS))
def test_modal_takes_one_spectral_radius_per_eigen_analysis_on_the_ddfs(
        rosenbrock: str, ddfs_counts: dict[str, list[dict[str, Any]]]) -> None:
    runs = ddfs_counts[rosenbrock]
    for stats in runs:
        # RODAS4: measured 131 and 131 once; the tree before took 2 439 estimates, one per
        # Jacobian
        assert stats["spectral_radii"] == stats["eigen_analyses"]
        assert stats["spectral_radii"] <= 200
    # RODAS4: measured 1 493 Jacobians and 33 715 right-hand sides; the tree before: 2 439 and
    # 40 010, a Jacobian at every RODAS4 step.  Since the cost-weighted switch back to DOPRI5
    # (driver.RODAS4_COST, 2026-12-05) more calls, each DOPRI5 step ≈ 5× cheaper than a RODAS4
    # step (benchmarks/bench_switch_cost.py): BOUNDS, on the medians
    jacobians, rosenbrock_steps, calls = BOUNDS[rosenbrock]
    assert median(s["jacobians"] for s in runs) <= jacobians
    assert median(s["rosenbrock_steps"] for s in runs) <= rosenbrock_steps
    assert median(s["rhs_evaluations"] - s["output_rhs_evaluations"] for s in runs) <= calls


def test_auto_still_estimates_the_spectral_radius_at_every_jacobian() -> None:
    # ``auto`` has no eigen-analysis: its switch back needs the estimate of each Jacobian
    system = DriveSystem(fd.preset("wang2021"), "ddfs", 0.4)
    stats = simulate(system, ConstantSpeed(0.5e-3, 16e-3), 1.0,
                     options=SolverOptions(method="auto")).solver_stats
    assert stats["eigen_analyses"] == 0
    assert stats["spectral_radii"] == stats["jacobians"] > 0


def test_a_continued_modal_run_keeps_its_spectral_radius() -> None:
    # the estimate, the quiet flag and the Jacobians since the eigen-analysis are carried in
    # the driver's memory: a DDFS run continued at 1 s is bit for bit the one-call run with a
    # step end there (with the estimate lost at the call, the continued run switched to
    # DOPRI5 and back in every later call)
    import math

    import numpy as np

    from feeddrive.engine.simulate import Simulation, profile_breakpoints
    from feeddrive.solvers import switching

    system = DriveSystem(fd.preset("wang2021"), "ddfs", 0.4)
    profile = ConstantSpeed(0.5e-3, 16e-3)
    sim = Simulation(system, profile, SolverOptions())
    model, grid = sim.model, sim.grid
    stops = np.sort(np.append(profile_breakpoints(profile, 2.0, grid.base), 1.0))

    def run(start: int, end: float, y0: np.ndarray, held: np.ndarray,
            memory: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        _, y, _, stats, _ = switching.integrate(
            model, y0, end, grid.out_every, grid.base, grid.schedule, sim.tolerances.rtol,
            sim.atol, sim.rel, 1e-6, math.inf, 1, 10 ** 6, sim.options.driver_mode[0],
            stops,
            want_aux=False, start=start, held=held, memory=memory)
        return y, stats

    n = len(model.states)
    whole, stats = run(0, 2.0, sim.y0, np.zeros(model.n_held), switching.new_memory(n))
    held, memory = np.zeros(model.n_held), switching.new_memory(n)
    first, s1 = run(0, 1.0, sim.y0, held, memory)
    second, s2 = run(int(round(1.0 / grid.base)), 2.0, first[-1].copy(), held, memory)
    assert np.array_equal(np.vstack([first, second[1:]]), whole)
    assert s1[7] + s2[7] == stats[7]  # the method switches
