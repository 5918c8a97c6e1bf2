"""Guards the stale-numba-cache bug: numba re-compiles a cached function only when its own
file changes, so a change to a kernel it calls in another module ran old code (found when a
new hollow-motor option in control.py had no effect through the cached solver).  With the
composable core the generated model modules are named after a hash of their text and of every
kernel source, so the same guard covers them."""

from __future__ import annotations

from pathlib import Path

import pytest

import feeddrive
from feeddrive import _jit
from feeddrive._jit import HAVE_NUMBA
from feeddrive.model import codegen
from feeddrive.model.reference import ConstantSpeed

needs_numba = pytest.mark.skipif(
    not HAVE_NUMBA, reason="numba is not installed (the optional extra feeddrive[numba]); "
    ".ci/min-versions installs it and runs this test of the numba build")


PKG = Path(feeddrive.__file__).resolve().parent


def test_every_kernel_module_is_in_the_cache_hash() -> None:
    defining = {p.resolve() for p in PKG.rglob("*.py")
                if "@kernel" in p.read_text() or "@inline_kernel" in p.read_text()}
    assert defining <= {p.resolve() for p in _jit._kernel_files()}


def test_cache_folder_follows_the_sources(monkeypatch, tmp_path) -> None:
    fake = tmp_path / "pkg"
    for path in _jit._kernel_files():
        rel = path.relative_to(PKG)
        (fake / rel).parent.mkdir(parents=True, exist_ok=True)
        (fake / rel).write_text(path.read_text())
    monkeypatch.setattr(_jit, "_HERE", fake)
    before = _jit._source_digest()
    lugre = fake / "model" / "friction" / "lugre.py"
    lugre.write_text(lugre.read_text() + "\n# changed\n")
    assert _jit._source_digest() != before


def test_one_generated_module_serves_a_topology_and_parameter_changes() -> None:
    """Numbers live in the parameter vector: the table position, gains and profile length do
    not create new compiled modules (each costs seconds to compile).  The topology does since
    the reference became the named signals a topology follows (issue 40 item 2): the DDFS reads
    the nut's reference, the CDFS's code never sees it."""
    w = feeddrive.preset("wang2021")
    a = feeddrive.DriveSystem(w, "cdfs", 0.3).model(ConstantSpeed(1e-3))
    b = feeddrive.DriveSystem(w.replace_path("controller.position_gain", 3.0), "cdfs",
                              0.5).model(ConstantSpeed(2e-3))
    assert a.module is b.module
    d1 = feeddrive.DriveSystem(w, "ddfs", 0.3).model(ConstantSpeed(1e-3, 16e-3))
    d2 = feeddrive.DriveSystem(w.replace_path("controller.position_gain", 3.0), "ddfs",
                               0.5).model(ConstantSpeed(1e-3, 8e-3))
    assert d1.module is d2.module
    assert d1.module is not a.module
    c = feeddrive.DriveSystem(w.replace_path("friction.guide.law", "stribeck"), "cdfs",
                              0.4).model(ConstantSpeed(1e-3))
    assert c.module is not a.module


def test_generated_module_file_is_named_after_its_text(tmp_path) -> None:
    source = '"""test module"""\nVALUE = 3\n'
    first = codegen.compile_module(source, [])
    assert first.VALUE == 3
    again = codegen.compile_module(source, [])
    assert again is first
    other = codegen.compile_module(source + "OTHER = 1\n", [])
    assert other is not first and Path(other.__file__).name != Path(first.__file__).name


@needs_numba
def test_a_second_process_loads_the_assembled_model_from_disk(tmp_path) -> None:
    """The claim of docs/extending.md: per assembled model, numba's disk cache is hit in a new
    process (no recompilation)."""
    import os
    import subprocess
    import sys

    code = ("import feeddrive as fd\n"
            "from feeddrive.model.reference import ConstantSpeed\n"
            "s = fd.DriveSystem(fd.preset('linear-motor-example'), 'linear-motor')\n"
            "fd.simulate(s, ConstantSpeed(1e-3), 0.01)\n"
            "from feeddrive.solvers import shared\n"
            "st = shared._module()[0].integrate_dense.stats\n"
            "rhs = s.model(ConstantSpeed(1e-3)).module._bound._model_values()['rhs']\n"
            "print(sum(st.cache_hits.values()), sum(st.cache_misses.values()),"
            " rhs._cache_hits)\n")
    # the numba build's cache (feeddrive.solvers.builds chooses C where a compiler is found)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path), FEEDDRIVE_ENGINE="numba")
    runs = [subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                           text=True, check=True, timeout=300).stdout.split()
            for _ in range(2)]
    # the shared driver and the model's first-class right-hand side: the first process
    # compiles and stores them, the second loads both from disk
    assert runs[0] == ["0", "1", "0"]
    assert runs[1] == ["1", "0", "1"]
    assert list(tmp_path.rglob("model_*.py"))

