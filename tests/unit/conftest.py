"""Fixtures of the unit tests shared by more than one file."""

from __future__ import annotations

from pathlib import Path

import pytest

from feeddrive.backends import c_cache


@pytest.fixture
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty C cache folder of the test's own (``$FEEDDRIVE_C_CACHE``), the cache's counts
    set to zero (tests/unit/test_c_cache.py, test_c_cache_damage.py)."""
    folder = tmp_path / "cache"
    monkeypatch.setenv(c_cache.CACHE_ENV, str(folder))
    monkeypatch.setattr(c_cache, "STATS", {"compiles": 0, "hits": 0})
    return folder
