"""Ctrl-C inside a long solver call (an outside check, 2026-12-06): at tight but valid settings
one chunk of a run (up to ``DENSE_CHUNK`` = 10 simulated seconds) took seconds, and Ctrl-C
waited for it: ``feeddrive simulate --drive ddfs … --method rodas4 --accuracy 1e-8`` stopped
4.5 s after the signal, ``--position-tolerance 1e-30`` 17 s after, the bar frozen meanwhile.
Runs started on the main thread now wait for their chunks in a helper thread; Ctrl-C asks
the compiled solver to stop after its current step (``Simulation.request_stop``).

The behaviour is tested, not the time: the signal is sent from the progress callback at the
first report *inside* the first chunk (which only a live report can give), and the run must
end there — before the chunk's end — with the part finished (``SimulationInterrupted``).
Before the change no report came before the chunk's end and the run went on past it.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.engine import simulate as simulate_module

SCRIPT = textwrap.dedent("""
    import json, os, signal
    import feeddrive as fd
    from feeddrive.engine.simulate import DENSE_CHUNK, SimulationInterrupted

    system = fd.DriveSystem(fd.preset("wang2021"), "ddfs", 0.4)
    options = fd.SolverOptions(method="rodas4", accuracy=1e-8)  # ≈ 1 s of CPU per 1.3 s
    reports = []

    def progress(t, t_end):
        reports.append(t)
        if len(reports) == 1:
            os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C at the first report

    out = {"chunk": DENSE_CHUNK}
    try:
        fd.simulate(system, fd.ConstantSpeed(0.5e-3, 16e-3), 60.0, options=options,
                    progress=progress)
        out["ended"] = "completed"
    except SimulationInterrupted as err:
        out.update(ended="interrupted", t_reached=err.t_reached,
                   samples=int(err.result.time.size))
    except KeyboardInterrupt:
        out["ended"] = "keyboard interrupt"
    out["reports"] = reports
    print(json.dumps(out))
""")


@pytest.mark.slow
def test_ctrl_c_stops_the_run_inside_its_first_chunk() -> None:
    done = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                          timeout=600, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    out = json.loads(done.stdout.strip().splitlines()[-1])
    # the first report came from inside the first chunk (the solver's live time) ...
    assert 0.0 < out["reports"][0] < out["chunk"], out
    # ... and the run ended at the signal, the unfinished chunk not kept
    assert out["ended"] == "interrupted", out
    assert out["t_reached"] == 0.0 and out["samples"] == 0, out
    assert len(out["reports"]) == 1, out  # nothing reported after the stop


def _runs(threaded: bool) -> tuple[fd.Result, list[float]]:
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    reports: list[float] = []
    keep = simulate_module._interruptible
    simulate_module._interruptible = lambda *_: threaded  # type: ignore[assignment]
    try:
        result = fd.simulate(system, fd.ConstantSpeed(1.2e-3), 25.0,
                             progress=lambda t, _: reports.append(t))
    finally:
        simulate_module._interruptible = keep  # type: ignore[assignment]
    return result, reports


def test_a_run_waited_on_in_a_helper_thread_is_the_run_itself() -> None:
    """The same steps either way (the helper thread runs the same calls), the chunk ends
    reported in order, the last one the run's end."""
    (direct, direct_reports), (threaded, reports) = _runs(False), _runs(True)
    for name in ("table_speed", "table_position", "screw_current"):
        assert np.array_equal(np.asarray(direct[name]), np.asarray(threaded[name])), name
    assert direct.solver_stats["steps"] == threaded.solver_stats["steps"]
    assert reports == sorted(reports) and reports[-1] == pytest.approx(25.0)
    assert direct_reports[-1] == pytest.approx(25.0)


def test_an_error_in_progress_stops_the_run_and_is_raised(monkeypatch) -> None:
    """A progress callback that raises (the explorer's cancel, a closed terminal) ends the
    run waited on in a helper thread, as it ended the run called directly."""
    monkeypatch.setattr(simulate_module, "_interruptible", lambda *_: True)
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    before = threading.active_count()

    def progress(t: float, t_end: float) -> None:
        raise RuntimeError("closed")

    with pytest.raises(RuntimeError, match="closed"):
        fd.simulate(system, fd.ConstantSpeed(2e-3), 30.0, progress=progress)
    for _ in range(500):  # the helper thread ends right after handing its error over
        if threading.active_count() == before:
            break
        time.sleep(0.01)
    assert threading.active_count() == before


def test_the_docs_state_the_live_report_interval_of_the_code() -> None:
    from pathlib import Path

    every = f"when no chunk has ended for {simulate_module.LIVE_PROGRESS_EVERY:g} s"
    assert every in " ".join(fd.simulate.__doc__.split())
    model_md = Path(__file__).resolve().parents[2] / "docs" / "model.md"
    assert every in " ".join(model_md.read_text(encoding="utf-8").split())


CLI_SCRIPT = textwrap.dedent("""
    import os, signal, sys, threading, time
    from feeddrive import __main__ as entry
    from feeddrive.engine import simulate

    advance = simulate._Chunks.advance
    running = []

    def advance_then_ctrl_c(self, *args, **kwargs):
        # Ctrl-C 1 s into the run's first chunk (≈ 8 s of work at these settings)
        running.append(self)
        threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGINT)).start()
        simulate._Chunks.advance = advance
        return advance(self, *args, **kwargs)

    simulate._Chunks.advance = advance_then_ctrl_c
    sys.argv = ["feeddrive", "simulate", "--drive", "ddfs", "--nut-speed", "16",
                "--table-speed", "0.5", "--duration", "300", "--method", "rodas4",
                "--accuracy", "1e-8", "--json"]
    try:
        entry.main()
    finally:  # where the solver was when the run ended [simulated s]
        print("solver reached", float(running[0].live[-1]), "of a chunk of",
              simulate.DENSE_CHUNK)
""")


@pytest.mark.slow
def test_the_command_line_stops_a_run_without_progress_inside_its_chunk() -> None:
    """The command line asks every run to be stopped within a step (``feeddrive._sigint``),
    also one that reports no progress (``--json``): the run ends at t = 0 s, inside its first
    chunk, not at the chunk's end (t = 10 s, as a run from Python without ``progress`` does)."""
    done = subprocess.run([sys.executable, "-c", CLI_SCRIPT], capture_output=True, text=True,
                          timeout=600, check=False)
    assert done.returncode == 130, (done.returncode, done.stderr[-2000:])
    assert "simulation interrupted at t = 0 s" in done.stderr, done.stderr[-2000:]
    words = done.stdout.split()
    reached, chunk = float(words[2]), float(words[-1])
    assert 0.0 < reached < chunk, done.stdout  # stopped inside the chunk, not at its end


def test_a_run_from_python_without_progress_is_called_directly() -> None:
    """Not asked for (no ``progress``, ``stop_within_a_step`` off), a run on the main thread
    calls the solver itself: the helper thread's 0.1–0.2 ms is not paid by a loop of short
    runs."""
    from feeddrive import _sigint

    assert not _sigint.asked()
    assert not simulate_module._interruptible(None)
