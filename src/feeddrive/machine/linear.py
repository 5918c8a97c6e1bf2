"""The loops of a machine: each axis' own, and the MIMO closed loop of the whole machine.

Per axis, :func:`axis_loops` is the single-drive
:func:`~feeddrive.analysis.linear.loop_analysis` of that axis (its coupling parts left
out).  :func:`linearize_machine` linearises the one assembled model of the machine — every
axis and coupling part — at the axes' steady sliding states, by central differences of its
right-hand side (the method of :func:`~feeddrive.analysis.linear.linearize`): a
python-control ``StateSpace`` (:meth:`MachineLinearModel.to_control`) whose inputs are every
axis' ``<axis>.table_position_reference`` and ``<axis>.load_force`` and whose outputs are
every axis' ``<axis>.table_position`` and ``<axis>.following_error``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from ..analysis.linear import (
    _INPUT_STEP,
    LinearModel,
    LoopAnalysis,
    _Evaluator,
    _frictionless,
    _input_columns,
    _live_states,
    _scales,
    _state_steps,
    loop_analysis,
    steady_state,
)
from ..engine.simulate import DriveSystem
from ..model.reference import ConstantSpeed
from . import Machine, MachineAxis, MachineProfile, assemble_machine

__all__ = ["MachineLinearModel", "axis_loops", "cross_coupling", "gain_limit", "linearize_machine",
           "spectral_abscissa"]


class MachineLinearModel(LinearModel):
    """A machine's linearised closed loop (:class:`~feeddrive.analysis.linear.LinearModel`),
    its names ``<axis>.<name>``.

    python-control reserves ``.`` for ``system.signal`` in ``interconnect``: the
    ``StateSpace`` of :meth:`to_control` names them ``<axis>:<name>``
    (``x:table_position_reference``).

    Parameters
    ----------
    A, B, C, D : numpy.ndarray
        The state-space matrices [SI].
    states, inputs, outputs : tuple of str
        Names ``<axis>.<name>``.
    operating_point : dict of str to float
        The steady state by state name [SI, per state].
    table_speed : float
        The largest axis speed of the operating point [m/s].
    nut_speed : float
        0 [m/s].
    frictionless : bool
        Whether the friction sites were left out.
    notes : tuple of str, default ()
        Warnings.
    axes : tuple of str, default ()
        Unused (the machine's inputs and outputs are named per axis).
    """

    def to_control(self) -> Any:
        """The model as a python-control ``StateSpace`` named ``<axis>:<name>``.

        Returns
        -------
        control.StateSpace
            With the state, input and output names, ``.`` written ``:``.
        """
        import control

        def names(seq: tuple[str, ...]) -> list[str]:
            return [n.replace(".", ":") for n in seq]

        return control.ss(self.A, self.B, self.C, self.D, states=names(self.states),
                          inputs=names(self.inputs), outputs=names(self.outputs),
                          name="machine")


def _system(ax: MachineAxis, frictionless: bool) -> DriveSystem:
    system = DriveSystem(ax.parameters, ax.drive, ax.table_position, ax.nut_hold)
    return _frictionless(system) if frictionless else system


def axis_loops(machine: Machine, table_speed: float = 1e-3, *,
               frictionless: bool = True) -> dict[str, LoopAnalysis]:
    """Each axis' loops on its own (its coupling parts left out).

    Parameters
    ----------
    machine : Machine
        The machine.
    table_speed : float, default 1e-3
        Steady table speed of every axis' operating point [m/s].
    frictionless : bool, default True
        Linearise with every friction law set to "none".

    Returns
    -------
    dict of str to LoopAnalysis
        Axis name → its poles, margins and bandwidths.
    """
    return {ax.name: loop_analysis(_system(ax, False), table_speed,
                                   frictionless=frictionless) for ax in machine.axes}


def linearize_machine(machine: Machine, table_speeds: Mapping[str, float] | None = None, *,
                      frictionless: bool = True) -> MachineLinearModel:
    """The machine's closed loop linearised at its axes' steady sliding states.

    Each axis' operating point is its own steady state at its table speed (the single-drive
    :func:`~feeddrive.analysis.linear.steady_state`); the coupling parts are evaluated at
    that point, not solved for (a note says so when the machine has any).

    Parameters
    ----------
    machine : Machine
        The machine (continuous loops).
    table_speeds : mapping of str to float, optional
        Steady table speed per axis [m/s] (default 0 for every axis: at rest, which needs
        ``frictionless``).
    frictionless : bool, default True
        Linearise with every friction law set to "none".

    Returns
    -------
    MachineLinearModel
        A, B, C, D over the live states of every axis; inputs
        ``<axis>.table_position_reference`` [m] and ``<axis>.load_force`` [N], outputs
        ``<axis>.table_position`` and ``<axis>.following_error`` [m]
        (``to_control()``: a python-control ``StateSpace``, the names ``<axis>:<name>``).
    """
    from ..parameters import ParameterError
    from ..parameters.validation import check_flag

    frictionless = check_flag("frictionless", frictionless)  # "yes" was read as true
    speeds = {ax.name: 0.0 for ax in machine.axes} | dict(table_speeds or {})
    unknown = sorted(set(speeds) - {ax.name for ax in machine.axes})
    if unknown:
        machine.axis(unknown[0])
    if not frictionless and any(v == 0.0 for v in speeds.values()):
        raise ParameterError("table_speeds", speeds, "steady sliding of every axis needs a "
                             "non-zero speed [m/s] (or frictionless)")
    axes = []
    points: dict[str, float] = {}
    live_names: list[str] = []
    for ax in machine.axes:
        system = _system(ax, frictionless)
        axes.append(replace(ax, parameters=system.parameters))
        model, y = steady_state(system, speeds[ax.name])
        points.update({f"{ax.name}.{n}": float(v) for n, v in zip(model.state_names, y,
                                                                    strict=True)})
        live_names += [f"{ax.name}.{model.state_names[k]}" for k in _live_states(model, system)]
    flat = replace(machine, axes=tuple(axes))
    profile = MachineProfile(time=np.array([0.0, 1.0]), table_speed=np.zeros(2), axes=tuple(
        (ax.name, ConstantSpeed(speeds[ax.name], ramp_time=0.0))  # type: ignore[misc]
        for ax in machine.axes))
    model = assemble_machine(flat, profile)
    names = model.state_names
    # the coupling parts' own states (a beam, a controller's integral) start at 0
    live_names += [f"{c.name}.{state}" for c in machine.couplings for state in c.states()]
    y = np.array([points.get(n, 0.0) for n in names])
    live = [names.index(n) for n in live_names]
    f = _Evaluator(model)
    scale = _scales(model)
    aux = [a.name for a in model.aux]
    outs: list[tuple[str, Callable[..., float]]] = []
    for ax in machine.axes:
        k_x = names.index(f"{ax.name}.table_position")
        k_ref = aux.index(f"{ax.name}.table_position_reference")
        outs.append((f"{ax.name}.table_position", lambda yv, av, k=k_x: yv[k]))
        outs.append((f"{ax.name}.following_error",
                     lambda yv, av, k=k_x, r=k_ref: av[r] - yv[k]))

    def outputs(yv: np.ndarray, av: np.ndarray) -> np.ndarray:
        return np.array([fn(yv, av) for _, fn in outs])

    n = len(live)
    A = np.empty((n, n))
    C = np.empty((len(outs), n))
    for j, h, (yp, dp, ap), (ym, dm, am) in _state_steps(f, y, live, scale):
        A[:, j] = (dp[live] - dm[live]) / (2 * h)
        C[:, j] = (outputs(yp, ap) - outputs(ym, am)) / (2 * h)
    ins = [(f"{ax.name}.{name}", model.parameter_names.index(f"{ax.name}.inputs.{name}"), unit)
           for ax in machine.axes
           for name, unit in (("table_position_reference", "m"), ("load_force", "N"))]
    B, D = _input_columns(f, model, y, live, outputs,
                          [(slot, _INPUT_STEP[unit]) for _, slot, unit in ins])
    notes = (("the coupling parts are evaluated at the axes' own steady states, not solved "
              "for with them, their own states at 0",) if machine.couplings else ())
    return MachineLinearModel(A=A, B=B, C=C, D=D, states=tuple(names[k] for k in live),
                       inputs=tuple(name for name, _, _ in ins),
                       outputs=tuple(name for name, _ in outs),
                       operating_point={names[k]: float(y[k]) for k in live},
                       table_speed=max(speeds.values(), key=abs), nut_speed=0.0,
                       frictionless=frictionless, notes=notes)


def cross_coupling(lin: MachineLinearModel, frequencies: np.ndarray | None = None
                   ) -> dict[str, float]:
    """The largest gain from one axis' position reference to another axis' position over
    frequency: how much a command of one axis moves another (0 for independent axes).

    Parameters
    ----------
    lin : MachineLinearModel
        The machine's linear model.
    frequencies : numpy.ndarray, optional
        Frequencies [Hz] (default 0.1 … 1000 Hz, 200 points).

    Returns
    -------
    dict of str to float
        ``"<from> -> <to>"`` → the peak |x_to / x_ref,from| [-].
    """
    f = np.logspace(-1, 3, 200) if frequencies is None else np.asarray(frequencies)
    s = 2j * np.pi * f
    axes = [name.removesuffix(".table_position_reference") for name in lin.inputs
            if name.endswith(".table_position_reference")]
    out = {}
    I = np.eye(lin.A.shape[0])
    for a in axes:
        j = lin.inputs.index(f"{a}.table_position_reference")
        for b in axes:
            if a == b:
                continue
            i = lin.outputs.index(f"{b}.table_position")
            g = [abs(lin.C[i] @ np.linalg.solve(z * I - lin.A, lin.B[:, j]) + lin.D[i, j])
                 for z in s]
            out[f"{a} -> {b}"] = float(max(g))
    return out


def spectral_abscissa(lin: LinearModel) -> complex:
    """The least-damped closed-loop pole: the eigenvalue of ``A`` with the largest real part.

    An eigenvalue at 0 to rounding (an integrator nothing reads: a cross-coupled
    controller's integral at ``integral_gain = 0``) is left out; it neither grows nor decays.

    Parameters
    ----------
    lin : LinearModel
        A linearised closed loop.

    Returns
    -------
    complex
        The pole [1/s] (its real part < 0: stable).
    """
    ev = np.linalg.eigvals(lin.A)
    ev = ev[np.abs(ev) > 1e-9 * max(1.0, float(np.max(np.abs(ev))))]
    return complex(ev[np.argmax(ev.real)])


def gain_limit(machine: Machine, part: str, field: str = "gain",
               table_speeds: Mapping[str, float] | None = None, *,
               frictionless: bool = True, rtol: float = 1e-3) -> float:
    """The largest value of a coupling part's gain for which the machine's linearised closed
    loop is stable: bisection on the real part of its least-damped pole
    (:func:`spectral_abscissa` of :func:`linearize_machine`).

    A gain is designed from it by a stated margin: ``gain_limit(...) / 2`` is the classical
    6-dB gain margin on that loop (docs/machine.md, the gantry's cross-coupled controller).

    Parameters
    ----------
    machine : Machine
        The machine (continuous loops).
    part : str
        The coupling part's name (``[couplings.<part>]``).
    field : str, default "gain"
        The parameter varied.
    table_speeds : mapping of str to float, optional
        Steady table speed per axis [m/s] (:func:`linearize_machine`).
    frictionless : bool, default True
        Linearise without friction (the conservative loop: friction at sliding adds damping
        that vanishes as the speed falls); False: with the friction laws at steady sliding
        (needs a non-zero speed for every axis).
    rtol : float, default 1e-3
        Relative width of the final bracket [-].

    Returns
    -------
    float
        The limit [the field's unit]; ``inf`` when no value up to 1e6 destabilises the loop.

    Raises
    ------
    ParameterError
        For an unknown part or field, or a loop that is unstable at 0.
    """
    from ..parameters import ParameterError

    parts = {c.name: c for c in machine.couplings}
    if part not in parts:
        raise ParameterError("part", part, f"expected one of the machine's coupling parts: "
                             f"{', '.join(parts) or '(none)'}")
    if field not in parts[part].units:
        raise ParameterError("field", field, f"expected a parameter of couplings.{part}: "
                             f"{', '.join(parts[part].units)}")

    def growth(value: float) -> float:
        changes: dict[str, Any] = {field: value}
        c = replace(parts[part], **changes)
        m = replace(machine, couplings=tuple(c if x.name == part else x
                                             for x in machine.couplings))
        return spectral_abscissa(linearize_machine(m, table_speeds,
                                                   frictionless=frictionless)).real

    if growth(0.0) >= 0.0:
        raise ParameterError(f"couplings.{part}.{field}", 0.0,
                             "the machine is unstable with this gain at 0: no limit to find")
    lo, hi = 0.0, 1.0
    while growth(hi) < 0.0:
        lo, hi = hi, 2.0 * hi
        if hi > 1e6:
            return float("inf")
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if growth(mid) < 0.0 else (lo, mid)
    return 0.5 * (lo + hi)
