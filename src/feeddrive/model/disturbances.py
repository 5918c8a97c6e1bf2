"""Disturbances: table load force, motor torque ripple and cogging, screw lead error.

Each is a kernel plus an ``emit_*`` helper that registers its parameters and returns the code
of the term the mechanism adds to a body's equation.  None of them is emitted when its
amplitudes are all zero, so the default model is exactly the undisturbed one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import registry
from .._jit import kernel
from ..parameters import Component, ParameterError
from ..parameters.validation import MISSING, quantities, quantity, real_array
from .codegen import Builder

#: the load block ``disturbances.<name>``: constant force [N] and its start [s], the record's
#: sample step [s], where its samples lie in ``T`` and how many there are
LOAD_SLOTS = ("load_force", "load_start", "load_step", "load_offset", "load_points")
LOAD, LOAD_START, LOAD_STEP, LOAD_OFFSET, LOAD_POINTS = range(len(LOAD_SLOTS))
#: a harmonic series' block: its n orders, then n amplitudes, then n phases (sub-block k at
#: ``o + k·n``)
HARMONIC_FIELDS = ("orders", "amplitudes", "phases")
ORDERS, AMPLITUDES, PHASES = range(len(HARMONIC_FIELDS))
#: the largest load force on the table [N], constant (``disturbances.load_force``) or in a
#: record (:class:`LoadProfile`)
LARGEST_LOAD_FORCE = 1e6


@kernel
def harmonics(theta: float, P: np.ndarray, o: int, n: int) -> tuple[float, float]:
    """A harmonic series and its slope: (Σ A_k sin(n_k θ + φ_k), Σ A_k n_k cos(n_k θ + φ_k)).

    Used for motor torque ripple and cogging (θ the motor angle) and for the screw's lead error
    (θ the relative screw–nut angle).

    Parameters
    ----------
    theta : float
        The angle the series is periodic in [rad].
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the block in ``P``: n orders [-], n amplitudes [N m or m], n phases [rad]
        (:data:`HARMONIC_FIELDS`).
    n : int
        Number of harmonics.

    Returns
    -------
    value : float
        The series at ``theta`` [N m for ripple, m for lead error].
    slope : float
        Its derivative with respect to ``theta`` [N m/rad or m/rad].
    """
    value = 0.0
    slope = 0.0
    orders = o + ORDERS * n
    amplitudes = o + AMPLITUDES * n
    phases = o + PHASES * n
    for k in range(n):
        arg = P[orders + k] * theta + P[phases + k]
        value += P[amplitudes + k] * math.sin(arg)
        slope += P[amplitudes + k] * P[orders + k] * math.cos(arg)
    return value, slope


@kernel
def load_force(t: float, P: np.ndarray, o: int, T: np.ndarray) -> float:
    """Table load force at time t: a constant step plus an optional sampled record.

    The constant ``P[o + LOAD]`` acts from ``P[o + LOAD_START]`` on; the record
    (``P[o + LOAD_POINTS]`` samples at ``T[P[o + LOAD_OFFSET]:]``, uniform step
    ``P[o + LOAD_STEP]``) is interpolated linearly and its last value held.

    Parameters
    ----------
    t : float
        Time [s].
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the load block (:data:`LOAD_SLOTS`) in ``P``.
    T : numpy.ndarray
        The model's packed tables (the record's samples [N]).

    Returns
    -------
    float
        Load force against positive table motion [N].
    """
    f = P[o + LOAD] if t >= P[o + LOAD_START] else 0.0
    to = int(P[o + LOAD_OFFSET])
    n = int(P[o + LOAD_POINTS])
    if n > 1:
        u = t / P[o + LOAD_STEP]
        k = int(math.floor(u))
        if k >= n - 1:
            f += T[to + n - 1]
        elif k >= 0:
            w = u - k
            f += T[to + k] * (1.0 - w) + T[to + k + 1] * w
    return f


@dataclass(frozen=True)
class LoadProfile:
    """A table load force record, acting against positive table motion.

    Linear interpolation between samples, the last value held after the record.

    Parameters
    ----------
    time : numpy.ndarray
        Uniform, increasing sample instants from 0 [s].
    force : numpy.ndarray
        Load force at each instant [N].
    """

    time: np.ndarray
    force: np.ndarray

    def __post_init__(self) -> None:
        # refused when made, naming the field (a NaN force was refused only at simulate, in a
        # bare ValueError, strings in numpy's words: an outside check, 2026-12-07)
        self.encode()

    def encode(self) -> tuple[float, np.ndarray]:
        """The record as (sample interval, force samples) for the load kernel.

        Returns
        -------
        tuple of (float, numpy.ndarray)
            The sample interval [s] and the force samples [N].

        Raises
        ------
        ParameterError
            For arrays that are not numbers, not 1-D of one length ≥ 2, not finite, forces
            beyond ``LARGEST_LOAD_FORCE``, or times not on a uniform grid from 0.
        """
        t = real_array("load.time", self.time, "s")  # complex, bool, text: session 29
        f = real_array("load.force", self.force, "N")
        if t.ndim != 1 or t.size < 2 or f.shape != t.shape:
            raise ParameterError("load.time/force", MISSING,
                                 f"expected 1-D arrays of one length ≥ 2 (shapes {t.shape}, "
                                 f"{f.shape}) [s, N]")
        for name, arr, unit in (("time", t, "s"), ("force", f, "N")):
            if not np.all(np.isfinite(arr)):
                bad = int(np.flatnonzero(~np.isfinite(arr))[0])
                raise ParameterError(f"load.{name}[{bad}]", float(arr[bad]),
                                     f"expected finite values [{unit}]")
        if np.any(np.abs(f) > LARGEST_LOAD_FORCE):
            bad = int(np.flatnonzero(np.abs(f) > LARGEST_LOAD_FORCE)[0])
            raise ParameterError(f"load.force[{bad}]", float(f[bad]),
                                 f"expected |force| ≤ {LARGEST_LOAD_FORCE:g} [N] (as "
                                 "disturbances.load_force)")
        dt = np.diff(t)
        if abs(t[0]) > 1e-12 or np.any(dt <= 0) or np.ptp(dt) > 1e-9 * dt.mean():
            raise ParameterError("load.time", MISSING,
                                 "expected a uniform, increasing grid starting at 0 [s]")
        return float(dt.mean()), f


def emit_load(b: Builder, force: float, start: float, record: LoadProfile | None) -> str | None:
    """Register the table-load block and return the code of the load force.

    Parameters
    ----------
    b : Builder
        The model builder.
    force : float
        Constant load force [N].
    start : float
        Time the constant load is applied [s].
    record : LoadProfile or None
        A sampled load record added to the constant, if any.

    Returns
    -------
    str or None
        Code of the load force [N]; None when there is no load (force 0 and no record).
    """
    if force == 0.0 and record is None:
        return None
    step, values = record.encode() if record is not None else (1.0, np.zeros(1))
    where = b.table(values) if record is not None else 0
    o = b.named_params("disturbances", LOAD_SLOTS, np.array(
        [force, start, step, where, values.size if record is not None else 0]))
    b.add_aux("load_force", "N", "load force on the table (against positive motion)")
    return f"{b.use(load_force)}({{t}}, P, {o}, T)"


def emit_harmonics(b: Builder, name: str,
                   ripple: TorqueRipple | LeadError) -> tuple[int, int] | None:
    """Register a harmonic series (torque ripple or lead error) as a parameter block.

    Parameters
    ----------
    b : Builder
        The model builder.
    name : str
        The block's name below ``disturbances.``.
    ripple : TorqueRipple or LeadError
        Orders [-], amplitudes [N m or m] and phases [rad] of the harmonics.

    Returns
    -------
    tuple of (int, int) or None
        (offset of the block in ``P``, number of harmonics); None when every amplitude is 0.
    """
    if not any(a != 0.0 for a in ripple.amplitudes):
        return None
    series = [tuple(getattr(ripple, f)) for f in HARMONIC_FIELDS]  # the kernel's sub-blocks
    o = b.params(f"disturbances.{name}", np.array(sum(series, ())))
    return o, len(series[ORDERS])


# ---- the disturbances' parameters: section [disturbances]


@dataclass(frozen=True)
class TorqueRipple(Component):
    """Motor torque ripple and cogging: T_r(θ) = Σ_k A_k·sin(n_k·θ + φ_k), θ the motor shaft
    angle [rad].  ``orders`` n_k per revolution, ``amplitudes`` A_k [N m], ``phases`` φ_k [rad].

    Parameters
    ----------
    orders : tuple of float
        Harmonic orders n_k per revolution [-].
    amplitudes : tuple of float
        Amplitudes A_k [N m].
    phases : tuple of float
        Phases φ_k [rad].
    """

    orders: tuple[float, ...] = quantities("-", low=0, high=1e4)
    amplitudes: tuple[float, ...] = quantities("N m", low=0, high=1e3)
    phases: tuple[float, ...] = quantities("rad", low=-1e3, high=1e3)
    _label = "ripple"

    def _check(self) -> None:
        _same_length(self, ("orders", "amplitudes", "phases"))


@dataclass(frozen=True)
class LeadError(Component):
    """Screw lead error: the nut advances H·θ + Σ_k a_k·sin(n_k·θ + φ_k) [m] for a relative
    screw–nut angle θ [rad]; ``amplitudes`` a_k [m] (typically a few µm).

    Parameters
    ----------
    orders : tuple of float
        Harmonic orders n_k per revolution [-].
    amplitudes : tuple of float
        Amplitudes a_k [m].
    phases : tuple of float
        Phases φ_k [rad].
    """

    orders: tuple[float, ...] = quantities("-", low=0, high=1e4)
    amplitudes: tuple[float, ...] = quantities("m", low=0, high=1e-3, hint="1 µm = 1e-6 m")
    phases: tuple[float, ...] = quantities("rad", low=-1e3, high=1e3)
    _label = "lead_error"

    def _check(self) -> None:
        _same_length(self, ("orders", "amplitudes", "phases"))


def _same_length(obj: Any, names: tuple[str, ...]) -> None:
    lengths = {len(getattr(obj, n)) for n in names}
    if len(lengths) > 1:
        raise ParameterError(f"{obj._label}.{names[1]}", getattr(obj, names[1]),
                             f"expected as many entries as {names[0]} "
                             f"({len(getattr(obj, names[0]))})")


@dataclass(frozen=True)
class Disturbances(Component):
    """Forces and errors acting on the drive besides friction (all zero by default).

    ``load_force`` [N] acts on the table against positive motion (a cutting force resisting
    the feed is positive), from ``load_start`` [s]; a time profile is given through the API
    (:class:`feeddrive.LoadProfile`).

    Parameters
    ----------
    load_force : float, default 0.0
        Constant load on the table against positive motion [N].
    load_start : float, default 0.0
        When the load is applied [s].
    screw_motor_ripple : TorqueRipple
        Torque ripple of the screw motor.
    hollow_motor_ripple : TorqueRipple
        Torque ripple of the hollow motor.
    lead_error : LeadError
        The screw's lead error.
    """

    load_force: float = quantity("N", low=-LARGEST_LOAD_FORCE, high=LARGEST_LOAD_FORCE,
                                 default=0.0)
    load_start: float = quantity("s", low=0, high=1e9, low_inclusive=True, default=0.0)
    screw_motor_ripple: TorqueRipple = field(default_factory=lambda: TorqueRipple())
    hollow_motor_ripple: TorqueRipple = field(default_factory=lambda: TorqueRipple())
    lead_error: LeadError = field(default_factory=lambda: LeadError())
    _label = "disturbances"


registry.register(registry.SECTIONS, "disturbances", Disturbances)
