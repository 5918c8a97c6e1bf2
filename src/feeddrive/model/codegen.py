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

import functools
import hashlib
import importlib.util
import inspect
import os
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from .._jit import CACHE_DIR, SOURCE_DIGEST

# Tolerance classes of a state: how its absolute tolerance follows from the solver options.
TOLERANCE_KINDS = ("position", "speed", "angle", "rotary_speed", "current", "current_integral",
                   "velocity_integral", "none")
# Kinds whose error is also weighed relative to the state's size.
RELATIVE_KINDS = ("speed", "rotary_speed", "current")


@dataclass(frozen=True)
class Signal:
    """A named slot: state, auxiliary output or parameter."""

    name: str
    unit: str
    description: str
    kind: str = ""  # tolerance kind (states only)


@dataclass
class Builder:
    """Collects the slots and code lines of all parts of one model."""

    states: list[Signal] = field(default_factory=list)
    aux: list[Signal] = field(default_factory=list)
    held: list[str] = field(default_factory=list)
    param_names: list[str] = field(default_factory=list)
    param_values: list[float] = field(default_factory=list)
    tables: list[np.ndarray] = field(default_factory=list)
    rhs_lines: list[str] = field(default_factory=list)
    sample_lines: list[str] = field(default_factory=list)
    imports: dict[str, str] = field(default_factory=dict)  # alias -> "module:attr"
    dynamic: dict[str, str] = field(default_factory=dict)  # alias -> registry expression
    dynamic_sources: list[str] = field(default_factory=list)
    local_kernels: dict[str, int] = field(default_factory=dict)  # alias -> its state count
    # the sample schedule: (name, index in P of its period [s]) of every sampled part
    clocks: list[tuple[str, int]] = field(default_factory=list)
    table_size: int = 0
    reference_call: str = "(0.0, 0.0, 0.0, 0.0)"
    tol_scale: dict[str, float] = field(default_factory=dict)
    derived: list[tuple[Signal, str, float]] = field(default_factory=list)
    state_index: dict[str, int] = field(default_factory=dict)
    aux_index: dict[str, int] = field(default_factory=dict)
    param_index: dict[str, int] = field(default_factory=dict)

    # ---- slots
    def state(self, name: str, unit: str, description: str, kind: str,
              scale: float = 1.0) -> int:
        """Declare a state; ``scale`` [m per state unit] converts the solver's position and
        speed tolerances for angles (the transmission ratio H)."""
        self.tol_scale[name] = scale
        if name in self.state_index:
            raise ValueError(f"state {name!r} declared twice")
        if kind not in TOLERANCE_KINDS:
            raise ValueError(f"state {name!r}: unknown tolerance kind {kind!r}")
        self.state_index[name] = len(self.states)
        self.states.append(Signal(name, unit, description, kind))
        return self.state_index[name]

    def y(self, name: str) -> str:
        return f"y[{self.state_index[name]}]"

    def dy(self, name: str) -> str:
        return f"dy[{self.state_index[name]}]"

    def param(self, name: str, value: float) -> int:
        """Register parameter ``name`` (SI) and return its index in P."""
        if name in self.param_index:
            raise ValueError(f"parameter {name!r} declared twice")
        self.param_index[name] = len(self.param_values)
        self.param_names.append(name)
        self.param_values.append(float(value))
        return self.param_index[name]

    def params(self, prefix: str, values: np.ndarray) -> int:
        """Register a block of parameters ``prefix[0..n)``; return the offset of the first."""
        first = len(self.param_values)
        for i, v in enumerate(np.asarray(values, dtype=float)):
            self.param(f"{prefix}[{i}]", float(v))
        return first

    def named_params(self, prefix: str, names: tuple[str, ...], values: np.ndarray) -> int:
        """Register a block of parameters ``prefix.name`` for each of ``names`` (SI), in
        order; return the offset of the first (kernels add their part's named offsets)."""
        values = np.asarray(values, dtype=float)
        if values.shape != (len(names),):
            raise ValueError(f"{prefix}: {values.size} values for {len(names)} named slots")
        first = len(self.param_values)
        for name, v in zip(names, values, strict=True):
            self.param(f"{prefix}.{name}", float(v))
        return first

    def p(self, name: str) -> str:
        return f"P[{self.param_index[name]}]"

    def add_aux(self, name: str, unit: str, description: str) -> int:
        if name in self.aux_index:
            raise ValueError(f"auxiliary signal {name!r} declared twice")
        self.aux_index[name] = len(self.aux)
        self.aux.append(Signal(name, unit, description))
        return self.aux_index[name]

    def add_derived(self, name: str, unit: str, description: str, source: str,
                    factor: float) -> None:
        """Declare a signal that is ``factor`` times state or signal ``source`` (e.g. the
        screw's linear speed H·ω_s), computed from the recorded run when read."""
        if name in self.aux_index or name in self.state_index:
            raise ValueError(f"derived signal {name!r} is already a state or signal")
        self.derived.append((Signal(name, unit, description), source, float(factor)))

    def a(self, name: str) -> str:
        return f"aux[{self.aux_index[name]}]"

    def add_held(self, name: str) -> str:
        self.held.append(name)
        return f"held[{len(self.held) - 1}]"

    def h(self, name: str) -> str:
        return f"held[{self.held.index(name)}]"

    def clock(self, name: str) -> int:
        """Declare a sampled part's clock, its period [s] the parameter slot ``name`` (0: the
        part runs continuously): the solver merges every clock's instants k·period into its
        event times and calls ``sample_update`` there with ``tick[c]``, the count k of the
        clock's instant now (−1: not one of its instants).  Returns the clock's index c: the
        sampled update tests ``tick[c] >= 0`` (``tick[c] == 0``: its first instant), the
        right-hand side ``P[<period>] > 0.0`` (sampled, holding its outputs) — a model reads
        its schedule from its parameter vector, the solver's call arguments stay the same
        for every model."""
        if any(n == name for n, _ in self.clocks):
            raise ValueError(f"clock {name!r} declared twice")
        self.clocks.append((name, self.param_index[name]))
        return len(self.clocks) - 1

    def tick(self, name: str) -> str:
        """Code of clock ``name``'s count at this instant in the sampled update (−1: none)."""
        return f"tick[{[n for n, _ in self.clocks].index(name)}]"

    def table(self, values: np.ndarray) -> int:
        """Append a flat data table (profiles, load records); return its offset in T."""
        flat = np.ascontiguousarray(values, dtype=float).ravel()
        offset = self.table_size
        self.tables.append(flat)
        self.table_size += flat.size
        return offset

    # ---- code
    def use(self, fn: Any) -> str:
        """Import a package kernel into the generated module; return its local alias."""
        alias = f"_{fn.__name__}"
        target = f"{fn.__module__}:{fn.__name__}"
        if self.imports.get(alias, target) != target:
            alias = f"_{fn.__module__.rsplit('.', 1)[-1]}_{fn.__name__}"
        self.imports[alias] = target
        return alias

    def use_dynamic(self, alias: str, expression: str, kernel: Any) -> str:
        """A kernel found at import time by ``expression`` (e.g. a registered friction law
        defined outside the package); its source enters the module's hash."""
        self.dynamic[alias] = expression
        self.dynamic_sources.append(source_of(getattr(kernel, "py_func", kernel)))
        return alias

    def local_kernel(self, alias: str, n_states: int) -> None:
        """Declare that kernel ``alias`` reads only ``y[k : k + n_states]`` of the state array it
        is given (``k``: the argument after ``y``) and writes exactly ``dy`` at those places
        (the friction-law interface); the Jacobian's sparsity pattern relies on it
        (:mod:`feeddrive.model.sparsity`)."""
        self.local_kernels[alias] = n_states

    def emit(self, line: str, *, sampled: bool = False) -> None:
        (self.sample_lines if sampled else self.rhs_lines).append(line)

    # ---- packing
    def packed_parameters(self) -> np.ndarray:
        return np.array(self.param_values, dtype=float)

    def packed_tables(self) -> np.ndarray:
        if not self.tables:
            return np.zeros(1)
        return np.concatenate(self.tables)


@functools.lru_cache(maxsize=256)
def source_of(fn: Any) -> str:
    """Source text of a function (cached: ``inspect.getsource`` re-reads the file)."""
    try:
        return inspect.getsource(fn)
    except (OSError, TypeError):
        return repr(fn)


def _indent(lines: list[str], level: int = 1) -> str:
    pad = "    " * level
    return "\n".join(pad + ln if ln else "" for ln in lines)


def rhs_source(builder: Builder) -> str:
    """The generated right-hand side ``rhs`` (without its decorator)."""
    return ("def rhs(t, y, held, P, T, dy, aux):\n"
            + _indent(builder.rhs_lines or ["pass"]) + "\n")


def module_source(builder: Builder, solver_sources: list[str]) -> str:
    """The full text of the generated module."""
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
        "@kernel",
        rhs_source(builder),
        "",
        "@kernel",
        "def sample_update(t, y, held, P, T, tick):",
        _indent(builder.sample_lines or ["pass"]),
        "",
    ]
    return "\n".join(head) + "\n\n" + "\n\n".join(solver_sources) + "\n"


_LOADED: dict[str, ModuleType] = {}


def compile_module(source: str, extra_sources: list[str]) -> ModuleType:
    """Write ``source`` to the cache folder under a hash name and import it (once per process)."""
    digest = hashlib.sha256(source.encode())
    digest.update(SOURCE_DIGEST.encode())
    for s in extra_sources:
        digest.update(s.encode())
    key = digest.hexdigest()[:20]
    if key in _LOADED:
        return _LOADED[key]
    folder = Path(CACHE_DIR) / "models"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"model_{key}.py"
    if not path.is_file() or path.read_text(encoding="utf-8") != source:
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".model_{key}.", suffix=".tmp")
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(source)
        os.replace(tmp, path)  # atomic: concurrent processes never import a half file
    name = f"feeddrive_model_{key}"
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    _LOADED[key] = module
    return module
