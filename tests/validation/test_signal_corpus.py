"""The regression corpus of issue 40: the tree reproduces the one before the named-signal work.

``tests/data/signal_corpus_d4dd4b5.npz`` was recorded at commit d4dd4b5 by
``reference/record_signal_corpus.py``, whose cases are generated from the registry (every
topology × friction law, × loop configuration, every preset, every optional part).  Each case
is rebuilt here and compared bit for bit: its structure (names, Jacobian pattern, clocks,
declared flows), its packed parameters, its right-hand side at a random state and a short
``dopri5`` run at the legacy fixed tolerances, stepping across the friction reversals
(``locate_reversals=False``: the corpus predates their location by ``dopri5``).

Operation orders that had to move, with the bound they are held to instead: none so far.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.record_signal_corpus import cases, record  # noqa: E402

import feeddrive as fd  # noqa: E402

# the record at d4dd4b5 and the supplements holding only the cases a later option or part
# added, each recorded at the commit that added it: issue 37 item 3 (controller.position_feedback
# = "motor", the [backlash] part), recorded at its commit on branch issue-37-backlash
RECORDS = [np.load(ROOT / "tests" / "data" / name)
           for name in ("signal_corpus_d4dd4b5.npz", "signal_corpus_issue37_backlash.npz")]
STRUCTURE = {k: v for data in RECORDS for k, v in json.loads(str(data["structure"])).items()}


def recorded(key: str) -> np.ndarray:
    """One recorded array, from whichever record holds it."""
    return next(data[key] for data in RECORDS if key in data.files)
CASES = {case.name: case for case in cases()}


def test_the_corpus_is_generated_from_the_registry_and_matches_the_record() -> None:
    from feeddrive import registry

    assert sorted(CASES) == sorted(STRUCTURE)
    for drive in registry.names(registry.MECHANISMS):
        for law in registry.names(registry.FRICTION_LAWS):
            assert f"{drive}/law={law}" in CASES
        assert f"{drive}/sampled" in CASES


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(STRUCTURE))
def test_each_case_is_bit_identical_to_d4dd4b5(name: str) -> None:
    expected = STRUCTURE[name]
    if "error" in expected:
        with pytest.raises((fd.ParameterError, ValueError)) as info:
            record(CASES[name])
        assert str(info.value) == expected["error"]
        return
    got = record(CASES[name])
    assert got.pop("structure") == expected
    for key, value in got.items():
        np.testing.assert_array_equal(np.asarray(value), recorded(f"{name}|{key}"),
                                      err_msg=f"{name}: {key}")
