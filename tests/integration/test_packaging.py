"""Packaging metadata a researcher cites and a packager reads (issue 26 item 2).

The wheel and sdist themselves are built and smoke-tested in fresh virtual environments by
``.ci/package`` (run by ``.ci/run``); these are the cheap checks of what they are built from.
"""

from __future__ import annotations

import json
import re
import tomllib
from pathlib import Path

import jsonschema
import yaml

import feeddrive

ROOT = Path(__file__).resolve().parents[2]
# the Citation File Format's own schema, version 1.2.0 (citation-file-format/
# citation-file-format, schema.json; as shipped by cffconvert 2.0.0)
CFF_SCHEMA = ROOT / "tests" / "data" / "citation-file-format-1.2.0.schema.json"


def _project() -> dict:
    with open(ROOT / "pyproject.toml", "rb") as f:
        return tomllib.load(f)


def test_citation_cff_is_valid_cff_1_2_and_cites_wang2021() -> None:
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    schema = json.loads(CFF_SCHEMA.read_text(encoding="utf-8"))
    jsonschema.validate(cff, schema)
    assert cff["cff-version"] == "1.2.0"
    assert cff["version"] == feeddrive.__version__
    assert " AND ".join(cff["license"]) == _project()["project"]["license"]
    (paper,) = [r for r in cff["references"] if r.get("doi") == "10.5194/ms-12-791-2021"]
    assert [a["family-names"] for a in paper["authors"]] == ["Wang", "Feng", "Yang", "Jin"]
    assert (paper["journal"], paper["volume"], paper["start"], paper["end"], paper["year"]) \
        == ("Mechanical Sciences", 12, 791, 800, 2021)


def test_cff_schema_refuses_a_broken_file() -> None:
    """The schema check can fail: a CFF without its required ``authors`` is refused."""
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    del cff["authors"]
    schema = json.loads(CFF_SCHEMA.read_text(encoding="utf-8"))
    try:
        jsonschema.validate(cff, schema)
    except jsonschema.ValidationError as err:
        assert "authors" in str(err)
    else:
        raise AssertionError("a CFF without authors passed the schema")


def test_pep639_license_and_metadata() -> None:
    project = _project()
    meta = project["project"]
    # an SPDX expression, PEP 639: the package's MIT and the BSD-2-Clause of the FMI
    # standard's headers it ships (src/feeddrive/fmu/include, copied into every FMU)
    assert meta["license"] == "MIT AND BSD-2-Clause"
    assert meta["license-files"] == ["LICENSE", "src/feeddrive/fmu/include/LICENSE.txt"]
    assert (ROOT / "LICENSE").read_text(encoding="utf-8").startswith("MIT License")
    headers = ROOT / "src" / "feeddrive" / "fmu" / "include"
    bsd = (headers / "LICENSE.txt").read_text(encoding="utf-8")
    for header in headers.glob("*.h"):  # each header states the licence the file names
        text = header.read_text(encoding="utf-8")
        assert "2-Clause BSD License" in text and header.name in bsd, header.name
        body = text.split("Redistribution and use", 1)[1].split("----", 1)[0]
        assert " ".join(("Redistribution and use" + body).split()) in " ".join(bsd.split())
    # setuptools reads PEP 639 metadata from version 77 on
    (setuptools,) = [r for r in project["build-system"]["requires"]
                     if r.startswith("setuptools")]
    assert re.fullmatch(r"setuptools>=(\d+).*", setuptools)
    assert int(re.fullmatch(r"setuptools>=(\d+).*", setuptools).group(1)) >= 77
    assert meta["authors"] and meta["classifiers"] and meta["urls"]
    # PEP 639: no License :: classifier beside a license expression
    assert not [c for c in meta["classifiers"] if c.startswith("License ::")]
    requires = meta["requires-python"].removeprefix(">=")
    assert f"Programming Language :: Python :: {requires}" in meta["classifiers"]


def test_changelog_follows_keep_a_changelog() -> None:
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    assert text.startswith("# Changelog")
    assert "Keep a Changelog" in text
    versions = re.findall(r"^## \[([^\]]+)\]", text, flags=re.MULTILINE)
    assert versions[0] == "Unreleased"
    kinds = {"Added", "Changed", "Deprecated", "Removed", "Fixed", "Security"}
    sections = re.findall(r"^### (.+)$", text, flags=re.MULTILINE)
    assert sections and set(sections) <= kinds
