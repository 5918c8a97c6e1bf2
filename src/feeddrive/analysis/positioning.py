"""ISO 230-2 positioning test: accuracy, repeatability and reversal value of one axis.  SI.

The axis is sent to m target positions P_i, each approached n ≥ 5 times in the positive
(↑) and in the negative (↓) direction; at each stop the actual position P_ij is read and the
positional deviation x_ij = P_ij − P_i kept.  :func:`positioning_test` evaluates them with the
formulas of ISO 230-2 [1]_ (written out with their numbers in docs/acceptance-tests.md):

- x̄_i↑ = (1/n) Σ_j x_ij↑: mean unidirectional positional deviation at P_i (x̄_i↓ alike);
- x̄_i = (x̄_i↑ + x̄_i↓)/2: mean bidirectional positional deviation at P_i;
- B_i = x̄_i↑ − x̄_i↓: reversal value at P_i; B = max │B_i│ and B̄ = (1/m) Σ B_i: the
  reversal value and the mean reversal value of the axis;
- s_i↑ = √(Σ_j (x_ij↑ − x̄_i↑)² / (n − 1)): estimator of the unidirectional repeatability;
- R_i↑ = 4 s_i↑: unidirectional repeatability at P_i; R_i = max(2s_i↑ + 2s_i↓ + │B_i│;
  R_i↑; R_i↓): bidirectional repeatability at P_i; R↑ = max R_i↑, R = max R_i: of the axis;
- E↑ = max x̄_i↑ − min x̄_i↑, E = max(x̄_i↑; x̄_i↓) − min(x̄_i↑; x̄_i↓): unidirectional and
  bidirectional systematic positional deviation;
- M = max x̄_i − min x̄_i: range of the mean bidirectional positional deviation;
- A↑ = max(x̄_i↑ + 2s_i↑) − min(x̄_i↑ − 2s_i↑), A = max(x̄_i↑ + 2s_i↑; x̄_i↓ + 2s_i↓) −
  min(x̄_i↑ − 2s_i↑; x̄_i↓ − 2s_i↓): unidirectional and bidirectional accuracy.

:func:`positioning_cycle` lays out the stops of the standard's linear test cycle or of its
pilgrim-step cycle; :func:`read_approaches` takes the actual positions from a recorded (or
simulated) trace of such a run.

References
----------
.. [1] ISO 230-2:2014, Test code for machine tools — Part 2: Determination of accuracy and
       repeatability of positioning of numerically controlled axes; the definitions of
       Clause 3 and its test cycles (the formulas are those of the 2006 edition,
       whose definitions are numbered 2.10–2.24 as cited in public implementations; the
       2014 clause numbers could not be checked here).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from ..parameters import ParameterError
from ..parameters.validation import real_array, refuse_repeats

__all__ = ["MIN_CYCLES", "PositioningTest", "Stop", "describe", "positioning_cycle",
           "positioning_test", "read_approaches", "reading_motion"]

#: fewest approaches per target and direction (ISO 230-2: five)
MIN_CYCLES = 5
#: fraction of each dwell, at its end, over which the actual position is averaged
READ_FRACTION = 0.25


@dataclass(frozen=True)
class PositioningTest:
    """ISO 230-2 quantities of one axis [m], per target (arrays of length m) and of the axis.

    Parameters
    ----------
    targets : numpy.ndarray
        Target positions P_i [m].
    deviation_up, deviation_down : numpy.ndarray
        x_ij↑, x_ij↓, shape (m, n) [m].
    mean_up, mean_down, mean : numpy.ndarray
        x̄_i↑, x̄_i↓, x̄_i [m].
    s_up, s_down : numpy.ndarray
        s_i↑, s_i↓ [m].
    reversal_at : numpy.ndarray
        B_i [m].
    repeatability_up_at, repeatability_down_at, repeatability_at : numpy.ndarray
        R_i↑, R_i↓, R_i [m].
    reversal, mean_reversal : float
        B, B̄ [m].
    repeatability_up, repeatability_down, repeatability : float
        R↑, R↓, R [m].
    systematic_up, systematic_down, systematic : float
        E↑, E↓, E [m].
    mean_range : float
        M [m].
    accuracy_up, accuracy_down, accuracy : float
        A↑, A↓, A [m].
    """

    targets: np.ndarray
    deviation_up: np.ndarray
    deviation_down: np.ndarray
    mean_up: np.ndarray
    mean_down: np.ndarray
    mean: np.ndarray
    s_up: np.ndarray
    s_down: np.ndarray
    reversal_at: np.ndarray
    repeatability_up_at: np.ndarray
    repeatability_down_at: np.ndarray
    repeatability_at: np.ndarray
    reversal: float
    mean_reversal: float
    repeatability_up: float
    repeatability_down: float
    repeatability: float
    systematic_up: float
    systematic_down: float
    systematic: float
    mean_range: float
    accuracy_up: float
    accuracy_down: float
    accuracy: float

    #: the axis's quantities: attribute → (symbol, label) as reports print them
    AXIS_QUANTITIES: ClassVar[dict[str, tuple[str, str]]] = {
        "accuracy": ("A", "bidirectional accuracy"),
        "accuracy_up": ("A↑", "unidirectional accuracy, positive approach"),
        "accuracy_down": ("A↓", "unidirectional accuracy, negative approach"),
        "repeatability": ("R", "bidirectional repeatability"),
        "repeatability_up": ("R↑", "unidirectional repeatability, positive approach"),
        "repeatability_down": ("R↓", "unidirectional repeatability, negative approach"),
        "reversal": ("B", "reversal value (largest |B_i|)"),
        "mean_reversal": ("B̄", "mean reversal value"),
        "systematic": ("E", "bidirectional systematic positional deviation"),
        "systematic_up": ("E↑", "unidirectional systematic positional deviation, positive"),
        "systematic_down": ("E↓", "unidirectional systematic positional deviation, negative"),
        "mean_range": ("M", "range of the mean bidirectional positional deviation"),
    }

    def __repr__(self) -> str:
        # what a notebook prints: the axis's headline quantities in µm, never the arrays
        um = 1e6
        p = self.targets
        return (f"<feeddrive.PositioningTest {p.size} targets {1e3 * float(p.min()):.6g} … "
                f"{1e3 * float(p.max()):.6g} mm, {self.deviation_up.shape[1]} approaches: "
                f"A {self.accuracy * um:.4g}, R {self.repeatability * um:.4g}, "
                f"B {self.reversal * um:.4g}, E {self.systematic * um:.4g}, "
                f"M {self.mean_range * um:.4g} µm; .to_dict(), describe()>")

    def to_dict(self) -> dict[str, Any]:
        """JSON form: targets in mm, every deviation in µm.

        Returns
        -------
        dict
            ``axis`` (the quantities of the axis, ``<name>_um``), ``targets`` (per target: the
            means, s, B_i, R_i and every approach's deviation) and ``cycles``.
        """
        um = 1e6
        axis = {f"{k}_um": float(getattr(self, k)) * um for k in self.AXIS_QUANTITIES}
        per_target = [
            {"target_mm": float(f"{float(p) * 1e3:.12g}"),  # as typed, not 175.00000000000003
             "mean_up_um": float(self.mean_up[i]) * um,
             "mean_down_um": float(self.mean_down[i]) * um,
             "mean_um": float(self.mean[i]) * um,
             "s_up_um": float(self.s_up[i]) * um, "s_down_um": float(self.s_down[i]) * um,
             "reversal_um": float(self.reversal_at[i]) * um,
             "repeatability_up_um": float(self.repeatability_up_at[i]) * um,
             "repeatability_down_um": float(self.repeatability_down_at[i]) * um,
             "repeatability_um": float(self.repeatability_at[i]) * um,
             "deviations_up_um": [float(v) * um for v in self.deviation_up[i]],
             "deviations_down_um": [float(v) * um for v in self.deviation_down[i]]}
            for i, p in enumerate(self.targets)]
        return {"axis": axis, "targets": per_target,
                "cycles": int(self.deviation_up.shape[1])}


def positioning_test(targets: ArrayLike, deviation_up: ArrayLike, deviation_down: ArrayLike
                     ) -> PositioningTest:
    """The ISO 230-2 quantities from the deviations of every approach.

    Parameters
    ----------
    targets : array_like
        Target positions P_i, m ≥ 2 of them [m].
    deviation_up, deviation_down : array_like
        x_ij = P_ij − P_i of the positive and of the negative approaches, shape (m, n),
        n ≥ 5 [m].

    Returns
    -------
    PositioningTest
        Every quantity of the list in the module's docstring (ISO 230-2, Clause 3 [1]_).

    Raises
    ------
    ParameterError
        For fewer than 5 approaches per direction, fewer than 2 targets, a target given twice,
        shapes that do not match or values that are not finite.

    References
    ----------
    .. [1] ISO 230-2:2014, Clause 3 (docs/acceptance-tests.md).

    Examples
    --------
    An axis that stops 2 µm short in each direction has B = −4 µm, no scatter:

    >>> import numpy as np
    >>> from feeddrive.analysis.positioning import positioning_test
    >>> p = np.array([0.0, 0.1, 0.2])
    >>> res = positioning_test(p, np.full((3, 5), -2e-6), np.full((3, 5), 2e-6))
    >>> print(f"B = {res.reversal * 1e6:.1f} µm, B̄ = {res.mean_reversal * 1e6:.1f} µm, "
    ...       f"A = {res.accuracy * 1e6:.1f} µm")
    B = 4.0 µm, B̄ = -4.0 µm, A = 4.0 µm
    """
    p = real_array("targets", targets, "m")
    up = real_array("deviation_up", deviation_up, "m")
    down = real_array("deviation_down", deviation_down, "m")
    if p.ndim != 1 or p.size < 2:
        raise ParameterError("targets", p.size, "expected at least 2 target positions")
    # a target twice was counted twice in the mean reversal value B̄ (an earlier sweep,
    # session 30); a record read from a file holds each once
    refuse_repeats("targets", p.tolist(), "each target position once [m] (twice, it would "
                   "count twice in the mean reversal value)")
    for name, x in (("deviation_up", up), ("deviation_down", down)):
        if x.ndim != 2 or x.shape[0] != p.size:
            raise ParameterError(name, x.shape, f"expected shape ({p.size}, cycles)")
        if x.shape[1] < MIN_CYCLES:
            raise ParameterError("cycles", x.shape[1],
                                 f"expected at least {MIN_CYCLES} approaches per target and "
                                 "direction (ISO 230-2)")
        if not np.all(np.isfinite(x)):
            raise ParameterError(name, "non-finite", "expected finite deviations [m]")
    mean_up = up.mean(axis=1)
    mean_down = down.mean(axis=1)
    mean = (mean_up + mean_down) / 2.0
    s_up = up.std(axis=1, ddof=1)
    s_down = down.std(axis=1, ddof=1)
    b_i = mean_up - mean_down
    r_up_i = 4.0 * s_up
    r_down_i = 4.0 * s_down
    r_i = np.maximum.reduce([2.0 * s_up + 2.0 * s_down + np.abs(b_i), r_up_i, r_down_i])
    both_mean = np.concatenate([mean_up, mean_down])
    hi = np.concatenate([mean_up + 2.0 * s_up, mean_down + 2.0 * s_down])
    lo = np.concatenate([mean_up - 2.0 * s_up, mean_down - 2.0 * s_down])
    return PositioningTest(
        targets=p, deviation_up=up, deviation_down=down, mean_up=mean_up,
        mean_down=mean_down, mean=mean, s_up=s_up, s_down=s_down, reversal_at=b_i,
        repeatability_up_at=r_up_i, repeatability_down_at=r_down_i, repeatability_at=r_i,
        reversal=float(np.max(np.abs(b_i))), mean_reversal=float(np.mean(b_i)),
        repeatability_up=float(np.max(r_up_i)), repeatability_down=float(np.max(r_down_i)),
        repeatability=float(np.max(r_i)),
        systematic_up=float(np.ptp(mean_up)), systematic_down=float(np.ptp(mean_down)),
        systematic=float(np.max(both_mean) - np.min(both_mean)),
        mean_range=float(np.ptp(mean)),
        accuracy_up=float(np.max(mean_up + 2.0 * s_up) - np.min(mean_up - 2.0 * s_up)),
        accuracy_down=float(np.max(mean_down + 2.0 * s_down)
                            - np.min(mean_down - 2.0 * s_down)),
        accuracy=float(np.max(hi) - np.min(lo)))


@dataclass(frozen=True)
class Stop:
    """One commanded stop of a test cycle.

    Parameters
    ----------
    position : float
        Where the axis is sent [m].
    target : int
        Index i of the target, or −1 for a reversal point beyond a target (not read).
    direction : int
        +1 (↑, approached from below) or −1 (↓); 0 for a reversal point.
    cycle : int
        Index j of the approach (0-based) for that target and direction.
    """

    position: float
    target: int
    direction: int
    cycle: int


def positioning_cycle(targets: ArrayLike, cycles: int = MIN_CYCLES, *, kind: str = "linear",
               overshoot: float = 2e-3) -> list[Stop]:
    """The stops of an ISO 230-2 test cycle, each target approached ``cycles`` times each way.

    ``"linear"`` (the standard test cycle): from P_1 − overshoot, up through every target to
    P_m, on to P_m + overshoot, back down through every target to P_1 and to P_1 − overshoot;
    ``cycles`` times.  ``"pilgrim"`` (the pilgrim-step cycle): target by target, ``cycles``
    approaches from P_i − overshoot, then ``cycles`` from P_i + overshoot.

    Parameters
    ----------
    targets : array_like
        Target positions, increasing [m].
    cycles : int, default 5
        Approaches per target and direction (at least 5).
    kind : str, default "linear"
        ``"linear"`` or ``"pilgrim"``.
    overshoot : float, default 2e-3
        How far beyond a target the axis reverses [m].

    Returns
    -------
    list of Stop
        The stops in order, the first one the start.

    Raises
    ------
    ParameterError
        For fewer than 5 cycles, fewer than 2 or non-increasing targets, an unknown kind or an
        overshoot ≤ 0.
    """
    p = np.asarray(targets, dtype=float)
    if isinstance(cycles, bool) or int(cycles) != cycles or cycles < MIN_CYCLES:
        raise ParameterError("cycles", cycles, f"expected at least {MIN_CYCLES} (ISO 230-2: "
                             "five approaches per target and direction)")
    if p.ndim != 1 or p.size < 2 or not np.all(np.isfinite(p)) or np.any(np.diff(p) <= 0):
        raise ParameterError("targets", p.tolist(), "expected at least 2 increasing positions")
    if not (math.isfinite(overshoot) and overshoot > 0.0):
        raise ParameterError("overshoot", overshoot, "expected a distance > 0 [m]")
    stops: list[Stop] = []
    m = p.size
    if kind == "linear":
        stops.append(Stop(float(p[0] - overshoot), -1, 0, 0))
        for j in range(int(cycles)):
            stops += [Stop(float(p[i]), i, 1, j) for i in range(m)]
            stops.append(Stop(float(p[-1] + overshoot), -1, 0, 0))
            stops += [Stop(float(p[i]), i, -1, j) for i in reversed(range(m))]
            stops.append(Stop(float(p[0] - overshoot), -1, 0, 0))
    elif kind == "pilgrim":
        stops.append(Stop(float(p[0] - overshoot), -1, 0, 0))
        for i in range(m):
            for direction in (1, -1):
                for j in range(int(cycles)):
                    if stops[-1].position != p[i] - direction * overshoot:
                        stops.append(Stop(float(p[i] - direction * overshoot), -1, 0, 0))
                    stops.append(Stop(float(p[i]), i, direction, j))
                    if j < cycles - 1:
                        stops.append(Stop(float(p[i] - direction * overshoot), -1, 0, 0))
    else:
        raise ParameterError("kind", kind, "expected 'linear' or 'pilgrim'")
    return stops


def read_approaches(time: ArrayLike, position: ArrayLike, stops: Sequence[Stop],
                    stop_times: ArrayLike, dwell: float, targets: ArrayLike
                    ) -> tuple[np.ndarray, np.ndarray]:
    """The deviations x_ij↑, x_ij↓ of a run of :func:`positioning_cycle` from its position trace.

    At each stop the actual position is the mean of the trace over the last
    ``READ_FRACTION`` (a quarter) of the dwell (the axis at rest, as the standard reads it):
    the time average of the trace's piecewise-linear interpolant between the window's first
    and last samples, so that where the axis still moves while read the reading converges as
    the output interval shrinks (the plain mean of the samples weighs the window's ends by
    the sampling's phase; an outside check, 2026-12-07).

    Parameters
    ----------
    time : array_like
        Sample times of the trace [s].
    position : array_like
        Actual position, in the targets' frame [m].
    stops : sequence of Stop
        The cycle's stops.
    stop_times : array_like
        When each stop's dwell ends [s].
    dwell : float
        The dwell at each stop [s].
    targets : array_like
        The target positions [m].

    Returns
    -------
    tuple of numpy.ndarray
        Deviations of the positive and of the negative approaches, shape (m, n) [m].

    Raises
    ------
    ValueError
        When a reading window holds no sample.
    """
    t = np.asarray(time, dtype=float)
    x = np.asarray(position, dtype=float)
    p = np.asarray(targets, dtype=float)
    ends = np.asarray(stop_times, dtype=float)
    n = 1 + max(s.cycle for s in stops)
    up = np.full((p.size, n), np.nan)
    down = np.full((p.size, n), np.nan)
    for s, end in zip(stops, ends, strict=True):
        if s.target < 0:
            continue
        window = _reading_window(t, s, end, dwell)
        (up if s.direction > 0 else down)[s.target, s.cycle] = _window_mean(t, x, window) \
            - p[s.target]
    return up, down


def _window_mean(t: np.ndarray, x: np.ndarray, window: np.ndarray) -> float:
    """The time average of the linear interpolant of ``x(t)`` between the first and the last
    sample of ``window`` (no value from outside it: after the window's end the next move
    starts), or the sample itself when it holds one."""
    tt, xx = t[window], x[window]
    if tt.size < 2 or tt[-1] <= tt[0]:
        return float(np.mean(xx))
    return float(np.sum(0.5 * (xx[1:] + xx[:-1]) * np.diff(tt)) / (tt[-1] - tt[0]))


def _reading_window(t: np.ndarray, stop: Stop, end: float, dwell: float) -> np.ndarray:
    window = (t >= end - READ_FRACTION * dwell - 1e-12) & (t <= end + 1e-12)
    if not window.any():
        raise ValueError(f"no sample in the reading window {end - READ_FRACTION * dwell:g}"
                         f" … {end:g} s of the stop at {stop.position * 1e3:g} mm")
    return window


def reading_motion(time: ArrayLike, position: ArrayLike, stops: Sequence[Stop],
                   stop_times: ArrayLike, dwell: float) -> float:
    """The largest peak-to-peak motion of the axis within a reading window of
    :func:`read_approaches`: how far the axis is from rest while it is read.

    ISO 230-2 reads each target with the axis at rest; a reading taken while the axis still
    rings after the move measures the ringing's phase, not the position (issue 37: a 0.3-s
    dwell on ``wang2021-drive`` read a 5.5-Hz servo mode mid-swing and gave B = 273 µm).

    Parameters
    ----------
    time : array_like
        Sample times of the trace [s].
    position : array_like
        Actual position [m].
    stops : sequence of Stop
        The cycle's stops.
    stop_times : array_like
        When each stop's dwell ends [s].
    dwell : float
        The dwell at each stop [s].

    Returns
    -------
    float
        max over the measured stops of (max − min) of the position in the window [m].
    """
    t = np.asarray(time, dtype=float)
    x = np.asarray(position, dtype=float)
    motion = [float(np.ptp(x[_reading_window(t, s, end, dwell)]))
              for s, end in zip(stops, np.asarray(stop_times, dtype=float), strict=True)
              if s.target >= 0]
    return max(motion, default=0.0)


def describe(result: PositioningTest) -> list[str]:
    """The result as text lines (mm, µm), as ``feeddrive positioning`` and ``analyze
    --positioning`` print it.

    Parameters
    ----------
    result : PositioningTest
        The evaluation.

    Returns
    -------
    list of str
        A table per target, then one line per quantity of the axis
        (:attr:`PositioningTest.AXIS_QUANTITIES`).
    """
    um = 1e6
    lines = ["ISO 230-2, per target [µm]: x̄↑ x̄↓ x̄ B_i s↑ s↓ R↑ R↓ R_i",
             f"  {'P_i [mm]':>12} {'x̄↑':>9} {'x̄↓':>9} {'x̄':>9} {'B_i':>9} {'s↑':>9} "
             f"{'s↓':>9} {'R↑':>9} {'R↓':>9} {'R_i':>9}"]
    for i, p in enumerate(result.targets):
        values = (result.mean_up[i], result.mean_down[i], result.mean[i],
                  result.reversal_at[i], result.s_up[i], result.s_down[i],
                  result.repeatability_up_at[i], result.repeatability_down_at[i],
                  result.repeatability_at[i])
        lines.append(f"  {p * 1e3:12.6g} " + " ".join(f"{v * um:9.4f}" for v in values))
    lines.append(f"ISO 230-2, the axis ({result.deviation_up.shape[1]} approaches per target "
                 "and direction)")
    for name, (symbol, label) in result.AXIS_QUANTITIES.items():
        lines.append(f"  {symbol:<3} {float(getattr(result, name)) * um:10.4f} µm  {label}")
    return lines
