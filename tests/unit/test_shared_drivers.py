"""The solver drivers compiled once for every model (feeddrive.solvers.shared, issue 21
item 3: a cold ``reproduce`` compiled the drivers again for each of its 8 models)."""

from __future__ import annotations

import numpy as np
import pytest

import feeddrive
from feeddrive._jit import HAVE_NUMBA
from feeddrive.model.reference import ConstantSpeed
from feeddrive.solvers import shared

needs_numba = pytest.mark.skipif(
    not HAVE_NUMBA, reason="numba is not installed (the optional extra feeddrive[numba]); "
    ".ci/min-versions installs it and runs this test of the numba build")



@pytest.fixture(autouse=True)
def _numba_build(monkeypatch: pytest.MonkeyPatch) -> None:
    """These tests are of the numba build (feeddrive.solvers.builds chooses C where a compiler
    is found)."""
    monkeypatch.setenv("FEEDDRIVE_ENGINE", "numba")


def test_model_names_become_leading_arguments_passed_on_to_callees() -> None:
    """A function reading a model name — itself or through a function it calls — takes it
    first, and passes it on; the others are left as they are.  The rewritten text runs."""
    source = (
        "def inner(x):\n    return rhs(x) + N_AUX\n\n"
        "def middle(x):\n    return inner(x) * 2\n\n"
        "def outer(x):\n    return middle(x) + sample_update(x)\n\n"
        "def alone(x):\n    return x + 1\n")
    text, added = shared.model_arguments(source)
    assert added == {"inner": ("rhs", "N_AUX"), "middle": ("rhs", "N_AUX"),
                     "outer": ("rhs", "sample_update", "N_AUX")}
    namespace: dict = {}
    exec(compile(text, "<rewritten>", "exec"), namespace)  # noqa: S102 - the test's text
    # no global rhs, sample_update or N_AUX: each comes in as an argument
    assert namespace["outer"](lambda x: 10 * x, lambda x: 1000, 3, 2) == (20 + 3) * 2 + 1000
    assert namespace["alone"](1) == 2


def test_the_shared_module_text_is_kept_and_a_damaged_one_rewritten(tmp_path) -> None:
    built = shared.module_source(tmp_path / "missing.py")
    assert built.startswith(shared._HEADER) and "\nMODEL_ARGUMENTS = " in built
    kept = tmp_path / "drivers.py"
    kept.write_text(built)
    assert shared.module_source(kept) == built
    marked = built.replace("import math", "import math  # kept as it is", 1)
    kept.write_text(marked)
    assert shared.module_source(kept) == marked  # a file there is used, not rebuilt
    for damaged in ("def broken(:\n", "VALUE = 1\n", built[:len(built) // 2],
                    built[len(built) // 2:]):
        kept.write_text(damaged)
        assert shared.module_source(kept) == built


@needs_numba
def test_two_model_structures_share_one_compiled_driver() -> None:
    """Two generated modules (another structure: the motor torque ripple adds a part) run
    through the same driver, compiled for one signature; their results are their own."""
    plain = feeddrive.DriveSystem(feeddrive.preset("wang2021"), "cdfs", 0.4)
    ripple = feeddrive.DriveSystem(feeddrive.preset("wang2021-ripple"), "cdfs", 0.4)
    profile = ConstantSpeed(2e-3)
    assert plain.model(profile).module is not ripple.model(profile).module
    a = feeddrive.simulate(plain, profile, 0.3)
    b = feeddrive.simulate(ripple, profile, 0.3)
    driver = shared._module()[0].integrate_dense
    assert len(driver.signatures) == 1
    xa = np.asarray(a.dataset["table_speed"].values)
    xb = np.asarray(b.dataset["table_speed"].values)
    assert xa.shape == xb.shape and not np.array_equal(xa, xb)


def test_a_model_module_offers_the_other_solver_functions_bound_to_it() -> None:
    model = feeddrive.DriveSystem(feeddrive.preset("wang2021"), "cdfs", 0.4).model(
        ConstantSpeed(1e-3))
    n = len(model.states)
    J = np.diag(np.arange(1.0, n + 1.0))
    rho = model.module._r4_spectral_radius(J, np.ones(n), np.empty(n), np.empty(n), 60)
    assert rho == pytest.approx(float(n), rel=1e-2)  # the largest eigenvalue, by power iteration
    with pytest.raises(AttributeError, match="no function 'no_such_step'"):
        model.module.no_such_step  # noqa: B018 - the attribute access is the test


def test_threads_that_first_use_a_model_together_compile_its_functions_once(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The explorer runs jobs in threads: two that need a model's first-class functions at
    once get the same ones, made once."""
    import threading
    import time

    model = feeddrive.DriveSystem(feeddrive.preset("wang2021"), "ddfs", 0.3).model(
        ConstantSpeed(1e-3, 16e-3))
    bound = shared.Bound(*model.module._bound._kernels, model.module._bound._sizes,
                         model.module.__file__)  # a fresh binding: nothing made yet
    made: list[str] = []
    real = shared.first_class

    def slow(fn, signature, name):  # type: ignore[no-untyped-def]
        made.append(name)
        time.sleep(0.2)  # the other thread arrives meanwhile
        return real(fn, signature, name)

    monkeypatch.setattr(shared, "first_class", slow)
    got: list[dict] = []
    threads = [threading.Thread(target=lambda: got.append(bound._model_values()))
               for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(made) == ["rhs_fc", "sample_update_fc"]
    assert got[0] is got[1]


@needs_numba
def test_the_linearisations_evaluations_are_the_kernels_own_to_the_bit() -> None:
    """``feeddrive.solvers.evaluate`` through the shared drivers (issue 21, fifth round): the
    rates and the state matrix are those of the model's own ``rhs`` kernel called from
    Python, operation for operation — and after its first call ``compiled`` calls the entry
    point, with the same result."""
    from feeddrive.analysis import linear

    system = feeddrive.DriveSystem(feeddrive.preset("wang2021"), "ddfs", 0.4)
    model, y = linear.steady_state(system, 1.5e-3, 16e-3)
    f = linear._Evaluator(model)
    held, P, T = f.held, f.P, model.T
    n, n_aux = y.size, len(model.aux)

    def kernel(state: np.ndarray) -> np.ndarray:
        dy, aux = np.empty(n), np.empty(n_aux)
        model.module.rhs(linear._T0, state, held, P, T, dy, aux)
        return dy

    assert np.array_equal(f(y)[0], kernel(y))
    live = linear._live_states(model, system)
    scale = linear._scales(model)
    expected = np.empty((len(live), len(live)))
    for j, k in enumerate(live):
        h = 1e-2 * scale[k]
        yp, ym = y.copy(), y.copy()
        yp[k] += h
        ym[k] -= h
        expected[:, j] = (kernel(yp)[live] - kernel(ym)[live]) / (2 * h)
    assert np.array_equal(f.columns(y, live, scale), expected)
    assert np.array_equal(linear.state_matrix(system, 1.5e-3, 16e-3), expected)
    assert "_ev_central_columns" in model.module._bound._entries  # the entry point, used
    assert np.array_equal(f.columns(y, live, scale), expected)


@needs_numba
def test_prepared_models_compile_a_models_functions_and_stop_at_its_first_driver_call() -> None:
    """Inside ``prepared_models`` a run stops at its first driver call with the model's
    first-class functions made (a cold ``reproduce``'s idle worker compiles the study's models
    so, ``runner.prepare_models``); outside it the same run runs."""
    from feeddrive.engine.simulate import Simulation

    system = feeddrive.DriveSystem(feeddrive.preset("wang2021"), "cdfs", 0.3)
    sim = Simulation(system, ConstantSpeed(1.5e-3), None)
    bound = sim.model.module._bound
    with shared.prepared_models():
        sim.run(0.05)
        pytest.fail("the run went past its first driver call")  # pragma: no cover
    assert bound._values is not None and {"rhs", "sample_update"} <= set(bound._values)
    result = Simulation(system, ConstantSpeed(1.5e-3), None).run(0.05)
    assert result.time[-1] == pytest.approx(0.05)
    assert not shared._DRY_RUN.on  # left: off again
    # a function already called through its entry point (Bound.compiled) stops there too
    from feeddrive.analysis import linear

    linear.state_matrix(system, 1.5e-3)
    assert sim.model.module._bound._entries
    with shared.prepared_models():
        linear.state_matrix(system, 1.5e-3)
        pytest.fail("the linearisation went past its first driver call")  # pragma: no cover


def test_prepare_models_goes_through_tasks_until_the_drivers_are_on_disk(monkeypatch) -> None:
    from feeddrive.reproduce import runner

    seen: list[int] = []

    def task(k: int) -> None:
        seen.append(k)
        if k == 2:
            raise ValueError("a task's own error: left to its real run")
        system = feeddrive.DriveSystem(feeddrive.preset("wang2021"), "ddfs", 0.4)
        feeddrive.simulate(system, ConstantSpeed(1e-3, 16e-3), 0.05)
        seen.append(-k)  # not reached: stopped at the first driver call

    on_disk = iter([False, False, False, True])
    monkeypatch.setattr(shared, "drivers_on_disk", lambda: next(on_disk))
    assert runner.prepare_models([(task, (1,)), (task, (2,)), (task, (3,)), (task, (4,))]) == 3
    assert seen == [1, 2, 3]
