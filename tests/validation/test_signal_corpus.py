"""The regression corpus of issue 40: the tree reproduces the one before the named-signal work.

``tests/data/signal_corpus_d4dd4b5.npz`` was recorded at commit d4dd4b5 by
``reference/record_signal_corpus.py``, whose cases are generated from the registry (every
topology × friction law, × loop configuration, every preset, every optional part).  Each case
is rebuilt here and compared bit for bit: its structure (names, Jacobian pattern, clocks,
declared flows), its packed parameters, its right-hand side at a random state and a short
``dopri5`` run at the legacy fixed tolerances, stepping across the friction reversals
(``locate_reversals=False``: the corpus predates their location by ``dopri5``).

Operation orders that had to move, with the bound they are held to instead: none so far.

The declared flows are compared by what each rate and signal is computed from in states,
rates, signals and time — through the named values the code computes on the way (``f_d``,
``k_eq`` …), not by those values' names.  Since issue 40 item 1 the flows are derived from the
code's text instead of declared beside it, and two intermediate nodes are named as the code
names them: the record's ``reference`` (a name no code carried) is the four values the reference
line writes, ``ref_x``, ``ref_v``, ``ref_xn``, ``ref_vn``; and the backlash's ``gap_e`` reads what
its expression reads (the record declared the whole stretch, a superset that reached the same
states).  The Jacobian pattern, compared bit for bit, is what those flows produce.

Structure that had to change, listed: issue 40 item 2 — a drive that follows no nut reference
(its topology's ``followed_references``: the CDFS) no longer reads one.  Its held nut is
commanded 0 by its own code, so what its nut signals and its nut axis' loop compute no longer
depends on the time: ``t`` leaves the ``nut_*`` signals' and rates' flows and the time column
of the ``nut_*`` rows of the Jacobian pattern (the record's nut reference of such a drive was
the constant 0, so no number moves: every other field is compared as recorded).
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


def computed_from(flows: dict[str, list[str]]) -> dict[str, set[str]]:
    """Each rate's and signal's flows expanded through the named values to states
    (``y:``), rates (``dy:``), signals (``aux:``) and time."""
    def base(name: str, seen: frozenset[str]) -> set[str]:
        if name == "t" or name.startswith(("y:", "dy:", "aux:")):
            return {name}
        assert name not in seen, f"a cycle through {name}"
        return {b for r in flows[name] for b in base(r, seen | {name})}

    return {w: {b for r in reads for b in base(r, frozenset())}
            for w, reads in flows.items() if w.startswith(("dy:", "aux:"))}


def follows_no_nut_reference(case: str) -> bool:
    """Whether the case's drive has a nut (a ``nut_`` state) but follows no nut reference."""
    system = fd.DriveSystem(CASES[case].parameters, CASES[case].drive, 0.4)
    return (not system.topology().follows("nut")
            and any(s.startswith("nut_") for s in STRUCTURE[case]["states"]))


def without_nut_reference(flows: dict[str, set[str]], pattern: np.ndarray,
                          states: list[str]) -> tuple[dict[str, set[str]], np.ndarray]:
    """The record's structure of a drive that follows no nut reference as item 2 makes it
    (module docstring): no time in its nut signals' and rates' flows and pattern rows."""
    nut = ("aux:nut_", "dy:nut_")
    flows = {w: r - {"t"} if w.startswith(nut) else r for w, r in flows.items()}
    pattern = pattern.copy()
    for i, name in enumerate(states):
        if name.startswith("nut_"):
            pattern[i, len(states)] = 0
    return flows, pattern


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
    structure = got.pop("structure")
    flows = computed_from(expected["flows"])
    n = len(expected["states"])
    pattern = np.unpackbits(recorded(f"{name}|pattern"))[:n * (n + 1)].reshape(n, n + 1)
    if follows_no_nut_reference(name):
        flows, pattern = without_nut_reference(flows, pattern, expected["states"])
    assert computed_from(structure.pop("flows")) == flows
    assert structure == {k: v for k, v in expected.items() if k != "flows"}
    np.testing.assert_array_equal(
        np.unpackbits(got.pop("pattern"))[:n * (n + 1)].reshape(n, n + 1), pattern)
    for key, value in got.items():
        np.testing.assert_array_equal(np.asarray(value), recorded(f"{name}|{key}"),
                                      err_msg=f"{name}: {key}")
