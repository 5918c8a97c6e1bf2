"""Shared fixtures of the integration tests."""

from __future__ import annotations

import signal
from typing import Any

import pytest


@pytest.fixture(scope="session")
def interruptible() -> dict[str, Any]:
    """``subprocess.Popen`` keyword arguments that let a child feeddrive see Ctrl-C as a user's
    terminal sends it: a test run started as a background job inherits SIGINT *ignored*, and
    Python keeps an ignored SIGINT ignored, so a SIGINT sent to the child would do nothing."""
    return {"preexec_fn": lambda: signal.signal(signal.SIGINT, signal.SIG_DFL)}
