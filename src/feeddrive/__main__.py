"""``feeddrive`` / ``python -m feeddrive``: the CLI entry point.

Kept free of imports so that a Ctrl-C at any moment, even while the CLI is still being
imported, ends with one line and exit status 130 rather than a traceback (issue 12 item 7).

When the command has ended (its outputs written and closed, however it ended), the objects
alive are moved out of the garbage collector's reach (``gc.freeze``): the interpreter's exit
then skips its last collections over numba's and the command's object graph, which cost a
short ``feeddrive simulate`` 0.15–0.17 s CPU of its 0.8 s (issue 21 item 4; measured with
benchmarks/bench_startup.py).  Nothing is lost: files are closed by the code that wrote them,
standard streams are flushed by the interpreter, ``atexit`` handlers still run.
"""

from __future__ import annotations

import gc
import sys

from .exit_codes import INTERRUPTED


def _run_app() -> None:
    from .cli import app_for

    app_for(sys.argv[1:])()  # only the running command's module is imported (issue 21)


def main() -> None:
    from . import _sigint

    _sigint.stop_within_a_step()  # Ctrl-C stops a command's runs within a solver step
    try:
        _run_app()
    except KeyboardInterrupt:
        sys.stderr.write("\ninterrupted\n")
        sys.exit(INTERRUPTED)
    finally:
        gc.freeze()  # a quick exit: no last collection over what the command leaves alive


if __name__ == "__main__":
    main()
