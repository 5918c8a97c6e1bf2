"""What the command-line tests share: a refusal read as the one line it must be."""

from __future__ import annotations

from typer.testing import CliRunner

from feeddrive.cli import app

RUNNER = CliRunner()

#: a fit record of one free parameter (``feeddrive predict``/``validate`` read it), its
#: variance a format field: ``FIT_RECORD.format(variance="1e4")``
FIT_RECORD = """extends = "wang2021"
name = "fitted"
[controller]
velocity_integral_gain = 3925.28
[fit]
drive = "cdfs"
table_position = 0.4
free = ["controller.velocity_integral_gain"]
estimates = [3925.28]
covariance = [[{variance}]]
interrupted = false
"""


def one_line_refusal(args: list[str]) -> str:
    """Run ``feeddrive ARGS`` and return its one line on standard error, checking that it was
    refused: exit status 2, nothing on standard output, exactly one non-blank line on standard
    error (the rule for bad input).

    Parameters
    ----------
    args : list of str
        The command line after ``feeddrive``.

    Returns
    -------
    str
        The refusal's line.
    """
    result = RUNNER.invoke(app, args)
    assert result.exit_code == 2, result.output
    assert result.stdout == "", result.stdout
    lines = [s for s in result.stderr.splitlines() if s.strip()]
    assert len(lines) == 1, result.stderr
    return lines[0]
