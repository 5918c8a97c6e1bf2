"""Sweeps run end to end (issue 10 acceptance): a real Dask scheduler and two worker
processes on loopback give the local pool's numbers; a sweep killed with SIGKILL and rerun
has every point once with the uninterrupted values; the example's map; exports.

Cheap quantities keep this short: short creep trials (2 s) and the linear band on a coarse
scan.  Every sweep runs as a user runs it, ``python -m feeddrive sweep …`` in a subprocess.
"""

from __future__ import annotations

import os
import signal
import socket
import sqlite3
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
BIN = Path(sys.executable).parent

SMALL = """
name = "small"
drive = "cdfs"
[quantity]
kind = "creep-trial"
initial_duration = 2.0
max_duration = 2.0
[axes]
table_speed = [0.5, 1.0, 3.0]
table_position = [300, 500]
"""


def _sweep(*args: str, cwd: Path, timeout: float = 240) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "feeddrive", "sweep", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout)


def _values(path: Path) -> pd.DataFrame:
    frame = pd.read_csv(path)
    return frame.drop(columns=[c for c in frame.columns if c.startswith("seconds")])


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture()
def dask_cluster(tmp_path: Path):  # type: ignore[no-untyped-def]
    """A Dask scheduler and two single-threaded worker processes on 127.0.0.1."""
    pytest.importorskip("distributed")
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    procs = [subprocess.Popen([str(BIN / "dask"), "scheduler", "--host", "127.0.0.1", "--port",
                               str(port), "--no-dashboard"], cwd=tmp_path, env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            break
        except OSError:
            time.sleep(0.3)
    for _ in range(2):
        procs.append(subprocess.Popen(
            [str(BIN / "dask"), "worker", address, "--nthreads", "1", "--no-dashboard",
             "--host", "127.0.0.1"], cwd=tmp_path, env=env,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
    from distributed import Client

    with Client(address, timeout="30s") as client:
        client.wait_for_workers(2, timeout=60)
    try:
        yield address
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(20)
            except subprocess.TimeoutExpired:
                p.kill()


def test_dask_scheduler_gives_the_local_pool_numbers(tmp_path: Path, dask_cluster: str) -> None:
    cfg = tmp_path / "small.toml"
    cfg.write_text(SMALL)
    local = _sweep(str(cfg), "--workers", "2", "--store", "local.sqlite", "--output",
                   "local.csv", cwd=tmp_path)
    assert local.returncode == 0, local.stderr
    remote = _sweep(str(cfg), "--scheduler", dask_cluster, "--store", "dask.sqlite",
                    "--output", "dask.csv", cwd=tmp_path)
    assert remote.returncode == 0, remote.stderr
    assert "dask (tcp://127.0.0.1" in remote.stdout
    a, b = _values(tmp_path / "local.csv"), _values(tmp_path / "dask.csv")
    assert len(a) == 6 and a["done"].all()
    assert a["ripple_ratio [1]" if "ripple_ratio [1]" in a else "ripple_ratio"].notna().all()
    pd.testing.assert_frame_equal(a, b)


def _count(path: Path) -> int:
    try:
        db = sqlite3.connect(path, timeout=30)
        try:
            return int(db.execute("SELECT COUNT(*) FROM results").fetchone()[0])
        finally:
            db.close()
    except sqlite3.Error:
        return 0


KILL = """
name = "kill"
drive = "cdfs"
[quantity]
kind = "critical-speed"
low = 1.0
high = 2.0
coarse_step = 0.5
resolution = 0.1
initial_duration = 3.0
max_duration = 3.0
linear = false
[axes]
table_position = [250, 350, 450, 550]
"controller.velocity_integral_gain" = [3600, 3925.28, 4200]
"""


def test_sigkill_then_rerun_loses_and_duplicates_nothing(tmp_path: Path) -> None:
    cfg = tmp_path / "kill.toml"
    cfg.write_text(KILL)
    store = tmp_path / "killed.sqlite"
    proc = subprocess.Popen([sys.executable, "-m", "feeddrive", "sweep", str(cfg), "--workers",
                             "1", "--store", str(store)], cwd=tmp_path, start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 180
    while time.monotonic() < deadline and proc.poll() is None and _count(store) < 3:
        time.sleep(0.05)
    assert proc.poll() is None, "the sweep finished (or failed) before the kill"
    os.killpg(proc.pid, signal.SIGKILL)  # the sweep and its worker processes
    proc.wait(30)
    killed_at = _count(store)
    assert 3 <= killed_at < 12
    again = _sweep(str(cfg), "--workers", "2", "--store", str(store), "--output", "resumed.csv",
                   cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert f"{killed_at} found" in again.stdout
    clean = _sweep(str(cfg), "--workers", "2", "--store", "clean.sqlite", "--output",
                   "clean.csv", cwd=tmp_path)
    assert clean.returncode == 0, clean.stderr
    db = sqlite3.connect(store)
    assert db.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    assert db.execute("SELECT COUNT(*), COUNT(DISTINCT key) FROM results").fetchone() == (12, 12)
    assert db.execute("SELECT COUNT(*) FROM points WHERE sweep = 'kill'").fetchone()[0] == 12
    db.close()
    resumed, uninterrupted = _values(tmp_path / "resumed.csv"), _values(tmp_path / "clean.csv")
    assert resumed["index"].is_unique and len(resumed) == 12
    pd.testing.assert_frame_equal(resumed, uninterrupted)


def test_example_map_shows_the_gain_and_not_the_position(tmp_path: Path) -> None:
    """examples/position_velocity_gain.toml (issue 24 item 12: the previous example's map was
    1.56 in every CDFS cell, a colourbar for a constant field and two legend entries for
    boundaries never drawn), on a coarser grid and search: the critical speed changes along
    the gain axis, is the same at every position, and the NetCDF export has both axes."""
    text = (EXAMPLES / "position_velocity_gain.toml").read_text()
    data = tomllib.loads(text)
    assert data["axes"]["controller.velocity_gain"]["relative"] is True
    text = text.replace("[quantity]\n", "[quantity]\nlow = 1.0\nhigh = 3.0\ncoarse_step = 0.5\n"
                        "resolution = 0.1\ninitial_duration = 6.0\nmax_duration = 24.0\n"
                        "linear_points = 8\n")
    text = text.replace("table_position = { low = 200, high = 600, points = 3 }",
                        "table_position = { low = 200, high = 600, points = 2 }")
    text = text.replace("values = [0.8, 0.9, 1.0, 1.1, 1.2]", "values = [0.9, 1.2]")
    cfg = tmp_path / "position_velocity_gain.toml"
    cfg.write_text(text)
    res = _sweep(str(cfg), "--plot", "map.png", "--output", "map.nc", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert "map of critical_speed over table_position × controller.velocity_gain" in res.stdout
    assert (tmp_path / "map.png").stat().st_size > 10_000
    ds = xr.open_dataset(tmp_path / "map.nc")
    assert ds.attrs["Conventions"] == "CF-1.8"
    # a CF variable name has no dot: the parameter path is kept in the attribute `parameter`
    assert dict(ds.sizes) == {"table_position": 2, "controller_velocity_gain": 2}
    assert ds["controller_velocity_gain"].attrs["parameter"] == "controller.velocity_gain"
    crit = ds["critical_speed"].transpose("table_position", "controller_velocity_gain").values
    ds.close()
    assert np.all(np.isfinite(crit))
    # a higher velocity-loop gain damps the servo mode: a lower critical speed (0.1 mm/s
    # resolution here); the position moves it by less than one resolution step
    assert np.all(crit[:, 0] > crit[:, 1] + 0.5e-3)
    assert np.all(np.abs(crit[0] - crit[1]) <= 0.1e-3 + 1e-9)
    again = subprocess.run([sys.executable, "-m", "feeddrive", "map",
                            "position_velocity_gain.sqlite", "--x", "controller.velocity_gain",
                            "--y", "table_position", "--plot", "map2.png"],
                           cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    assert (tmp_path / "map2.png").exists()


def test_monte_carlo_histogram_and_percentiles(tmp_path: Path) -> None:
    cfg = tmp_path / "mc.toml"
    cfg.write_text("""
name = "mc"
drive = "cdfs"
[design]
kind = "lhs"
samples = 8
seed = 1
[quantity]
kind = "linear-band"
linear_points = 12
[axes]
"friction.*.*.static_force" = { low = 0.9, high = 1.1, relative = true }
"stiffness.equivalent_stiffness" = { low = 0.8, high = 1.2, relative = true }
""")
    res = _sweep(str(cfg), "--plot", "hist.png", "--workers", "1", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert (tmp_path / "hist.png").exists()
    out = subprocess.run([sys.executable, "-m", "feeddrive", "map", "mc.sqlite", "--json"],
                         cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    import json

    stats = json.loads(out.stdout)["statistics"]
    assert stats["value"] == "linear_upper" and stats["points"] == 8
    assert stats["p5"] <= stats["p50"] <= stats["p95"]
