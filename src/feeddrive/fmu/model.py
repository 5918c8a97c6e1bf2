"""The model an FMU carries: the drive assembled with its reference and load read from inputs.

The reference is :class:`InputReference` (``feeddrive.model.reference.REF_INPUT``): the reference
kernel reads the commanded positions and speeds from a 4 × 2 block of the data table ``T``
that the FMU writes from its inputs at each communication point (co-simulation) or each
input change (model exchange).  The table load force is the parameter slot
``disturbances.load_force`` (acting from ``disturbances.load_start`` on), present in every
exported model (a zero load record makes the assembler emit it).  Nothing else differs from
the model ``feeddrive.simulate`` integrates.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import ModuleType

import numpy as np

from ..model.assemble import Model, assemble
from ..model.codegen import compile_module
from ..model.disturbances import LoadProfile
from ..model.reference import INPUT_INSTANT, KIND, REF_INPUT, TABLE_OFFSET
from ..parameters import DriveParameters
from ..parameters.validation import check_speed
from ..solvers import schedule, steps
from . import solver

# the zero load record that makes the assembler emit the load-force slot
_NO_LOAD = LoadProfile(time=np.array([0.0, 1.0]), force=np.zeros(2))


@dataclass(frozen=True)
class InputReference:
    """The reference as external inputs: start values of the table and nut speeds [m/s].

    Parameters
    ----------
    table_speed : float, default 0.0
        Start value of the table speed [m/s].
    nut_speed : float, default 0.0
        Start value of the nut speed [m/s].
    """

    table_speed: float = 0.0
    nut_speed: float = 0.0

    def encode(self) -> tuple[dict[int, float], np.ndarray]:
        """The reference as (parameter slots, data table) for the reference kernel: the
        external-input kind and a 4 × 2 table the host writes (speeds in rows 1 and 3).

        Returns
        -------
        slots : dict of int to float
            Profile-block slot → value.
        table : numpy.ndarray
            The 4 × 2 input table [m, m/s].

        Raises
        ------
        ParameterError
            For a start speed that is not a finite speed within
            :data:`~feeddrive.units.LARGEST_SPEED` (the shared
            :func:`~feeddrive.parameters.validation.check_speed`); the FMU's run-time inputs
            are checked by its C wrapper against their declared range (finite).
        """
        table = np.zeros((4, 2))
        table[1, 0] = check_speed("table_speed", self.table_speed, sign="any")
        table[3, 0] = check_speed("nut_speed", self.nut_speed, sign="any")
        return {KIND: REF_INPUT}, table


@dataclass(frozen=True)
class FmuModel:
    """The assembled model and where its inputs live (indices into ``P`` and ``T``).

    Parameters
    ----------
    model : Model
        The assembled model.
    drive : str
        The drive name.
    profile_offset : int
        First slot of the profile block in ``P``.
    table_offset : int
        First slot of the reference block in ``T``.
    load_slot : int
        ``P`` index of ``disturbances.load_force``.
    nut_inputs : bool
        The nut has a live axis (DDFS, or the CDFS nut on its servo).
    nut_position_input : bool
        ... with a position loop (``controller.nut_loop = "position"``).
    periods : dict of str to float
        The loops' sample periods by loop name [s]; 0 for continuous.
    parameters : DriveParameters
        The exported set (units of the parameter slots).
    table_position : float, default 0.4
        The nut's start position a [m].
    nut_hold : str, default "locked"
        How the CDFS holds its nut.
    solver_starts : dict of str to float, default {}
        Start values of the embedded solver's settings (:func:`feeddrive.fmu.solver_starts`);
        a setting not listed starts at its value in ``description.SETTINGS``.
    blocks : tuple of InputBlock, default ()
        One input block per axis of a machine (:func:`feeddrive.fmu.machine.build_machine`);
        empty for one drive, whose block is ``profile_offset``, ``table_offset`` and
        ``load_slot`` (:attr:`input_blocks`).
    """

    model: Model
    drive: str
    profile_offset: int  # first slot of the profile block in P
    table_offset: int  # first slot of the reference block in T
    load_slot: int  # P index of disturbances.load_force
    nut_inputs: bool  # the nut has a live axis (DDFS, or the CDFS nut on its servo)
    nut_position_input: bool  # ... with a position loop (controller nut_loop = "position")
    periods: dict[str, float]  # the loops' sample periods [s] (0: continuous), by loop name
    parameters: DriveParameters  # the exported set (units of the parameter slots)
    table_position: float = 0.4  # [m] the nut's start position a (ball-screw drives)
    nut_hold: str = "locked"
    # start values of the solver settings (feeddrive.fmu.solver_starts); others: SETTINGS'
    solver_starts: dict[str, float] = field(default_factory=dict)
    blocks: tuple[InputBlock, ...] = ()

    @property
    def input_blocks(self) -> tuple[InputBlock, ...]:
        """Where each block of inputs lives: the drive's one, or one per machine axis."""
        if self.blocks:
            return self.blocks
        return (InputBlock("", self.table_offset, self.profile_offset + INPUT_INSTANT,
                           self.load_slot, tuple(f"controller.{k}" for k in self.periods)),)


@dataclass(frozen=True)
class InputBlock:
    """One drive's (or machine axis') inputs in the model's arrays (``wrapper.c`` BLOCK_*).

    Parameters
    ----------
    prefix : str
        Prefix of its variables' names: ``""`` for one drive, ``"<axis>."`` on a machine.
    table_offset : int
        First slot of its reference block in ``T``.
    instant_slot : int
        ``P`` index of the instant its inputs were last written.
    load_slot : int
        ``P`` index its load-force input is written to.
    periods : tuple of str
        The parameter slots of its loops' sample periods (each a setting of the FMU, named
        as the slot).
    """

    prefix: str
    table_offset: int
    instant_slot: int
    load_slot: int
    periods: tuple[str, ...]


def build(parameters: DriveParameters, drive: str, table_position: float,
          nut_hold: str = "locked", table_speed: float = 0.0,
          nut_speed: float = 0.0) -> FmuModel:
    """Assemble ``drive`` with its reference and load force read from the FMU's inputs.

    Parameters
    ----------
    parameters : DriveParameters
        The parameter set [SI].
    drive : str
        The drive name.
    table_position : float
        The nut's start position a [m].
    nut_hold : str, default "locked"
        How the CDFS holds its nut.
    table_speed : float, default 0.0
        Start value of the table-speed input [m/s].
    nut_speed : float, default 0.0
        Start value of the nut-speed input [m/s].

    Returns
    -------
    FmuModel
        The model and the indices of its inputs.
    """
    from ..engine.simulate import DriveSystem

    system = DriveSystem(parameters, drive, table_position, nut_hold)  # simulate's checks
    profile = InputReference(table_speed, nut_speed)
    # assemble reads only a profile's encode(): InputReference is one (not a simulate profile)
    model = assemble(parameters, drive, table_position, nut_hold,
                     profile, _NO_LOAD)  # type: ignore[arg-type]
    names = model.parameter_names
    o = names.index("profile[0]")
    # the nut's reference inputs exist where the drive follows a nut reference (the DDFS); a
    # CDFS with its nut on the servo commands the held nut 0 and reads no nut input
    nut_inputs = ("controller.nut.kpp" in names and model.parameter("nut.active") > 0.5
                  and system.topology().follows("nut"))
    nut_position = nut_inputs and model.parameter("controller.nut.speed_mode") < 0.5
    return FmuModel(model=model, drive=drive, profile_offset=o,
                    table_offset=int(model.P[o + TABLE_OFFSET]),
                    load_slot=names.index("disturbances.load_force"),
                    nut_inputs=nut_inputs, nut_position_input=nut_position,
                    periods={"position_period": parameters.controller.position_period,
                             "velocity_period": parameters.controller.velocity_period,
                             "current_period": parameters.controller.current_period},
                    parameters=parameters, table_position=table_position, nut_hold=nut_hold)


def numba_module(model: Model) -> ModuleType:
    """The model's generated module with the FMU's integrator
    (:func:`feeddrive.fmu.solver.template_source`) and the steps it calls
    (:func:`feeddrive.solvers.steps.template_sources`) compiled beside its kernels
    (``module.advance``): the numba build of the FMU's integrator.

    Parameters
    ----------
    model : Model
        The assembled model.

    Returns
    -------
    module
        The compiled module, with ``advance``.
    """
    return compile_module("\n\n".join([model.source, *steps.template_sources(),
                                      solver.template_source()]) + "\n", [])


class NumbaCoSimulation:
    """The FMU's co-simulation step run through numba (the same integrator text as the C
    build): what the tests compare the FMU's binary with, and the benchmark's in-process
    reference.  ``inputs`` of :meth:`do_step` are held over the step, as the FMU holds them.

    Parameters
    ----------
    fm : FmuModel
        The assembled model.
    rtol : float, default 1e-6
        Relative tolerance [-].
    position_tolerance : float, default 1e-10
        Absolute tolerance of positions [m].
    speed_tolerance : float, default 1e-8
        Absolute tolerance of speeds [m/s].
    current_tolerance : float, default 1e-6
        Absolute tolerance of currents [A].
    h_max : float, default 1e-3
        Largest step [s].
    integrate_speed_reference : bool, default True
        Integrate the speed inputs into the position references, as the FMU does.
    max_steps : int, default 10000000
        Step limit per call.
    P : numpy.ndarray, optional
        Parameter vector to use instead of the model's [SI, per slot].
    """

    def __init__(self, fm: FmuModel, *, rtol: float = 1e-6, position_tolerance: float = 1e-10,
                 speed_tolerance: float = 1e-8, current_tolerance: float = 1e-6,
                 h_max: float = 1e-3, integrate_speed_reference: bool = True,
                 max_steps: int = 10_000_000, P: np.ndarray | None = None) -> None:
        from ..engine.simulate import sampling

        self.fm = fm
        m = fm.model
        self.module = numba_module(m)
        self.P = m.P.copy() if P is None else np.array(P, dtype=float)
        self.T = m.T.copy()
        self.n = len(m.states)
        self.y = np.zeros(self.n)
        self.held = np.zeros(m.n_held)
        self.held_prev = np.zeros(m.n_held)
        self.atol, self.rel = m.tolerances(position_tolerance, speed_tolerance,
                                           current_tolerance)
        self.rtol, self.h_max, self.max_steps = rtol, h_max, max_steps
        self.integrate = integrate_speed_reference
        self.work = [np.zeros(self.n) for _ in range(10)]
        self.aux = np.zeros(len(m.aux))
        self.memory = solver.new_memory(1e-6)
        self.grid: tuple[float, np.ndarray] | None = None  # breakpoint unit [s], schedule
        self.tick = m.continuous_ticks()
        self.t = 0.0
        self.x_int = np.zeros(2)  # integrals of the speed references (table, nut)
        self._sampling = sampling

    def start(self, params: DriveParameters, inputs: dict[str, float]) -> None:
        """Initialise as the FMU does: the sample grid, the inputs and the update at t = 0.

        Parameters
        ----------
        params : DriveParameters
            The parameter set (its sample periods).
        inputs : dict of str to float
            Input name → value [SI unit of the input].
        """
        m = self.fm.model
        for name, k in m.clocks:  # the loops' periods of ``params`` (the FMU's settings)
            if name.startswith("controller."):
                self.P[k] = getattr(params.controller, name.split(".", 1)[1])
        g = self._sampling(params, 1e-3, m, P=self.P)
        self.P = g.parameters(m, self.P)  # the periods on the grid, as the FMU writes them
        self.grid = (g.base, g.schedule)
        self._write_inputs(inputs)
        self.held_prev[:] = self.held  # as the FMU: the update at t0 is redone if the inputs
        if schedule.due(0, g.schedule, self.tick) > 0:
            self.module.sample_update(0.0, self.y, self.held, self.P, self.T, self.tick)
        self.memory[solver.MEM_AT_SAMPLE] = 1.0  # change before the first step
        self._last_inputs = dict(inputs)

    def _write_inputs(self, inputs: dict[str, float]) -> None:
        fm, T, to = self.fm, self.T, self.fm.table_offset
        vt = inputs.get("table_speed_reference", 0.0)
        vn = inputs.get("nut_speed_reference", 0.0)
        T[to] = self.x_int[0] if self.integrate else inputs.get("table_position_reference", 0.0)
        T[to + 2], T[to + 3] = vt, 0.0
        T[to + 4] = self.x_int[1] if self.integrate else inputs.get("nut_position_reference",
                                                                     0.0)
        T[to + 6], T[to + 7] = vn, 0.0
        self.P[fm.profile_offset + INPUT_INSTANT] = self.t
        self.P[fm.load_slot] = inputs.get("load_force", 0.0)

    def do_step(self, h: float, inputs: dict[str, float]) -> None:
        """Advance one communication step with the inputs held over it, as ``fmi2DoStep`` does.

        Parameters
        ----------
        h : float
            Step length [s].
        inputs : dict of str to float
            Input name → value [SI unit of the input].

        Raises
        ------
        RuntimeError
            When the integrator reports a failure (its status message).
        """
        assert self.grid is not None
        base, steps = self.grid
        redo = 1 if inputs != self._last_inputs else 0
        self._last_inputs = dict(inputs)
        self._write_inputs(inputs)
        w = self.work
        status = self.module.advance(
            self.t, self.t + h, 0.0, self.n, self.y, self.held, self.held_prev, self.P, self.T,
            steps, self.tick, base, self.rtol, self.atol, self.rel, self.h_max,
            self.max_steps, redo, self.memory, *w[:10], self.aux)
        if status != solver.STATUS_OK:
            raise RuntimeError(f"t = {self.t:g} s: {solver.STATUS_MESSAGES[status]}")
        self.x_int[0] += inputs.get("table_speed_reference", 0.0) * h
        self.x_int[1] += inputs.get("nut_speed_reference", 0.0) * h
        self.t += h
