"""Usage errors in one line (an outside check, 2026-12-06): ``feeddrive simulate --rtol abc``
printed click's usage line, a hint and ``Error: Invalid value …`` — four lines, not the
``error:`` line docs/outputs.md promises for every failure.  The app's group
(:class:`feeddrive.cli._usage.OneLineGroup`) now turns every usage error into one line naming
the option and the command's help; exit status 2 as before; a bare group still shows its
help."""

from __future__ import annotations

import subprocess
import sys

import pytest
from typer.testing import CliRunner

from feeddrive.cli import app

runner = CliRunner()


@pytest.mark.parametrize(("args", "names"), [
    (["simulate", "--table-speed", "1", "--rtol", "abc"], ["--rtol", "simulate --help"]),
    (["creep", "--accuracy", "tight"], ["--accuracy", "creep --help"]),
    (["simulate", "--no-such-option"], ["--no-such-option"]),
    (["no-such-command"], ["no-such-command", "--help"]),  # the runner names the app "root"
    (["export", "fmu", "--bogus"], ["--bogus", "export fmu --help"]),
    (["simulate", "--table-speed"], ["--table-speed"]),
])
def test_a_usage_error_is_one_error_line(args: list[str], names: list[str]) -> None:
    result = runner.invoke(app, args)
    assert result.exit_code == 2
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1, result.output
    assert lines[0].startswith("error: ")
    assert all(name in lines[0] for name in names), lines[0]
    assert "Usage:" not in result.output and "Traceback" not in result.output


def test_a_bare_group_still_shows_its_help() -> None:
    result = runner.invoke(app, ["export"])
    assert "Usage:" in result.output and "fmu" in result.output
    assert "error:" not in result.output


def test_the_installed_entry_point_says_it_on_stderr() -> None:
    done = subprocess.run([sys.executable, "-m", "feeddrive", "simulate", "--rtol", "abc"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.count("\n") == 1 and done.stderr.startswith("error: ")
    assert "'--rtol'" in done.stderr
