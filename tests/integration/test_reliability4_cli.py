"""Issue 39 (reliability, round 4) through the CLI: a full disk under a NetCDF output, a fit
on a trace with a gap, work bounded before it starts, numbers that mean nothing, a foreign
SQLite store, a short analysis window.

Full disks are a file-size limit (``RLIMIT_FSIZE``, ``SIGXFSZ`` ignored: a write past it fails
with ``EFBIG`` as a full disk fails with ``ENOSPC``), a 1-MB tmpfs in a user namespace
(``unshare -rm``, where the kernel allows one) and an ``ENOSPC`` injected into the writer.
"""

from __future__ import annotations

import errno
import resource
import shutil
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from feeddrive.cli import app

runner = CliRunner()


def _one_line(result: Any, *names: str) -> str:
    """The single ``error:`` line of a refused or failed command (CliRunner result)."""
    assert result.exit_code != 0, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), \
        repr(result.exception)
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert all(n in lines[0] for n in names), (names, lines[0])
    return str(lines[0])


def _limited(limit: int) -> Any:
    def preexec() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.RLIM_INFINITY))
    return preexec


def _feeddrive(*args: str, cwd: Path, timeout: float = 240, **kw: Any
               ) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "feeddrive", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout, **kw)


# ------------------------------------------------------------------ item 1: .nc on a full disk

#: a 10-s CDFS run: about 400 kB as NetCDF, so a 100-kB limit or a 1-MB tmpfs with a filler
#: stops its writer mid-file
NC_RUN = ("simulate", "--table-speed", "1", "--duration", "10", "--output", "run.nc")


def _full_disk_line(proc: subprocess.CompletedProcess[str], folder: Path) -> str:
    """rc 1 and one line naming the output, never HDF5's dump (a temp path, a pointer, a
    literal ``\\n``), nothing left under any name."""
    assert proc.returncode == 1, (proc.returncode, proc.stderr)  # was 139: SIGSEGV
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: run.nc: "), proc.stderr
    line = lines[0]
    assert "\\n" not in line and "partial" not in line and "0x" not in line, line
    assert not (folder / "run.nc").exists()
    assert not list(folder.glob(".*partial*"))
    return line


def test_a_netcdf_output_past_the_file_size_limit_is_one_line_and_rc_1(tmp_path: Path) -> None:
    proc = _feeddrive(*NC_RUN, cwd=tmp_path, preexec_fn=_limited(100 * 1024))
    assert "too large" in _full_disk_line(proc, tmp_path).lower()


def test_a_netcdf_output_on_a_full_tmpfs_is_one_line_and_rc_1(tmp_path: Path) -> None:
    """ENOSPC itself: a 1-MB tmpfs mounted in a user namespace, filled but for 100 kB."""
    unshare = shutil.which("unshare")
    probe = subprocess.run([unshare or "unshare", "-rm", "true"], capture_output=True) \
        if unshare else None
    if probe is None or probe.returncode != 0:
        pytest.skip("no unprivileged user namespaces here (the file-size limit and the "
                    "injected ENOSPC cover the same path)")
    mount = tmp_path / "disk"
    mount.mkdir()
    script = (f"mount -t tmpfs -o size=1m tmpfs {mount} && "
              f"head -c 950000 /dev/zero > {mount}/filler && cd {mount} && "
              f"{sys.executable} -m feeddrive {' '.join(NC_RUN)}")
    proc = subprocess.run([unshare, "-rm", "sh", "-c", script], capture_output=True,
                          text=True, timeout=240)
    line = _full_disk_line(proc, mount)  # the mount is gone: nothing can be left there
    assert "No space left on device" in line


def test_an_enospc_injected_into_the_netcdf_writer_is_one_line_and_rc_1(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from feeddrive.io import outputs

    def full(fd: int, data: Any) -> int:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(outputs, "_write_fd", full)
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, list(NC_RUN))
    line = _one_line(result, "run.nc", "No space left on device")
    assert result.exit_code == 1 and "partial" not in line
    assert not list(tmp_path.glob("*run*"))


# ------------------------------------------------------------------ "before any work"


class WorkStarted(AssertionError):
    """Raised by the fakes below: a simulation, a model build or a pool was started."""


@pytest.fixture()
def no_work(monkeypatch: pytest.MonkeyPatch) -> None:
    """Fail the command the moment it starts work: a simulation, a compiled model's warm-up,
    a process pool, a Dask cluster or an FMU build."""
    import concurrent.futures as cf

    from feeddrive.engine import simulate as engine
    from feeddrive.sweep import executors, quantities

    def fail(*args: Any, **kw: Any) -> Any:
        raise WorkStarted("work started before the request was checked")

    monkeypatch.setattr(engine.Simulation, "__init__", fail)
    monkeypatch.setattr(cf.ProcessPoolExecutor, "__init__", fail)
    monkeypatch.setattr(executors, "executor", fail)
    monkeypatch.setattr(executors, "warm", fail)
    monkeypatch.setattr(quantities, "warm", fail)
    monkeypatch.setattr("feeddrive.fmu.build.compile_library", fail)
    try:
        import distributed
    except ImportError:
        return
    monkeypatch.setattr(distributed, "LocalCluster", fail)


# ------------------------------------------------------------------ item 3: fit on a gap


def _trace(path: Path, *, gap_at: float | None = None, rows: int = 2001,
           cell: str | None = None) -> Path:
    """A 2-s CDFS-like record at 1 kHz (table position, current, command), optionally one
    more row at ``gap_at`` [s] or one position cell replaced by ``cell``."""
    lines = ["time [s],table_position [mm],screw_current [A],table_speed_reference [mm/s]"]
    for k in range(rows):
        t = k * 1e-3
        lines.append(f"{t:.3f},{min(t, 1.9) * 0.9:.6f},{0.1 + 0.01 * (k % 7):.4f},1")
    if cell is not None:
        first = lines[5].split(",")
        lines[5] = ",".join([first[0], cell, *first[2:]])
    if gap_at is not None:
        lines.append(f"{gap_at:g},1.8,0.1,1")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_fit_refuses_a_gap_in_a_trace_before_any_work_as_analyze_does(
        tmp_path: Path, no_work: None) -> None:
    """One row at t = 1e6 s after a 2-s record: rc 1 "out of memory" after trying to
    allocate the grid; now the rule of ``analyze`` (trace_input.resample_size), line named."""
    gap = _trace(tmp_path / "gap.csv", gap_at=1e6)
    fit = runner.invoke(app, ["fit", str(gap), "--free", "controller.velocity_integral_gain"])
    line = _one_line(fit, "gap.csv", "time: a gap of", "before line 2003", "split the record")
    assert fit.exit_code == 2, line
    analyze = runner.invoke(app, ["analyze", str(gap)])
    assert analyze.exit_code == 2
    assert line.split("gap.csv", 1)[1] == _one_line(analyze).split("gap.csv", 1)[1]
