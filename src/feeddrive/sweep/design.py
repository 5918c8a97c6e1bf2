"""Sweep configurations (TOML) and their designs: grid, random, Latin hypercube.

A configuration names a base parameter set, the axes to vary and the quantity computed at each
point (:mod:`.quantities`).  Everything a user can get wrong is checked by
:func:`load_config` / :meth:`SweepConfig.points` *before* any simulation: each refusal is a
:class:`~feeddrive.parameters.ParameterError` naming the configuration key
(``axes."friction.screw.positive.static_force"``), the value and what was expected.

A ``[solver]`` table gives integrator settings (docs/parameters.md, "[solver]"): over the base
parameter file's own table, under the command line's (and the API's) settings.

Axis units: ``table_position`` [mm], ``nut_speed`` and ``table_speed`` [mm/s] (the CLI's
units, converted to SI here, once); a parameter named by its dotted path takes the parameter
file's SI unit, or a factor on the base value with ``relative = true``.  ``drive`` and
``preset`` take names.  A ``*`` in a parameter path (``friction.*.*.static_force``) expands to
one axis per matching numeric parameter, each varied on its own (relative only).
"""

from __future__ import annotations

import fnmatch
import hashlib
import itertools
import math
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from .. import units
from ..parameters import DriveParameters, ParameterError, dumps, load, preset
from ..parameters.components import solver_over, solver_table
from ..parameters.toml_io import read_toml_file, table_applied, to_dict
from ..parameters.validation import TABLE_BASIS_NOTE, path_unit_label
from .quantities import QuantitySettings

DESIGNS = ("grid", "random", "lhs")
#: axes that are not parameters of the set: name → (unit in the configuration, SI factor)
SPECIAL_AXES: dict[str, tuple[str, float]] = {
    "drive": ("", 1.0), "preset": ("", 1.0),
    "table_position": ("mm", units.MM), "nut_speed": ("mm/s", units.MM_PER_S),
    "table_speed": ("mm/s", units.MM_PER_S),
}
def _drives() -> tuple[str, ...]:
    """The registered drives (a sweep runs any topology)."""
    from ..model.mechanisms import drive_names

    return drive_names()


def _no_nut(drive: str) -> bool:
    """Whether ``drive`` follows no nut speed (its topology says: the CDFS holds its nut, a
    linear motor has none): its nut speed is 0 whatever an axis says, so those points share
    one stored result.  An unknown drive counts as driving none (it is refused later)."""
    from ..model.mechanisms import drive_names, mechanism

    return drive not in drive_names() or "nut" not in mechanism(drive).followed_references(drive)


def _ignored(drive: str) -> tuple[str, ...]:
    """The special axes ``drive``'s model does not read (its topology says): ``nut_speed``
    on a drive that drives no nut (:func:`_no_nut`), ``table_position`` on one whose model
    does not depend on where the table starts (the linear motor, the rack and pinion:
    ``Mechanism.uses_table_position``; its DriveSystem refuses a position other than the
    default, session 30).  Those points share one stored result.  An unknown drive reads
    neither (it is refused later)."""
    from ..model.mechanisms import drive_names, mechanism

    no_position = drive not in drive_names() or not mechanism(drive).uses_table_position
    return (*(("nut_speed",) if _no_nut(drive) else ()),
            *(("table_position",) if no_position else ()))


#: the integrator settings' table, as a parameter file's (docs/parameters.md, "[solver]")
SOLVER_KEY = "solver"
_TOP_KEYS = ("name", "preset", "params", "drive", "table_position", "nut_speed", "store",
             "design", "quantity", "axes", "map", SOLVER_KEY)
_AXIS_KEYS = ("values", "low", "high", "points", "scale", "relative")
#: most design points of one sweep (grid points or samples), refused from the counts alone
MAX_POINTS = 1_000_000
#: longest sweep name [characters]; a name is also a file name (NAME.sqlite)
MAX_NAME = 100


def _refuse(key: str, value: object, message: str) -> ParameterError:
    return ParameterError(key, value, message)


@dataclass(frozen=True)
class Axis:
    """One swept name and how its values are drawn.

    ``values``: explicit values (grid: all of them; random / LHS: drawn among them).
    ``low``/``high``: a continuous range in the configuration's unit; ``points`` values on a
    grid (``scale`` ``linear`` or ``log``); random and LHS draw uniformly (log-uniformly).
    ``relative``: the values are factors on the base parameter value.

    Parameters
    ----------
    name : str
        The swept name: a parameter path (``friction.screw.bristle_stiffness``) or a special
        axis (``table_speed``, ``table_position``, ``nut_speed``, ``drive``, ``preset``).
    values : tuple, optional
        Explicit values, in the configuration's unit.
    low : float, optional
        Lower end of a continuous range [configuration unit of the axis].
    high : float, optional
        Upper end of the range [configuration unit of the axis].
    points : int, optional
        Number of grid values on the range.
    scale : str, default "linear"
        ``"linear"`` or ``"log"`` spacing (uniform or log-uniform draws).
    relative : bool, default False
        The values are factors on the base parameter value.
    parameter_unit : str, default ""
        A parameter's SI unit, as its declaration states it (:func:`parameter_unit`; filled
        by :func:`parse_config`).
    """

    name: str
    values: tuple[Any, ...] | None = None
    low: float | None = None
    high: float | None = None
    points: int | None = None
    scale: str = "linear"
    relative: bool = False
    parameter_unit: str = ""

    @property
    def key(self) -> str:
        """The axis's key in the configuration file, quoted when the name is dotted."""
        return f'axes."{self.name}"' if "." in self.name else f"axes.{self.name}"

    @property
    def unit(self) -> str:
        """The configuration unit of the axis's values: mm or mm/s for the special axes, a
        parameter's SI unit (:attr:`parameter_unit`), ``"1"`` for a relative axis."""
        if self.relative:
            return "1"
        if self.name in SPECIAL_AXES:
            return SPECIAL_AXES[self.name][0]
        return self.parameter_unit

    def size(self) -> int:
        """How many values a grid takes on this axis (nothing materialised).

        Returns
        -------
        int
            The number of explicit values, or ``points``.
        """
        return len(self.values) if self.values is not None else int(self.points or 0)

    def grid(self) -> list[Any]:
        """The axis's grid values, in the configuration's unit.

        Returns
        -------
        list
            The explicit values, or ``points`` values from ``low`` to ``high`` on the axis's
            scale.
        """
        if self.values is not None:
            return list(self.values)
        assert self.low is not None and self.high is not None
        n = self.points or 0
        if n == 1:
            return [self.low]
        if self.scale == "log":
            return [float(v) for v in np.geomspace(self.low, self.high, n)]
        return [float(v) for v in np.round(np.linspace(self.low, self.high, n), 12)]

    def draw(self, u: float) -> Any:
        """The value at a quantile of the axis's distribution (random and LHS designs).

        Parameters
        ----------
        u : float
            The quantile, in [0, 1) [-].

        Returns
        -------
        object
            One of the explicit values, or a value in [low, high) drawn uniformly or
            log-uniformly [configuration unit of the axis].
        """
        if self.values is not None:
            return self.values[min(int(u * len(self.values)), len(self.values) - 1)]
        assert self.low is not None and self.high is not None
        if self.scale == "log":
            return float(math.exp(math.log(self.low) + u * math.log(self.high / self.low)))
        return float(self.low + u * (self.high - self.low))


@dataclass(frozen=True)
class Point:
    """One design point: its index, coordinates (configuration units) and the task a worker
    evaluates (:func:`.quantities.evaluate`), keyed by :func:`.store.point_key`.

    Parameters
    ----------
    index : int
        The point's number in design order.
    coords : dict
        Axis name → value, in configuration units.
    task : dict
        What a worker needs: parameter set as TOML, drive, position, nut speed, quantity (SI).
    key : str
        The store key of the task.
    """

    index: int
    coords: dict[str, Any]
    task: dict[str, Any]
    key: str


@dataclass(frozen=True)
class SweepConfig:
    """A parsed sweep configuration (see docs/sweeps.md).

    Parameters
    ----------
    name : str
        The sweep's name (``check_name``).
    source : str
        The configuration file.
    base : str
        Preset name, or the parameter file's path.
    drive : str
        The drive name.
    table_position : float
        Table position [mm].
    nut_speed : float
        Nut speed [mm/s].
    design : str
        ``"grid"``, ``"random"`` or ``"lhs"``.
    samples : int or None
        Number of points of a random or LHS design.
    seed : int
        Seed of the random and LHS draws.
    axes : tuple of Axis
        The swept names.
    quantity : QuantitySettings
        What each point computes.
    store : Path or None
        The store file; ``NAME.sqlite`` when None.
    map_axes : tuple of (str or None, str or None), default (None, None)
        The default x and y axes of ``feeddrive map``.
    raw : dict, optional
        The parsed TOML, recorded in the store.
    solver : tuple of (str, object, str), default ()
        The configuration's ``[solver]`` settings (setting, value, source), laid over the
        ``[solver]`` table each base set carries
        (:func:`~feeddrive.parameters.components.solver_over`), so that every point's set
        carries them to its runs, in this process and in a worker's
        (:func:`feeddrive.engine.simulate.run_options`).
    """

    name: str
    source: str
    base: str  # preset name, or the parameter file's path
    drive: str
    table_position: float  # [mm]
    nut_speed: float  # [mm/s]
    design: str
    samples: int | None
    seed: int
    axes: tuple[Axis, ...]
    quantity: QuantitySettings
    store: Path | None
    map_axes: tuple[str | None, str | None] = (None, None)
    raw: dict[str, Any] = field(default_factory=dict)
    solver: tuple[tuple[str, Any, str], ...] = ()

    # ------------------------------------------------------------------ points

    def count(self) -> int:
        """How many design points, from the axes' sizes or ``samples``; nothing is built.

        Returns
        -------
        int
            The number of points.
        """
        if self.design == "grid":
            return math.prod(a.size() for a in self.axes)
        assert self.samples is not None
        return self.samples

    def iter_coordinates(self) -> Iterator[dict[str, Any]]:
        """The design's coordinates, in the configuration's units, in a fixed order, one at
        a time (a grid is never materialised; a random or LHS design holds its n × d
        quantiles, ≤ ``MAX_POINTS`` rows)."""
        _check_count(self.count(), self.design)
        names = [a.name for a in self.axes]
        if self.design == "grid":
            grids = [a.grid() for a in self.axes]
            for combo in itertools.product(*grids):
                yield dict(zip(names, combo, strict=True))
            return
        assert self.samples is not None
        n, d = self.samples, len(self.axes)
        if self.design == "lhs":
            from scipy.stats import qmc

            u = qmc.LatinHypercube(d=d, seed=self.seed).random(n) if d else np.zeros((n, 0))
        else:
            u = np.random.default_rng(self.seed).random((n, d))
        for i in range(n):
            yield {a.name: a.draw(float(u[i, j])) for j, a in enumerate(self.axes)}

    def coordinates(self) -> list[dict[str, Any]]:
        """Every coordinate of :meth:`iter_coordinates` as a list.

        Returns
        -------
        list of dict
            Axis name → value, in configuration units, in design order.
        """
        return list(self.iter_coordinates())

    def effective(self, coords: Mapping[str, Any]) -> tuple[Any, ...]:
        """What a point's result depends on among its coordinates.

        A drive without a nut ignores ``nut_speed``, one whose model does not depend on the
        table's position ignores ``table_position`` (:func:`_ignored`), so those points share
        one stored result.

        Parameters
        ----------
        coords : mapping
            The point's coordinates.

        Returns
        -------
        tuple
            Sorted (name, repr of value) pairs.
        """
        return self._effective(coords, _ignored)

    def _effective(self, coords: Mapping[str, Any],
                   ignored: Callable[[str], tuple[str, ...]]) -> tuple[Any, ...]:
        drive = str(coords.get("drive", self.drive))
        return tuple(sorted((k, repr(v)) for k, v in coords.items()
                            if k not in ignored(drive)))

    def distinct_count(self) -> int:
        """How many distinct computations the design asks for, from the coordinates alone
        (:meth:`effective`); no parameter set is built.  A grid's count is a sum over its
        drives of products of its axes' distinct values (never a walk over its points).

        Returns
        -------
        int
            The number of distinct points.
        """
        _check_count(self.count(), self.design)
        known: dict[str, tuple[str, ...]] = {}

        def ignored(drive: str) -> tuple[str, ...]:
            if drive not in known:
                known[drive] = _ignored(drive)
            return known[drive]

        if self.design == "grid":
            values = {a.name: {repr(v): v for v in a.grid()} for a in self.axes}
            drives = ([str(v) for v in values["drive"].values()] if "drive" in values
                      else [str(self.drive)])
            return sum(math.prod(len(distinct) for name, distinct in values.items()
                                 if name != "drive" and name not in ignored(drive))
                       for drive in drives)
        seen = set()
        for coords in self.iter_coordinates():
            seen.add(hashlib.blake2b(repr(self._effective(coords, ignored)).encode(),
                                     digest_size=12).digest())
        return len(seen)

    def iter_points(self, *, bases: dict[str, DriveParameters] | None = None
                    ) -> Iterator[Point]:
        """Every design point with its task and store key, built one at a time.

        Parameters
        ----------
        bases : dict of str to DriveParameters, optional
            Cache of base parameter sets by name, filled as they are loaded.

        Yields
        ------
        Point
            The points, in design order.
        """
        from .store import point_key

        bases = {} if bases is None else bases
        for i, coords in enumerate(self.iter_coordinates()):
            task = self.task(coords, bases)
            yield Point(index=i, coords=coords, task=task, key=point_key(task))

    def points(self) -> list[Point]:
        """Every design point with its task and store key.

        Every point's parameter set is built and validated here, so a bad value stops the sweep
        before any simulation (a run does not hold them all: :func:`.executors.run_sweep` streams
        :meth:`iter_points`).

        Returns
        -------
        list of Point
            The points, in design order.
        """
        return list(self.iter_points())

    def _base(self, name: str, cache: dict[str, DriveParameters]) -> DriveParameters:
        if name not in cache:
            cache[name] = _with_solver(_load_base(name, self.source), self.solver)
        return cache[name]

    def task(self, coords: Mapping[str, Any],
             cache: dict[str, DriveParameters] | None = None) -> dict[str, Any]:
        """What a worker needs for one point, in SI.

        Parameters
        ----------
        coords : mapping
            The point's coordinates, in configuration units.
        cache : dict of str to DriveParameters, optional
            Cache of base parameter sets by name.

        Returns
        -------
        dict
            The full parameter set as TOML text, drive, table position [m], nut speed [m/s],
            the quantity settings and the integrator settings in force
            (:meth:`feeddrive.SolverOptions.record`).

        Raises
        ------
        ParameterError
            When a coordinate makes an invalid parameter set.
        """
        cache = {} if cache is None else cache
        base_name = str(coords.get("preset", self.base))
        params = self._base(base_name, cache)
        drive = str(coords.get("drive", self.drive))
        from ..model.mechanisms.base import DEFAULT_TABLE_POSITION

        # a drive whose model does not read the start is given none (the default), as one
        # that drives no nut is given no nut speed: those points share one result
        position = (DEFAULT_TABLE_POSITION if "table_position" in _ignored(drive) else
                    float(coords.get("table_position", self.table_position)) * units.MM)
        nut = 0.0 if _no_nut(drive) else \
            float(coords.get("nut_speed", self.nut_speed)) * units.MM_PER_S
        quantity = self.quantity
        if "table_speed" in coords:
            quantity = quantity.with_table_speed(float(coords["table_speed"]) * units.MM_PER_S)
        deferred = []
        for axis in self.axes:
            if axis.name in SPECIAL_AXES:
                continue
            value = coords[axis.name]
            if axis.relative and _is_chain_stiffness(axis.name, params):
                deferred.append((axis, value))
                continue
            params = _apply(params, axis, value)
        for axis, value in deferred:
            from ..model.mechanisms.ball_screw_stiffness import equivalent_stiffness

            params = _apply_value(params, axis, value * equivalent_stiffness(params, position))
        from ..engine.simulate import DriveSystem

        try:
            DriveSystem(params, drive=drive, table_position=position)
        except ParameterError as err:
            key = {"table_position": _axis_or("table_position", self.axes),
                   "drive": _axis_or("drive", self.axes)}.get(err.field, err.field)
            value, message = err.value, err.message
            if err.field == "table_position":  # shown as the configuration gives it [mm]
                value = float(coords.get("table_position", self.table_position))
                message += "; the configuration's positions are in mm"
            raise _refuse(key, value, message) from None
        from ..engine.options import current

        # the integrator settings in force (a command's --accuracy): part of the point's key
        return {"parameters": dumps(params), "drive": drive, "table_position": position,
                "nut_speed": nut, "quantity": quantity.to_dict(),
                "solver": current().record()}


def _check_count(count: int, design: str) -> None:
    if count > MAX_POINTS:
        key = "design.samples" if design != "grid" else "axes"
        raise _refuse(key, count, f"{count} design points; at most {MAX_POINTS} (refused "
                      "before any point is built)")


def check_name(key: str, name: Any) -> str:
    """Check a sweep's name: text of 1 to ``MAX_NAME`` printable characters, no path separator,
    no ``:`` and no leading dot.

    ``NAME.sqlite`` is the default store, in the current folder: a name never reaches another
    folder.

    Parameters
    ----------
    key : str
        The configuration key, for the message.
    name : object
        The value given.

    Returns
    -------
    str
        ``name``.

    Raises
    ------
    ParameterError
        For anything else.
    """
    if not isinstance(name, str):
        raise _refuse(key, name, "expected a text name")
    if not name.strip():
        raise _refuse(key, name, "expected a non-empty name")
    if len(name) > MAX_NAME:
        raise _refuse(key, name, f"{len(name)} characters; at most {MAX_NAME}")
    if not name.isprintable():
        raise _refuse(key, name, "contains control characters")
    if any(c in name for c in "/\\") or name.startswith(".") or ":" in name:
        raise _refuse(key, name, "a name, not a path: no /, \\, : and no leading dot")
    return name


def _axis_or(name: str, axes: Sequence[Axis]) -> str:
    return next((a.key for a in axes if a.name == name), name)


def _is_chain_stiffness(name: str, params: DriveParameters) -> bool:
    return name == "stiffness.equivalent_stiffness" and params.stiffness.equivalent_stiffness == 0


def _apply(params: DriveParameters, axis: Axis, value: Any) -> DriveParameters:
    if axis.relative:
        base = _get_path(params, axis.name)
        if _is_component(base):
            try:
                return params.replace_path(axis.name, base.scaled(value))
            except ParameterError as err:
                raise _refuse(axis.key, value, f"{err.field} = {err.value!r}: "
                              f"{err.message}") from None
        return _apply_value(params, axis, base * value)
    return _apply_value(params, axis, value)


def _apply_value(params: DriveParameters, axis: Axis, value: Any) -> DriveParameters:
    if isinstance(value, list):
        value = tuple(value)
    try:
        return params.replace_path(axis.name, value)
    except ParameterError as err:
        detail = f" ({err.field} = {err.value!r})" if err.field != axis.name else ""
        raise _refuse(axis.key, value, f"{err.message}{detail}") from None


def _is_component(obj: Any) -> bool:
    return hasattr(obj, "scaled") and callable(obj.scaled)


def _get_path(params: Any, path: str) -> Any:
    obj = params
    for part in path.split("."):
        obj = getattr(obj, part)
    return obj


def parameter_unit(params: DriveParameters, path: str) -> str:
    """The SI unit a parameter file gives the parameter at a dotted path: the unit its
    declaration states (the field metadata a parameter file is checked against,
    :func:`feeddrive.parameters.validation.path_unit_label`), for the set's velocity-gain
    basis (A s/m per table speed or A s/rad), without the basis note.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    path : str
        A dotted parameter name (``friction.screw.positive.stribeck_velocity``).

    Returns
    -------
    str
        The unit (``"m/s"``); ``"1"`` for a dimensionless number; ``""`` for what has no
        unit (a name, a mode, a whole friction site) or a path the set does not have.
    """
    try:
        label = path_unit_label(params, path)
    except KeyError:
        return ""
    unit = label.removesuffix(f", {TABLE_BASIS_NOTE}")
    return "1" if unit == "-" else unit


def _with_unit(axis: Axis, bases: Sequence[DriveParameters]) -> Axis:
    """``axis`` with its parameter's unit: the one every base set (the configuration's and a
    ``preset`` axis's) declares, or none where they differ (A s/m and A s/rad gains)."""
    if axis.relative or axis.name in SPECIAL_AXES:
        return axis
    found = {parameter_unit(b, axis.name) for b in bases}
    return replace(axis, parameter_unit=found.pop() if len(found) == 1 else "")


def _preset_bases(axes: Sequence[Axis], source: str) -> list[DriveParameters]:
    """The base sets a ``preset`` axis names (one it cannot load is refused later, at its
    point, naming the axis)."""
    out = []
    for axis in axes:
        if axis.name == "preset":
            for name in axis.values or ():
                try:
                    out.append(_load_base(str(name), source))
                except (ParameterError, OSError):
                    continue
    return out


def _load_base(name: str, source: str) -> DriveParameters:
    if name.endswith(".toml"):
        path = Path(name)
        if not path.is_absolute():
            path = Path(source).parent / path
        return load(path)
    try:
        return preset(name)
    except ParameterError as err:
        raise _refuse("preset", name, err.message) from None


def _with_solver(params: DriveParameters, solver: tuple[tuple[str, Any, str], ...]
                 ) -> DriveParameters:
    """A base set with the configuration's ``[solver]`` settings over its own."""
    if not solver:
        return params
    try:
        return replace(params, solver=solver_over(params.solver, solver))
    except ParameterError as err:
        raise _refuse(err.field, err.value, err.message) from None


def _solver_settings(data: Mapping[str, Any], source: str) -> tuple[tuple[str, Any, str], ...]:
    """The configuration's ``[solver]`` settings: its table checked by name and kind, or,
    inside a command that merged it into the options in force, what that command gives
    (:func:`feeddrive.parameters.toml_io.tables_applied`: nothing, its settings are in the
    base set's)."""
    applied = table_applied(source)
    if applied is not None:
        return applied
    if SOLVER_KEY not in data:
        return ()
    return solver_table(data[SOLVER_KEY], f"[solver] in {source}")


def numeric_paths(params: DriveParameters) -> list[str]:
    """Dotted names of every numeric parameter of a set (what a ``*`` axis sweeps).

    Parameters
    ----------
    params : DriveParameters
        The parameter set.

    Returns
    -------
    list of str
        The paths, in the set's order.
    """
    out: list[str] = []

    def walk(d: Mapping[str, Any], prefix: str) -> None:
        for k, v in d.items():
            path = f"{prefix}{k}"
            if isinstance(v, Mapping):
                walk(v, path + ".")
            elif isinstance(v, int | float) and not isinstance(v, bool):
                out.append(path)

    walk(to_dict(params), "")
    return out


# ---------------------------------------------------------------------- parsing


def _number(key: str, value: Any, *, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise _refuse(key, value, "expected a finite number")
    if positive and value <= 0:
        raise _refuse(key, value, "expected a number > 0")
    return float(value)


def _parse_axis(name: str, spec: Any) -> Axis:
    key = f'axes."{name}"' if "." in name else f"axes.{name}"
    if isinstance(spec, list):
        spec = {"values": spec}
    if not isinstance(spec, dict):
        raise _refuse(key, spec, "expected a list of values or a table "
                      "{ low, high, points } / { values }")
    unknown = sorted(set(spec) - set(_AXIS_KEYS))
    if unknown:
        raise _refuse(f"{key}.{unknown[0]}", spec[unknown[0]],
                      f"unknown key; expected one of {', '.join(_AXIS_KEYS)}")
    relative = spec.get("relative", False)
    if not isinstance(relative, bool):
        raise _refuse(f"{key}.relative", relative, "expected true or false")
    scale = spec.get("scale", "linear")
    if scale not in ("linear", "log"):
        raise _refuse(f"{key}.scale", scale, "expected linear or log")
    if "values" in spec:
        values = spec["values"]
        if not isinstance(values, list) or not values:
            raise _refuse(f"{key}.values", values, "empty: expected at least one value")
        if any(k in spec for k in ("low", "high", "points")):
            raise _refuse(key, spec, "give either values or low/high, not both")
        if relative:
            for v in values:
                _number(f"{key}.values", v, positive=True)
        return Axis(name=name, values=tuple(values), relative=relative)
    if "low" not in spec or "high" not in spec:
        raise _refuse(key, spec, "expected values = [...] or low and high")
    low = _number(f"{key}.low", spec["low"])
    high = _number(f"{key}.high", spec["high"])
    if not low < high and not (low == high and spec.get("points") == 1):
        raise _refuse(f"{key}.high", high, f"empty range: expected > low = {low:g}")
    points = spec.get("points")
    if points is not None and (isinstance(points, bool) or not isinstance(points, int)
                               or points < 1):
        raise _refuse(f"{key}.points", points, "expected a whole number ≥ 1")
    if points is not None and points > MAX_POINTS:
        raise _refuse(f"{key}.points", points, f"at most {MAX_POINTS} design points")
    if scale == "log" and low <= 0:
        raise _refuse(f"{key}.low", low, "a log scale needs low > 0")
    if relative and low <= 0:
        raise _refuse(f"{key}.low", low, "a relative factor must be > 0")
    return Axis(name=name, low=low, high=high, points=points, scale=scale, relative=relative)


def _check_axis_name(axis: Axis, base: DriveParameters) -> None:
    """An unknown name, a relative special axis or a value of the wrong kind is refused."""
    if axis.name in SPECIAL_AXES:
        if axis.relative:
            raise _refuse(f"{axis.key}.relative", True, f"{axis.name} cannot be relative")
        if axis.name == "drive":
            for v in axis.values or ():
                if v not in _drives():
                    raise _refuse(f"{axis.key}.values", v,
                                  f"expected one of {', '.join(_drives())}")
        if axis.name in ("drive", "preset") and axis.values is None:
            raise _refuse(axis.key, axis.low, "expected values = [...] (names)")
        if axis.name not in ("drive", "preset"):  # a number in its unit, checked here (a
            # text or NaN value failed at its point: an outside check, 2026-12-07)
            unit = SPECIAL_AXES[axis.name][0]
            for v in axis.values or ():
                value = _number(f"{axis.key}.values", v, positive=axis.name != "nut_speed")
                if axis.name == "nut_speed" and value < 0:
                    raise _refuse(f"{axis.key}.values", v, f"expected a speed ≥ 0 [{unit}]")
        return
    try:
        current = _get_path(base, axis.name)
    except AttributeError:
        # replace_path names the first unknown part
        try:
            base.replace_path(axis.name, 0.0)
        except ParameterError as err:
            raise _refuse(axis.key, axis.name, err.message + " (not a parameter name)") from None
        raise _refuse(axis.key, axis.name, "not a parameter name") from None
    if axis.relative and not (_is_component(current) or (
            isinstance(current, int | float) and not isinstance(current, bool))):
        raise _refuse(f"{axis.key}.relative", True,
                      f"{axis.name} is not a number or a friction site; give values instead")
    if not axis.relative and _is_component(current) and axis.values is None:
        raise _refuse(axis.key, axis.name, "a friction site is varied by relative = true")


def _expand(axis: Axis, base: DriveParameters) -> list[Axis]:
    if "*" not in axis.name:
        return [axis]
    if not axis.relative:
        raise _refuse(f"{axis.key}.relative", False, "a name with * needs relative = true "
                      "(each matching parameter has its own base value)")
    names = [p for p in numeric_paths(base) if fnmatch.fnmatchcase(p, axis.name)]
    if not names:
        raise _refuse(axis.key, axis.name, "matches no numeric parameter")
    return [Axis(name=n, values=axis.values, low=axis.low, high=axis.high, points=axis.points,
                 scale=axis.scale, relative=True) for n in names]


def parse_config(data: Mapping[str, Any], source: str) -> SweepConfig:
    """A :class:`SweepConfig` from parsed TOML; every key checked (see the module).

    Parameters
    ----------
    data : mapping
        The parsed TOML.
    source : str
        The file it came from (relative paths in it are relative to its folder).

    Returns
    -------
    SweepConfig
        The configuration.

    Raises
    ------
    ParameterError
        For an unknown key or a bad value, naming the key.
    """
    unknown = sorted(set(data) - set(_TOP_KEYS))
    if unknown:
        raise _refuse(unknown[0], data[unknown[0]],
                      f"unknown key; expected one of {', '.join(_TOP_KEYS)}")
    if "preset" in data and "params" in data:
        raise _refuse("params", data["params"], "give either preset or params, not both")
    base = str(data.get("params", data.get("preset", "wang2021")))
    if "params" in data and not base.endswith(".toml"):
        raise _refuse("params", base, "expected a .toml parameter file")
    solver = _solver_settings(data, source)
    base_params = _with_solver(_load_base(base, source), solver)
    drive = data.get("drive", "cdfs")
    if drive not in _drives():
        raise _refuse("drive", drive, f"expected one of {', '.join(_drives())}")
    position = _number("table_position", data.get("table_position", 400.0))
    nut = _number("nut_speed", data.get("nut_speed", 0.0))

    design = data.get("design", {})
    if not isinstance(design, dict):
        raise _refuse("design", design, "expected a table")
    for k in design:
        if k not in ("kind", "samples", "seed"):
            raise _refuse(f"design.{k}", design[k], "unknown key; expected kind, samples, seed")
    kind = design.get("kind", "grid")
    if kind not in DESIGNS:
        raise _refuse("design.kind", kind, f"expected one of {', '.join(DESIGNS)}")
    samples = design.get("samples")
    if kind != "grid":
        if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
            raise _refuse("design.samples", samples, "expected a whole number ≥ 1")
        if samples > MAX_POINTS:
            raise _refuse("design.samples", samples, f"at most {MAX_POINTS} samples (as a "
                          "grid's points)")
    elif samples is not None:
        raise _refuse("design.samples", samples, "only for random or lhs designs")
    seed = design.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise _refuse("design.seed", seed, "expected a whole number ≥ 0")

    axes_spec = data.get("axes", {})
    if not isinstance(axes_spec, dict):
        raise _refuse("axes", axes_spec, "expected a table of axes")
    axes: list[Axis] = []
    for name, spec in axes_spec.items():
        axis = _parse_axis(name, spec)
        for a in _expand(axis, base_params):
            _check_axis_name(a, base_params)
            if kind == "grid" and a.values is None and a.points is None:
                raise _refuse(f"{a.key}.points", None, "a grid axis needs points (or values)")
            axes.append(a)
    if kind != "grid" and not axes:
        raise _refuse("axes", {}, f"a {kind} design needs at least one axis")
    bases = [base_params, *_preset_bases(axes, source)]
    axes = [_with_unit(a, bases) for a in axes]

    quantity = QuantitySettings.parse(data.get("quantity", {}))
    if "table_speed" in axes_spec and quantity.kind not in ("creep-trial", "loop-margins"):
        raise _refuse("axes.table_speed", axes_spec["table_speed"],
                      f"only for quantity creep-trial or loop-margins, not {quantity.kind}")

    store = data.get("store")
    if store is not None and (not isinstance(store, str) or not store.strip()):
        raise _refuse("store", store, "expected a file name")
    store_path = None if store is None else (Path(source).parent / store)
    map_spec = data.get("map", {})
    if not isinstance(map_spec, dict):
        raise _refuse("map", map_spec, "expected a table { x, y }")
    names = {a.name for a in axes}
    for k, v in map_spec.items():
        if k not in ("x", "y"):
            raise _refuse(f"map.{k}", v, "unknown key; expected x, y")
        if v not in names:
            raise _refuse(f"map.{k}", v, "not an axis of this sweep")
    if kind == "grid":
        _check_count(math.prod(a.size() for a in axes), kind)
    name = check_name("name", data.get("name", Path(source).stem))
    return SweepConfig(name=name, source=source, base=base, drive=drive,
                       table_position=position, nut_speed=nut, design=kind,
                       samples=samples if kind != "grid" else None, seed=seed,
                       axes=tuple(axes), quantity=quantity, store=store_path,
                       map_axes=(map_spec.get("x"), map_spec.get("y")), raw=dict(data),
                       solver=solver)


def load_config(path: str | os.PathLike[str]) -> SweepConfig:
    """Read and check a sweep configuration file.

    Parameters
    ----------
    path : str or os.PathLike
        The TOML file.

    Returns
    -------
    SweepConfig
        The configuration.

    Raises
    ------
    ParameterError
        Naming the file and the key.
    """
    data = read_toml_file(os.fspath(path))
    try:
        return parse_config(data, os.fspath(path))
    except ParameterError as err:
        raise err.in_file(os.fspath(path)) from None


__all__ = ["DESIGNS", "MAX_POINTS", "Axis", "Point", "SweepConfig", "check_name",
           "load_config", "numeric_paths", "parameter_unit", "parse_config"]


def __getattr__(name: str) -> Any:
    """Names that moved from here before 0.2.0: importable until 0.3.0, with a
    DeprecationWarning naming their new place (:mod:`feeddrive._compat`)."""
    from .. import _compat

    return _compat.moved(__name__, name)
