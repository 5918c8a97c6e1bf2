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
    """A move: ramp from rest to ``table_speed`` [m/s] over ``ramp_time`` [s], hold, and
    ramp back to rest so that the table stops at ``duration`` [s].  The nut speed [m/s]
    (DDFS) follows the same shape."""
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
    """The paper's step-down experiment (Wang2021 Sect. 6): run at ``start_speed`` [m/s] for
    ``lead_in`` [s], then lower the command by ``step`` [m/s] every ``dwell`` [s] down to
    ``lowest_speed``.  Returns the profile and the step speeds [m/s]; its duration is
    ``profile.time[-1]``.  The same staircase `creep --method stepdown` runs."""
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
    """A profile from a CSV file with columns ``time`` and ``table_speed`` (optionally
    ``nut_speed``), in s and mm/s unless a header states its unit (``time [ms]``,
    ``table_speed [m/s]``).  Times must increase from 0; they are resampled onto a uniform
    grid of ``interval`` [s].  The format of docs/measured-data.md (``#`` comments, separator
    detected)."""
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
