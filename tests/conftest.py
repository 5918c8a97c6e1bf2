"""Fixtures for the whole suite."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from feeddrive import registry


def _one_command_per_app() -> None:
    """typer's test runner builds the whole click command tree from the app at every
    ``invoke`` (each command's signature and type hints: ≈ 45 ms for feeddrive's app, measured
    2026-12-07, beside a refusal that takes a few ms); the ``feeddrive`` process builds it
    once.  The suite does the same: one build per app object, reused by every invoke."""
    import typer.testing

    build = getattr(typer.testing, "_get_command", None)
    if build is None or getattr(build, "one_per_app", False):
        return
    built: dict[int, tuple[Any, Any]] = {}

    def command(app: Any) -> Any:
        kept = built.get(id(app))
        if kept is None or kept[0] is not app:
            kept = built[id(app)] = (app, build(app))
        return kept[1]

    command.one_per_app = True  # type: ignore[attr-defined]
    typer.testing._get_command = command  # type: ignore[attr-defined]


_one_command_per_app()

#: the rounding-level perturbations of :func:`ddfs_counts`: table positions 0.4·(1 + k·1e-12) m
PERTURBATIONS = tuple(range(-3, 4))


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


@pytest.fixture(scope="session")
def ddfs_counts() -> dict[str, list[dict[str, Any]]]:
    """``solver_stats`` of bench_engine.py's ``ddfs_0p5_vn16`` run (``wang2021`` DDFS, table
    0.5 mm/s, hollow motor 16 mm/s, 10 s, the default settings but the Rosenbrock method) at
    table positions 0.4·(1 + k·1e-12) m, k in :data:`PERTURBATIONS`, per Rosenbrock method.

    A DDFS run's counts are not a property of the method alone: where a run hands over between
    DOPRI5 and the Rosenbrock method moves with the last bits of its arithmetic.  Measured on
    the tree of f191cdd (2026-12-06): RODAS5P's right-hand sides 19 248–26 101 and steps
    2 275–3 562 over these seven positions, RODAS4's 46 265–49 044 and 7 343–7 880, while the
    work weighed as the switch weighs it (steps + 5.5 × Rosenbrock steps) stayed within
    7 309–8 226.  So the tests that bound counts bound their medians over these runs."""
    import feeddrive as fd

    profile = fd.ConstantSpeed(0.5e-3, 16e-3)
    return {rb: [fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "ddfs", 0.4 * (1 + k * 1e-12)),
                             profile, 10.0, options=fd.SolverOptions(rosenbrock=rb)).solver_stats
                 for k in PERTURBATIONS]
            for rb in ("rodas4", "rodas5p")}
