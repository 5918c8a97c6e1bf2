"""Issue 41 item 6: output piped to a file was hard-wrapped at 80 columns mid-phrase, and
`reproduce` printed nothing for minutes when its output was not a terminal."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from feeddrive.cli import _common, app

COMMANDS = [
    ["loops", "--drive", "cdfs"],
    ["friction", "--site", "screw"],
    ["stability", "--drive", "cdfs"],
]


def _piped(args: list[str], columns: int) -> str:
    env = {k: v for k, v in os.environ.items() if k not in ("COLUMNS", "LINES")}
    done = subprocess.run([sys.executable, "-m", "feeddrive", *args], capture_output=True,
                          text=True, timeout=300, env={**env, "COLUMNS": str(columns)})
    assert done.returncode == 0, done.stderr
    return done.stdout


@pytest.mark.parametrize("args", COMMANDS, ids=lambda a: a[0])
def test_piped_output_is_not_wrapped(args: list[str]) -> None:
    """Whatever width the environment states, a pipe gets the same unbroken lines (before,
    rich wrapped them at $COLUMNS, else 80)."""
    narrow, wide = _piped(args, 40), _piped(args, 250)
    assert narrow == wide
    longest = max(len(line) for line in narrow.splitlines())
    assert longest > 80  # lines longer than the old wrap width stayed whole
    if args[0] == "loops":
        first = narrow.splitlines()[0]
        assert first.startswith("CDFS (wang2021)") and "least-damped mode" in first


def test_plain_progress_prints_each_stage_and_a_line_while_nothing_changes() -> None:
    lines: list[str] = []
    beats = threading.Event()

    def say(text: str) -> None:
        lines.append(text)
        if len(lines) >= 4:
            beats.set()

    with _common.PlainProgress("reproduce", say, every=0.01) as plain:
        plain.update("CDFS critical speed", 0, 14)
        plain.update("CDFS critical speed", 1, 14)  # the same stage: no line of its own
        assert beats.wait(30)  # the work goes on without a change: the beat prints
    assert lines[0].startswith("reproduce: starting (")
    assert lines[1].startswith("reproduce: CDFS critical speed 0/14 (")
    assert all(line.startswith("reproduce: CDFS critical speed ") for line in lines[1:])
    assert any(" 1/14 (" in line for line in lines[2:])


def test_reproduce_not_on_a_terminal_prints_plain_progress(tmp_path: Path,
                                                           monkeypatch: Any) -> None:
    """The CLI's path when its output is a pipe (CliRunner's is not a terminal); the real
    run's lines are checked on the session's reproduction (tests/validation)."""
    import feeddrive.reproduce as reproduce

    assert _common.PROGRESS_EVERY <= 10.0
    monkeypatch.setattr(_common, "PROGRESS_EVERY", 0.01)
    heard = threading.Event()

    def fake_run(params: Any, out: Path, *, progress: Any, **kwargs: Any) -> dict[str, Any]:
        progress("figures", 0, 3)
        progress("report", 1, 3)
        heard.wait(0.5)  # beats print while a stage runs on
        return {"figures": [], "wall_time_s": 1.0}

    monkeypatch.setattr(reproduce, "run", fake_run)
    result = CliRunner().invoke(app, ["reproduce", "--out", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0] == "reproduce: starting (0 s)"
    assert lines[1].startswith("reproduce: figures 0/3 (")
    assert lines[2].startswith("reproduce: report 1/3 (")
    assert sum(line.startswith("reproduce: report ") for line in lines) >= 3
    assert lines[-1].startswith("wrote ")
