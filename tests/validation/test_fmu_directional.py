"""Directional derivatives of the model-exchange FMU (issue 38 item 4): the model's tangent,
generated from its own kernels (feeddrive.backends.tangent), against central differences of
the FMU's own derivatives on every declared (state, derivative) pair; the declared sparsity
against the differences where nothing is declared; inputs and outputs too; and the benefit in
the importer that calls them (PathSim's ModelExchangeFMU)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from fmu_helpers import Model, SharedExports, check_jacobian, require_c_compiler, richardson

from feeddrive.parameters import load, loads, preset

fmpy = pytest.importorskip("fmpy")
require_c_compiler()

GMS_FILE = Path(__file__).parents[2] / "examples" / "gms_guide.toml"
#: a set with the compensator's observer, torque ripple and lead error (every kernel kind)
LOADED = """extends = "wang2021-ripple"
name = "observer-ripple-lead"
[controller.compensation]
mode = "observer"
observer_gain = 100.0
[disturbances.lead_error]
orders = [1.0, 2.0]
amplitudes = [2e-6, 1e-6]
phases = [0.0, 0.3]
"""
CASES = {"ddfs-2": ("ddfs", "wang2021", 2), "ddfs-3": ("ddfs", "wang2021", 3),
         "cdfs-sampled": ("cdfs", "wang2021-drive", 2), "cdfs-gms": ("cdfs", "gms", 3),
         "cdfs-observer-ripple-lead": ("cdfs", "loaded", 2),
         "linear-motor": ("linear-motor", "linear-motor-example", 3),
         "rack-pinion": ("rack-pinion", "rack-pinion-example", 2)}


def _params(name: str):  # type: ignore[no-untyped-def]
    if name == "gms":
        return load(GMS_FILE)
    if name == "loaded":
        return loads(LOADED)
    return preset(name)


class _Exported(dict):  # type: ignore[type-arg]
    """The model-exchange FMU of each case, exported when a test first asks for it: the
    module's tests are spread over the test workers, and each worker built all seven
    (gcc, ≈ 2 s each) whatever it ran.  Exported once in the session (``shared_fmus``: the
    DDFS ones are those other FMU test files read too)."""

    def __init__(self, shared: SharedExports) -> None:
        super().__init__()
        self.shared = shared

    def __missing__(self, case: str) -> Path:
        drive, params, fmi = CASES[case]
        path = Path(self.shared.drive(_params(params), drive, fmi=fmi, kind="me").path)
        self[case] = path
        return path


@pytest.fixture(scope="module")
def models(shared_fmus: SharedExports) -> dict[str, Path]:
    return _Exported(shared_fmus)


def _point(m: Model) -> tuple[float, np.ndarray]:
    """A point away from rest: the states at 10× their nominal magnitudes (signs mixed, the
    friction sites sliding), mid-run."""
    rng = np.random.default_rng(38)
    x = rng.standard_normal(m.n) * 10 * m.nominals()
    return 0.05, x


def _inputs(m: Model) -> dict[str, float]:
    values = {"table_speed_reference": 2e-3, "nut_speed_reference": 16e-3, "load_force": 50.0}
    return {k: v for k, v in values.items() if m.var.get(k) is not None
            and m.var[k].causality == "input"}


@pytest.mark.parametrize("case", list(CASES))
def test_directional_derivatives_match_central_differences(models: dict, case: str,
                                                           tmp_path: Path) -> None:
    """Every declared (state, derivative) pair: the FMU's directional derivative equals the
    Richardson-extrapolated central difference of its own derivatives to 1e-6 relative
    (measured: ≤ 1e-8); where the pattern declares nothing the differences vanish too, so the
    declared sparsity (ModelStructure dependencies) holds."""
    m = Model(models[case], tmp_path)
    m.start(_inputs(m))
    t, x = _point(m)
    checked = check_jacobian(m, t, x, case)
    assert checked >= m.n  # the declared pairs live at this point (sampled loops: held)


@pytest.mark.parametrize("case", ["ddfs-2", "ddfs-3", "cdfs-sampled"])
def test_by_inputs_and_of_outputs(models: dict, case: str, tmp_path: Path) -> None:
    """The derivatives by each input (the reference through T, the load force through P)
    and the outputs (signals, motor torque, following error) by the states, against central
    differences (1e-6 relative)."""
    m = Model(models[case], tmp_path)
    inputs = _inputs(m)
    m.start(inputs)
    t, x = _point(m)
    ders = [d.valueReference for d in m.ders]
    for name, value in inputs.items():
        m.states_at(t, x)
        dd = m.directional(ders, [m.vr[name]], [1.0])

        def f(u: float, name: str = name) -> np.ndarray:
            m.set(name, u)
            m.states_at(t, x)
            return m.derivatives()

        fd = richardson(f, value, 1e-4 * max(abs(value), 1e-3))
        m.set(name, value)
        live = np.abs(fd) > 1e-9 * np.max(np.abs(fd))
        assert live.any(), name
        assert np.all(np.abs(dd - fd)[live] <= 1e-6 * np.abs(fd)[live]), (name, dd, fd)
        assert np.all(np.abs(dd[~live]) <= 1e-9 * np.max(np.abs(fd))), name
    outputs = [v.name for v in m.md.modelVariables if v.causality == "output"]
    nominal = m.nominals()
    for j in (1, 5, m.n - 4):  # a motor speed, the table speed, a loop integral
        m.states_at(t, x)
        seed = [0.0] * m.n
        seed[j] = 1.0
        dd = m.directional([m.vr[o] for o in outputs], [s.valueReference for s in m.states],
                           seed)

        def g(xj: float, j: int = j) -> np.ndarray:
            xx = x.copy()
            xx[j] = xj
            m.states_at(t, xx)
            return m.get(outputs)

        fd = richardson(g, x[j], 1e-4 * nominal[j])
        scale = np.max(np.abs(fd))
        assert np.all(np.abs(dd - fd) <= 1e-6 * np.abs(fd) + 1e-10 * scale), (j, outputs)


def test_jacobian_is_evaluated_once_per_point_and_the_swapped_request_works(
        models: dict, tmp_path: Path) -> None:
    """A Jacobian asked column by column costs one tangent evaluation per column group of the
    declared pattern at a point (cached until time, a state, an input or a parameter
    changes); the request with unknowns and knowns swapped (pathsim-fmi 0.1.1) gets the same
    Jacobian, with one warning; a known that is no state or input is refused, naming it."""
    m = Model(models["ddfs-3"], tmp_path)
    m.start(_inputs(m))
    t, x = _point(m)
    m.states_at(t, x)
    ders = [d.valueReference for d in m.ders]
    states = [s.valueReference for s in m.states]
    before = m.count("evaluations.tangents")
    cols, swapped = [], []
    for j in range(m.n):
        seed = [0.0] * m.n
        seed[j] = 1.0
        cols.append(m.directional(ders, states, seed))
        swapped.append(m.directional(states, ders, seed))
    used = m.count("evaluations.tangents") - before
    from feeddrive.fmu.model import build

    fm = build(preset("wang2021"), "ddfs", 0.4)
    groups = int(fm.model.jacobian_colours[:len(fm.model.states)].max()) + 1 + 2
    assert used == groups < m.n  # 10 sweeps for 17 columns
    assert np.array_equal(np.array(cols), np.array(swapped))
    warnings = [text for status, text in m.log if status == 1]
    assert len(warnings) == 1 and "swapped" in warnings[0]
    m.states_at(t + 1e-3, x)  # a new point: evaluated again
    m.directional(ders, states, [1.0] + [0.0] * (m.n - 1))
    assert m.count("evaluations.tangents") - before == 2 * groups
    with pytest.raises(Exception, match="status 3"):
        m.directional(ders, [m.vr["table.mass"]], [1.0])
    assert "expected a continuous state or an input" in m.log[-1][1]


def test_fmpy_cvode_does_not_call_them(models: dict) -> None:
    """fmpy 0.3's model-exchange solver (SUNDIALS CVODE) differences its own Jacobian: a run
    asks no directional derivative (docs/fmu.md says so)."""
    from fmpy import simulate_fmu

    res = simulate_fmu(str(models["ddfs-2"]), stop_time=0.05, output_interval=1e-3,
                       start_values={"table_speed_reference": 2e-3},
                       output=["evaluations.derivatives", "evaluations.tangents"])
    assert res["evaluations.derivatives"][-1] > 0
    assert res["evaluations.tangents"][-1] == 0


@pytest.mark.slow
def test_pathsim_model_exchange_needs_far_fewer_derivative_evaluations(models: dict) -> None:
    """The importer that calls them: PathSim's ModelExchangeFMU (pathsim-fmi) with an implicit
    solver (ESDIRK4, dt = 0.1 ms, fixed-point tolerance 1e-12), 30 ms of the DDFS at 0.5 mm/s
    with v_n = 16 mm/s.  Without directional derivatives PathSim differences its Jacobian
    (central, 2 derivative evaluations per state) at every implicit solve; with them it asks
    the FMU, which evaluates the model's tangent once per column group.  Counted by the FMU
    itself: derivative evaluations at most half (measured: 11.5× fewer; the tangent
    evaluations, 3× the derivative ones, not counted as derivatives), and the same trace: the
    Jacobian changes how the fixed-point iteration converges, not its fixed point, so the two
    traces agree within the iteration's tolerance, 1e-12 (PathSim's max-norm of the last
    update).  Measured 2.3e-16 m (1e-10 of the 2.3-µm stroke) on an Intel Xeon host and 2.9e-15
    m (1.3e-9) on an AMD EPYC one, whose LAPACK rounds PathSim's solves otherwise: the 1e-9 of
    the stroke asserted until then (2.3e-15 m) was tighter than the tolerance guarantees."""
    pytest.importorskip("pathsim_fmi")
    from fmu_helpers import pathsim_model_exchange

    path = models["ddfs-2"]  # the DDFS (wang2021) as an FMI 2.0 model-exchange FMU
    (rhs_without, tan_without), t0, x0, _ = pathsim_model_exchange(path, 0.03, False)
    (rhs_with, tan_with), t1, x1, _ = pathsim_model_exchange(path, 0.03, True)
    assert tan_without == 0 and tan_with > 0
    assert rhs_with <= 0.5 * rhs_without
    assert np.array_equal(t0, t1)
    stroke = abs(x0[-1] - x0[0])
    assert stroke > 1e-6 and math.isfinite(stroke)
    assert np.max(np.abs(x1 - x0)) <= 1e-12  # [m]: tolerance_fpi (fmu_helpers)
