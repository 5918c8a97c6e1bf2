"""What the command-line tests share: a refusal read as the one line it must be."""

from __future__ import annotations

from typer.testing import CliRunner

from feeddrive.cli import app

RUNNER = CliRunner()


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
