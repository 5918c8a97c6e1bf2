"""``Calibration.reason`` when the fitted value's own search ends undecided (an outside check,
2026-12-06): ``feeddrive calibrate --max-duration 12 --tolerance 0.3 --low 2000 --high 8000``
bisected to a value whose critical speed from rest was undecided (no speed) and the reason's
``critical_speed * 1e3`` raised a TypeError — a traceback instead of the command's one
``error: target … not reached: …`` line."""

from __future__ import annotations

import feeddrive as fd
from feeddrive.analysis.calibrate import Calibration, Target, Unknown
from feeddrive.analysis.critical import CriticalSpeed


def _calibration(status: str, critical: float | None) -> Calibration:
    achieved = CriticalSpeed(drive="cdfs", table_position=0.4, nut_speed=0.0, start="rest",
                             critical_speed=critical, status=status, resolution=1e-5,
                             speed_range=(0.05e-3, 3.0e-3))
    return Calibration(parameters=fd.preset("wang2021"),
                       unknown=Unknown("controller.velocity_integral_gain", 2000.0, 8000.0),
                       value=3668.02, target=Target("cdfs", 1.56e-3), achieved=achieved,
                       evaluations=10)


def test_an_undecided_search_gives_a_reason_not_a_traceback() -> None:
    cal = _calibration("undecided", None)
    assert not cal.reached
    text = cal.reason()
    assert "undecided" in text and "max_duration" in text
    assert "controller.velocity_integral_gain = 3668.02" in text


def test_a_found_speed_off_target_still_names_it() -> None:
    text = _calibration("found", 1.30e-3).reason()
    assert "1.30 mm/s" in text and "-17 %" in text
