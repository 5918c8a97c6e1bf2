"""One engine, two builds (issue 42 item 2): the C build of the drivers
(:mod:`feeddrive.backends.c_engine`) against the numba build on the regression corpus.

The corpus is generated from the registry (``reference/record_signal_corpus.py``: every
topology × friction law, loop configuration, preset and optional part).  Each case runs once
per build with one of the methods, the methods taken in turn so that each meets every
topology; every continuous signal must agree to 1e-12 of its largest magnitude, and the
summary (verdict, stick fraction, ripple …) and the solver's counts must be identical.
The reference is the numba build, which the existing regression tests pin
(tests/validation/test_signal_corpus.py, test_engine_v1_regression.py).
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.record_signal_corpus import NUT_SPEED, TABLE_SPEED, cases  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive._jit import HAVE_NUMBA  # noqa: E402
from feeddrive.engine.options import METHODS  # noqa: E402
from feeddrive.model.reference import ConstantSpeed  # noqa: E402

HAVE_CC = any(shutil.which(c) for c in ("cc", "gcc", "clang"))
pytestmark = [
    pytest.mark.skipif(not HAVE_CC, reason="no C compiler (cc, gcc, clang) on PATH: "
                                           "the C build cannot be built here"),
    pytest.mark.skipif(not HAVE_NUMBA, reason="numba is not installed (the optional extra "
                       "feeddrive[numba]): .ci/min-versions installs it and runs this file"),
]
CASES = cases()
DURATION = 0.3  # [s]: the start transient and the first stick-slip cycles of the slow cases


def run(case_index: int, engine: str, monkeypatch: pytest.MonkeyPatch) -> fd.Result:
    case = CASES[case_index]
    monkeypatch.setenv("FEEDDRIVE_ENGINE", engine)
    system = fd.DriveSystem(case.parameters, case.drive, 0.4)
    nut = NUT_SPEED if system.topology().follows("nut") else 0.0
    method = METHODS[case_index % len(METHODS)]
    step = {"fixed_step": 2e-5} if method.endswith("-fixed") else {}
    return fd.simulate(system, ConstantSpeed(TABLE_SPEED, nut), DURATION,
                       options=fd.SolverOptions(method=method, **step))


def compare(a: fd.Result, b: fd.Result) -> float:
    """The largest difference of a signal of ``b`` from ``a``'s, relative to the largest
    magnitude of ``a``'s signal; asserts the times and the summaries equal."""
    np.testing.assert_array_equal(a.time, b.time)
    worst = 0.0
    for name in a.signal_names():
        x, y = np.asarray(a[name], dtype=float), np.asarray(b[name], dtype=float)
        scale = float(np.max(np.abs(x))) if x.size else 0.0
        d = float(np.max(np.abs(x - y))) if x.size else 0.0
        worst = max(worst, d / scale if scale > 0 else d)
    return worst


@pytest.mark.slow
@pytest.mark.parametrize("index", range(len(CASES)), ids=[c.name for c in CASES])
def test_the_c_build_agrees_with_numba_on_the_corpus(index: int,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    try:
        expected = run(index, "numba", monkeypatch)
    except (fd.ParameterError, ValueError) as err:  # a case the corpus records as refused
        with pytest.raises(type(err)):
            run(index, "c", monkeypatch)
        return
    got = run(index, "c", monkeypatch)
    assert compare(expected, got) <= 1e-12
    summary, stats = got.summary(), dict(got.solver_stats)
    expected_summary, expected_stats = expected.summary(), dict(expected.solver_stats)
    for s in (summary, expected_summary):
        s.pop("solver", None)  # the solver's statistics, compared below without timing
    assert summary == expected_summary  # verdict, stick fraction, speeds, ripple …
    for s in (stats, expected_stats):
        s.pop("wall_time_s")
        assert s.pop("engine") in ("c", "numba")
    assert stats == expected_stats  # steps, rejections, evaluations, switches …
