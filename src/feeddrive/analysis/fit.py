"""Fit a whole drive to measured time traces, with uncertainty.  SI units inside.

Output-error least squares (``scipy.optimize.least_squares``, trust-region reflective):
each experiment (a trace file) is simulated from rest with its own reference, taken from
the file's command columns (``table_speed_reference``/``command_speed`` and, for the DDFS,
``nut_speed_reference``) or given as a profile, and every measured signal (table position
or speed, motor current or torque) is compared sample by sample with the simulation,
interpolated onto the measured times.

Free parameters are addressed by their dotted path (``controller.velocity_integral_gain``),
as ``calibrate --unknown`` and sweep axes address them
(``DriveParameters.replace_path``); they are fitted as factors on
their start value, bounded by the parameter's declared plausible range
(:func:`~feeddrive.parameters.validation.quantity`) unless bounds are given.

Weights.  Each signal of each experiment is divided by its noise level σ estimated from the
data alone, without the model: the robust (median absolute deviation) scale of its second
differences / √6 (white noise: var Δ²e = 6σ²), but never below the record's resolution
q/√12 (q the smallest step between samples: encoder or interferometer quantisation, or the
printed digits).  ``weights`` multiply that.  With the model right, the weighted residual
then has rms ≈ 1; the *residual check* compares each signal's residual rms with its σ and
refuses to call any parameter determined when a ratio exceeds ``MAX_RESIDUAL_RATIO``.

A table position is compared up to a constant per record (``OFFSET_FREE``: the start within
an encoder count is unknown; the mean of its residual is removed).

Numerical error.  At the optimum the forward model's integration error is estimated per
fitted signal (``simulate(error_estimate=True)``) and the integrator tightened (×0.1 of every
tolerance, the search resumed) until it is ≤ ``ERROR_TO_NOISE`` × every signal's noise and a
ten-times-tighter integrator moves no estimate by more than ``ESTIMATE_SHIFT`` standard
errors and changes the standard error of no linear interval by more than ``STDERR_SHIFT`` of
itself; else the intervals are withheld (:class:`IntegrationCheck`).

Uncertainty.  The covariance is the HAC sandwich of
:mod:`~feeddrive.analysis.fit_residuals` (the white-noise s²(JᵀJ)⁻¹ kept for comparison);
a residual above ``MAX_RESIDUAL_RATIO`` × its noise: "model inadequate", intervals withheld.
The search's Jacobian: forward differences (``JACOBIAN_STEP``), each column one batch of
simulations, run in parallel through the sweep executors when asked; its optimum is then
polished by Gauss–Newton steps with central differences (``TANGENT_STEP``), the Jacobian the
intervals use (the forward secant is not the tangent where an interval is far narrower
than its step).  Also: the correlation matrix, the
condition number of J with columns scaled by the parameter values, and the poorly
determined combinations: the right singular vectors whose singular value is below
1/``MAX_CONDITION`` of the largest.  A parameter whose
linear interval is not credible (half-width above ``PROFILE_ABOVE`` of its value, or
reaching a bound) or over which the problem is nonlinear (the sum of squares at the
interval's ends off the linearisation by a factor above ``NONLINEARITY_LIMIT``) gets a
profile-likelihood interval: it is fixed on a grid and the others refitted; the interval
keeps the values whose SSR stays below SSR·(1 + κ·F(1, dof)/dof), κ its HAC-to-white
variance ratio (at least 1); a value the set refuses ends it at the last admissible one.
"""

from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import functools
import math
import time as _time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

# scipy.optimize and scipy.stats are imported where used: ≈ 1 s of imports that the callers
# of this module's light helpers (`_no_effect`, `Experiment`: the sensitivity) need not pay
from .._kept import Kept
from ..parameters import DriveParameters, ParameterError, dumps
from ..parameters.toml_io import toml_comment, toml_string
from ..parameters.validation import MISSING, check_flag, check_speed, is_real
from .fit_residuals import HacCovariance, ResidualDiagnostics, diagnose, hac_covariance
from .fit_statistics import NOISE_MIN_SAMPLES, correlation, covariance, noise_level

__all__ = ["INPUT_COLUMNS", "MEASURABLE", "Experiment", "FitError", "FitResult", "IntegrationCheck",
           "ParameterEstimate",
           "fit_drive", "free_parameter_bounds", "read_experiment"]

#: signals a trace may carry: name → (dimension, default unit, header aliases)
MEASURABLE: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "table_position": ("length", "mm", ("table_position", "position")),
    "table_speed": ("speed", "mm/s", ("table_speed",)),
    "screw_current": ("current", "A", ("screw_current", "screw_motor_current", "current")),
    "nut_current": ("current", "A", ("nut_current", "hollow_motor_current")),
    "screw_torque": ("torque", "N m", ("screw_torque", "screw_motor_torque", "torque")),
    "motor_current": ("current", "A", ("motor_current",)),
    "drive_force": ("force", "N", ("drive_force",)),
}
#: a residual rms above this multiple of the data's own noise level: a poor fit
MAX_RESIDUAL_RATIO = 2.0
#: condition number of the scaled Jacobian above which a combination is poorly determined
MAX_CONDITION = 1e3
#: a linear 95 % half-width above this fraction of the value is not trusted: profile instead
PROFILE_ABOVE = 0.25
#: relative half-width above which a parameter is reported poorly determined
MAX_RELATIVE_HALF_WIDTH = 0.5
#: the sum of squares at a linear interval's end may rise by this factor more or less than
#: the linearisation says; beyond, the problem is nonlinear there and the interval is a
#: profile-likelihood one (Bates & Watts 1988, Ch. 6: the profile t plots)
NONLINEARITY_LIMIT = 1.5
#: relative forward-difference step of the Jacobian (the search's)
JACOBIAN_STEP = 1e-3
#: relative central-difference step of the Jacobian the intervals use, and of the Gauss–Newton
#: steps that polish the search's optimum: the forward secant over 10⁻³ is not the tangent
#: when an interval is 10⁻⁵ of the value wide (measured on the Radau calibration: the static
#: force's column 6 % off, its optimum 0.3–0.5 s.e. off the tangent's stationary point;
#: central steps of 10⁻⁴ and 10⁻⁵ agree within 0.3 %)
TANGENT_STEP = 1e-4
#: polishing stops once every Gauss–Newton step is below this fraction of its standard error
POLISH_TOLERANCE = 0.02
#: … or after this many steps
MAX_POLISH_STEPS = 3
#: the range of a signal's weight [-]: its residuals are already divided by the data's own
#: noise level, so a factor of 10⁶ either way is already extreme; 1e308 overflowed the sum of
#: squares to inf and the fit to NaN (issue 39 item 5)
WEIGHT_RANGE = (1e-6, 1e6)
#: most residual evaluations per stage (each simulates every trace)
MAX_EVALUATIONS = 100_000
#: the forward model's estimated integration error at the optimum must stay at or below this
#: fraction of every fitted signal's noise σ (issue 36 item 1)
ERROR_TO_NOISE = 0.1
#: each tightening divides every tolerance by this factor (``accuracy`` × 0.1) …
ACCURACY_STEP = 10.0
#: … at most this many times; still above: no intervals
MAX_ACCURACY_STEPS = 3
#: and the estimates may move by at most this many standard errors when the integrator is
#: ten times tighter (the error's effect on the estimates, not only on the signals)
ESTIMATE_SHIFT = 0.1
#: and the standard error of every linear interval may change by at most this fraction when
#: the integrator is ten times tighter (the error's effect on the intervals: a Jacobian
#: column of a weakly determined parameter is a difference of two runs, and where that
#: difference is of the integration error's size the covariance is the integrator's; a
#: standard error 10 % too small leaves a nominal 95 % interval covering 93 %)
STDERR_SHIFT = 0.1
#: and at the optimum the central-difference Gauss–Newton step may be at most
#: ``ESTIMATE_SHIFT`` standard errors: a larger one that the sum of squares refuses says the
#: objective is rough at the integrator's error (the located friction reversals move with θ
#: by the integrator's tolerance), and the point where the search stopped is that roughness's
#: local minimum, not the least-squares optimum (measured on an rpm-CSV and a .mat record of
#: one rig: refused steps of 0.23 and 0.39 s.e. at accuracy 1, 0.017 and 0.016 at 0.1, where
#: the two fits agree to 0.0003 s.e.).  The integrator is tightened while the refused step
#: shrinks at least this factor with each tightening; one that does not is the model's own
#: roughness (a stick–slip record's), recorded and not tightened against.
ROUGHNESS_SHRINK = 2.0
#: signals compared up to a constant per record: a position reading starts in an unknown
#: place within an encoder count (or from an arbitrary zero), a nuisance offset profiled out
#: (its mean removed from the residual; variable projection, Golub & Pereyra 1973)
OFFSET_FREE = ("table_position",)

_TORQUE_UNITS = {"N m": 1.0, "Nm": 1.0, "N·m": 1.0, "mN m": 1e-3}


class FitError(ValueError):
    """A fit was refused before it started (bad path, unusable trace, no overlap …)."""


# ------------------------------------------------------------------ experiments


@dataclass(frozen=True)
class Experiment:
    """One measured trace: sample times [s] from the start of the record (the drive at
    rest at 0), measured signals (SI) and the reference the drive followed.

    Parameters
    ----------
    source : str
        The file (or label) it came from.
    time : numpy.ndarray
        Sample times from the start of the record [s].
    signals : mapping of str to numpy.ndarray
        Measured signals by name (:data:`MEASURABLE`) [SI unit of the signal].
    reference_time : numpy.ndarray
        Uniform grid from 0 of the reference [s].
    table_speed : numpy.ndarray
        Commanded table speed on ``reference_time`` [m/s].
    nut_speed : numpy.ndarray, optional
        Commanded nut speed on ``reference_time`` [m/s].
    noise : mapping of str to float, optional
        Noise σ per signal, from the data alone [SI unit of the signal].
    input : str, optional
        ``""``: the reference drives the loops.  Otherwise the role of a measured signal that
        drives the model open-loop (:data:`feeddrive.model.replay.REPLAYS`: ``"current"``
        [A], ``"torque"`` [N m], ``"force"`` [N], ``"speed"`` [rad/s of the motor]); its
        samples are ``input_value`` on ``reference_time`` (the record's instants from 0, a
        piecewise-linear table with them as breakpoints), and ``table_speed`` is then the
        table speed the record shows on those instants (its directions and the run's speed
        scale), not a command.
    input_value : numpy.ndarray, optional
        The replayed signal on ``reference_time`` [SI unit of the role].
    """

    source: str
    time: np.ndarray
    signals: Mapping[str, np.ndarray]
    reference_time: np.ndarray  # uniform grid from 0 [s] (a replay: the record's instants)
    table_speed: np.ndarray  # [m/s] commanded table speed on reference_time
    nut_speed: np.ndarray | None = None  # [m/s]
    noise: Mapping[str, float] = field(default_factory=dict)  # σ per signal (SI)
    input: str = ""
    input_value: np.ndarray | None = None

    def __post_init__(self) -> None:
        check_experiment(self)

    def __repr__(self) -> str:
        t = np.asarray(self.time, dtype=float)
        replay = f", replaying the {self.input}" if self.input else ""
        top = float(np.max(np.abs(self.table_speed), initial=0.0))
        return (f"<feeddrive.Experiment {self.source!r}: {t.size} samples, {t[0]:g} … "
                f"{t[-1]:g} s; signals {', '.join(self.signals) or 'none'}; command up to "
                f"{1e3 * top:.4g} mm/s{replay}>")

    @property
    def duration(self) -> float:
        """Length of the record, its last sample time [s]."""
        return float(self.time[-1])

    @property
    def span(self) -> float:
        """Length of the record [s] (its first sample may come after the start)."""
        return float(self.time[-1] - self.time[0])

    def profile(self) -> Any:
        """The reference as a profile the simulator follows, or the replay that drives it.

        Returns
        -------
        SampledSpeed or Replay
            ``reference_time``, ``table_speed`` and ``nut_speed`` [SI]; with an ``input``, its
            :class:`~feeddrive.model.replay.Replay` of ``input_value``.
        """
        return experiment_profile(self.reference_time, self.table_speed, self.nut_speed,
                                  self.input, self.input_value)

    def direction(self) -> set[int]:
        """Signs of the commanded table speed during the record.

        Returns
        -------
        set of int
            +1, −1 or both.
        """
        v = self.table_speed
        out = set()
        if np.any(v > 1e-12):
            out.add(1)
        if np.any(v < -1e-12):
            out.add(-1)
        return out


#: SI unit of a measurable signal's dimension (:data:`MEASURABLE`), for messages
SI_UNITS = {"length": "m", "speed": "m/s", "current": "A", "torque": "N m", "force": "N"}


def _samples(field: str, value: object, unit: str, source: str | None,
             size: int | None = None, of: str = "") -> np.ndarray:
    """``value`` as a 1-D float array of finite samples (``size`` of them when given), or a
    :class:`ParameterError` naming ``field``, the first bad index and the unit."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(field, value, f"expected an array of numbers [{unit}]",
                             source=source) from None
    if a.ndim != 1:
        raise ParameterError(field, MISSING, f"expected a 1-D array [{unit}]; its shape is "
                             f"{a.shape}", source=source)
    if size is not None and a.size != size:
        raise ParameterError(field, MISSING, f"expected {size} samples, one per {of} "
                             f"[{unit}]; it has {a.size}", source=source)
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        i = int(bad[0])
        more = f" (and {bad.size - 1} more)" if bad.size > 1 else ""
        raise ParameterError(field, float(a[i]), f"expected finite samples [{unit}]; index "
                             f"{i} of {a.size} is not{more}", source=source)
    return a


def check_experiment(e: Experiment) -> None:
    """Refuse an :class:`Experiment` whose arrays a fit cannot use: a signal that is not
    :data:`MEASURABLE`, arrays of another length than their times, non-finite samples
    (named with their first index: a NaN reached the fit as a zero Jacobian column), fewer
    than 2 sample times or times that do not increase.  Run when one is made and again when
    :func:`fit_drive` takes it (an array changed in place since).

    Parameters
    ----------
    e : Experiment
        The record.

    Raises
    ------
    ParameterError
        Naming the field (``signals.<name>``, ``time``, …), the value and the unit.
    """
    if not isinstance(e.source, str):
        raise ParameterError("source", e.source, "expected the record's label, a str")
    src = e.source or None
    t = _samples("time", e.time, "s", src)
    if t.size < 2:
        raise ParameterError("time", MISSING, f"expected at least 2 sample times [s]; it has "
                             f"{t.size}", source=src)
    down = np.flatnonzero(np.diff(t) <= 0.0)
    if down.size:
        i = int(down[0]) + 1
        raise ParameterError("time", float(t[i]), f"expected strictly increasing times [s]; "
                             f"index {i} follows {float(t[i - 1])!r}", source=src)
    if not isinstance(e.signals, Mapping):
        raise ParameterError("signals", e.signals, "expected a mapping of signal name to "
                             "samples (e.g. {'table_position': x})", source=src)
    for name, values in e.signals.items():
        if name not in MEASURABLE:
            from ..parameters.validation import did_you_mean

            raise ParameterError(f"signals.{name}", MISSING, "expected a measurable signal, "
                                 f"one of {', '.join(MEASURABLE)}"
                                 f"{did_you_mean(name, MEASURABLE)}", source=src)
        _samples(f"signals.{name}", values, SI_UNITS[MEASURABLE[name][0]], src, t.size,
                 "sample time")
    ref = _samples("reference_time", e.reference_time, "s", src)
    _samples("table_speed", e.table_speed, "m/s", src, ref.size, "reference time")
    if e.nut_speed is not None:
        _samples("nut_speed", e.nut_speed, "m/s", src, ref.size, "reference time")
    if e.input_value is not None:
        _samples("input_value", e.input_value, "SI unit of the replayed input", src)


def experiment_profile(reference_time: np.ndarray, table_speed: np.ndarray,
                       nut_speed: np.ndarray | None, input: str = "",
                       input_value: np.ndarray | None = None) -> Any:
    """The profile an experiment is simulated with (:meth:`Experiment.profile`; the fit's
    workers call it with the task's arrays).

    Parameters
    ----------
    reference_time : numpy.ndarray
        Sample instants from 0 [s].
    table_speed : numpy.ndarray
        Commanded table speed (a replay: the record's table speed) [m/s].
    nut_speed : numpy.ndarray or None
        Commanded nut speed [m/s].
    input : str, default ""
        The replayed role (:class:`Experiment`); "" for none.
    input_value : numpy.ndarray or None, default None
        The replayed signal [SI unit of the role].

    Returns
    -------
    SampledSpeed or Replay
        The profile.
    """
    from ..model.reference import SampledSpeed
    from ..model.replay import REPLAYS

    if input:
        return REPLAYS[input](time=np.asarray(reference_time, dtype=float),
                              value=np.asarray(input_value, dtype=float),
                              speed_scale=float(np.max(np.abs(table_speed), initial=0.0)))
    return SampledSpeed(time=np.asarray(reference_time, dtype=float),
                        table_speed=np.asarray(table_speed, dtype=float),
                        nut_speed=None if nut_speed is None else np.asarray(nut_speed, float))


def check_replay(topology: Any, experiment: Experiment) -> None:
    """Refuse, before any simulation, a replayed input the drive cannot take or a record
    that also fits the input it replays.

    Parameters
    ----------
    topology : Mechanism
        The drive's topology.
    experiment : Experiment
        A record with an ``input``.

    Raises
    ------
    FitError
        One line naming the input and the drive.
    """
    from ..model.replay import REPLAYS

    role, src = experiment.input, experiment.source
    if role not in REPLAYS:
        raise FitError(f"--input {role!r}: expected one of {', '.join(REPLAYS)}")
    if experiment.input_value is None or \
            np.shape(experiment.input_value) != np.shape(experiment.reference_time):
        raise FitError(f"{src}: --input {role}: no samples of the replayed {role} on the "
                       "record's instants")
    try:
        state, axis = REPLAYS[role].imposed(topology)
    except ParameterError as err:
        raise FitError(f"{src}: {err}") from None
    replayed = {state, f"{axis}_current"} if role != "speed" else {state}
    both = sorted(replayed & set(experiment.signals))
    if both:
        raise FitError(f"{src}: --input {role} drives {state}; it cannot also be a fitted "
                       f"signal ({both[0]})")


def _uniform_reference(t: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The command on a uniform grid from 0 (the record's median step)."""
    dt = float(np.median(np.diff(t)))
    n = int(math.floor(t[-1] / dt + 1e-9)) + 1
    grid = np.arange(n + 1) * dt
    vv = np.interp(grid, t, v, left=v[0], right=v[-1])
    return grid, vv


#: ``--input`` of a CSV trace → (dimension, default unit, the columns looked for)
INPUT_COLUMNS: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "current": ("current", "A", ("motor_current", "screw_current", "current")),
    "torque": ("torque", "N m", ("motor_torque", "screw_torque", "torque")),
    "force": ("force", "N", ("motor_force", "force")),
    "speed": ("rotary_speed", "rad/s", ("motor_speed", "screw_speed")),
}
_ROTARY_SPEED_UNITS = {"rad/s": 1.0, "rpm": 2.0 * math.pi / 60.0,
                       "rev/min": 2.0 * math.pi / 60.0}


def _replayed_column(table: Any, src: str, input: str) -> np.ndarray:
    """The ``--input`` column of a CSV trace in SI (:data:`INPUT_COLUMNS`)."""
    dim, default, aliases = INPUT_COLUMNS[input]
    col = next((a for a in aliases if table.has(a)), None)
    if col is None:
        raise FitError(f"{src}: --input {input}: no column for it (looked for "
                       f"{', '.join(aliases)}; columns: {', '.join(table.names)})"
                       f"{table.header_hint()}")
    if dim in ("current", "force"):
        return np.asarray(table.quantity([col], dim, unit=None, default_unit=default)[0])
    i = table.find(col)
    unit = table.units[i] if i is not None and table.units[i] else default
    units = _TORQUE_UNITS if dim == "torque" else _ROTARY_SPEED_UNITS
    if unit not in units:
        raise FitError(f"{src}: column {col!r}: unit {unit!r}; expected one of "
                       f"{', '.join(units)}")
    values = table.numbers(col) * units[unit]
    if dim == "torque":
        table.check_magnitude(i or 0, values, "torque", unit, units[unit])
    return np.asarray(values, dtype=float)


def read_experiment(path: str | Path, *, signals: Sequence[str] | None = None,
                    command_speed: float | None = None,
                    profile: tuple[np.ndarray, np.ndarray] | None = None,
                    torque_constant: float | None = None,
                    record_start: float = 0.0, input: str | None = None,
                    speed_ratio: float = 1.0, sep: str | None = None, decimal: str = ".",
                    time_unit: str | None = None) -> Experiment:
    """Read one trace file (docs/measured-data.md rules; ``simulate --output X.csv`` files).

    ``signals``: the measured signals to fit (:data:`MEASURABLE` names); default every one
    found among table position and motor current/torque.  The reference: ``profile`` (time
    [s], table speed [m/s], on the record's clock), else ``command_speed`` [m/s] (constant,
    after a 0.1-s ramp as ``simulate`` does), else the file's command column.  The record's
    first sample is taken as t = 0 with the drive at rest, or, with ``record_start`` [s]
    (``command_speed`` only), as that long after the start from rest (a record of steady
    sliding).  ``torque_constant`` [N m/A] turns a measured torque into the screw current
    the model has.

    Parameters
    ----------
    path : str or Path
        The trace file.
    signals : sequence of str, optional
        The signals to fit.
    command_speed : float, optional
        Constant commanded table speed [m/s].
    profile : tuple of (numpy.ndarray, numpy.ndarray), optional
        (time [s], table speed [m/s]) of the reference.
    torque_constant : float, optional
        K_t [N m/A], to turn a measured torque into current.
    record_start : float, default 0.0
        Time of the first sample after the start from rest [s].
    input : str, optional
        An open-loop replay (:class:`Experiment`): the column of this role
        (:data:`INPUT_COLUMNS`; current [A], torque [N m], force [N], motor speed [rad/s or
        rpm]) drives the model on the record's own instants; no reference is then read, and
        the default fitted signals are the table position and speed and the drive force.
    speed_ratio : float, default 1.0
        Table travel per motor radian [m/rad], for the speed scale of a motor-speed replay
        of a trace without a table position or speed.
    sep : str, optional
        Column separator; detected from the header when omitted (``read_csv_table``).
    decimal : str, default "."
        Decimal mark (``","`` for a European locale).
    time_unit : str, optional
        The time column's unit (``"s"``, ``"ms"``, …), overriding the default [s]; one that
        contradicts the header's bracketed unit is refused.

    Returns
    -------
    Experiment
        The trace in SI.

    Raises
    ------
    FitError
        For a trace that cannot be fitted (no signal, no reference, bad cells).
    ValueError
        For a gap in the record (the rule of ``analyze``:
        :func:`~feeddrive.analysis.trace_input.resample_size`), naming its line.
    """
    from ..io.measured import COMMAND_COLUMNS, check_increasing, read_csv_table
    from .trace_input import resample_size

    table = read_csv_table(path, sep=sep, decimal=decimal)
    src = table.source
    if len(table) < 16:
        raise FitError(f"{src}: {len(table)} data rows; a trace needs at least 16")
    time_col = next((c for c in ("time",) if table.has(c)), None)
    if time_col is None:
        raise table._missing(["time"])
    t_raw, _, _ = table.quantity(["time"], "time", unit=time_unit, default_unit="s")
    check_increasing(table, t_raw, "time")
    if time_unit is None and table.units[table.find("time") or 0] is None and \
            unit_steps(t_raw):  # not guessed: said, and the unit asked for
        raise ParameterError("time", MISSING, f"expected sample times in seconds [s] (the "
                             f"header gives no unit, nor --time-unit): {t_raw.size} samples, "
                             f"{t_raw[0]:.6g} … {t_raw[-1]:.6g}; {MS_TIME_HINT}: give its "
                             "unit, --time-unit ms or a header 'time [ms]' (--time-unit s for "
                             "a 1-s step)", source=src)
    # a gap (one row at 1e6 s after a 2-s record) would make the reference grid huge:
    # refused as `analyze` refuses it, naming the line, before any work (issue 39 item 3)
    resample_size(t_raw, float(np.median(np.diff(t_raw))), lines=table.lines, source=src)
    t0 = float(t_raw[0])
    if not (math.isfinite(record_start) and record_start >= 0):
        raise FitError(f"--record-start {record_start!r}: expected a time ≥ 0 [s]")
    if record_start > 0 and command_speed is None:
        raise FitError(f"--record-start {record_start:g}: needs --command-speed (the reference "
                       "before the record is otherwise unknown)")
    t = t_raw - t0 + record_start
    if input is not None:
        if input not in INPUT_COLUMNS:
            raise FitError(f"--input {input!r}: expected one of {', '.join(INPUT_COLUMNS)}")
        if command_speed is not None or profile is not None or record_start > 0:
            raise FitError(f"--input {input}: the loops are bypassed and no reference drives "
                           "the model; not with --command-speed, --profile or --record-start")
    wanted = list(signals) if signals else (
        ["table_position", "table_speed", "drive_force"] if input is not None else
        ["table_position", "screw_current", "screw_torque", "motor_current"])
    for name in wanted:
        if name not in MEASURABLE:
            raise FitError(f"--signal {name!r}: not a measurable signal; expected one of "
                           f"{', '.join(MEASURABLE)}")
    measured: dict[str, np.ndarray] = {}
    for name in wanted:
        dim, default, aliases = MEASURABLE[name]
        col = next((a for a in aliases if table.has(a)), None)
        if col is None:
            if signals:
                raise FitError(f"{src}: no column for signal {name!r} (looked for "
                               f"{', '.join(aliases)}; columns: {', '.join(table.names)})"
                               f"{table.header_hint()}")
            continue
        if dim == "torque":
            i = table.find(col)
            unit = table.units[i] if i is not None and table.units[i] else default
            if unit not in _TORQUE_UNITS:
                raise FitError(f"{src}: column {col!r}: unit {unit!r} is not a torque unit; "
                               f"expected one of {', '.join(_TORQUE_UNITS)}")
            if not torque_constant:
                raise FitError(f"{src}: column {col!r}: a torque needs the motor torque "
                               "constant to compare with the model's current")
            torque = table.numbers(col) * _TORQUE_UNITS[unit]
            table.check_magnitude(table.find(col) or 0, torque, "torque", unit,
                                  _TORQUE_UNITS[unit])
            values = torque / torque_constant
            name = "screw_current"
        else:
            values, _, _ = table.quantity([col], dim, unit=None, default_unit=default)
        if float(np.ptp(values)) == 0.0:
            if signals:
                raise FitError(f"{src}: signal {name!r} (column {col!r}) is constant: no "
                               "usable information")
            continue
        measured[name] = values
    if not measured:
        raise FitError(f"{src}: no usable measured signal (looked for "
                       f"{', '.join(wanted)}; columns: {', '.join(table.names)})"
                       f"{table.header_hint()}")
    if input is not None:
        value = _replayed_column(table, src, input)
        if "table_speed" in measured:
            speed = measured["table_speed"]
        elif "table_position" in measured:
            speed = np.gradient(measured["table_position"], t)
        else:
            speed = value * speed_ratio if input == "speed" else np.zeros_like(t)
        return Experiment(source=src, time=t, signals=measured, reference_time=t,
                          table_speed=speed, noise={k: noise_level(v)
                                                    for k, v in measured.items()},
                          input=input, input_value=value)
    nut = None
    if profile is not None:
        pt, pv = (np.asarray(a, dtype=float) for a in profile)
        if pt.size < 2 or pt[0] > t_raw[0] + 1e-9 or pt[-1] < t_raw[-1] - 1e-9:
            raise FitError(f"{src}: times {t_raw[0]:g} … {t_raw[-1]:g} s are not covered by "
                           f"the profile's {pt[0]:g} … {pt[-1]:g} s (non-overlapping times)")
        ref_t, ref_v = _uniform_reference(t, np.interp(t_raw, pt, pv))
    elif command_speed is not None:
        ref_t = np.arange(int(math.ceil(t[-1] / 1e-3)) + 2) * 1e-3
        ref_v = float(command_speed) * np.clip(ref_t / 0.1, 0.0, 1.0)
    else:
        col = next((c for c in COMMAND_COLUMNS if table.has(c)), None)
        if col is None:
            raise FitError(f"{src}: no command column ({', '.join(COMMAND_COLUMNS)}): give the "
                           "reference (--command-speed or --profile)")
        cmd, _, _ = table.quantity([col], "speed", unit=None, default_unit="mm/s")
        ref_t, ref_v = _uniform_reference(t, cmd)
        if table.has("nut_speed_reference"):
            ncmd, _, _ = table.quantity(["nut_speed_reference"], "speed", unit=None,
                                        default_unit="mm/s")
            if np.any(ncmd != 0):
                nut = np.interp(ref_t, t, ncmd)
    if not np.any(ref_v != 0.0):
        raise FitError(f"{src}: the command speed is zero throughout: nothing to fit")
    return Experiment(source=src, time=t, signals=measured, reference_time=ref_t,
                      table_speed=ref_v, nut_speed=nut,
                      noise={k: noise_level(v) for k, v in measured.items()})


# ------------------------------------------------------------------ parameters


def _field_meta(params: DriveParameters, path: str,
                option: str = "--free") -> tuple[float, dict[str, Any]]:
    """(current value, metadata) of a numeric parameter ``path``; one-line refusals naming
    ``option``."""
    obj: Any = params
    parts = path.split(".")
    for k, part in enumerate(parts):
        names = {f.name: f for f in dataclasses.fields(obj)} if dataclasses.is_dataclass(obj) \
            else {}
        sections = dict(getattr(obj, "sections", ()) if k == 0 else ())
        if part in sections and k < len(parts) - 1:  # a part's section of the composition
            obj = sections[part]
            continue
        if part in sections or (part in names and dataclasses.is_dataclass(
                getattr(obj, part)) and k == len(parts) - 1):
            # a section named alone ("screw": it said "'screw' is not a field … (did you
            # mean 'screw'?)": an outside check, 2026-12-07)
            raise FitError(f"{option} {path}: a section of the parameter set, not a numeric "
                           f"parameter; expected a path into it ({path}.<field>; `feeddrive "
                           "params show` prints them)")
        if part not in names:
            from ..parameters.validation import did_you_mean

            where = ".".join(parts[:k]) or "the parameter set"
            raise FitError(f"{option} {path}: unknown parameter ({part!r} is not a field of "
                           f"{where}){did_you_mean(part, [*names, *sections])}")
        f = names[part]
        obj = getattr(obj, part)
        if k == len(parts) - 1:
            if obj is None or dataclasses.is_dataclass(obj) or isinstance(obj, bool) or \
                    not isinstance(obj, int | float) or "unit" not in f.metadata:
                raise FitError(f"{option} {path}: not a numeric parameter")
            return float(obj), dict(f.metadata)
        if obj is None:
            raise FitError(f"{option} {path}: {'.'.join(parts[:k + 1])} is not set in this "
                           "parameter set")
    raise FitError(f"{option} {path}: not a numeric parameter")


def free_parameter_bounds(params: DriveParameters, path: str) -> tuple[float, float]:
    """The declared plausible range [SI] of parameter ``path``.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    path : str
        The parameter's dotted path.

    Returns
    -------
    tuple of (float, float)
        (low, high) [SI unit of the parameter].

    Raises
    ------
    FitError
        For a path that is not a numeric parameter of the set.
    """
    _, meta = _field_meta(params, path)
    return float(meta["low"]), float(meta["high"])


def _no_effect(params: DriveParameters, drive: str, path: str,
               experiments: Sequence[Experiment]) -> str | None:
    """Why ``path`` cannot change the simulated traces, or None (checked before any run)."""
    from ..model.mechanisms import drive_names, mechanism

    head = path.split(".")
    directions = set().union(*(e.direction() for e in experiments)) if experiments else set()
    # the topology as the fit builds it (nut locked); what it declares decides
    topology = mechanism(drive)(params, drive, 0.4, "locked")
    nut_driven = topology.follows("nut") and any(
        e.nut_speed is not None and np.any(e.nut_speed != 0) for e in experiments)
    if head[0] not in topology.own_sections:  # a section of another topology's parts
        owner = next((m for m in map(mechanism, drive_names()) if head[0] in m.own_sections),
                     None)
        if owner is not None:
            return f"{type(topology).drive_label(drive)} has no {owner.part_name}"
    held, why = topology.held_parameters()
    if any(path == p or path.startswith(p + ".") for p in held):
        return why
    if head[0] in ("controller", "hollow_controller") and experiments and \
            all(e.input for e in experiments):
        return "every record is an open-loop replay (--input): the loops are bypassed"
    if len(head) >= 4 and head[0] == "friction" and head[2] in ("positive", "negative"):
        sign = 1 if head[2] == "positive" else -1
        if directions and sign not in directions and not (nut_driven and head[1] != "guide"):
            return (f"every trace moves the table in the "
                    f"{'positive' if -sign > 0 else 'negative'} direction only")
    if head[:2] == ["controller", "compensation"] and head[-1] != "mode" and \
            params.controller.compensation.mode == "none":
        return "friction compensation is off (controller.compensation.mode = none)"
    if path == "disturbances.load_start" and params.disturbances.load_force == 0:
        return "there is no load force (disturbances.load_force = 0)"
    if path.endswith("_limit"):
        return None
    if path == "stiffness.equivalent_stiffness" and params.stiffness.equivalent_stiffness == 0:
        return "0 means the chain stiffness of Eqs. (2)–(5) is used; free the parts instead"
    return None


# ------------------------------------------------------------------ evaluation (workers)


#: the most bytes of residual vectors a fit keeps for points it may ask for again
RESIDUAL_CACHE_BYTES = 256 * 2 ** 20


#: the parameter sets whose task text this process wrote (:meth:`_Evaluator._tasks`), by
#: that text: a task run here takes the set itself instead of reading the text back
#: (``loads(dumps(p)) == p``, :func:`~feeddrive.parameters.dumps`; the read was ≈ 1/10 of a
#: serial fit's time, once per parameter point); a worker process reads the text
_WRITTEN_HERE = Kept(8)


def _parameters_of(text: str) -> DriveParameters:
    """The parameter set of a task's TOML text: the set itself where this process wrote the
    text (:data:`_WRITTEN_HERE`), else read once per text in a process: the experiments of
    one parameter point carry the same text (a parameter set is immutable, so one object
    serves them all)."""
    written = _WRITTEN_HERE.get(text)
    return written if written is not None else _read_parameters(text)


@functools.lru_cache(maxsize=8)
def _read_parameters(text: str) -> DriveParameters:
    from ..parameters import loads

    return loads(text)


def _options_for(exp_dt: float) -> dict[str, float]:
    return {"output_interval": min(1e-3, exp_dt)}


#: the source of a fit run's output interval (:func:`_record_step`)
RECORD_STEP_SOURCE = "fit (the record's sample step)"


def _record_step(base: Any, interval: float) -> Any:
    """``base`` with the output interval ``interval`` [s] and every sample a step end, the
    interval named as the fit's: it holds even where it equals the default and the set's
    ``[solver]`` table gives another (a default-valued setting is the table's to set)."""
    from dataclasses import replace

    origin = {**dict(base.origin), "output_interval": RECORD_STEP_SOURCE}
    return replace(base, output_interval=interval, sample_steps=True,
                   origin=tuple(sorted(origin.items())))


def simulate_experiment(task: Mapping[str, Any]) -> dict[str, Any]:
    """Simulate one experiment at one parameter point and return the fitted signals on the
    measured times (SI).  Module-level and picklable: every executor runs it.  ``task``:
    ``parameters`` (TOML text), ``drive``, ``table_position`` [m], ``reference_time``,
    ``table_speed``, ``nut_speed``, ``input`` and ``input_value`` (a replay,
    :class:`Experiment`), ``time``, ``signals`` (names), ``solver`` (the fit's
    integrator settings, :meth:`feeddrive.SolverOptions.record`) and ``solver_origin`` (their
    sources, :meth:`~feeddrive.SolverOptions.from_record`).

    Parameters
    ----------
    task : mapping
        The task.

    Returns
    -------
    dict
        ``{"signals": {name: values on the measured times}}`` [SI unit of each signal], or
        ``{"error": message}`` when the simulation failed.
    """

    from ..engine.options import SolverOptions, current
    from ..engine.simulate import DriveSystem, SimulationError, simulate

    # the integrator settings of the fit (its --accuracy, its tightened tolerances), carried
    # to the worker with where each came from
    base = (SolverOptions.from_record(task["solver"], task.get("solver_origin"))
            if "solver" in task else current())
    try:
        params = _parameters_of(task["parameters"])
        system = DriveSystem(params, drive=task["drive"], table_position=task["table_position"])
        prof = experiment_profile(task["reference_time"], task["table_speed"],
                                  task["nut_speed"], task.get("input", ""),
                                  task.get("input_value"))
        t = np.asarray(task["time"])
        estimate = bool(task.get("error_estimate", False))
        try:
            # every sample a step end: the residual moves smoothly with the parameters; the
            # output interval is the record's, given as the fit's (a [solver] table's does not
            # replace it, feeddrive.engine.simulate.run_options)
            opts = _record_step(base, task["output_interval"])
            result = simulate(system, prof, float(t[-1]) + opts.output_interval, options=opts,
                              error_estimate=estimate)
        except ParameterError:
            result = simulate(system, prof, float(t[-1]) + 1e-3,
                              options=_record_step(base, 1e-3), error_estimate=estimate)
        out = {}
        for name in task["signals"]:
            out[name] = np.interp(t, result.time, result[name])
        if estimate:
            signals = result.solver_stats["error_estimate"]["signals"]
            return {"signals": out,
                    "errors": {name: float(signals[name]["absolute"])
                               for name in task["signals"]}}
        return {"signals": out}
    except ParameterError as err:
        if err.field == "error_estimate":  # the settings leave no run ten times tighter
            return {"error": err.message}
        return {"error": f"{type(err).__name__}: {err}"}
    except (SimulationError, ValueError, ArithmeticError) as err:
        return {"error": f"{type(err).__name__}: {err}"}


class _Evaluator:
    """Residuals at parameter points, each experiment one task; batches go to an executor
    (or run here), so a Jacobian's columns are simulated in parallel."""

    def __init__(self, base: DriveParameters, drive: str, table_position: float,
                 paths: Sequence[str], start: np.ndarray, experiments: Sequence[Experiment],
                 weights: Mapping[str, float], pool: cf.Executor | None,
                 progress: Callable[[str], None] | None, label: str = "",
                 ctrl_c: Any = None) -> None:
        self.label = label
        self.ctrl_c = ctrl_c  # sweep.executors.CtrlC: nothing handed out after a Ctrl-C
        self.base, self.drive, self.position = base, drive, table_position
        self.paths, self.start = list(paths), start
        self.experiments = list(experiments)
        self.weights = weights
        self.pool = pool
        self.progress = progress
        self.scale = []
        self.evaluations = 0
        self.best: tuple[float, np.ndarray] | None = None
        self.best_residual: np.ndarray | None = None
        for e in self.experiments:
            for name in e.signals:
                self.scale.append(weights.get(name, 1.0) / e.noise[name])
        self.n_residuals = sum(e.time.size * len(e.signals) for e in self.experiments)
        self._cache: dict[bytes, np.ndarray] = {}
        # the residual vectors kept: up to 256, within RESIDUAL_CACHE_BYTES (a long record's
        # vector is megabytes), and never fewer than a tangent's points
        self.cache_kept = max(2 * len(self.paths) + 2,
                              min(256, RESIDUAL_CACHE_BYTES // (8 * max(1, self.n_residuals))))

    def parameters(self, theta: np.ndarray) -> DriveParameters:
        p = self.base
        for path, s, v0 in zip(self.paths, theta, self.start, strict=True):
            p = p.replace_path(path, float(s * v0))
        return p

    def _tasks(self, theta: np.ndarray) -> list[dict[str, Any]] | None:
        from ..engine.options import current

        try:
            params = self.parameters(theta)
            text = dumps(params)
        except ParameterError:
            return None
        if not params.solver:  # a [solver] table reads back with its source as the set's
            _WRITTEN_HERE.put(text, params)
        options = current()
        solver, origin = options.record(), [list(pair) for pair in options.origin]
        return [{"parameters": text, "drive": self.drive, "table_position": self.position,
                 "reference_time": e.reference_time, "table_speed": e.table_speed,
                 "nut_speed": e.nut_speed, "input": e.input, "input_value": e.input_value,
                 "time": e.time, "signals": list(e.signals),
                 "output_interval": _options_for(float(np.median(np.diff(e.time))))[
                     "output_interval"], "solver": solver, "solver_origin": origin}
                for e in self.experiments]

    def _residual(self, outs: list[dict[str, Any]] | None) -> np.ndarray:
        if outs is None or any("error" in o for o in outs):
            return np.full(self.n_residuals, 1e6)
        parts = []
        k = 0
        for e, o in zip(self.experiments, outs, strict=True):
            for name, meas in e.signals.items():
                diff = o["signals"][name] - meas
                if name in OFFSET_FREE:  # the count the table starts in is not known
                    diff = diff - diff.mean()
                parts.append(diff * self.scale[k])
                k += 1
        r = np.concatenate(parts)
        return r if np.all(np.isfinite(r)) else np.full(self.n_residuals, 1e6)

    def batch(self, thetas: Sequence[np.ndarray]) -> list[np.ndarray]:
        """Residual vectors at each of ``thetas`` (cached)."""
        keys = [np.asarray(th, dtype=float).tobytes() for th in thetas]
        todo = [(k, th) for k, th in zip(keys, thetas, strict=True) if k not in self._cache]
        todo = list({k: th for k, th in todo}.items())
        tasks = [(k, self._tasks(np.asarray(th, dtype=float))) for k, th in todo]
        flat = [(k, i, t) for k, ts in tasks if ts is not None for i, t in enumerate(ts)]
        if self.ctrl_c is not None and flat:
            self.ctrl_c.check()  # nothing new is simulated after a Ctrl-C
        if self.pool is not None and len(flat) > 1:
            futures = [self.pool.submit(simulate_experiment, t) for _, _, t in flat]
            try:
                results = [f.result() for f in futures]
            except BaseException:  # Ctrl-C: what has not started never starts
                for f in futures:
                    f.cancel()
                raise
        else:
            results = [simulate_experiment(t) for _, _, t in flat]
        by_key: dict[bytes, list[dict[str, Any]]] = {}
        for (k, _, _), res in zip(flat, results, strict=True):
            by_key.setdefault(k, []).append(res)
        for (k, ts), (_, th) in zip(tasks, todo, strict=True):
            r = self._residual(by_key.get(k) if ts is not None else None)
            self._cache[k] = r
            self.evaluations += 1
            cost = 0.5 * float(r @ r)
            if self.best is None or cost < self.best[0]:
                self.best = (cost, np.asarray(th, dtype=float).copy())
                self.best_residual = r
        if len(self._cache) > self.cache_kept:
            for k in list(self._cache)[:len(self._cache) // 2]:
                self._cache.pop(k)
        return [self._cache[k] if k in self._cache else self.batch([th])[0]
                for k, th in zip(keys, thetas, strict=True)]

    def fresh(self, label: str) -> _Evaluator:
        """The same problem with nothing cached (for other integrator settings)."""
        return _Evaluator(self.base, self.drive, self.position, self.paths, self.start,
                          self.experiments, self.weights, self.pool, self.progress,
                          label=label, ctrl_c=self.ctrl_c)

    def integration_errors(self, theta: np.ndarray) -> list[dict[str, float]] | str:
        """Per experiment, the estimated global integration error of each fitted signal at
        ``theta`` under the options in force [SI] (``simulate(error_estimate=True)``: a
        second run ten times tighter), or why it could not be estimated."""
        tasks = self._tasks(np.asarray(theta, dtype=float))
        if tasks is None:
            return "the parameter set at the optimum is refused"
        tasks = [{**t, "error_estimate": True} for t in tasks]
        if self.ctrl_c is not None:
            self.ctrl_c.check()
        if self.pool is not None and len(tasks) > 1:
            outs = list(self.pool.map(simulate_experiment, tasks))
        else:
            outs = [simulate_experiment(t) for t in tasks]
        for o in outs:
            if "error" in o:
                return str(o["error"])
        return [dict(o["errors"]) for o in outs]

    def remember(self, theta: np.ndarray, residual: np.ndarray | None) -> None:
        """Keep a residual vector already computed at ``theta`` (the best point's), so that
        reading it again simulates nothing."""
        if residual is not None:
            self._cache[np.asarray(theta, dtype=float).tobytes()] = residual

    def residual(self, theta: np.ndarray) -> np.ndarray:
        r = self.batch([theta])[0]
        if self.progress is not None and self.best is not None:
            self.progress(f"{self.label}: evaluation {self.evaluations}: cost "
                          f"{0.5 * float(r @ r):.6g} (best {self.best[0]:.6g})")
        return r

    def jacobian(self, theta: np.ndarray, lb: np.ndarray | None = None,
                 ub: np.ndarray | None = None) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        steps = JACOBIAN_STEP * np.maximum(np.abs(theta), 1e-3)
        if ub is not None:
            steps = np.where(theta + steps > ub, -steps, steps)
        points = [theta]
        for j in range(theta.size):
            p = theta.copy()
            p[j] += steps[j]
            points.append(p)
        rs = self.batch(points)
        return np.column_stack([(rs[j + 1] - rs[0]) / steps[j] for j in range(theta.size)])

    def records(self) -> list[list[slice]]:
        """Per experiment, the slices of its signals in a residual vector (the HAC's
        records)."""
        out: list[list[slice]] = []
        offset = 0
        for e in self.experiments:
            out.append([])
            for _ in e.signals:
                out[-1].append(slice(offset, offset + e.time.size))
                offset += e.time.size
        return out

    def tangent(self, theta: np.ndarray, lb: np.ndarray, ub: np.ndarray) -> np.ndarray:
        """The Jacobian by central differences of :data:`TANGENT_STEP` (one-sided where a
        bound is within reach) [residual per θ]."""
        theta = np.asarray(theta, dtype=float)
        steps = TANGENT_STEP * np.maximum(np.abs(theta), 1e-3)
        points = [theta]
        for j in range(theta.size):
            for sign in (1.0, -1.0):
                p = theta.copy()
                p[j] += sign * steps[j]
                points.append(p)
        rs = self.batch(points)
        cols = []
        for j in range(theta.size):
            up, down = theta[j] + steps[j] <= ub[j], theta[j] - steps[j] >= lb[j]
            if up and down:
                cols.append((rs[2 * j + 1] - rs[2 * j + 2]) / (2.0 * steps[j]))
            elif up:
                cols.append((rs[2 * j + 1] - rs[0]) / steps[j])
            else:
                cols.append((rs[0] - rs[2 * j + 2]) / steps[j])
        return np.column_stack(cols)


# ------------------------------------------------------------------ results


@dataclass(frozen=True)
class ParameterEstimate:
    """One fitted parameter [SI]: value, standard error, interval, how it was found.

    Parameters
    ----------
    path : str
        The parameter's dotted path.
    unit : str
        Its unit.
    start : float
        Its start value [unit].
    value : float
        Its estimate [unit].
    stderr : float
        Standard error [unit].
    low : float
        Lower end of the confidence interval [unit].
    high : float
        Upper end [unit].
    interval : str
        ``"linear"`` (from the covariance) or ``"profile"`` (profile likelihood).
    determined : bool
        Whether the data determine it.
    issue : str, optional
        Why it is not determined, if so.
    stderr_white : float, default nan
        The standard error white residuals would give, s²(JᵀJ)⁻¹ [unit]; ``stderr`` is the
        HAC one (:mod:`~feeddrive.analysis.fit_residuals`).
    linearity : tuple of float, default (nan, nan)
        At the linear interval's lower and upper end (the others at their conditional
        optimum of the linearised model), the actual rise of the sum of squares over the
        rise the linearisation predicts [-]: 1 where the problem is linear over the interval;
        outside 1/``NONLINEARITY_LIMIT`` … ``NONLINEARITY_LIMIT`` (1.5) the interval is a
        profile-likelihood one.
    """

    path: str
    unit: str
    start: float
    value: float
    stderr: float
    low: float
    high: float
    interval: str  # "linear", "profile", "none" or "withheld"
    determined: bool
    issue: str | None = None
    stderr_white: float = math.nan
    linearity: tuple[float, float] = (math.nan, math.nan)

    @property
    def relative_half_width(self) -> float:
        """Half the interval's width over |value| [-]; inf when unbounded."""
        if self.value == 0 or not (math.isfinite(self.low) and math.isfinite(self.high)):
            return math.inf
        return 0.5 * (self.high - self.low) / abs(self.value)

    def to_dict(self) -> dict[str, Any]:
        """The estimate for the JSON report.

        Returns
        -------
        dict
            The fields, non-finite numbers as None, and the relative half-width.
        """
        def fin(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None

        return {"path": self.path, "unit": self.unit, "start": self.start, "value": self.value,
                "stderr": fin(self.stderr), "stderr_white_noise": fin(self.stderr_white),
                "ci_low": fin(self.low), "ci_high": fin(self.high),
                "interval": self.interval, "relative_half_width": fin(self.relative_half_width),
                "linearity": [fin(x) for x in self.linearity],
                "determined": self.determined, "issue": self.issue}


@dataclass(frozen=True)
class SignalResidual:
    """The residual of one fitted signal of one trace against the data's own noise.

    Parameters
    ----------
    source : str
        The trace.
    signal : str
        The signal.
    samples : int
        Samples compared.
    rms : float
        Residual rms [SI unit of the signal].
    noise : float
        Noise σ of the data, from the data alone [SI unit of the signal].
    ratio : float
        rms / noise [-]; about 1 for a model that explains the data.
    diagnostics : ResidualDiagnostics, optional
        Autocorrelation, runs test and spectral peak of the residual.
    integration_error : float, default nan
        Estimated global integration error of the simulated signal at the optimum, at the
        accuracy the intervals were computed with [SI unit of the signal].
    """

    source: str
    signal: str
    samples: int
    rms: float  # [SI]
    noise: float  # [SI], from the data alone
    ratio: float
    diagnostics: ResidualDiagnostics | None = None
    integration_error: float = math.nan

    def to_dict(self) -> dict[str, Any]:
        """The residual for the JSON report.

        Returns
        -------
        dict
            The fields (the diagnostics as a table, a missing error estimate as None).
        """
        return {"source": self.source, "signal": self.signal, "samples": self.samples,
                "rms": self.rms, "noise": self.noise, "ratio": self.ratio,
                "diagnostics": None if self.diagnostics is None
                else self.diagnostics.to_dict(),
                "integration_error": (self.integration_error
                                      if math.isfinite(self.integration_error) else None)}


@dataclass(frozen=True)
class IntegrationCheck:
    """How the fit chose its integrator accuracy: the forward model's estimated integration
    error at the optimum against ``ERROR_TO_NOISE`` × each fitted signal's noise, the
    estimates' shift and the standard errors' change with the integrator ten times tighter
    against ``ESTIMATE_SHIFT`` and ``STDERR_SHIFT``.

    Parameters
    ----------
    met : bool
        Whether every signal's error ended at or below the limit.
    accuracy : float
        The ``accuracy`` factor of the final settings [-].
    rtol : float or None
        Their explicit relative tolerance (None: the default × ``accuracy``) [-].
    steps : int
        Tightenings made (each ×1/``ACCURACY_STEP``: the explicit tolerances divided,
        ``accuracy`` for the defaults, :func:`~feeddrive.engine.error_estimate.tightened`).
    history : tuple of dict
        Per attempt: ``integrator`` (:func:`_settings_entry`: the label and the explicit
        tolerances), ``accuracy``, ``rtol``, ``worst_ratio`` (error / noise, the largest),
        ``signals`` (source, signal, error [SI], noise [SI], ratio) and, once the signals
        pass, ``estimate_shift_stderr`` (:func:`_estimate_shift`) and, once that passes,
        ``stderr_shift`` (:func:`_stderr_shift`) with ``stderr_shift_at`` (the parameter
        and its two standard errors; empty: no credible linear interval to compare), and,
        once that passes, ``gauss_newton_step_stderr`` (:func:`_stationarity`), with
        ``gauss_newton_step_refused`` where the sum of squares refused it and ``roughness``
        ("the model's") where it did not shrink with the integrator.
    reason : str, optional
        Why the limit was not reached.
    integrator : dict, optional
        The final settings (:func:`_settings_entry`): ``label`` (the tolerances in words,
        :meth:`~feeddrive.SolverOptions.tolerances_label`: ``"rtol 1e-7, accuracy 0.1"``)
        and the explicit tolerances [SI] (None: the default × ``accuracy``).
    """

    met: bool
    accuracy: float
    rtol: float | None
    steps: int
    history: tuple[dict[str, Any], ...]
    reason: str | None = None
    integrator: dict[str, Any] = field(default_factory=dict)

    @property
    def label(self) -> str:
        """The final settings' tolerances in words (``"accuracy 0.01"``, ``"rtol 1e-8,
        accuracy 0.01"``), as the progress and the summary print them."""
        return str(self.integrator.get("label") or f"accuracy {self.accuracy:g}")

    def to_dict(self) -> dict[str, Any]:
        """The check for JSON.

        Returns
        -------
        dict
            The fields, with the limit.
        """
        return {"met": self.met, "limit_fraction_of_noise": ERROR_TO_NOISE,
                "limit_estimate_shift_stderr": ESTIMATE_SHIFT,
                "limit_stderr_shift": STDERR_SHIFT,
                "accuracy": self.accuracy, "rtol": self.rtol, "steps": self.steps,
                "integrator": dict(self.integrator) or None,
                "history": list(self.history), "reason": self.reason}


@dataclass(frozen=True)
class FitResult:
    """What :func:`fit_drive` found; :meth:`to_dict` is the CLI's JSON.

    Parameters
    ----------
    parameters : DriveParameters
        The base set with the fitted values.
    base_name : str
        The base set's name.
    drive : str
        The drive.
    table_position : float
        Table position [m].
    sources : tuple of str
        The traces.
    estimates : tuple of ParameterEstimate
        One per free parameter.
    covariance : numpy.ndarray
        Covariance of the free parameters [SI, per pair].
    correlation : numpy.ndarray
        Their correlation matrix [-].
    condition_number : float
        Condition number of the scaled Jacobian [-].
    singular_values : numpy.ndarray
        Its singular values [-].
    poorly_determined : tuple of dict
        The parameter combinations the data barely determine.
    residuals : tuple of SignalResidual
        One per trace and signal.
    residual_ok : bool
        Whether every residual is near the data's noise.
    cost : float
        Final weighted sum of squares [-].
    dof : int
        Degrees of freedom.
    evaluations : int
        Simulations run.
    confidence : float
        Confidence level of the intervals [-].
    interrupted : bool, default False
        Stopped by Ctrl-C (best point so far, no intervals).
    message : str, default ""
        The optimiser's message.
    simulated : tuple of dict, default ()
        The simulated signals per trace, at the estimate.
    experiments : tuple of Experiment, default ()
        The traces fitted.
    integration : IntegrationCheck, optional
        The integrator accuracy chosen against the noise (None: not checked).
    hac : HacCovariance, optional
        How the covariance was made (HAC bandwidths and their stability).
    inadequate : str, optional
        "model inadequate" and the residual's structure, when the residual is not noise.
    """

    parameters: DriveParameters
    base_name: str
    drive: str
    table_position: float
    sources: tuple[str, ...]
    estimates: tuple[ParameterEstimate, ...]
    covariance: np.ndarray  # SI, of the free parameters
    correlation: np.ndarray
    condition_number: float
    singular_values: np.ndarray
    poorly_determined: tuple[dict[str, Any], ...]
    residuals: tuple[SignalResidual, ...]
    residual_ok: bool
    cost: float
    dof: int
    evaluations: int
    confidence: float
    interrupted: bool = False
    message: str = ""
    simulated: tuple[dict[str, np.ndarray], ...] = ()
    experiments: tuple[Experiment, ...] = ()
    integration: IntegrationCheck | None = None
    hac: HacCovariance | None = None
    inadequate: str | None = None

    def __repr__(self) -> str:
        # what a notebook prints: one line of what was fitted, one per estimate, never the
        # arrays (it printed 3552 characters, down to the residual autocorrelations)
        state = ("interrupted" if self.interrupted else "residual check " +
                 ("passed" if self.residual_ok else "failed"))
        if self.inadequate:
            state += ", model inadequate"
        head = (f"<feeddrive.FitResult {self.drive} of {self.base_name!r}, "
                f"{len(self.sources)} trace{'s' if len(self.sources) != 1 else ''}, "
                f"{self.evaluations} evaluations, {state}")
        rows = []
        for e in self.estimates:
            spread = f" ± {e.stderr:.2g}" if math.isfinite(e.stderr) else ""
            note = "" if e.determined else " (poorly determined)"
            rows.append(f"  {e.path} = {e.value:.6g}{spread} {e.unit}{note}")
        return "\n".join([head, *rows, "  .estimates .residuals, .to_dict()>"])

    @property
    def paths(self) -> list[str]:
        """The free parameters' dotted paths, in estimate order."""
        return [e.path for e in self.estimates]

    def to_dict(self) -> dict[str, Any]:
        """The result for the JSON report (``feeddrive fit --json``).

        Returns
        -------
        dict
            Set, drive, position [mm], data, estimates, correlation, condition number, poorly
            determined combinations, residuals, cost and counts.
        """
        corr = np.where(np.isfinite(self.correlation), self.correlation, 0.0)
        return {"parameter_set": self.base_name, "drive": self.drive,
                "table_position_mm": self.table_position * 1e3, "data": list(self.sources),
                "estimates": [e.to_dict() for e in self.estimates],
                "correlation": corr.tolist(),
                "condition_number": (float(self.condition_number)
                                     if math.isfinite(self.condition_number) else None),
                "poorly_determined_combinations": list(self.poorly_determined),
                "residuals": [r.to_dict() for r in self.residuals],
                "residual_check": ("passed" if self.residual_ok else
                                   f"failed: a residual rms exceeds {MAX_RESIDUAL_RATIO:g}× "
                                   "the data's noise; no parameter is reported determined"),
                "cost": self.cost, "dof": self.dof, "evaluations": self.evaluations,
                "confidence": self.confidence, "interrupted": self.interrupted,
                "message": self.message,
                "integration_check": (None if self.integration is None
                                      else self.integration.to_dict()),
                "covariance_method": None if self.hac is None else self.hac.to_dict(),
                "model_inadequate": self.inadequate}

    def fitted_toml(self, extends: str, data_names: Sequence[str] | None = None) -> str:
        """A parameter file that ``extends`` the base set with the fitted values, and a
        ``[fit]`` table recording data, free parameters, estimates, intervals, covariance
        (the loader ignores ``[fit]``; ``feeddrive predict`` reads it).

        Parameters
        ----------
        extends : str
            What the file extends: a preset name or the base file's path.
        data_names : sequence of str, optional
            The data files as recorded; the sources by default.

        Returns
        -------
        str
            The TOML text.
        """
        lines = ["# feeddrive fit: fitted parameter set (docs/fitting.md). SI units.",
                 f"extends = {toml_string(extends)}",
                 f"name = {toml_string(self.base_name + '-fitted')}"]
        groups: dict[str, list[ParameterEstimate]] = {}
        for e in self.estimates:
            table, _, key = e.path.rpartition(".")
            groups.setdefault(table, []).append(e)
        for table, ests in groups.items():
            if table:
                lines.append(f"\n[{table}]")
            for e in ests:
                ci = (f"{100 * self.confidence:.0f} % CI {e.low:.6g} … {e.high:.6g} "
                      f"({e.interval})" if math.isfinite(e.low) and math.isfinite(e.high)
                      else "interval not determined")
                note = "" if e.determined else f"; POORLY DETERMINED: {e.issue}"
                key = e.path.rpartition(".")[2]
                lines.append(f"{key} = {e.value!r}  # [{e.unit}] {toml_comment(ci + note)}")
        names = list(data_names or self.sources)
        lines += ["\n[fit]",
                  f"data = [{', '.join(toml_string(s) for s in names)}]",
                  f"drive = {toml_string(self.drive)}",
                  f"table_position = {self.table_position!r}  # [m]",
                  f"free = [{', '.join(toml_string(p) for p in self.paths)}]",
                  f"estimates = [{', '.join(repr(e.value) for e in self.estimates)}]",
                  f"ci_low = [{', '.join(repr(_toml_float(e.low)) for e in self.estimates)}]",
                  f"ci_high = [{', '.join(repr(_toml_float(e.high)) for e in self.estimates)}]",
                  f"interval = [{', '.join(toml_string(e.interval) for e in self.estimates)}]",
                  f"determined = [{', '.join('true' if e.determined else 'false' for e in self.estimates)}]",  # noqa: E501
                  f"confidence = {self.confidence!r}",
                  "covariance = [" + ", ".join(
                      "[" + ", ".join(repr(_toml_float(v)) for v in row) + "]"
                      for row in self.covariance) + "]",
                  f"residual_check = {'true' if self.residual_ok else 'false'}",
                  f"interrupted = {'true' if self.interrupted else 'false'}"]
        if self.integration is not None:
            lines.append(f"accuracy = {self.integration.accuracy!r}  # the integrator's "
                         f"({toml_comment(self.integration.label)}), "
                         f"error ≤ {ERROR_TO_NOISE:g} × noise: "
                         f"{'met' if self.integration.met else 'NOT met'}")
        if self.inadequate:
            lines.append(f"model_inadequate = {toml_string(self.inadequate)}")
        return "\n".join(lines) + "\n"


def _toml_float(x: float) -> float:
    """TOML has inf but the record is read back by numpy: keep a huge finite stand-in."""
    return float(x) if math.isfinite(x) else 1e300


# ------------------------------------------------------------------ the fit

#: the first stage of the horizon continuation [s], and the factor between stages
FIRST_HORIZON = 0.5
HORIZON_FACTOR = 3.0


def horizons(duration: float) -> list[float]:
    """Record lengths [s] the search is run on in turn: 0.5 s, ×3 each stage, then all of
    it.  A stick-slip or lightly damped record drifts in phase as a parameter changes, so
    its misfit over a long record is a narrow valley among local minima; over its first
    half second (the start-up transient) it is nearly quadratic.  Each stage starts from
    the last one's optimum, inside the next one's valley (measured: from factors 1.2, 0.8,
    1.1 off, a fit on the full 10-s records ends in a local minimum with σ2 5× too large;
    the continuation reaches the truth within the noise).

    Parameters
    ----------
    duration : float
        The longest record [s].

    Returns
    -------
    list of float
        The stage lengths [s], the last one ``duration``.
    """
    out = []
    h = FIRST_HORIZON
    while h < duration:
        out.append(h)
        h *= HORIZON_FACTOR
    out.append(duration)
    return out


#: the hint of a refusal for a time vector whose steps are exactly 1: those of milliseconds
MS_TIME_HINT = "steps of exactly 1 are those of a time in milliseconds"


def unit_steps(time: np.ndarray) -> bool:
    """Whether a time vector's median step is exactly 1: read in seconds, a 1-Hz record; in
    milliseconds, the 1-kHz record of a drive (:data:`MS_TIME_HINT`).

    Parameters
    ----------
    time : numpy.ndarray
        Sample times as recorded [its unit].

    Returns
    -------
    bool
        True for a median step of exactly 1.
    """
    return time.size >= 2 and float(np.median(np.diff(time))) == 1.0


def _check_first_stage(e: Experiment, first: float) -> None:
    """Refuse a record with fewer than 2 samples in the fit's first stage (its first
    ``first`` seconds, :func:`horizons`): the stage's cut record was refused as "expected at
    least 2 sample times [s]; it has 1" for a record of 2001 samples whose time, in ms, was
    read as seconds (an outside check, 2026-12-07)."""
    if e.span <= first:
        return  # the first stage takes it whole
    n = int(np.count_nonzero(e.time <= float(e.time[0]) + first + 1e-12))
    if n >= 2:
        return
    step = float(np.median(np.diff(e.time)))
    hint = (f"; {MS_TIME_HINT}: give its unit (--map time=VARIABLE[ms], --time-unit ms, or "
            "a CSV header 'time [ms]')" if unit_steps(e.time) else "")
    raise ParameterError("time", MISSING, f"expected at least 2 samples in the fit's first "
                         f"stage, the record's first {first:g} s [s]; it has {n} of its "
                         f"{e.time.size} samples (median step {step:.6g} s){hint}",
                         source=e.source or None)


def _cut(e: Experiment, h: float) -> Experiment:
    end = float(e.time[0]) + h
    m = e.time <= end + 1e-12
    keep = e.reference_time <= end + 2 * float(np.median(np.diff(e.reference_time)))
    return dataclasses.replace(e, time=e.time[m], signals={k: v[m] for k, v in
                                                           e.signals.items()},
                               reference_time=e.reference_time[keep],
                               table_speed=e.table_speed[keep],
                               nut_speed=None if e.nut_speed is None else e.nut_speed[keep],
                               input_value=None if e.input_value is None
                               else e.input_value[keep])


def _linearity(ev: _Evaluator, theta: np.ndarray, white: np.ndarray, cov: np.ndarray,
               ssr: float, tq: float, wanted: bool) -> list[tuple[float, float]]:
    """Per parameter, at each end θ_j ± t·se_j of its linear interval with the others at
    their conditional optimum in the linearised model (θ + δ·W[:, j]/W[j, j], W ∝ (JᵀJ)⁻¹),
    the actual rise of the sum of squares over the predicted δ²·s²/W[j, j]: one batch of 2p
    simulations.  NaN where not computed (no intervals wanted, an infinite s.e., an end
    outside the bounds: profiled anyway)."""
    p = theta.size
    out = [(math.nan, math.nan)] * p
    if not wanted:
        return out
    s2 = ssr / max(ev.n_residuals - p, 1)
    points, where = [], []
    for j in range(p):
        if not (math.isfinite(cov[j, j]) and math.isfinite(white[j, j]) and cov[j, j] > 0
                and white[j, j] > 0):
            continue
        delta = tq * math.sqrt(cov[j, j])
        for sign in (-1.0, 1.0):
            points.append(theta + sign * delta * white[:, j] / white[j, j])
            where.append((j, sign, delta * delta * s2 / white[j, j]))
    if not points:
        return out
    rs = ev.batch(points)
    ratios: dict[int, list[float]] = {}
    for (j, _, predicted), r in zip(where, rs, strict=True):
        ratios.setdefault(j, []).append((float(r @ r) - ssr) / predicted)
    for j, (lo, hi) in ratios.items():
        out[j] = (lo, hi)
    return out


def _profile(ev: _Evaluator, theta: np.ndarray, j: int, lb: np.ndarray, ub: np.ndarray,
             ssr: float, threshold: float, se: float, say: Callable[[str], None]
             ) -> tuple[float, float]:
    """Profile-likelihood interval of parameter ``j`` (in θ units): walk out on each side,
    refitting the others, until SSR crosses ``threshold`` or a bound is reached."""
    others = [k for k in range(theta.size) if k != j]

    def refit(value: float, start: np.ndarray) -> tuple[float, np.ndarray]:
        if not others:
            th = theta.copy()
            th[j] = value
            r = ev.batch([th])[0]
            return float(r @ r), th

        def fun(sub: np.ndarray) -> np.ndarray:
            th = theta.copy()
            th[others] = sub
            th[j] = value
            return ev.batch([th])[0]

        def jac(sub: np.ndarray) -> np.ndarray:
            th = theta.copy()
            th[others] = sub
            th[j] = value
            return ev.jacobian(th)[:, others]

        from scipy.optimize import least_squares  # (imported where used: see the module's)

        res = least_squares(fun, start[others], jac=jac, bounds=(lb[others], ub[others]),
                            x_scale=np.maximum(np.abs(start[others]), 1e-3), max_nfev=20,
                            xtol=1e-6, ftol=1e-8)
        th = theta.copy()
        th[others] = res.x
        th[j] = value
        return 2.0 * float(res.cost), th

    ends = []
    refused = 1e11 * ev.n_residuals  # the residual of a refused set is 1e6 per sample
    step = max(se, 0.02 * abs(theta[j]), 1e-6) if math.isfinite(se) else 0.1 * abs(theta[j])
    for sign in (-1.0, 1.0):
        prev_v, prev_s = theta[j], ssr
        start = theta.copy()
        found = math.inf * sign
        v = theta[j]
        for k in range(12):
            v = theta[j] + sign * step * (1.6 ** k)
            bound = lb[j] if sign < 0 else ub[j]
            if (sign < 0 and v <= bound) or (sign > 0 and v >= bound):
                v = bound
            say(f"profile {ev.paths[j]}: {'lower' if sign < 0 else 'upper'} side, point {k + 1}")
            s, start_v = refit(v, start)
            if s >= refused:
                # the set's own checks refuse this value (F_s below F_c, …): not a rise of
                # the likelihood; bisect for the last admissible value, the end if the
                # profile is still below the threshold there
                good_v, good_s, bad_v = prev_v, prev_s, v
                for _ in range(8):
                    mid = 0.5 * (good_v + bad_v)
                    s_mid, start_mid = refit(mid, start)
                    if s_mid >= refused:
                        bad_v = mid
                        continue
                    if s_mid > threshold:
                        found = float(np.interp(threshold, [good_s, s_mid], [good_v, mid]))
                        break
                    good_v, good_s, start = mid, s_mid, start_mid
                else:
                    found = good_v
                break
            start = start_v
            if s > threshold:
                found = float(np.interp(threshold, [prev_s, s], [prev_v, v]))
                break
            prev_v, prev_s = v, s
            if v == bound:
                found = bound if sign < 0 and bound > 0 else (-math.inf if sign < 0 else
                                                               math.inf)
                if sign < 0 and bound <= 0:
                    found = max(bound, 0.0)
                break
        ends.append(found)
    return ends[0], ends[1]


def _same_record(a: Experiment, b: Experiment) -> bool:
    """Whether two experiments hold the same samples: times and every measured signal."""
    if not isinstance(a, Experiment) or not isinstance(b, Experiment):
        return False
    return (np.array_equal(a.time, b.time) and a.signals.keys() == b.signals.keys()
            and all(np.array_equal(a.signals[k], b.signals[k]) for k in a.signals))


#: why a fit takes each record once (:func:`_refuse_repeated_records`)
ONCE_IN_A_FIT = ("each record counts once in a fit (twice, its residuals would weigh double "
                 "and its intervals shrink by √2)")


def _refuse_repeated_records(experiments: Sequence[Experiment],
                             why: str = ONCE_IN_A_FIT) -> None:
    """Refuse one record given twice (the same file twice on the command line), in one line
    naming it and saying ``why``: in a fit its residuals counted twice and its standard
    errors came out 1/√2 of its own, without a word (a bad-input sweep, session 29);
    ``validate`` scored it twice (session 30)."""
    seen: list[Experiment] = []
    for e in experiments:
        twin = next((s for s in seen if _same_record(s, e)), None)
        if twin is not None:
            same = "given twice" if twin.source == e.source else f"the same record as {twin.source}"
            raise FitError(f"{e.source}: {same}; {why}")
        seen.append(e)


def fit_drive(base: DriveParameters, experiments: Sequence[Experiment], free: Sequence[str],
              *, drive: str = "cdfs", table_position: float = 0.4,
              weights: Mapping[str, float] | None = None,
              bounds: Mapping[str, tuple[float, float]] | None = None,
              confidence: float = 0.95, max_evaluations: int = 200,
              profile: bool = True, horizon_continuation: bool = True,
              accuracy_check: bool = True, workers: int | None = None,
              dask_workers: int | None = None, scheduler: str | None = None,
              progress: Callable[[str], None] | None = None) -> FitResult:
    """Least-squares fit of the ``free`` parameters (dotted paths) of ``base`` to every
    experiment at once (see the module).  ``weights`` multiply a signal's residuals (by
    signal name); ``bounds`` replace a parameter's declared range [SI].  Jacobian columns
    are simulated through a local process pool (``workers`` > 1) or Dask (``dask_workers``
    or ``scheduler``); by default here, one after the other.  ``horizon_continuation``:
    the search runs on the first ``horizons`` seconds of every record, each stage
    starting from the last (see docs/fitting.md); the intervals are always from the whole
    records.  Ctrl-C stops the search and
    returns the best point so far (``interrupted``; no intervals).  Everything is checked
    before the first simulation: a :class:`FitError` names the problem.

    Parameters
    ----------
    base : DriveParameters
        The set whose ``free`` parameters are fitted.
    experiments : sequence of Experiment
        The measured traces, fitted at once.
    free : sequence of str
        Dotted paths of the parameters to fit.
    drive : str, default "cdfs"
        The drive.
    table_position : float, default 0.4
        Table position [m].
    weights : mapping of str to float, optional
        Factor on each signal's residuals, by signal name [-].
    bounds : mapping of str to (float, float), optional
        Ranges replacing the declared ones [SI unit of the parameter].
    confidence : float, default 0.95
        Confidence level of the intervals [-].
    max_evaluations : int, default 200
        Most simulations of the search.
    profile : bool, default True
        Profile-likelihood intervals where the linear ones are unreliable.
    horizon_continuation : bool, default True
        Run the search on growing record lengths (``horizons``).
    accuracy_check : bool, default True
        At the optimum, estimate the forward model's integration error per fitted signal
        and tighten the integrator (every tolerance ÷ 10: an explicit one from the command
        line, a ``[solver]`` table or the API divided, ``accuracy`` × 0.1 for the defaults;
        at most ``MAX_ACCURACY_STEPS`` times, refitting each time) until it is at most
        ``ERROR_TO_NOISE`` × the signal's noise; no intervals when that is not reached.
    workers : int, optional
        Local worker processes for the Jacobian columns.
    dask_workers : int, optional
        Workers of a local Dask cluster.
    scheduler : str, optional
        Address of a Dask scheduler.
    progress : callable, optional
        Told in one line what is being done.

    Returns
    -------
    FitResult
        Estimates, intervals, covariance and residuals.

    Raises
    ------
    FitError
        For a problem found before the first simulation.

    References
    ----------
    .. [1] M. A. Branch, T. F. Coleman, Y. Li, "A subspace, interior, and conjugate gradient
       method for large-scale bound-constrained minimization problems", SIAM J. Sci.
       Comput. 21 (1999) 1–23 (the trust-region reflective method of
       ``scipy.optimize.least_squares``).
    .. [2] D. M. Bates, D. G. Watts, Nonlinear Regression Analysis and Its Applications,
       Wiley, 1988 (linear and profile intervals).
    """
    from ..engine.simulate import DriveSystem

    say = progress or (lambda _t: None)
    if not isinstance(base, DriveParameters):  # a preset's name said "'controller' is not a
        # field of the parameter set" (an outside check, 2026-12-07)
        raise ParameterError("base", base, 'expected DriveParameters, e.g. '
                             'fd.preset("wang2021") or fd.load("my.toml")')
    profile = check_flag("profile", profile)
    horizon_continuation = check_flag("horizon_continuation", horizon_continuation)
    accuracy_check = check_flag("accuracy_check", accuracy_check)
    if isinstance(experiments, Experiment):
        raise ParameterError("experiments", experiments, "expected a list of Experiment, "
                             "e.g. [experiment]")
    if not experiments:
        raise FitError("no trace given")
    _refuse_repeated_records(experiments)
    if isinstance(free, str):  # one path given as text: its letters were read as paths
        raise FitError(f"free = {free[:60]!r}: expected a list of parameter paths, e.g. "
                       f"[{free[:60]!r}] (--free on the command line)")
    if not free:
        raise FitError("--free: give at least one parameter path to fit")
    if len(set(free)) != len(free):
        raise FitError(f"--free: {sorted({p for p in free if list(free).count(p) > 1})[0]} "
                       "given twice")
    weights = dict(weights or {})
    for name, w in weights.items():
        if name not in MEASURABLE:
            raise FitError(f"--weight {name}: not a measurable signal; expected one of "
                           f"{', '.join(MEASURABLE)}")
        if not (math.isfinite(w) and WEIGHT_RANGE[0] <= w <= WEIGHT_RANGE[1]):
            raise FitError(f"--weight {name}={w!r}: expected a weight in "
                           f"[{WEIGHT_RANGE[0]:g}, {WEIGHT_RANGE[1]:g}]")
    if not (0 < confidence < 1):
        raise FitError(f"confidence = {confidence!r}: expected a fraction in (0, 1)")
    if isinstance(max_evaluations, bool) or not isinstance(max_evaluations, int) or \
            not 1 <= max_evaluations <= MAX_EVALUATIONS:
        raise FitError(f"--max-evaluations {max_evaluations!r}: expected a whole number in "
                       f"[1, {MAX_EVALUATIONS}]")
    from ..sweep.executors import check_executor

    check_executor(workers=workers, scheduler=scheduler, dask_workers=dask_workers)
    for k, e in enumerate(experiments):
        if not isinstance(e, Experiment):
            raise ParameterError(f"experiments[{k}]", e, "expected an Experiment "
                                 "(read_experiment, synthetic_experiment)")
        check_experiment(e)  # again: an array may have been changed in place since
    if bounds is not None and not isinstance(bounds, Mapping):
        raise ParameterError("bounds", bounds, "expected a mapping of free parameter path to "
                             "a (low, high) pair in the parameter's unit")
    for path in bounds or {}:
        if path not in free:
            raise ParameterError(f"bounds.{path}", MISSING, "expected the path of a free "
                                 f"parameter, one of {', '.join(free)}")
    start = np.empty(len(free))
    lb = np.empty(len(free))
    ub = np.empty(len(free))
    units_ = []
    from ..parameters.validation import path_unit_label

    for i, path in enumerate(free):
        value, meta = _field_meta(base, path)
        unit = path_unit_label(base, path)  # the label params show prints (issue 41 item 3)
        reason = _no_effect(base, drive, path, experiments)
        if reason:
            raise FitError(f"--free {path}: has no effect on these traces ({reason})")
        if value == 0.0:
            raise FitError(f"--free {path}: starts at 0 [{unit}]; give a nonzero "
                           "start value in the parameter file (the fit works in factors on "
                           "the start)")
        lo, hi = (_bounds_pair(path, bounds[path], unit) if bounds and path in bounds
                  else (meta["low"], meta["high"]))
        if not lo < value < hi and not (lo <= value <= hi):
            raise FitError(f"--free {path}: start {value:g} outside its bounds {lo:g} … "
                           f"{hi:g} [{unit}]")
        start[i] = value
        lo_t, hi_t = lo / value, hi / value
        lb[i], ub[i] = min(lo_t, hi_t), max(lo_t, hi_t)
        if not meta.get("low_inclusive", False):
            lb[i] = lb[i] * (1 + 1e-9) if lb[i] > 0 else lb[i] + 1e-12
        units_.append(unit)
    system = DriveSystem(base, drive=drive, table_position=table_position)  # validates both
    for e in experiments:
        if e.nut_speed is not None and not system.topology().follows("nut"):
            raise FitError(f"{e.source}: commands a nut speed; only the DDFS drives its nut")
        if e.input:
            check_replay(system.topology(), e)
    for k, e in enumerate(experiments):
        _check_fitted_signals(k, e)
    theta0 = np.ones(len(free))

    longest = max(e.span for e in experiments)
    stages = horizons(longest) if horizon_continuation else [longest]
    for e in experiments:
        _check_first_stage(e, stages[0])

    def run(pool: cf.Executor | None, ctrl_c: Any = None) -> FitResult:
        theta = theta0
        interrupted = False
        message = ""
        evaluations = 0
        t0 = _time.perf_counter()
        ev = None
        done: tuple[_Evaluator, list[Experiment], float] | None = None  # last stage run
        for k, h in enumerate(stages, start=1):
            stage = [e if e.span <= h else _cut(e, h) for e in experiments]
            ev = _Evaluator(base, drive, table_position, free, start, stage, weights, pool,
                            say, label=f"stage {k}/{len(stages)} (first {h:g} s)",
                            ctrl_c=ctrl_c)
            from scipy.optimize import least_squares  # (imported where used)

            try:
                res = least_squares(ev.residual, theta, jac=lambda th, ev=ev: ev.jacobian(
                                        th, lb, ub),
                                    bounds=(lb, ub), x_scale=np.ones(len(free)), method="trf",
                                    max_nfev=max_evaluations, xtol=1e-8, ftol=1e-10,
                                    gtol=1e-10)
                theta = np.clip(res.x, lb, ub)
                message = str(res.message)
            except KeyboardInterrupt:
                interrupted = True  # (_summarise counts the reported stage's evaluations)
                if ev.best is None:  # nothing evaluated in this stage: the last one's best
                    if done is None:
                        raise
                    ev, stage, h = done
                    evaluations -= ev.evaluations  # counted when that stage ended
                assert ev.best is not None
                theta = ev.best[1]
                ev.remember(theta, ev.best_residual)
                message = (f"interrupted (Ctrl-C) in stage {k} of {len(stages)}: the best "
                           f"point so far, its residuals over the first {h:g} s")
                reported = stage
                break
            done = (ev, stage, h)
            evaluations += ev.evaluations
        assert ev is not None
        # after a Ctrl-C nothing more is simulated: the stage's own best point and residuals
        final = ev if interrupted or stages[-1] >= longest else _Evaluator(
            base, drive, table_position, free, start, experiments, weights, pool, say,
            label="final")
        if not interrupted:
            reported = list(experiments)
        say(f"search done: {evaluations} evaluations in {_time.perf_counter() - t0:.1f} s")
        from ..engine.options import current, using

        try:
            check = None
            settings = current()
            if accuracy_check and not interrupted:
                theta, final, settings, check, more = _settle_accuracy(
                    final, theta, lb, ub, max_evaluations, say, confidence)
                evaluations += more
            with using(settings):
                tangent = None
                if not interrupted:
                    theta, tangent = _polish(final, theta, lb, ub, say)
                return _summarise(final, theta, start, lb, ub, units_, reported, base, drive,
                                  table_position, confidence, interrupted, message, profile,
                                  say, evaluations, check, tangent)
        except KeyboardInterrupt:  # during the intervals: the estimates without them
            if final.best is not None and final.best_residual is not None:
                theta = final.best[1]  # evaluated already: nothing more is simulated
                final.remember(theta, final.best_residual)
            return _summarise(final, theta, start, lb, ub, units_, reported, base, drive,
                              table_position, confidence, True,
                              "interrupted (Ctrl-C) while computing the intervals",
                              profile, say, evaluations)

    from ..sweep.executors import CtrlC, executor

    if workers is None and dask_workers is None and scheduler is None:
        with CtrlC() as ctrl_c:
            return run(None, ctrl_c)
    from ..sweep.quantities import warm

    warm_task = {"parameters": dumps(base), "drive": drive, "table_position": table_position,
                 "nut_speed": 0.0, "quantity": {"kind": "creep-trial", "table_speed": 1e-3,
                                                "linear": False}}
    warm(warm_task)
    try:
        with CtrlC() as ctrl_c, executor(workers=workers, scheduler=scheduler,
                                         dask_workers=dask_workers,
                                         warm_tasks=[warm_task]) as (pool, n, where):
            say(f"Jacobian columns on {where}")
            result = run(pool, ctrl_c)
            if result.interrupted:  # leave the pool by an exception: its workers are stopped
                raise _Interrupted(result)  # at once, not left to finish what was queued
            return result
    except _Interrupted as stop:
        return stop.result


def _bounds_pair(path: str, pair: object, unit: str) -> tuple[float, float]:
    """``bounds[path]`` as (low, high) [SI], or a :class:`ParameterError` naming it: a bare
    number said "cannot unpack non-iterable int" (an outside check, 2026-12-07)."""
    where = f"bounds.{path}"
    expected = f"expected a (low, high) pair, low < high [{unit}]"
    if isinstance(pair, str) or not isinstance(pair, Sequence | np.ndarray) or len(pair) != 2:
        raise ParameterError(where, pair, expected)
    lo, hi = pair[0], pair[1]
    if not (is_real(lo) and is_real(hi)) or math.isnan(lo) or math.isnan(hi) or not lo < hi:
        raise ParameterError(where, pair, expected)
    return float(lo), float(hi)


def _check_fitted_signals(k: int, e: Experiment) -> None:
    """Refuse, before any simulation, a record with nothing to fit or without the noise σ
    every fitted signal is weighted by (a missing one was ``KeyError: 'name'``; a NaN one,
    from fewer than 8 samples, a NaN fit)."""
    src = e.source or None
    if not e.signals:
        raise ParameterError(f"experiments[{k}].signals", MISSING, "expected at least one "
                             f"measured signal, one of {', '.join(MEASURABLE)}", source=src)
    for name in e.signals:
        unit = SI_UNITS[MEASURABLE[name][0]]
        where = f"experiments[{k}].noise.{name}"
        if not isinstance(e.noise, Mapping) or name not in e.noise:
            raise ParameterError(where, MISSING, f"expected the noise σ of every fitted signal "
                                 f"[{unit}] (e.g. fit_statistics.noise_level(samples))",
                                 source=src)
        sigma = e.noise[name]
        if not is_real(sigma) or not 0.0 < sigma < math.inf:
            raise ParameterError(where, sigma, f"expected a finite noise σ > 0 [{unit}] "
                                 f"(noise_level needs at least {NOISE_MIN_SAMPLES} samples)",
                                 source=src)


class _Interrupted(Exception):
    """Carries an interrupted fit's result out of its executor (which stops its workers)."""

    def __init__(self, result: FitResult) -> None:
        super().__init__("interrupted")
        self.result = result


def _hac_stderr(ev: _Evaluator, jac: np.ndarray, r: np.ndarray) -> np.ndarray:
    """The HAC standard errors of θ from the Jacobian ``jac`` and residual ``r`` (the
    records as :meth:`_Evaluator.records` splits them) [θ units]."""
    with np.errstate(all="ignore"):
        return np.sqrt(np.abs(np.diag(hac_covariance(jac, r, ev.records()).covariance)))


def _shadow(ev: _Evaluator, settings: Any) -> tuple[Any, _Evaluator] | None:
    """The settings ten times tighter and an evaluator of its own for them (shared by the
    checks of one attempt, so that a point they both evaluate is run once); None where the
    integrator cannot be tightened further."""
    from ..engine.error_estimate import tightened

    try:
        return tightened(settings, ACCURACY_STEP), ev.fresh("ten times tighter")
    except ParameterError:
        return None


def _estimate_shift(ev: _Evaluator, shadow: tuple[Any, _Evaluator] | None, theta: np.ndarray,
                    lb: np.ndarray, ub: np.ndarray, settings: Any) -> float:
    """How far the estimates move, in standard errors, when the integrator is ten times
    tighter (``shadow``, :func:`_shadow`): δθ = J⁺ (r − r_shadow), against the HAC standard
    errors; the largest over the parameters (the linearised effect of the integration error
    on the estimate)."""
    from ..engine.options import using

    with using(settings):
        r = ev.batch([theta])[0]
        jac = ev.jacobian(theta, lb, ub)
    if shadow is None:
        return math.inf
    with using(shadow[0]):
        r_shadow = shadow[1].batch([theta])[0]
    delta, *_ = np.linalg.lstsq(jac, r - r_shadow, rcond=None)
    se = _hac_stderr(ev, jac, r)
    with np.errstate(all="ignore"):
        ratio = np.where(se > 0, np.abs(delta) / se, math.inf)
    return float(np.max(ratio)) if ratio.size else 0.0


def _fraction(x: float) -> str:
    """A relative change as a percentage (``inf``: an interval's kind changes)."""
    return f"{100 * x:.3g} %" if math.isfinite(x) else "a change of interval kind"


def _stderr_shift(ev: _Evaluator, shadow: tuple[Any, _Evaluator] | None, theta: np.ndarray,
                  lb: np.ndarray, ub: np.ndarray, settings: Any, confidence: float
                  ) -> tuple[float, str]:
    """How much the linear intervals' standard errors change when the integrator is ten
    times tighter: the HAC standard errors from the tangent Jacobian (central differences,
    :meth:`_Evaluator.tangent`, the one the intervals use) at ``settings`` and at ten times
    tighter (``shadow``, :func:`_shadow`), both at ``theta``.

    A parameter counts where its linear interval is credible (as :func:`_summarise` judges:
    half-width at most ``PROFILE_ABOVE`` of the value, within the bounds) at either setting:
    its relative change |s.e./s.e.(tighter) − 1|, or inf where the interval is credible at
    one setting and not at the other (the tighter one profiles it or calls it undetermined,
    the looser one would report it).  Parameters credible at neither are profiled either way
    and do not count.

    Returns
    -------
    tuple
        (the largest change [-], the parameter it is at and both standard errors, or "").
    """
    from scipy import stats  # (imported where used: see the module's)

    from ..engine.options import using

    if shadow is None:
        return math.inf, "the integrator cannot be tightened further"
    ses, credible = [], []
    for s, evaluator in ((settings, ev), shadow):
        with using(s):
            r = evaluator.batch([theta])[0]
            jac = evaluator.tangent(theta, lb, ub)
        dof = max(r.size - theta.size, 1)
        tq = float(stats.t.ppf(0.5 + confidence / 2.0, dof))
        se = _hac_stderr(ev, jac, r)
        ses.append(se)
        credible.append(np.isfinite(se) & (tq * se <= PROFILE_ABOVE * np.abs(theta))
                        & (theta - tq * se >= lb) & (theta + tq * se <= ub))
    worst, which = 0.0, ""
    for j, path in enumerate(ev.paths):
        if not (credible[0][j] or credible[1][j]):
            continue
        with np.errstate(all="ignore"):  # (a zero standard error: an infinite change)
            change = (float(abs(ses[0][j] / ses[1][j] - 1.0))
                      if credible[0][j] and credible[1][j] else math.inf)
        change = change if math.isfinite(change) else math.inf
        if change > worst or not which:
            unit = ev.start[j]
            worst, which = change, (f"{path}: {abs(ses[0][j] * unit):.3g} against "
                                    f"{abs(ses[1][j] * unit):.3g}")
    return float(worst), which


def _gauss_newton_step(ev: _Evaluator, theta: np.ndarray, lb: np.ndarray, ub: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, float | None, np.ndarray | None]:
    """The central-difference Gauss–Newton step at ``theta`` (the tangent Jacobian,
    :meth:`_Evaluator.tangent`, the one the intervals use; cached per point).

    Returns
    -------
    tuple
        (the residual there, the tangent Jacobian, the step's largest size in HAC standard
        errors — None where it cannot be judged: a non-finite Jacobian, residual or standard
        error —, the point it leads to — None where that leaves the bounds).
    """
    r = ev.batch([theta])[0]
    jac = ev.tangent(theta, lb, ub)
    if not (np.all(np.isfinite(jac)) and np.all(np.isfinite(r))):
        return r, jac, None, None
    step = -np.linalg.lstsq(jac, r, rcond=None)[0]
    with np.errstate(all="ignore"):
        size = np.abs(step) / _hac_stderr(ev, jac, r)
    if not np.all(np.isfinite(size)):
        return r, jac, None, None
    new = theta + step
    inside = not (np.any(new < lb) or np.any(new > ub))
    return r, jac, float(np.max(size)) if size.size else 0.0, new if inside else None


def _stationarity(ev: _Evaluator, theta: np.ndarray, lb: np.ndarray, ub: np.ndarray,
                  settings: Any) -> tuple[float | None, np.ndarray | None]:
    """The Gauss–Newton step at ``theta`` (:func:`_gauss_newton_step`, its Jacobian cached
    from :func:`_stderr_shift`) in standard errors, and the point it leads to if that step is
    above ``ESTIMATE_SHIFT``, within the bounds and lowers the sum of squares (None: refused —
    the objective is rough there).

    Returns
    -------
    tuple
        (the step's size [standard errors], or None where it cannot be judged, as
        :func:`_polish` stops there; the point or None).
    """
    from ..engine.options import using

    with using(settings):
        r, _, largest, new = _gauss_newton_step(ev, theta, lb, ub)
        if largest is None or largest <= ESTIMATE_SHIFT or new is None:
            return largest, None
        r_new = ev.batch([new])[0]
    return largest, (new if float(r_new @ r_new) < float(r @ r) else None)


def _polish(ev: _Evaluator, theta: np.ndarray, lb: np.ndarray, ub: np.ndarray,
            say: Callable[[str], None]) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Newton steps with the central-difference Jacobian (:func:`_gauss_newton_step`)
    from the search's optimum, until each step is below :data:`POLISH_TOLERANCE` of its HAC
    standard error (at most :data:`MAX_POLISH_STEPS`; a step that raises the sum of squares
    or leaves the bounds is not taken).  The search's forward-difference Jacobian is a secant
    over 10⁻³ of each value; where an interval is far narrower its stationary point is not
    the least-squares optimum.  Returns the point and the tangent Jacobian there."""
    for k in range(MAX_POLISH_STEPS + 1):
        r, jac, largest, new = _gauss_newton_step(ev, theta, lb, ub)
        if k == MAX_POLISH_STEPS or largest is None or largest < POLISH_TOLERANCE or new is None:
            break
        r_new = ev.batch([new])[0]
        if float(r_new @ r_new) > float(r @ r):
            break
        say(f"polish {k + 1}: Gauss–Newton step of at most {largest:.2g} "
            "standard errors (central differences)")
        theta = new
    return theta, jac


def _settle_accuracy(ev: _Evaluator, theta: np.ndarray, lb: np.ndarray, ub: np.ndarray,
                     max_evaluations: int, say: Callable[[str], None], confidence: float
                     ) -> tuple[np.ndarray, _Evaluator, Any, IntegrationCheck, int]:
    """Numerical error below the noise (issue 36 item 1): at the optimum, the estimated
    global integration error of every fitted signal (``simulate(error_estimate=True)``,
    :mod:`feeddrive.engine.error_estimate`) against ``ERROR_TO_NOISE`` × its noise, the
    estimates' shift (:func:`_estimate_shift`) against ``ESTIMATE_SHIFT`` and the standard
    errors' change (:func:`_stderr_shift`) against ``STDERR_SHIFT``, each with the
    integrator ten times tighter, and the central-difference Gauss–Newton step there
    (:func:`_stationarity`) against ``ESTIMATE_SHIFT`` — taken where it lowers the sum of
    squares (at most ``MAX_POLISH_STEPS`` per setting), else the objective is rough at this
    integrator, and tightening goes on only while that step shrinks ``ROUGHNESS_SHRINK``× per
    tightening; while above, every tolerance ÷ ``ACCURACY_STEP``
    (:func:`~feeddrive.engine.error_estimate.tightened`: ``accuracy`` for the defaults, the
    explicit ones divided) and the search resumed from the optimum on the whole records.

    Returns
    -------
    tuple
        (θ, the evaluator at the final settings, those settings, the check, evaluations run).
    """
    from scipy.optimize import least_squares  # (imported where used: see the module's)

    from ..engine.error_estimate import tightened
    from ..engine.options import current, using

    settings = current()
    history: list[dict[str, Any]] = []
    reason: str | None = None
    evaluations = 0
    steps = 0
    moves = 0  # Gauss–Newton steps taken at one setting (:func:`_stationarity`)
    refused: float | None = None  # the last setting's refused step [standard errors]
    while True:
        with using(settings):
            errors = ev.integration_errors(theta)
        if isinstance(errors, str):
            reason = f"the integration error could not be estimated: {errors}"
            break
        rows: list[dict[str, Any]] = [
            {"source": e.source, "signal": name, "error": float(err[name]),
             "noise": float(e.noise[name]), "ratio": float(err[name] / e.noise[name])}
            for e, err in zip(ev.experiments, errors, strict=True) for name in e.signals]
        worst = max(float(r["ratio"]) for r in rows)
        # a run and its shadow that agree exactly took the same steps (every step capped by
        # the sample instants at both tolerances): their difference says nothing of the
        # error, so it is not taken as met (measured: 0 estimated at accuracy 100 where the
        # error against a run at 1e-4 was 8e-10 A)
        blind = any(r["error"] == 0.0 for r in rows)
        history.append({"integrator": _settings_entry(settings),
                        "accuracy": settings.accuracy, "rtol": settings.rtol,
                        "worst_ratio": worst, "estimable": not blind, "signals": rows})
        say(f"integration error at {settings.tolerances_label()}: up to {worst:.3g}× the "
            f"noise (limit {ERROR_TO_NOISE:g})" + ("; a signal's estimate is exactly 0 "
                                                   "(not estimable)" if blind else ""))
        shift = spread = math.nan
        which = ""
        if worst <= ERROR_TO_NOISE and not blind:
            shadow = _shadow(ev, settings)
            shift = _estimate_shift(ev, shadow, theta, lb, ub, settings)
            history[-1]["estimate_shift_stderr"] = shift
            say(f"estimates move by up to {shift:.3g} standard errors with the integrator "
                f"ten times tighter (limit {ESTIMATE_SHIFT:g})")
            if shift <= ESTIMATE_SHIFT:
                spread, which = _stderr_shift(ev, shadow, theta, lb, ub, settings,
                                              confidence)
                history[-1]["stderr_shift"] = spread
                history[-1]["stderr_shift_at"] = which
                say(f"standard errors change by up to {_fraction(spread)} with the "
                    f"integrator ten times tighter (limit {_fraction(STDERR_SHIFT)}; "
                    + (which or "no parameter has a credible linear interval to compare")
                    + ")")
                if spread <= STDERR_SHIFT:
                    rough, better = _stationarity(ev, theta, lb, ub, settings)
                    history[-1]["gauss_newton_step_stderr"] = rough
                    if rough is None or rough <= ESTIMATE_SHIFT:  # (None: not judged)
                        break
                    if better is not None and moves < MAX_POLISH_STEPS:
                        say(f"Gauss–Newton step of {rough:.3g} standard errors taken "
                            "(central differences); the checks again there")
                        theta, moves = better, moves + 1
                        continue
                    history[-1]["gauss_newton_step_refused"] = better is None
                    if better is not None:  # still lowering after MAX_POLISH_STEPS: a refit
                        say(f"still a Gauss–Newton step of {rough:.3g} standard errors after "
                            f"{moves} (limit {ESTIMATE_SHIFT:g})")
                    else:
                        say(f"a Gauss–Newton step of {rough:.3g} standard errors raises the "
                            f"sum of squares (limit {ESTIMATE_SHIFT:g}): the objective is "
                            "rough at this integrator")
                        if refused is not None and rough * ROUGHNESS_SHRINK > refused:
                            history[-1]["roughness"] = "the model's"
                            say(f"it did not shrink {ROUGHNESS_SHRINK:g}× with the integrator "
                                f"ten times tighter ({refused:.3g} before): the model's own "
                                "roughness, not the integrator's")
                            break
                        refused = rough
        if steps == MAX_ACCURACY_STEPS:
            reason = ((f"the integration error is still {worst:.3g}× the noise"
                       if worst > ERROR_TO_NOISE and not blind else
                       "the integration error is not estimable (the run and its shadow agree "
                       "exactly)" if blind else
                       f"the integration error still moves the estimates by {shift:.3g} "
                       "standard errors" if shift > ESTIMATE_SHIFT else
                       "the optimum is still not stationary: a Gauss–Newton step of "
                       f"{history[-1]['gauss_newton_step_stderr']:.3g} standard errors"
                       + (" raises the sum of squares"
                          if history[-1].get("gauss_newton_step_refused") else "")
                       if history[-1].get("gauss_newton_step_stderr") is not None
                       and history[-1]["gauss_newton_step_stderr"] > ESTIMATE_SHIFT
                       else
                       f"the integration error still changes the standard errors by "
                       f"{_fraction(spread)} ({which})") +
                      f" after {steps} tightenings ({settings.tolerances_label()}); limit "
                      f"{ERROR_TO_NOISE:g}× the noise")
            break
        try:
            settings = tightened(settings, ACCURACY_STEP)
        except ParameterError as err:
            reason = (f"the integration error is {worst:.3g}× the noise and the integrator "
                      f"cannot be tightened further ({err.message})")
            break
        if steps:  # a refit's evaluations (the last one's are counted with the intervals)
            evaluations += ev.evaluations
        steps += 1
        moves = 0
        ev = ev.fresh(f"refit at {settings.tolerances_label()}")
        with using(settings):
            res = least_squares(ev.residual, theta, jac=lambda th, ev=ev: ev.jacobian(th, lb, ub),
                                bounds=(lb, ub), x_scale=np.ones(theta.size), method="trf",
                                max_nfev=max_evaluations, xtol=1e-8, ftol=1e-10, gtol=1e-10)
        theta = np.clip(res.x, lb, ub)
    check = IntegrationCheck(met=reason is None, accuracy=settings.accuracy,
                             rtol=settings.rtol, steps=steps, history=tuple(history),
                             reason=reason, integrator=_settings_entry(settings))
    return theta, ev, settings, check, evaluations


def _settings_entry(settings: Any) -> dict[str, Any]:
    """The integrator settings of an attempt as the check records them: ``label``
    (:meth:`~feeddrive.SolverOptions.tolerances_label`), ``accuracy`` [-] and the explicit
    tolerances ``rtol`` [-], ``position_tolerance`` [m], ``speed_tolerance`` [m/s],
    ``current_tolerance`` [A] (None: the default × ``accuracy``)."""
    from ..engine.options import TOLERANCES

    return {"label": settings.tolerances_label(), "accuracy": settings.accuracy,
            **{name: getattr(settings, name) for name, _, _ in TOLERANCES}}


def _summarise(ev: _Evaluator, theta: np.ndarray, start: np.ndarray, lb: np.ndarray,
               ub: np.ndarray, units_: list[str], experiments: Sequence[Experiment],
               base: DriveParameters, drive: str, table_position: float, confidence: float,
               interrupted: bool, message: str, profile: bool,
               say: Callable[[str], None], evaluations: int = 0,
               integration: IntegrationCheck | None = None,
               tangent: np.ndarray | None = None) -> FitResult:
    r = ev.batch([theta])[0]
    ssr = float(r @ r)
    n, p = r.size, theta.size
    dof = max(n - p, 1)
    params = ev.parameters(theta)
    # residuals per signal, in SI, against the data's own noise
    residuals = []
    simulated: list[dict[str, np.ndarray]] = []
    records: list[list[slice]] = []  # per experiment, its signals' slices of r (HAC)
    k = 0
    offset = 0
    ok = True
    final_errors: dict[tuple[str, str], float] = {}
    if integration is not None and integration.history:
        final_errors = {(row["source"], row["signal"]): row["error"]
                        for row in integration.history[-1]["signals"]}
    for e in experiments:
        sims = {}
        records.append([])
        for name, meas in e.signals.items():
            m = meas.size
            raw = r[offset:offset + m] / ev.scale[k]
            sims[name] = meas + raw
            rms = float(np.sqrt(np.mean(raw ** 2)))
            ratio = rms / e.noise[name]
            ok &= ratio <= MAX_RESIDUAL_RATIO
            residuals.append(SignalResidual(
                source=e.source, signal=name, samples=m, rms=rms, noise=float(e.noise[name]),
                ratio=ratio, diagnostics=diagnose(raw, e.time),
                integration_error=final_errors.get((e.source, name), math.nan)))
            records[-1].append(slice(offset, offset + m))
            offset += m
            k += 1
        simulated.append(sims)
    inadequate = None
    if not ok:  # the structure of the worst residual, said out loud (issue 36 item 3)
        worst = max(residuals, key=lambda x: x.ratio)
        inadequate = (f"model inadequate: the {worst.signal} residual of {worst.source} "
                      f"is {worst.ratio:.3g}× the data's noise, "
                      "structured: " + (worst.diagnostics.describe() if worst.diagnostics
                                        else "no diagnostics"))
    if interrupted:
        nan = np.full((p, p), math.nan)
        partial = tuple(ParameterEstimate(path=path, unit=u, start=float(s0), value=float(th * s0),
                                       stderr=math.nan, low=math.nan, high=math.nan,
                                       interval="none", determined=False,
                                       issue="fit interrupted: no interval")
                     for path, u, s0, th in zip(ev.paths, units_, start, theta, strict=True))
        return FitResult(parameters=params, base_name=base.name, drive=drive,
                         table_position=table_position, sources=tuple(e.source for e in
                                                                      experiments),
                         estimates=partial, covariance=nan, correlation=nan,
                         condition_number=math.nan, singular_values=np.full(p, math.nan),
                         poorly_determined=(), residuals=tuple(residuals), residual_ok=ok,
                         cost=0.5 * ssr, dof=dof, evaluations=evaluations + ev.evaluations,
                         confidence=confidence, interrupted=True, message=message,
                         simulated=tuple(simulated), experiments=tuple(experiments))
    say("Jacobian at the optimum")
    jac = tangent if tangent is not None else ev.tangent(theta, lb, ub)
    zero = [ev.paths[j] for j in range(p) if not np.any(jac[:, j] != 0)]
    s2 = ssr / dof
    # in relative units (columns × θ): a scale-free condition number
    scaled = jac * np.where(theta != 0, theta, 1.0)
    _, sv, vt = np.linalg.svd(scaled, full_matrices=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf
    combos: list[dict[str, Any]] = []
    for i in range(sv.size):
        if sv[i] <= sv[0] / MAX_CONDITION or sv[i] == 0:
            vec = vt[i]
            order = np.argsort(-np.abs(vec))
            combos.append({"singular_value_ratio": float(sv[i] / sv[0]) if sv[0] > 0 else 0.0,
                           "combination": {ev.paths[j]: float(vec[j]) for j in order
                                           if abs(vec[j]) >= 0.1}})
    white_t = covariance(jac, ssr, dof)  # θ units, for independent residuals only
    # residuals of quantised closed-loop records are correlated: the HAC sandwich
    hac = hac_covariance(jac, r, records)
    cov_t = hac.covariance
    corr = correlation(cov_t)
    from scipy import stats  # (imported where used)

    tq = float(stats.t.ppf(0.5 + confidence / 2.0, dof))
    f_quantile = float(stats.f.ppf(confidence, 1, dof))
    cov = cov_t * np.outer(start, start)
    numerical = integration is not None and not integration.met
    linearity = _linearity(ev, theta, white_t, cov_t, ssr, tq, profile and ok and not numerical)
    ests: list[ParameterEstimate] = []
    for j, path in enumerate(ev.paths):
        se_t = math.sqrt(cov_t[j, j]) if math.isfinite(cov_t[j, j]) and cov_t[j, j] >= 0 \
            else math.inf
        se_w = math.sqrt(white_t[j, j]) if math.isfinite(white_t[j, j]) and \
            white_t[j, j] >= 0 else math.inf
        lo_t, hi_t = theta[j] - tq * se_t, theta[j] + tq * se_t
        how = "linear"
        nonlinear = any(not (1.0 / NONLINEARITY_LIMIT <= q <= NONLINEARITY_LIMIT)
                        for q in linearity[j] if not math.isnan(q))
        credible = (math.isfinite(se_t) and tq * se_t <= PROFILE_ABOVE * abs(theta[j])
                    and lo_t >= lb[j] and hi_t <= ub[j])
        if profile and ok and not numerical and (not credible or nonlinear):
            # the likelihood-ratio threshold scaled by the HAC-to-white variance ratio of
            # this parameter, so that the profile interval carries the residual's correlation
            # (at least the white-noise threshold)
            inflation = (se_t / se_w) ** 2 if math.isfinite(se_t) and 0 < se_w < math.inf \
                else 1.0
            threshold = ssr * (1.0 + max(inflation, 1.0) * f_quantile / dof)
            lo_p, hi_p = _profile(ev, theta, j, lb, ub, ssr, threshold, se_t, say)
            how = "profile"
            if credible:
                # sent to the profile by the linearity check alone: the profile widens the
                # linearised interval, never narrows it.  A sum of squares rising faster than
                # predicted within one standard error is, on these problems, the simulated
                # signals' non-smoothness at the integration error's scale (a 1-µm encoder
                # without other noise: profile ends 1000x inside the s.e., missing the truth)
                if lo_p >= lo_t and hi_p <= hi_t:
                    how = "linear"
                lo_t, hi_t = min(lo_p, lo_t), max(hi_p, hi_t)
            else:
                lo_t, hi_t = lo_p, hi_p
        value = float(theta[j] * start[j])
        lo, hi = sorted((lo_t * start[j], hi_t * start[j]))
        issue = None
        half = 0.5 * (hi - lo) / abs(value) if math.isfinite(hi - lo) else math.inf
        if path in zero:
            issue = "no effect on the simulated traces (zero Jacobian column)"
        elif numerical:
            assert integration is not None
            issue = f"interval withheld: {integration.reason}"
        elif not ok:
            assert inadequate is not None
            issue = f"interval withheld: {inadequate}"
        elif half > MAX_RELATIVE_HALF_WIDTH:
            issue = (f"{100 * confidence:.0f} % interval wider than "
                     f"±{100 * MAX_RELATIVE_HALF_WIDTH:.0f} % of the value")
        elif any(path in c["combination"] and abs(c["combination"][path]) >= 0.3
                 for c in combos):
            issue = "part of a poorly determined combination (see the SVD)"
        if numerical or not ok:  # never a tight interval around a biased value
            lo, hi, how = math.nan, math.nan, "withheld"
        ests.append(ParameterEstimate(path=path, unit=units_[j], start=float(start[j]),
                                      value=value, stderr=se_t * abs(start[j]), low=lo, high=hi,
                                      interval=how, determined=issue is None, issue=issue,
                                      stderr_white=se_w * abs(start[j]),
                                      linearity=linearity[j]))
    del s2
    return FitResult(parameters=params, base_name=base.name, drive=drive,
                     table_position=table_position,
                     sources=tuple(e.source for e in experiments), estimates=tuple(ests),
                     covariance=cov, correlation=corr, condition_number=cond,
                     singular_values=sv, poorly_determined=tuple(combos),
                     residuals=tuple(residuals), residual_ok=ok, cost=0.5 * ssr, dof=dof,
                     evaluations=evaluations + ev.evaluations, confidence=confidence,
                     interrupted=False, message=message, simulated=tuple(simulated),
                     experiments=tuple(experiments), integration=integration, hac=hac,
                     inadequate=inadequate)


# ------------------------------------------------------------------ synthetic rig data


def synthetic_experiment(params: DriveParameters, speed: float, duration: float, *,
                         drive: str = "cdfs", table_position: float = 0.4,
                         position_quantum: float = 0.05e-6, current_noise: float = 0.01,
                         seed: int = 0, ramp_time: float = 0.1, record_start: float = 0.0,
                         source: str | None = None) -> Experiment:
    """A rig record made by simulation: constant ``speed`` [m/s] after a ``ramp_time`` [s]
    ramp for ``duration`` [s], sampled at 1 ms; table position quantised to
    ``position_quantum`` [m] (an encoder or interferometer count) and screw current with
    white noise of ``current_noise`` × its rms (seeded); ``record_start`` [s]: the record
    keeps only the samples from then on (a record of steady sliding).  For tests, the calibration
    (benchmarks/fit_calibration.py) and docs/fitting.md's worked example.

    Parameters
    ----------
    params : DriveParameters
        The "true" parameter set.
    speed : float
        Commanded table speed [m/s].
    duration : float
        Record length [s].
    drive : str, default "cdfs"
        The drive.
    table_position : float, default 0.4
        Table position [m].
    position_quantum : float, default 5e-8
        Count size of the position measurement [m].
    current_noise : float, default 0.01
        Current noise σ relative to its rms [-].
    seed : int, default 0
        Seed of the noise.
    ramp_time : float, default 0.1
        Start ramp [s].
    record_start : float, default 0.0
        Start of the kept record [s].
    source : str, optional
        The record's label.

    Returns
    -------
    Experiment
        The synthetic record.
    """
    from ..engine.simulate import DriveSystem, simulate
    from ..model.reference import ConstantSpeed

    # refused before the run: a negative or NaN noise σ (NaN made every current sample NaN),
    # a quantum that was silently ignored, numpy's "expected non-negative integer" for a
    # seed, and a record start past the end (an empty record) (an outside check, 2026-12-07)
    for name, value, unit in (("current_noise", current_noise, "-, σ over the current's rms"),
                              ("position_quantum", position_quantum, "m"),
                              ("record_start", record_start, "s")):
        if not is_real(value) or not 0.0 <= value < math.inf:
            raise ParameterError(name, value, f"expected a finite number ≥ 0 [{unit}]")
    if is_real(duration) and record_start >= duration:
        raise ParameterError("record_start", record_start, f"expected a start before the "
                             f"record's end, 0 ≤ record_start < duration = {duration:g} [s]")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int | np.integer)
                             or seed < 0):
        raise ParameterError("seed", seed, "expected a whole number ≥ 0 [-]")
    # the shared check, naming ``speed`` (a str or NaN was refused as "profile.table_speed",
    # a field the caller never wrote); either sign and 0 as the profile takes them
    speed = check_speed("speed", speed, sign="any")
    system = DriveSystem(params, drive=drive, table_position=table_position)
    result = simulate(system, ConstantSpeed(speed, ramp_time=ramp_time), duration)
    t = np.asarray(result.time)
    rng = np.random.default_rng(seed)
    x = np.asarray(result["table_position"])
    if position_quantum > 0:
        x = np.round(x / position_quantum) * position_quantum
    cur_name = f"{system.topology().table_axis}_current"  # the table-driving motor's
    i = np.asarray(result[cur_name])
    i = i + current_noise * float(np.sqrt(np.mean(i ** 2))) * rng.standard_normal(i.size)
    ref = np.asarray(result["table_speed_reference"])
    keep = t >= record_start - 1e-12
    if np.count_nonzero(keep) < NOISE_MIN_SAMPLES:  # no noise σ, so nothing to fit
        raise ParameterError("record_start", record_start, "expected a start at least "
                             f"{NOISE_MIN_SAMPLES} samples before the end ({t[-1]:g} s; "
                             f"samples every {t[1] - t[0]:g} s), for the noise estimate [s]")
    signals = {"table_position": x[keep], cur_name: i[keep]}
    return Experiment(source=source or f"synthetic {speed * 1e3:g} mm/s (seed {seed})",
                      time=t[keep], signals=signals, reference_time=t, table_speed=ref,
                      noise={k: noise_level(v) for k, v in signals.items()})


# ------------------------------------------------------------------ residual plots

#: signal → (engineering unit, factor from SI) for plots and the CLI
EDGE_UNITS = {"table_position": ("µm", 1e6), "table_speed": ("mm/s", 1e3),
              "screw_current": ("A", 1.0), "nut_current": ("A", 1.0),
              "motor_current": ("A", 1.0), "drive_force": ("N", 1.0)}


def plot_residuals(result: FitResult, path: str | Path) -> Path:
    """One row per measured signal of each trace: measured and simulated (left; position
    relative to the command's integral), residual against time with ±2σ of the data's noise
    (middle), and the residual's histogram (right).

    Parameters
    ----------
    result : FitResult
        The fit (with its simulated signals).
    path : str or Path
        The image file.

    Returns
    -------
    Path
        The file written.
    """
    from matplotlib.figure import Figure

    rows = [(e, name, sim) for e, sims in zip(result.experiments, result.simulated,
                                              strict=True) for name, sim in sims.items()]
    fig = Figure(figsize=(12, 2.4 * len(rows) + 0.6))
    axes = fig.subplots(len(rows), 3, squeeze=False, gridspec_kw={"width_ratios": [3, 3, 1]})
    for (e, name, sim), ax in zip(rows, axes, strict=True):
        unit, k = EDGE_UNITS.get(name, ("SI", 1.0))
        meas = np.asarray(e.signals[name])
        shown_meas, shown_sim = meas, np.asarray(sim)
        label = name
        if name == "table_position":
            ref = np.interp(e.time, e.reference_time, np.concatenate(
                [[0.0], np.cumsum(0.5 * (e.table_speed[1:] + e.table_speed[:-1])
                                  * np.diff(e.reference_time))]))
            shown_meas, shown_sim = meas - ref, shown_sim - ref
            label = "position − command"
        ax[0].plot(e.time, k * shown_meas, lw=0.6, label="measured")
        ax[0].plot(e.time, k * shown_sim, lw=0.8, label="fitted model")
        ax[0].set_ylabel(f"{label} [{unit}]", fontsize=8)
        ax[0].set_title(Path(e.source).name, fontsize=8)
        ax[0].legend(fontsize=7, loc="best")
        res = k * (shown_sim - shown_meas)
        ax[1].plot(e.time, res, lw=0.5)
        sig = 2 * k * e.noise[name]
        ax[1].axhline(sig, color="k", ls="--", lw=0.6)
        ax[1].axhline(-sig, color="k", ls="--", lw=0.6)
        ax[1].set_ylabel(f"residual [{unit}]", fontsize=8)
        ax[2].hist(res, bins=40, orientation="horizontal", color="0.5")
        ax[2].set_xticks([])
    axes[-1][0].set_xlabel("time [s]")
    axes[-1][1].set_xlabel("time [s] (dashed: ±2σ of the data's own noise)")
    check = "passed" if result.residual_ok else "FAILED"
    fig.suptitle(f"feeddrive fit — {result.drive.upper()}, residual check {check}",
                 fontsize=10)
    fig.tight_layout()
    from ..io.outputs import save_figure

    return save_figure(fig, path, dpi=100)
