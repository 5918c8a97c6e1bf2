"""Issue 39 (reliability, round 4), the library side: the bounds a request is checked
against before any work, the NetCDF writer's plain file I/O, a covariance that is one."""

from __future__ import annotations

import errno
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from feeddrive.analysis import protocol
from feeddrive.io import outputs
from feeddrive.parameters import ParameterError
from feeddrive.sweep.executors import check_executor
from feeddrive.sweep.quantities import QuantitySettings

# ------------------------------------------------------------------ item 4: bounded searches


def test_the_shared_protocol_is_within_the_search_bounds() -> None:
    """The defaults of `creep`, `reproduce`, `predict` and the sweeps pass their own check."""
    for start, coarse in (("rest", protocol.COARSE_STEP),
                          ("running", protocol.STAIRCASE_COARSE_STEP)):
        protocol.check_search(low=protocol.SPEED_RANGE[0], high=protocol.SPEED_RANGE[1],
                              coarse_step=coarse, resolution=protocol.RESOLUTION)
        QuantitySettings.parse({"kind": "critical-speed", "start": start})


@pytest.mark.parametrize(("settings", "field", "says"), [
    ({"resolution": 1e-300}, "quantity.resolution", "expected ≥ 0.0001 [mm/s]"),
    ({"resolution": 0.00005}, "quantity.resolution", "expected ≥ 0.0001"),
    ({"coarse_step": 1e-6}, "quantity.coarse_step", "speeds on the scan"),
    ({"start": "running", "coarse_step": 3.0, "resolution": 0.001}, "quantity.resolution",
     "coarse step 3 / 2000"),
])
def test_a_search_whose_work_is_not_bounded_is_refused_when_parsed(
        settings: dict[str, Any], field: str, says: str) -> None:
    """A bisection to 1e-300 mm/s never ended: its speeds are rounded to 1e-12 m/s, so the
    same interval was bisected again and again (`predict --resolution 1e-300`)."""
    with pytest.raises(ParameterError, match=re.escape(says)) as err:
        QuantitySettings.parse({"kind": "critical-speed", **settings})
    assert err.value.field == field


def test_the_search_functions_refuse_before_the_first_trial(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from feeddrive.analysis import critical
    from feeddrive.engine.simulate import DriveSystem
    from feeddrive.parameters import preset

    def trial(*args: Any, **kw: Any) -> Any:
        raise AssertionError("a trial was run")

    monkeypatch.setattr(critical, "creep_trial", trial)
    monkeypatch.setattr(critical, "walk_down", trial)
    system = DriveSystem(preset("wang2021"), "cdfs", 0.4)
    with pytest.raises(ParameterError, match="resolution"):
        critical.critical_speed_from_rest(system, resolution=1e-300)
    with pytest.raises(ParameterError, match="step"):
        critical.critical_speed_stepdown(system, step=1e-15)


# ------------------------------------------------------------------ item 5: executors


@pytest.mark.parametrize(("kw", "says"), [
    ({"workers": 0}, "--workers = 0"), ({"workers": -2}, "--workers = -2"),
    ({"dask_workers": 0}, "--dask-workers = 0"), ({"workers": True}, "--workers = True"),
    ({"scheduler": "tcp://h:1", "dask_workers": 2}, "give one, not both"),
])
def test_an_executor_request_that_means_nothing_is_refused(kw: dict[str, Any],
                                                           says: str) -> None:
    with pytest.raises(ValueError, match=says):
        check_executor(**kw)


# ------------------------------------------------------------------ item 5: covariance


FIT = """extends = "wang2021"
[fit]
drive = "cdfs"
table_position = 0.4
free = ["controller.velocity_integral_gain", "controller.velocity_gain"]
estimates = [3925.28, 45.0]
covariance = {cov}
interrupted = false
"""


@pytest.mark.parametrize(("cov", "says"), [
    ("[[-1.0, 0.0], [0.0, 1.0]]", "variance of controller.velocity_integral_gain is negative"),
    ("[[1.0, 0.5], [0.2, 1.0]]", "not symmetric"),
    ("[[1.0, 2.0], [2.0, 1.0]]", "not positive semi-definite"),
])
def test_a_covariance_that_is_not_one_is_refused(tmp_path: Path, cov: str, says: str) -> None:
    """A negative variance was drawn from silently (its eigenvalue clipped to 0)."""
    from feeddrive.analysis.predict import read_fit_record

    path = tmp_path / "fit.toml"
    path.write_text(FIT.format(cov=cov))
    with pytest.raises(ParameterError, match=says) as err:
        read_fit_record(path)
    assert err.value.field == "fit.covariance"


def test_a_covariance_that_is_one_is_read(tmp_path: Path) -> None:
    from feeddrive.analysis.predict import read_fit_record

    path = tmp_path / "fit.toml"
    path.write_text(FIT.format(cov="[[4.0, 1.0], [1.0, 1.0]]"))
    assert read_fit_record(path).covariance.tolist() == [[4.0, 1.0], [1.0, 1.0]]


# ------------------------------------------------------------------ item 5: measured values


@pytest.mark.parametrize(("header", "cell", "says"), [
    ("position [mm]", "1e308", "column 'position': 1e308 [mm] is beyond any feed drive"),
    ("position [m]", "-2000", "column 'position': -2000 [m]"),
    ("position [mm]", "1e-300", None),  # small is fine
])
def test_a_measured_value_beyond_any_feed_drive_is_refused_naming_its_line(
        tmp_path: Path, header: str, cell: str, says: str | None) -> None:
    from feeddrive.io.measured import MeasuredDataError, read_position_trace

    rows = [f"{k * 1e-3:.3f},{k * 1e-3:.6f}" for k in range(20)]
    rows[7] = f"{7e-3:.3f},{cell}"
    path = tmp_path / "t.csv"
    path.write_text(f"time [s],{header}\n" + "\n".join(rows) + "\n")
    if says is None:
        read_position_trace(path)
        return
    with pytest.raises(MeasuredDataError, match=re.escape(says)) as err:
        read_position_trace(path)
    assert err.value.line == 9 and "check the file's unit" in str(err.value)


# ------------------------------------------------------------------ item 1: the writer


def test_write_bytes_writes_everything_even_in_short_writes(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import os

    data = np.random.default_rng(0).bytes(3 * 1024 * 1024 + 17)
    calls = []

    def short(fd: int, view: memoryview) -> int:  # a write may take fewer bytes than given
        calls.append(len(view))
        return os.write(fd, view[:1000 + len(calls)])

    monkeypatch.setattr(outputs, "_write_fd", short)
    outputs.write_bytes(tmp_path / "f.bin", memoryview(data))
    assert (tmp_path / "f.bin").read_bytes() == data and len(calls) > 3


def test_write_bytes_raises_the_write_error_and_closes_the_file(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import os

    opened = len(os.listdir("/proc/self/fd"))

    def full(fd: int, view: memoryview) -> int:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(outputs, "_write_fd", full)
    with pytest.raises(OSError, match="No space left"):
        outputs.write_bytes(tmp_path / "f.bin", b"x" * 10)
    assert len(os.listdir("/proc/self/fd")) == opened
