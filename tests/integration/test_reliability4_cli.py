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
from cli_support import FIT_RECORD
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


# ------------------------------------------------------------------ item 4: every output option

#: the options that name what a command writes
OUTPUT_OPTIONS = ("--out", "--output", "--plot", "--store")


SWEEP = """name = "fast"
drive = "cdfs"
[quantity]
kind = "loop-margins"
[axes]
table_position = [300, 500]
"""


def _inputs(folder: Path) -> dict[str, list[str]]:
    """Each command with the least it needs to run (its required arguments), files made."""
    trace = _trace(folder / "trace.csv")
    (folder / "fit.toml").write_text(FIT_RECORD.format(variance="1e4"))
    (folder / "sweep.toml").write_text(SWEEP)
    (folder / "static.csv").write_text("speed [mm/s],force [N]\n1,100\n")
    (folder / "fragment.toml").write_text('extends = "wang2021"\n')
    return {
        "analyze": ["analyze", str(trace)], "calibrate": ["calibrate"],
        "simulate": ["simulate", "--table-speed", "1"],
        "fit": ["fit", str(trace), "--free", "controller.velocity_integral_gain"],
        "predict": ["predict", str(folder / "fit.toml")],
        "validate": ["validate", str(folder / "fit.toml"), str(trace)], "loops": ["loops"],
        "stability": ["stability"], "reproduce": ["reproduce"],
        "sensitivity": ["sensitivity", "--quantity", "linear-band"],
        "sweep": ["sweep", str(folder / "sweep.toml")], "map": ["map", str(folder / "s.sq")],
        "friction": ["friction"], "export fmu": ["export", "fmu", "--drive", "cdfs"],
        "identify static": ["identify", "static", str(folder / "static.csv")],
        "identify dynamic": ["identify", "dynamic", str(trace)],
        "identify merge": ["identify", "merge", str(folder / "fragment.toml")],
        "positioning": ["positioning", "--targets", "100,110"],
        "circular": ["circular"],
        "compensate": ["compensate", "--compare"],
    }


def _output_options() -> list[tuple[str, str]]:
    """(command, option) of every output option, read from the CLI itself."""
    import typer

    from feeddrive.cli import load_commands

    def walk(cmd: Any, path: tuple[str, ...] = ()) -> Any:
        if hasattr(cmd, "commands"):
            for name, sub in cmd.commands.items():
                yield from walk(sub, (*path, name))
        else:
            yield " ".join(path), cmd

    return [(name, opt) for name, cmd in walk(typer.main.get_command(load_commands()))
            for p in cmd.params for opt in p.opts if opt in OUTPUT_OPTIONS]


def test_the_output_options_are_the_ones_this_test_knows() -> None:
    found = _output_options()
    assert {c for c, _ in found} == set(_COMMANDS)  # a new one: add it to _inputs
    assert len(found) >= 20  # 23 at be498e0


_COMMANDS = ("analyze", "calibrate", "simulate", "fit", "predict", "validate", "loops",
             "stability",
             "reproduce", "sensitivity", "sweep", "map", "friction", "export fmu",
             "identify static", "identify dynamic", "identify merge", "positioning",
             "circular", "compensate")


def _declared(command: str, option: str) -> Any:
    """The formats the command declares for the option (``_common.outputs``)."""
    import typer

    from feeddrive.cli import _common, load_commands

    cmd: Any = typer.main.get_command(load_commands())
    for part in command.split():
        cmd = cmd.commands[part]
    return _common.declared_outputs(cmd.callback)[option]


def _bad_names(folder: Path, formats: Any) -> list[tuple[str, str]]:
    """(name, what the refusal says) for one output option."""
    ext = formats[0] if isinstance(formats, tuple) and formats else ""
    (folder / "a-folder").mkdir(exist_ok=True)
    names = [(str(folder / f"{'n' * 300}{ext}"), "too long"),
             (str(folder / "missing" / f"x{ext}"), "does not exist")]
    if formats != "folder":
        names.append((str(folder / "a-folder"), "folder"))
        # a name the file system holds, but not the temporary name it is written under
        names.append((str(folder / f"{'m' * (250 - len(ext))}{ext}"), "too long"))
    if isinstance(formats, tuple):
        names.append((str(folder / "r.txt"), "expected a"))
    return names


@pytest.mark.parametrize(("command", "option"), _output_options())
def test_every_output_option_of_every_command_is_refused_before_any_work(
        tmp_path: Path, no_work: None, command: str, option: str) -> None:
    """One output check (``_common.outputs``, ``io.outputs.check_output_file``) serves every
    output option: a wrong format, a name too long for the file system (the final name, or
    the temporary name it is written under), a missing folder, a folder: each refused with
    status 2 in one line naming the option, before a simulation, a model or a pool starts.
    (``sensitivity --plot r.txt`` ran the whole study first; a 304-character ``export fmu
    --out`` failed after the build.)"""
    formats = _declared(command, option)
    base = _inputs(tmp_path)[command]
    for name, says in _bad_names(tmp_path, formats):
        result = runner.invoke(app, [*base, option, name])
        line = _one_line(result, option)
        assert says in line, (name[-40:], line)
        assert result.exit_code == 2, line
        assert len(line) < 600, line
    assert not list(tmp_path.rglob(".*partial*"))


# ------------------------------------------------------------------ items 4, 5: values


@pytest.mark.parametrize(("args", "says"), [
    # item 4: bounded before it starts (the sweep's cap on a design; a search's steps)
    (["predict", "{fit}", "--samples", "1000000000"], ("--samples", "[1, 1000000]")),
    (["predict", "{fit}", "--resolution", "1e-300"], ("--resolution", "expected ≥ 0.0001")),
    (["export", "fmu", "--drive", "cdfs", "--out", "{dir}/a.fmu", "--table-speed", "1e300"],
     ("--table-speed", "≤ 100000 [mm/s]")),
    # item 5: numbers that mean nothing
    (["predict", "{neg}"], ("fit.covariance", "neg.toml", "variance", "negative")),
    (["fit", "{trace}", "--free", "controller.velocity_integral_gain", "--weight",
      "table_position=1e308"], ("--weight table_position=1e+308", "[1e-06, 1e+06]")),
    (["fit", "{big}", "--free", "controller.velocity_integral_gain"],
     ("big.csv, line 6", "table_position", "1e308", "check the file's unit")),
    (["fit", "{trace}", "--free", "controller.velocity_integral_gain", "--workers", "0"],
     ("--workers = 0", "≥ 1")),
    (["fit", "{trace}", "--free", "controller.velocity_integral_gain", "--out",
      "{dir}/fitted.csv"], ("--out", "fitted.csv", "expected a .toml file name")),
], ids=["samples", "resolution", "fmu-speed", "negative-variance",
        "weight", "huge-cell", "workers", "fit-out"])
def test_a_value_that_means_nothing_is_refused_in_one_line_before_any_work(
        tmp_path: Path, no_work: None, args: list[str], says: tuple[str, ...]) -> None:
    files = {"fit": tmp_path / "fit.toml", "neg": tmp_path / "neg.toml",
             "trace": _trace(tmp_path / "trace.csv"),
             "big": _trace(tmp_path / "big.csv", cell="1e308"), "dir": tmp_path}
    files["fit"].write_text(FIT_RECORD.format(variance="1e4"))
    files["neg"].write_text(FIT_RECORD.format(variance="-1e4"))
    result = runner.invoke(app, [a.format(**files) for a in args])
    line = _one_line(result, *says)  # no numpy warning, no "looks like m/s" warning
    assert result.exit_code == 2, line
    assert not list(tmp_path.glob("*.sqlite")) and not (tmp_path / "fitted.csv").exists()


def test_an_internal_error_is_still_rc_1_with_its_traceback(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """No handler maps an unknown exception to a refusal (status 2): a bug stays a bug."""
    from feeddrive.analysis import predict

    def broken(*args: Any, **kw: Any) -> Any:
        raise RuntimeError("injected internal error")

    monkeypatch.setattr(predict, "read_fit_record", broken)
    (tmp_path / "fit.toml").write_text(FIT_RECORD.format(variance="1e4"))
    result = runner.invoke(app, ["predict", str(tmp_path / "fit.toml")])
    assert result.exit_code == 1
    assert isinstance(result.exception, RuntimeError)  # CliRunner keeps what would print


# ------------------------------------------------------------------ fuzz: hostile invocations

#: option → values each refused before any work (one of them makes an invocation hostile)
HOSTILE: dict[str, dict[str, list[str]]] = {
    "fit": {
        "--workers": ["0", "-1"], "--dask-workers": ["0", "-4"],
        "--weight": ["table_position=1e308", "table_position=0", "table_position=nan",
                     "nope=1", "=2", "table_position=1e-320", "table_position"],
        "--free": ["nope.path", "controller", ""], "--drive": ["nope", "../x", ""],
        "--preset": ["nope", "../../etc/passwd"], "--params": ["{missing}", "{dir}", "{bin}"],
        "--signal": ["nope", "table_position/"],
        "--command-speed": ["nan", "inf", "1e300", "-1e300"],
        "--profile": ["{missing}", "{dir}", "{bin}"],
        "--position": ["nan", "-1", "0", "1e300", "5000"],
        "--confidence": ["0", "1", "nan", "-0.5", "1.5"],
        "--max-evaluations": ["0", "-5", "1000000000000"],
        "--out": ["{dir}/f.csv", "{long}.toml", "{dir}/missing/f.toml", "{dir}"],
        "--plot": ["{dir}/r.txt", "{long}.png", "{dir}/missing/r.png", "{dir}"],
        "TRACE": ["{missing}", "{dir}", "{bin}", "{gap}", "{big}", "{short}"],
    },
    "predict": {
        "--samples": ["0", "-3", "1000001", "1000000000"], "--seed": ["-1"],
        "--workers": ["0", "-2"], "--dask-workers": ["0"],
        "--resolution": ["0", "-1", "nan", "inf", "1e-300", "1e300", "0.00001"],
        "--low": ["nan", "0", "-1", "1e300"], "--high": ["inf", "-3", "1e300"],
        "--store": ["{dir}", "{long}.sqlite", "{dir}/missing/s.sqlite", "{fit}"],
        "--plot": ["{dir}/r.txt", "{long}.png", "{dir}"],
        "FIT": ["{missing}", "{dir}", "{bin}", "{neg}", "{nofit}"],
    },
    "sensitivity": {
        "--quantity": ["nope", ""], "--drive": ["nope"], "--preset": ["nope"],
        "--params": ["{missing}", "{dir}", "{bin}"], "--parameters": ["nope.*", "x"],
        "--position": ["nan", "-5", "1e300"], "--workers": ["0"], "--dask-workers": ["0"],
        "--store": ["{dir}", "{long}.sqlite", "{dir}/missing/s.sqlite"],
        "--plot": ["{dir}/r.txt", "{long}.png", "{dir}"],
    },
    "export": {
        "--drive": ["nope", ""], "--out": ["{dir}/a.txt", "{long}.fmu", "{dir}/missing/a.fmu",
                                           "{dir}"],
        "--preset": ["nope"], "--params": ["{missing}", "{dir}"],
        "--position": ["nan", "0", "1e300"], "--fmi": ["1", "4"], "--kind": ["x", ""],
        "--table-speed": ["nan", "inf", "1e300"], "--nut-speed": ["1e300", "1"],
        "--nut-hold": ["x"],
    },
}


def _fuzz_files(folder: Path) -> dict[str, str]:
    (folder / "dir").mkdir()
    (folder / "bin.csv").write_bytes(b"\x00\x01\x02" * 50)
    (folder / "fit.toml").write_text(FIT_RECORD.format(variance="1e4"))
    (folder / "neg.toml").write_text(FIT_RECORD.format(variance="-1e4"))
    (folder / "nofit.toml").write_text('extends = "wang2021"\n')
    return {"missing": str(folder / "missing.csv"), "dir": str(folder / "dir"),
            "bin": str(folder / "bin.csv"), "fit": str(folder / "fit.toml"),
            "neg": str(folder / "neg.toml"), "nofit": str(folder / "nofit.toml"),
            "trace": str(_trace(folder / "trace.csv")),
            "gap": str(_trace(folder / "gap.csv", gap_at=1e6)),
            "big": str(_trace(folder / "big.csv", cell="-1e308")),
            "short": str(_trace(folder / "short.csv", rows=5)),
            "long": str(folder / ("n" * 300))}


def _hostile(rng: Any, files: dict[str, str]) -> tuple[list[str], list[str]]:
    """One invocation with one to three hostile values; the options it made hostile."""
    command = rng.choice(sorted(HOSTILE))
    table = HOSTILE[command]
    chosen = rng.sample(sorted(table), rng.randint(1, min(3, len(table))))
    values = {k: rng.choice(table[k]).format(**files) for k in chosen}
    if command == "fit":
        args = ["fit", values.pop("TRACE", files["trace"]), "--free",
                values.pop("--free", "controller.velocity_integral_gain")]
    elif command == "predict":
        args = ["predict", values.pop("FIT", files["fit"])]
    elif command == "export":
        args = ["export", "fmu", "--drive", values.pop("--drive", "cdfs"), "--out",
                values.pop("--out", files["dir"] + "/ok.fmu")]
    else:
        args = ["sensitivity"]
    for option, value in values.items():
        args += [option, value]
    return args, chosen


def test_a_seeded_fuzz_of_160_hostile_invocations_is_refused_in_one_line_before_any_work(
        tmp_path: Path, no_work: None) -> None:
    """fit, predict, sensitivity and export: each invocation carries one to three values
    that mean nothing (or name what cannot be read or written).  Every one is refused with
    status 2 in one line, no traceback, no warning, before a simulation, model or pool
    starts (``no_work``), and nothing is written."""
    import random

    rng = random.Random(39)
    files = _fuzz_files(tmp_path)
    before = sorted(p.name for p in tmp_path.rglob("*"))
    for _ in range(160):
        args, chosen = _hostile(rng, files)
        result = runner.invoke(app, args)
        assert result.exit_code == 2, (args, result.exit_code, result.exception,
                                       result.stderr)
        line = _one_line(result)
        assert len(line) < 800, line
    assert sorted(p.name for p in tmp_path.rglob("*")) == before  # nothing written


def test_docs_outputs_md_lists_every_output_option_the_cli_declares() -> None:
    """docs/outputs.md "Options that write" (and ``reproduce --out``) is the CLI's list."""
    import re

    doc = (Path(__file__).resolve().parents[2] / "docs" / "outputs.md").read_text()
    listed = re.search(r"Options that write: (.*?); each has.*?`(reproduce --out)`", doc, re.S)
    assert listed is not None
    documented: set[tuple[str, str]] = set()
    for item in [*re.findall(r"`([^`]+)`", listed.group(1)), listed.group(2)]:
        words = " ".join(item.split()).split(" --")
        commands, options = words[0].split(" "), words[1].split("/")
        for variant in commands[-1].split("|"):
            name = " ".join([*commands[:-1], variant])
            documented |= {(name, f"--{o.lstrip('-')}") for o in options}
    assert documented == set(_output_options())
    for command, option in documented:  # and each is declared to the one check
        assert _declared(command, option)


# ------------------------------------------------------------------ item 7: smaller


@pytest.mark.parametrize("schema", [
    "CREATE TABLE results (id INTEGER PRIMARY KEY, value TEXT)",  # a name of ours
    "CREATE TABLE points (x REAL); CREATE TABLE other (y TEXT)",
    "CREATE TABLE inventory (item TEXT, count INTEGER)",
])
@pytest.mark.parametrize("command", ["sweep", "map", "predict", "sensitivity"])
def test_a_foreign_sqlite_file_as_a_store_is_refused_and_left_untouched(
        tmp_path: Path, no_work: None, schema: str, command: str) -> None:
    """Was rc 1 ``no such column: key`` after switching the file to WAL."""
    import sqlite3

    foreign = tmp_path / "other.sqlite"
    db = sqlite3.connect(foreign)
    db.executescript(schema)
    db.commit()
    db.close()
    before = foreign.read_bytes()
    (tmp_path / "fit.toml").write_text(FIT_RECORD.format(variance="1e4"))
    (tmp_path / "sweep.toml").write_text(SWEEP)
    args = {"sweep": ["sweep", str(tmp_path / "sweep.toml"), "--store", str(foreign)],
            "map": ["map", str(foreign)],
            "predict": ["predict", str(tmp_path / "fit.toml"), "--store", str(foreign)],
            "sensitivity": ["sensitivity", "--quantity", "linear-band", "--store",
                            str(foreign)]}[command]
    result = runner.invoke(app, args)
    line = _one_line(result, "other.sqlite", "not a feeddrive sweep store")
    assert result.exit_code == 2, line
    assert foreign.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir() if "other" in p.name) == ["other.sqlite"]


def test_analyze_says_how_short_a_window_it_judged(tmp_path: Path) -> None:
    """A 16-sample record with a given command got a verdict with nothing about its length
    (the command column's runs shorter than --min-segment are skipped, saying so)."""
    rows = ["time [s],position [mm]"] + [f"{k * 1e-3:.3f},{k * 1e-3:.6f}" for k in range(16)]
    (tmp_path / "s16.csv").write_text("\n".join(rows) + "\n")
    result = runner.invoke(app, ["analyze", str(tmp_path / "s16.csv"), "--command-speed", "1",
                                 "--smoothing", "5", "--json"])
    assert result.exit_code == 0, result.output
    import json

    notes = json.loads(result.stdout)["notes"]
    short = [n for n in notes if "shorter than --min-segment 1 s" in n]
    assert len(short) == 1, notes
    assert "16 samples (0.015 s)" in short[0] and "steady window of" in short[0]


#: table position [mm] at 1.979 … 1.994 s of ``feeddrive simulate --table-speed 1 --duration 2
#: --output t.csv`` (CDFS, wang2021): still accelerating to 1.9 mm/s
ACCELERATING = [1.9170081, 1.918829118, 1.920662428, 1.92250742, 1.92436359, 1.926229825,
                1.928104443, 1.929986149, 1.931874435, 1.933768699, 1.935667677, 1.937569705,
                1.939473514, 1.941378609, 1.943284411, 1.945189511]


def test_a_window_too_short_for_the_metrics_names_the_file(tmp_path: Path) -> None:
    """Was ``error: window: only 7 samples …`` without the file."""
    rows = ["time [s],position [mm]"] + [f"{1.979 + k * 1e-3:.3f},{x!r}"
                                         for k, x in enumerate(ACCELERATING)]
    (tmp_path / "s16.csv").write_text("\n".join(rows) + "\n")
    result = runner.invoke(app, ["analyze", str(tmp_path / "s16.csv"), "--command-speed", "1",
                                 "--smoothing", "5"])
    line = _one_line(result, "s16.csv", "samples between", "1.979–1.994 s")
    assert result.exit_code == 2, line
