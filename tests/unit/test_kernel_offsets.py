"""The generated code passes its offsets to the package kernels typed int64 (issue 21, sixth
round; `feeddrive.model.codegen.index`): numba typed a bare constant as ``Literal[int]`` and
compiled a kernel once per offset value, so every new model structure recompiled the friction
kernels (13–16 copies of each LuGre kernel after one `reproduce`)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from feeddrive._jit import HAVE_NUMBA
from feeddrive.model.codegen import index

needs_numba = pytest.mark.skipif(
    not HAVE_NUMBA, reason="numba is not installed (the optional extra feeddrive[numba]); "
    ".ci/min-versions installs it and runs this test of the numba build")

# two structures whose friction sites sit at different offsets of P (the ripple adds slots
# before them), each simulated briefly; then the LuGre kernels' compiled signatures
_RUN = """
import numpy as np
import feeddrive as fd
from feeddrive._jit import start_numba
start_numba()  # the numba build (a process running C never imports numba)
from feeddrive.engine.simulate import DriveSystem
from feeddrive.model.friction import lugre
from feeddrive.model.reference import ConstantSpeed
offsets = set()
for preset in ("wang2021", "wang2021-ripple"):
    model = DriveSystem(fd.preset(preset), "cdfs", 0.4).model(ConstantSpeed(1e-3))
    offsets.add(model.parameter_names.index("friction.guide.positive.coulomb_force"))
    n = len(model.states)
    model.module.rhs(0.0, np.zeros(n), np.zeros(model.n_held), model.P, model.T, np.zeros(n),
                     np.zeros(len(model.aux)))  # compiles the rhs and the kernels it calls
print(len(offsets))
for kernel in (lugre.lugre_kernel, lugre.force, lugre.bristle_rate):
    print(kernel.__name__, len(kernel.signatures), "Literal" in str(kernel.signatures))
"""


def test_an_offset_is_typed_int64_in_the_generated_source() -> None:
    assert index(71) == "int(71)"


@needs_numba
def test_the_friction_kernels_compile_once_for_every_offset(tmp_path) -> None:
    # an empty compile cache: the kernels are compiled, not loaded, so their signatures show
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    out = subprocess.run([sys.executable, "-c", _RUN], capture_output=True, text=True,
                         check=True, env=env).stdout.splitlines()
    assert out[0] == "2"  # the two structures' guide sites do sit at different offsets
    for line in out[1:]:
        name, count, literal = line.split()
        assert (count, literal) == ("1", "False"), line  # one int64 signature for both


def test_a_kernel_source_is_read_once(monkeypatch) -> None:
    """`codegen.source_of` caches what `inspect.getsource` reads (it re-reads the file each
    time; an uncached assembly of a new parameter set took ≈ 3.5 ms instead of ≈ 1.7)."""
    import inspect

    from feeddrive.model import codegen
    from feeddrive.model.friction import lugre

    reads = []
    real = inspect.getsource
    monkeypatch.setattr(inspect, "getsource", lambda fn: reads.append(fn) or real(fn))
    codegen.source_of.cache_clear()
    first = codegen.source_of(lugre.force)
    assert codegen.source_of(lugre.force) == first
    assert len(reads) == 1
