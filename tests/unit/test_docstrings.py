"""Docstrings are part of the API (issue 19 item 8; python-control's docstrings_test.py):
every public name of ``feeddrive`` — functions, classes and their public methods — and every
registered friction law and mechanism passes ``numpydoc.validate`` for documented parameters
(PR01, PR02), a Returns section (RT01) and a docstring at all (GL08); every Parameters entry
of a physical quantity states its unit in brackets (``[m/s]``; ``[-]`` when dimensionless);
a law or mechanism from a publication carries a References section."""

from __future__ import annotations

import importlib
import inspect
import re

import pytest
from numpydoc.docscrape import NumpyDocString
from numpydoc.validate import validate

import feeddrive as fd
from feeddrive import registry

CHECKED = ("PR01", "PR02", "RT01", "GL08")
UNIT = re.compile(r"\[[^\]]+\]")
# types whose values are physical quantities (or arrays of them) unless stated otherwise
PHYSICAL_TYPE = re.compile(r"\b(float|ndarray|array)\b")


def _members(owner: type, prefix: str) -> list[str]:
    names = []
    for name, value in vars(owner).items():
        if name.startswith("_"):
            continue
        if inspect.isfunction(value) or isinstance(value, classmethod | staticmethod
                                                   | property):
            names.append(f"{prefix}.{name}")
    return names


def public_api() -> list[str]:
    """Import paths of the public names and of their public methods."""
    paths = []
    for name in fd.__all__:
        obj = getattr(fd, name)
        if inspect.ismodule(obj) or name == "__version__":
            continue
        path = f"{obj.__module__}.{obj.__qualname__}"
        paths.append(path)
        if inspect.isclass(obj):
            paths += _members(obj, path)
    for group in (registry.FRICTION_LAWS, registry.MECHANISMS):
        for obj in registry.table(group).values():
            cls = obj if inspect.isclass(obj) else type(obj)
            if cls.__module__.startswith("feeddrive."):  # the package's own parts
                paths.append(f"{cls.__module__}.{cls.__qualname__}")
    return sorted(set(paths))


API = public_api()


def test_the_public_api_is_collected():
    """The list covers the top-level names, their methods and the registered parts."""
    assert "feeddrive.engine.simulate.simulate" in API
    assert "feeddrive.engine.result.Result.summary" in API
    assert "feeddrive.model.friction.lugre.LuGre" in API
    assert "feeddrive.model.mechanisms.ball_screw.BallScrewDrive" in API or any(
        p.startswith("feeddrive.model.mechanisms.ball_screw.") for p in API)


@pytest.mark.parametrize("path", API)
def test_numpydoc_sections(path):
    errors = [f"{code}: {msg}" for code, msg in validate(path)["errors"] if code in CHECKED]
    assert errors == [], path


def _object(path: str):
    parts = path.split(".")
    for cut in range(len(parts), 0, -1):  # the longest importable module prefix
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for part in parts[cut:]:
            obj = getattr(obj, part)
        return obj
    raise ImportError(path)


@pytest.mark.parametrize("path", API)
def test_physical_parameters_give_their_unit(path):
    doc = NumpyDocString(inspect.getdoc(_object(path)) or "")
    missing = [p.name for p in doc["Parameters"]
               if PHYSICAL_TYPE.search(p.type) and not UNIT.search(" ".join(p.desc))]
    assert missing == [], f"{path}: no [unit] in the description of {missing}"


@pytest.mark.parametrize("group", [registry.FRICTION_LAWS, registry.MECHANISMS])
def test_published_parts_cite_their_source(group):
    for obj in registry.table(group).values():
        cls = obj if inspect.isclass(obj) else type(obj)
        if not cls.__module__.startswith("feeddrive.") or not getattr(cls, "published", True):
            continue
        doc = NumpyDocString(inspect.getdoc(cls) or "")
        assert doc["References"], f"{cls.__qualname__}: no References section"


def test_the_unit_check_can_fail():
    doc = NumpyDocString("Summary.\n\nParameters\n----------\nspeed : float\n    The speed.\n")
    assert [p.name for p in doc["Parameters"]
            if PHYSICAL_TYPE.search(p.type) and not UNIT.search(" ".join(p.desc))] == ["speed"]
