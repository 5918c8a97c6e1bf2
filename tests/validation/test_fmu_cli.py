"""`feeddrive export fmu`: the acceptance run and the refusals (issue 20 acceptance)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fmu_helpers import TIGHT, Reference, needed_libraries, on_grid, run_feeddrive, run_fmu
from typer.testing import CliRunner

from feeddrive.cli import app

pytest.importorskip("fmpy")


def one_line_error(result: Any) -> str:
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error: ")
    return str(lines[0])


@pytest.mark.slow
def test_acceptance_ddfs_fmu(tmp_path: Path) -> None:
    """`feeddrive export fmu --drive ddfs --nut-speed 16 --out ddfs.fmu`: fmpy validate
    accepts it, its binary needs only libc and libm, and 10 s of DDFS 0.5 mm/s with
    v_n = 16 mm/s in fmpy follow feeddrive within 1e-6 of the stroke."""
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    proc = subprocess.run([sys.executable, "-m", "feeddrive", "export", "fmu", "--drive",
                           "ddfs", "--nut-speed", "16", "--out", "ddfs.fmu"], cwd=tmp_path,
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    path = tmp_path / "ddfs.fmu"
    assert "wrote ddfs.fmu" in proc.stdout
    assert validate_fmu(str(path)) == []
    assert needed_libraries(path, tmp_path / "x") <= {"libc.so.6", "libm.so.6"}
    md = read_model_description(str(path))
    start = {v.name: v.start for v in md.modelVariables if v.causality == "input"}
    assert float(start["nut_speed_reference"]) == pytest.approx(16e-3)
    ref = Reference.ramp(0.5, 16.0, 10.0)
    rec = run_fmu(path, ref)  # the FMU as exported: feeddrive's default tolerances
    result = run_feeddrive("ddfs", ref, **TIGHT)
    x = result["table_position"]
    stroke = abs(float(x[-1] - x[0]))
    assert stroke == pytest.approx(0.5e-3 * (10.0 - 0.05), rel=1e-3)  # after the 0.1-s ramp
    assert np.max(np.abs(on_grid(rec, result.time, "table_position") - x)) <= 1e-6 * stroke


@pytest.mark.parametrize(("args", "says"), [
    (["--drive", "xdfs"], "--drive = 'xdfs': expected one of cdfs, ddfs, linear-motor"),
    (["--drive", "ddfs", "--fmi", "4"], "--fmi = 4: expected 2 or 3"),
    (["--drive", "ddfs", "--kind", "se"], "--kind = 'se': expected cs"),
    (["--drive", "cdfs", "--nut-speed", "3"], "the cdfs drive has no live nut axis"),
    (["--drive", "ddfs", "--table-speed", "nan"], "--table-speed = nan"),
    (["--drive", "ddfs", "--position", "2000"], "--position = 2000.0"),
])
def test_bad_requests_stop_with_one_line(tmp_path: Path, args: list[str], says: str) -> None:
    out = tmp_path / "a.fmu"
    res = CliRunner().invoke(app, ["export", "fmu", *args, "--out", str(out)])
    assert says in one_line_error(res)
    assert not out.exists()


def test_output_destination_is_checked_first(tmp_path: Path) -> None:
    runner = CliRunner()
    missing = tmp_path / "nope" / "a.fmu"
    assert "does not exist" in one_line_error(
        runner.invoke(app, ["export", "fmu", "--drive", "ddfs", "--out", str(missing)]))
    assert ".fmu" in one_line_error(
        runner.invoke(app, ["export", "fmu", "--drive", "ddfs", "--out",
                            str(tmp_path / "a.zip")]))
    existing = tmp_path / "b.fmu"
    existing.write_bytes(b"keep")
    assert "--force" in one_line_error(
        runner.invoke(app, ["export", "fmu", "--drive", "ddfs", "--out", str(existing)]))
    assert existing.read_bytes() == b"keep"
    # the bad destination is named even when the drive is bad too: nothing ran
    if os.geteuid() != 0:  # root writes anywhere
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o500)
        assert "cannot write" in one_line_error(
            runner.invoke(app, ["export", "fmu", "--drive", "ddfs", "--out",
                                str(ro / "a.fmu")]))


def test_no_compiler_is_refused_before_work(tmp_path: Path, monkeypatch: pytest.MonkeyPatch
                                            ) -> None:
    monkeypatch.setenv("CC", "no-such-compiler-xyz")
    out = tmp_path / "a.fmu"
    res = CliRunner().invoke(app, ["export", "fmu", "--drive", "ddfs", "--out", str(out)])
    line = one_line_error(res)
    assert "CC" in line and "no-such-compiler-xyz" in line
    assert not out.exists()


def test_json_names_what_was_written(tmp_path: Path) -> None:
    import json

    out = tmp_path / "lm.fmu"
    res = CliRunner().invoke(app, ["export", "fmu", "--drive", "linear-motor", "--fmi", "3",
                                   "--kind", "me", "--table-speed", "2", "--out", str(out),
                                   "--json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert data["fmi_version"] == "3.0" and data["kind"] == "model exchange"
    assert data["inputs"] == ["table_position_reference", "table_speed_reference",
                              "load_force"]
    assert {"table_position", "table_speed", "motor_current", "motor_force", "guide_friction",
            "following_error"} <= set(data["outputs"])
    assert out.stat().st_size == data["size_bytes"]
