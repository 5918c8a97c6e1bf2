"""The σ1 profile interval's edges do not depend on the profile's grid (session 26).

``identify dynamic`` interpolated each edge linearly between two points of a 13-point grid
(``np.geomspace(1e-3, 1, 13) × s1_max``, 78 % apart), and the printed bound moved 3–4 % with
a finer grid (an outside check, 2026-12-07: a slow record at 100 Hz, 4.09e+04 N s/m at 13
points, 4.24e+04 at 49 or 193).  Each edge is now the root of the profile itself in the grid's
bracket.  Checked here against an independent evaluation of the profile (σ0 refitted by
scipy's bounded scalar minimiser on the engine's pre-sliding simulation, not by the fit's own
code) on a fine 400-point grid across the bracket, and against the grid's size (11, 13 and 25
points).  Records as tests/unit/test_identification.py makes them: a mass on the full LuGre
contact (wang2021's screw site) integrated by DOP853, plus 1 % position noise.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from scipy.optimize import minimize_scalar
from test_identification import lugre_reference

import feeddrive
from feeddrive.analysis import presliding
from feeddrive.analysis.presliding import DynamicFit, fit_presliding, site_mass
from feeddrive.analysis.presliding_rig import simulate_presliding

PARAMS = feeddrive.preset("wang2021")
SCREW = PARAMS.friction.screw
MASS = site_mass(PARAMS, "screw", "cdfs")

#: [-] an edge equals the fine-grid evaluation to this (relative): the fine grid's spacing is
#: 1/400 of a bracket, so its linear interpolation is good to ~1e-6; the old 13-point
#: interpolation was 4e-2 off on the slow record, 2.5e-4 on the step record's edges
FINE_RTOL = 1e-4
#: [-] the edges at 11, 13 and 25 grid points agree to this (relative): the root-finder's
#: tolerance (presliding.PROFILE_EDGE_RTOL, 1e-6) with margin
GRID_RTOL = 1e-5


def _record(force: Callable[[float], float], duration: float, rate: float,
            seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """test_identification's DOP853 reference of mass + LuGre, 1 % position noise."""
    t, f, x = lugre_reference(force, duration, rate)
    rng = np.random.default_rng(seed)
    return t, f, x + 0.01 * np.ptp(x) * rng.standard_normal(x.size)


def _slow(time: float) -> float:
    """A 0.5 Hz raised cosine to 30 N: σ1 poorly determined, the interval 0 … an upper edge
    (the outside check's record: 4 s at 100 Hz, noise seed 0)."""
    return 15.0 * (1.0 - math.cos(2.0 * math.pi * 0.5 * time))


def _step(time: float) -> float:
    """30 N over 2 ms at 50 ms: σ1 determined, both edges finite."""
    return 30.0 * min(max((time - 0.05) / 0.002, 0.0), 1.0)


RECORDS = {"slow": (_slow, 4.0, 100.0, 0), "step": (_step, 0.3, 2000.0, 0)}


_CACHE: dict[object, object] = {}


def _cached(key: object, make: Callable[[], object]) -> object:
    if key not in _CACHE:
        _CACHE[key] = make()
    return _CACHE[key]


def _rec(name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return _cached(("record", name), lambda: _record(*RECORDS[name]))  # type: ignore[return-value]


def _fit(name: str, points: int) -> DynamicFit:
    """The fit of record ``name`` with a ``points``-point profile grid (cached)."""
    def make() -> DynamicFit:
        t, f, x = _rec(name)
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(presliding, "PROFILE_GRID_POINTS", points, raising=False)
            return fit_presliding(t, f, x, mass=MASS, friction=SCREW)

    return _cached(("fit", name, points), make)  # type: ignore[return-value]


def _profile(t: np.ndarray, f: np.ndarray, x: np.ndarray, s1: float, s0: float) -> float:
    """The profiled SSR at σ1 [m²], independently: σ0 by a bounded scalar minimisation in
    log σ0 (within a factor e of ``s0``), the offset free."""
    def ssr(log_s0: float) -> float:
        params = SCREW.with_values(bristle_stiffness=math.exp(log_s0), bristle_damping=s1)
        r = x - simulate_presliding(t, f, MASS, params)
        r = r - r.mean()
        return float(r @ r)

    res = minimize_scalar(ssr, bounds=(math.log(s0) - 1.0, math.log(s0) + 1.0),
                          method="bounded", options={"xatol": 1e-10})
    return float(res.fun)


def _fine_edge(name: str, side: int) -> float:
    """The edge (``side`` 0: low, 1: high) on a fine grid: 400 points evenly across the
    13-point fit's bracket of it (its grid neighbours), the independent profile on them,
    interpolated linearly where it crosses the threshold.  The profile is monotone in the
    bracket, so the crossing pair is found by bisection over the 400 indices (9 evaluations:
    the pair that evaluating all 400 finds)."""
    return _cached(("fine", name, side), lambda: _fine(name, side))  # type: ignore[return-value]


def _fine(name: str, side: int) -> float:
    t, f, x = _rec(name)
    fit = _fit(name, 13)
    edge = fit.sigma1_interval[side]
    s1 = fit.profile_sigma1
    fine = np.linspace(s1[s1 < edge].max(), s1[s1 > edge].min(), 400)
    s0 = fit.bristle_stiffness.value
    known: dict[int, float] = {}

    def excess(i: int) -> float:
        if i not in known:
            known[i] = _profile(t, f, x, float(fine[i]), s0) - fit.ssr_threshold
        return known[i]

    a, b = 0, fine.size - 1
    assert excess(a) * excess(b) < 0.0  # the bracket holds one crossing
    while b - a > 1:
        m = (a + b) // 2
        if (excess(m) < 0.0) == (excess(a) < 0.0):
            a = m
        else:
            b = m
    ea, eb = excess(a), excess(b)
    return float(fine[a] + (fine[b] - fine[a]) * ea / (ea - eb))


@pytest.mark.parametrize("points", [13, 11, 25])
@pytest.mark.parametrize("name", sorted(RECORDS))
def test_the_edges_are_the_profiles_crossings_whatever_the_grid(name: str,
                                                                 points: int) -> None:
    """At 11, 13 and 25 grid points each edge is the fine-grid crossing to FINE_RTOL and the
    13-point edge to GRID_RTOL, and the profile returned passes through the threshold there
    (the slow record's interval is 0 … an edge, the step record's has two)."""
    fit = _fit(name, points)
    low, high = fit.sigma1_interval
    if name == "slow":
        assert low == 0.0 and not fit.sigma1_determined
    else:
        assert 0.0 < low < fit.bristle_damping.value < high and fit.sigma1_determined
    for side in ((1,) if name == "slow" else (0, 1)):
        edge = fit.sigma1_interval[side]
        assert math.isfinite(edge)
        assert edge == pytest.approx(_fine_edge(name, side), rel=FINE_RTOL), (name, side)
        assert edge == pytest.approx(_fit(name, 13).sigma1_interval[side], rel=GRID_RTOL)
        on = fit.profile_ssr[fit.profile_sigma1 == edge]
        assert on.size == 1 and on[0] == pytest.approx(fit.ssr_threshold, rel=1e-5)
