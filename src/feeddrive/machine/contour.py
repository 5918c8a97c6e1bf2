"""Contours for a machine of two axes: a line, a circle, a corner and a CSV path.

A contour is a path in the plane of two axes (``x`` and ``y`` by default) followed at a feed
F along its arc length s, with an acceleration-limited lead-in and lead-out: ṡ rises from 0
to F at the tangential acceleration a, stays at F, and falls back to 0 at the end
(trapezoidal feed profile).  Each axis' reference is the path coordinate's rate,
ẋ(t) = dx/ds · ṡ(t), sampled on a uniform grid as a
:class:`~feeddrive.model.reference.SampledSpeed` (speeds interpolated linearly, positions their
exact integrals).  Positions are relative to the start point, as an axis' table position is.

The contour error of a run is the signed normal distance of the actual point to the path
(:meth:`Contour.contour_error`) [1]_: outside a circle positive, left of a line positive.

References
----------
.. [1] Y. Koren, "Cross-coupled biaxial computer control for manufacturing systems",
   ASME J. Dyn. Syst. Meas. Control 102 (1980) 265–272 (contour error as the normal
   distance to the path).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..model.reference import SampledSpeed
from ..parameters import ParameterError

__all__ = ["INTERVAL", "Circle", "Contour", "Line", "Polyline", "Together", "corner", "from_csv"]

#: grid spacing of the axis references [s]
INTERVAL = 1e-4
#: the most samples an axis reference may hold (500 s at INTERVAL; 8 bytes × 4 rows each)
MAX_REFERENCE_SAMPLES = 5_000_000


#: the largest values a contour takes: feeds to 10 m/s (600 m/min, beyond any machine tool's
#: rapid traverse), accelerations to 1000 m/s², radii and lines to 10 m and 100 m, 1000 turns
#: (a feed of 1e300 overflowed into a traceback: an outside check, 2026-12-07)
LIMITS = {"feed": 10.0, "acceleration": 1000.0, "radius": 10.0, "distance": 100.0,
          "turns": 1000.0}


def _positive(field: str, value: float, unit: str) -> float:
    high = LIMITS.get(field.removeprefix("contour."), math.inf)
    if not (isinstance(value, int | float) and not isinstance(value, bool)
            and math.isfinite(value) and 0 < value <= high):
        raise ParameterError(field, value, f"expected a positive number [{unit}]"
                             if high == math.inf else f"expected > 0, ≤ {high:g} [{unit}]")
    return float(value)


@dataclass(frozen=True)
class Contour:
    """A path p(s) in the plane of two axes, followed at ``feed`` with ramps of
    ``acceleration``.

    Subclasses give the path's length and its points and unit tangents at arc lengths
    (:meth:`point`, :meth:`tangent`) and may give an exact :meth:`contour_error`.

    Parameters
    ----------
    feed : float
        Path speed F [m/s] (5000 mm/min = 0.0833 m/s).
    acceleration : float
        Tangential acceleration of the lead-in and lead-out [m/s^2].
    axes : tuple of str, default ("x", "y")
        The machine axes of the path's first and second coordinate.
    dwell : float, default 0.0
        Time at rest after the lead-out [s].
    """

    feed: float
    acceleration: float
    axes: tuple[str, str] = ("x", "y")
    dwell: float = 0.0

    def __post_init__(self) -> None:
        _positive("contour.feed", self.feed, "m/s")
        _positive("contour.acceleration", self.acceleration, "m/s^2")
        if len(self.axes) != 2 or self.axes[0] == self.axes[1]:
            raise ParameterError("contour.axes", self.axes, "expected two different axis names")
        if not (math.isfinite(self.dwell) and self.dwell >= 0):
            raise ParameterError("contour.dwell", self.dwell, "expected ≥ 0 [s]")
        ramp = self.feed / self.acceleration * self.feed  # lead-in plus lead-out length [m]
        if ramp > self.length:
            raise ParameterError("contour.acceleration", self.acceleration,
                                 f"the lead-in and lead-out need {ramp:g} m, the path is "
                                 f"{self.length:g} m long; expected ≥ "
                                 f"{self.feed ** 2 / self.length:g} [m/s^2]")

    @property
    def length(self) -> float:
        """The path's length [m]."""
        raise NotImplementedError

    def point(self, s: np.ndarray) -> np.ndarray:
        """Points of the path, relative to the start.

        Parameters
        ----------
        s : numpy.ndarray
            Arc lengths [m].

        Returns
        -------
        numpy.ndarray
            Shape (2, n): the two coordinates [m].
        """
        raise NotImplementedError

    def tangent(self, s: np.ndarray) -> np.ndarray:
        """Unit tangents of the path.

        Parameters
        ----------
        s : numpy.ndarray
            Arc lengths [m].

        Returns
        -------
        numpy.ndarray
            Shape (2, n): dx/ds and dy/ds [-].
        """
        raise NotImplementedError

    @property
    def duration(self) -> float:
        """Time from start to rest at the end, dwell included [s]."""
        return self.length / self.feed + self.feed / self.acceleration + self.dwell

    @property
    def lead_in(self) -> float:
        """Duration of the lead-in ramp, F/a [s]."""
        return self.feed / self.acceleration

    def path_speed(self, t: np.ndarray) -> np.ndarray:
        """ṡ(t): the trapezoidal feed profile.

        Parameters
        ----------
        t : numpy.ndarray
            Times [s].

        Returns
        -------
        numpy.ndarray
            Path speed [m/s].
        """
        t = np.asarray(t, dtype=float)
        ramp = self.lead_in
        cruise_end = self.length / self.feed
        return np.clip(np.minimum(t / ramp, (cruise_end + ramp - t) / ramp), 0.0, 1.0) * self.feed

    def arc_length(self, t: np.ndarray) -> np.ndarray:
        """s(t), the integral of :meth:`path_speed`.

        Parameters
        ----------
        t : numpy.ndarray
            Times [s].

        Returns
        -------
        numpy.ndarray
            Arc length travelled [m].
        """
        t = np.asarray(t, dtype=float)
        a, F, ramp = self.acceleration, self.feed, self.lead_in
        end = self.length / F + ramp  # the instant the path ends
        s = np.where(t < ramp, 0.5 * a * t ** 2, 0.5 * F * ramp + F * (t - ramp))
        tail = np.maximum(end - t, 0.0)
        return np.where(t > end - ramp, self.length - 0.5 * a * tail ** 2, np.maximum(s, 0.0))

    def references(self, interval: float = INTERVAL) -> dict[str, SampledSpeed]:
        """Each axis' reference: its speed dx/ds·ṡ sampled every ``interval`` [s].

        Parameters
        ----------
        interval : float, default INTERVAL
            Grid spacing [s].

        Returns
        -------
        dict of str to SampledSpeed
            Axis name → its tabulated speed [m/s].
        """
        _positive("contour.interval", interval, "s")
        n = int(math.ceil(self.duration / interval)) + 2
        if n > MAX_REFERENCE_SAMPLES:  # refused before the table is built
            raise ParameterError("contour.duration", round(self.duration, 6),
                                 f"the references would hold {n:.3g} samples every "
                                 f"{interval:g} s; expected ≤ "
                                 f"{MAX_REFERENCE_SAMPLES * interval:g} [s] (fewer turns, a "
                                 "shorter path or a higher feed)")
        t = np.arange(n) * interval
        v = self.tangent(self.arc_length(t)) * self.path_speed(t)
        return {axis: SampledSpeed(time=t, table_speed=v[i]) for i, axis in enumerate(self.axes)}

    def contour_error(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Signed normal distance of the points (x, y) [m] to the path [m]: the distance to
        the nearest point of a dense polyline of the path, positive to its left.

        Parameters
        ----------
        x, y : numpy.ndarray
            Positions of the path's first and second axis, relative to the start [m].

        Returns
        -------
        numpy.ndarray
            The contour error per point [m].
        """
        from scipy.spatial import cKDTree

        s = np.linspace(0.0, self.length, max(2, int(self.length / 1e-4) + 1))
        vertices = self.point(s).T
        _, k = cKDTree(vertices).query(np.column_stack([x, y]))
        best = np.full(len(k), np.inf)
        sign = np.ones(len(k))
        p = np.column_stack([x, y])
        for shift in (-1, 0):  # the segments before and after the nearest vertex
            i = np.clip(k + shift, 0, len(vertices) - 2)
            a, b = vertices[i], vertices[i + 1]
            ab = b - a
            u = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.einsum("ij,ij->i", ab, ab),
                        0.0, 1.0)
            d = p - (a + u[:, None] * ab)
            dist = np.hypot(d[:, 0], d[:, 1])
            cross = ab[:, 0] * d[:, 1] - ab[:, 1] * d[:, 0]
            better = dist < best
            best = np.where(better, dist, best)
            sign = np.where(better, np.where(cross >= 0, 1.0, -1.0), sign)
        return sign * best


@dataclass(frozen=True)
class Line(Contour):
    """A straight line of ``distance`` at ``angle`` to the first axis.

    Parameters
    ----------
    feed : float
        Path speed F [m/s].
    acceleration : float
        Tangential acceleration of the lead-in and lead-out [m/s^2].
    axes : tuple of str, default ("x", "y")
        The machine axes of the path's first and second coordinate.
    dwell : float, default 0.0
        Time at rest after the lead-out [s].
    distance : float, default 0.1
        Its length [m].
    angle : float, default 0.0
        Its direction from the first axis, counter-clockwise [rad].
    """

    distance: float = 0.1
    angle: float = 0.0

    def __post_init__(self) -> None:
        _positive("contour.distance", self.distance, "m")
        super().__post_init__()

    @property
    def length(self) -> float:  # noqa: D102
        return self.distance

    def tangent(self, s: np.ndarray) -> np.ndarray:  # noqa: D102
        s = np.asarray(s, dtype=float)
        return np.array([np.full(s.shape, math.cos(self.angle)),
                         np.full(s.shape, math.sin(self.angle))])

    def point(self, s: np.ndarray) -> np.ndarray:  # noqa: D102
        return self.tangent(s) * np.asarray(s, dtype=float)


@dataclass(frozen=True)
class Together(Line):
    """Every axis of the machine moving ``distance`` together at the feed (a gantry's
    carriages): no path in a plane, so no contour error; ``axes`` is not used.

    Parameters
    ----------
    feed : float
        Speed of every axis at the top of the move [m/s].
    acceleration : float
        Acceleration of the ramps [m/s^2].
    axes : tuple of str, default ("x", "y")
        Not used.
    dwell : float, default 0.0
        Time at rest after the move [s].
    distance : float, default 0.1
        Travel of every axis [m].
    angle : float, default 0.0
        Not used [rad].
    """


@dataclass(frozen=True)
class Circle(Contour):
    """A circle of ``radius`` started at ``start_angle``, run ``turns`` times.

    The start point is the axes' origin; the centre lies at −R(cos θ0, sin θ0).

    Parameters
    ----------
    feed : float
        Path speed F [m/s].
    acceleration : float
        Tangential acceleration of the lead-in and lead-out [m/s^2].
    axes : tuple of str, default ("x", "y")
        The machine axes of the path's first and second coordinate.
    dwell : float, default 0.0
        Time at rest after the lead-out [s].
    radius : float, default 0.05
        R [m].
    clockwise : bool, default False
        Run clockwise (G02) instead of counter-clockwise (G03).
    start_angle : float, default 0.0
        θ0, the start point's angle seen from the centre [rad].
    turns : float, default 1.0
        Revolutions, lead-in and lead-out included [-].
    """

    radius: float = 0.05
    clockwise: bool = False
    start_angle: float = 0.0
    turns: float = 1.0

    def __post_init__(self) -> None:
        from ..parameters.validation import check_flag

        _positive("contour.radius", self.radius, "m")
        _positive("contour.turns", self.turns, "-")
        # "yes" or 0 was read as a direction; kept a bool (np.bool_ taken)
        object.__setattr__(self, "clockwise", check_flag("contour.clockwise", self.clockwise))
        super().__post_init__()

    @property
    def length(self) -> float:  # noqa: D102
        return 2.0 * math.pi * self.radius * self.turns

    @property
    def centre(self) -> tuple[float, float]:
        """The centre relative to the start point [m]."""
        return (-self.radius * math.cos(self.start_angle),
                -self.radius * math.sin(self.start_angle))

    def _angle(self, s: np.ndarray) -> np.ndarray:
        sense = -1.0 if self.clockwise else 1.0
        return self.start_angle + sense * np.asarray(s, dtype=float) / self.radius

    def point(self, s: np.ndarray) -> np.ndarray:  # noqa: D102
        phi = self._angle(s)
        cx, cy = self.centre
        return np.array([cx + self.radius * np.cos(phi), cy + self.radius * np.sin(phi)])

    def tangent(self, s: np.ndarray) -> np.ndarray:  # noqa: D102
        phi = self._angle(s)
        sense = -1.0 if self.clockwise else 1.0
        return sense * np.array([-np.sin(phi), np.cos(phi)])

    def contour_error(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Radius error |p − c| − R [m]: positive outside the circle (exact).

        Parameters
        ----------
        x, y : numpy.ndarray
            Positions of the first and second axis, relative to the start [m].

        Returns
        -------
        numpy.ndarray
            The contour error per point [m].
        """
        cx, cy = self.centre
        return np.hypot(np.asarray(x) - cx, np.asarray(y) - cy) - self.radius


@dataclass(frozen=True)
class Polyline(Contour):
    """A path through points, straight between them (a CSV path, a corner's polygon).

    Parameters
    ----------
    feed : float
        Path speed F [m/s].
    acceleration : float
        Tangential acceleration of the lead-in and lead-out [m/s^2].
    axes : tuple of str, default ("x", "y")
        The machine axes of the path's first and second coordinate.
    dwell : float, default 0.0
        Time at rest after the lead-out [s].
    points : tuple of (float, float), default ()
        The vertices relative to the start, the first (0, 0) [m].
    """

    points: tuple[tuple[float, float], ...] = ()

    def __post_init__(self) -> None:
        p = np.asarray(self.points, dtype=float)
        if p.ndim != 2 or p.shape[0] < 2 or p.shape[1] != 2 or not np.all(np.isfinite(p)):
            raise ParameterError("contour.points", len(self.points),
                                 "expected two or more finite (x, y) points [m]")
        if np.any(np.hypot(*np.diff(p, axis=0).T) == 0.0):
            raise ParameterError("contour.points", len(self.points),
                                 "expected no repeated consecutive point")
        super().__post_init__()

    def _cumulative(self) -> tuple[np.ndarray, np.ndarray]:
        p = np.asarray(self.points, dtype=float)
        return p, np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])

    @property
    def length(self) -> float:  # noqa: D102
        return float(self._cumulative()[1][-1])

    def point(self, s: np.ndarray) -> np.ndarray:  # noqa: D102
        p, cum = self._cumulative()
        s = np.clip(np.asarray(s, dtype=float), 0.0, cum[-1])
        return np.array([np.interp(s, cum, p[:, 0]), np.interp(s, cum, p[:, 1])]) - p[0][:, None]

    def tangent(self, s: np.ndarray) -> np.ndarray:  # noqa: D102
        p, cum = self._cumulative()
        seg = np.clip(np.searchsorted(cum, np.asarray(s, dtype=float), side="right") - 1,
                      0, len(cum) - 2)
        d = np.diff(p, axis=0) / np.diff(cum)[:, None]
        return d[seg].T


def corner(*, feed: float, acceleration: float, leg: float = 0.05, angle: float = 90.0,
           radius: float = 0.005, axes: tuple[str, str] = ("x", "y"),
           dwell: float = 0.0) -> Polyline:
    """A corner: a line, an arc of ``radius`` turning by ``angle`` degrees, a line.

    The arc is tabulated every 0.1° as a polyline (its chord error R(1 − cos 0.05°) is below
    4e-7·R).

    Parameters
    ----------
    feed : float
        Path speed [m/s].
    acceleration : float
        Tangential acceleration of the lead-in and lead-out [m/s^2].
    leg : float, default 0.05
        Length of each straight leg [m].
    angle : float, default 90.0
        The turn, counter-clockwise positive [deg].
    radius : float, default 0.005
        Radius of the blend arc [m].
    axes : tuple of str, default ("x", "y")
        The two axes.
    dwell : float, default 0.0
        Time at rest at the end [s].

    Returns
    -------
    Polyline
        The corner path.
    """
    _positive("contour.leg", leg, "m")
    _positive("contour.radius", radius, "m")
    if not (math.isfinite(angle) and 0 < abs(angle) < 180):
        raise ParameterError("contour.angle", angle, "expected 0 < |angle| < 180 [deg]")
    turn = math.radians(angle)
    sense = 1.0 if turn > 0 else -1.0
    pts = [(0.0, 0.0), (leg, 0.0)]
    n = max(2, int(abs(angle) / 0.1))
    for k in range(1, n + 1):
        phi = turn * k / n
        pts.append((leg + radius * math.sin(abs(phi)), sense * radius * (1.0 - math.cos(phi))))
    end = pts[-1]
    pts.append((end[0] + leg * math.cos(turn), end[1] + leg * math.sin(turn)))
    return Polyline(feed=feed, acceleration=acceleration, axes=axes, dwell=dwell,
                    points=tuple(pts))


def from_csv(path: str | Path, *, feed: float, acceleration: float,
             axes: tuple[str, str] = ("x", "y"), dwell: float = 0.0) -> Polyline:
    """A path read from a CSV file of two coordinates, in mm unless a header says otherwise.

    ``#`` lines and blank lines are skipped.  With a header, the columns are found by name: the
    first coordinate's is the first axis' name or ``x``, the second's the second axis' or
    ``y``, each with an optional unit (``x [mm]``, ``x_mm``, ``y [m]``, ``y [µm]``); without
    one, the file holds exactly two columns, x then y.  Every row must give both numbers
    (a bad or missing cell is refused naming its line, never skipped).

    Parameters
    ----------
    path : str or Path
        The file.
    feed : float
        Path speed [m/s].
    acceleration : float
        Tangential acceleration of the lead-in and lead-out [m/s^2].
    axes : tuple of str, default ("x", "y")
        The two axes.
    dwell : float, default 0.0
        Time at rest at the end [s].

    Returns
    -------
    Polyline
        The path, relative to its first point [m].

    Raises
    ------
    ParameterError
        For a file that cannot be read, a header without the two coordinates, or a row that
        is not two finite numbers (its line named).
    """
    pts = _csv_points(Path(path), axes)
    return Polyline(feed=feed, acceleration=acceleration, axes=axes, dwell=dwell,
                    points=tuple(map(tuple, pts)))


#: the units a path file's header may give its coordinates [m per unit]
_PATH_UNITS = {"mm": 1e-3, "m": 1.0, "µm": 1e-6, "um": 1e-6}


def _numbers(cells: list[str]) -> bool:
    """Whether every cell reads as a number."""
    try:
        [float(c) for c in cells]
    except ValueError:
        return False
    return True


def _csv_points(path: Path, axes: tuple[str, str]) -> np.ndarray:
    """The (x, y) points of a path file relative to its first [m] (:func:`from_csv`); it was
    read without a word of a header's names, and rows with bad cells were skipped (an outside
    check, 2026-12-07)."""
    import re

    def refuse(what: str) -> ParameterError:
        return ParameterError("contour.csv", str(path), what)

    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise refuse(f"cannot be read ({type(exc).__name__}: {exc})") from None
    rows = [(k, line) for k, line in enumerate(text.splitlines(), start=1)
            if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise refuse("has no rows; expected two columns x, y [mm]")
    first = [c.strip() for c in rows[0][1].split(",")]
    columns, scale, width = [0, 1], [1e-3, 1e-3], 2
    if not _numbers(first):  # a header: the coordinates by name
        rows, width = rows[1:], len(first)
        names, units = [], []
        for cell in first:
            m = re.fullmatch(r"(.*?)\s*(?:\[(.*)\]|_(mm|m|um|µm))?", cell)
            assert m is not None
            names.append(m.group(1).strip().lower())
            units.append((m.group(2) or m.group(3) or "mm").strip())
        for i, (axis, plain) in enumerate(zip(axes, ("x", "y"), strict=True)):
            found = [j for j, n in enumerate(names) if n in (axis.lower(), plain)]
            if len(found) != 1:
                named = f"'{plain}'" if axis.lower() == plain else f"'{axis}' or '{plain}'"
                raise refuse(f"has {'no' if not found else 'more than one'} column for the "
                             f"path's {'first' if i == 0 else 'second'} coordinate ({named}); "
                             f"its header: {', '.join(first)}")
            if units[found[0]] not in _PATH_UNITS:
                raise refuse(f"column '{first[found[0]]}': unit {units[found[0]]!r}; expected "
                             f"one of {', '.join(_PATH_UNITS)}")
            columns[i], scale[i] = found[0], _PATH_UNITS[units[found[0]]]
    points = np.empty((len(rows), 2))
    for r, (k, line) in enumerate(rows):
        cells = [c.strip() for c in line.split(",")]
        if len(cells) != width:
            raise refuse(f"line {k}: {len(cells)} cells; expected {width}")
        for i in (0, 1):
            try:
                value = float(cells[columns[i]])
            except ValueError:
                raise refuse(f"line {k}: {cells[columns[i]][:20]!r} is not a number") from None
            if not math.isfinite(value):
                raise refuse(f"line {k}: {cells[columns[i]]!r}; expected a finite number")
            points[r, i] = value
    if len(points) < 2:
        raise refuse("has fewer than two points; expected a path of two or more")
    return (points - points[0]) * np.array(scale)  # relative to the first point, as before
