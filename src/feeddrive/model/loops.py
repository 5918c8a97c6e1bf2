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
from dataclasses import dataclass

import numpy as np

from .._jit import kernel
from .codegen import Builder

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
    """Floor quantisation to ``step`` (an incremental encoder or grating count); 0 = ideal."""
    if step <= 0.0:
        return value
    return step * math.floor(value / step)


@kernel
def position_law(error: float, speed_ff: float, P: np.ndarray, o: int) -> float:
    """Speed command [rad/s of the axis] from position error [m] and feed-forward [m/s]."""
    k = P[o + KPP]
    if int(P[o + KV_PLACE]) == 1:
        k *= P[o + KV]
    return (k * error + P[o + FF] * speed_ff) / P[o + H_AX]


@kernel
def speed_command(error: float, speed_ref: float, P: np.ndarray, o: int) -> float:
    """Position loop, or (speed mode, the hollow motor's ``nut_loop = "speed"``) the
    commanded speed itself with no position feedback."""
    if P[o + SPEED_MODE] > 0.5:
        return speed_ref / P[o + H_AX]
    return position_law(error, speed_ref, P, o)


@kernel
def velocity_error(speed_cmd: float, speed_meas: float, P: np.ndarray, o: int) -> float:
    """Velocity-loop error in the units the gains act on (see module docstring)."""
    e = speed_cmd - speed_meas
    if int(P[o + V_BASIS]) == 1:
        e *= P[o + H_AX]
    if int(P[o + KV_PLACE]) == 2:
        e /= P[o + KV]
    return e


@kernel
def saturate(value: float, limit: float) -> float:
    if value > limit:
        return limit
    if value < -limit:
        return -limit
    return value


@kernel
def integrator_rate(error: float, unsaturated: float, limit: float) -> float:
    """Conditional integration (anti-windup): stop integrating into a saturated output."""
    if (unsaturated > limit and error > 0.0) or (unsaturated < -limit and error < 0.0):
        return 0.0
    return error


@kernel
def current_command(error: float, integral: float, P: np.ndarray, o: int) -> float:
    return P[o + KVP] * error + P[o + KVI] * integral


@kernel
def voltage_command(error: float, integral: float, P: np.ndarray, o: int) -> float:
    return P[o + KIP] * error + P[o + KII] * integral


@dataclass(frozen=True)
class Channel:
    """A measured position for sampled loops: state expression and quantisation slot."""

    name: str
    state: str  # code expression of the true value, e.g. "y[4]"
    speed: str  # code expression of its true rate
    quantum: str  # code expression of the count size (0 = ideal)


@dataclass(frozen=True)
class Axis:
    """One motor's cascade, as the mechanism wires it.

    ``position``/``position_q``: code for the measured position [m] continuous/sampled (with
    quantised channels as ``q_<channel>``); ``feedforward``: speed [m/s]; ``reference``:
    commanded position [m]; ``speed``: the measured motor speed, continuous; ``speed_q``: the
    same from sampled channel speeds (``s_<channel>``); ``active``: code of a condition under
    which the axis runs ("" = always); ``speed_unit``: unit of its speed command;
    ``speed_law = "speed"``: the axis may run a speed loop only (its block's speed-mode slot).
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


def axis_parameters(b: Builder, axis: str, c: object, H: float, *, speed_mode: bool) -> int:
    """Register the parameter block of ``axis`` from a :class:`Controller`; return offset."""
    from ..parameters import Controller

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
    as clocks of the model's sample schedule (:meth:`Builder.clock`; 0 = continuous)."""
    for name in CLOCKS:
        b.param(f"controller.{name}", float(getattr(c, name)))
        b.clock(f"controller.{name}")


def _period(b: Builder, loop: str) -> str:
    """Code of a loop's sample period [s] (``loop``: position, velocity or current)."""
    return b.p(f"controller.{loop}_period")


def declare_states(b: Builder, axes: list[Axis]) -> None:
    """Loop integrator states, grouped by loop (all velocity integrals, then all current)."""
    for ax in axes:
        b.state(f"{ax.name}_velocity_integral", "rad", f"{ax.name} velocity-loop integral",
                "velocity_integral")
    for ax in axes:
        b.state(f"{ax.name}_current_integral", "A s", f"{ax.name} current-loop integral",
                "current_integral")


def declare_signals(b: Builder, axes: list[Axis]) -> None:
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
    """Speed and current commands of every axis into ``target`` (aux array expression)."""
    P = "P"
    sc = [f"{target}[{b.aux_index[f'{ax.name}_speed_command']}]" for ax in axes]
    ic = [f"{target}[{b.aux_index[f'{ax.name}_current_command']}]" for ax in axes]
    verr, sat, ccmd = b.use(velocity_error), b.use(saturate), b.use(current_command)
    out.append(f"if {_period(b, 'position')} > 0.0:")
    for ax, s in zip(axes, sc, strict=True):
        out.append(f"    {s} = {b.h(ax.name + '.speed_command')}")
    out.append("else:")
    for ax, s in zip(axes, sc, strict=True):
        out.append(f"    {s} = {_speed_law(b, ax)}({ax.reference} - {ax.position}, "
                   f"{ax.feedforward}, {P}, {ax.param_offset}) + "
                   f"{P}[{ax.param_offset + INJ_SPEED}]")
    out.append(f"if {_period(b, 'velocity')} > 0.0:")
    for ax, c in zip(axes, ic, strict=True):
        held = b.h(ax.name + '.current_command')
        out.append(f"    {c} = {sat}({held} + {ax.current_feedforward}, "
                   f"{P}[{ax.param_offset + I_MAX}])" if ax.current_feedforward
                   else f"    {c} = {held}")
    out.append("else:")
    for ax in axes:
        out.append(f"    e_{ax.name} = {verr}({target}[{b.aux_index[ax.name + '_speed_command']}], "
                   f"{ax.speed}, {P}, {ax.param_offset})")
    for ax, c in zip(axes, ic, strict=True):
        o = ax.param_offset
        # compensation is continuous-only (refused with sampled loops): right-hand side only
        extra = f" + {ax.extra_current}" if ax.extra_current and target == "aux" else ""
        if ax.current_feedforward:
            extra += f" + {ax.current_feedforward}"
        out.append(f"    {c} = {sat}({ccmd}(e_{ax.name}, {b.y(ax.name + '_velocity_integral')}, "
                   f"{P}, {o}) + {P}[{o + INJ_CURRENT}]{extra}, {P}[{o + I_MAX}])")


def emit_cascade(b: Builder, axes: list[Axis], channels: list[Channel]) -> None:
    """Write the continuous part into the right-hand side and the sampled part into the
    controller update, for every axis."""
    rate, sat, vcmd = b.use(integrator_rate), b.use(saturate), b.use(voltage_command)
    verr, ccmd, quant = b.use(velocity_error), b.use(current_command), b.use(quantise)

    # ---- right-hand side: commands, continuous integrators, current loops
    lines: list[str] = []
    _emit_commands(b, axes, lines, "aux")
    lines.append(f"if {_period(b, 'velocity')} == 0.0 and P[{axes[0].param_offset + KVI}] != 0.0:")
    for ax in axes:
        o = ax.param_offset
        lines += _guarded(ax, [
            f"e_{ax.name} = {verr}({b.a(ax.name + '_speed_command')}, {ax.speed}, P, {o})",
            f"raw = P[{o + KVP}] * e_{ax.name} + P[{o + KVI}] * "
            f"{b.y(ax.name + '_velocity_integral')}",
            f"{b.dy(ax.name + '_velocity_integral')} = {rate}(e_{ax.name}, raw, "
            f"P[{o + I_MAX}])"])
        if ax.active:
            lines.append("    else:")
            lines.append(f"        {b.dy(ax.name + '_velocity_integral')} = 0.0")
    lines.append("else:")
    for ax in axes:
        lines.append(f"    {b.dy(ax.name + '_velocity_integral')} = 0.0")
    for ax in axes:
        o = ax.param_offset
        ic = ax.name + "_current_integral"
        lines += [
            f"if {_period(b, 'current')} > 0.0:",
            f"    u = {b.h(ax.name + '.voltage')}",
            f"    {b.dy(ic)} = 0.0",
            "else:",
            f"    e = {b.a(ax.name + '_current_command')} - {ax.current_state}",
            f"    raw = {vcmd}(e, {b.y(ic)}, P, {o})",
            f"    u = {sat}(raw, P[{o + U_MAX}])",
            f"    {b.dy(ic)} = {rate}(e, raw, P[{o + U_MAX}]) if P[{o + KII}] != 0.0 else 0.0",
            f"{b.a(ax.name + '_voltage')} = u",
        ]
        if ax.active:  # a held axis (the CDFS nut) freezes its current integral too
            lines += [f"if not ({ax.active}):", f"    {b.dy(ic)} = 0.0"]
    for ln in lines:
        b.emit(ln)

    # ---- sampled update
    s: list[str] = [f"ref_x, ref_v, ref_xn, ref_vn = {b.reference_call}"]
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
            f"cmd[{b.aux_index[ax.name + '_current_command']}] - {ax.current_state}", vcmd,
            b.h(ax.name + ".current_integral"), b.h(ax.name + ".voltage"), ax.param_offset,
            U_MAX, rate, sat, "tc", "u_raw"))
    for ln in s:
        b.emit(ln, sampled=True)
