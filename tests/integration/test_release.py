"""Issue 41 item 13: ready for PyPI and conda-forge — one version everywhere (0.2.0 for this
release), README links that work on PyPI, classifiers naming the Python the suite runs on.
(`twine check --strict` of the built wheel and sdist runs in `.ci/package`.)"""

from __future__ import annotations

import re
import sys
import tomllib
from pathlib import Path

import yaml

import feeddrive
from feeddrive import _compat

ROOT = Path(__file__).resolve().parents[2]
PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]


def test_one_version_everywhere_and_the_policy_states_it() -> None:
    version = PROJECT["version"]
    assert version == feeddrive.__version__ == "0.2.0"
    assert yaml.safe_load((ROOT / "CITATION.cff").read_text("utf-8"))["version"] == version
    assert f"version = {{{version}}}" in (ROOT / "docs" / "citing.md").read_text("utf-8")
    changelog = (ROOT / "CHANGELOG.md").read_text("utf-8")
    assert f"the first release is\n**{version}**" in changelog and "`v<version>`" in changelog
    # the moved names of 7831378 go one minor release after this one
    major, minor, _ = (int(x) for x in version.split("."))
    assert _compat.REMOVAL == f"{major}.{minor + 1}.0"


def test_readme_links_work_on_pypi() -> None:
    """PyPI renders the README without the repository: a relative link there is broken.
    Every link is absolute; every path the README names exists (and travels in the sdist)."""
    text = (ROOT / "README.md").read_text("utf-8")
    targets = re.findall(r"\]\(([^)]+)\)", text) + re.findall(r'href="([^"]+)"', text)
    assert all(re.match(r"https://", t) for t in targets), targets
    paths = set(re.findall(r"`((?:docs|benchmarks|src|examples)/[\w./-]+\.(?:md|py|toml))`",
                           text))
    assert len(paths) >= 10
    assert [p for p in paths if not (ROOT / p).is_file()] == []
    manifest = (ROOT / "MANIFEST.in").read_text("utf-8")
    assert "recursive-include docs *.md" in manifest and "include benchmarks/README.md" in \
        manifest


def test_classifiers_name_the_python_the_suite_runs_on() -> None:
    pythons = {c.rsplit(" :: ", 1)[1] for c in PROJECT["classifiers"]
               if re.fullmatch(r"Programming Language :: Python :: 3\.\d+", c)}
    running = f"{sys.version_info.major}.{sys.version_info.minor}"
    assert running in pythons, (running, pythons)
    assert PROJECT["requires-python"] == f">={min(pythons, key=lambda v: int(v[2:]))}"
