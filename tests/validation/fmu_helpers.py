"""Shared by the FMU tests: scenarios, an fmpy run with the reference as an input table, and
the feeddrive run driven by the same zero-order-held reference."""

from __future__ import annotations

import ctypes
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from feeddrive.engine.simulate import DriveSystem, SolverOptions, simulate
from feeddrive.model.reference import SampledSpeed
from feeddrive.parameters import preset

#: the issue's scenarios (issue 20 item 5): drive, table speed, nut speed [mm/s]
SCENARIOS = {"cdfs-2": ("cdfs", 2.0, 0.0), "cdfs-1.2": ("cdfs", 1.2, 0.0),
             "ddfs-0.5-16": ("ddfs", 0.5, 16.0)}
#: communication step h [s] and the reference's start ramp [s] (as ConstantSpeed's default)
STEP = 1e-3
RAMP = 0.1
#: tolerances of both integrators in the comparison: 1000× tighter than feeddrive's defaults,
#: so the comparison measures the FMU, not the integrators' own error (with the defaults the
#: creeping CDFS at 1.2 mm/s differs by 2e-8 m of 12 mm between the two, stick-slip timing)
TIGHT = {"rtol": 1e-9, "position_tolerance": 1e-13, "speed_tolerance": 1e-11,
         "current_tolerance": 1e-9}
FMU_TIGHT = {"solver.relative_tolerance": 1e-9, "solver.position_tolerance": 1e-13,
             "solver.speed_tolerance": 1e-11, "solver.current_tolerance": 1e-9}


@dataclass(frozen=True)
class Reference:
    """A commanded speed ramp sampled at the communication points."""

    time: np.ndarray
    table_speed: np.ndarray  # [m/s]
    nut_speed: np.ndarray

    @classmethod
    def ramp(cls, table_mm_s: float, nut_mm_s: float, duration: float,
             step: float = STEP, ramp: float = RAMP) -> Reference:
        n = int(round(duration / step))
        t = np.arange(n + 1) * step
        f = np.minimum(t / ramp, 1.0) if ramp > 0 else np.ones_like(t)
        return cls(t, table_mm_s * 1e-3 * f, nut_mm_s * 1e-3 * f)

    def positions(self) -> tuple[np.ndarray, np.ndarray]:
        """Integrals of the held speeds at the sample times (what a set-point generator
        gives as position commands)."""
        dt = np.diff(self.time)
        xt = np.concatenate([[0.0], np.cumsum(self.table_speed[:-1] * dt)])
        xn = np.concatenate([[0.0], np.cumsum(self.nut_speed[:-1] * dt)])
        return xt, xn

    def profile(self, drive: str, hold: bool = True) -> SampledSpeed:
        """Held (as a co-simulation FMU holds its inputs over a step) or linearly
        interpolated (as fmpy interpolates a model exchange FMU's inputs)."""
        return SampledSpeed(self.time, self.table_speed,
                            self.nut_speed if drive == "ddfs" else None, hold=hold)


def input_table(ref: Reference, names: tuple[str, ...], *, with_positions: bool = False
                ) -> np.ndarray:
    xt, xn = ref.positions()
    columns = {"table_speed_reference": ref.table_speed, "nut_speed_reference": ref.nut_speed,
               "table_position_reference": xt, "nut_position_reference": xn}
    use = [n for n in names if n in columns and (with_positions or "speed" in n)]
    table = np.zeros(ref.time.size, dtype=[("time", "f8"), *((n, "f8") for n in use)])
    table["time"] = ref.time
    for n in use:
        table[n] = columns[n]
    return table


def run_fmu(path: Path, ref: Reference, *, start_values: dict | None = None,
            with_positions: bool = False, outputs: tuple[str, ...] = ("table_position",
                                                                      "table_speed"),
            **kw: object) -> np.ndarray:
    from fmpy import read_model_description, simulate_fmu

    md = read_model_description(str(path))
    inputs = tuple(v.name for v in md.modelVariables if v.causality == "input")
    values = dict(start_values or {})
    if with_positions:
        values["integrate_speed_reference"] = False
    return simulate_fmu(str(path), start_time=0.0, stop_time=float(ref.time[-1]),
                        output_interval=STEP, input=input_table(ref, inputs,
                                                                with_positions=with_positions),
                        start_values=values, output=list(outputs), **kw)


def run_feeddrive(drive: str, ref: Reference, params_name: str = "wang2021",
                  params: object = None, hold: bool = True,
                  **options: object):  # type: ignore[no-untyped-def]
    p = params if params is not None else preset(params_name)
    return simulate(DriveSystem(p, drive, 0.4), ref.profile(drive, hold), float(ref.time[-1]),
                    options=SolverOptions(**options))  # type: ignore[arg-type]


def on_grid(rec: np.ndarray, times: np.ndarray, name: str) -> np.ndarray:
    """The recorded ``name`` at ``times`` (the last record at each instant: model exchange
    records before and after an event)."""
    idx = np.searchsorted(rec["time"], times + 1e-9 * STEP, side="right") - 1
    return rec[name][idx]


def needed_libraries(fmu: Path, folder: Path) -> set[str]:
    """The NEEDED entries of the FMU's binary (readelf -d)."""
    import subprocess

    with zipfile.ZipFile(fmu) as zf:
        names = [n for n in zf.namelist() if n.startswith("binaries/")]
        zf.extractall(folder)
    out = subprocess.run(["readelf", "-d", str(folder / names[0])], capture_output=True,
                         text=True, check=True).stdout
    return {line.split("[", 1)[1].split("]", 1)[0] for line in out.splitlines()
            if "(NEEDED)" in line}


#: the logger callbacks of every Slave made (Slave: fmpy's proxy keeps the last one)
_KEEP_ALIVE: list[object] = []


class Slave:
    """A co-simulation FMU (FMI 2 or 3) driven step by step through fmpy, with the messages
    its logger receives kept in ``log`` ([(status, text)]) and uniform get/set by name."""

    def __init__(self, path: Path, folder: Path, name: str = "x") -> None:
        from fmpy import extract, read_model_description

        self.md = read_model_description(str(path))
        self.fmi = int(self.md.fmiVersion[0])
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.log: list[tuple[int, str]] = []
        unzipped = extract(str(path), unzipdir=str(folder / f"u-{name}"))
        ident = self.md.coSimulation.modelIdentifier
        if self.fmi == 2:
            from ctypes import byref

            from fmpy.fmi2 import (
                FMU2Slave,
                calloc,
                fmi2CallbackAllocateMemoryTYPE,
                fmi2CallbackFreeMemoryTYPE,
                fmi2CallbackFunctions,
                fmi2CallbackLoggerTYPE,
                free,
            )
            from fmpy.logging import addLoggerProxy

            def logger(env, inst, status, category, message):  # type: ignore[no-untyped-def]
                self.log.append((int(status), message.decode("utf-8")))

            cb = fmi2CallbackFunctions()
            cb.logger = fmi2CallbackLoggerTYPE(logger)
            cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
            cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
            addLoggerProxy(byref(cb))
            # fmpy's native proxy keeps the last logger it wrapped in a global: every FMI 2
            # instance made after this one (fmpy's default callbacks too) logs through it, so
            # it must outlive this instance (else a later instance's message calls freed
            # memory)
            _KEEP_ALIVE.append(cb)
            self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=unzipped,
                                 modelIdentifier=ident, instanceName=name)
            self.fmu.instantiate(callbacks=cb)
        else:
            from fmpy.fmi3 import FMU3Slave

            def log3(env, status, category, message):  # type: ignore[no-untyped-def]
                self.log.append((int(status), message.decode("utf-8")))

            self.fmu = FMU3Slave(guid=self.md.guid, unzipDirectory=unzipped,
                                 modelIdentifier=ident, instanceName=name)
            self.fmu.instantiate(logMessage=log3)
        self.t = 0.0

    def set(self, name: str, value: float) -> None:
        vr, kind = [self.vr[name]], self.types[name]
        f = self.fmu
        if kind in ("Integer", "Int64"):
            (f.setInteger if self.fmi == 2 else f.setInt64)(vr, [int(value)])
        elif kind == "Boolean":
            f.setBoolean(vr, [bool(value)])
        else:
            (f.setReal if self.fmi == 2 else f.setFloat64)(vr, [float(value)])

    def get(self, name: str) -> float:
        vr, kind = [self.vr[name]], self.types[name]
        f = self.fmu
        if kind in ("Integer", "Int64"):
            return float((f.getInteger if self.fmi == 2 else f.getInt64)(vr)[0])
        return float((f.getReal if self.fmi == 2 else f.getFloat64)(vr)[0])

    def initialize(self, start: float = 0.0) -> None:
        if self.fmi == 2:
            self.fmu.setupExperiment(startTime=start)
            self.fmu.enterInitializationMode()
        else:
            self.fmu.enterInitializationMode(startTime=start)
        self.fmu.exitInitializationMode()
        self.t = start

    def step(self, h: float) -> None:
        self.fmu.doStep(currentCommunicationPoint=self.t, communicationStepSize=h)
        self.t += h

    def reset(self) -> None:
        self.fmu.reset()
        self.t = 0.0

    def free(self) -> None:
        self.fmu.terminate()
        self.fmu.freeInstance()


def require_c_compiler() -> None:
    """Skip the calling test module when this machine has no C compiler (CI has one)."""
    import pytest

    from feeddrive.backends.c_backend import CompilerNotFound, find_compiler

    try:
        find_compiler()
    except CompilerNotFound:  # pragma: no cover - CI has a compiler
        pytest.skip("no C compiler", allow_module_level=True)


def pathsim_model_exchange(path: Path, duration: float, use_them: bool
                           ) -> tuple[tuple[int, int], np.ndarray, np.ndarray, float]:
    """The DDFS model-exchange FMU ``path`` in PathSim (pathsim-fmi's ModelExchangeFMU,
    ESDIRK4 at a fixed 0.1-ms step, fixed-point tolerance 1e-12, 0.5 mm/s with v_n = 16 mm/s
    from rest) for ``duration`` [s], with the FMU's directional derivatives (``use_them``) or
    with PathSim's own central differences.  Returns the FMU's counters (derivative and
    tangent evaluations), the recorded time and table position, and the CPU time [s]."""
    import time

    from pathsim import Connection, Simulation
    from pathsim.blocks import Constant, Scope
    from pathsim.solvers import ESDIRK4
    from pathsim_fmi import ModelExchangeFMU

    fmu = ModelExchangeFMU(str(path))
    assert fmu.op_dyn._jac_x is not None  # it reads providesDirectionalDerivative
    if not use_them:
        fmu.op_dyn._jac_x = None
    v_t, v_n = Constant(0.5e-3), Constant(16e-3)
    scope = Scope(labels=["table_position"])
    sim = Simulation([v_t, v_n, fmu, scope],
                     [Connection(v_t, fmu["table_speed_reference"]),
                      Connection(v_n, fmu["nut_speed_reference"]),
                      Connection(fmu["table_position"], scope)],
                     dt=1e-4, Solver=ESDIRK4, tolerance_fpi=1e-12, log=False)
    t0 = time.process_time()
    sim.run(duration)
    cpu = time.process_time() - t0
    w = fmu.fmu_wrapper
    vr = {v.name: v.valueReference for v in w.model_description.modelVariables}
    rhs, tangents = w.fmu.getInteger([vr["evaluations.derivatives"],
                                      vr["evaluations.tangents"]])
    t, (x,) = scope.read()
    return (int(rhs), int(tangents)), np.asarray(t), np.asarray(x), cpu


class Model:
    """A model-exchange FMU in continuous-time mode through fmpy (FMI 2 or 3)."""

    def __init__(self, path: Path, folder: Path) -> None:
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Model
        from fmpy.fmi3 import FMU3Model

        self.md = md = read_model_description(str(path))
        self.fmi = int(md.fmiVersion[0])
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.var = {v.name: v for v in md.modelVariables}
        cls = FMU2Model if self.fmi == 2 else FMU3Model
        self.fmu = cls(guid=md.guid, unzipDirectory=extract(str(path), unzipdir=str(folder)),
                       modelIdentifier=md.modelExchange.modelIdentifier, instanceName="m")
        self.log: list[tuple[int, str]] = []
        if self.fmi == 2:
            self.fmu.instantiate()
            self.fmu.setupExperiment(startTime=0.0)
            self.fmu.enterInitializationMode()
        else:
            def log3(env, status, category, message):  # type: ignore[no-untyped-def]
                self.log.append((int(status), message.decode("utf-8")))

            self.fmu.instantiate(logMessage=log3)
            self.fmu.enterInitializationMode(startTime=0.0)
        self.states = [d.variable.derivative for d in md.derivatives]
        self.ders = [d.variable for d in md.derivatives]
        self.n = len(self.ders)

    def start(self, inputs: dict[str, float]) -> None:
        for name, value in inputs.items():
            self.set(name, value)
        self.fmu.exitInitializationMode()
        if self.fmi == 2:
            self.fmu.newDiscreteStates()
        else:
            self.fmu.updateDiscreteStates()
        self.fmu.enterContinuousTimeMode()

    def _ptr(self, a: np.ndarray):  # type: ignore[no-untyped-def]
        return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))

    def set(self, name: str, value: float) -> None:
        f = self.fmu.setReal if self.fmi == 2 else self.fmu.setFloat64
        f([self.vr[name]], [value])

    def get(self, names: list[str]) -> np.ndarray:
        f = self.fmu.getReal if self.fmi == 2 else self.fmu.getFloat64
        return np.array(f([self.vr[n] for n in names]))

    def states_at(self, t: float, x: np.ndarray) -> None:
        self.fmu.setTime(t)
        self.fmu.setContinuousStates(self._ptr(np.ascontiguousarray(x, float)), self.n)

    def derivatives(self) -> np.ndarray:
        dx = np.zeros(self.n)
        if self.fmi == 2:
            self.fmu.getDerivatives(self._ptr(dx), self.n)
        else:
            self.fmu.getContinuousStateDerivatives(self._ptr(dx), self.n)
        return dx

    def nominals(self) -> np.ndarray:
        out = np.zeros(self.n)
        self.fmu.getNominalsOfContinuousStates(self._ptr(out), self.n)
        return out

    def directional(self, unknowns: list[int], knowns: list[int], seed: list[float]
                    ) -> np.ndarray:
        return np.array(self.fmu.getDirectionalDerivative(unknowns, knowns, seed))

    def count(self, name: str) -> int:
        f = self.fmu.getInteger if self.fmi == 2 else self.fmu.getInt64
        return int(f([self.vr[name]])[0])


def richardson(f, x0: float, h: float) -> np.ndarray:  # type: ignore[no-untyped-def]
    """d f / d x at x0 by Richardson-extrapolated central differences (O(h^4))."""
    d1 = (f(x0 + h) - f(x0 - h)) / (2 * h)
    d2 = (f(x0 + 2 * h) - f(x0 - 2 * h)) / (4 * h)
    return (4 * d1 - d2) / 3


def check_jacobian(m: Model, t: float, x: np.ndarray, case: str) -> int:
    """Every declared (state, derivative) pair of the model-exchange FMU ``m`` at (t, x): its
    directional derivative equals the Richardson-extrapolated central difference of its own
    derivatives to 1e-6 relative; where the pattern declares nothing the differences vanish
    too (the declared sparsity holds).

    Returns
    -------
    int
        How many pairs were live (checked against a non-zero difference).
    """
    nominal = m.nominals()
    ders = [d.valueReference for d in m.ders]
    states = [s.valueReference for s in m.states]

    def f_of(j: int):  # type: ignore[no-untyped-def]
        def f(xj: float) -> np.ndarray:
            xx = x.copy()
            xx[j] = xj
            m.states_at(t, xx)
            return m.derivatives()
        return f

    J = np.zeros((m.n, m.n))
    D = np.zeros((m.n, m.n))
    for j in range(m.n):
        m.states_at(t, x)
        seed = [0.0] * m.n
        seed[j] = 1.0
        J[:, j] = m.directional(ders, states, seed)
        D[:, j] = richardson(f_of(j), x[j], 1e-4 * nominal[j])
    declared = np.zeros((m.n, m.n), dtype=bool)
    index = {s.name: j for j, s in enumerate(m.states)}
    for i, d in enumerate(m.md.derivatives):
        for v in d.dependencies:
            if v.name in index:
                declared[i, index[v.name]] = True
    # a difference's own rounding noise, row by row: ε·|f_i| / h_j (with a factor 100)
    m.states_at(t, x)
    f0 = np.abs(m.derivatives())
    noise = 100 * np.finfo(float).eps * np.outer(np.maximum(f0, 1e-300),
                                                 1.0 / (1e-4 * nominal))
    checked = 0
    for i in range(m.n):
        for j in range(m.n):
            if declared[i, j]:
                if abs(D[i, j]) > noise[i, j]:
                    assert abs(J[i, j] - D[i, j]) <= 1e-6 * abs(D[i, j]), (case, i, j)
                    checked += 1
                else:  # zero here (a switched-off part): the tangent says so too
                    assert abs(J[i, j]) <= noise[i, j], (case, i, j)
            else:
                assert J[i, j] == 0.0 and abs(D[i, j]) <= noise[i, j], (case, i, j)
    return checked


class SharedExports:
    """FMUs exported once per test session and read by every test that only simulates,
    validates or inspects them (the ``shared_fmus`` fixture of conftest.py): the same
    ``export_fmu`` / ``export_machine_fmu`` call with the same arguments was made again by
    several test files (the DDFS model-exchange FMU by four of them, ≈ 2 s of code generation
    and gcc each).

    An FMU is keyed by everything its export reads: the parameter set's full text
    (:func:`feeddrive.parameters.dumps`, its name and ``[solver]`` table with where each came
    from), the drive, the FMI version, the kind and the other arguments (a machine: the key
    its caller gives, its definition's text).  The file and the :class:`ExportedFmu` the
    export returned live in the session's shared folder (one export for every pytest-xdist
    worker, made under a file lock as the session's one ``feeddrive reproduce`` is); nothing
    outlives the session, so each session exports anew.  Tests only read the files (each
    unzips into a folder of its own); tests of the export itself (its command line, its
    environment, its platforms) still export their own."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        folder.mkdir(parents=True, exist_ok=True)
        self._made: dict[str, object] = {}

    def _get(self, key: str, make):  # type: ignore[no-untyped-def]
        import hashlib
        import pickle

        from reproduce_session import locked

        name = hashlib.sha256(key.encode("utf-8")).hexdigest()[:24]
        if name not in self._made:
            path = self.folder / f"{name}.fmu"
            record = self.folder / f"{name}.pickle"
            with locked(self.folder / f"{name}.lock"):
                if not record.exists():
                    exported = make(path)
                    record.write_bytes(pickle.dumps(exported))
            self._made[name] = pickle.loads(record.read_bytes())  # noqa: S301 - our own file
        return self._made[name]

    def problems(self, path: Path) -> list[str]:
        """``fmpy.validation.validate_fmu(path)`` of a shared FMU, run once for every test
        that asserts it (≈ 1 s each: fmpy parses every variable name with its Earley
        grammar); test_fmu.py and test_fmu_metadata.py validate the same four DDFS FMUs."""
        import json

        from fmpy.validation import validate_fmu
        from reproduce_session import locked

        path = Path(path)
        assert path.parent == self.folder, path  # only a file of this cache: never changed
        record = path.with_suffix(".problems.json")
        with locked(path.with_suffix(".lock")):
            if not record.exists():
                record.write_text(json.dumps([str(p) for p in validate_fmu(str(path))]),
                                  encoding="utf-8")
        return list(json.loads(record.read_text(encoding="utf-8")))

    def drive(self, params: object, drive: str, *, fmi: int = 2, kind: str = "cs",
              **kw: object):  # type: ignore[no-untyped-def]
        """``export_fmu(params, drive, <file>, fmi=fmi, kind=kind, **kw)``, made once: its
        :class:`~feeddrive.fmu.ExportedFmu` (``.path``: the file)."""
        import inspect

        from feeddrive.fmu import export_fmu
        from feeddrive.parameters import dumps

        # every keyword argument, a default one too: nut_hold="locked" given or not, one FMU
        args = inspect.signature(export_fmu).bind(params, drive, "x.fmu", fmi=fmi, kind=kind,
                                                  **kw)
        args.apply_defaults()
        given = {k: v for k, v in args.arguments.items()
                 if k not in ("parameters", "drive", "out")}
        key = repr(("drive", dumps(params), params.solver, drive,  # type: ignore[attr-defined]
                    sorted(given.items())))
        return self._get(key, lambda path: export_fmu(params, drive, path, fmi=fmi,  # type: ignore[arg-type]
                                                      kind=kind, **kw))

    def machine(self, key: str, machine: object, *, fmi: int = 2, kind: str = "cs"):  # type: ignore[no-untyped-def]
        """``export_machine_fmu(machine, <file>, fmi=fmi, kind=kind)``, made once per ``key``
        (the machine's definition: a name of ``load_machine`` or its dict's text)."""
        from feeddrive.fmu import export_machine_fmu

        return self._get(repr(("machine", key, fmi, kind)),
                         lambda path: export_machine_fmu(machine, path, fmi=fmi,  # type: ignore[arg-type]
                                                         kind=kind))
