"""Reference profiles: what the table (and, for the DDFS, the nut) is commanded to do.

Profiles are immutable descriptions; each profile's ``encode()`` gives the numbers the
compiled ``reference_kernel`` reads (a parameter block and a data table).

Speed profiles built on :class:`SampledSpeed` (SI units): :func:`trapezoid`, the paper's
step-down staircase (:func:`stepdown`), and a profile read from a CSV file
(:func:`from_csv`).  The solver sees every one of them as a sampled table (linear
interpolation of speed, exact integral for position), so none needs a new kernel.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._jit import kernel
from ..parameters import ParameterError
from ..parameters.validation import MISSING, check_speed, is_real, real_array
from ..units import LARGEST_SPEED

REF_CONSTANT, REF_SINE, REF_SAMPLED, REF_INPUT = 0, 1, 2, 3
# parameter block of a profile: kind, table speed, nut speed, ramp time, frequency or step,
# and where its data table lies in T (offset, columns)
PROFILE_PARAMS = ("kind", "table_speed", "nut_speed", "ramp_time", "frequency", "table_offset",
                  "table_columns")
# the block's named offsets (a sine's amplitudes share the speed slots, a sampled profile's
# hold flag the ramp slot, its sample step and an input's sample instant the frequency slot)
KIND, TABLE_SPEED, NUT_SPEED, RAMP_TIME, FREQUENCY, TABLE_OFFSET, TABLE_COLUMNS = \
    range(len(PROFILE_PARAMS))
HOLD, SAMPLE_STEP, INPUT_INSTANT = RAMP_TIME, FREQUENCY, FREQUENCY


def commanded_references(block: np.ndarray, table: np.ndarray
                         ) -> dict[str, tuple[float, np.ndarray]]:
    """The reference signals beyond the table's that an encoded profile commands, for the
    drive's topology to refuse those it does not follow
    (:meth:`feeddrive.model.mechanisms.Mechanism.check_profile`).

    Parameters
    ----------
    block : numpy.ndarray
        The profile's parameter block (``PROFILE_PARAMS``) [SI, per slot].
    table : numpy.ndarray
        Its 4-row data table (rows: table position, table speed, nut position, nut speed)
        [m, m/s].

    Returns
    -------
    dict of str to (float, numpy.ndarray)
        Signal → (constant speed, tabulated speed) [m/s]: the nut's.
    """
    return {"nut": (float(block[NUT_SPEED]), table[3])}


@kernel
def reference_kernel(t: float, P: np.ndarray, o: int,
                     T: np.ndarray) -> tuple[float, float, float, float]:
    """Commanded (table position, table speed, nut position, nut speed) at time t.

    ``P[o:o+7]`` is the profile block (``PROFILE_PARAMS``); sampled profiles read a 4 × n
    table at ``T[to:]`` (rows: table position, table speed, nut position, nut speed), their
    speeds interpolated linearly or, with ``P[o + HOLD]`` = 1, held (zero-order hold).  An
    external input (``REF_INPUT``, :mod:`feeddrive.fmu`) reads a 4 × 2 table written by its
    host: positions X (rows 0, 2) and speeds V with their rates A (rows 1, 3: [V, A]) at the
    instant ``P[o + INPUT_INSTANT]``, x = X + V·τ + A·τ²/2, v = V + A·τ, τ = t − that instant.

    Parameters
    ----------
    t : float
        Time [s].
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the profile block in ``P``.
    T : numpy.ndarray
        The packed tables (sampled profiles, the external input's table) [SI].

    Returns
    -------
    tuple of float
        Table position [m], table speed [m/s], nut position [m], nut speed [m/s].
    """
    kind = int(P[o + KIND])
    if kind == REF_CONSTANT:
        tr = P[o + RAMP_TIME]
        vt = P[o + TABLE_SPEED]
        vn = P[o + NUT_SPEED]
        if tr > 0.0 and t < tr:
            f = t / tr
            return vt * t * f / 2.0, vt * f, vn * t * f / 2.0, vn * f
        shift = tr / 2.0 if tr > 0.0 else 0.0
        return vt * (t - shift), vt, vn * (t - shift), vn
    if kind == REF_SINE:
        w = 2.0 * math.pi * P[o + FREQUENCY]
        s = math.sin(w * t)
        c = math.cos(w * t)
        a_t = P[o + TABLE_SPEED]
        a_n = P[o + NUT_SPEED]
        return a_t * (1.0 - c) / w, a_t * s, a_n * (1.0 - c) / w, a_n * s
    to = int(P[o + TABLE_OFFSET])
    if kind == REF_INPUT:
        tau = t - P[o + INPUT_INSTANT]
        return (T[to] + (T[to + 2] + 0.5 * T[to + 3] * tau) * tau, T[to + 2] + T[to + 3] * tau,
                T[to + 4] + (T[to + 6] + 0.5 * T[to + 7] * tau) * tau,
                T[to + 6] + T[to + 7] * tau)
    dt = P[o + SAMPLE_STEP]
    n = int(P[o + TABLE_COLUMNS])
    hold = P[o + HOLD] > 0.5
    u = t / dt
    # held speeds jump at the samples: an instant within 1e-9 of a sample step belongs to the
    # new one (t = k·dt computed in floating point may land a hair before it)
    k = int(math.floor(u + 1e-9)) if hold else int(math.floor(u))
    if k >= n - 1:
        k = n - 2
        u = float(n - 1)
    if k < 0:
        k = 0
        u = 0.0
    f = u - k
    tau = f * dt
    v0 = T[to + n + k]
    v1 = T[to + n + k + 1]
    slope = 0.0 if hold else (v1 - v0) / dt
    x_t = T[to + k] + v0 * tau + 0.5 * slope * tau * tau
    v_t = v0 + slope * tau
    v0 = T[to + 3 * n + k]
    v1 = T[to + 3 * n + k + 1]
    slope = 0.0 if hold else (v1 - v0) / dt
    x_n = T[to + 2 * n + k] + v0 * tau + 0.5 * slope * tau * tau
    v_n = v0 + slope * tau
    return x_t, v_t, x_n, v_n


#: zero-valued inputs added to the profile's reference (the linearisation's reference inputs,
#: :mod:`feeddrive.analysis.linear`), in the order ``reference_signal`` reads them
REFERENCE_INPUTS = ("table_position_reference", "table_speed_reference",
                    "nut_position_reference", "nut_speed_reference")
TABLE_POSITION_INPUT, TABLE_SPEED_INPUT, NUT_POSITION_INPUT, NUT_SPEED_INPUT = \
    range(len(REFERENCE_INPUTS))


#: the reference signals a profile encodes, in the order of its data table's row pairs
#: (position, speed) and of the linearisation's inputs (:data:`REFERENCE_INPUTS`); the table's
#: is every drive's, the others a topology follows when it says so
#: (:meth:`feeddrive.model.mechanisms.Mechanism.followed_references`)
REFERENCE_SIGNALS = ("table", "nut")


@kernel
def reference_signal(t: float, P: np.ndarray, o: int, oi: int, T: np.ndarray,
                     k: int) -> tuple[float, float]:
    """One reference signal's commanded position and speed, the linearisation's inputs added.

    Parameters
    ----------
    t : float
        Time [s].
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the profile block in ``P``.
    oi : int
        Offset of the reference inputs (:data:`REFERENCE_INPUTS`, zero in a simulation).
    T : numpy.ndarray
        The packed tables [SI].
    k : int
        The signal's index in :data:`REFERENCE_SIGNALS`.

    Returns
    -------
    tuple of float
        Its position [m] and speed [m/s].
    """
    x_t, v_t, x_n, v_n = reference_kernel(t, P, o, T)
    if k == 0:
        return x_t + P[oi + TABLE_POSITION_INPUT], v_t + P[oi + TABLE_SPEED_INPUT]
    return x_n + P[oi + NUT_POSITION_INPUT], v_n + P[oi + NUT_SPEED_INPUT]


@dataclass(frozen=True)
class ConstantSpeed:
    """Constant table speed (and nut speed for the DDFS) after a linear start ramp.

    Parameters
    ----------
    table_speed : float
        Commanded table speed [m/s] (Wang2021 Sect. 5.2: 1.55e-3 for Fig. 6).
    nut_speed : float, default 0
        Commanded speed of the nut driven by the hollow motor [m/s] (DDFS only; v_n of
        Wang2021 Fig. 7); the screw turns at the sum of both.
    ramp_time : float, default 0.1
        Duration of the linear ramp from rest to the commanded speeds [s].
    """

    table_speed: float
    nut_speed: float = 0.0
    ramp_time: float = 0.1  # [s]

    def __post_init__(self) -> None:
        # refused when made, naming the field (a negative ramp was refused only at
        # simulate, in a bare ValueError: an outside check, 2026-12-07)
        check_speed("profile.table_speed", self.table_speed, sign="any")
        check_speed("profile.nut_speed", self.nut_speed, sign="any")
        _number("ramp_time", self.ramp_time)
        _plain(self, ("table_speed", "nut_speed", "ramp_time"))
        if not (self.ramp_time >= 0.0 and math.isfinite(self.ramp_time)):
            raise ParameterError("profile.ramp_time", self.ramp_time,
                                 "expected a finite duration ≥ 0 [s]")

    def encode(self) -> tuple[dict[int, float], np.ndarray]:
        """The profile as (parameter slots, data table) for the reference kernel.

        Returns
        -------
        tuple of (dict, numpy.ndarray)
            Slot index → value [SI] of the profile's parameter block, and its (empty) table.
        """
        self.__post_init__()
        return ({KIND: REF_CONSTANT, TABLE_SPEED: self.table_speed,
                 NUT_SPEED: self.nut_speed, RAMP_TIME: self.ramp_time}, _EMPTY_TABLE)


#: the highest sine frequency a profile takes [Hz]: far above a feed drive's bandwidth (a
#: frequency of 1e300 Hz ran, and its summary failed in numpy: an outside check, 2026-12-07)
MAX_FREQUENCY = 1000.0


@dataclass(frozen=True)
class SineSpeed:
    """Sinusoidal speeds v(t) = A·sin(2πft) of the table and the nut.

    The screw's amplitude is their sum (Wang2021 Figs. 9–10: v_sp = v_tp + v_np).  The paper
    does not state the frequency; 0.2 Hz is our default (see docs/model.md).

    Parameters
    ----------
    table_amplitude : float
        Amplitude of the table speed [m/s].
    nut_amplitude : float, default 0
        Amplitude of the nut speed driven by the hollow motor [m/s] (DDFS only).
    frequency : float, default 0.2
        Frequency f of both sines [Hz].

    References
    ----------
    .. [1] Wang2021 Sect. 5.3, Figs. 9–10.
    """

    table_amplitude: float
    nut_amplitude: float = 0.0
    frequency: float = 0.2  # [Hz]

    def __post_init__(self) -> None:
        # refused when made, naming the field (a zero frequency was refused only at
        # simulate, in a bare ValueError: an outside check, 2026-12-07)
        check_speed("profile.table_amplitude", self.table_amplitude, sign="any")
        check_speed("profile.nut_amplitude", self.nut_amplitude, sign="any")
        _number("frequency", self.frequency)
        _plain(self, ("table_amplitude", "nut_amplitude", "frequency"))
        if not (0.0 < self.frequency <= MAX_FREQUENCY):
            raise ParameterError("profile.frequency", self.frequency,
                                 f"expected > 0, ≤ {MAX_FREQUENCY:g} [Hz]")
        # the sine is the table's command, and its summary judges the table against it: a
        # zero amplitude was refused only by the summary, after the run, in a bare
        # ValueError (an outside check, 2026-12-07); nothing builds one on purpose
        if self.table_amplitude == 0.0:
            raise ParameterError("profile.table_amplitude", self.table_amplitude,
                                 "expected a non-zero amplitude [m/s] (the table's command, "
                                 "which the run is judged against)")

    def encode(self) -> tuple[dict[int, float], np.ndarray]:
        """The profile as (parameter slots, data table) for the reference kernel.

        Returns
        -------
        tuple of (dict, numpy.ndarray)
            Slot index → value [SI] of the profile's parameter block, and its (empty) table.
        """
        self.__post_init__()
        return ({KIND: REF_SINE, TABLE_SPEED: self.table_amplitude,
                 NUT_SPEED: self.nut_amplitude, FREQUENCY: self.frequency}, _EMPTY_TABLE)


@dataclass(frozen=True)
class SampledSpeed:
    """Table and nut speeds sampled on a uniform time grid starting at 0.

    Speeds are interpolated linearly or, with ``hold``, each held until the next sample
    (zero-order hold, as a co-simulation FMU holds its inputs over a communication step);
    positions are their exact integrals.

    Past the last sample the speeds are held and the positions stand, so a run may go on past
    the end only of a profile that ends at rest (:func:`feeddrive.simulate` refuses one
    longer than a profile still moving at its end).

    Parameters
    ----------
    time : numpy.ndarray
        Uniform, increasing sample instants from 0 [s].
    table_speed : numpy.ndarray
        Commanded table speed at each instant, |v| ≤ ``units.LARGEST_SPEED`` [m/s].
    nut_speed : numpy.ndarray or None, default None
        Commanded nut speed at each instant [m/s] (DDFS; None: zero).
    hold : bool, default False
        Hold each sample until the next (zero-order hold) instead of interpolating.
    """

    time: np.ndarray
    table_speed: np.ndarray
    nut_speed: np.ndarray | None = None
    hold: bool = False

    def __post_init__(self) -> None:
        # refused when made, naming the field (as the other profiles)
        self._arrays()

    def _arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The checked arrays: time, table speed, nut speed and the time steps [s, m/s]."""
        if not isinstance(self.hold, bool | np.bool_):  # hold="no" was taken as True
            raise ParameterError("profile.hold", self.hold, "expected True or False")
        # complex speeds were cast to their real part with a warning, booleans to 0 and
        # 1 m/s (session 29): refused naming the first value
        t = real_array("profile.time", self.time, "s")
        vt = real_array("profile.table_speed", self.table_speed, "m/s")
        vn = (np.zeros_like(vt) if self.nut_speed is None
              else real_array("profile.nut_speed", self.nut_speed, "m/s"))
        if t.ndim != 1 or t.size < 2 or vt.shape != t.shape or vn.shape != t.shape:
            raise ParameterError("profile.time/table_speed/nut_speed", MISSING,
                                 f"expected 1-D arrays of one length ≥ 2 (shapes {t.shape}, "
                                 f"{vt.shape}, {vn.shape}) [s, m/s]")
        for name, arr in (("time", t), ("table_speed", vt), ("nut_speed", vn)):
            if not np.all(np.isfinite(arr)):
                bad = int(np.flatnonzero(~np.isfinite(arr))[0])
                raise ParameterError(f"profile.{name}[{bad}]", float(arr[bad]),
                                     "expected finite values [" + ("s" if name == "time"
                                                                   else "m/s") + "]")
        for name, arr in (("table_speed", vt), ("nut_speed", vn)):
            if np.any(np.abs(arr) > LARGEST_SPEED):
                bad = int(np.flatnonzero(np.abs(arr) > LARGEST_SPEED)[0])
                check_speed(f"profile.{name}[{bad}]", float(arr[bad]), sign="any")
        dt = np.diff(t)
        # uniform to round-off: the spacing of doubles grows with t (at 8192 s it is 1.8e-12
        # s, and a 1-ms grid past that was refused: an outside check, 2026-12-07)
        spread = 1e-9 * max(dt.mean(), 1e-300) + 16 * np.finfo(float).eps * abs(t[-1])
        if abs(t[0]) > 1e-12 or np.any(dt <= 0) or np.ptp(dt) > spread:
            raise ParameterError("profile.time", MISSING, "expected a uniform, increasing "
                                 "grid starting at 0 [s]")
        return t, vt, vn, dt

    def encode(self) -> tuple[dict[int, float], np.ndarray]:
        """The profile as (parameter slots, data table) for the reference kernel.

        Returns
        -------
        tuple of (dict, numpy.ndarray)
            Slot index → value [SI] of the profile's parameter block, and the table of
            sample rows (time [s], table speed [m/s], nut speed [m/s], positions [m]).
        """
        t, vt, vn, dt = self._arrays()
        table = np.empty((4, t.size))
        for j, v in enumerate((vt, vn)):
            table[2 * j + 1] = v
            table[2 * j, 0] = 0.0
            table[2 * j, 1:] = np.cumsum((v[:-1] if self.hold else 0.5 * (v[1:] + v[:-1])) * dt)
        return ({KIND: REF_SAMPLED, HOLD: 1.0 if self.hold else 0.0,
                 SAMPLE_STEP: float(dt.mean())}, table)

    @classmethod
    def from_function(cls, table_speed: Callable[[np.ndarray], np.ndarray], duration: float,
                      nut_speed: Callable[[np.ndarray], np.ndarray] | None = None,
                      interval: float = 1e-4) -> SampledSpeed:
        """Sample user functions of time on a uniform grid.

        Parameters
        ----------
        table_speed : callable
            Time [s] (array) → commanded table speed [m/s].
        duration : float
            Time to cover [s] (the grid runs a little beyond it).
        nut_speed : callable or None, default None
            Time [s] (array) → commanded nut speed [m/s] (DDFS; None: zero).
        interval : float, default 1e-4
            Grid spacing [s].

        Returns
        -------
        SampledSpeed
            The sampled profile.

        Raises
        ------
        ParameterError
            For a function that is not callable or does not return one speed (or one per
            instant), a duration or interval that is not a finite number > 0, or a grid of
            more than ``MAX_PROFILE_SAMPLES`` samples (refused before it is made).
        """
        # refused naming the argument, before any array is made (an interval of 0 raised
        # ZeroDivisionError, a NaN duration "cannot convert float NaN to integer", 1e9 s a
        # MemoryError of 72.8 TiB: an outside check, 2026-12-07)
        for name, function in (("table_speed", table_speed), ("nut_speed", nut_speed)):
            if not (callable(function) or (name == "nut_speed" and function is None)):
                raise ParameterError(name, type(function).__name__, "expected a function of "
                                     "the time [s] (an array) returning the speed [m/s]")
        duration = _positive("duration", duration, "s")
        interval = _positive("interval", interval, "s")
        _check_span("duration", duration, duration, interval, "s")
        n = int(math.ceil(duration / interval)) + 2
        t = np.arange(n) * interval
        vt = _sampled("table_speed", table_speed(t), t)
        vn = None if nut_speed is None else _sampled("nut_speed", nut_speed(t), t)
        return cls(time=t, table_speed=vt, nut_speed=vn)


Profile = ConstantSpeed | SineSpeed | SampledSpeed


def _sampled(name: str, values: object, t: np.ndarray) -> np.ndarray:
    """What a function given to :meth:`SampledSpeed.from_function` returned at the instants
    ``t``: one speed or one per instant [m/s], else refused naming the argument ``name``."""
    try:
        v = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        v = None
    if v is None or not (v.ndim == 0 or v.shape == t.shape):
        raise ParameterError(name, MISSING, f"expected a function returning a number or one "
                             f"per instant of its argument ({t.size} instants) [m/s]")
    return v * np.ones_like(t)


def sine_field(profile: str, name: str) -> float | None:
    """A field of a ``SineSpeed`` profile (``frequency`` [Hz], ``table_amplitude`` [m/s] …)
    read from its repr in a run's attributes; None for another profile.

    Parameters
    ----------
    profile : str
        The ``profile`` attribute of a run.
    name : str
        The field.

    Returns
    -------
    float or None
        Its value [SI].
    """
    return profile_field(profile, "SineSpeed", name)


def profile_field(profile: str, kind: str, name: str) -> float | None:
    """A field of a ``kind`` profile (``"ConstantSpeed"``, ``"SineSpeed"``) read from its repr
    in a run's attributes (a NumPy scalar's too, ``np.float64(0.2)``, as a file written before
    the fields were made plain floats holds it); None for another profile.

    Parameters
    ----------
    profile : str
        The ``profile`` attribute of a run.
    kind : str
        The profile's class name.
    name : str
        The field.

    Returns
    -------
    float or None
        Its value [SI].
    """
    import re

    found = re.match(rf"{kind}\(.*\b{name}=(?:np\.\w+\()?([0-9.eE+-]+)", profile)
    return float(found.group(1)) if found else None


_EMPTY_TABLE = np.zeros((4, 2))


def _plain(profile: object, names: tuple[str, ...]) -> None:
    """Make NumPy scalar fields plain floats (the same value): the repr a run keeps in its
    attributes is read back by :func:`profile_field`, and ``np.float64(0.2)`` was not (a sine
    given NumPy numbers was summarised as a creep test: an outside check, 2026-12-07)."""
    for name in names:
        value = getattr(profile, name)
        if isinstance(value, np.floating | np.integer):
            object.__setattr__(profile, name, float(value))


def _number(name: str, value: object) -> None:
    """Refuse a ``profile.name`` that is not a real number (a str or a list), naming it."""
    if not is_real(value):
        raise ParameterError(f"profile.{name}", value, "expected a number")


# ---------------------------------------------------------------- profiles built on SampledSpeed

_INTERVAL = 1e-3  # [s] sampling of the built profiles
#: the most samples a built or read profile tabulates: 20 000 s at 1 ms (each array 160 MB);
#: a 1e6-s file or a 1e-9-mm/s staircase step ran out of memory or hung before any check (an
#: outside check, 2026-12-07)
MAX_PROFILE_SAMPLES = 20_000_000


def _check_span(name: str, value: float, span: float, interval: float, unit: str) -> None:
    """Refuse, before any array is made, a profile of ``span`` seconds that would tabulate
    more than ``MAX_PROFILE_SAMPLES`` samples at ``interval``; ``name`` = ``value``
    [``unit``] is the setting that made it so long."""
    if not span / interval <= MAX_PROFILE_SAMPLES:
        raise ParameterError(name, value, f"makes a profile of {span:.4g} s, "
                             f"{span / interval:.3g} samples at {interval:g} s; expected ≤ "
                             f"{MAX_PROFILE_SAMPLES} samples ({MAX_PROFILE_SAMPLES * interval:g}"
                             f" s) [{unit}]")


def _positive(name: str, value: float, unit: str) -> float:
    # a str or a list is refused here too, not in numpy ("ufunc 'isfinite' not supported")
    if not is_real(value) or not (math.isfinite(value) and value > 0.0):
        raise ParameterError(name, value, f"expected a finite value > 0 [{unit}]")
    return float(value)


def trapezoid(table_speed: float, duration: float, *, ramp_time: float = 0.5,
              nut_speed: float = 0.0, interval: float = _INTERVAL) -> SampledSpeed:
    """A move: ramp from rest to a table speed, hold, and ramp back so the table stops at the end.

    Parameters
    ----------
    table_speed : float
        Hold speed [m/s].
    duration : float
        Time at which the table is back at rest [s].
    ramp_time : float, default 0.5
        Length of each ramp, less than half the duration [s].
    nut_speed : float, default 0.0
        Hold speed of the nut (DDFS), same shape [m/s].
    interval : float, optional
        Sample interval of the tabulated profile [s].

    Returns
    -------
    SampledSpeed
        The tabulated profile.

    Raises
    ------
    ParameterError
        For a speed that is not a number of at most ``units.LARGEST_SPEED``, a non-positive
        duration or ramp time, or ramps longer than the move.

    Examples
    --------
    >>> import numpy as np
    >>> import feeddrive as fd
    >>> move = fd.trapezoid(2e-3, duration=2.0, ramp_time=0.5)
    >>> [round(1e3 * float(np.interp(t, move.time, move.table_speed)), 3) for t in (0.25, 1, 2)]
    [1.0, 2.0, 0.0]
    """
    check_speed("table_speed", table_speed, sign="any")
    check_speed("nut_speed", nut_speed, sign="any")
    duration = _positive("duration", duration, "s")
    ramp_time = _positive("ramp_time", ramp_time, "s")
    interval = _positive("interval", interval, "s")
    if 2.0 * ramp_time >= duration:
        raise ParameterError("ramp_time", ramp_time,
                             f"expected < duration / 2 = {duration / 2:g} [s]")
    _check_span("duration", duration, duration, interval, "s")
    t = np.arange(int(np.ceil(duration / interval)) + 2) * interval
    shape = np.clip(np.minimum(t, duration - t) / ramp_time, 0.0, 1.0)
    return SampledSpeed(time=t, table_speed=table_speed * shape, nut_speed=nut_speed * shape)


def stepdown(start_speed: float, lowest_speed: float, *, step: float = 0.01e-3,
             dwell: float = 4.0, lead_in: float = 6.0, nut_speed: float = 0.0,
             interval: float = _INTERVAL) -> tuple[SampledSpeed, np.ndarray]:
    """The paper's step-down experiment: lower the commanded speed in steps until the table crawls.

    Run at ``start_speed`` for ``lead_in``, then lower the command by ``step`` every ``dwell``
    down to ``lowest_speed`` (Wang2021 Sect. 6, Fig. 13) — the staircase ``creep --method
    stepdown`` runs.  The profile's duration is ``profile.time[-1]``.

    Parameters
    ----------
    start_speed : float
        First speed [m/s].
    lowest_speed : float
        Last speed, below ``start_speed`` [m/s].
    step : float, default 1e-5
        Speed decrement, the paper's 0.01 mm/s [m/s].
    dwell : float, default 4.0
        Time at each step [s].
    lead_in : float, default 6.0
        Time at the first speed [s].
    nut_speed : float, default 0.0
        Constant nut speed (DDFS) [m/s].
    interval : float, optional
        Sample interval of the tabulated profile [s].

    Returns
    -------
    profile : SampledSpeed
        The tabulated staircase.
    speeds : numpy.ndarray
        The step speeds [m/s].

    Raises
    ------
    ParameterError
        For a value that is not a number, a non-positive one, a speed above
        ``units.LARGEST_SPEED`` or ``lowest_speed ≥ start_speed``.

    References
    ----------
    .. [1] Wang2021 Sect. 6, Fig. 13.

    Examples
    --------
    The staircase from 1.60 to 1.50 mm/s in the paper's 0.01-mm/s steps:

    >>> import feeddrive as fd
    >>> profile, speeds = fd.stepdown(1.60e-3, 1.50e-3)
    >>> print(f"{speeds.size} steps, {profile.time[-1]:.0f} s")
    11 steps, 50 s
    """
    for name, value in (("start_speed", start_speed), ("lowest_speed", lowest_speed),
                        ("step", step)):
        _positive(name, value, "m/s")
    check_speed("start_speed", start_speed, sign="any")
    check_speed("nut_speed", nut_speed, sign="any")
    _positive("dwell", dwell, "s")
    _positive("lead_in", lead_in, "s")
    _positive("interval", interval, "s")
    if lowest_speed >= start_speed:
        raise ParameterError("lowest_speed", lowest_speed,
                             f"expected < start_speed = {start_speed:g} [m/s]")
    steps = (start_speed - lowest_speed) / step
    span = lead_in + (steps + 1) * dwell
    # the setting that made it long: one dwell beyond the limit, else the count of steps
    if dwell / interval > MAX_PROFILE_SAMPLES:
        _check_span("dwell", dwell, span, interval, "s")
    _check_span("step", step, span, interval, "m/s")
    n = int(np.floor(steps + 1e-9)) + 1
    speeds = np.round(start_speed - step * np.arange(n), 12)
    profile, _ = _staircase(speeds, dwell, lead_in, nut_speed, interval)
    return profile, speeds


def from_csv(path: str | Path, *, interval: float = _INTERVAL) -> SampledSpeed:
    """A speed profile from a CSV file with columns ``time`` and ``table_speed`` (optionally
    ``nut_speed``).

    In s and mm/s unless a header states its unit (``time [ms]``, ``table_speed [m/s]``); the
    format of docs/measured-data.md (``#`` comments, separator detected).  Times must increase
    from 0; they are resampled onto a uniform grid.

    Parameters
    ----------
    path : str or Path
        The CSV file.
    interval : float, optional
        Sample interval of the resampled profile [s].

    Returns
    -------
    SampledSpeed
        The profile in SI.

    Raises
    ------
    MeasuredDataError
        For missing columns, bad cells, or times that do not increase from 0.
    """
    from ..io.measured import MeasuredDataError, read_csv_table

    if not isinstance(path, str | Path):  # a number failed in os.fspath's words
        raise ParameterError("path", path, "expected a CSV file's path (str or pathlib.Path)")
    _positive("interval", interval, "s")
    table = read_csv_table(path)
    t, _, _ = table.quantity(["time"], "time", unit=None, default_unit="s")
    vt, _, _ = table.quantity(["table_speed"], "speed", unit=None, default_unit="mm/s")
    vn = (table.quantity(["nut_speed"], "speed", unit=None, default_unit="mm/s")[0]
          if table.has("nut_speed") else None)
    if t.size < 2 or abs(t[0]) > 1e-12 or np.any(np.diff(t) <= 0):
        raise MeasuredDataError(table.source, table.header_line,
                                "column 'time': expected times [s] increasing from 0, at "
                                "least two rows")
    if not t[-1] / interval <= MAX_PROFILE_SAMPLES:
        raise MeasuredDataError(table.source, table.header_line,
                                f"column 'time': the profile spans {t[-1]:.4g} s, "
                                f"{t[-1] / interval:.3g} samples at {interval:g} s; expected "
                                f"≤ {MAX_PROFILE_SAMPLES * interval:g} s")
    grid = np.arange(int(np.floor(t[-1] / interval + 1e-9)) + 1) * interval
    if grid.size < 2:
        raise MeasuredDataError(table.source, table.header_line,
                                f"column 'time': expected a profile longer than {interval:g} s")
    return SampledSpeed(time=grid, table_speed=np.interp(grid, t, vt),
                        nut_speed=None if vn is None else np.interp(grid, t, vn))


def _staircase(speeds: np.ndarray, dwell: float | Sequence[float], lead_in: float,
               nut_speed: float, interval: float = 1e-3) -> tuple[SampledSpeed, np.ndarray]:
    """Speed staircase: a ramp to speeds[0] held for ``lead_in`` [s], then each speed for its
    ``dwell`` [s] (one number for all, or one per speed)."""
    dwells = np.broadcast_to(np.asarray(dwell, dtype=float), (len(speeds),))
    starts = lead_in + np.concatenate([[0.0], np.cumsum(dwells[:-1])])
    t_end = starts[-1] + dwells[-1]
    t = np.arange(int(round(t_end / interval)) + 1) * interval
    idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(speeds) - 1)
    vt = speeds[idx].astype(float)
    ramp = min(0.1, lead_in) if lead_in > 0 else 0.1
    vt = np.where(t < ramp, speeds[0] * t / ramp, vt)
    vn = np.where(t < ramp, nut_speed * t / ramp, nut_speed)
    return SampledSpeed(time=t, table_speed=vt, nut_speed=vn), starts
