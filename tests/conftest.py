"""Fixtures for the whole suite."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from feeddrive import registry


def _home(obj: object) -> str:
    """The module that defined ``obj`` (a class, a function or an instance of a class)."""
    return str(getattr(obj, "__module__", None) or type(obj).__module__)


@pytest.fixture(autouse=True)
def _registry_left_as_found() -> Iterator[None]:
    """A law, part or coupling a test registers is gone after it: the registry is global per
    process, and a test that enumerates it (the signal corpus, generated from the registry)
    would otherwise see another test's toy law, depending on which tests a worker ran first.
    Entries the package's own providers register while the test runs stay."""
    before = {group: dict(tab) for group, tab in registry._TABLES.items()}
    yield
    for group, tab in registry._TABLES.items():
        for name in [n for n in tab if n not in before[group]]:
            if not _home(tab[name]).startswith("feeddrive"):
                del tab[name]
        for name, obj in before[group].items():
            tab[name] = obj
