"""``feeddrive`` / ``python -m feeddrive``: the CLI entry point.

Kept free of imports so that a Ctrl-C at any moment, even while the CLI is still being
imported, ends with one line and exit status 130 rather than a traceback (issue 12 item 7).
"""

from __future__ import annotations

import sys

from .exit_codes import INTERRUPTED


def _run_app() -> None:
    from .cli import app_for

    app_for(sys.argv[1:])()  # only the running command's module is imported (issue 21)


def main() -> None:
    try:
        _run_app()
    except KeyboardInterrupt:
        sys.stderr.write("\ninterrupted\n")
        sys.exit(INTERRUPTED)


if __name__ == "__main__":
    main()
