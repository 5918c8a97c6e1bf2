"""Fixtures of the unit tests shared by more than one file."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from feeddrive.backends import c_cache


@pytest.fixture
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty C cache folder of the test's own (``$FEEDDRIVE_C_CACHE``), the cache's counts
    set to zero (tests/unit/test_c_cache.py, test_c_cache_damage.py)."""
    folder = tmp_path / "cache"
    monkeypatch.setenv(c_cache.CACHE_ENV, str(folder))
    monkeypatch.setattr(c_cache, "STATS", {"compiles": 0, "hits": 0})
    return folder


#: one short run of the C build (wang2021 CDFS at mid-screw): what fills a C cache with the
#: drivers' texts and library, the model's text and library and their digests
FILL_RUN = """
import feeddrive as fd
from feeddrive.model.reference import ConstantSpeed
fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4), ConstantSpeed(2e-3), 0.01)
"""


@pytest.fixture(scope="session")
def filled_c_cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A C cache one fresh process filled from empty (:data:`FILL_RUN`): compiled once per
    session (the drivers' compile is ≈ 4 CPU s) for the tests that damage a *copy* of a
    whole cache (test_s20_c_texts.py, test_c_cache_damage.py).  Never changed: copy it."""
    from feeddrive.solvers import builds

    try:
        c_cache.find_compiler()
    except c_cache.CompilerNotFound:
        pytest.skip("no C compiler")
    root = tmp_path_factory.mktemp("filled-c-cache")
    (root / "tmp").mkdir()
    env = dict(os.environ, **{c_cache.CACHE_ENV: str(root / "c")}, TMPDIR=str(root / "tmp"),
               FEEDDRIVE_ENGINE="c")
    env.pop(builds.SAID_ENV, None)
    done = subprocess.run([sys.executable, "-c", FILL_RUN], env=env, capture_output=True,
                          text=True, timeout=600, check=False)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    return root / "c"
