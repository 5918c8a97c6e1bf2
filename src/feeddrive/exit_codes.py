"""Exit status of an interrupted command; a leaf module that imports nothing, so that
:mod:`feeddrive.__main__` can read it before anything else is imported and the CLI commands
can share it without importing the entry point."""

INTERRUPTED = 130  # 128 + SIGINT, the shell convention
