"""ISO 230-4 circular test: circular deviations and the ballbar diagnostics of an XY trace.  SI.

A circular test drives two axes round a circle, once counter-clockwise (CCW) and once
clockwise (CW), and reads the path's deviation from the nominal circle (ISO 230-4:2005 [1]_).
This module takes a measured or simulated trace (time, x, y), finds its full revolutions,
and computes

- the quantities of ISO 230-4:2005, Clause 3 (terms and definitions): the circular deviation
  G(CW), G(CCW) of each run, the bidirectional circular deviation G(b) of both runs together,
  the mean bidirectional radial deviation (the mean radius deviation) and the radial deviation
  F (F_max, F_min) about the nominal centre;
- the ballbar diagnostics read by machine-tool engineers (the Renishaw QC10/QC20 analysis
  ([2]_): squareness, scale mismatch, servo mismatch, backlash and lateral play per axis, cyclic
  error per axis when the screw's pitch is given, and the reversal spike's height and width at
  each of the four axis reversals of each run.

Every diagnostic is the amplitude of one physical error's signature in the radial deviation,
fitted by linear least squares to both runs at once (as the ballbar analysis fits its error
model, [2]_), with the reversal spikes read from the residual (the samples right after each
reversal are left out of the fit while a spike is found there).  The signatures are derived in
docs/acceptance-tests.md, each from the error applied to the axes' positions; for an error e_x
of the X axis and e_y of the Y axis the radial deviation at the path angle θ is
δ = e_x·cos θ + e_y·sin θ (first order in e/R).

References
----------
.. [1] ISO 230-4:2005, Test code for machine tools — Part 4: Circular tests for numerically
       controlled machine tools, Clause 3 (terms and definitions), and its test procedure
       (CW and CCW runs, feed, radius, the lead-in and lead-out arcs left out; that clause's
       number not checked here).
.. [2] Renishaw plc, QC20-W ballbar system, Ballbar 20 software help (2009): the diagnostics
       squareness [µm/m], scale mismatch [µm], servo mismatch [ms], backlash [µm], lateral play
       [µm], cyclic error [µm] and reversal spikes [µm]; cited in Jiang & Cripps (2013),
       "Characterisation of geometric errors in 5-axis machine tools using double ball bar
       system", IMC 30.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..parameters import ParameterError
from ..parameters.validation import is_real, real_array

__all__ = ["CircularRun", "CircularTest", "ReversalSpike", "circular_test", "describe",
           "fit_circle", "split_runs"]

#: window after each axis reversal searched for the reversal spike [rad]
SPIKE_WINDOW = math.radians(45.0)
#: a spike's excluded region ends where its residual has fallen below this fraction of its peak
SPIKE_TAIL = 0.02
#: samples farther than this fraction of R from the nominal circle are no part of the test
#: (a radial approach from the centre).  It must lie well above any deviation the test
#: measures: at 1 % it cut the reversal spikes of a 5-mm circle on ``wang2021-drive``
#: (46.2 µm read, 52.8 µm at 2 %, issue 37 item 4); the runs themselves are the stretches
#: that turn one way (:func:`split_runs`), which a radial approach never does
OFF_CIRCLE = 0.1
#: with no nominal circle given, the least-squares circle is fitted to the samples within
#: this fraction of R of it (iterated), which keeps a radial approach's last samples out of it
ON_CIRCLE = 0.01
#: smallest spike height [m] that excludes its region from the fit (below: measurement noise)
SPIKE_FLOOR = 1e-9
#: a stretch of the trace ends (a run's direction reverses) where the angle about the centre
#: turns back by more than this [rad]; a smaller turn back — stick-slip at a low feed, where
#: the path stops and slips back by a fraction of a micrometre (≈ 2e-4° at 100 mm/min on
#: the ``xy-table``) — stays in its run.  The quantities do not depend on it between the
#: largest such turn back and the lead arcs (tests/unit/test_circular_stick_slip.py)
REVERSAL = math.radians(1.0)
_AXIS_OF_REVERSAL = ("x", "y", "x", "y")  # axis reversing at θ = 0°, 90°, 180°, 270°


@dataclass(frozen=True, repr=False)
class CircularRun:
    """One full revolution of a circular test, about the nominal centre.

    Parameters
    ----------
    direction : str
        ``"CCW"`` or ``"CW"``.
    time : numpy.ndarray
        Sample times [s].
    x, y : numpy.ndarray
        Measured positions [m].
    angle : numpy.ndarray
        Travel angle from the nominal centre, unwrapped, advancing along the run (turns back
        smaller than ``REVERSAL`` aside: stick-slip) [rad].
    """

    direction: str
    time: np.ndarray
    x: np.ndarray
    y: np.ndarray
    angle: np.ndarray

    @property
    def sign(self) -> int:
        """+1 for CCW, −1 for CW [-]."""
        return 1 if self.direction == "CCW" else -1

    def __repr__(self) -> str:
        # one line: the dataclass' repr printed its four arrays (an outside check, 2026-12-07)
        t = self.time
        span = f", {float(t[0]):.6g} … {float(t[-1]):.6g} s" if t.size else ""
        return f"<feeddrive CircularRun {self.direction}: {t.size} samples{span}>"


@dataclass(frozen=True)
class ReversalSpike:
    """The reversal spike after one axis reversal (radial residual of the error model).

    Parameters
    ----------
    direction : str
        The run, ``"CCW"`` or ``"CW"``.
    angle : float
        Where the axis reverses: 0, 90, 180 or 270 [°].
    axis : str
        The axis that reverses there, ``"x"`` or ``"y"``.
    height : float
        Signed peak of the residual within 45° after the reversal; > 0 outwards [m].
    width : float
        Angle over which the residual stays above half the peak [°].
    width_length : float
        The same width as path length R·Δθ [m].
    peak_angle : float
        Where the peak lies, travel after the reversal [°].
    before : float, default 0.0
        The residual's largest magnitude in the 45° before the reversal [m].
    stands_out : bool, default True
        Whether the peak stands out of that (above ``SPIKE_FLOOR`` and three times
        ``before``).  When it does not, the path deviates as much between the reversals (at
        a low feed: stick-slip or a sustained oscillation) and the height is the residual's
        largest within 45° after the reversal, not a reversal transient; it then depends on
        that window.
    """

    direction: str
    angle: float
    axis: str
    height: float
    width: float
    width_length: float
    peak_angle: float
    before: float = 0.0
    stands_out: bool = True

    def to_dict(self) -> dict[str, Any]:
        """JSON form, in µm, mm and degrees.

        Returns
        -------
        dict
            ``height_um``, ``width_deg``, ``width_mm``, ``peak_after_deg``, ``before_um``,
            ``stands_out`` and the labels.
        """
        return {"direction": self.direction, "angle_deg": self.angle, "axis": self.axis,
                "height_um": self.height * 1e6, "width_deg": self.width,
                "width_mm": self.width_length * 1e3, "peak_after_deg": self.peak_angle,
                "before_um": self.before * 1e6, "stands_out": self.stands_out}


@dataclass(frozen=True, repr=False)
class CircularTest:
    """Result of :func:`circular_test`.  SI: lengths [m], angles of diagnostics [rad].

    Parameters
    ----------
    radius : float
        Nominal radius R [m].
    centre : tuple of float
        Nominal centre (x, y) [m].
    runs : tuple of CircularRun
        The revolutions analysed (CCW first when both are present).
    circular_deviation : dict
        G(CCW), G(CW) by run direction: radial span about each run's least-squares circle [m]
        (ISO 230-4:2005, Clause 3, circular deviation G).
    bidirectional_circular_deviation : float or None
        G(b): radial span of both runs about the least-squares circle of both [m]; None with
        one run (ISO 230-4:2005, Clause 3).
    mean_radius_deviation : float
        Mean of the runs' least-squares radii minus R [m] (ISO 230-4:2005, Clause 3, mean
        bidirectional radial deviation; one run: that run's).
    radius_deviation : dict
        Each run's least-squares radius minus R [m].
    radial_deviation_max, radial_deviation_min : float
        F: largest and smallest distance from the nominal centre minus R over all runs [m]
        (ISO 230-4:2005, Clause 3, radial deviation F, centre as set up).
    feed : float
        Mean path speed of the runs [m/s].
    squareness : float
        Angle by which the Y axis leans towards +X (the axes' angle 90° − squareness) [rad]
        (reported in µm/m).
    scale_mismatch : float
        R·(s_x − s_y), s the axes' scale errors [m] (reported in µm).
    servo_mismatch : float or None
        τ_x − τ_y, the X axis's lag minus the Y axis's [s]; None with one run.
    backlash : dict
        Lost motion b per axis [m]: the axis trails its command by b/2 in its direction of
        motion.
    lateral_play : dict or None
        Sideways shift per axis [m]: the other axis's position changes by this when the axis
        reverses; None with one run.
    cyclic_error : dict or None
        Amplitude of a sinusoidal error of period ``pitch`` per axis [m]; None without pitch.
    pitch : float or None
        The period looked for [m].
    spikes : tuple of ReversalSpike
        Four per run.
    residual_rms : float
        RMS of the error model's residual outside the spike regions [m].
    notes : tuple of str
        What was inferred or left out.
    """

    radius: float
    centre: tuple[float, float]
    runs: tuple[CircularRun, ...]
    circular_deviation: dict[str, float]
    bidirectional_circular_deviation: float | None
    mean_radius_deviation: float
    radius_deviation: dict[str, float]
    radial_deviation_max: float
    radial_deviation_min: float
    feed: float
    squareness: float
    scale_mismatch: float
    servo_mismatch: float | None
    backlash: dict[str, float]
    lateral_play: dict[str, float] | None
    cyclic_error: dict[str, float] | None
    pitch: float | None
    spikes: tuple[ReversalSpike, ...]
    residual_rms: float
    notes: tuple[str, ...] = field(default=())

    def __repr__(self) -> str:
        # one line: the dataclass' repr ran to ≈ 3600 characters, the runs' arrays among them
        # (an outside check, 2026-12-07); describe() gives every quantity
        return (f"<feeddrive CircularTest R {self.radius * 1e3:.6g} mm, runs "
                f"{','.join(r.direction for r in self.runs)}, feed {self.feed * 6e4:.6g} "
                f"mm/min: {deviations(self)}>")

    def to_dict(self) -> dict[str, Any]:
        """JSON form in the CLI's units: µm, mm, mm/min, µm/m, ms.

        Returns
        -------
        dict
            Every quantity, keys naming the unit.
        """
        um = 1e6

        def per_axis(d: dict[str, float] | None) -> dict[str, float] | None:
            return None if d is None else {k: v * um for k, v in d.items()}

        return {
            "radius_mm": self.radius * 1e3,
            "centre_mm": [c * 1e3 for c in self.centre],
            "runs": [r.direction for r in self.runs],
            "feed_mm_min": self.feed * 6e4,
            "circular_deviation_um": {k: v * um for k, v in self.circular_deviation.items()},
            "bidirectional_circular_deviation_um": (
                None if self.bidirectional_circular_deviation is None
                else self.bidirectional_circular_deviation * um),
            "mean_radius_deviation_um": self.mean_radius_deviation * um,
            "radius_deviation_um": {k: v * um for k, v in self.radius_deviation.items()},
            "radial_deviation_max_um": self.radial_deviation_max * um,
            "radial_deviation_min_um": self.radial_deviation_min * um,
            "squareness_um_per_m": self.squareness * 1e6,
            "scale_mismatch_um": self.scale_mismatch * um,
            "servo_mismatch_ms": None if self.servo_mismatch is None
            else self.servo_mismatch * 1e3,
            "backlash_um": per_axis(self.backlash),
            "lateral_play_um": per_axis(self.lateral_play),
            "cyclic_error_um": per_axis(self.cyclic_error),
            "pitch_mm": None if self.pitch is None else self.pitch * 1e3,
            "reversal_spikes": [s.to_dict() for s in self.spikes],
            "residual_rms_um": self.residual_rms * um,
            "notes": list(self.notes),
        }


def fit_circle(x: ArrayLike, y: ArrayLike, *, start: tuple[float, float] | None = None
               ) -> tuple[float, float, float]:
    """Least-squares circle: the centre and radius minimising Σ (r_i − r)² (geometric fit).

    Gauss–Newton from the algebraic (Kåsa) fit or ``start``; the ISO 230-4 least-squares
    circle.

    Parameters
    ----------
    x, y : array_like
        Points of the path [m].
    start : tuple of float, optional
        Initial centre [m].

    Returns
    -------
    tuple of float
        Centre x, centre y, radius [m].
    """
    px = np.asarray(x, dtype=float)
    py = np.asarray(y, dtype=float)
    # work about the points' mean: the normal equations then stay well conditioned far from 0
    mx, my = float(px.mean()), float(py.mean())
    u, v = px - mx, py - my
    if start is None:
        a = np.column_stack([u, v, np.ones_like(u)])
        sol = np.linalg.lstsq(a, u * u + v * v, rcond=None)[0]
        cx, cy = sol[0] / 2.0, sol[1] / 2.0
    else:
        cx, cy = start[0] - mx, start[1] - my
    for _ in range(50):
        du, dv = u - cx, v - cy
        r = np.hypot(du, dv)
        rm = float(r.mean())
        jac = np.column_stack([-du / r, -dv / r, -np.ones_like(r)])
        step = np.linalg.lstsq(jac, -(r - rm), rcond=None)[0]
        cx += step[0]
        cy += step[1]
        if math.hypot(step[0], step[1]) < 1e-15 * max(rm, 1e-300):
            break
    r = np.hypot(u - cx, v - cy)
    return cx + mx, cy + my, float(r.mean())


def _turning_points(phi: np.ndarray, reversal: float) -> list[int]:
    """Where the angle ``phi`` turns back by more than ``reversal`` [rad]: the record's
    start, each such turning point (the extreme before the turn) and its end — a zigzag
    with hysteresis over the samples where the raw motion changes sign."""
    step = np.diff(phi)
    moving = np.flatnonzero(step != 0.0)
    flips = moving[1:][np.sign(step[moving[1:]]) != np.sign(step[moving[:-1]])]
    cand = np.concatenate([[0], flips, [phi.size - 1]])
    value = phi[cand]
    turns = [0]
    direction = 0
    hi = lo = ext = 0
    for i in range(1, cand.size):
        v = value[i]
        if direction == 0:
            hi = i if v > value[hi] else hi
            lo = i if v < value[lo] else lo
            if value[hi] - value[lo] > reversal:
                direction = 1 if hi > lo else -1
                ext = hi if direction > 0 else lo
        elif (v - value[ext]) * direction >= 0.0:
            ext = i
        elif (value[ext] - v) * direction > reversal:
            turns.append(int(cand[ext]))
            direction, ext = -direction, i
    if turns[-1] != phi.size - 1:
        turns.append(phi.size - 1)
    return turns


def _no_revolution(phi: np.ndarray, reversal: float) -> str:
    """Why no run was found: the turns back (when a larger reversal angle would find one)
    or the record itself."""
    wide = _turning_points(phi, math.radians(359.0))
    for k, j in zip(wide[:-1], wide[1:], strict=True):
        sign = 1.0 if phi[j] > phi[k] else -1.0
        if abs(phi[j] - phi[k]) >= 2.0 * math.pi * (1.0 - 1e-9):
            travel = (phi[k:j + 1] - phi[k]) * sign
            back = float(np.max(np.maximum.accumulate(travel) - travel))
            return (f"no full revolution about the centre one way: the path turns 360° but "
                    f"turns back inside by up to {math.degrees(back):.3g}°, more than the "
                    f"reversal angle {math.degrees(reversal):.3g}° that ends a run (stick-slip "
                    "at a low feed?); a larger --reversal-angle keeps such turns back in the "
                    "run")
    return ("no full revolution about the centre: a circular test needs at least 360° "
            "turned one way (check --centre and the x, y columns)")


def split_runs(time: ArrayLike, x: ArrayLike, y: ArrayLike, centre: tuple[float, float],
               *, reversal: float = REVERSAL) -> tuple[list[CircularRun], list[str]]:
    """The full revolutions of a trace: one per stretch of one turning direction.

    A stretch turning one way about the centre for at least 360° gives one run: its middle
    360° (the lead-in and lead-out arcs of the ISO 230-4 test procedure are left out equally
    at both ends).  A stretch ends where the angle turns back by more than ``reversal``; a
    smaller turn back (stick-slip at a low feed: the path stops and slips back by a fraction
    of a micrometre) stays inside its run, and a note counts them and gives the largest.

    Parameters
    ----------
    time : array_like
        Sample times, increasing [s].
    x, y : array_like
        Positions [m].
    centre : tuple of float
        Nominal centre [m].
    reversal : float, default ``REVERSAL`` (1°)
        Smallest turn back that ends a stretch [rad].

    Returns
    -------
    runs : list of CircularRun
        CCW first, then CW; one of each at most (the first of each direction).
    notes : list of str
        What was left out, and the turns back inside each run.

    Raises
    ------
    ValueError
        When no stretch covers a full revolution.
    ParameterError
        For a ``reversal`` that is not an angle in (0, 2π).
    """
    if not (is_real(reversal) and 0.0 < reversal < 2.0 * math.pi):  # True was 1 rad
        raise ParameterError("reversal", reversal, "expected a turn-back angle > 0 and "
                             "< 2π [rad]")
    t = np.asarray(time, dtype=float)
    px = np.asarray(x, dtype=float)
    py = np.asarray(y, dtype=float)
    phi = np.unwrap(np.arctan2(py - centre[1], px - centre[0]))
    radius = float(np.median(np.hypot(px - centre[0], py - centre[1])))
    turns = _turning_points(phi, reversal)
    notes: list[str] = []
    runs: dict[str, CircularRun] = {}
    for k, j in zip(turns[:-1], turns[1:], strict=True):
        sign = 1.0 if phi[j] > phi[k] else -1.0
        span = abs(phi[j] - phi[k])
        direction = "CCW" if sign > 0 else "CW"
        if span < 2.0 * math.pi * (1.0 - 1e-9):
            continue
        if direction in runs:
            notes.append(f"a further {direction} revolution at t = {t[k]:.4g} s left out")
            continue
        travel = (phi[k:j + 1] - phi[k]) * sign
        reached = np.maximum.accumulate(travel)
        lead = (span - 2.0 * math.pi) / 2.0
        a = int(np.searchsorted(reached, lead, side="left"))
        b = int(np.searchsorted(reached, lead + 2.0 * math.pi, side="right"))
        sl = slice(k + a, k + b)
        runs[direction] = CircularRun(direction=direction, time=t[sl], x=px[sl], y=py[sl],
                                      angle=phi[sl])
        if lead > 1e-6:
            notes.append(f"{direction}: {math.degrees(lead):.3g}° of lead-in and of "
                         "lead-out left out (ISO 230-4 test procedure)")
        back = reached[a:b] - travel[a:b]
        if np.any(back > 0.0):
            started = np.count_nonzero((back[1:] > 0.0) & (back[:-1] == 0.0)) + int(back[0] > 0)
            largest = float(back.max())
            notes.append(f"{direction}: the path turned back {started} times inside the run "
                         f"(stick-slip), by at most {math.degrees(largest):.3g}° "
                         f"({largest * radius * 1e6:.3g} µm along the path); a run ends "
                         f"only where it turns back more than {math.degrees(reversal):.3g}°")
    if not runs:
        raise ValueError(_no_revolution(phi, reversal))
    ordered = [runs[d] for d in ("CCW", "CW") if d in runs]
    return ordered, notes


def _columns(theta: np.ndarray, d: np.ndarray, run: np.ndarray, nruns: int,
             both: bool, pitch: float | None, xs: np.ndarray, ys: np.ndarray,
             radius: float, omega: float) -> tuple[np.ndarray, list[str]]:
    """Signatures of the error model in the radial deviation (docs/acceptance-tests.md)."""
    c, s = np.cos(theta), np.sin(theta)
    cols: list[np.ndarray] = []
    names: list[str] = []
    for k in range(nruns):  # each run's radius (servo lag shrinks the circle per direction)
        cols.append((run == k).astype(float))
        names.append(f"radius{k}")
    cols += [c, s]
    names += ["centre_x", "centre_y"]
    # squareness α (Y leans towards +X): e_x = α·y  →  δ = α·R·sin2θ/2
    cols.append(radius * np.sin(2 * theta) / 2.0)
    names.append("squareness")
    # scale mismatch m = R(s_x − s_y): δ = R(s_x + s_y)/2 + m·cos2θ/2
    cols.append(np.cos(2 * theta) / 2.0)
    names.append("scale_mismatch")
    # backlash b (axis trails by b/2 in its direction of motion): e_x = −sign(ẋ)·b/2,
    # sign(ẋ) = −d·sign(sin θ), sign(ẏ) = d·sign(cos θ)
    cols.append(d * np.sign(s) * c / 2.0)
    names.append("backlash_x")
    cols.append(-d * np.sign(c) * s / 2.0)
    names.append("backlash_y")
    if both:
        # servo mismatch Δτ = τ_x − τ_y: δ = d·R·ω·Δτ·sin2θ/2
        cols.append(d * radius * omega * np.sin(2 * theta) / 2.0)
        names.append("servo_mismatch")
        # lateral play l of X (Y shifts by sign(ẋ)·l/2): δ = −d·|sin θ|·l/2; of Y likewise
        cols.append(-d * np.abs(s) / 2.0)
        names.append("lateral_play_x")
        cols.append(d * np.abs(c) / 2.0)
        names.append("lateral_play_y")
    if pitch is not None:
        # cyclic error e_x = a·sin(2πx/p) + b·cos(2πx/p)
        for axis, pos, proj in (("x", xs, c), ("y", ys, s)):
            w = 2.0 * math.pi * pos / pitch
            cols += [proj * np.sin(w), proj * np.cos(w)]
            names += [f"cyclic_{axis}_sin", f"cyclic_{axis}_cos"]
    return np.column_stack(cols), names


def _spike(residual: np.ndarray, travel: np.ndarray, radius: float
           ) -> tuple[float, float, float, float, int, int]:
    """Peak, width [°], peak position [°] and the excluded sample range of one window."""
    if residual.size == 0:
        return 0.0, 0.0, 0.0, 0.0, 0, 0
    k = int(np.argmax(np.abs(residual)))
    peak = float(residual[k])
    half = np.abs(residual) >= abs(peak) / 2.0
    lo = k
    while lo > 0 and half[lo - 1]:
        lo -= 1
    hi = k
    while hi < residual.size - 1 and half[hi + 1]:
        hi += 1
    width = float(travel[hi] - travel[lo])
    tail = k
    while tail < residual.size - 1 and abs(residual[tail]) > SPIKE_TAIL * abs(peak):
        tail += 1
    end = min(residual.size, int(np.searchsorted(travel, 1.5 * travel[tail], side="right")))
    return peak, math.degrees(width), width * radius, math.degrees(float(travel[k])), 0, end


def circular_test(time: ArrayLike, x: ArrayLike, y: ArrayLike, *, radius: float | None,
                  centre: tuple[float, float] | None, pitch: float | None = None,
                  reversal: float = REVERSAL) -> CircularTest:
    """ISO 230-4 quantities and the ballbar diagnostics of a circular-test trace.

    Parameters
    ----------
    time : array_like
        Sample times, increasing [s].
    x, y : array_like
        Measured (or simulated) positions of the two axes [m]; one CCW and/or one CW
        revolution of at least 360° each, lead-in and lead-out arcs allowed.
    radius : float or None
        Nominal radius R [m]; None: the least-squares radius of the whole record (the mean
        radius deviation is then about 0 by construction; a note says so).
    centre : tuple of float or None
        Nominal centre (x, y) [m]; None: the least-squares centre of the whole record (noted).
    pitch : float, optional
        Period of the cyclic error looked for (the screw's lead) [m]; None: not fitted.
    reversal : float, default ``REVERSAL`` (1°)
        Smallest turn back of the angle about the centre that ends a run [rad]
        (:func:`split_runs`); smaller ones (stick-slip) stay in their run.

    Returns
    -------
    CircularTest
        The quantities, SI.

    Raises
    ------
    ParameterError
        For a bad radius, centre or pitch, or a trace that is not a circle of that radius.
    ValueError
        For arrays of different lengths or a trace without a full revolution.

    Notes
    -----
    G is the radial span about the least-squares circle (:func:`fit_circle`): of each run
    for G(CW), G(CCW); of both runs' points together for G(b) (ISO 230-4:2005, Clause 3).
    The quantities are those of ISO 230-4 [1]_; the diagnostics, named as the ballbar
    software names them [2]_, are the least-squares amplitudes of the signatures of
    docs/acceptance-tests.md in the radial deviation about the least-squares centre of both
    runs; a reversal spike is the residual's signed peak within 45° after the reversal, its
    width the angle over which it stays above half its peak, and while a spike stands out of
    the residual (above 1 nm and three times the largest residual in the 45° before the
    reversal) its region, to where it falls below 2 % of its peak (× 1.5),
    is left out of the fit.

    References
    ----------
    .. [1] ISO 230-4:2005, Clauses 3 and 5.
    .. [2] Renishaw plc, QC20-W ballbar system, Ballbar 20 software help (2009).

    Examples
    --------
    A perfect CCW circle of 50 mm has no deviation:

    >>> import numpy as np
    >>> from feeddrive.analysis.circular import circular_test
    >>> a = np.linspace(0.0, 2 * np.pi, 3601)
    >>> res = circular_test(a, 0.05 * np.cos(a), 0.05 * np.sin(a), radius=0.05,
    ...                     centre=(0.0, 0.0))
    >>> print(f"G(CCW) = {res.circular_deviation['CCW'] * 1e6:.3f} µm")
    G(CCW) = 0.000 µm
    """
    # a str or a bare number was Python's TypeError ("must be real number, not str", "object
    # of type 'int' has no len()": an API sweep of session 29)
    if radius is not None and not (is_real(radius) and math.isfinite(radius) and radius > 0):
        raise ParameterError("radius", radius, "expected a radius > 0 [m]")
    if centre is not None and (isinstance(centre, str) or not hasattr(centre, "__len__")
                               or len(centre) != 2
                               or not all(is_real(c) and math.isfinite(c) for c in centre)):
        raise ParameterError("centre", centre, "expected two finite coordinates [m]")
    if pitch is not None and not (is_real(pitch) and math.isfinite(pitch) and pitch > 0):
        raise ParameterError("pitch", pitch, "expected a period > 0 [m]")
    t = real_array("time", time, "s")
    px = real_array("x", x, "m")
    py = real_array("y", y, "m")
    if not (t.shape == px.shape == py.shape and t.ndim == 1):
        raise ValueError("time, x, y: expected 1-D arrays of one length")
    if t.size < 16 or not (np.all(np.isfinite(t)) and np.all(np.isfinite(px))
                           and np.all(np.isfinite(py))):
        raise ValueError("time, x, y: expected at least 16 finite samples")
    back = np.flatnonzero(np.diff(t) < 0)
    if back.size:  # a reversed record was measured at a negative feed (session 29)
        i = int(back[0]) + 1
        raise ParameterError(f"time[{i}]", float(t[i]), f"expected increasing sample times "
                             f"[s] (time[{i - 1}] = {float(t[i - 1])!r})")
    inferred: list[str] = []
    if centre is None or radius is None:
        # fitted to the samples near the circle: a radial approach from the centre left out
        d = np.hypot(px - np.mean(px), py - np.mean(py))
        near = np.abs(d - np.median(d)) <= 0.2 * np.median(d)
        fx, fy, fr = fit_circle(px[near], py[near])
        for _ in range(3):  # then those within ON_CIRCLE of the fitted circle
            near = np.abs(np.hypot(px - fx, py - fy) - fr) <= ON_CIRCLE * fr
            fx, fy, fr = fit_circle(px[near], py[near], start=(fx, fy))
        if centre is None:
            centre = (fx, fy)
            inferred.append(f"centre ({fx * 1e3:.6g}, {fy * 1e3:.6g}) mm inferred: the "
                            "least-squares centre of the record")
        if radius is None:
            radius = fr
            inferred.append(f"radius {fr * 1e3:.6g} mm inferred: the least-squares radius of "
                            "the record, so the mean radius deviation is about 0 by "
                            "construction")
    cx0, cy0 = float(centre[0]), float(centre[1])
    r_all = np.hypot(px - cx0, py - cy0)
    on = np.abs(r_all - radius) <= OFF_CIRCLE * radius
    if np.count_nonzero(on) < max(16, t.size // 2):
        raise ParameterError("radius", radius, f"the trace lies {r_all.min():.6g} … "
                             f"{r_all.max():.6g} m from the centre, mostly not within "
                             f"{OFF_CIRCLE:.0%} of that radius; check --radius, --centre and "
                             "the units")
    if not on.all():
        inferred.append(f"{t.size - np.count_nonzero(on)} samples farther than "
                        f"{OFF_CIRCLE:.0%} of R from the circle left out (a radial lead-in or "
                        "lead-out)")
        t, px, py = t[on], px[on], py[on]
    runs, notes = split_runs(t, px, py, (cx0, cy0), reversal=reversal)
    notes = inferred + notes
    gee: dict[str, float] = {}
    dr: dict[str, float] = {}
    for r in runs:
        fx, fy, fr = fit_circle(r.x, r.y, start=(cx0, cy0))
        gee[r.direction] = float(np.ptp(np.hypot(r.x - fx, r.y - fy)))
        dr[r.direction] = fr - radius
    ax = np.concatenate([r.x for r in runs])
    ay = np.concatenate([r.y for r in runs])
    bx, by, _ = fit_circle(ax, ay, start=(cx0, cy0))
    both = len(runs) == 2
    g_b = float(np.ptp(np.hypot(ax - bx, ay - by))) if both else None
    if not both:
        notes.append(f"one run ({runs[0].direction}) only: G(b), servo mismatch and lateral "
                     "play need both CW and CCW; squareness then includes any servo mismatch")
    # the net travel: a stick-slip turn back is travelled twice but advances nothing
    feeds = [float(abs(r.angle[-1] - r.angle[0]) * radius / (r.time[-1] - r.time[0]))
             for r in runs]
    feed = float(np.mean(feeds))
    omega = feed / radius

    theta = np.concatenate([np.arctan2(r.y - by, r.x - bx) for r in runs])
    delta = np.hypot(ax - bx, ay - by) - radius
    d = np.concatenate([np.full(r.x.size, r.sign, dtype=float) for r in runs])
    run_index = np.concatenate([np.full(r.x.size, k) for k, r in enumerate(runs)])
    design, names = _columns(theta, d, run_index, len(runs), both, pitch, ax, ay, radius, omega)

    # the four reversals of each run: where the travel passes 0°, 90°, 180°, 270° about the
    # fitted centre, each with the samples of its window
    offsets = np.cumsum([0] + [r.x.size for r in runs])
    # run, angle, samples after the reversal, their travel past it, samples before it
    windows: list[tuple[int, float, np.ndarray, np.ndarray, np.ndarray]] = []
    for k, r in enumerate(runs):
        th = np.unwrap(theta[offsets[k]:offsets[k + 1]])
        for q in range(4):
            base = q * math.pi / 2.0
            rel = (th - base) * r.sign
            # the window may wrap round the run's start: order its samples by travel
            after_all = np.mod(rel, 2 * math.pi)
            idx = np.flatnonzero(after_all <= SPIKE_WINDOW)
            idx = idx[np.argsort(after_all[idx], kind="stable")]
            after = after_all[idx]
            before = np.flatnonzero(after_all >= 2 * math.pi - SPIKE_WINDOW)
            windows.append((k, math.degrees(base), offsets[k] + idx, after,
                            offsets[k] + before))

    keep = np.ones(delta.size, dtype=bool)
    coef = np.zeros(design.shape[1])
    for _ in range(8):
        coef = np.linalg.lstsq(design[keep], delta[keep], rcond=None)[0]
        residual = delta - design @ coef
        new_keep = np.ones(delta.size, dtype=bool)
        for _k, _angle, idx, after, before in windows:
            peak, *_rest, end = _spike(residual[idx], after, radius)
            # a spike stands out after the reversal against the residual just before it
            level = float(np.max(np.abs(residual[before]))) if before.size else 0.0
            if abs(peak) > max(SPIKE_FLOOR, 3.0 * level):
                new_keep[idx[:end]] = False
        if np.array_equal(new_keep, keep):
            break
        keep = new_keep
    residual = delta - design @ coef
    value = dict(zip(names, (float(v) for v in coef), strict=True))
    spikes = []
    for k, angle, idx, after, before in windows:
        peak, width, width_len, peak_at, _, _ = _spike(residual[idx], after, radius)
        level = float(np.max(np.abs(residual[before]))) if before.size else 0.0
        spikes.append(ReversalSpike(direction=runs[k].direction, angle=angle,
                                    axis=_AXIS_OF_REVERSAL[int(round(angle / 90.0)) % 4],
                                    height=peak, width=width, width_length=width_len,
                                    peak_angle=peak_at, before=level,
                                    stands_out=abs(peak) > max(SPIKE_FLOOR, 3.0 * level)))
    hidden = [sp for sp in spikes if not sp.stands_out and abs(sp.height) > SPIKE_FLOOR]
    if hidden:
        # a low feed's stick-slip or hunting: said, not passed off as reversal transients (an
        # outside check, 2026-12-07: at 100 mm/min the "spikes" were an oscillation's peaks)
        notes.append(f"{len(hidden)} of {len(spikes)} reversal spikes do not stand out of "
                     "the residual in the 45° before their reversal (at most 3× its largest, "
                     f"up to {max(sp.before for sp in hidden) * 1e6:.3g} µm): the path "
                     "deviates as much between the reversals (at a low feed, stick-slip or a "
                     "sustained oscillation), so their heights are the residual's largest "
                     "within 45° after the reversal, not reversal transients, and depend on "
                     "that window")
    cyclic = None
    if pitch is not None:
        cyclic = {a: math.hypot(value[f"cyclic_{a}_sin"], value[f"cyclic_{a}_cos"])
                  for a in ("x", "y")}
    radial = np.concatenate([np.hypot(r.x - cx0, r.y - cy0) for r in runs]) - radius
    return CircularTest(
        radius=float(radius), centre=(cx0, cy0), runs=tuple(runs),
        circular_deviation=gee, bidirectional_circular_deviation=g_b,
        mean_radius_deviation=float(np.mean(list(dr.values()))), radius_deviation=dr,
        radial_deviation_max=float(radial.max()), radial_deviation_min=float(radial.min()),
        feed=feed, squareness=value["squareness"], scale_mismatch=value["scale_mismatch"],
        servo_mismatch=value.get("servo_mismatch"),
        backlash={"x": value["backlash_x"], "y": value["backlash_y"]},
        lateral_play=({"x": value["lateral_play_x"], "y": value["lateral_play_y"]}
                      if both else None),
        cyclic_error=cyclic, pitch=pitch, spikes=tuple(spikes),
        residual_rms=float(np.sqrt(np.mean(residual[keep] ** 2))), notes=tuple(notes))


def deviations(result: CircularTest) -> str:
    """The test's circular deviation in a few words: G(b), or each run's G with one run [µm]
    (the one-line reprs of :class:`CircularTest` and of a simulated test's trace).

    Parameters
    ----------
    result : CircularTest
        The analysis.

    Returns
    -------
    str
        E.g. ``"G(b) 12.35 µm"``.
    """
    if result.bidirectional_circular_deviation is not None:
        return f"G(b) {result.bidirectional_circular_deviation * 1e6:.4g} µm"
    return ", ".join(f"G({k}) {v * 1e6:.4g} µm" for k, v in result.circular_deviation.items())


def describe(result: CircularTest) -> list[str]:
    """The result as text lines (µm, mm, mm/min), as ``feeddrive analyze --circular`` prints.

    Parameters
    ----------
    result : CircularTest
        The analysis.

    Returns
    -------
    list of str
        One line per quantity.
    """
    um = 1e6
    lines = [f"circle R = {result.radius * 1e3:.6g} mm about ({result.centre[0] * 1e3:.6g}, "
             f"{result.centre[1] * 1e3:.6g}) mm, runs {', '.join(r.direction for r in result.runs)}"
             f", feed {result.feed * 6e4:.6g} mm/min"]
    lines.append("ISO 230-4:2005")
    for k, v in result.circular_deviation.items():
        lines.append(f"  circular deviation G({k}) {v * um:.4f} µm")
    if result.bidirectional_circular_deviation is not None:
        lines.append(f"  bidirectional circular deviation G(b) "
                     f"{result.bidirectional_circular_deviation * um:.4f} µm")
    lines.append(f"  mean radius deviation {result.mean_radius_deviation * um:+.4f} µm ("
                 + ", ".join(f"{k} {v * um:+.4f}" for k, v in result.radius_deviation.items())
                 + ")")
    lines.append(f"  radial deviation F: max {result.radial_deviation_max * um:+.4f} µm, "
                 f"min {result.radial_deviation_min * um:+.4f} µm")
    lines.append("ballbar diagnostics")
    lines.append(f"  squareness {result.squareness * 1e6:+.4g} µm/m")
    lines.append(f"  scale mismatch {result.scale_mismatch * um:+.4f} µm")
    if result.servo_mismatch is not None:
        lines.append(f"  servo mismatch {result.servo_mismatch * 1e3:+.4g} ms")
    lines.append(f"  backlash X {result.backlash['x'] * um:+.4f} µm, "
                 f"Y {result.backlash['y'] * um:+.4f} µm")
    if result.lateral_play is not None:
        lines.append(f"  lateral play X {result.lateral_play['x'] * um:+.4f} µm, "
                     f"Y {result.lateral_play['y'] * um:+.4f} µm")
    if result.cyclic_error is not None and result.pitch is not None:
        lines.append(f"  cyclic error (pitch {result.pitch * 1e3:.4g} mm) X "
                     f"{result.cyclic_error['x'] * um:.4f} µm, Y "
                     f"{result.cyclic_error['y'] * um:.4f} µm")
    for s in result.spikes:
        lines.append(f"  reversal spike {s.direction} at {s.angle:.0f}° ({s.axis.upper()} "
                     f"reverses): height {s.height * um:+.4f} µm, width {s.width:.3g}° "
                     f"({s.width_length * 1e3:.3g} mm)"
                     + ("" if s.stands_out or abs(s.height) <= SPIKE_FLOOR else
                        f" — does not stand out of the {s.before * um:.3g} µm before it"))
    lines.append(f"  residual of the error model {result.residual_rms * um:.4f} µm rms")
    return lines

