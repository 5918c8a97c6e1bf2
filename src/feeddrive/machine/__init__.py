"""A machine of axes: several drives, each any registered topology with its own parameter set,
assembled into one model whose names are ``<axis>.<signal>``.

A machine file (TOML)::

    name = "my-xy"
    extends = "xy-table"           # optional: a built-in machine (MACHINES) to start from

    [axes.x]
    extends = "wang2021"           # the axis' parameter set, as a parameter file gives it
    drive = "cdfs"                 # its topology (default: the set's example drive)
    table_position = 0.4           # [m], where the ball-screw nut starts (default 0.4)

    [axes.y]
    drive = "linear-motor"         # without extends: the drive's example set
    [axes.y.table]
    mass = 30.0

Each axis is declared inside a :meth:`Builder.scope <feeddrive.model.codegen.Builder.scope>`
of its name, so its states, signals, parameters and clocks are ``x.table_speed``,
``x.controller.position_period`` …, and its code runs in a function of its own.  The machine
is simulated by the one engine (:func:`simulate_machine`), following a :mod:`contour
<feeddrive.machine.contour>`, and the run carries every axis' signals and the contour error.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..model.reference import SampledSpeed
from ..parameters import DriveParameters, ParameterError
from ..parameters.validation import MISSING
from .contour import Circle, Contour, Line, Polyline, Together, corner, from_csv
from .couplings import AXIS_INPUTS, Coupling, coupling

__all__ = ["CONTOURS", "MACHINES", "Circle", "Contour", "Line", "Machine", "MachineAxis",
           "MachineProfile", "MachineSystem", "Polyline", "Together", "assemble_machine",
           "check_machine",
           "corner", "from_csv", "load_machine", "machine_from_dict", "machine_summary",
           "machine_toml", "make_contour", "plan", "simulate_machine"]

#: built-in machines: name → the machine file's content
MACHINES: dict[str, dict[str, Any]] = {
    # two independent wang2021 CDFS axes at right angles (issue 40's XY table)
    "xy-table": {"name": "xy-table", "axes": {
        "x": {"extends": "wang2021", "drive": "cdfs"},
        "y": {"extends": "wang2021", "drive": "cdfs"}}},
    # two wang2021 CDFS axes carrying one beam (feeddrive.machine.couplings.gantry); add a
    # synchronisation part ([couplings.sync] part = "master_slave" or "cross_coupled")
    "gantry": {"name": "gantry", "axes": {
        "x1": {"extends": "wang2021", "drive": "cdfs"},
        "x2": {"extends": "wang2021", "drive": "cdfs"}},
        "couplings": {"beam": {"part": "gantry_beam", "a": "x1", "b": "x2"}}},
}

_AXIS_KEYS = ("drive", "table_position", "nut_hold")


@dataclass(frozen=True)
class MachineAxis:
    """One axis of a machine: a drive with its own parameter set.

    Parameters
    ----------
    name : str
        The axis' name, an identifier (``"x"``); its signals are ``<name>.<signal>``.
    parameters : DriveParameters
        Its parameter set [SI].
    drive : str
        A registered topology (``"cdfs"``, ``"linear-motor"`` …).
    table_position : float, default 0.4
        Start position of a ball-screw nut from the motor-side support [m]; refused on an
        axis of another drive unless the default (a machine file refuses it there written
        at all).
    nut_hold : str, default "locked"
        How a CDFS holds its nut (``"locked"`` or ``"servo"``); ``"servo"`` refused on an
        axis of another drive (a machine file refuses it there written at all).
    """

    name: str
    parameters: DriveParameters
    drive: str
    table_position: float = 0.4
    nut_hold: str = "locked"

    def __post_init__(self) -> None:
        from ..model.mechanisms import drive_names
        from ..model.mechanisms.base import check_nut_hold, check_table_position

        # both were taken and dropped on a drive that does not read them (an earlier sweep,
        # session 30); a drive not registered is refused where the axis is built
        if isinstance(self.drive, str) and self.drive in drive_names():
            check_table_position(self.drive, self.table_position)
            check_nut_hold(self.drive, self.nut_hold)


@dataclass(frozen=True)
class Machine:
    """Several axes, each assembled into one model under its own name.

    Parameters
    ----------
    name : str
        The machine's name.
    axes : tuple of MachineAxis
        Its axes.
    couplings : tuple of Coupling, default ()
        Its coupling parts (:mod:`feeddrive.machine.couplings`), joined to the axes by
        named signals.
    """

    name: str
    axes: tuple[MachineAxis, ...]
    couplings: tuple[Coupling, ...] = ()

    def axis(self, name: str) -> MachineAxis:
        """The axis called ``name``.

        Parameters
        ----------
        name : str
            An axis name.

        Returns
        -------
        MachineAxis
            The axis.

        Raises
        ------
        ParameterError
            For a name the machine has no axis of.
        """
        for ax in self.axes:
            if ax.name == name:
                return ax
        raise ParameterError("axes", name, "no such axis; expected one of "
                             + ", ".join(a.name for a in self.axes))


def _axis(name: str, table: Any, base_dir: Path | None) -> MachineAxis:
    """One ``[axes.<name>]`` table → its axis; every error names ``axes.<name>.…``."""
    from ..model.mechanisms import drive_names, mechanism
    from ..model.mechanisms.base import (
        DEFAULT_TABLE_POSITION,
        check_nut_hold,
        check_table_position,
    )
    from ..parameters.toml_io import from_dict

    if not isinstance(name, str) or not name.isidentifier():
        raise ParameterError(f"axes.{name}", name, "expected an identifier as the axis' name "
                             "(letters, digits, _)")
    if not isinstance(table, Mapping):
        raise ParameterError(f"axes.{name}", table, "expected a table")
    data = dict(table)
    given = {key for key in ("table_position", "nut_hold") if key in data}
    drive = data.pop("drive", None)
    position = data.pop("table_position", DEFAULT_TABLE_POSITION)
    hold = data.pop("nut_hold", "locked")
    if drive is not None and drive not in drive_names():
        raise ParameterError(f"axes.{name}.drive", drive,
                             f"expected one of {', '.join(drive_names())}")
    if "extends" not in data:
        data["extends"] = mechanism(drive or "cdfs").example_preset
    if set(data) == {"extends"}:  # the set itself, unchanged: its own name
        data["name"] = data["extends"]
    try:
        params = from_dict(data, base_dir=base_dir)
    except ParameterError as err:
        raise ParameterError(f"axes.{name}.{err.field}", err.value, err.message) from None
    if drive is None:
        drive = next((d for d in drive_names()
                      if mechanism(d).example_preset == data["extends"]), "cdfs")
    if not (isinstance(position, int | float) and math.isfinite(position)):
        raise ParameterError(f"axes.{name}.table_position", position, "expected a number [m]")
    # any start position written on an axis whose model does not read it (the default too,
    # which was read and dropped: session 30; machine_toml writes it only where used)
    check_table_position(drive, position, field=f"axes.{name}.table_position",
                         given="table_position" in given)
    try:
        mechanism(drive).check(params, drive, float(position))
    except ParameterError as err:
        raise ParameterError(f"axes.{name}.{err.field}", err.value, err.message) from None
    if hold not in ("locked", "servo"):
        raise ParameterError(f"axes.{name}.nut_hold", hold, "expected locked or servo")
    # any nut hold written on an axis that holds no nut ("locked" too, which was read and
    # dropped: session 30; machine_toml writes it only where a nut is held)
    check_nut_hold(drive, hold, field=f"axes.{name}.nut_hold", given="nut_hold" in given)
    return MachineAxis(name, params, drive, float(position), hold)


def _merged(data: Mapping[str, Any]) -> dict[str, Any]:
    """A machine file with its built-in parent (``extends``) merged in, axis by axis."""
    data = dict(data)
    parent = data.pop("extends", None)
    if parent is None:
        return data
    if parent not in MACHINES:
        raise ParameterError("extends", parent,
                             f"expected a built-in machine: {', '.join(MACHINES)}")
    base = MACHINES[parent]
    axes = {k: dict(v) for k, v in base["axes"].items()}
    given = data.get("axes", {})
    for k, v in (given.items() if isinstance(given, Mapping) else ()):
        axes[k] = {**axes.get(k, {}), **dict(v)} if isinstance(v, Mapping) else v
    couplings = {k: dict(v) for k, v in base.get("couplings", {}).items()}
    given = data.get("couplings", {})
    for k, v in (given.items() if isinstance(given, Mapping) else ()):
        couplings[k] = {**couplings.get(k, {}), **dict(v)} if isinstance(v, Mapping) else v
    return {**base, **data, "axes": axes, "couplings": couplings}


def _couplings(data: Mapping[str, Any]) -> tuple[Coupling, ...]:
    tables = data.get("couplings", {})
    if not isinstance(tables, Mapping):
        raise ParameterError("couplings", tables, "expected [couplings.<name>] tables")
    out = []
    for name, table in tables.items():
        if not isinstance(table, Mapping) or "part" not in table:
            raise ParameterError(f"couplings.{name}", table, "expected a table with part = "
                                 "\"<a registered coupling part>\"")
        try:
            cls = coupling(table["part"])
        except ParameterError as err:
            raise ParameterError(f"couplings.{name}.part", err.value, err.message) from None
        out.append(cls.from_table(name, {k: v for k, v in table.items() if k != "part"}))
    return tuple(out)


def _axis_tables(data: Mapping[str, Any]) -> Mapping[str, Any]:
    unknown = sorted(set(data) - {"name", "axes", "couplings"})
    if unknown:
        raise ParameterError(unknown[0], data[unknown[0]], "unknown key of a machine file; "
                             "expected name, extends, axes, couplings")
    tables = data.get("axes")
    if not isinstance(tables, Mapping) or not tables:
        raise ParameterError("axes", tables, "expected one or more [axes.<name>] tables")
    return tables


def machine_from_dict(data: Mapping[str, Any], *, base_dir: Path | None = None) -> Machine:
    """Build a machine from a parsed machine file.

    Parameters
    ----------
    data : mapping
        The file's content: ``name``, optionally ``extends`` (a built-in machine of
        :data:`MACHINES`), ``[axes.<name>]`` tables.
    base_dir : Path, optional
        Folder relative ``extends`` files of the axes are read from.

    Returns
    -------
    Machine
        The machine.

    Raises
    ------
    ParameterError
        The first error, naming the axis (``axes.y.table.mass``) or the key.

    Examples
    --------
    The built-in XY table, and the circle of docs/machine.md (R 50 mm, F 5000 mm/min) it
    would follow: one revolution at the feed (2πR/F = 3.770 s) plus the lead-in and lead-out
    ramps at 1 m/s² (F/a = 0.083 s in all):

    >>> from feeddrive.machine import machine_from_dict, make_contour
    >>> machine = machine_from_dict({"extends": "xy-table"})
    >>> [axis.name for axis in machine.axes]
    ['x', 'y']
    >>> circle = make_contour("circle", feed=5000 / 60e3, acceleration=1.0, radius=0.05)
    >>> print(f"{circle.duration:.4f} s")
    3.8532 s
    """
    data = _merged(data)
    tables = _axis_tables(data)
    axes = tuple(_axis(k, v, base_dir) for k, v in tables.items())
    machine = Machine(str(data.get("name", "machine")), axes, _couplings(data))
    plan(machine)  # the signals connect: refused here, before any work
    return machine


def check_machine(data: Mapping[str, Any], *, base_dir: Path | None = None) -> list[str]:
    """Every error of a machine file, one line each, naming the axis (``params check``).

    Parameters
    ----------
    data : mapping
        The parsed machine file.
    base_dir : Path, optional
        Folder relative ``extends`` files are read from.

    Returns
    -------
    list of str
        One line per error; empty for a valid file.
    """
    try:
        tables = _axis_tables(_merged(data))
    except ParameterError as err:
        return [str(err)]
    errors = []
    axes = []
    for name, table in tables.items():
        try:
            axes.append(_axis(name, table, base_dir))
        except ParameterError as err:
            errors.append(str(err))
    try:
        couplings = _couplings(_merged(data))
    except ParameterError as err:
        return [*errors, str(err)]
    if not errors:
        try:
            plan(Machine("check", tuple(axes), couplings))
        except ParameterError as err:
            errors.append(str(err))
    return errors


def load_machine(path: str | Path) -> Machine:
    """Read a machine file.

    Parameters
    ----------
    path : str or Path
        The TOML file, or the name of a built-in machine (:data:`MACHINES`).

    Returns
    -------
    Machine
        The machine.

    Raises
    ------
    ParameterError
        For a file that cannot be read or a refused value, naming the axis.
    """
    from ..parameters.toml_io import read_toml_file

    if str(path) in MACHINES:
        return machine_from_dict(MACHINES[str(path)])
    data = read_toml_file(path, field="machine")
    return machine_from_dict(data, base_dir=Path(path).parent)


@dataclass(frozen=True)
class MachineProfile(SampledSpeed):
    """The references of a machine's axes on one time grid.

    As a :class:`~feeddrive.model.reference.SampledSpeed` it is the path speed (the engine's
    speed scales and step ends read it); ``axes`` holds each axis' own reference.

    Parameters
    ----------
    time : numpy.ndarray
        Uniform sample instants from 0 [s].
    table_speed : numpy.ndarray
        The path speed at each instant [m/s].
    nut_speed : numpy.ndarray or None, default None
        Unused (zero) [m/s].
    hold : bool, default False
        Hold each sample (zero-order hold) instead of interpolating.
    axes : tuple of (str, SampledSpeed), default ()
        Axis name → its reference.
    contour : Contour or None, default None
        The path the references follow (its contour error), if any.
    """

    axes: tuple[tuple[str, SampledSpeed], ...] = ()
    contour: Contour | None = None

    @classmethod
    def from_contour(cls, contour: Contour, machine: Machine,
                     interval: float | None = None) -> MachineProfile:
        """The references of a contour; axes the contour does not move stand still.

        Parameters
        ----------
        contour : Contour
            The path.
        machine : Machine
            The machine (its axes).
        interval : float, optional
            Grid spacing [s] (default :data:`feeddrive.machine.contour.INTERVAL`).

        Returns
        -------
        MachineProfile
            The references.
        """
        from .contour import INTERVAL

        if isinstance(contour, Together):  # every axis along the path's length
            refs = contour.references(interval or INTERVAL)
            t = next(iter(refs.values())).time
            common = SampledSpeed(time=t, table_speed=contour.path_speed(t))
            return cls(time=t, table_speed=common.table_speed,
                       axes=tuple((ax.name, common) for ax in machine.axes), contour=contour)
        for name in contour.axes:
            machine.axis(name)
        refs = contour.references(interval or INTERVAL)
        t = next(iter(refs.values())).time
        zero = SampledSpeed(time=t, table_speed=np.zeros_like(t))
        return cls(time=t, table_speed=contour.path_speed(t),
                   axes=tuple((ax.name, refs.get(ax.name, zero)) for ax in machine.axes),
                   contour=contour)

    @classmethod
    def common(cls, machine: Machine, reference: SampledSpeed) -> MachineProfile:
        """Every axis following one reference (a gantry's two carriages).

        Parameters
        ----------
        machine : Machine
            The machine.
        reference : SampledSpeed
            The table speed every axis follows [m/s].

        Returns
        -------
        MachineProfile
            The references.
        """
        return cls(time=reference.time, table_speed=reference.table_speed,
                   axes=tuple((ax.name, reference) for ax in machine.axes))

    def axis(self, name: str) -> SampledSpeed:
        """The reference of one axis.

        Parameters
        ----------
        name : str
            The axis' name.

        Returns
        -------
        SampledSpeed
            Its reference [m/s].
        """
        return dict(self.axes)[name]


@dataclass(frozen=True)
class Plan:
    """How a machine's parts connect: the order their code runs in and each coupling's reads.

    Parameters
    ----------
    order : tuple of str
        Axis names and ``couplings.<name>`` in the order their code runs (each value computed
        before it is read).
    inputs : tuple of str
        The axes' input signals some part writes (``y.external_force``).
    """

    order: tuple[str, ...]
    inputs: tuple[str, ...]


def _declare_axes(b: Any, machine: Machine, profile: MachineProfile | None,
                  inputs: set[str], order: tuple[str, ...]) -> list[Any]:
    """Declare each axis in a scope of its name (its functions called where the caller says)."""
    import dataclasses as dc

    from ..model.assemble import declare_drive
    from ..model.reference import ConstantSpeed

    laws: list[Any] = []
    for name in order:
        ax = machine.axis(name)
        ref = profile.axis(name) if profile is not None else ConstantSpeed(0.0)
        with b.scope(name, call=False):
            axis_laws, _ = declare_drive(b, ax.parameters, ax.drive, ax.table_position,
                                         ax.nut_hold, ref, None,
                                         external_force=f"{name}.external_force" in inputs,
                                         speed_correction=f"{name}.speed_correction" in inputs)
        laws += [(dc.replace(site, name=f"{name}.{site.name}"), law, first)
                 for site, law, first in axis_laws]
    return laws


def plan(machine: Machine) -> Plan:
    """Connect a machine's coupling parts to its axes by signal name, and order them.

    Every refusal is one line naming the signal or the part: a read no axis or part writes,
    a signal two parts write, a write to no axis input, an algebraic cycle.

    Parameters
    ----------
    machine : Machine
        The machine.

    Returns
    -------
    Plan
        The order and the written inputs.

    Raises
    ------
    ParameterError
        When the signals do not connect.
    """
    from ..model import codegen

    axis_names = [ax.name for ax in machine.axes]
    if len(set(axis_names)) != len(axis_names):
        raise ParameterError("axes", axis_names, "expected each axis name once")
    writer: dict[str, str] = {}
    for c in machine.couplings:
        if c.name in axis_names:
            raise ParameterError(f"couplings.{c.name}", c.name,
                                 "a part named as an axis; expected another name")
        for signal in c.writes():
            own = re.fullmatch(rf"der\({re.escape(c.name)}\.(.+)\)", signal)
            if own and own.group(1) in c.states():
                continue  # the rate of its own state
            axis, _, port = signal.partition(".")
            if axis not in axis_names or port not in AXIS_INPUTS:
                raise ParameterError(f"couplings.{c.name}", signal,
                                     "writes no axis input; expected <axis>."
                                     f"{{{', '.join(AXIS_INPUTS)}}} of an axis of the machine")
            if signal in writer:
                raise ParameterError(signal, f"{writer[signal]}, couplings.{c.name}",
                                     "a signal written by two parts")
            writer[signal] = f"couplings.{c.name}"
    # declare the axes once (no code is compiled) to know their states and signals
    b = codegen.Builder()
    _declare_axes(b, machine, None, set(writer), tuple(axis_names))
    _declare_part_states(b, machine)
    after: dict[str, set[str]] = {n: set() for n in axis_names}
    after.update({f"couplings.{c.name}": set() for c in machine.couplings})
    for signal, part in writer.items():
        after[signal.partition(".")[0]].add(part)
    for c in machine.couplings:
        me = f"couplings.{c.name}"
        for name in c.reads():
            rate = re.fullmatch(r"der\((.+)\)", name)
            target = rate.group(1) if rate else name
            if rate and target in b.state_index or target in writer:
                after[me].add(writer.get(target, target.partition(".")[0]))
            elif target in b.state_index:
                continue  # a state: known at the start of a call, no algebraic dependency
            elif target in b.aux_index:
                after[me].add(target.partition(".")[0])
            else:
                raise ParameterError(f"couplings.{c.name}", name,
                                     "a signal read that no axis or part writes")
    order: list[str] = []
    pending = dict(after)
    while pending:
        ready = [n for n, deps in pending.items() if deps <= set(order)]
        if not ready:
            loop = ", ".join(f"{n} after {' and '.join(sorted(d - set(order)))}"
                             for n, d in pending.items())
            raise ParameterError("couplings", sorted(writer),
                                 f"a cycle of algebraic signals: {loop}")
        order += ready
        for n in ready:
            del pending[n]
    return Plan(tuple(order), tuple(writer))


def _declare_part_states(b: Any, machine: Machine) -> None:
    """Every coupling part's own states, ``<part>.<state>``."""
    for c in machine.couplings:
        for state, (unit, kind, description, scale) in c.states().items():
            b.state(f"{c.name}.{state}", unit, description, kind, scale)


def _emit_coupling(b: Any, step: str, c: Coupling) -> None:
    """A coupling part's equations at the machine level: its parameters as slots
    ``couplings.<name>.<field>`` with their units (:attr:`Coupling.units`; a run's
    ``parameter_slots`` recorded none: session 27), their braced names replaced by the slots'
    code, every other braced name a signal the builder resolves and derives the flows from
    (:meth:`Builder.emit <feeddrive.model.codegen.Builder.emit>`)."""
    from ..model.codegen import SIGNAL

    slots = {}
    for key, value in c.parameters().items():  # each with the unit its class declares
        b.param(f"{step}.{key}", value, c.units[key])
        slots[key] = b.p(f"{step}.{key}")
    for signal, expression in c.equations().items():
        rate = re.fullmatch(r"der\((.+)\)", signal)
        if not rate and signal not in b.aux_index:  # an axis input, declared by its writer
            b.add_aux(signal, *AXIS_INPUTS[signal.partition(".")[2]])
        code = SIGNAL.sub(lambda m: slots.get(m.group(1), m.group(0)), expression)
        b.emit(f"{{{signal}}} = {code}")


def assemble_machine(machine: Machine, profile: MachineProfile) -> Any:
    """Build the one compiled model of a machine: every axis inside a scope of its name, the
    coupling parts between them in the order :func:`plan` finds.

    Parameters
    ----------
    machine : Machine
        The machine.
    profile : MachineProfile
        Each axis' reference.

    Returns
    -------
    Model
        The assembled model; its names are ``<axis>.<name>``.
    """
    from ..model import codegen
    from ..model.assemble import package

    steps = plan(machine)
    b = codegen.Builder()
    b.imports["_friction_law"] = "feeddrive.model.friction:friction_law"
    laws = _declare_axes(b, machine, profile, set(steps.inputs),
                         tuple(ax.name for ax in machine.axes))
    _declare_part_states(b, machine)
    parts = {f"couplings.{c.name}": c for c in machine.couplings}
    for step in steps.order:
        if step in parts:
            _emit_coupling(b, step, parts[step])
        else:
            b.call_scope(step)
    return package(b, machine.name, laws, None, b.control_axes)


@dataclass(frozen=True)
class MachineSystem:
    """A machine as the engine simulates it (the role :class:`~feeddrive.DriveSystem` has for
    one drive).

    The engine reads its first axis' parameter set where it needs one set (the controller's
    current limit for the tolerance scale, quantisation settings); a run's attributes record
    every axis' set (:meth:`parameter_sets`).

    Parameters
    ----------
    machine : Machine
        The machine.
    initial_state : mapping of str to float, default {}
        States by name (``"x.table_speed"``) [SI].
    load : None, default None
        No load record (the axes' loads come from their parameter sets and coupling parts).
    """

    machine: Machine
    initial_state: Mapping[str, float] = field(default_factory=dict)
    load: None = None

    @property
    def parameters(self) -> DriveParameters:
        """The first axis' parameter set."""
        return self.machine.axes[0].parameters

    def parameter_sets(self) -> dict[str, DriveParameters]:
        """Each axis' parameter set, by axis name in axis order: a run records each one
        (``<axis>_parameters_toml``, as each axis' start position) where one drive's run records
        its set (``parameters_toml``); it recorded the first axis' set alone (session 27).

        Returns
        -------
        dict of str to DriveParameters
            Axis name → its parameter set, as given.
        """
        return {ax.name: ax.parameters for ax in self.machine.axes}

    @property
    def drive(self) -> str:
        """The machine's name (the engine's label of the run; a run's ``drive`` attribute
        names its axes' drives, ``machine`` the machine: :meth:`run_attrs`)."""
        return self.machine.name

    @property
    def table_position(self) -> float:
        """The first axis' start position [m]."""
        return self.machine.axes[0].table_position

    @property
    def nut_hold(self) -> str:
        """The first axis' nut hold."""
        return self.machine.axes[0].nut_hold

    def model(self, profile: MachineProfile) -> Any:
        """The machine's assembled model following ``profile``.

        Parameters
        ----------
        profile : MachineProfile
            Each axis' reference.

        Returns
        -------
        Model
            The model (:func:`assemble_machine`).
        """
        if not isinstance(profile, MachineProfile):
            raise ParameterError("profile", type(profile).__name__,
                                 "a machine follows a MachineProfile (a contour's references)")
        return assemble_machine(self.machine, profile)

    def initial_vector(self, model: Any) -> np.ndarray:
        """Zeros except the states named in ``initial_state``.

        Parameters
        ----------
        model : Model
            The assembled model (its state order).

        Returns
        -------
        numpy.ndarray
            One value per state [SI, per state].
        """
        from ..engine.simulate import DriveSystem

        # the drive's own rule (it reads initial_state only)
        return DriveSystem.initial_vector(self, model)  # type: ignore[arg-type]

    def run_attrs(self, profile: Any) -> dict[str, Any]:
        """What marks a run of this machine in its attributes: the machine's name
        (``machine``), its axes' drives and parameter sets as one drive's run names its own
        (``drive``, ``parameter_set``, ``nut_hold``: the axes' values, each once, in axis
        order, ``", "``-joined where they differ), each axis' start position
        (``<axis>_table_start_position_m`` [m], a float), the path it followed, and its axes
        (``axes``: name → drive, parameter set, start position [m], nut hold, JSON;
        ``feeddrive.engine.machine_axes.machine_axes``).  A machine has no one start
        position: ``table_start_position_m`` is ``None`` (left out of the run's attributes).

        Every machine run carries them (:func:`simulate_machine`): a run following given
        references (a circular test's) lacked them and was read as one drive's, whose
        ``table_speed_reference`` it has not (an outside check, 2026-12-07).  ``drive`` and
        ``parameter_set`` held the machine's name, ``table_start_position_m`` the first
        axis' start alone (an outside check, 2026-12-07).

        Parameters
        ----------
        profile : MachineProfile or Contour
            What the run followed: a contour, or references (their contour if they have one).

        Returns
        -------
        dict
            ``machine``, ``drive``, ``parameter_set``, ``nut_hold``, ``profile``, ``axes``
            (str values), ``<axis>_table_start_position_m`` (float) and
            ``table_start_position_m`` (None).
        """
        contour = profile if isinstance(profile, Contour) else getattr(profile, "contour", None)
        if contour is not None:
            what = (f"{type(contour).__name__}(length={contour.length:g} m, "
                    f"feed={contour.feed:g} m/s)")
        else:
            what = f"{type(profile).__name__}({float(profile.time[-1]):g} s)"
        machine = self.machine

        def each(values: Any) -> str:  # each value once, in axis order
            return ", ".join(dict.fromkeys(values))

        return {"machine": machine.name,
                "drive": each(ax.drive for ax in machine.axes),
                "parameter_set": each(ax.parameters.name for ax in machine.axes),
                "nut_hold": each(ax.nut_hold for ax in machine.axes),
                "table_start_position_m": None,
                **{f"{ax.name}_table_start_position_m": float(ax.table_position)
                   for ax in machine.axes},
                "profile": what, "axes": json.dumps({
                    ax.name: {"drive": ax.drive, "parameter_set": ax.parameters.name,
                              "table_start_position_m": ax.table_position,
                              "nut_hold": ax.nut_hold} for ax in machine.axes})}


def simulate_machine(machine: Machine, contour: Contour | MachineProfile,
                     duration: float | None = None, *, options: Any = None,
                     interval: float | None = None,
                     progress: Callable[[float, float], None] | None = None) -> Any:
    """Simulate a machine following a contour (or given references).

    Parameters
    ----------
    machine : Machine
        The machine.
    contour : Contour or MachineProfile
        The path (its axes name two of the machine's), or each axis' reference (no contour
        error then).
    duration : float, optional
        Simulated time [s]; default the contour's duration (the references' length).
    options : SolverOptions, optional
        Integrator settings.
    interval : float, optional
        Grid spacing of the references [s].
    progress : callable, optional
        ``progress(t, t_end)`` after each chunk of the run (as
        :func:`feeddrive.simulate`); an exception it raises stops the run.

    Returns
    -------
    Result
        Every axis' states and signals as ``<axis>.<name>``, and ``contour_error`` [m]
        (signed normal distance of the actual point to the path).
    """
    from ..engine.result import Result
    from ..engine.simulate import simulate

    if isinstance(contour, MachineProfile):
        t_end = float(contour.time[-1]) if duration is None else float(duration)
        result = simulate(MachineSystem(machine), contour, t_end, options=options,  # type: ignore[arg-type]
                          progress=progress)
        return result
    profile = MachineProfile.from_contour(contour, machine, interval)
    t_end = contour.duration if duration is None else float(duration)
    result = simulate(MachineSystem(machine), profile, t_end, options=options,  # type: ignore[arg-type]
                      progress=progress)
    if isinstance(contour, Together):  # no path in a plane: no contour error
        return result
    ds = result.dataset
    a, b = contour.axes
    err = contour.contour_error(np.asarray(ds[f"{a}.table_position"]),
                                np.asarray(ds[f"{b}.table_position"]))
    ds["contour_error"] = ("time", err, {"units": "m", "long_name": "contour error (signed "
                                         "normal distance of the actual point to the path)"})
    return Result(ds)  # its attributes name the machine (MachineSystem.run_attrs)


#: the contour kinds :func:`make_contour` builds
CONTOURS = ("circle", "line", "corner", "csv", "together")


def make_contour(kind: str, *, feed: float, acceleration: float, radius: float = 0.05,
                 clockwise: bool = False, start_angle: float = 0.0, turns: float = 1.0,
                 length: float = 0.1, angle: float = 0.0, path_file: str | None = None,
                 axes: tuple[str, str] = ("x", "y")) -> Contour:
    """A contour by kind, from SI values (what ``simulate --machine`` passes on).

    Parameters
    ----------
    kind : str
        One of :data:`CONTOURS` (``together``: every axis moves ``length`` at once, a
        gantry's carriages).
    feed : float
        Path speed [m/s].
    acceleration : float
        Tangential acceleration of the lead-in and lead-out [m/s^2].
    radius : float, default 0.05
        Circle radius; corner blend radius [m].
    clockwise : bool, default False
        Circle sense.
    start_angle : float, default 0.0
        Circle start angle [rad].
    turns : float, default 1.0
        Circle revolutions [-].
    length : float, default 0.1
        Line length; corner leg length [m].
    angle : float, default 0.0
        Line direction [rad]; corner turn [rad] (0: 90°).
    path_file : str, optional
        CSV path file (x, y in mm).
    axes : tuple of str, default ("x", "y")
        The two axes.

    Returns
    -------
    Contour
        The path.
    """
    if kind == "circle":
        return Circle(feed=feed, acceleration=acceleration, axes=axes, radius=radius,
                      clockwise=clockwise, start_angle=start_angle, turns=turns)
    if kind == "together":
        return Together(feed=feed, acceleration=acceleration, axes=axes, distance=length)
    if kind == "line":
        return Line(feed=feed, acceleration=acceleration, axes=axes, distance=length,
                    angle=angle)
    if kind == "corner":
        return corner(feed=feed, acceleration=acceleration, axes=axes, leg=length,
                      radius=radius, angle=math.degrees(angle) if angle else 90.0)
    if kind == "csv":
        if path_file is None:
            raise ParameterError("contour.csv", MISSING, "a CSV path file is needed (x, y [mm])")
        return from_csv(path_file, feed=feed, acceleration=acceleration, axes=axes)
    raise ParameterError("contour", kind, f"expected one of {', '.join(CONTOURS)}")


def machine_summary(result: Any, machine: Machine, contour: Contour) -> dict[str, Any]:
    """The figures ``simulate --machine`` prints: per axis the largest following error, and
    the contour error's extremes (for a circle the mean radius and roundness after the
    lead-in) [SI].

    Parameters
    ----------
    result : Result
        A run of :func:`simulate_machine`.
    machine : Machine
        The machine.
    contour : Contour
        The path it followed.

    Returns
    -------
    dict
        ``machine``, ``axes`` (name → drive, set, largest |following error| [m]),
        ``contour_error_max``, ``contour_error_min`` [m] (not for ``Together``); for a
        circle ``mean_radius``,
        ``radius_reduction`` and ``roundness`` [m] over the cruise after the lead-in.
    """
    t = result.time
    out: dict[str, Any] = {
        "machine": machine.name, "contour": type(contour).__name__.lower(),
        "axes": {ax.name: {"drive": ax.drive, "parameter_set": ax.parameters.name,
                           "following_error_max": float(np.max(np.abs(
                               result[f"{ax.name}.following_error"])))}
                 for ax in machine.axes},
    }
    if "contour_error" not in result:  # every axis together: no path in a plane
        return out
    err = np.asarray(result["contour_error"])
    out.update(contour_error_max=float(np.max(err)), contour_error_min=float(np.min(err)))
    if isinstance(contour, Circle):
        cruise = (t >= contour.lead_in) & (t <= contour.length / contour.feed)
        if np.any(cruise):
            radius = contour.radius + err[cruise]
            out.update(mean_radius=float(np.mean(radius)),
                       radius_reduction=float(contour.radius - np.mean(radius)),
                       roundness=float(np.ptp(radius)))
    return out


def machine_toml(machine: Machine) -> str:
    """The machine as a machine file: each axis' drive, start position and nut hold (where
    its drive uses them: a ball screw's start position, a held nut's hold) and whole resolved
    parameter set under ``[axes.<name>]``, each coupling part under ``[couplings.<name>]``
    (SI units; read back by :func:`machine_from_dict` to the same machine).

    Parameters
    ----------
    machine : Machine
        The machine.

    Returns
    -------
    str
        TOML text.
    """
    from ..model.mechanisms import mechanism
    from ..parameters import dumps

    out = ["# feeddrive machine file. SI units throughout (docs/machine.md).",
           f"name = {json.dumps(machine.name)}", ""]
    for ax in machine.axes:
        topology = mechanism(ax.drive)
        out += [f"[axes.{ax.name}]", f"drive = {json.dumps(ax.drive)}"]
        if topology.uses_table_position:  # the reader refuses them where unused
            out.append(f"table_position = {ax.table_position!r}  # [m]")
        if topology.held_part(ax.drive) == "nut":
            out.append(f"nut_hold = {json.dumps(ax.nut_hold)}")
        for line in dumps(ax.parameters).splitlines():
            if line.startswith("#"):
                continue
            out.append(re.sub(r"^\[(.+)\]$", rf"[axes.{ax.name}.\1]", line))
        out.append("")
    for c in machine.couplings:
        out += [f"[couplings.{c.name}]", f"part = {json.dumps(c.part)}"]
        for f in c.fields():
            unit = f"  # [{c.units[f]}]" if f in c.units else ""
            out.append(f"{f} = {json.dumps(getattr(c, f))}{unit}")
        out.append("")
    return "\n".join(out)
