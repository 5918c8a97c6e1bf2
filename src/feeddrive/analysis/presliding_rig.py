"""A pre-sliding test simulated on the package's engine.  SI units.

A mass m on one LuGre contact under a measured force F(t):

    m ẍ = F(t) − (σ0 z + σ1 ż + σ2 ẋ),   ż from Wang2021 Eq. (11)

assembled like a drive (:class:`feeddrive.model.codegen.Builder`): the friction force and
bristle rate are the LuGre law's own compiled kernel (:mod:`feeddrive.model.friction.lugre`,
the one every drive model calls), the force record enters as the engine's sampled load
(:func:`feeddrive.model.disturbances.load_force`, linear between samples; a load acts against
positive motion, so the record is −F), and the package's DOPRI5 driver
(:mod:`feeddrive.solvers.dopri5`) integrates it with the record's sample instants as its
breakpoints, so no step straddles a kink of the force.  One compiled module serves every
record and every (σ0, σ1): the numbers are the model's named parameter slots.

The driver runs at a fixed step (its ``adaptive = 0`` mode): h·max(√(σ0/m), (σ1 + σ2)/m) ≤
:data:`STEP_RATE` (the rule of the RK4 this replaced), and at least :data:`MIN_STEPS` steps
within each sample interval.  A least-squares fit differentiates the simulated response by
finite differences in (σ0, σ1); an adaptive step sequence that changes with the parameters
would add tolerance-level noise to that derivative (0.5 % of it at rtol 1e-10, measured),
fixed steps keep the response smooth in them.  The kinks of the LuGre force where the speed
changes sign (|v| and the branch switch) are crossed at low order by any fixed step, hence the
second step where the rate rule allows one: the screw-site step test of the tests (2 kHz) is
1.0e-5 of its displacement off scipy's DOP853 at rtol 1e-10 with one step per sample, 2.6e-6
with two (the RK4 was 9.2e-6 off).

A record sampled unevenly (jitter above 1e-6 of its mean step) is integrated on a uniform grid
of a quarter of its median step, the force interpolated onto it, and the displacement read at
the record's instants by cubic Hermite interpolation of the grid's position and speed.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from types import ModuleType
from typing import Literal

import numpy as np

from ..model import codegen
from ..model.disturbances import LoadProfile, emit_load
from ..model.friction import friction_law
from ..model.friction.lugre_parameters import LuGreParameters
from ..solvers import builds
from ..solvers.dopri5 import STATUS_MESSAGES, STATUS_OK, new_memory
from ..solvers.driver import step_space
from ..solvers.schedule import no_schedule

__all__ = ["LINEAR_BREAKAWAY", "MIN_STEPS", "STEP_RATE", "UNIFORM_JITTER", "simulate_presliding"]

#: breakaway force [N] the ``"linear"`` model gives both branches: σ0|v|z/g(v) vanishes
#: against v, so ż = v and the bristle follows the body (z = x)
LINEAR_BREAKAWAY = 1e300

#: a record whose instants stray from a uniform grid by more than this fraction of its step
#: is integrated on a finer grid (see the module docstring)
UNIFORM_JITTER = 1e-6

#: largest h·max(√(σ0/m), (σ1 + σ2)/m) of the fixed step
STEP_RATE = 0.25
#: fewest steps per sample interval
MIN_STEPS = 2

_LAW = "lugre"
_SITE = "friction.site"


@dataclass(frozen=True)
class _Rig:
    """The rig's generated module and what the engine's builds read of a model
    (:func:`feeddrive.solvers.builds.driver`: the C build translates the module's kernels)."""

    module: ModuleType
    parameter_names: tuple[str, ...]
    n_states: int
    bristle: int  # index of the bristle state
    states: tuple[codegen.Signal, ...]
    aux: tuple[codegen.Signal, ...]
    P: np.ndarray
    T: np.ndarray
    drive: str = "presliding-rig"

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.states)

    def slot(self, name: str) -> int:
        return self.parameter_names.index(name)


@functools.cache
def _rig() -> _Rig:
    """The test rig (built once per process; compiled by the engine's build, C or numba,
    at its first run)."""
    law = friction_law(_LAW)
    site = None  # the LuGre law's slots and states do not depend on the values
    b = codegen.Builder()
    b.imports["_friction_law"] = "feeddrive.model.friction:friction_law"
    b.state("position", "m", "test mass displacement", "position")
    b.state("speed", "m/s", "test mass speed", "speed")
    first = len(b.states)
    for state in law.states(site):
        b.state(f"site_{state}", law.state_unit, f"{law.name} {state} state", "position")
    b.param("mass", 1.0)
    slots = law.site_slots(site)
    o = b.named_params(_SITE, slots, np.zeros(len(slots)))
    # a placeholder record: the real one is written into P and T at each call
    load = emit_load(b, 0.0, 0.0, LoadProfile(np.array([0.0, 1.0]), np.zeros(2)))
    alias = b.use_dynamic(f"_law_{law.name}", f"_friction_law({law.name!r}).compiled",
                          law.compiled)
    own = tuple(f"site_{state}" for state in law.states(site))
    b.emit("{v} = {speed}")
    # the law's kernel reads and writes its own states y[first:] (beside its text)
    b.emit(codegen.Line(f"{{f_site}} = {alias}({{v}}, y, {first}, P, {o}, dy)",
                        writes=tuple(f"dy:{s}" for s in own),
                        reads=tuple(f"y:{s}" for s in own)))
    b.emit(f"{{f_load}} = {load}")
    b.emit("{load_force} = {f_load}")
    b.emit("{der(position)} = {v}")
    b.emit(f"{{der(speed)}} = (- {{f_load}} - {{f_site}}) / {b.p('mass')}")
    module = codegen.compile_module(codegen.module_source(b),
                                    b.dynamic_sources)
    return _Rig(module=module, parameter_names=tuple(b.param_names), n_states=len(b.states),
                bristle=first, states=tuple(b.states), aux=tuple(b.aux),
                P=b.packed_parameters(), T=b.packed_tables())


def _integrate(step: float, force: np.ndarray, mass: float, packed: np.ndarray,
               slots: tuple[str, ...], sigma0: float, damping: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """(position [m], speed [m/s]) at k·``step``, k = 0 … len(force) − 1, from rest in
    equilibrium with ``force[0]`` (z = x = F(0)/σ0)."""
    rig = _rig()
    P = np.zeros(len(rig.parameter_names))
    P[rig.slot("mass")] = mass
    for name, value in zip(slots, packed, strict=True):
        P[rig.slot(f"{_SITE}.{name}")] = value
    P[rig.slot("disturbances.load_step")] = step
    P[rig.slot("disturbances.load_offset")] = 0.0
    P[rig.slot("disturbances.load_points")] = force.size
    T = np.ascontiguousarray(-force, dtype=float)  # a load acts against positive motion
    rate = max(math.sqrt(sigma0 / mass), damping / mass)
    substeps = max(MIN_STEPS, math.ceil(step * rate / STEP_RATE))
    # a hair longer than step/substeps, so that the last step of each interval is the one
    # cut to the breakpoint: the same number of steps in every interval
    h = step / substeps * (1.0 + 1e-9)
    y0 = np.zeros(rig.n_states)
    y0[0] = y0[rig.bristle] = force[0] / sigma0
    n = rig.n_states
    t_end = (force.size - 1) * step
    # the build of the engine (C, or numba without a compiler) of every model
    integrate = builds.driver(rig, "integrate")  # type: ignore[arg-type]
    schedule = no_schedule(1)
    _, y, _, stats, _ = integrate(
        y0, t_end, 1, step, schedule, P, T, 1e-6, np.ones(n), np.zeros(n), math.inf, 1.0, 0,
        substeps * force.size + 10, 0, np.zeros(1), new_memory(n, h), np.full(n, math.inf),
        np.zeros((0, n)), *step_space(y0, schedule, len(rig.aux)))
    status = int(stats[0])
    if status != STATUS_OK or y.shape[0] != force.size:
        raise ValueError(f"pre-sliding simulation: {STATUS_MESSAGES.get(status, status)} at "
                         f"t = {stats[4]:.6g} s (mass {mass:.4g} kg, σ0 {sigma0:.4g} N/m)")
    return y[:, 0], y[:, 1]


def simulate_presliding(time: object, force: object, mass: float, friction: LuGreParameters,
                        *, model: Literal["lugre", "linear"] = "lugre") -> np.ndarray:
    """Displacement of a mass on a LuGre contact under a measured force.

    ``model="lugre"``: m ẍ = F − (σ0 z + σ1 ż + σ2 ẋ), ż from Wang2021 Eq. (11);
    ``model="linear"``: z = x, i.e. m ẍ + (σ1 + σ2) ẋ + σ0 x = F with σ2 the mean of the two
    branches (both branches' breakaway set to :data:`LINEAR_BREAKAWAY`).  Starts at rest in
    equilibrium with the initial force; the force is linear between the samples.

    Parameters
    ----------
    time : array_like
        Sample instants [s], increasing.
    force : array_like
        Force applied to the mass at those instants [N].
    mass : float
        The moving mass [kg] (for a rotary site, the inertia referred to the table: J/H²).
    friction : LuGreParameters
        The contact's parameters (F_c, F_s [N], v_s [m/s], σ2 [N s/m] per branch, σ0 [N/m],
        σ1 [N s/m]).
    model : {"lugre", "linear"}, default "lugre"
        The full bristle equation, or its linearisation.

    Returns
    -------
    numpy.ndarray
        Displacement at each instant [m], from the rest position x = 0 before the force.

    References
    ----------
    .. [1] Wang2021 Eq. (11).
    .. [2] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    """
    t = np.asarray(time, dtype=float)
    f = np.asarray(force, dtype=float)
    if model not in ("lugre", "linear"):
        raise ValueError(f"model = {model!r}: expected 'lugre' or 'linear'")
    if t.ndim != 1 or f.shape != t.shape or t.size < 2:
        raise ValueError("time, force: expected 1-D arrays of one length ≥ 2 [s, N]")
    law = friction_law(_LAW)
    slots = law.site_slots(friction)
    packed = np.array(law.pack(friction), dtype=float)
    if model == "linear":
        sigma2 = 0.5 * (friction.positive.viscous_coefficient
                        + friction.negative.viscous_coefficient)
        for d in ("positive", "negative"):
            packed[slots.index(f"{d}.coulomb_force")] = LINEAR_BREAKAWAY
            packed[slots.index(f"{d}.static_force")] = LINEAR_BREAKAWAY
            packed[slots.index(f"{d}.viscous_coefficient")] = sigma2
    sigma0 = friction.bristle_stiffness
    damping = friction.bristle_damping + max(friction.positive.viscous_coefficient,
                                             friction.negative.viscous_coefficient)
    span = float(t[-1] - t[0])
    step = span / (t.size - 1)
    k = np.arange(t.size)
    if float(np.max(np.abs(t - (t[0] + k * step)))) <= UNIFORM_JITTER * step:
        x, _ = _integrate(step, f, float(mass), packed, slots, sigma0, damping)
        return x
    fine = 0.25 * float(np.median(np.diff(t)))
    n = int(math.ceil(span / fine)) + 1
    grid = t[0] + fine * np.arange(n)
    x, v = _integrate(fine, np.interp(grid, t, f), float(mass), packed, slots, sigma0, damping)
    # cubic Hermite through (x, ẋ) at the grid points around each instant
    i = np.minimum(((t - t[0]) / fine).astype(int), n - 2)
    s = (t - grid[i]) / fine
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    return np.asarray(h00 * x[i] + h10 * fine * v[i] + h01 * x[i + 1] + h11 * fine * v[i + 1])
