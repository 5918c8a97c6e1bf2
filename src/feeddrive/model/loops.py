"""Cascade servo loops, one axis per motor: position (P) → velocity (P/PI) → current (P/PI).

Wang2021 Sect. 2.1 (Fig. 2); the structure is an explicit reading, see docs/model.md:

* position loop on the axis' measured position (the table's grating for the screw motor and
  a linear motor, the hollow motor's encoder for the nut), with velocity feed-forward;
  the hollow motor may run a speed loop only (``controller.nut_loop = "speed"``);
* K_v (Table 2's "velocity-adjusting gain") where ``kv_placement`` says; velocity gains on
  rad/s of the motor or (``velocity_gain_basis = "table"``) on m/s of table motion;
* each loop continuous (period 0) or sampled with zero-order hold at its own period, with
  encoder/grating quantisation on sampled loops; conditional-integration anti-windup.

Each axis has its own parameter block (:data:`AXIS_PARAMS`), so per-axis gains are a matter of
filling the block differently.  The kernels below are the loop laws; :func:`emit_cascade`
writes the per-axis code into the assembled model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import registry
from .._jit import kernel
from ..parameters import Component, ParameterError
from ..parameters.validation import choice, flag, quantity
from .codegen import SIGNAL, Builder

# parameter block of one axis (offsets from the axis' first slot)
# ``inj_speed`` [rad/s] and ``inj_current`` [A] are zero inputs added to the continuous speed
# and current commands: loop-breaking points for the linearisation (feeddrive.analysis.linear).
AXIS_PARAMS = ("kpp", "kvp", "kvi", "kip", "kii", "kv", "kv_place", "v_basis", "v_feedback",
               "ff", "i_max", "u_max", "enc_q", "grat_q", "speed_mode", "H", "inj_speed",
               "inj_current")
KPP, KVP, KVI, KIP, KII, KV, KV_PLACE, V_BASIS, V_FEEDBACK, FF, I_MAX, U_MAX, ENC_Q, GRAT_Q, \
    SPEED_MODE, H_AX, INJ_SPEED, INJ_CURRENT = range(len(AXIS_PARAMS))


@kernel
def quantise(value: float, step: float) -> float:
    """Floor quantisation to a count size: what an incremental encoder or grating reports.

    Parameters
    ----------
    value : float
        The true position [rad or m].
    step : float
        The count size [rad or m]; 0 or less for an ideal sensor.

    Returns
    -------
    float
        ``step·floor(value/step)``, or ``value`` unchanged [rad or m].
    """
    if step <= 0.0:
        return value
    return step * math.floor(value / step)


@kernel
def position_law(error: float, speed_ff: float, P: np.ndarray, o: int) -> float:
    """Position-loop law: speed command from the position error and the speed feed-forward.

    ω_cmd = (K_pp·e [·K_v] + ff·v_ff) / H, K_v applied here when ``kv_placement =
    "position_output"`` (Wang2021 Sect. 2.1, Fig. 2; Table 2's K_pp).

    Parameters
    ----------
    error : float
        Position error, reference − measured [m].
    speed_ff : float
        Speed feed-forward [m/s].
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the axis' parameter block (:data:`AXIS_PARAMS`) in ``P``.

    Returns
    -------
    float
        Speed command of the axis' motor [rad/s] (m/s for a linear motor, H = 1).

    References
    ----------
    .. [1] Wang2021 Sect. 2.1, Fig. 2 (cascade), Table 2 (gains).
    """
    k = P[o + KPP]
    if int(P[o + KV_PLACE]) == 1:
        k *= P[o + KV]
    return (k * error + P[o + FF] * speed_ff) / P[o + H_AX]


@kernel
def speed_command(error: float, speed_ref: float, P: np.ndarray, o: int) -> float:
    """The axis' speed command: the position loop, or in speed mode the commanded speed itself.

    Speed mode is the hollow motor's ``controller.nut_loop = "speed"``: no position feedback.

    Parameters
    ----------
    error : float
        Position error, reference − measured [m].
    speed_ref : float
        Commanded speed, also the feed-forward [m/s].
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the axis' parameter block (:data:`AXIS_PARAMS`) in ``P``.

    Returns
    -------
    float
        Speed command of the axis' motor [rad/s].
    """
    if P[o + SPEED_MODE] > 0.5:
        return speed_ref / P[o + H_AX]
    return position_law(error, speed_ref, P, o)


@kernel
def velocity_error(speed_cmd: float, speed_meas: float, P: np.ndarray, o: int) -> float:
    """Velocity-loop error in the units its gains act on.

    e = ω_cmd − ω_meas, times H when the gains act on table motion (``velocity_gain_basis =
    "table"``), divided by K_v when ``kv_placement = "velocity_error"``.

    Parameters
    ----------
    speed_cmd : float
        Speed command [rad/s].
    speed_meas : float
        Measured speed [rad/s].
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the axis' parameter block (:data:`AXIS_PARAMS`) in ``P``.

    Returns
    -------
    float
        The error the velocity gains multiply [rad/s, or m/s on the table basis].
    """
    e = speed_cmd - speed_meas
    if int(P[o + V_BASIS]) == 1:
        e *= P[o + H_AX]
    if int(P[o + KV_PLACE]) == 2:
        e /= P[o + KV]
    return e


@kernel
def saturate(value: float, limit: float) -> float:
    """Clip a command to ±limit.

    Parameters
    ----------
    value : float
        The unsaturated command [A or V].
    limit : float
        The limit, positive [A or V].

    Returns
    -------
    float
        ``value`` clipped to [−limit, limit] [A or V].
    """
    if value > limit:
        return limit
    if value < -limit:
        return -limit
    return value


@kernel
def integrator_rate(error: float, unsaturated: float, limit: float) -> float:
    """Conditional integration (anti-windup): the integrator's input, zero while it winds up.

    Parameters
    ----------
    error : float
        The loop error being integrated [rad/s or A].
    unsaturated : float
        The loop's output before saturation [A or V].
    limit : float
        The output limit [A or V].

    Returns
    -------
    float
        ``error``, or 0 when the output is saturated and the error drives it further out.
    """
    if (unsaturated > limit and error > 0.0) or (unsaturated < -limit and error < 0.0):
        return 0.0
    return error


@kernel
def current_command(error: float, integral: float, P: np.ndarray, o: int) -> float:
    """Velocity-loop PI law: current command K_vp·e + K_vi·∫e.

    Parameters
    ----------
    error : float
        Velocity error from :func:`velocity_error` [rad/s].
    integral : float
        The velocity-loop integral state [rad].
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the axis' parameter block (:data:`AXIS_PARAMS`) in ``P``.

    Returns
    -------
    float
        Current command before saturation [A].
    """
    return P[o + KVP] * error + P[o + KVI] * integral


@kernel
def voltage_command(error: float, integral: float, P: np.ndarray, o: int) -> float:
    """Current-loop PI law: armature voltage K_ip·e + K_ii·∫e.

    Parameters
    ----------
    error : float
        Current error, command − measured [A].
    integral : float
        The current-loop integral state [A s].
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the axis' parameter block (:data:`AXIS_PARAMS`) in ``P``.

    Returns
    -------
    float
        Voltage command before saturation [V].
    """
    return P[o + KIP] * error + P[o + KII] * integral


@dataclass(frozen=True)
class Channel:
    """A measured position the sampled loops read, with its quantisation.

    Parameters
    ----------
    name : str
        The channel's name; sampled code reads it as ``q_<name>`` and its speed as
        ``s_<name>``.
    state : str
        Code of the true position, e.g. ``"y[4]"`` [rad or m].
    speed : str
        Code of its true rate [rad/s or m/s].
    quantum : str
        Code of the count size (0 = ideal) [rad or m].
    """

    name: str
    state: str  # code expression of the true value, e.g. "y[4]"
    speed: str  # code expression of its true rate
    quantum: str  # code expression of the count size (0 = ideal)


@dataclass(frozen=True)
class Axis:
    """One motor's cascade as the mechanism wires it: its references, feedback and current.

    The continuous fields are code with their signals in braces (``"{table_position}"``,
    ``"({ref_v} + {ref_vn})"``, :meth:`Builder.emit <feeddrive.model.codegen.Builder.emit>`):
    what the loops read follows from that text.

    Parameters
    ----------
    name : str
        The axis' name (``"screw"``, ``"nut"``, ``"motor"``).
    param_offset : int
        Offset of its parameter block in ``P`` (from :func:`axis_parameters`).
    reference : str
        Code of the commanded position [m].
    feedforward : str
        Code of the speed feed-forward [m/s].
    position : str
        Code of the measured position, continuous [m].
    position_q : str
        The same from quantised channels (``q_<channel>``), for sampled loops [m].
    speed : str
        Code of the measured motor speed, continuous [rad/s].
    speed_q : str
        The same from sampled channel speeds (``s_<channel>``) [rad/s].
    current_state : str
        Code of the motor current state, the state named in braces (``"{screw_current}"``)
        [A].
    active : str, default ""
        Code of the condition under which the axis runs; empty for always.
    speed_unit : str, default "rad/s"
        Unit of its speed command.
    speed_law : str, default "position"
        ``"speed"``: the axis may run a speed loop only (its block's speed-mode slot).
    extra_current : str, default ""
        Code of a current added to the command, continuous loops only (compensation) [A].
    current_feedforward : str, default ""
        Code of a current added to the command in every loop configuration (a feed-forward
        part), saturated with it [A].
    speed_correction : str, default ""
        Code of a speed added to the continuous speed command (a machine's synchronisation
        part) [rad/s].
    velocity_prelude : tuple of str, default ()
        Sampled code run at each velocity-loop instant just before its PI update; it may read
        ``ref_x`` and the quantised positions and change the held integral (a reset part).
    """

    name: str
    param_offset: int
    reference: str
    feedforward: str
    position: str
    position_q: str
    speed: str
    speed_q: str
    current_state: str
    active: str = ""
    speed_unit: str = "rad/s"
    speed_law: str = "position"  # "speed": may run as a speed loop (controller.nut_loop)
    extra_current: str = ""  # code of a current [A] added to the command (compensation)
    # code of a current [A] added to the current command in every loop configuration,
    # sampled or continuous (a feed-forward part); saturated with the command
    current_feedforward: str = ""
    # code of a speed [rad/s] added to the continuous speed command (a machine's
    # synchronisation part writes it)
    speed_correction: str = ""
    # sampled code run at the velocity loop's instants just before its PI update, where the
    # quantised positions (``q_<channel>``) and ``ref_x`` are known (a reset-integrator part)
    velocity_prelude: tuple[str, ...] = ()


def axis_parameters(b: Builder, axis: str, c: object, H: float, *, speed_mode: bool) -> int:
    """Register an axis' parameter block (:data:`AXIS_PARAMS`) from its controller settings.

    Parameters
    ----------
    b : Builder
        The model builder.
    axis : str
        The axis' name; the slots are ``controller.<axis>.<name>``.
    c : Controller
        The axis' controller parameters (gains [SI], limits, placement options).
    H : float
        The axis' transmission ratio, table travel per motor radian [m/rad].
    speed_mode : bool
        Whether the axis runs a speed loop only.

    Returns
    -------
    int
        Offset of the block's first slot in ``P``.
    """
    assert isinstance(c, Controller)
    values = {
        "kpp": c.position_gain, "kvp": c.velocity_gain, "kvi": c.velocity_integral_gain,
        "kip": c.current_gain, "kii": c.current_integral_gain, "kv": c.velocity_command_gain,
        "kv_place": ("none", "position_output", "velocity_error").index(c.kv_placement),
        "v_basis": ("motor", "table").index(c.velocity_gain_basis),
        "v_feedback": ("motor", "table").index(c.velocity_feedback),
        "ff": 1.0 if c.velocity_feedforward else 0.0,
        "i_max": c.current_limit, "u_max": c.voltage_limit,
        "enc_q": 2.0 * math.pi / c.encoder_counts if c.encoder_counts > 0 else 0.0,
        "grat_q": c.grating_resolution,
        "speed_mode": 1.0 if speed_mode else 0.0, "H": H, "inj_speed": 0.0,
        "inj_current": 0.0,
    }
    first = -1
    for name in AXIS_PARAMS:
        k = b.param(f"controller.{axis}.{name}", float(values[name]))
        first = k if first < 0 else first
    return first


CLOCKS = ("position_period", "velocity_period", "current_period")


def declare_clocks(b: Builder, c: object) -> None:
    """The three loops' sample periods [s] as parameter slots ``controller.<loop>_period`` and
    as clocks of the model's sample schedule (:meth:`Builder.clock`; 0 = continuous).

    Parameters
    ----------
    b : Builder
        The model builder.
    c : Controller
        The controller parameters (its three periods [s]).
    """
    for name in CLOCKS:
        b.param(f"controller.{name}", float(getattr(c, name)))
        b.clock(f"controller.{name}")


def _period(b: Builder, loop: str) -> str:
    """Code of a loop's sample period [s] (``loop``: position, velocity or current)."""
    return b.p(f"controller.{loop}_period")


def declare_states(b: Builder, axes: list[Axis]) -> None:
    """Declare the loops' integrator states, grouped by loop (all velocity integrals, then all
    current integrals).

    Parameters
    ----------
    b : Builder
        The model builder.
    axes : list of Axis
        The mechanism's axes.
    """
    for ax in axes:
        b.state(f"{ax.name}_velocity_integral", "rad", f"{ax.name} velocity-loop integral",
                "velocity_integral")
    for ax in axes:
        b.state(f"{ax.name}_current_integral", "A s", f"{ax.name} current-loop integral",
                "current_integral")


@dataclass(frozen=True)
class ControlAxis:
    """What a controller axis declares to its consumers (the linearisation, the FMU): the
    names of its signals and where its parameter block starts — read from the model, never
    rebuilt from a naming rule.

    Parameters
    ----------
    name : str
        The axis' name (``"screw"``, ``"motor"``).
    speed_command : str
        Its speed-command signal (auxiliary output) [rad/s or m/s].
    current_command : str
        Its current-command signal [A].
    current : str
        The motor-current state it drives [A].
    block : int
        Offset of its parameter block (:data:`AXIS_PARAMS`) in ``P``; ``block + INJ_SPEED``
        and ``block + INJ_CURRENT`` are the linearisation's injection slots.
    """

    name: str
    speed_command: str
    current_command: str
    current: str
    block: int


def control_axes(b: Builder, axes: list[Axis]) -> tuple[ControlAxis, ...]:
    """The declarations of every axis (after :func:`declare_signals`), model-wide names.

    Parameters
    ----------
    b : Builder
        The model builder.
    axes : list of Axis
        The mechanism's axes.

    Returns
    -------
    tuple of ControlAxis
        One per axis, in order.
    """
    out = []
    for ax in axes:
        current = [n for n in SIGNAL.findall(ax.current_state) if b.q(n) in b.state_index]
        if len(current) != 1:
            raise ValueError(f"axis {ax.name!r}: its current_state {ax.current_state!r} "
                             "names no one state in braces")
        out.append(ControlAxis(ax.name, b.q(f"{ax.name}_speed_command"),
                               b.q(f"{ax.name}_current_command"), b.q(current[0]),
                               ax.param_offset))
    return tuple(out)


def declare_signals(b: Builder, axes: list[Axis]) -> None:
    """Declare the cascade's outputs (speed and current commands, voltages) and the values a
    sampled loop holds between its updates.

    Parameters
    ----------
    b : Builder
        The model builder.
    axes : list of Axis
        The mechanism's axes.
    """
    for ax in axes:
        b.add_aux(f"{ax.name}_speed_command", ax.speed_unit, f"{ax.name} speed command")
    for ax in axes:
        b.add_aux(f"{ax.name}_current_command", "A", f"{ax.name} current command")
    for ax in axes:
        b.add_aux(f"{ax.name}_voltage", "V", f"{ax.name} motor armature voltage")
    for ax in axes:
        for held in ("speed_command", "current_command", "voltage", "velocity_integral",
                     "current_integral"):
            b.add_held(f"{ax.name}.{held}")


def _guarded(ax: Axis, body: list[str], indent: str = "    ") -> list[str]:
    """``body`` at ``indent``, under ``if <ax.active>:`` when the axis is not always on."""
    if not ax.active:
        return [indent + ln for ln in body]
    return [f"{indent}if {ax.active}:", *(f"{indent}    {ln}" for ln in body)]


def _sampled_pi(error: str, law: str, integral: str, output: str, o: int, limit: int,
                rate: str, sat: str, period: str, raw: str) -> list[str]:
    """A sampled PI update with conditional anti-windup: error, unsaturated output, integral
    advanced by ``period``, saturated output held."""
    return [f"e = {error}",
            f"{raw} = {law}(e, {integral}, P, {o})",
            f"{integral} += {period} * {rate}(e, {raw}, P[{o + limit}])",
            f"{output} = {sat}({raw}, P[{o + limit}])"]


def _speed_law(b: Builder, ax: Axis) -> str:
    """The kernel that turns the axis' position error into its speed command."""
    return b.use(position_law) if ax.speed_law == "position" else b.use(speed_command)


def _emit_commands(b: Builder, axes: list[Axis], out: list[str], target: str) -> None:
    """Speed and current commands of every axis into ``target``: ``"aux"``, the signals
    (right-hand side), or a local array of the sampled update."""
    P = "P"
    if target == "aux":
        sc = [f"{{{ax.name}_speed_command}}" for ax in axes]
        ic = [f"{{{ax.name}_current_command}}" for ax in axes]
    else:
        sc = [f"{target}[{b.aux_index[b.q(f'{ax.name}_speed_command')]}]" for ax in axes]
        ic = [f"{target}[{b.aux_index[b.q(f'{ax.name}_current_command')]}]" for ax in axes]
    verr, sat, ccmd = b.use(velocity_error), b.use(saturate), b.use(current_command)
    out.append(f"if {_period(b, 'position')} > 0.0:")
    for ax, s in zip(axes, sc, strict=True):
        out.append(f"    {s} = {b.h(ax.name + '.speed_command')}")
    out.append("else:")
    for ax, s in zip(axes, sc, strict=True):
        extra = f" + {ax.speed_correction}" if ax.speed_correction and target == "aux" else ""
        out.append(f"    {s} = {_speed_law(b, ax)}({ax.reference} - {ax.position}, "
                   f"{ax.feedforward}, {P}, {ax.param_offset}) + "
                   f"{P}[{ax.param_offset + INJ_SPEED}]{extra}")
    out.append(f"if {_period(b, 'velocity')} > 0.0:")
    for ax, c in zip(axes, ic, strict=True):
        held = b.h(ax.name + '.current_command')
        out.append(f"    {c} = {sat}({held} + {ax.current_feedforward}, "
                   f"{P}[{ax.param_offset + I_MAX}])" if ax.current_feedforward
                   else f"    {c} = {held}")
    out.append("else:")
    for ax, s in zip(axes, sc, strict=True):
        out.append(f"    e_{ax.name} = {verr}({s}, {ax.speed}, {P}, {ax.param_offset})")
    for ax, c in zip(axes, ic, strict=True):
        o = ax.param_offset
        # compensation is continuous-only (refused with sampled loops): right-hand side only
        extra = f" + {ax.extra_current}" if ax.extra_current and target == "aux" else ""
        if ax.current_feedforward:
            extra += f" + {ax.current_feedforward}"
        out.append(f"    {c} = {sat}({ccmd}(e_{ax.name}, {{{ax.name}_velocity_integral}}, "
                   f"{P}, {o}) + {P}[{o + INJ_CURRENT}]{extra}, {P}[{o + I_MAX}])")


def emit_cascade(b: Builder, axes: list[Axis], channels: list[Channel]) -> None:
    """Write every axis' cascade: the continuous part into the right-hand side, the sampled part
    into the controller update.

    Parameters
    ----------
    b : Builder
        The model builder.
    axes : list of Axis
        The mechanism's axes.
    channels : list of Channel
        The measured positions the sampled loops quantise.
    """
    rate, sat, vcmd = b.use(integrator_rate), b.use(saturate), b.use(voltage_command)
    verr, ccmd, quant = b.use(velocity_error), b.use(current_command), b.use(quantise)

    # ---- right-hand side: commands, continuous integrators, current loops
    lines: list[str] = []
    _emit_commands(b, axes, lines, "aux")
    lines.append(f"if {_period(b, 'velocity')} == 0.0 and P[{axes[0].param_offset + KVI}] != 0.0:")
    for ax in axes:
        o = ax.param_offset
        vi = f"{ax.name}_velocity_integral"
        lines += _guarded(ax, [
            f"e_{ax.name} = {verr}({{{ax.name}_speed_command}}, {ax.speed}, P, {o})",
            f"raw = P[{o + KVP}] * e_{ax.name} + P[{o + KVI}] * {{{vi}}}",
            f"{{der({vi})}} = {rate}(e_{ax.name}, raw, P[{o + I_MAX}])"])
        if ax.active:
            lines.append("    else:")
            lines.append(f"        {{der({vi})}} = 0.0")
    lines.append("else:")
    for ax in axes:
        lines.append(f"    {{der({ax.name}_velocity_integral)}} = 0.0")
    for ax in axes:
        o = ax.param_offset
        ic = ax.name + "_current_integral"
        lines += [
            f"if {_period(b, 'current')} > 0.0:",
            f"    u = {b.h(ax.name + '.voltage')}",
            f"    {{der({ic})}} = 0.0",
            "else:",
            f"    e = {{{ax.name}_current_command}} - {ax.current_state}",
            f"    raw = {vcmd}(e, {{{ic}}}, P, {o})",
            f"    u = {sat}(raw, P[{o + U_MAX}])",
            f"    {{der({ic})}} = {rate}(e, raw, P[{o + U_MAX}]) if P[{o + KII}] != 0.0 "
            "else 0.0",
            f"{{{ax.name}_voltage}} = u",
        ]
        if ax.active:  # a held axis (the CDFS nut) freezes its current integral too
            lines += [f"if not ({ax.active}):", f"    {{der({ic})}} = 0.0"]
    for ln in lines:
        b.emit(ln)

    # ---- sampled update
    s: list[str] = list(b.references)
    s.append(f"if {b.tick('controller.position_period')} >= 0:")
    for ax in axes:
        body = [f"q_{ch.name} = {quant}({ch.state}, {ch.quantum})" for ch in channels
                if f"q_{ch.name}" in ax.position_q]
        body.append(f"{b.h(ax.name + '.speed_command')} = {_speed_law(b, ax)}({ax.reference} - "
                    f"{ax.position_q}, {ax.feedforward}, P, {ax.param_offset})")
        s += _guarded(ax, body)
    s.append(f"if {b.tick('controller.velocity_period')} >= 0:")
    s.append(f"    tv = {_period(b, 'velocity')}")
    for ax in axes:
        s.append(f"    w_cmd_{ax.name} = {b.h(ax.name + '.speed_command')} if "
                 f"{_period(b, 'position')} > 0.0 else "
                 f"{_speed_law(b, ax)}({ax.reference} - {ax.position}, {ax.feedforward}, P, "
                 f"{ax.param_offset})")
    for ch in channels:
        s.append(f"    q_{ch.name} = {quant}({ch.state}, {ch.quantum})")
    quanta = " or ".join(f"{ch.quantum} > 0.0" for ch in dict(
        (c.quantum, c) for c in channels).values())
    s.append(f"    if {quanta}:")
    s.append(f"        if {b.tick('controller.velocity_period')} == 0:")
    for ch in channels:
        s.append(f"            s_{ch.name} = 0.0")
    s.append("        else:")
    for ch in channels:
        s.append(f"            s_{ch.name} = (q_{ch.name} - {b.h('prev.' + ch.name)}) / tv")
    s.append("    else:")
    for ch in channels:
        s.append(f"        s_{ch.name} = {ch.speed}")
    for ch in channels:
        s.append(f"    {b.h('prev.' + ch.name)} = q_{ch.name}")
    for ax in axes:
        if ax.velocity_prelude:
            s += _guarded(ax, list(ax.velocity_prelude))
        s += _guarded(ax, _sampled_pi(
            f"{verr}(w_cmd_{ax.name}, {ax.speed_q}, P, {ax.param_offset})", ccmd,
            b.h(ax.name + ".velocity_integral"), b.h(ax.name + ".current_command"),
            ax.param_offset, I_MAX, rate, sat, "tv", "i_raw"))
    s.append(f"if {b.tick('controller.current_period')} >= 0:")
    s.append(f"    tc = {_period(b, 'current')}")
    s.append("    cmd = np.empty(N_AUX)")
    cmd_lines: list[str] = []
    _emit_commands(b, axes, cmd_lines, "cmd")
    s += ["    " + ln for ln in cmd_lines]
    for ax in axes:
        s += _guarded(ax, _sampled_pi(
            f"cmd[{b.aux_index[b.q(ax.name + '_current_command')]}] - {ax.current_state}", vcmd,
            b.h(ax.name + ".current_integral"), b.h(ax.name + ".voltage"), ax.param_offset,
            U_MAX, rate, sat, "tc", "u_raw"))
    for ln in s:
        b.emit(ln, sampled=True)


# ---- the loops' parameters: sections [controller] and [hollow_controller]

#: shortest sampling period of a discrete loop [s]: 1 µs (a faster loop is continuous: 0)
MIN_PERIOD = 1e-6
#: finest linear-scale resolution [m]: 1 nm
MIN_GRATING = 1e-9


@dataclass(frozen=True)
class Compensation(Component):
    """Friction compensation on the table-driving motor (screw motor or linear motor).

    ``mode``: ``none``; ``feedforward`` — the static Stribeck + Coulomb + viscous curve of the
    compensated sites at the *commanded* speed, added as current (model-based feed-forward,
    Armstrong-Hélouvry et al., Automatica 30 (1994) 1083–1138); ``observer`` — a LuGre
    observer at the *measured* speeds, ẑ' = v − σ0|v|ẑ/g(v) − k·e with e the table position
    error, F̂ = σ0ẑ + σ1ẑ' + σ2v (Canudas de Wit, Olsson, Åström, Lischinsky, IEEE TAC 40
    (1995) 419–425, Sect. V), added as current.  Compensated sites: the screw shaft and the
    guide (the guide only, for a linear motor).  The ``*_scale`` factors give the model
    mismatch the compensator works with (1 = exact; 1.2 = its value is 20 % high).

    Parameters
    ----------
    mode : str, default "none"
        ``"none"``, ``"feedforward"`` or ``"observer"``.
    coulomb_scale : float, default 1.0
        The compensator's F_c over the site's [-].
    static_scale : float, default 1.0
        Its F_s over the site's [-].
    stribeck_velocity_scale : float, default 1.0
        Its v_s over the site's [-].
    viscous_scale : float, default 1.0
        Its σ2 over the site's [-].
    observer_gain : float, default 0.0
        Observer gain k [1/s].

    References
    ----------
    .. [1] B. Armstrong-Hélouvry, P. Dupont, C. Canudas de Wit, "A survey of models, analysis
       tools and compensation methods for the control of machines with friction",
       Automatica 30 (1994) 1083–1138.
    .. [2] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    """

    mode: str = choice(("none", "feedforward", "observer"), default="none")
    # a model a thousand times off is no compensator: the lower bounds keep the products
    # physical (a factor 1e-320 passed and the run then overflowed)
    coulomb_scale: float = quantity("-", low=1e-3, high=10, low_inclusive=True, default=1.0)
    static_scale: float = quantity("-", low=1e-3, high=10, low_inclusive=True, default=1.0)
    stribeck_velocity_scale: float = quantity("-", low=1e-3, high=10, low_inclusive=True,
                                              default=1.0)
    viscous_scale: float = quantity("-", low=0, high=10, low_inclusive=True, default=1.0)
    observer_gain: float = quantity("1/s", low=0, high=1e6, low_inclusive=True, default=0.0,
                                    hint="k of the observer's correction −k·e [1/s]")
    _label = "compensation"


@dataclass(frozen=True)
class Controller(Component):
    """Cascade servo (position → velocity → current) shared by both motors.  Wang2021 Sect. 2.1.

    The block diagram (Fig. 5) is an image; the structure is an explicit choice, see
    docs/model.md.  Gains are in the units stated; a period of 0 means a continuous loop.

    Parameters
    ----------
    position_gain : float
        K_pp [1/s].
    velocity_gain : float
        K_vp [A s/rad] (A s/m on the table basis).
    current_gain : float
        K_ip [V/A].
    velocity_command_gain : float
        K_v, Table 2's "velocity-adjusting gain" [rad/(V s)].
    velocity_integral_gain : float, default 0.0
        K_vi [A/rad] (A/m on the table basis).
    current_integral_gain : float, default 0.0
        K_ii [V/(A s)].
    kv_placement : str, default "none"
        Where K_v enters: ``"none"``, ``"position_output"``, ``"velocity_error"``.
    velocity_gain_basis : str, default "motor"
        Velocity gains on rad/s of the motor or m/s of the table (``"table"``).
    velocity_feedback : str, default "motor"
        Velocity feedback from the motor encoder or the table scale.
    position_feedback : str, default "table"
        Position feedback of a ball-screw drive's table axis: the linear scale on the table
        (``"table"``, closed loop) or the motor encoders referred to the table through the
        lead, H·(θ_s − θ_n) (``"motor"``, semi-closed loop: lost motion at the nut is outside
        the loop).
    velocity_feedforward : bool, default True
        Feed the commanded speed forward.
    nut_loop : str, default "position"
        The hollow motor's loop: ``"position"`` or ``"speed"``.
    mode : str, default "cascade"
        ``"cascade"`` or ``"torque_off"``.
    compensation : Compensation
        Friction compensation.
    current_limit : float, default 1e4
        Current limit [A].
    voltage_limit : float, default 1e5
        Voltage limit [V].
    position_period : float, default 0.0
        Position-loop sample period; 0 = continuous [s].
    velocity_period : float, default 0.0
        Velocity-loop sample period [s].
    current_period : float, default 0.0
        Current-loop sample period [s].
    encoder_counts : float, default 0.0
        Motor encoder counts per revolution; 0 = ideal [counts/rev].
    grating_resolution : float, default 0.0
        Table scale resolution; 0 = ideal [m].

    References
    ----------
    .. [1] Wang2021 Sect. 2.1, Table 2.
    """

    position_gain: float = quantity("1/s", low=0, high=1e5, low_inclusive=True)
    # per rad/s of the motor, or per m/s of table speed with velocity_gain_basis = "table"
    velocity_gain: float = quantity("A s/rad", low=0, high=1e5, low_inclusive=True,
                                    table_unit="A s/m")
    current_gain: float = quantity("V/A", low=0, high=1e5, low_inclusive=True)
    velocity_command_gain: float = quantity("rad/(V s)", low=0, high=1e6)
    velocity_integral_gain: float = quantity(
        "A/rad", low=0, high=1e9, low_inclusive=True, default=0.0, table_unit="A/m"
    )
    current_integral_gain: float = quantity(
        "V/(A s)", low=0, high=1e9, low_inclusive=True, default=0.0
    )
    kv_placement: str = choice(("none", "position_output", "velocity_error"), default="none")
    velocity_gain_basis: str = choice(("motor", "table"), default="motor")
    velocity_feedback: str = choice(("motor", "table"), default="motor")
    position_feedback: str = choice(("table", "motor"), default="table")
    velocity_feedforward: bool = flag(default=True)
    nut_loop: str = choice(("position", "speed"), default="position")
    mode: str = choice(("cascade", "torque_off"), default="cascade")
    compensation: Compensation = field(default_factory=lambda: Compensation())
    current_limit: float = quantity("A", low=0, high=1e4, default=1e4)
    voltage_limit: float = quantity("V", low=0, high=1e5, default=1e5)
    position_period: float = quantity("s", low=0, high=0.1, low_inclusive=True, default=0.0)
    velocity_period: float = quantity("s", low=0, high=0.1, low_inclusive=True, default=0.0)
    current_period: float = quantity("s", low=0, high=0.1, low_inclusive=True, default=0.0)
    encoder_counts: float = quantity(
        "counts/rev", low=0, high=1e10, low_inclusive=True, default=0.0
    )
    grating_resolution: float = quantity(
        "m", low=0, high=1e-3, low_inclusive=True, default=0.0, hint="1 µm = 1e-6 m"
    )
    _label = "controller"

    def _check(self) -> None:
        periods = [p for p in (self.position_period, self.velocity_period, self.current_period)]
        for name, p in zip(("position", "velocity", "current"), periods, strict=True):
            if 0 < p < MIN_PERIOD:
                raise ParameterError(f"controller.{name}_period", p,
                                     f"expected 0 (a continuous loop) or {MIN_PERIOD:g} … 0.1 "
                                     "[s] (1 µs = 1e-6 s)")
        if 0 < self.grating_resolution < MIN_GRATING:
            raise ParameterError("controller.grating_resolution", self.grating_resolution,
                                 f"expected 0 (no quantisation) or {MIN_GRATING:g} … 0.001 [m]")
        if 0 < self.encoder_counts < 1:
            raise ParameterError("controller.encoder_counts", self.encoder_counts,
                                 "expected 0 (no quantisation) or ≥ 1 [counts/rev]")
        nonzero = [p for p in periods if p > 0]
        if nonzero:
            base = min(nonzero)
            for name, p in zip(("position", "velocity", "current"), periods, strict=True):
                if p > 0 and abs(p / base - round(p / base)) > 1e-9:
                    raise ParameterError(
                        f"controller.{name}_period",
                        p,
                        f"must be an integer multiple of the fastest period {base:g} [s]",
                    )


def default_controller() -> Controller:
    """The cascade with Wang2021 Table 2's gains (K_pp, K_vp, K_ip, K_v), everything else at
    its default.

    Returns
    -------
    Controller
        The default ``[controller]`` section.

    References
    ----------
    .. [1] Wang2021 Table 2.
    """
    return Controller(position_gain=8.0, velocity_gain=45.0, current_gain=2.0,
                      velocity_command_gain=250.0)


for _name in ("controller", "hollow_controller"):
    registry.register(registry.SECTIONS, _name, Controller)
