"""The command line's usage errors in the package's one-line form.

click reports a usage error — a value its type cannot parse (``--rtol abc``), an unknown or
missing option — as a usage line, a hint and ``Error: …``: four lines that do not start with
``error:`` (docs/outputs.md: every failure is one line on stderr starting with ``error:``).
:class:`OneLineGroup` is the app's group class: the usage errors raised while it parses a line
or invokes its command leave as :class:`OneLineUsageError`, one line naming the option and the
command's help, exit status 2 as before.  A group or command given no arguments still prints
its help (click's ``NoArgsIsHelpError``)."""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterator
from typing import IO, Any

import typer
from typer.core import TyperGroup

#: click's exceptions as this typer raises them: its own copy of click (typer ≥ 0.24 vendors
#: it as ``typer._click``) or click itself (older typer)
_EXCEPTIONS = sys.modules[typer.BadParameter.__module__]
_CLICK_ERROR: Any = _EXCEPTIONS.ClickException
_USAGE_ERROR: Any = _EXCEPTIONS.UsageError
#: raised for a bare group or command that shows its help (click ≥ 8.2); not a failure
_HELP: Any = getattr(_EXCEPTIONS, "NoArgsIsHelpError", ())


class OneLineUsageError(_CLICK_ERROR):
    """A usage error shown as one ``error:`` line (exit status 2)."""

    exit_code = 2

    def show(self, file: IO[Any] | None = None) -> None:
        typer.echo(f"error: {self.format_message()}", file=file, err=True)


def one_line(error: Any) -> str:
    """The message of ``error`` on one line, with where to read the command's options.

    Parameters
    ----------
    error : click.UsageError
        A usage error (click's class as typer raises it).

    Returns
    -------
    str
        E.g. ``Invalid value for '--rtol': 'abc' is not a valid float. (feeddrive simulate
        --help)``.
    """
    text = " ".join(error.format_message().split())
    ctx = error.ctx
    return f"{text} ({ctx.command_path} --help)" if ctx is not None else text


@contextlib.contextmanager
def _usage_in_one_line() -> Iterator[None]:
    try:
        yield
    except _HELP:
        raise
    except _USAGE_ERROR as error:
        raise OneLineUsageError(one_line(error)) from error


class OneLineGroup(TyperGroup):
    """The app's group: its usage errors in one line (:class:`OneLineUsageError`)."""

    def make_context(self, info_name: str | None, args: list[str],
                     parent: Any = None, **extra: Any) -> Any:
        with _usage_in_one_line():
            return super().make_context(info_name, args, parent, **extra)

    def invoke(self, ctx: Any) -> Any:
        with _usage_in_one_line():
            return super().invoke(ctx)
