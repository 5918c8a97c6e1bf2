"""A model too large for the thread's stack does not kill the process (an outside check,
2026-12-07: a 34-axis machine in the explorer, 510 states, died with a segmentation fault).

The C build keeps its work matrices on the stack (C99 variable-length arrays, ≈ 32 n² bytes
for n states); a call whose need (``c_engine.stack_need``) exceeds
``c_engine.STACK_OWN_THREAD`` runs on a thread given that stack.  Checked in a child process
whose stack is limited to 1 MiB (as a Windows main thread has): a 12-axis DDFS machine
(180 states) crashed there before, and runs now; its result equals the same run on the main
thread of an unlimited process."""

from __future__ import annotations

import json
import resource
import shutil
import subprocess
import sys

import pytest

from feeddrive.backends import c_engine

HAVE_CC = any(shutil.which(cc) for cc in ("cc", "gcc", "clang"))
pytestmark = pytest.mark.skipif(not HAVE_CC, reason="no C compiler (cc, gcc, clang) on PATH")

_RUN = """
import json, sys
import numpy as np
import feeddrive as fd
from feeddrive.machine import machine_from_dict, simulate_machine
from feeddrive.machine import MachineProfile
from feeddrive.model.reference import SampledSpeed
k = int(sys.argv[1])
machine = machine_from_dict({"name": "m", "axes": {f"a{i}": {"extends": "wang2021",
                             "drive": "ddfs"} for i in range(k)}})
t = np.array([0.0, 0.02])
profile = MachineProfile.common(machine, SampledSpeed(t, np.full(2, 1e-3), np.full(2, 16e-3)))
r = simulate_machine(machine, profile, 0.02)
print(json.dumps({"engine": r.solver_stats["engine"], "steps": r.solver_stats["steps"],
                  "end": [float(r.dataset[f"a{i}.table_position"][-1]) for i in range(k)]}))
"""


def _limited() -> None:
    resource.setrlimit(resource.RLIMIT_STACK, (1 << 20, 1 << 20))


def _run(k: int, limited: bool) -> dict:
    out = subprocess.run([sys.executable, "-c", _RUN, str(k)], capture_output=True, text=True,
                         timeout=600, preexec_fn=_limited if limited else None)
    assert out.returncode == 0, (out.returncode, out.stderr[-2000:])
    return json.loads(out.stdout.splitlines()[-1])


def test_only_a_large_models_calls_get_a_thread() -> None:
    import feeddrive as fd

    for drive in ("cdfs", "ddfs"):  # one axis: the thread's start would cost every call
        model = fd.DriveSystem(fd.preset("wang2021"), drive, 0.4).model(fd.ConstantSpeed(1e-3))
        assert c_engine.stack_need(len(model.states), len(model.aux)) <= \
            c_engine.STACK_OWN_THREAD / 4
    need = c_engine.stack_need(180, 400)  # 12 DDFS axes
    assert need > c_engine.STACK_OWN_THREAD and need > 2 * 8 * 4 * 180 ** 2
    assert c_engine.thread_stack(need) % (1 << 20) == 0
    assert c_engine.thread_stack(need) >= need + (1 << 20)


@pytest.mark.slow
def test_a_12_axis_machine_runs_within_a_1_mib_stack() -> None:
    limited = _run(12, limited=True)
    assert limited["engine"] == "c"
    assert limited == _run(12, limited=False)


def test_ctrl_c_while_waiting_asks_the_driver_to_stop_and_waits_for_it() -> None:
    import _thread
    import threading
    import time

    import numpy as np

    memory = np.zeros(4)
    ended = threading.Event()

    def driver() -> int:  # stands for a compiled driver polling its stop request
        while memory[-2] == 0.0:
            time.sleep(0.01)
        ended.set()
        return 7

    threading.Timer(0.3, _thread.interrupt_main).start()
    with pytest.raises(KeyboardInterrupt):
        c_engine.on_own_stack(driver, (), 2 << 20, memory)
    assert memory[-2] == 1.0 and ended.is_set()  # asked to stop, and returned before the raise
    assert c_engine.on_own_stack(lambda a, b: a + b, (2, 3), 2 << 20) == 5
    with pytest.raises(ZeroDivisionError):
        c_engine.on_own_stack(lambda: 1 / 0, (), 2 << 20)
