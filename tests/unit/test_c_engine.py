"""The C build of the engine (issue 42 items 1–2, :mod:`feeddrive.backends.c_engine`): the
choice of build (``FEEDDRIVE_ENGINE``), the driver's text lowered only at the Python/C
boundary, the unit compiled with the strict warning set, and every method of the driver
giving numba's results — split into chunks with the memory carried over, and stopped by the
memory's stop slot with the same status.  The whole regression corpus through both builds:
tests/validation/test_engine_builds.py."""

from __future__ import annotations

import ast
import inspect
import re
import shutil
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.backends import c_cache, c_engine
from feeddrive.backends.c_backend import STRICT_FLAGS
from feeddrive.model.mechanisms.base import drive_names, mechanism
from feeddrive.model.reference import ConstantSpeed
from feeddrive.solvers import builds, dopri5, driver, driver_text, switching

HAVE_CC = any(shutil.which(c) for c in ("cc", "gcc", "clang"))
needs_cc = pytest.mark.skipif(not HAVE_CC, reason="no C compiler (cc, gcc, clang) on PATH")
needs_numba = pytest.mark.skipif(
    not builds.HAVE_NUMBA, reason="numba is not installed (the optional extra "
    "feeddrive[numba]); .ci/min-versions installs it and runs this numba-versus-C comparison")


def test_the_build_is_chosen_by_feeddrive_engine(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("FEEDDRIVE_ENGINE", "numba")
    if builds.HAVE_NUMBA:
        assert builds.engine_name() == "numba"
    else:  # asked for a build that is not installed: one line saying how to get it
        with pytest.raises(builds.NoEngine) as absent:
            builds.engine_name()
        assert "\n" not in str(absent.value)
        assert "pip install 'feeddrive[numba]'" in str(absent.value)
    monkeypatch.setenv("FEEDDRIVE_ENGINE", " Fortran ")
    with pytest.raises(ValueError) as info:
        builds.engine_name()
    message = str(info.value)
    assert "\n" not in message
    assert "FEEDDRIVE_ENGINE = ' Fortran '" in message and "auto, c, numba" in message


def _no_compiler(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))  # an empty folder: no cc, gcc, clang
    monkeypatch.setattr(c_cache, "_SAID", [])


@needs_numba
def test_without_a_compiler_numba_runs_said_once_in_one_line(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
        ) -> None:
    _no_compiler(monkeypatch, tmp_path)
    monkeypatch.delenv("FEEDDRIVE_ENGINE", raising=False)
    assert builds.engine_name() == "numba"
    assert builds.engine_name() == "numba"
    err = capsys.readouterr().err
    assert err == c_cache.NO_COMPILER + "\n"  # once, one line, how to get either


def test_forcing_c_without_a_compiler_is_a_one_line_error(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    _no_compiler(monkeypatch, tmp_path)
    monkeypatch.setenv("FEEDDRIVE_ENGINE", "c")
    expected = c_cache.CompilerNotFound if builds.HAVE_NUMBA else builds.NoEngine
    with pytest.raises(expected) as info:
        builds.engine_name()
    assert "\n" not in str(info.value) and "FEEDDRIVE_ENGINE = 'c'" in str(info.value)


@pytest.mark.parametrize("engine", ["auto", "c"])
def test_without_a_compiler_and_without_numba_one_line_says_how_to_get_either(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path, engine: str) -> None:
    """Neither build can run (issue 42's acceptance): one line naming both ways out, not a
    fallback to the drivers in plain Python."""
    _no_compiler(monkeypatch, tmp_path)
    monkeypatch.setattr(builds, "HAVE_NUMBA", False)
    monkeypatch.setenv("FEEDDRIVE_ENGINE", engine)
    with pytest.raises(builds.NoEngine) as info:
        builds.engine_name()
    message = str(info.value)
    assert "\n" not in message
    assert "C compiler" in message and "apt-get install gcc" in message
    assert "pip install 'feeddrive[numba]'" in message


@pytest.mark.parametrize("use", c_engine.USES)
def test_the_driver_is_lowered_at_the_boundary_only(use: str) -> None:
    """The outputs become the caller's buffers, the statistics a caller's array, the result
    the count; every other statement of the driver's text is kept.  The dense driver, which
    takes its work arrays (driver.work_space), is called by an entry that makes them."""
    text, n_stats = c_engine.lowered_source(use)
    functions = {f.name: f for f in ast.parse(text).body if isinstance(f, ast.FunctionDef)}
    entry = functions[use]
    fn = functions.get(f"{use}_loop", entry)
    names = {n.id for n in ast.walk(fn) if isinstance(n, ast.Name)}
    assert not names & set(c_engine.OUTPUTS) and "stats" not in names
    assert [a.arg for a in fn.args.args][-1] == c_engine.STATS_OUT
    assert [a.arg for a in entry.args.args][-1] == c_engine.STATS_OUT
    if fn is not entry:  # the entry takes the rest, makes these
        made = {e.id for maker in (driver.step_space, driver.work_space) for e in ast.parse(
            inspect.getsource(maker)).body[0].body[-1].value.elts}
        assert {a.arg for a in fn.args.args} - {a.arg for a in entry.args.args} <= made
    assert n_stats == (len(switching.STAT_NAMES) if use == "integrate_dense" else 5)
    original = ast.parse(driver_text.source(use, inline=False)).body[0]
    assert isinstance(original, ast.FunctionDef)
    def calls(tree: ast.AST) -> list[str]:
        returned = {id(n) for r in ast.walk(tree) if isinstance(r, ast.Return)
                    for n in ast.walk(r)}  # the result (its slices) is what changes
        return sorted(ast.unparse(n.func) for n in ast.walk(tree) if isinstance(n, ast.Call)
                      and id(n) not in returned and not ast.unparse(n.func).startswith("np."))

    # every step, Jacobian, event and eigen-analysis call is there
    assert calls(fn) == calls(original)


SYSTEM = fd.DriveSystem(fd.preset("wang2021"), "ddfs", 0.4)
PROFILE = ConstantSpeed(0.5e-3, 16e-3)


@needs_cc
@pytest.mark.parametrize("unit", ["driver", "model"])
def test_the_engine_units_compile_with_the_strict_warning_set(unit: str, tmp_path: Path
                                                               ) -> None:
    """The driver library's unit (every model's) and a model library's unit."""
    source = tmp_path / f"{unit}.c"
    source.write_text(c_engine.driver_source() if unit == "driver"
                      else c_engine.model_source(SYSTEM.model(PROFILE)))
    cc = c_cache.find_compiler()
    out = subprocess.run([*cc, *STRICT_FLAGS, "-c", str(source), "-o", str(tmp_path / "e.o")],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr


def test_the_driver_unit_does_not_depend_on_the_model() -> None:
    """One driver text for every model (issue 42's compile target): no size is a constant of
    it and no model function is called by name; the models of different sizes reach it
    through their tables."""
    text = c_engine.driver_source()
    assert "#define FD_N_STATE fd_n_state" in text
    assert text.count("const long fd_n_state = fd_m->n_state;") > 50  # in every function
    assert not re.search(r"#define FD_N_\w+ \d", text)
    assert not re.search(r"\bfd_rhs\(|\bfd_sample_update\(", text)
    for drive, nut in (("cdfs", 0.0), ("ddfs", 16e-3)):
        model = fd.DriveSystem(fd.preset("wang2021"), drive, 0.4).model(
            ConstantSpeed(0.5e-3, nut))
        unit = c_engine.model_source(model)
        assert f"#define FD_N_STATE {len(model.states)}\n" in unit
        assert "const fd_model fd_model_table = {FD_N_STATE, FD_N_AUX," in unit
        assert "fd_integrate" not in unit


def _halves(model: fd.Model, use: str, mode: int, stop: bool = False) -> list[np.ndarray]:
    """A 0.2-s run in two calls (the memory carried over), or one call stopped at once."""
    n = len(model.states)
    atol = np.full(n, 1e-9)
    rel = np.ones(n)
    sched = np.zeros(len(model.clocks), dtype=np.int64)
    y0 = np.zeros(n)
    held = np.zeros(model.n_held)
    out: list[np.ndarray] = []
    if use == "integrate":
        memory = np.zeros(4 + n + 2)
        memory[0], memory[1] = 1e-6, 1e-4
    else:
        memory = switching.new_memory(n)
    if stop:
        memory[-2] = 1.0
    y, start = y0, 0
    for t_end in ((0.2,) if stop else (0.1, 0.2)):
        if use == "integrate":
            t, yy, aa, stats, _ = dopri5.integrate(model, y, t_end, 10, 1e-3, sched, 1e-6,
                                                   atol, rel, 1e-6, 1e-3, 1, 10**6,
                                                   start=start, held=held, memory=memory)
        else:
            t, yy, aa, stats, _ = switching.integrate(model, y, t_end, 10, 1e-3, sched, 1e-6,
                                                      atol, rel, 1e-6, np.inf, 1, 10**6, mode,
                                                      np.zeros(0), start=start, held=held,
                                                      memory=memory)
        out += [t.copy(), yy.copy(), aa.copy(), stats.copy()]
        y, start = yy[-1].copy(), int(round(t_end / 1e-3))
    return [*out, held, memory]


@needs_cc
@pytest.mark.parametrize("use, mode", [("integrate", 0), ("integrate_dense", 0),
                                       ("integrate_dense", 1), ("integrate_dense", 2),
                                       ("integrate_dense", 3), ("integrate_dense", 5),
                                       ("integrate_dense", 6), ("integrate_dense", 7)],
                         ids=["dopri5", "dopri5-dense", "rodas4", "auto", "modal",
                              "rodas5p", "auto-rodas5p", "modal-rodas5p"])
@needs_numba
def test_every_method_gives_numbas_results_in_chunks_and_when_stopped(
        use: str, mode: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """Bit for bit: the same operations in the same order (gcc without contraction)."""
    model = SYSTEM.model(PROFILE)
    for stop in (False, True):
        runs = {}
        for engine in ("numba", "c"):
            monkeypatch.setenv("FEEDDRIVE_ENGINE", engine)
            runs[engine] = _halves(model, use, mode, stop)
        for a, b in zip(runs["numba"], runs["c"], strict=True):
            np.testing.assert_array_equal(a, b)
        status = runs["c"][3][0]
        assert status == (driver.STATUS_STOPPED if stop else driver.STATUS_OK)


@needs_cc
def test_the_linearisations_and_auxiliary_functions_give_numbas_results(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The shared module's other functions the C unit holds (the rates, central-difference
    columns, grouped Jacobian of the linearisations and steady states, the deferred auxiliary
    signals): bit for bit at random states with the shared module's own (numba's, or without
    numba the same text run by Python)."""
    model = SYSTEM.model(PROFILE)
    n, n_aux = len(model.states), len(model.aux)
    rng = np.random.default_rng(42)
    y = rng.normal(size=n) * np.array(model.tolerance_scales) * 1e3
    held = np.zeros(model.n_held)
    P, T = np.ascontiguousarray(model.P), np.ascontiguousarray(model.T)
    got: dict[str, list[np.ndarray]] = {}
    monkeypatch.setenv("FEEDDRIVE_ENGINE", "c")
    for engine in ("shared", "c"):
        def fn(name: str, engine: str = engine) -> Any:
            return model.module.compiled(name) if engine == "shared" else \
                builds.compiled(model, name)

        dy, aux = np.empty(n), np.empty(n_aux)
        fn("_ev_rates")(0.01, y, held, P, T, dy, aux)
        cols = np.arange(n, dtype=np.int64)
        A = np.empty((n, n))
        fn("_ev_central_columns")(
            0.01, y, held, P, T, cols, np.full(n, 1e-7), cols, A, np.empty(n), np.empty(n),
            np.empty(n), np.empty(n_aux))
        J, ft, f0 = np.empty((n, n)), np.empty(n), dy.copy()
        calls = fn("_r4_fd_jacobian")(
            0.01, y, f0, held, P, T, np.full(n, 1e-9), J, ft, np.empty(n), np.empty(n),
            np.empty(n_aux), np.ones(n, dtype=np.bool_),
            np.ascontiguousarray(model.jacobian_pattern), model.jacobian_colours)
        out = fn("auxiliary")(np.array([0.0, 0.01]), np.stack([y, 2 * y]), P, T)
        got[engine] = [dy, aux, A, J, ft, np.array([calls]), out]
    for a, b in zip(got["shared"], got["c"], strict=True):
        np.testing.assert_array_equal(a, b)
    assert got["c"][5][0] > 0 and got["c"][6].shape == (2, n_aux)


@needs_cc
def test_a_function_called_again_reads_and_writes_the_arrays_of_that_call(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The linearisations' functions keep the arrays of the last call with their addresses;
    a call with other arrays (or the same array changed in place) uses those."""
    model = SYSTEM.model(PROFILE)
    n, n_aux = len(model.states), len(model.aux)
    held, P, T = np.zeros(model.n_held), np.ascontiguousarray(model.P), model.T
    monkeypatch.setenv("FEEDDRIVE_ENGINE", "c")
    rates = builds.compiled(model, "_ev_rates")
    y, dy, aux = np.full(n, 1e-4), np.empty(n), np.empty(n_aux)
    rates(0.0, y, held, P, T, dy, aux)
    first = dy.copy()
    y[:] = 2e-4  # the same array, changed in place
    rates(0.0, y, held, P, T, dy, aux)
    other_dy = np.empty(n)
    rates(0.0, np.full(n, 1e-4), held, P, T, other_dy, aux)  # new arrays
    reference = model.module.compiled("_ev_rates")  # numba's, or Python's without numba
    expected = np.empty(n)
    reference(0.0, np.full(n, 2e-4), held, P, T, expected, np.empty(n_aux))
    np.testing.assert_array_equal(dy, expected)
    np.testing.assert_array_equal(other_dy, first)
    assert not np.array_equal(first, expected)


_THREE_MODELS = r"""
import json, sys
from pathlib import Path
import feeddrive as fd
from feeddrive.backends import c_cache
from feeddrive.model.reference import ConstantSpeed
from feeddrive.parameters.toml_io import load
runs = [(fd.preset("wang2021"), "cdfs", 0.0), (fd.preset("wang2021"), "ddfs", 16e-3),
        (load(sys.argv[1]), "cdfs", 0.0)]
sizes = []
for params, drive, nut in runs:
    system = fd.DriveSystem(params, drive, 0.4)
    for method in ("modal", "dopri5"):
        r = fd.simulate(system, ConstantSpeed(2e-3, nut), 0.05,
                        options=fd.SolverOptions(method=method))
        assert r.solver_stats["engine"] == "c"
    sizes.append(len(system.model(ConstantSpeed(2e-3, nut)).states))
folder = c_cache.cache_folder()
print(json.dumps({"compiles": c_cache.STATS["compiles"], "sizes": sizes,
                  "libraries": len(list(folder.glob("*" + c_cache.library_suffix())))}))
"""


@needs_cc
def test_the_drivers_are_compiled_once_for_models_of_every_size(tmp_path: Path) -> None:
    """Issue 42's compile target: a fresh process with an empty C cache runs three model
    structures (15, 15 and 18 states) with two methods each and compiles four libraries —
    the drivers' once, and each model's kernels."""
    import json
    import os
    import sys

    env = dict(os.environ, FEEDDRIVE_ENGINE="c", FEEDDRIVE_C_CACHE=str(tmp_path / "c"))
    root = Path(__file__).resolve().parents[2]
    done = subprocess.run([sys.executable, "-c", _THREE_MODELS,
                           str(root / "examples" / "gms_guide.toml")], env=env,
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    got = json.loads(done.stdout.strip().splitlines()[-1])
    assert got["sizes"] == [15, 15, 18]
    assert got["compiles"] == 4 and got["libraries"] == 4


@needs_cc
def test_a_models_c_text_is_translated_once_and_read_back_from_the_cache(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """``c_engine._model_text``: the first use of a model structure writes its translated C
    text to the cache folder (``model-<hash>.c``); a later call reads it back without
    translating (as a later process does), another structure has a key of its own, and a
    cache that cannot be written is left as it is, the text translated again."""
    monkeypatch.setenv(c_cache.CACHE_ENV, str(tmp_path / "c"))
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs")
    model = system.model(ConstantSpeed(1e-3))
    text = c_engine._model_text(model)
    assert text == c_engine.model_source(model)
    kept = sorted((tmp_path / "c").glob("model-*.c"))
    assert len(kept) == 1 and kept[0].read_text(encoding="utf-8") == text

    def refuse(_: Any) -> str:
        raise AssertionError("translated again")

    monkeypatch.setattr(c_engine, "model_source", refuse)
    assert c_engine._model_text(model) == text  # read back
    other = fd.DriveSystem(fd.preset("wang2021"), "ddfs").model(ConstantSpeed(1e-3, 16e-3))
    with pytest.raises(AssertionError, match="translated again"):
        c_engine._model_text(other)  # another structure, another key
    monkeypatch.undo()
    monkeypatch.setenv(c_cache.CACHE_ENV, str(tmp_path / "c"))

    def read_only(*_: Any, **__: Any) -> Any:
        raise PermissionError("read-only file system")

    from feeddrive.io import outputs

    monkeypatch.setattr(outputs, "atomic_path", read_only)  # a cache that cannot be written
    assert c_engine._model_text(other) == c_engine.model_source(other)
    assert len(list((tmp_path / "c").glob("model-*.c"))) == 1  # nothing written


@needs_cc
@pytest.mark.parametrize("drive", drive_names())
def test_every_packaged_drive_runs_in_c(drive: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every drive of the registry, on its example preset, translates whole to C: no kernel
    of the package (a solver piece, a law, a part) falls outside the C subset, where with
    numba installed the model would run in the numba build silently (said once on standard
    error) and without it not at all."""
    monkeypatch.delenv(builds.ENGINE_ENV, raising=False)
    parameters = fd.preset(mechanism(drive).example_preset)
    nut = 16e-3 if drive == "ddfs" else 0.0
    model = fd.DriveSystem(parameters, drive, 0.4).model(ConstantSpeed(0.5e-3, nut))
    assert builds.engine_of(model) == "c"
