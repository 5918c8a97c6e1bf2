"""Docstrings are part of the API (issue 19 item 8; python-control's docstrings_test.py).

The public API is enumerated, not listed: every module of ``feeddrive`` whose dotted path has
no part starting with ``_``, and in it every function and class *defined there* whose name does
not start with ``_``, with the public methods and properties of those classes (docs/docstrings.md
states the rule and its two exclusions: the Typer command functions of ``feeddrive.cli`` and
methods that override a method of a base class from outside ``feeddrive``).  Each of them must

- pass ``numpydoc.validate`` for PR01, PR02, RT01 and GL08 (numba kernels and ``lru_cache``
  wrappers are validated through the Python function they wrap);
- give a unit in brackets (``[m/s]``; ``[-]`` when dimensionless) in the description of every
  Parameters entry typed ``float``, ``complex`` or an array;
- carry a References section when it is a published model or method: a registered friction law
  or mechanism (unless its class says ``published = False``), a name in ``PUBLISHED`` below, or
  any docstring that cites a source in its text (``Wang2021``, ``et al.``).

Names that do not comply yet are listed in ``docstring_backlog.txt`` beside this file.  The list
may only shrink: a name not on it that breaks a rule fails, and so does a name on it that now
complies or no longer exists (delete its line).
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
import types
from functools import cache
from pathlib import Path

import pytest
from numpydoc.docscrape import NumpyDocString
from numpydoc.validate import get_doc_object, validate

import feeddrive as fd
from feeddrive import registry

CHECKED = ("PR01", "PR02", "RT01", "GL08")
# ``[N/m]``; not a citation ``[1]_`` nor an index ``P[o + k]``
UNIT = re.compile(r"(?<![\w\]])\[[^\]\s][^\]]*\](?!_)")
# types whose values are physical quantities (or arrays of them) unless stated otherwise
PHYSICAL_TYPE = re.compile(r"\b(float|complex|ndarray|array|array_like)\b")
COUNTS = re.compile(r"\bof (int|bool|str)\b")  # ``numpy.ndarray of int``: indices, flags
CITES = re.compile(r"Wang2021|et al\.")
# published methods that are not registered parts (those are found through the registry)
PUBLISHED = (
    "feeddrive.solvers.dopri5.integrate",  # Dormand & Prince 1980
    "feeddrive.solvers.switching.integrate",  # DOPRI5 + RODAS4 (Hairer & Wanner)
    "feeddrive.solvers.steps.explicit_step_source",  # the embedded Runge-Kutta step
    "feeddrive.solvers.steps.rosenbrock_step_source",  # Hairer & Wanner, Solving ODEs II
    "feeddrive.model.friction.lugre.force",  # Canudas de Wit et al. 1995
    "feeddrive.model.friction.lugre.bristle_rate",
    "feeddrive.model.friction.lugre.stribeck_magnitude",
    "feeddrive.model.friction.gms.gms_kernel",  # Al-Bender, Lampaert & Swevers 2005
    "feeddrive.model.friction.dahl.dahl_kernel",  # Dahl 1968
    "feeddrive.model.mechanisms.ball_screw_stiffness.screw_axial_stiffness",  # Wang2021 Eq. 4
    "feeddrive.model.mechanisms.ball_screw_stiffness.equivalent_stiffness_chain",  # Eqs. 2-5
)
BACKLOG_FILE = Path(__file__).with_name("docstring_backlog.txt")


def _module_names(package: types.ModuleType) -> list[str]:
    names = [package.__name__]
    for info in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.append(info.name)
    return sorted(names)


def _cli_commands() -> set[object]:
    """The callbacks the Typer app registers: their docstring is the ``--help`` text."""
    from feeddrive.cli import app

    found: set[object] = set()
    pending = [app]
    while pending:
        typer_app = pending.pop()
        found |= {c.callback for c in typer_app.registered_commands}
        found |= {g.typer_instance.registered_callback.callback
                  for g in typer_app.registered_groups
                  if g.typer_instance.registered_callback is not None}
        pending += [g.typer_instance for g in typer_app.registered_groups]
    return found


def _overrides_foreign(cls: type, name: str) -> bool:
    """True when ``name`` overrides a method of a base class from outside ``feeddrive``."""
    return any(name in vars(base) for base in cls.__mro__[1:]
               if not base.__module__.startswith("feeddrive"))


def _methods(cls: type, path: str) -> list[str]:
    names = []
    for name, value in vars(cls).items():
        if name.startswith("_") or _overrides_foreign(cls, name):
            continue
        if inspect.isfunction(value) or isinstance(value, classmethod | staticmethod
                                                   | property):
            names.append(f"{path}.{name}")
    return names


def _is_definition(value: object) -> bool:
    return (inspect.isfunction(value) or inspect.isclass(value)
            or hasattr(value, "py_func") or hasattr(value, "__wrapped__"))


def public_api(package: types.ModuleType = fd) -> list[str]:
    """Import paths of every public function, class and method of ``package``."""
    commands = _cli_commands() if package is fd else set()
    paths = []
    for module_name in _module_names(package):
        module = importlib.import_module(module_name)
        paths.append(module_name)
        for name, value in vars(module).items():
            if name.startswith("_") or not _is_definition(value):
                continue
            if getattr(value, "__module__", None) != module_name or value in commands:
                continue
            path = f"{module_name}.{name}"
            paths.append(path)
            if inspect.isclass(value):
                paths += _methods(value, path)
    return sorted(set(paths))


def _object(path: str) -> object:
    parts = path.split(".")
    for cut in range(len(parts), 0, -1):  # the longest importable module prefix
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for part in parts[cut:]:
            obj = inspect.getattr_static(obj, part) if inspect.isclass(obj) else getattr(
                obj, part)
        return obj
    raise ImportError(path)


def _plain(obj: object) -> object:
    """The Python function behind a numba dispatcher or a ``functools`` wrapper."""
    if isinstance(obj, classmethod | staticmethod):
        obj = obj.__func__
    obj = getattr(obj, "py_func", obj)
    while hasattr(obj, "__wrapped__"):
        obj = obj.__wrapped__
    return obj


@cache
def _published() -> frozenset[str]:
    paths = set(PUBLISHED)
    for group in (registry.FRICTION_LAWS, registry.MECHANISMS):
        for obj in registry.table(group).values():
            cls = obj if inspect.isclass(obj) else type(obj)
            if cls.__module__.startswith("feeddrive.") and getattr(cls, "published", True):
                paths.add(f"{cls.__module__}.{cls.__qualname__}")
    return frozenset(paths)


def problems(path: str, obj: object, published: bool = False) -> list[str]:
    """Every rule the docstring of ``obj`` (found at ``path``) breaks, one line each."""
    obj = _plain(obj)
    found = []
    if inspect.ismodule(obj):
        # a module introduces its topic; its functions and classes carry the sections
        return [] if inspect.getdoc(obj) else ["GL08: The module does not have a docstring"]
    else:
        # an override without a docstring of its own inherits its feeddrive base's (as
        # inspect.getdoc and Sphinx do): it is checked against that one
        inherited = not getattr(obj, "__doc__", None) and bool(inspect.getdoc(obj))
        found += [f"{code}: {message}" for code, message in
                  validate(get_doc_object(obj))["errors"]
                  if code in CHECKED and not (code == "GL08" and inherited)]
    text = inspect.getdoc(obj) or ""
    try:
        doc = NumpyDocString(text)
    except Exception as error:  # a malformed section is a defect of its own
        return [*found, f"unparsable docstring: {error}"]
    missing = [p.name for p in doc["Parameters"]
               if PHYSICAL_TYPE.search(p.type) and not COUNTS.search(p.type)
               and not UNIT.search(" ".join(p.desc))]
    if missing:
        found.append(f"no [unit] in the description of {missing}")
    body = " ".join(doc["Summary"] + doc["Extended Summary"] + doc["Notes"])
    if (published or CITES.search(body)) and not doc["References"]:
        found.append("a published model or method (or one that cites a source) "
                     "without a References section")
    return found


API = public_api()
BACKLOG = [line.split("#")[0].strip() for line in BACKLOG_FILE.read_text().splitlines()
           if line.split("#")[0].strip()]


def _problems_at(path: str) -> list[str]:
    return problems(path, _object(path), path in _published())


def test_the_public_api_is_collected():
    """The walk finds functions, classes, methods, kernels and parts of every layer."""
    for path in ("feeddrive.engine.simulate.simulate", "feeddrive.engine.result.Result.summary",
                 "feeddrive.model.friction.lugre.LuGre", "feeddrive.model.friction.lugre.force",
                 "feeddrive.analysis.cycle_verdict", "feeddrive.sweep.design"):
        assert path in API
    assert not any(".cli." in p and p.endswith("_command") for p in API)  # --help text
    assert not any("._" in p for p in API)
    assert len(API) > 700


@pytest.mark.parametrize("path", sorted(set(API) - set(BACKLOG)))
def test_docstring(path):
    assert _problems_at(path) == [], path


def test_every_published_name_exists():
    """A name in ``PUBLISHED`` that moved would silently escape the References rule."""
    assert [p for p in PUBLISHED if p not in API] == [], "update PUBLISHED to the new paths"


def test_the_backlog_only_shrinks():
    """A backlog name that complies now, or is gone, must leave the list."""
    assert len(BACKLOG) == len(set(BACKLOG)), "duplicate lines in the backlog"
    gone = [p for p in BACKLOG if p not in API]
    fixed = [p for p in BACKLOG if p in API and not _problems_at(p)]
    assert gone == [] and fixed == [], (
        f"delete from {BACKLOG_FILE.name}: gone {gone}, now documented {fixed}")


def test_the_rules_can_fail(tmp_path, monkeypatch):
    """A synthetic module: an undocumented function, one without units, Returns or
    References, and a fully documented one that passes."""
    (tmp_path / "fd_synthetic").mkdir()
    (tmp_path / "fd_synthetic" / "__init__.py").write_text('"""Synthetic."""\n')
    (tmp_path / "fd_synthetic" / "laws.py").write_text('''"""Synthetic laws."""

def bare(speed):
    return speed


def unitless(speed: float) -> float:
    """Twice the speed.

    Parameters
    ----------
    speed : float
        The speed.
    """
    return 2 * speed


def indexed(speed: float) -> float:
    """The speed read from the packed vector.

    Parameters
    ----------
    speed : float
        Taken from P[o + 2], not a unit.

    Returns
    -------
    float
        The speed [m/s].
    """
    return speed


def cited(speed: float) -> float:
    """The Stribeck curve of Wang2021 Eq. (9).

    Parameters
    ----------
    speed : float
        Sliding speed [m/s].

    Returns
    -------
    float
        Friction force [N].
    """
    return speed


def good(speed: float, count: int) -> float:
    """Sliding speed scaled by a count.

    Parameters
    ----------
    speed : float
        Sliding speed [m/s].
    count : int
        How many times.

    Returns
    -------
    float
        The product [m/s].

    References
    ----------
    .. [1] Nobody, "Nothing", 2000.
    """
    return speed * count


def _hidden(speed):
    return speed
''')
    monkeypatch.syspath_prepend(str(tmp_path))
    package = importlib.import_module("fd_synthetic")
    paths = public_api(package)
    assert paths == ["fd_synthetic", "fd_synthetic.laws", "fd_synthetic.laws.bare",
                     "fd_synthetic.laws.cited", "fd_synthetic.laws.good",
                     "fd_synthetic.laws.indexed", "fd_synthetic.laws.unitless"]
    found = {p: " ".join(problems(p, _object(p))) for p in paths}
    assert "GL08" in found["fd_synthetic.laws.bare"]
    assert "PR01" not in found["fd_synthetic.laws.unitless"]
    assert "RT01" in found["fd_synthetic.laws.unitless"]
    assert "no [unit]" in found["fd_synthetic.laws.unitless"]
    assert "no [unit]" in found["fd_synthetic.laws.indexed"]  # an index is not a unit
    assert "References" in found["fd_synthetic.laws.cited"]
    assert found["fd_synthetic.laws.good"] == ""
    bare = _object("fd_synthetic.laws.bare")
    assert "References" in " ".join(problems("fd_synthetic.laws.bare", bare, published=True))


def test_the_docs_state_the_rules():
    """docs/docstrings.md names the checked codes and the exclusions the walk applies."""
    page = (Path(__file__).parents[2] / "docs" / "docstrings.md").read_text()
    for code in CHECKED:
        assert code in page
    for phrase in ("Typer command", "`_`", "References", "[-]", "docstring_backlog.txt"):
        assert phrase in page, phrase


def _update_backlog() -> None:
    """Rewrite the backlog: drop the names that comply or are gone, add the failing ones.

    For merging code written before these rules (the layout moves renamed every root module);
    new code is documented instead.  Prints what it added, to be named in the merge commit.
    """
    failing = [p for p in API if _problems_at(p)]
    added = sorted(set(failing) - set(BACKLOG))
    header = [line for line in BACKLOG_FILE.read_text().splitlines() if line.startswith("#")]
    BACKLOG_FILE.write_text("\n".join([*header, *failing]) + "\n")
    print(f"{len(API)} public names, {len(failing)} in the backlog "
          f"({len(BACKLOG) - len(set(BACKLOG) & set(failing))} removed, {len(added)} added)")
    for p in added:
        print(f"  added {p}: {'; '.join(_problems_at(p))}")


if __name__ == "__main__":
    import sys

    if sys.argv[1:] != ["--update-backlog"]:
        sys.exit("usage: python tests/unit/test_docstrings.py --update-backlog")
    _update_backlog()
