"""Speed profiles built on :class:`~feeddrive.control.SampledSpeed`: trapezoid, the paper's
step-down staircase, and a profile read from a CSV file.  SI units.

The solver sees every one of them as a sampled table (linear interpolation of speed, exact
integral for position), so none needs a new kernel.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .control import SampledSpeed
from .parameters import ParameterError

_INTERVAL = 1e-3  # [s] sampling of the built profiles


def _positive(name: str, value: float, unit: str) -> float:
    if not (np.isfinite(value) and value > 0.0):
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
        For a non-positive duration or ramp time, or ramps longer than the move.
    """
    duration = _positive("duration", duration, "s")
    ramp_time = _positive("ramp_time", ramp_time, "s")
    if 2.0 * ramp_time >= duration:
        raise ParameterError("ramp_time", ramp_time,
                             f"expected < duration / 2 = {duration / 2:g} [s]")
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
        For a non-positive value or ``lowest_speed ≥ start_speed``.

    References
    ----------
    .. [1] Wang2021 Sect. 6, Fig. 13.
    """
    from .analysis.critical import _staircase

    for name, value in (("start_speed", start_speed), ("lowest_speed", lowest_speed),
                        ("step", step)):
        _positive(name, value, "m/s")
    _positive("dwell", dwell, "s")
    _positive("lead_in", lead_in, "s")
    if lowest_speed >= start_speed:
        raise ParameterError("lowest_speed", lowest_speed,
                             f"expected < start_speed = {start_speed:g} [m/s]")
    n = int(np.floor((start_speed - lowest_speed) / step + 1e-9)) + 1
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
    from .measured_io import MeasuredDataError, read_csv_table

    table = read_csv_table(path)
    t, _, _ = table.quantity(["time"], "time", unit=None, default_unit="s")
    vt, _, _ = table.quantity(["table_speed"], "speed", unit=None, default_unit="mm/s")
    vn = (table.quantity(["nut_speed"], "speed", unit=None, default_unit="mm/s")[0]
          if table.has("nut_speed") else None)
    if t.size < 2 or abs(t[0]) > 1e-12 or np.any(np.diff(t) <= 0):
        raise MeasuredDataError(table.source, table.header_line,
                                "column 'time': expected times [s] increasing from 0, at "
                                "least two rows")
    grid = np.arange(int(np.floor(t[-1] / interval + 1e-9)) + 1) * interval
    if grid.size < 2:
        raise MeasuredDataError(table.source, table.header_line,
                                f"column 'time': expected a profile longer than {interval:g} s")
    return SampledSpeed(time=grid, table_speed=np.interp(grid, t, vt),
                        nut_speed=None if vn is None else np.interp(grid, t, vn))
