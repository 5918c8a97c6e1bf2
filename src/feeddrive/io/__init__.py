"""Files in and out: where an output may be written (:mod:`~feeddrive.io.outputs`), the result
writers (:mod:`~feeddrive.io.results`), the measured-data readers (:mod:`~feeddrive.io.measured`)
and the checked JSON store of computed results (:mod:`~feeddrive.io.json_store`)."""

from __future__ import annotations

from typing import Any


def __getattr__(name: str) -> Any:
    """Names that moved from here before 0.2.0: importable until 0.3.0, with a
    DeprecationWarning naming their new place (:mod:`feeddrive._compat`)."""
    from .. import _compat

    return _compat.moved(__name__, name)
