"""The result store (feeddrive.io.json_store) cannot lie: issue 13, item 9.

Guards the bugs found in the reproduce cache: a hand-edited entry (1.56 → 9.99) went into the
report; the key omitted the package version and kernel hash; a truncated entry made every
rerun fail ("Unterminated string…", no file named); entries shared one temporary name, so
concurrent writers raced (24 FileNotFoundError, 33 half-written reads).

The concurrency and kill tests use a fast fake computation in subprocesses (the real
``reproduce`` kill test is in tests/integration/test_reproduce_kill.py, marked slow).
"""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

import feeddrive.io.json_store
from feeddrive import __version__
from feeddrive._jit import KERNEL_HASH
from feeddrive.io.json_store import ResultStore, store_key
from feeddrive.parameters import preset
from feeddrive.reproduce.runner import study_store
from feeddrive.reproduce.studies import StudySettings

KEY = store_key({"version": "test", "inputs": [1, 2, 3]})


def value(i: int) -> dict[str, object]:
    """A payload large enough that a write is not one system call's worth of bytes."""
    return {"name": f"entry-{i}", "critical_speed_mm_s": 1.56, "trace": list(range(20000))}


def test_round_trip_and_atomic_layout(tmp_path: Path) -> None:
    store = ResultStore(tmp_path, KEY)
    assert store.get("a") is None
    assert store.put("a", {"x": (1.5, 2)}) == {"x": [1.5, 2]}  # as a rerun will read it
    assert store.get("a") == {"x": [1.5, 2]}
    assert [p.name for p in tmp_path.iterdir()] == [store.path("a").name]  # no temp left
    head = store.path("a").read_bytes().partition(b"\n")[0]
    assert json.loads(head)["key"] == KEY


@pytest.mark.parametrize("damage", ["edit", "truncate", "header", "empty", "other-key"])
def test_damaged_entry_is_noticed_and_recomputed(tmp_path: Path, damage: str) -> None:
    notices: list[str] = []
    store = ResultStore(tmp_path, KEY, notice=notices.append)
    store.put("crit", {"critical_speed_mm_s": 1.56})
    p = store.path("crit")
    raw = p.read_bytes()
    if damage == "edit":  # the 1.56 → 9.99 hand edit of the issue
        p.write_bytes(raw.replace(b"1.56", b"9.99"))
    elif damage == "truncate":
        p.write_bytes(raw[: len(raw) - 5])
    elif damage == "header":
        p.write_bytes(b"{not json\n" + raw.partition(b"\n")[2])
    elif damage == "empty":
        p.write_bytes(b"")
    else:
        other = ResultStore(tmp_path, store_key({"version": "other"}))
        other.put("crit", {"critical_speed_mm_s": 9.99})
        os.replace(other.path("crit"), p)
    assert store.get("crit") is None
    assert len(notices) == 1 and "\n" not in notices[0]
    assert str(p) in notices[0] and "recomputing" in notices[0]
    assert store.get_or_compute("crit", lambda: {"critical_speed_mm_s": 1.56}) == \
        {"critical_speed_mm_s": 1.56}
    notices.clear()
    assert store.get("crit") == {"critical_speed_mm_s": 1.56}
    assert notices == []


def test_reproduce_key_has_version_kernel_code_and_inputs(tmp_path: Path) -> None:
    params = preset("wang2021")
    a = study_store(tmp_path, params, StudySettings())
    assert a.key == study_store(tmp_path, params, StudySettings()).key
    assert a.key != study_store(tmp_path, preset("wang2021-literal"), StudySettings()).key
    assert a.key != study_store(tmp_path, params, StudySettings(trial_initial_duration=6.0)).key
    assert a.key != store_key({"version": __version__, "kernel": KERNEL_HASH})
    assert len(KERNEL_HASH) == 16


# the store module alone (it imports only feeddrive.io.outputs, which imports nothing of
# feeddrive; the package's __init__ is not run): a worker starts in ~50 ms
_WORKER = textwrap.dedent("""
    import importlib
    import os
    import sys
    import types
    package = types.ModuleType("feeddrive")
    package.__path__ = [os.path.dirname(os.path.dirname(sys.argv[5]))]
    sys.modules["feeddrive"] = package
    store_module = importlib.import_module("feeddrive.io.json_store")
    root, key, worker, rounds = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    store = store_module.ResultStore(root, key)
    print("ready", flush=True)
    bad = 0
    for r in range(rounds):
        for i in range(6):
            want = {"name": f"entry-{i}", "critical_speed_mm_s": 1.56,
                    "trace": list(range(20000))}
            got = store.get(f"e{i}")
            if got is not None and got != want:
                bad += 1
            store.put(f"e{i}", want)
    print(bad)
""")


def _spawn(tmp_path: Path, *args: str) -> subprocess.Popen[str]:
    script = tmp_path / "worker.py"
    if not script.exists():
        script.write_text(_WORKER, encoding="utf-8")
    return subprocess.Popen([sys.executable, str(script), *args, feeddrive.io.json_store.__file__],
                            stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def test_concurrent_writers_never_race_or_read_half_an_entry(tmp_path: Path) -> None:
    root = tmp_path / "data"
    procs = [_spawn(tmp_path, str(root), KEY, str(w), "20") for w in range(4)]
    for p in procs:
        out, err = p.communicate(timeout=120)
        assert p.returncode == 0, err  # no FileNotFoundError from a shared temp name
        assert out.split() == ["ready", "0"]  # no half-written or wrong entry read
    store = ResultStore(root, KEY)
    notices: list[str] = []
    store.notice = notices.append
    for i in range(6):
        assert store.get(f"e{i}") == value(i)
    assert notices == []
    assert not list(root.glob(".*.tmp")) and not list(root.glob(".*.partial.*"))


def test_sigkill_at_random_points_never_leaves_a_corrupt_entry(tmp_path: Path) -> None:
    root = tmp_path / "data"
    rng = random.Random(13)
    for _ in range(10):
        p = _spawn(tmp_path, str(root), KEY, "0", "1000")
        assert p.stdout is not None and p.stdout.readline().strip() == "ready"
        time.sleep(rng.uniform(0.01, 0.4))  # kill mid-way through the writes
        p.send_signal(signal.SIGKILL)
        p.communicate()
        notices: list[str] = []
        store = ResultStore(root, KEY, notice=notices.append)
        for i in range(6):
            got = store.get(f"e{i}")
            assert got is None or got == value(i)
        assert notices == [], notices  # an entry is whole or absent, never damaged
