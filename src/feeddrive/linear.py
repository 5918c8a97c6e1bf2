"""Linearisation of an assembled drive at steady sliding, loop analysis, stability band.

* :func:`linearize` — A, B, C, D of the closed loop at steady sliding at a table speed (or
  frictionless), with named states, inputs and outputs; ``.to_control()`` gives a
  python-control ``StateSpace``.  The steady state is solved for (Newton on the compiled
  right-hand side, positions moving with the reference); the Jacobians are central
  differences of the compiled right-hand side, each state perturbed on its own tolerance
  scale.  The friction laws' analytic linearisations (``FrictionLaw.linearise``) serve the
  sliding-stability indicators of :mod:`feeddrive.friction` and are checked against this.
* :func:`loop_analysis` — poles with frequency and damping ratio, and the velocity- and
  position-loop transfer functions L(s) of each motor axis (loop broken at the current and
  speed commands by zero-valued injection inputs, L = 1/S − 1), with gain/phase margins and
  bandwidths.
* :func:`stability_band` — the speeds at which steady sliding is linearly unstable (full model,
  every friction site and bristle state), edges refined by bisection to a stated tolerance,
  with the unstable mode's frequency.

Inputs (per motor axis ``a``): ``a_speed_command_disturbance`` [rad/s, or m/s for a linear
motor] added to the position loop's output, ``a_current_command_disturbance`` [A] added to the
velocity loop's output.  Outputs: ``table_position`` [m], ``table_speed`` [m/s], and per axis
``a_speed_command``, ``a_current_command`` (the loop signals *after* the injection).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy import optimize

from . import protocol
from .control import ConstantSpeed
from .model.assemble import Model
from .model.loops import INJ_CURRENT, INJ_SPEED
from .parameters import ParameterError
from .simulate import DriveSystem

# kinematic pairs: (position-like state, its rate state) — positions move with the reference
_KINEMATIC = {"screw_angle": "screw_speed", "nut_angle": "nut_speed",
              "table_position": "table_speed"}
_T0 = 1.0  # [s] operating-point time (after the reference's start ramp)


@dataclass(frozen=True)
class LinearModel:
    """δẋ = A δx + B δu, δy = C δx + D δu around ``operating_point``."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    operating_point: dict[str, float]
    table_speed: float  # [m/s]
    nut_speed: float  # [m/s]
    frictionless: bool
    notes: tuple[str, ...] = field(default=())

    def poles(self) -> np.ndarray:
        return np.linalg.eigvals(self.A)

    def to_control(self) -> Any:
        """python-control ``StateSpace`` with the state, input and output names."""
        import control

        return control.ss(self.A, self.B, self.C, self.D, states=list(self.states),
                          inputs=list(self.inputs), outputs=list(self.outputs))


@dataclass(frozen=True)
class Pole:
    real: float  # [1/s]
    imag: float  # [rad/s]

    @property
    def frequency_hz(self) -> float:
        return abs(complex(self.real, self.imag)) / (2 * math.pi)

    @property
    def damping_ratio(self) -> float:
        mag = abs(complex(self.real, self.imag))
        return -self.real / mag if mag > 0 else 1.0


def _frictionless(system: DriveSystem) -> DriveSystem:
    p = system.parameters
    for site in ("screw", "nut", "guide"):
        p = p.replace_path(f"friction.{site}.law", "none")
    return replace(system, parameters=p)


def _check_continuous(system: DriveSystem) -> None:
    c = system.parameters.controller
    for name in ("position_period", "velocity_period", "current_period"):
        if getattr(c, name) > 0:
            raise ParameterError(f"controller.{name}", getattr(c, name),
                                 "linearisation needs continuous loops (period 0 [s]); a "
                                 "sampled loop is a discrete-time system")


def _live_states(model: Model, system: DriveSystem) -> list[int]:
    """States that move: with the CDFS nut locked its states are frozen and dropped."""
    live = []
    nut_held = model.drive == "cdfs" and system.nut_hold == "locked"
    for k, name in enumerate(model.state_names):
        if nut_held and (name.startswith("nut_") or name.startswith("ball_nut_z")):
            continue
        live.append(k)
    return live


def _scales(model: Model) -> np.ndarray:
    atol, _ = model.tolerances(1e-7, 1e-6, 1e-4)
    return atol


class _Evaluator:
    """Calls the compiled right-hand side at the operating-point time."""

    def __init__(self, model: Model) -> None:
        self.model = model
        self.held = np.zeros(model.n_held)
        self.aux = np.zeros(len(model.aux))
        self.n = len(model.states)

    def __call__(self, y: np.ndarray, P: np.ndarray | None = None) -> tuple[np.ndarray,
                                                                               np.ndarray]:
        dy = np.empty(self.n)
        aux = np.empty(len(self.model.aux))
        self.model.module.rhs(_T0, np.ascontiguousarray(y, dtype=float), self.held,
                              self.model.P if P is None else P, self.model.T, 0, 0, 0, dy, aux)
        return dy, aux


def steady_state(system: DriveSystem, table_speed: float, nut_speed: float = 0.0
                 ) -> tuple[Model, np.ndarray]:
    """The state of steady sliding at ``table_speed`` [m/s] (and nut speed) at t = 1 s:
    accelerations, bristle, current and integrator rates zero; positions move with the
    reference.  Raises ParameterError if no steady state is found."""
    _check_continuous(system)
    profile = ConstantSpeed(table_speed, nut_speed, ramp_time=0.0)
    model = system.model(profile)
    f = _Evaluator(model)
    names = model.state_names
    n = len(names)
    y0 = np.zeros(n)
    H = system.parameters.screw.transmission_ratio if "screw_speed" in names else 1.0
    speeds = {"table_speed": table_speed, "screw_speed": (table_speed + nut_speed) / H,
              "nut_speed": nut_speed / H}
    held_nut = model.drive == "cdfs" and system.nut_hold == "locked"
    if held_nut:
        speeds["nut_speed"] = 0.0
    for name, v in speeds.items():
        if name in names:
            y0[names.index(name)] = v
    x_ref = table_speed * _T0
    if "table_position" in names:
        y0[names.index("table_position")] = x_ref
    if "nut_angle" in names and not held_nut:
        y0[names.index("nut_angle")] = nut_speed * _T0 / H
    if "screw_angle" in names:
        y0[names.index("screw_angle")] = (x_ref + (0 if held_nut else nut_speed * _T0)) / H
    live = _live_states(model, system)
    fixed_speed = [names.index(s) for s in speeds if s in names]
    unknown = [k for k in live if k not in fixed_speed]
    scale = _scales(model)

    def residual(u: np.ndarray) -> np.ndarray:
        y = y0.copy()
        y[unknown] = u * scale[unknown]
        dy, _ = f(y)
        r = []
        for k in unknown:
            name = names[k]
            if name in _KINEMATIC:
                # its rate is the fixed speed: use the rate state's equation instead
                continue
            r.append(dy[k] / scale[k])
        for name, rate in _KINEMATIC.items():
            if name in names and names.index(name) in unknown:
                r.append(dy[names.index(rate)] / scale[names.index(rate)])
        return np.array(r)

    # Levenberg–Marquardt stays near the start along directions the equations leave free
    # (e.g. the table position with the position loop open)
    sol = optimize.least_squares(residual, y0[unknown] / scale[unknown], method="lm",
                                 xtol=1e-15, ftol=1e-15, gtol=1e-15)
    y = y0.copy()
    y[unknown] = sol.x * scale[unknown]
    res = residual(sol.x)
    # residuals are rates divided by the solver tolerances: 0.1 is a table acceleration of
    # 1e-7 m/s² (a force imbalance of ~1e-7 of the friction force), far below anything that
    # moves the linearisation; the finite-difference Newton steps stall around 1e-3
    if np.max(np.abs(res)) > 0.1 or not np.all(np.isfinite(y)):
        raise ParameterError("table_speed", table_speed * 1e3,
                             f"no steady sliding state found [mm/s] ({sol.message})")
    return model, y


def linearize(system: DriveSystem, table_speed: float = 1e-3, nut_speed: float = 0.0, *,
              frictionless: bool = False) -> LinearModel:
    """Linearise the closed loop of ``system`` at steady sliding at ``table_speed`` [m/s]
    (``nut_speed`` [m/s] for the DDFS), or with every friction law set to "none"."""
    if table_speed == 0.0 and not frictionless:
        raise ParameterError("table_speed", 0.0, "steady sliding needs a non-zero speed [m/s]")
    sys_ = _frictionless(system) if frictionless else system
    model, y = steady_state(sys_, table_speed, nut_speed)
    f = _Evaluator(model)
    live = _live_states(model, sys_)
    scale = _scales(model)
    n = len(live)
    A = np.empty((n, n))
    aux_names = [a.name for a in model.aux]
    axes = [a.removesuffix("_speed_command") for a in aux_names if a.endswith("_speed_command")]
    if sys_.drive == "cdfs" and sys_.nut_hold == "locked":
        axes = [a for a in axes if a != "nut"]
    out_aux = [f"{a}_{k}" for a in axes for k in ("speed_command", "current_command")]
    out_names = ["table_position", "table_speed", *out_aux]
    in_slots = []
    in_names = []
    for a in axes:
        first = model.parameter_names.index(f"controller.{a}.kpp")
        in_slots += [first + INJ_SPEED, first + INJ_CURRENT]
        in_names += [f"{a}_speed_command_disturbance", f"{a}_current_command_disturbance"]

    def outputs(yv: np.ndarray, aux: np.ndarray) -> np.ndarray:
        st = model.state_names
        return np.array([yv[st.index("table_position")], yv[st.index("table_speed")],
                         *[aux[aux_names.index(o)] for o in out_aux]])

    C = np.empty((len(out_names), n))
    for j, k in enumerate(live):
        h = 1e-2 * scale[k]  # a hundredth of the state's solver tolerance
        yp, ym = y.copy(), y.copy()
        yp[k] += h
        ym[k] -= h
        dp, ap = f(yp)
        dm, am = f(ym)
        A[:, j] = (dp[live] - dm[live]) / (2 * h)
        C[:, j] = (outputs(yp, ap) - outputs(ym, am)) / (2 * h)
    B = np.empty((n, len(in_slots)))
    D = np.empty((len(out_names), len(in_slots)))
    for j, slot in enumerate(in_slots):
        h = 1e-6  # [rad/s] or [A] of injected command
        Pp, Pm = model.P.copy(), model.P.copy()
        Pp[slot] += h
        Pm[slot] -= h
        dp, ap = f(y, Pp)
        dm, am = f(y, Pm)
        B[:, j] = (dp[live] - dm[live]) / (2 * h)
        D[:, j] = (outputs(y, ap) - outputs(y, am)) / (2 * h)
    names = tuple(model.state_names[k] for k in live)
    return LinearModel(A=A, B=B, C=C, D=D, states=names, inputs=tuple(in_names),
                       outputs=tuple(out_names),
                       operating_point={model.state_names[k]: float(y[k]) for k in live},
                       table_speed=table_speed, nut_speed=nut_speed, frictionless=frictionless)


# ---------------------------------------------------------------- loops


@dataclass(frozen=True)
class LoopResult:
    """One loop's open-loop transfer L(jω) and its margins."""

    name: str
    frequency_hz: np.ndarray
    magnitude_db: np.ndarray
    phase_deg: np.ndarray
    gain_margin_db: float | None
    phase_margin_deg: float | None
    crossover_hz: float | None
    bandwidth_hz: float | None  # closed loop −3 dB

    def as_dict(self) -> dict[str, Any]:
        return {"loop": self.name, "gain_margin_db": self.gain_margin_db,
                "phase_margin_deg": self.phase_margin_deg, "crossover_hz": self.crossover_hz,
                "closed_loop_bandwidth_hz": self.bandwidth_hz}


def _freq_response(lin: LinearModel, inp: str, out: str, w: np.ndarray) -> np.ndarray:
    i, o = lin.inputs.index(inp), lin.outputs.index(out)
    n = lin.A.shape[0]
    eye = np.eye(n)
    resp = np.empty(w.size, dtype=complex)
    for k, wk in enumerate(w):
        x = np.linalg.solve(1j * wk * eye - lin.A, lin.B[:, i])
        resp[k] = lin.C[o] @ x + lin.D[o, i]
    return resp


def _margins(freq: np.ndarray, L: np.ndarray, T: np.ndarray, name: str) -> LoopResult:
    mag = 20 * np.log10(np.abs(L))
    phase = np.degrees(np.unwrap(np.angle(L)))
    crossover = phase_margin = gain_margin = bandwidth = None
    idx = np.where((mag[:-1] >= 0) & (mag[1:] < 0))[0]
    if idx.size:
        k = idx[0]
        f = np.interp(0.0, [mag[k + 1], mag[k]], [freq[k + 1], freq[k]])
        ph = np.interp(f, freq[k:k + 2], phase[k:k + 2])
        crossover = float(f)
        phase_margin = float(((ph + 180.0) + 180.0) % 360.0 - 180.0)
    # phase crossings of −180° (mod 360) above the gain crossover
    wrapped = (phase + 180.0) % 360.0 - 180.0
    cross = np.where(np.abs(np.diff(np.sign(wrapped))) > 0)[0]
    for k in cross:
        if abs(wrapped[k] - wrapped[k + 1]) > 180.0:  # a jump of the wrap, not a crossing
            continue
        gm = -float(np.interp(0.0, [wrapped[k], wrapped[k + 1]], [mag[k], mag[k + 1]]))
        if crossover is None or freq[k] > crossover:
            gain_margin = gm
            break
    tmag = 20 * np.log10(np.abs(T))
    low = tmag[0]
    below = np.where(tmag < low - 3.0)[0]
    if below.size:
        bandwidth = float(freq[below[0]])
    return LoopResult(name, freq, mag, phase, gain_margin, phase_margin, crossover, bandwidth)


@dataclass(frozen=True)
class LoopAnalysis:
    poles: list[Pole]
    loops: list[LoopResult]
    linear: LinearModel

    def dominant(self) -> Pole:
        """The least-damped oscillatory pole pair (the mode friction destabilises first)."""
        osc = [p for p in self.poles if p.imag > 1e-6]
        return min(osc, key=lambda p: p.damping_ratio) if osc else min(
            self.poles, key=lambda p: -p.real)

    def as_dict(self) -> dict[str, Any]:
        d = self.dominant()
        return {
            "table_speed_mm_s": 1e3 * self.linear.table_speed,
            "frictionless": self.linear.frictionless,
            "least_damped_mode": {"frequency_hz": d.frequency_hz,
                                  "damping_ratio": d.damping_ratio},
            "poles": [{"real_1_per_s": p.real, "imag_rad_per_s": p.imag,
                       "frequency_hz": p.frequency_hz, "damping_ratio": p.damping_ratio}
                      for p in self.poles if p.imag >= 0],
            "loops": [lp.as_dict() for lp in self.loops],
        }


def loop_analysis(system: DriveSystem, table_speed: float = 1e-3, nut_speed: float = 0.0, *,
                  frictionless: bool = True, f_min: float = 0.5, f_max: float = 500.0,
                  points: int = 400) -> LoopAnalysis:
    """Poles and velocity/position loop transfers of every motor axis between ``f_min`` and
    ``f_max`` [Hz].  The velocity loop is analysed with the position loop open (K_pp = 0)."""
    lin = linearize(system, table_speed, nut_speed, frictionless=frictionless)
    freq = np.logspace(np.log10(f_min), np.log10(f_max), points)
    w = 2 * np.pi * freq
    open_pos = replace(system, parameters=system.parameters.replace_path(
        "controller.position_gain", 0.0))
    lin_v = linearize(open_pos, table_speed, nut_speed, frictionless=frictionless)
    loops = []
    for inp in lin.inputs:
        axis, kind = inp.split("_", 1)[0], inp
        if kind.endswith("current_command_disturbance"):
            S = _freq_response(lin_v, inp, f"{axis}_current_command", w)
            loops.append(_margins(freq, 1.0 / S - 1.0, 1.0 - S, f"{axis} velocity loop"))
        else:
            S = _freq_response(lin, inp, f"{axis}_speed_command", w)
            loops.append(_margins(freq, 1.0 / S - 1.0, 1.0 - S, f"{axis} position loop"))
    poles = sorted((Pole(float(z.real), float(z.imag)) for z in lin.poles()),
                   key=lambda p: p.frequency_hz)
    return LoopAnalysis(poles=poles, loops=loops, linear=lin)


# ---------------------------------------------------------------- stability band


@dataclass(frozen=True)
class StabilityBand:
    """Speeds [m/s] at which steady sliding is linearly unstable, with the unstable mode."""

    intervals: list[tuple[float, float]]  # (lower, upper) edges [m/s]
    mode_frequency_hz: list[float]  # of the rightmost pole, at each interval's middle
    speeds: np.ndarray  # scanned speeds [m/s]
    max_real_part: np.ndarray  # [1/s] rightmost pole at each scanned speed
    frequency_hz: np.ndarray  # of the rightmost pole
    tolerance: float  # [m/s] bisection tolerance of the edges
    nut_speed: float

    def as_dict(self) -> dict[str, Any]:
        return {
            "rule": "steady sliding is unstable where the closed loop linearised at that speed "
                    "(every friction site and bristle state) has a pole with positive real "
                    f"part (real poles below {MARGINAL:g} × the fastest pole are the free "
                    "rigid-body motions and are not counted)",
            "nut_speed_mm_s": 1e3 * self.nut_speed,
            "unstable_bands_mm_s": [[1e3 * lo, 1e3 * hi] for lo, hi in self.intervals],
            "unstable_mode_frequency_hz": self.mode_frequency_hz,
            "edge_tolerance_mm_s": 1e3 * self.tolerance,
            "scan_mm_s": [float(1e3 * self.speeds[0]), float(1e3 * self.speeds[-1]),
                          int(self.speeds.size)],
        }


# Free directions (e.g. the nut angle of a hollow motor on a speed loop, which no loop holds)
# give real poles at 0 that finite differences place at ±1e-9…1e-6 1/s; real poles smaller
# than this fraction of the fastest pole are treated as those marginal modes.
MARGINAL = 1e-7


def rightmost_pole(system: DriveSystem, v: float, nut_speed: float = 0.0
                   ) -> tuple[float, float]:
    """(real part [1/s], frequency [Hz]) of the rightmost pole of the closed loop linearised
    at steady sliding at ``v`` [m/s], the marginal free-motion poles (:data:`MARGINAL`) left
    out — the quantity :func:`stability_band` judges."""
    lin = linearize(system, v, nut_speed)
    ev = lin.poles()
    fastest = float(np.max(np.abs(ev)))
    ev = ev[~((np.abs(ev.imag) < MARGINAL * fastest) & (np.abs(ev) < MARGINAL * fastest))]
    k = int(np.argmax(ev.real))
    return float(ev[k].real), float(abs(ev[k].imag) / (2 * np.pi))


def stability_band(system: DriveSystem, nut_speed: float = 0.0, *,
                   low: float = protocol.LINEAR_SPEED_RANGE[0],
                   high: float = protocol.LINEAR_SPEED_RANGE[1],
                   points: int = protocol.LINEAR_POINTS, tolerance: float = 1e-6,
                   progress: Any = None) -> StabilityBand:
    """Scan table speeds from ``low`` to ``high`` [m/s] (log-spaced; default
    ``feeddrive.protocol.LINEAR_SPEED_RANGE``), then bisect every stable/unstable change to
    ``tolerance`` [m/s]."""
    if not (0 < low < high):
        raise ParameterError("low", low * 1e3, f"expected 0 < low < high = {high * 1e3} [mm/s]")
    speeds = np.geomspace(low, high, points)
    re = np.empty(points)
    fr = np.empty(points)
    for k, v in enumerate(speeds):
        re[k], fr[k] = rightmost_pole(system, float(v), nut_speed)
        if progress is not None:
            progress(k + 1, points)
    unstable = re > 0
    edges: list[float] = []
    for k in range(points - 1):
        if unstable[k] != unstable[k + 1]:
            a, b = float(speeds[k]), float(speeds[k + 1])
            ua = unstable[k]
            while b - a > tolerance:
                m = 0.5 * (a + b)
                if (rightmost_pole(system, m, nut_speed)[0] > 0) == ua:
                    a = m
                else:
                    b = m
            edges.append(0.5 * (a + b))
    intervals: list[tuple[float, float]] = []
    start = float(speeds[0]) if unstable[0] else None
    it = iter(edges)
    for k in range(points - 1):
        if unstable[k] != unstable[k + 1]:
            e = next(it)
            if unstable[k + 1]:
                start = e
            else:
                intervals.append((start if start is not None else float(speeds[0]), e))
                start = None
    if start is not None:
        intervals.append((start, float(speeds[-1])))
    freqs = [rightmost_pole(system, math.sqrt(lo * hi), nut_speed)[1] for lo, hi in intervals]
    return StabilityBand(intervals=intervals, mode_frequency_hz=freqs, speeds=speeds,
                         max_real_part=re, frequency_hz=fr, tolerance=tolerance,
                         nut_speed=nut_speed)


__all__ = ["LinearModel", "LoopAnalysis", "LoopResult", "Pole", "StabilityBand",
           "linearize", "loop_analysis", "rightmost_pole", "stability_band", "steady_state"]
