"""A machine of axes as one FMU, co-simulation or model exchange.

The machine's model (:func:`feeddrive.machine.assemble_machine`) is assembled with each axis'
reference read from inputs (:class:`~feeddrive.fmu.model.InputReference`, one reference block
of ``T`` per axis) and each axis' load force written into its ``inputs.load_force`` slot.
Every axis contributes the variables its single-drive FMU has (:func:`feeddrive.fmu.
description.variables` of the axis alone, same parameter set), renamed ``<axis>.<name>`` and
pointed at the machine's arrays: inputs, outputs, tunable parameters with their set-time range
checks, and its loop-period settings.  The coupling parts' own states and the signals they
write become outputs; their parameters are fixed at export (set in the machine file).  A
model-exchange FMU adds the rate of every continuous state; its directional derivatives are
the tangent of the machine's right-hand side (:func:`feeddrive.fmu.build.tangent_c`),
through each axis' scope function and the coupling parts' code between them.
"""

from __future__ import annotations

import numpy as np

from ..model.reference import INPUT_INSTANT, TABLE_OFFSET
from .description import (
    INPUTS,
    K_AUX,
    K_ERROR,
    K_INPUT,
    K_PARAM,
    K_PRODUCT,
    K_STATE,
    K_TIME,
    Variable,
    check_unique,
    display_unit,
    rate_variables,
    setting_variables,
    variables,
)
from .model import FmuModel, InputBlock, InputReference, build

_PERIODS = ("controller.position_period", "controller.velocity_period",
            "controller.current_period")


def build_machine(machine: object) -> tuple[FmuModel, dict[str, FmuModel]]:
    """Assemble ``machine`` with every axis' reference and load force read from inputs.

    Parameters
    ----------
    machine : feeddrive.machine.Machine
        The machine.

    Returns
    -------
    fm : FmuModel
        The machine's model and one input block per axis.
    axes : dict of str to FmuModel
        Each axis alone as a single-drive FMU model (the source of its variables' names,
        units, descriptions and ranges).
    """
    from ..machine import Machine, MachineProfile, assemble_machine

    assert isinstance(machine, Machine)
    axes = {ax.name: build(ax.parameters, ax.drive, ax.table_position, ax.nut_hold)
            for ax in machine.axes}
    # assemble reads only a reference's encode(): InputReference is one (as fmu.model.build)
    profile = MachineProfile(time=np.array([0.0, 1.0]), table_speed=np.zeros(2),
                             axes=tuple((ax.name, InputReference())  # type: ignore[misc]
                                        for ax in machine.axes))
    model = assemble_machine(machine, profile)
    names = model.parameter_names
    blocks = []
    periods: dict[str, float] = {}
    for ax in machine.axes:
        pre = f"{ax.name}."
        o = names.index(f"{pre}profile[0]")
        blocks.append(InputBlock(pre, int(model.P[o + TABLE_OFFSET]), o + INPUT_INSTANT,
                                 names.index(f"{pre}inputs.load_force"), _PERIODS))
        for slot in _PERIODS:
            periods[f"{pre}{slot}"] = float(model.P[names.index(f"{pre}{slot}")])
    first = blocks[0]
    fm = FmuModel(model=model, drive=machine.name,
                  profile_offset=names.index(f"{first.prefix}profile[0]"),
                  table_offset=first.table_offset, load_slot=first.load_slot,
                  nut_inputs=False, nut_position_input=False, periods=periods,
                  parameters=machine.axes[0].parameters,
                  table_position=machine.axes[0].table_position,
                  nut_hold=machine.axes[0].nut_hold, blocks=tuple(blocks))
    return fm, axes


def machine_variables(fm: FmuModel, axes: dict[str, FmuModel], kind: str = "cs"
                      ) -> list[Variable]:
    """Every variable of a machine's FMU (value reference = position).

    Parameters
    ----------
    fm : FmuModel
        The machine's model (:func:`build_machine`).
    axes : dict of str to FmuModel
        Each axis alone (:func:`build_machine`).
    kind : str, default "cs"
        ``"cs"`` (co-simulation) or ``"me"`` (model exchange: the rate ``der(<state>)`` of
        every continuous state, with its dependencies from the machine model's declared
        sparsity, and the evaluation counters instead of the solver's).

    Returns
    -------
    list of Variable
        The variables: time, each axis' own (``<axis>.<name>``), the coupling parts' states,
        the states' rates (model exchange), the coupling parts' signals, the settings.
    """
    from dataclasses import replace

    m = fm.model
    n = len(m.states)
    params = {name: k for k, name in enumerate(m.parameter_names)}
    aux = {a.name: j for j, a in enumerate(m.aux)}
    v: list[Variable] = [Variable("time", K_TIME, 0, 0, "independent", "continuous", None,
                                  None, "s", "simulation time")]
    covered_states: set[int] = set()
    covered_aux: set[int] = set()
    for k, block in enumerate(fm.input_blocks):
        pre = block.prefix
        am = axes[pre[:-1]].model
        na = len(am.states)
        for x in variables(axes[pre[:-1]], "cs"):
            name = pre + x.name
            if x.kind == K_INPUT:
                text = ("load force on the table, against positive motion [from t = 0]"
                        if x.name == "load_force" else x.description)
                v.append(replace(x, name=name, a=k * len(INPUTS) + x.a, description=text))
            elif x.kind == K_STATE:
                a = (m.index(pre + am.states[x.a].name) if x.a < na
                     else n + 2 * k + (x.a - na))
                covered_states.add(a)
                v.append(replace(x, name=name, a=a))
            elif x.kind == K_AUX:
                if pre + am.aux[x.a].name not in aux:  # the load record's signal: an input
                    continue
                a = aux[pre + am.aux[x.a].name]
                covered_aux.add(a)
                v.append(replace(x, name=name, a=a))
            elif x.kind in (K_PRODUCT, K_ERROR):
                a = (params[pre + am.parameter_names[x.a]] if x.kind == K_PRODUCT
                     else aux[pre + am.aux[x.a].name])
                v.append(replace(x, name=name, a=a, b=m.index(pre + am.states[x.b].name),
                                 display_unit=display_unit(x.name, x.unit)))
            elif x.kind == K_PARAM:
                slot = pre + am.parameter_names[x.a]
                if slot in params:  # a load record's slots: the axis' load is an input here
                    v.append(replace(x, name=name, a=params[slot],
                                     start=float(m.P[params[slot]]),
                                     description=f"{pre[:-1]} axis: {x.description}"))
    for i, s in enumerate(m.states):  # the coupling parts' own states
        if i not in covered_states:
            v.append(Variable(s.name, K_STATE, i, 0, "output", "continuous", "calculated",
                              None, s.unit, s.description,
                              display_unit=display_unit(s.name, s.unit)))
    if kind == "me":
        v += rate_variables(fm, v)
    for j, sig in enumerate(m.aux):  # the signals the coupling parts write
        if j not in covered_aux:
            v.append(Variable(sig.name, K_AUX, j, 0, "output", "continuous", "calculated", None,
                              sig.unit, sig.description,
                              display_unit=display_unit(sig.name, sig.unit)))
    v += setting_variables(fm, kind)
    return check_unique(v)
