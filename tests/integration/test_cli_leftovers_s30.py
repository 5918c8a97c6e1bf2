"""Leftovers of the earlier bad-input sweeps on the command line (session 30): each a
one-line refusal (exit 2, nothing on standard output) naming the option and what was
expected.

2. ``analyze --no-segments`` beside a command (``--command-speed`` or the file's command
   column) was dropped: the command sets the segments.
4. A machine file's ``nut_hold`` / ``table_position`` on a linear-motor axis were read and
   dropped (``params show --machine`` wrote both on every axis).
5. ``validate FIT a.csv a.csv`` printed the record's rows twice; ``stiffness --positions
   100,100`` printed the row twice — refused as ``fit a.csv a.csv`` is.
"""

from __future__ import annotations

from pathlib import Path

from cli_support import FIT_RECORD, RUNNER, one_line_refusal

from feeddrive.cli import app


def _trace(path: Path, command: bool) -> Path:
    """A 20-s record at 1 mm/s, 200 Hz, with a ``command_speed`` column or without."""
    head = "time [s],position [mm]" + (",command_speed [mm/s]" if command else "")
    rows = [f"{k * 5e-3:.3f},{k * 5e-3:.6f}" + (",1" if command else "") for k in range(4000)]
    path.write_text("\n".join([head, *rows]) + "\n", encoding="utf-8")
    return path


# ------------------------------------------------------------- 2: analyze --no-segments


def test_analyze_refuses_no_segments_beside_a_command_column(tmp_path: Path) -> None:
    trace = _trace(tmp_path / "cmd.csv", command=True)
    line = one_line_refusal(["analyze", str(trace), "--no-segments"])
    assert line == ("error: --no-segments = True: not with the command column "
                    "'command_speed' of cmd.csv, whose steps set the segments (segments are "
                    "detected only without a command); expected --segments")
    assert RUNNER.invoke(app, ["analyze", str(trace)]).exit_code == 0


def test_analyze_refuses_no_segments_beside_a_command_speed(tmp_path: Path) -> None:
    trace = _trace(tmp_path / "plain.csv", command=False)
    line = one_line_refusal(["analyze", str(trace), "--no-segments", "--command-speed", "1"])
    assert line == ("error: --no-segments = True: not with --command-speed, which makes the "
                    "whole trace one segment (segments are detected only without a command); "
                    "expected --segments")
    assert RUNNER.invoke(app, ["analyze", str(trace), "--no-segments"]).exit_code == 0


# ------------------------------------------------------ 4: a machine axis' extra keys


def test_params_check_refuses_a_nut_hold_on_a_linear_motor_axis(tmp_path: Path) -> None:
    machine = tmp_path / "m.toml"
    machine.write_text('name = "m"\n[axes.y]\ndrive = "linear-motor"\nnut_hold = "locked"\n',
                       encoding="utf-8")
    line = one_line_refusal(["params", "check", "--machine", str(machine)])
    assert "axes.y.nut_hold = 'locked': applies to a drive that holds its nut (cdfs), not to " \
           "linear-motor (it has no nut)" in line, line


def test_params_show_writes_a_machine_that_reads_back(tmp_path: Path) -> None:
    """What ``params show --machine`` prints is a machine file ``params check`` takes: the
    linear-motor axis without the keys it would refuse."""
    machine = tmp_path / "m.toml"
    machine.write_text('name = "m"\n[axes.x]\nextends = "wang2021"\ndrive = "cdfs"\n'
                       'nut_hold = "servo"\n[axes.y]\ndrive = "linear-motor"\n',
                       encoding="utf-8")
    shown = RUNNER.invoke(app, ["params", "show", "--machine", str(machine)])
    assert shown.exit_code == 0, shown.output
    written = tmp_path / "written.toml"
    written.write_text(shown.stdout, encoding="utf-8")
    y = shown.stdout[shown.stdout.index("[axes.y]"):]
    assert "nut_hold" not in y and "table_position" not in y
    assert 'nut_hold = "servo"' in shown.stdout
    checked = RUNNER.invoke(app, ["params", "check", "--machine", str(written)])
    assert checked.exit_code == 0, checked.output


# --------------------------------------------------------- 5: one value twice in a line


def test_stiffness_refuses_a_position_given_twice() -> None:
    line = one_line_refusal(["stiffness", "--positions", "100,100"])
    assert line == ("error: --positions = '100': given twice; expected each position once "
                    "[mm], e.g. 200,400")
    line = one_line_refusal(["stiffness", "--positions", "200,100,200.0"])
    assert line.startswith("error: --positions = '200.0': given twice")


def test_validate_refuses_a_record_given_twice(tmp_path: Path) -> None:
    fit = tmp_path / "fit.toml"
    fit.write_text(FIT_RECORD.format(variance="1e4"), encoding="utf-8")
    trace = tmp_path / "t.csv"
    rows = [f"{k * 1e-3:.3f},{min(k * 1e-3, 1.9) * 0.9:.6f},{0.1 + 0.01 * (k % 7):.4f},1"
            for k in range(2001)]
    trace.write_text("time [s],table_position [mm],screw_current [A],"
                     "table_speed_reference [mm/s]\n" + "\n".join(rows) + "\n",
                     encoding="utf-8")
    line = one_line_refusal(["validate", str(fit), str(trace), str(trace)])
    assert line == ("error: t.csv: given twice; each held-out record is scored once (twice, "
                    "its rows would repeat)")
