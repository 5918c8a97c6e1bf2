"""Turn a list of parts into one compiled module: names, packed vectors, generated kernels.

Every part (mechanism, friction site, motor, controller axis, disturbance, profile) asks a
:class:`Builder` for the slots it needs — states, parameters, auxiliary signals, held
(sampled-controller) values, data tables — by *name*, and receives the index expression to
write into the code it emits (``y[4]``, ``P[17]``).  Nothing keeps indices by hand.

The emitted right-hand side, sampled-controller update and the solver template (see
:mod:`feeddrive.solvers.dopri5`) are written to a Python file named after a hash of its text
and of every kernel source it calls, in the package's numba cache folder, and imported.  numba's
on-disk cache is per source file, so each assembled model gets its own cache entry, a second
process loads it without compiling, and a change in any part's kernel gives a new file name
(numba itself only notices changes to the cached function's *own* file).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import inspect
import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any

import numpy as np

from .._jit import SOURCE_DIGEST, import_generated
from ..solvers.shared import binding_source

# Tolerance classes of a state: how its absolute tolerance follows from the solver options.
# "deflection": a friction law's internal state (a bristle, a GMS element, an observer's
# state), scaled by its own size (its steady deflection at the onset of sliding).
TOLERANCE_KINDS = ("position", "speed", "angle", "rotary_speed", "current", "current_integral",
                   "velocity_integral", "deflection", "none")
# Kinds whose error is also weighed relative to the state's size.
RELATIVE_KINDS = ("speed", "rotary_speed", "current")


#: a signal named in a part's code: ``{table_speed}``, ``{der(table_speed)}``, ``{f_d}``
SIGNAL = re.compile(r"\{([^{}]+)\}")
_RATE = re.compile(r"der\((.+)\)")
# an identifier of the code outside braces (not an attribute, not a number's exponent)
_IDENT = re.compile(r"(?<![\w.])[A-Za-z_]\w*")
# a state, rate or signal slot read by index instead of by its braced name
_HIDDEN = re.compile(r"(?<![\w.])(?:y|dy|aux)\s*\[")
# ``targets = value`` or ``target op= value``, the targets before the first lone ``=``
_ASSIGN = re.compile(r"^(?P<lhs>[^=]+?)\s*(?P<op>[-+*/]?)=(?!=)\s*(?P<rhs>.*)$")


@dataclass
class _Frame:
    """An ``if`` block of emitted right-hand-side code (:meth:`Builder.emit`): its header's
    indent, the local values before it, each finished branch's, and what its condition
    reads."""

    indent: int
    entry: dict[str, frozenset[str]]
    condition: frozenset[str]
    branches: list[dict[str, frozenset[str]]] = field(default_factory=list)
    has_else: bool = False


@dataclass(frozen=True)
class Line:
    """A line of right-hand-side code with what its text cannot show: the states of a block
    a kernel receives whole (``y``, ``dy`` and an offset — a friction law's or an observer's
    own states).  Everything the text names in braces is derived from it
    (:meth:`Builder.emit`); these are added to it.

    Parameters
    ----------
    text : str
        The code, signals named in braces.
    writes : tuple of str, default ()
        The further quantities the line sets (``"dy:<state>"``), computed from what its
        text reads and ``reads``.
    reads : tuple of str, default ()
        The further quantities it reads (``"y:<state>"``), for every value it sets.
    """

    text: str
    writes: tuple[str, ...] = ()
    reads: tuple[str, ...] = ()

    def indented(self, pad: str) -> Line:
        """The same line behind ``pad``.

        Parameters
        ----------
        pad : str
            The indentation to add.

        Returns
        -------
        Line
            The indented line.
        """
        return Line(pad + self.text, self.writes, self.reads)


@dataclass(frozen=True)
class Signal:
    """A named slot of the model: a state, an auxiliary output or a parameter.

    Parameters
    ----------
    name : str
        The slot's name (``table_speed``, ``friction.screw.bristle_stiffness``).
    unit : str
        Its unit (SI, e.g. ``"m/s"``).
    description : str
        A short description for listings and exports.
    kind : str, default ""
        Tolerance class of a state (one of ``TOLERANCE_KINDS``); empty for other slots.
    """

    name: str
    unit: str
    description: str
    kind: str = ""  # tolerance kind (states only)


@dataclass
class Builder:
    """Collects the named slots and the code lines of every part of one model.

    Parts call its methods; the assembler then packs the parameters and tables and writes the
    module.  The fields are the builder's bookkeeping, filled by those calls.

    Parameters
    ----------
    states, aux : list of Signal
        Declared states and auxiliary outputs, in index order.
    held : list of str
        Names of the values a sampled controller holds between updates.
    param_names : list of str
        Parameter names, in ``P`` order.
    param_values : list of float
        Parameter values, in ``P`` order [SI, per slot].
    param_units : dict of str to str
        Slot name → the unit its declaration gave (:meth:`param`'s ``unit``: a machine's
        coupling parameters); the other slots' units follow from their names
        (:func:`feeddrive.model.slots.slot_unit`).
    tables : list of numpy.ndarray
        Flat data tables (profiles, load records), concatenated into ``T`` [SI].
    rhs_lines, sample_lines : list of str
        Code lines of the right-hand side and of the sampled-controller update.
    imports : dict of str to str
        Kernel alias → ``"module:attr"`` the generated module imports.
    dynamic : dict of str to str
        Kernel alias → expression that finds a kernel at import time (registered laws).
    dynamic_sources : list of str
        Sources of those kernels (they enter the module's hash).
    flows : dict of str to set of str
        Written quantity → what it reads, derived from the code's text (:meth:`emit`); the
        Jacobian's pattern comes from it.
    table_size : int
        Total length of ``T`` so far.
    references : list of str
        The reference lines: each writes one reference signal the model follows, its
        position and speed values (``{ref_x}, {ref_v} = …``; the table's first, then those
        the topology asks for), at the head of the right-hand side and of the sampled update.
    tol_scale : dict of str to float
        State → its tolerance scale [m per state unit].
    derived : list of (Signal, str, float)
        Derived signals: (signal, source state or signal, factor [signal unit per source
        unit]).
    clocks : list of (str, int)
        Declared clocks: period slot and its index in ``P`` (:meth:`clock`).
    state_index, aux_index, param_index : dict of str to int
        Name → index in ``y``, ``aux`` and ``P``.
    namespace : str
        The scope being declared (:meth:`scope`); empty outside any.
    control_axes : tuple of ControlAxis
        The controller axes' declarations (:class:`feeddrive.model.loops.ControlAxis`).
    scoped_rhs, scoped_sample : dict of str to list of str
        Each scope's own right-hand-side and sampled-update lines.
    imposed : dict of str to str
        State name → the code its reads give instead of ``y[k]`` (an open-loop replay's
        imposed state, :mod:`feeddrive.model.replay`).
    values : set of str
        The named values parts have written with a braced target (``{f_d} = …``), model-wide
        names: the flow nodes other parts read as ``{f_d}``.
    """

    states: list[Signal] = field(default_factory=list)
    aux: list[Signal] = field(default_factory=list)
    held: list[str] = field(default_factory=list)
    param_names: list[str] = field(default_factory=list)
    param_values: list[float] = field(default_factory=list)
    param_units: dict[str, str] = field(default_factory=dict)
    tables: list[np.ndarray] = field(default_factory=list)
    rhs_lines: list[str] = field(default_factory=list)
    sample_lines: list[str] = field(default_factory=list)
    imports: dict[str, str] = field(default_factory=dict)  # alias -> "module:attr"
    dynamic: dict[str, str] = field(default_factory=dict)  # alias -> registry expression
    dynamic_sources: list[str] = field(default_factory=list)
    # quantity -> the quantities it is computed from (``flow``): the Jacobian's structure
    flows: dict[str, set[str]] = field(default_factory=dict)
    # the sample schedule: (name, index in P of its period [s]) of every sampled part
    clocks: list[tuple[str, int]] = field(default_factory=list)
    table_size: int = 0
    references: list[str] = field(default_factory=list)
    tol_scale: dict[str, float] = field(default_factory=dict)
    derived: list[tuple[Signal, str, float]] = field(default_factory=list)
    state_index: dict[str, int] = field(default_factory=dict)
    aux_index: dict[str, int] = field(default_factory=dict)
    param_index: dict[str, int] = field(default_factory=dict)
    # the part of a machine being declared (``scope``): its names are qualified
    # ``<scope>.<name>`` and its code goes into functions of its own
    namespace: str = ""
    # the controller axes' declarations (feeddrive.model.loops.ControlAxis), model-wide names
    control_axes: tuple[Any, ...] = ()
    scoped_rhs: dict[str, list[str]] = field(default_factory=dict)
    scoped_sample: dict[str, list[str]] = field(default_factory=dict)
    # state name -> code every read of it gives instead of ``y[k]`` (an open-loop replay's
    # imposed state, feeddrive.model.replay)
    imposed: dict[str, str] = field(default_factory=dict)
    # named values written by a braced target (``{f_d} = …``), model-wide names
    values: set[str] = field(default_factory=set)
    # per code stream (scope): the right-hand side's unbraced locals → what they are computed
    # from, and the ``if`` blocks open at the line being emitted
    _locals: dict[str, tuple[dict[str, frozenset[str]], list[_Frame]]] = field(
        default_factory=dict, init=False, repr=False)

    # ---- names
    def q(self, name: str) -> str:
        """The model-wide name of ``name`` as the part being declared calls it: itself
        outside a :meth:`scope`, ``<scope>.<name>`` inside one (``"x.table_speed"``).

        Parameters
        ----------
        name : str
            A state, signal, parameter, held value or part-level name.

        Returns
        -------
        str
            The qualified name.
        """
        return f"{self.namespace}.{name}" if self.namespace and name != "t" else name

    def _qflow(self, name: str) -> str:
        kind, sep, rest = name.partition(":")
        if sep and kind in ("y", "dy", "aux"):
            return f"{kind}:{self.q(rest)}"
        return self.q(name)

    def call_scope(self, name: str) -> None:
        """Run scope ``name``'s functions here, in the right-hand side and the sampled update.

        Parameters
        ----------
        name : str
            A scope declared with ``scope(name, call=False)``.
        """
        self.rhs_lines.append(f"_rhs_{name}(t, y, held, P, T, dy, aux)")
        self.sample_lines.append(f"_sample_{name}(t, y, held, P, T, tick)")

    @contextlib.contextmanager
    def scope(self, name: str, *, call: bool = True) -> Iterator[None]:
        """Declare one part of a machine (an axis): inside, every name is qualified
        ``<name>.…`` (:meth:`q`) and the code lines go into the scope's own functions
        ``_rhs_<name>`` and ``_sample_<name>``, called where the scope opens (their local
        variables — ``ref_x``, ``f_d`` … — stay the axis' own).

        Parameters
        ----------
        name : str
            The scope's name, an identifier (``"x"``).
        call : bool, default True
            Call its functions where the scope opens; False: where :meth:`call_scope` says
            (a machine declares every axis first and runs them in the order its parts need).

        Raises
        ------
        ValueError
            For a name that is no identifier, a scope opened twice or inside another.
        """
        if not name.isidentifier() or self.namespace or name in self.scoped_rhs:
            raise ValueError(f"scope {name!r}: expected a new identifier outside any scope")
        if call:
            self.call_scope(name)
        self.scoped_rhs[name], self.scoped_sample[name] = [], []
        saved = list(self.references)
        self.namespace = name
        try:
            yield
        finally:
            self.namespace = ""
            self.references = saved

    # ---- slots
    def state(self, name: str, unit: str, description: str, kind: str,
              scale: float = 1.0) -> int:
        """Declare a state of the model.

        Parameters
        ----------
        name : str
            The state's name; unique in the model.
        unit : str
            Its unit (SI).
        description : str
            A short description.
        kind : str
            Its tolerance class, one of ``TOLERANCE_KINDS`` (how its absolute tolerance follows
            from the solver options).
        scale : float, default 1.0
            Converts the solver's position and speed tolerances for angles: the transmission ratio
            H [m per state unit]; for a ``"deflection"`` state its size, the steady deflection
            at the onset of sliding [state unit].

        Returns
        -------
        int
            The state's index in ``y``.

        Raises
        ------
        ValueError
            When the name is declared twice or the kind is unknown.
        """
        name = self.q(name)
        self.tol_scale[name] = scale
        if name in self.state_index:
            raise ValueError(f"state {name!r} declared twice")
        if kind not in TOLERANCE_KINDS:
            raise ValueError(f"state {name!r}: unknown tolerance kind {kind!r}")
        self.state_index[name] = len(self.states)
        self.states.append(Signal(name, unit, description, kind))
        return self.state_index[name]

    def y(self, name: str) -> str:
        """Code that reads state ``name`` in the generated kernels.

        Parameters
        ----------
        name : str
            The declared name.

        Returns
        -------
        str
            The index expression, e.g. ``"y[4]"``, or the code of the value imposed on it
            (:attr:`imposed`).
        """
        q = self.q(name)
        return self.imposed.get(q) or f"y[{self.state_index[q]}]"

    def dy(self, name: str) -> str:
        """Code that reads the rate of state ``name`` in the generated kernels.

        The right-hand side assigns each state's rate through it.

        Parameters
        ----------
        name : str
            The declared name.

        Returns
        -------
        str
            The index expression, e.g. ``"dy[4]"``.
        """
        return f"dy[{self.state_index[self.q(name)]}]"

    def param(self, name: str, value: float, unit: str | None = None) -> int:
        """Register a named parameter.

        Parameters
        ----------
        name : str
            The parameter's path (``screw_motor.torque_constant``); unique in the model.
        value : float
            Its value [SI, the unit of the quantity it names].
        unit : str, optional
            Its unit ("-": dimensionless), recorded with the slot (:attr:`param_units`) for a
            slot whose name does not lead to a declaration (a machine's coupling parameter);
            None: the unit follows from the name (:func:`feeddrive.model.slots.slot_unit`).

        Returns
        -------
        int
            Its index in ``P``.

        Raises
        ------
        ValueError
            When the name is declared twice.
        """
        name = self.q(name)
        if name in self.param_index:
            raise ValueError(f"parameter {name!r} declared twice")
        self.param_index[name] = len(self.param_values)
        self.param_names.append(name)
        self.param_values.append(float(value))
        if unit is not None:
            self.param_units[name] = unit
        return self.param_index[name]

    def params(self, prefix: str, values: np.ndarray) -> int:
        """Register an unnamed block of parameters ``prefix[0]`` … ``prefix[n-1]``.

        Parameters
        ----------
        prefix : str
            The block's name.
        values : numpy.ndarray
            The values [SI, per slot].

        Returns
        -------
        int
            Offset of the first in ``P``.
        """
        first = len(self.param_values)
        for i, v in enumerate(np.asarray(values, dtype=float)):
            self.param(f"{prefix}[{i}]", float(v))
        return first

    def named_params(self, prefix: str, names: tuple[str, ...], values: np.ndarray) -> int:
        """Register a block of parameters ``prefix.<name>`` for each of ``names``, in order.

        Kernels add their part's named offsets (``P[o + SIGMA0]``) to the returned offset.

        Parameters
        ----------
        prefix : str
            The block's path (``friction.screw``).
        names : tuple of str
            The slot names, in kernel order.
        values : numpy.ndarray
            One value per name [SI, per slot].

        Returns
        -------
        int
            Offset of the first in ``P``.

        Raises
        ------
        ValueError
            When the number of values differs from the number of names.
        """
        values = np.asarray(values, dtype=float)
        if values.shape != (len(names),):
            raise ValueError(f"{prefix}: {values.size} values for {len(names)} named slots")
        first = len(self.param_values)
        for name, v in zip(names, values, strict=True):
            self.param(f"{prefix}.{name}", float(v))
        return first

    def p(self, name: str) -> str:
        """Code that reads parameter ``name`` in the generated kernels.

        Parameters
        ----------
        name : str
            The declared name.

        Returns
        -------
        str
            The index expression, e.g. ``"P[4]"``.
        """
        return f"P[{self.param_index[self.q(name)]}]"

    def add_aux(self, name: str, unit: str, description: str) -> int:
        """Declare an auxiliary output (a signal the right-hand side computes and the run records).

        Parameters
        ----------
        name : str
            The signal's name; unique among the auxiliary outputs.
        unit : str
            Its unit (SI).
        description : str
            A short description.

        Returns
        -------
        int
            Its index in ``aux``.

        Raises
        ------
        ValueError
            When the name is declared twice.
        """
        name = self.q(name)
        if name in self.aux_index:
            raise ValueError(f"auxiliary signal {name!r} declared twice")
        self.aux_index[name] = len(self.aux)
        self.aux.append(Signal(name, unit, description))
        return self.aux_index[name]

    def add_derived(self, name: str, unit: str, description: str, source: str,
                    factor: float) -> None:
        """Declare a signal that is a fixed multiple of a state or signal, computed when read.

        E.g. the screw's linear speed H·ω_s; nothing is added to the right-hand side.

        Parameters
        ----------
        name : str
            The signal's name; not already a state or signal.
        unit : str
            Its unit (SI).
        description : str
            A short description.
        source : str
            The state or auxiliary signal it is computed from.
        factor : float
            The multiple [unit of the signal per unit of the source].

        Raises
        ------
        ValueError
            When the name is already a state or signal.
        """
        name, source = self.q(name), self.q(source)
        if name in self.aux_index or name in self.state_index:
            raise ValueError(f"derived signal {name!r} is already a state or signal")
        self.derived.append((Signal(name, unit, description), source, float(factor)))

    def a(self, name: str) -> str:
        """Code that reads auxiliary output ``name`` in the generated kernels.

        Parameters
        ----------
        name : str
            The declared name.

        Returns
        -------
        str
            The index expression, e.g. ``"aux[4]"``.
        """
        return f"aux[{self.aux_index[self.q(name)]}]"

    def add_held(self, name: str) -> str:
        """Declare a value a sampled controller holds between its updates.

        Parameters
        ----------
        name : str
            The held value's name (``screw.current_command``).

        Returns
        -------
        str
            The index expression in ``held``, e.g. ``"held[2]"``.
        """
        self.held.append(self.q(name))
        return f"held[{len(self.held) - 1}]"

    def h(self, name: str) -> str:
        """Code that reads held value ``name`` in the generated kernels.

        Parameters
        ----------
        name : str
            The declared name.

        Returns
        -------
        str
            The index expression, e.g. ``"held[4]"``.
        """
        return f"held[{self.held.index(self.q(name))}]"

    def clock(self, name: str) -> int:
        """Declare a sampled part's clock, its period [s] the parameter slot ``name`` (0: the
        part runs continuously): the solver merges every clock's instants k·period into its
        event times and calls ``sample_update`` there with ``tick[c]``, the count k of the
        clock's instant now (−1: not one of its instants).  Returns the clock's index c: the
        sampled update tests ``tick[c] >= 0`` (``tick[c] == 0``: its first instant), the
        right-hand side ``P[<period>] > 0.0`` (sampled, holding its outputs) — a model reads
        its schedule from its parameter vector, the solver's call arguments stay the same
        for every model.

        Parameters
        ----------
        name : str
            The parameter slot of the period (already declared).

        Returns
        -------
        int
            The clock's index c.

        Raises
        ------
        ValueError
            When the clock is declared twice.
        """
        name = self.q(name)
        if any(n == name for n, _ in self.clocks):
            raise ValueError(f"clock {name!r} declared twice")
        self.clocks.append((name, self.param_index[name]))
        return len(self.clocks) - 1

    def tick(self, name: str) -> str:
        """Code of clock ``name``'s count at this instant in the sampled update (−1: none).

        Parameters
        ----------
        name : str
            The clock's period slot.

        Returns
        -------
        str
            E.g. ``"tick[1]"``.
        """
        return f"tick[{[n for n, _ in self.clocks].index(self.q(name))}]"

    def table(self, values: np.ndarray) -> int:
        """Append a flat data table (tabulated profile, load record) to ``T``.

        Parameters
        ----------
        values : numpy.ndarray
            The table's values, flattened in C order [SI].

        Returns
        -------
        int
            Its offset in ``T``.
        """
        flat = np.ascontiguousarray(values, dtype=float).ravel()
        offset = self.table_size
        self.tables.append(flat)
        self.table_size += flat.size
        return offset

    # ---- code
    def use(self, fn: Any) -> str:
        """Import a package kernel into the generated module.

        Parameters
        ----------
        fn : numba dispatcher or function
            The kernel (defined at module level, importable by ``module:name``).

        Returns
        -------
        str
            Its local alias in the generated code (module-qualified when two kernels share a
            name).
        """
        alias = f"_{fn.__name__}"
        target = f"{fn.__module__}:{fn.__name__}"
        if self.imports.get(alias, target) != target:
            alias = f"_{fn.__module__.rsplit('.', 1)[-1]}_{fn.__name__}"
        self.imports[alias] = target
        return alias

    def use_dynamic(self, alias: str, expression: str, kernel: Any) -> str:
        """Bind a kernel that the generated module finds at import time by an expression.

        For kernels defined outside the package (a friction law a user registered); its source
        enters the module's hash, so editing it gives a new compiled module.

        Parameters
        ----------
        alias : str
            Its local name in the generated code.
        expression : str
            Python expression that evaluates to the kernel at import time.
        kernel : numba dispatcher or function
            The kernel itself (for its source).

        Returns
        -------
        str
            ``alias``.
        """
        self.dynamic[alias] = expression
        self.dynamic_sources.append(source_of(getattr(kernel, "py_func", kernel)))
        return alias

    def signal(self, name: str, *, write: bool = False) -> tuple[str, str]:
        """The code and the flow name of a signal a part names in braces in its code.

        ``t`` is the time; ``der(<state>)`` a state's rate (``dy[k]``, ``dy:<state>``); a
        state reads ``y[k]`` (``y:<state>``); an auxiliary output ``aux[k]``
        (``aux:<signal>``); any other name is a value a part writes with a braced target
        (``{f_d} = …``: the local ``f_d``, flow name ``f_d``).  Names are the part's own
        (:meth:`q` qualifies them inside a :meth:`scope`).

        Parameters
        ----------
        name : str
            The braced name.
        write : bool, default False
            The name is written (a rate, an auxiliary output or a new named value), not read.

        Returns
        -------
        code : str
            Its code in the generated kernels.
        flow : str
            Its name in :attr:`flows`.

        Raises
        ------
        ValueError
            For a read of a name nothing writes, or a write to a state or the time.
        """
        rate = _RATE.fullmatch(name)
        if rate:
            q = self.q(rate.group(1))
            if q not in self.state_index:
                raise ValueError(f"{{{name}}}: {rate.group(1)!r} is no state of the model")
            return f"dy[{self.state_index[q]}]", f"dy:{q}"
        q = self.q(name)
        if name == "t" or q in self.state_index:
            if write:
                raise ValueError(f"{{{name}}}: a state or the time is read, not written; "
                                 f"write its rate {{der({name})}}")
            return ("t", "t") if name == "t" else (self.y(name), f"y:{q}")
        if q in self.aux_index:
            return self.a(name), f"aux:{q}"
        if write and name.isidentifier():
            self.values.add(q)
        if q not in self.values:
            raise ValueError(f"{{{name}}}: read but no part writes it (expected a state, "
                             "der(<state>), an auxiliary signal, t or a value written as "
                             f"{{{name}}} = …)")
        return name, q

    def resolve(self, text: str) -> tuple[str, list[str]]:
        """Replace every braced name of ``text`` by its code (:meth:`signal`).

        Parameters
        ----------
        text : str
            Code with signals named in braces (``"{v_t} * {table.mass}"`` is not: parameters
            are written as ``b.p(...)`` code).

        Returns
        -------
        code : str
            The code.
        reads : list of str
            The flow names of the braced names, in order.
        """
        reads: list[str] = []

        def one(match: re.Match[str]) -> str:
            code, flow = self.signal(match.group(1))
            reads.append(flow)
            return code

        return SIGNAL.sub(one, text), reads

    def _track(self, line: str, hidden: Line | None = None) -> str:
        """The code of one right-hand-side line, its flows recorded from its text.

        A braced target is a node of :attr:`flows` (a rate, an auxiliary output, a named
        value) and is computed from the braced names the line reads, the unbraced locals it
        reads standing for what they were computed from at that line (the last value in
        straight-line code, the union of the branches after an ``if``/``else``), and the
        conditions of the ``if`` blocks the line is in."""
        env, frames = self._locals.setdefault(self.namespace, ({}, []))
        indent = len(line) - len(line.lstrip(" "))
        body = line.strip()

        def expanded(template: str) -> tuple[str, frozenset[str]]:
            code, reads = self.resolve(template)
            found = set(reads)
            bare = SIGNAL.sub(" ", template)
            hidden = _HIDDEN.search(bare)
            if hidden:  # a slot read its text does not name: it would miss from the flows
                raise ValueError(f"emit: {body!r} reads {hidden.group(0)}…]; name the state "
                                 "or signal in braces ({<state>}, {der(<state>)}, {<signal>})")
            for name in _IDENT.findall(bare):
                found |= env.get(name, frozenset())
            return code, frozenset(found)

        branch = body == "else:" or body.startswith("elif ")
        while frames and indent <= frames[-1].indent:
            top = frames[-1]
            if indent == top.indent and branch:
                break
            frames.pop()
            ends = [*top.branches, dict(env), *(() if top.has_else else (top.entry,))]
            env.clear()
            for branch_env in ends:
                for name, reads in branch_env.items():
                    env[name] = env.get(name, frozenset()) | reads
        outer = frames[-1].condition if frames else frozenset()
        if branch:
            if not frames or frames[-1].indent != indent:
                raise ValueError(f"emit: {body!r} without its if")
            top = frames[-1]
            top.branches.append(dict(env))
            env.clear()
            env.update(top.entry)
            top.has_else = body == "else:"
            top.condition = top.condition | expanded(body)[1]
            return self.resolve(line)[0]
        if body.startswith("if ") and body.endswith(":"):
            frames.append(_Frame(indent, dict(env), outer | expanded(body)[1]))
            return self.resolve(line)[0]
        match = _ASSIGN.match(body)
        if body == "pass":
            return line
        if match is None:
            raise ValueError(f"emit: {body!r} is no assignment and no if/else")
        reads = expanded(match.group("rhs"))[1] | outer
        if hidden is not None:  # a kernel's own block: read and written beside the text
            reads |= {self._qflow(r) for r in hidden.reads}
            for w in hidden.writes:
                self.flows.setdefault(self._qflow(w), set()).update(reads)
        for target in (t.strip() for t in match.group("lhs").split(",")):
            braced = SIGNAL.fullmatch(target)
            if braced:
                flow = self.signal(braced.group(1), write=True)[1]
                if match.group("op"):
                    reads |= {flow}
                if flow == "t" or flow.startswith("y:"):
                    raise ValueError(f"emit: {body!r} writes {target}")
                self.flows.setdefault(flow, set()).update(reads)
            elif target.isidentifier():
                env[target] = reads | (env.get(target, frozenset()) if match.group("op")
                                       else frozenset())
            else:
                raise ValueError(f"emit: {body!r}: write {target!r} through a braced name "
                                 "({der(<state>)}, {<signal>}, {<value>}) or to a local")
        return self.resolve(line)[0]

    def emit(self, line: str | Line, *, sampled: bool = False) -> None:
        """Append a line of code to the right-hand side or to the sampled-controller update.

        Signals are named in braces (:meth:`signal`): ``{der(table_position)} = {v_t}``.  In
        the right-hand side, what each braced target is computed from follows from the text
        (:meth:`_track`) and enters :attr:`flows`, from which the Jacobian's pattern follows —
        a part declares nothing beside its code.

        Parameters
        ----------
        line : str or Line
            The code, without the function body's indentation; a :class:`Line` adds what
            its text cannot show (a kernel's own block of states).
        sampled : bool, default False
            Append to the sampled-controller update instead of the right-hand side.
        """
        text, hidden = (line.text, line) if isinstance(line, Line) else (line, None)
        code = self.resolve(text)[0] if sampled else self._track(text, hidden)
        if self.namespace:
            scoped = self.scoped_sample if sampled else self.scoped_rhs
            scoped[self.namespace].append(code)
        else:
            (self.sample_lines if sampled else self.rhs_lines).append(code)

    # ---- packing
    def packed_parameters(self) -> np.ndarray:
        """The parameter vector ``P`` the kernels read.

        Returns
        -------
        numpy.ndarray
            The values in index order [SI, per slot].
        """
        return np.array(self.param_values, dtype=float)

    def packed_tables(self) -> np.ndarray:
        """The data-table vector ``T``: every table concatenated.

        Returns
        -------
        numpy.ndarray
            The tables in offset order (one zero when there are none) [SI].
        """
        if not self.tables:
            return np.zeros(1)
        return np.concatenate(self.tables)


def index(value: int) -> str:
    """An offset into ``P`` or ``y`` as the generated code passes it to a friction law's
    kernel: ``int(value)``.  numba types a bare constant argument as ``Literal[int]`` and
    compiles the callee once per value; a friction site's offsets move with the structure
    (slot 71 in one model, 76 in the next), so each new structure compiled the friction
    kernels anew (≈ 0.45 s a site; 13–16 copies of each LuGre kernel in the cache after one
    `reproduce`).  Through ``int()`` the argument is typed ``int64`` and each kernel compiles
    once for every offset (the same arithmetic, so the same numbers); the C backend reads
    ``int()`` as a cast.  The other kernels keep their constant offsets: theirs do not move
    between structures (one or two copies each), and the torque-ripple harmonics are faster
    with them (the ripple DDFS right-hand side ≈ 50 % slower with an int64 offset, measured).

    Parameters
    ----------
    value : int
        The offset [-].

    Returns
    -------
    str
        Its text in the generated source.
    """
    return f"int({int(value)})"


@functools.lru_cache(maxsize=256)
def source_of(fn: Any) -> str:
    """Source text of a function, cached (``inspect.getsource`` re-reads the file each time).

    Parameters
    ----------
    fn : function
        The function.

    Returns
    -------
    str
        Its source, or its ``repr`` when the source is not available.
    """
    try:
        return inspect.getsource(fn)
    except (OSError, TypeError):
        return repr(fn)


def _indent(lines: list[str], level: int = 1) -> str:
    pad = "    " * level
    return "\n".join(pad + ln if ln else "" for ln in lines)


def rhs_source(builder: Builder) -> str:
    """The text of the generated right-hand side ``rhs(t, y, held, P, T, n_pos, n_vel, n_cur,
    dy, aux)``, without its decorator.

    Parameters
    ----------
    builder : Builder
        The builder every part has declared to.

    Returns
    -------
    str
        Python source of the function.
    """
    return ("def rhs(t, y, held, P, T, dy, aux):\n"
            + _indent(builder.rhs_lines or ["pass"]) + "\n")


def module_source(builder: Builder) -> str:
    """The full text of the generated module: imports, sizes, ``rhs``, ``sample_update`` and
    the solver drivers bound to them (``integrate``, ``integrate_dense``, ``auxiliary``: the
    drivers are compiled once for every model, :mod:`feeddrive.solvers.shared`).

    Parameters
    ----------
    builder : Builder
        The builder every part has declared to.

    Returns
    -------
    str
        Python source of the module.
    """
    head = [
        '"""Generated by feeddrive.model.codegen: one assembled drive model.  Do not edit."""',
        "import math",
        "import numpy as np",
        "from feeddrive._jit import kernel",
    ]
    for alias, target in sorted(builder.imports.items()):
        mod, attr = target.split(":")
        head.append(f"from {mod} import {attr} as {alias}")
    for alias, expression in sorted(builder.dynamic.items()):
        head.append(f"{alias} = {expression}")
    head += [
        f"N_STATE = {len(builder.states)}",
        f"N_AUX = {len(builder.aux)}",
        f"N_HELD = {max(1, len(builder.held))}",
        f"N_CLOCK = {max(1, len(builder.clocks))}",
        "",
        "",
    ]
    for name in builder.scoped_rhs:  # a machine's parts, each in functions of its own
        head += [
            "@kernel",
            f"def _rhs_{name}(t, y, held, P, T, dy, aux):",
            _indent(builder.scoped_rhs[name] or ["pass"]),
            "",
            "",
            "@kernel",
            f"def _sample_{name}(t, y, held, P, T, tick):",
            _indent(builder.scoped_sample[name] or ["pass"]),
            "",
            "",
        ]
    head += [
        "@kernel",
        rhs_source(builder),
        "",
        "@kernel",
        "def sample_update(t, y, held, P, T, tick):",
        _indent(builder.sample_lines or ["pass"]),
        "",
    ]
    return "\n".join(head) + "\n\n" + binding_source()


def compile_module(source: str, extra_sources: list[str]) -> ModuleType:
    """Write a generated module to the cache folder under a hash of its text and import it.

    The hash covers ``source``, the package's kernel sources and ``extra_sources``, so a change
    to any of them gives a new file and numba's per-file cache stays valid; imported once per
    process.

    Parameters
    ----------
    source : str
        Python source from :func:`module_source`.
    extra_sources : list of str
        Further sources that enter the hash (kernels of registered laws).

    Returns
    -------
    module
        The imported module.
    """
    digest = hashlib.sha256(source.encode())
    digest.update(SOURCE_DIGEST.encode())
    for s in extra_sources:
        digest.update(s.encode())
    return import_generated("models", f"model_{digest.hexdigest()[:20]}", source)


def __getattr__(name: str) -> Any:
    """Names that moved from here before 0.2.0: importable until 0.3.0, with a
    DeprecationWarning naming their new place (:mod:`feeddrive._compat`)."""
    from .. import _compat

    return _compat.moved(__name__, name)
