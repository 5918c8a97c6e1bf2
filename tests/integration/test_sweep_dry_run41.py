"""Issue 41 item 8: the dry run of a 4-point critical-speed grid took 2.8 CPU s (the sweep
itself 7.2) and its estimate (0.94 s) left out the workers' start-up and compilation; and
`sensitivity` took a fitted file only as --params while `predict` takes it as its argument."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

import feeddrive.engine.simulate as engine
from feeddrive.analysis import protocol
from feeddrive.cli import app
from feeddrive.sweep import executors
from feeddrive.sweep.design import load_config
from feeddrive.sweep.quantities import QuantitySettings

FOUR = """
name = "four"
preset = "wang2021"
drive = "cdfs"
[design]
kind = "grid"
[quantity]
kind = "{kind}"
{settings}
[axes]
table_position = [300, 500]
"controller.velocity_gain" = {{ values = [0.9, 1.1], relative = true }}
"""
#: each kind's own settings (a setting its kind does not read is refused)
SETTINGS = {"critical-speed": "linear = false", "creep-trial": "linear = false\ntable_speed = 2"}


def _four(kind: str) -> str:
    return FOUR.format(kind=kind, settings=SETTINGS[kind])


def _config(tmp_path: Path, kind: str) -> Any:
    path = tmp_path / f"{kind}.toml"
    path.write_text(_four(kind), encoding="utf-8")
    return load_config(path)


def test_a_simulated_quantity_is_probed_not_evaluated(tmp_path: Path, monkeypatch) -> None:
    """No full evaluation, one parameter set, one probe run of PROBE_DURATION; the estimate
    includes each worker's start and brackets the points between the protocol's bounds."""
    evaluated, runs = [], []
    monkeypatch.setattr(executors, "evaluate", lambda task: evaluated.append(task))
    original = engine.simulate

    def counted(system: Any, profile: Any, duration: float, **kw: Any) -> Any:
        runs.append(duration)
        return original(system, profile, duration, **kw)

    monkeypatch.setattr(engine, "simulate", counted)
    est = executors.estimate(_config(tmp_path, "critical-speed"), None, workers=2)
    assert evaluated == [] and est.built == 1 and est.timed == 0
    assert runs[-1] == executors.PROBE_DURATION and sum(runs) <= 1.1  # warm-up 0.02 s + probe
    assert est.startup_seconds > 0 and est.probe_rate > 0
    lo, hi = est.point_range
    short, long = executors.simulated_range(QuantitySettings().to_dict())
    assert (lo, hi) == pytest.approx((short * est.probe_rate, long * est.probe_rate))
    # 4 points on 2 workers: two points each, plus one start per worker (in parallel)
    assert est.seconds_range == pytest.approx((2 * lo + est.startup_seconds,
                                               2 * hi + est.startup_seconds))


def test_the_protocols_simulated_time() -> None:
    """The default search from rest: 0.02–3.02 mm/s in 0.2-mm/s steps is 16 trials, each
    bisection 5 halvings of 0.2 mm/s to 0.01 mm/s; trials 12 s doubled up to 240 s
    (feeddrive.analysis.protocol)."""
    q = QuantitySettings().to_dict()
    assert protocol.TRIAL_DURATION == 12.0 and protocol.TRIAL_MAX_DURATION == 240.0
    assert executors.simulated_range(q) == (16 * 12.0, (16 + 4 * 5) * 240.0)
    assert executors.simulated_range({**q, "kind": "creep-trial"}) == (12.0, 240.0)
    assert executors.simulated_range({**q, "start": "running"}) == (16 * 12.0, (16 + 20) * 240.0)


def test_a_real_points_simulated_time_lies_in_the_protocols_range(tmp_path: Path) -> None:
    """The bounds the estimate scales are the protocol's: a real creep trial's simulated
    time (not its CPU, which a loaded machine moves) lies between them."""
    cfg = _config(tmp_path, "creep-trial")
    point = next(iter(cfg.iter_coordinates()))
    task = cfg.task(point, {})
    out = executors.evaluate(task)
    lo, hi = executors.simulated_range(task["quantity"])
    assert lo <= out["values"]["duration"] <= hi, (lo, out["values"]["duration"], hi)


@pytest.mark.parametrize("build", ["numba", "c"])
def test_compiling_in_the_dry_run_is_reported(tmp_path: Path, monkeypatch, build: str) -> None:
    """A kernel compiled while the dry run loads them is reported as compilation (numba's
    compile events, or a library the C build compiled), not counted as a worker's start."""
    from feeddrive._jit import HAVE_NUMBA
    from feeddrive.backends import c_cache

    if build == "numba" and not HAVE_NUMBA:
        pytest.skip("numba is not installed (the optional extra feeddrive[numba]); "
                    ".ci/min-versions installs it")

    def compile_something(task: dict[str, Any]) -> None:
        if build == "c":  # what c_cache.cached_library counts when it compiles a library
            monkeypatch.setitem(c_cache.STATS, "compiles", c_cache.STATS["compiles"] + 1)
            return
        import numba

        numba.njit(lambda x: x + 1.5)(1.0)  # a new function: numba compiles it now

    monkeypatch.setattr(executors, "warm", compile_something)
    monkeypatch.setattr(executors, "_probe_rate", lambda task: 1e-3)
    if build == "numba":  # the numba build started (as an earlier test in this process may
        # have, or not): its compile events are what is read, whichever build runs by default
        import feeddrive._jit

        monkeypatch.setattr(feeddrive._jit, "numba_started", lambda: True)
    est = executors.estimate(_config(tmp_path, "critical-speed"), None, workers=2)
    assert est.compile_seconds > 0


def test_the_dry_run_prints_the_start_up_and_the_range(tmp_path: Path) -> None:
    path = tmp_path / "four.toml"
    path.write_text(_four("critical-speed"), encoding="utf-8")
    res = CliRunner().invoke(app, ["sweep", str(path), "--dry-run", "--store",
                                   str(tmp_path / "four.sqlite")])
    assert res.exit_code == 0, res.output
    line = " ".join(res.stdout.split())
    assert "s CPU per point (a 1-s probe:" in line and "s to start each worker → about" in line
    assert not (tmp_path / "four.sqlite").exists()


FITTED = """
extends = "wang2021"
name = "wang2021-fitted"
[fit]
drive = "ddfs"
table_position = 0.3
"""


def test_sensitivity_takes_the_fit_as_its_argument(tmp_path: Path, monkeypatch) -> None:
    """As `predict FIT.toml`: the file is the argument; its drive and position are the
    defaults."""
    import feeddrive.analysis.sensitivity as sens

    seen: dict[str, Any] = {}

    class Stop(Exception):
        pass

    def capture(source: Any, **kw: Any) -> Any:
        seen.update(source=source, **kw)
        raise Stop

    monkeypatch.setattr(sens, "sensitivity", capture)
    fit = tmp_path / "fitted.toml"
    fit.write_text(FITTED, encoding="utf-8")
    res = CliRunner().invoke(app, ["sensitivity", str(fit), "--quantity", "linear-band"])
    assert isinstance(res.exception, Stop), res.output
    assert seen["source"] == str(fit) and seen["drive"] == "ddfs"
    assert seen["table_position"] == pytest.approx(0.3)
    res = CliRunner().invoke(app, ["sensitivity", str(fit), "--params", str(fit)])
    assert res.exit_code == 2 and "give the parameter file once" in res.stderr
