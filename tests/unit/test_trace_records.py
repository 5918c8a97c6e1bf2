"""`analyze` on records that are not a constant-speed creep test (issue 22 item 4).

The public rack-and-pinion record of the issue (a point-to-point move 0 → 644 → 0 mm/s in
0.54 s) is not redistributable; the move here has its shape: a sin² speed profile.
"""

from __future__ import annotations

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.analysis.trace import MAX_SPEED_TREND, analyze_trace, speed_trend


def _move(rate: float = 5000.0) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(0.0, 0.9, 1.0 / rate)
    tau = np.clip((t - 0.1) / 0.54, 0.0, 1.0)
    v = 0.644 * np.sin(np.pi * tau) ** 2  # [m/s]
    x = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    return t, np.round(x / 1e-6) * 1e-6  # 1-µm encoder counts


def test_point_to_point_move_is_not_judged_for_creep() -> None:
    t, x = _move()
    result = analyze_trace(t, x)
    assert result.record == "non-constant-speed"
    assert result.segments == () and result.critical == ()
    note = next(n for n in result.notes if n.startswith("non-constant-speed record"))
    assert "644" in note or "643" in note
    assert result.to_dict()["record"] == "non-constant-speed"


def test_ramp_with_a_command_column_is_not_judged() -> None:
    t = np.arange(0.0, 10.0, 1e-3)
    v = 5e-4 * t  # 0 → 5 mm/s over 10 s
    x = 0.5 * 5e-4 * t**2
    result = analyze_trace(t, x, command=v)
    assert result.record == "non-constant-speed"


def test_stick_slip_at_constant_command_stays_a_constant_speed_record() -> None:
    """The trend rule must not take creep for a move: wang2021's CDFS at 1 mm/s creeps
    (Wang2021 Sect. 5.2: critical speed 1.56 mm/s) and is judged so."""
    r = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4),
                    fd.ConstantSpeed(1.0e-3), 6.0)
    t, x, v = r.time, r["table_position"], r["table_speed"]
    sel = t > 1.0
    assert speed_trend(t[sel], v[sel]) < MAX_SPEED_TREND / 2
    result = analyze_trace(t, x)
    assert result.record == "constant-speed"
    assert result.segments[-1].metrics.creeping


def test_start_up_transient_is_not_a_segment() -> None:
    """Issue 22: at 1.6 mm/s (just above the 1.56 mm/s critical speed) the decaying start-up
    oscillation of a command-less record made its own "creeping" segment at 1.599 mm/s
    beside the smooth 1.6 mm/s one, and analyze reported a critical speed of 1.6 mm/s."""
    r = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4),
                    fd.ConstantSpeed(1.6e-3), 10.0)
    result = analyze_trace(r.time, r["table_position"])
    assert len(result.segments) == 1
    assert not result.segments[0].metrics.creeping
    assert result.segments[0].command_speed == pytest.approx(1.6e-3, rel=1e-3)
    assert result.critical == ()
    assert any(n.startswith("start-up transient") for n in result.notes)
