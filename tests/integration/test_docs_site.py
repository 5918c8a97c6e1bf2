"""The documentation site (issue 26 item 1) against the code.

The README's test command builds the site (``sphinx-build -W``: warnings are errors, every
gallery example runs) before pytest; these tests read that build.  Run alone without a
build, the build-reading tests skip — except in CI (``CI`` set), where a missing build is a
failure.  The set-up commands are compared wherever they are printed.
"""

from __future__ import annotations

import importlib
import os
import pkgutil
import re
import zlib
from pathlib import Path

import pytest

import feeddrive

ROOT = Path(__file__).resolve().parents[2]
HTML = ROOT / "docs" / "_build" / "html"
EXAMPLES = sorted((ROOT / "docs" / "examples").glob("*.py"))


def _blocks(text: str) -> list[str]:
    return re.findall(r"```bash\n(.*?)\n```", text, flags=re.DOTALL)


def test_setup_commands_are_the_same_everywhere() -> None:
    """README's two set-up commands, as getting-started prints them and as .ci/run runs the
    second (its last line, verbatim)."""
    readme = _blocks((ROOT / "README.md").read_text(encoding="utf-8"))[:2]
    started = _blocks((ROOT / "docs" / "getting-started.md").read_text(encoding="utf-8"))[:2]
    assert readme == started
    ci_last = (ROOT / ".ci" / "run").read_text(encoding="utf-8").strip().splitlines()[-1]
    assert ci_last == readme[1]
    assert "sphinx-build -W --keep-going" in readme[1]
    # the whole suite on both cores (pytest-xdist)
    assert readme[1].endswith("-m pytest -n 2")


def _inventory() -> dict[str, set[str]]:
    """objects.inv of the built site: {role ("py:function", "std:label", …): {names}}."""
    path = HTML / "objects.inv"
    if not path.exists():
        if os.environ.get("CI"):
            pytest.fail("docs/_build/html is missing: the README's test command builds it")
        pytest.skip("the site is not built (README: sphinx-build … docs docs/_build/html)")
    raw = path.read_bytes()
    body = zlib.decompress(raw.split(b"\n", 4)[4]).decode("utf-8")
    out: dict[str, set[str]] = {}
    for line in body.splitlines():
        m = re.match(r"(.+?)\s+(\S+:\S+)\s+(-?\d+)\s+(\S+)\s+(.*)", line)
        if m:
            out.setdefault(m.group(2), set()).add(m.group(1))
    return out


def _public_modules() -> dict[str, list[str]]:
    """Every feeddrive module with an ``__all__`` (the CLI is the CLI reference's)."""
    found = {"feeddrive": list(feeddrive.__all__)}
    for info in pkgutil.walk_packages(feeddrive.__path__, "feeddrive."):
        if info.name.startswith("feeddrive.cli"):
            continue
        module = importlib.import_module(info.name)
        if hasattr(module, "__all__"):
            found[info.name] = list(module.__all__)
    return found


def test_every_public_name_is_in_the_reference() -> None:
    """Every name of every public ``__all__`` has an entry: under its module, or under
    another public module (or package) that exports the same object — a re-exported name is
    documented once (``feeddrive.parameters.ParameterError`` is ``feeddrive.ParameterError``)."""
    inv = _inventory()
    py = set().union(*(names for role, names in inv.items() if role.startswith("py:")))
    public = _public_modules()
    modules = {name: importlib.import_module(name) for name in public}
    missing = []
    for module, names in public.items():
        for name in names:
            obj = getattr(modules[module], name)
            homes = [m for m, mod in modules.items()
                     if name in public[m] and getattr(mod, name, None) is obj]
            if not any(f"{home}.{name}" in py for home in homes):
                missing.append(f"{module}.{name}")
    assert not missing, missing
    # the reference is no empty shell: the everyday API's classes and functions by kind
    assert {"feeddrive.Simulation", "feeddrive.Result"} <= inv["py:class"]
    assert {"feeddrive.simulate", "feeddrive.preset"} <= inv["py:function"]
    assert {"feeddrive.model.friction.stribeck", "feeddrive.sweep"} <= inv["py:module"]


def test_every_cli_command_is_in_the_reference() -> None:
    import sys

    sys.path.insert(0, str(ROOT / "docs" / "_ext"))
    from feeddrive_docs import commands

    labels = _inventory()["std:label"]
    paths = commands()
    assert {("simulate",), ("identify", "static"), ("sweep",), ("map",)} <= set(paths)
    missing = [p for p in paths if f"cli-{'-'.join(p)}" not in labels]
    assert not missing, missing
    page = (HTML / "cli.html").read_text(encoding="utf-8")
    assert "--table-speed" in page and "[mm/s]" in page  # --help text, units kept


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_every_gallery_example_ran_in_the_build(script: Path) -> None:
    _inventory()  # skips or fails as above when there is no build
    page = HTML / "auto_examples" / f"{script.stem}.html"
    assert page.exists(), page
    text = page.read_text(encoding="utf-8")
    assert "Total running time of the script" in text
    assert re.search(r'<img [^>]*src="[^"]*sphx_glr_' + script.stem, text), \
        "the example drew no figure"


def test_gallery_covers_the_brief() -> None:
    """Issue 26: a paper figure, a drive from parts, a friction fit from a measured file, a
    sweep map, linear analysis, and the FMU export (``feeddrive export fmu``)."""
    stems = " ".join(p.stem for p in EXAMPLES)
    for topic in ("fig6", "custom_drive", "identify", "sweep_map", "linear"):
        assert topic in stems, topic
    from typer.main import get_command

    from feeddrive.cli import app

    assert "export" in get_command(app).commands  # type: ignore[attr-defined]
    assert "fmu_export" in stems
