"""The three bad-input cases the session-29 sweep left for a decision:

1. a sweep's ``[quantity]`` setting its kind does not read (``table_speed`` for
   ``linear-band``) was dropped with exit 0; it is refused naming the key, the kind and the
   settings that kind reads (``feeddrive.sweep.quantities.READS``);
2. ``export fmu --nut-hold`` on a topology whose nut nothing holds;
3. a measured trace whose header is not UTF-8 said only "no column …" with ``�``.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from cli_support import one_line_refusal

from feeddrive.parameters import ParameterError
from feeddrive.sweep import QuantitySettings
from feeddrive.sweep.quantities import READS, reads

# ------------------------------------------------------------------ 1: [quantity] settings


@pytest.mark.parametrize(("kind", "key", "value", "shown"), [
    ("linear-band", "table_speed", 2, "2"),
    ("linear-band", "linear", False, "False"),
    ("linear-band", "initial_duration", 3.0, "3.0"),
    ("loop-margins", "linear", True, "True"),
    ("loop-margins", "low", 1.0, "1.0"),
    ("creep-trial", "start", "rest", "'rest'"),
    ("creep-trial", "linear_points", 8, "8"),
    ("critical-speed", "table_speed", 2, "2"),
])
def test_a_setting_the_kind_does_not_read_is_refused(kind: str, key: str, value: object,
                                                     shown: str) -> None:
    with pytest.raises(ParameterError) as err:
        QuantitySettings.parse({"kind": kind, key: value})
    assert str(err.value) == (f"quantity.{key} = {shown}: not read by kind {kind}, which "
                              f"reads {', '.join(READS[kind])}")


@pytest.mark.parametrize("linear", [True, False])
def test_each_kind_takes_every_setting_it_reads(linear: bool) -> None:
    """With ``linear`` on and off: a critical-speed search reads ``linear_points`` only with
    its linear band (``quantities.reads``)."""
    good = {"start": "rest", "low": 1.0, "high": 2.0, "coarse_step": 0.5, "resolution": 0.1,
            "initial_duration": 3.0, "max_duration": 3.0, "table_speed": 2.0, "linear": linear,
            "linear_points": 8}
    for kind in READS:
        keys = reads(kind, linear)
        q = QuantitySettings.parse({"kind": kind, **{k: good[k] for k in keys}})
        assert set(q.to_dict()) == {"kind", *keys}


def test_the_default_kind_refuses_a_creep_trials_table_speed() -> None:
    with pytest.raises(ParameterError, match=r"^quantity.table_speed = 1: not read by kind "
                                             r"critical-speed, which reads start, "):
        QuantitySettings.parse({"table_speed": 1})


def test_sweep_refuses_a_setting_its_kind_does_not_read(tmp_path: Path) -> None:
    cfg = tmp_path / "lb.toml"
    cfg.write_text('name = "lb"\ndrive = "cdfs"\n[design]\nkind = "grid"\n[quantity]\n'
                   'kind = "linear-band"\ntable_speed = 2\n[axes]\n'
                   'table_position = [200, 400]\n', encoding="utf-8")
    line = one_line_refusal(["sweep", str(cfg), "--dry-run", "--store",
                              str(tmp_path / "lb.sqlite")])
    assert line == (f"error: {cfg}: quantity.table_speed = 2: not read by kind linear-band, "
                    "which reads low, high, linear_points"), line
    assert not (tmp_path / "lb.sqlite").exists()


# ------------------------------------------------------------------ 2: --nut-hold


@pytest.mark.parametrize(("drive", "why"), [
    ("linear-motor", "it has no nut"), ("rack-pinion", "it has no nut"),
    ("ddfs", "it drives its nut: the nut speed reference")])
@pytest.mark.parametrize("hold", ["servo", "locked"])
def test_export_fmu_refuses_a_nut_hold_its_drive_does_not_read(tmp_path: Path, drive: str,
                                                               why: str, hold: str) -> None:
    out = tmp_path / "x.fmu"
    line = one_line_refusal(["export", "fmu", "--drive", drive, "--nut-hold", hold,
                              "--out", str(out)])
    assert line == (f"error: --nut-hold = '{hold}': applies to a drive that holds its nut "
                    f"(cdfs), not to {drive} ({why})"), line
    assert not out.exists()


def test_only_the_cdfs_holds_its_nut() -> None:
    from feeddrive.model.mechanisms import mechanism

    held = {"cdfs": "nut", "ddfs": "", "linear-motor": "", "rack-pinion": ""}
    assert {d: mechanism(d).held_part(d) for d in held} == held


@pytest.mark.parametrize(("drive", "preset"), [("ddfs", "wang2021"),
                                               ("linear-motor", "linear-motor-example")])
def test_the_library_refuses_servo_where_no_nut_is_held(tmp_path: Path, drive: str,
                                                        preset: str) -> None:
    import feeddrive as fd
    from feeddrive.fmu import export_fmu

    params = fd.preset(preset)
    with pytest.raises(ParameterError, match=rf"^nut_hold = 'servo': applies to a drive that "
                                             rf"holds its nut \(cdfs\), not to {drive} \("):
        fd.DriveSystem(params, drive, 0.4, nut_hold="servo")
    with pytest.raises(ParameterError, match=r"^nut_hold = 'servo': "):
        export_fmu(params, drive, tmp_path / "x.fmu", nut_hold="servo")
    assert not (tmp_path / "x.fmu").exists()
    fd.DriveSystem(params, drive, 0.4, nut_hold="locked")  # the default, taken everywhere
    fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4, nut_hold="servo")


def test_a_machine_axis_refuses_servo_where_no_nut_is_held() -> None:
    from feeddrive.machine import machine_from_dict

    axes = {"x": {"extends": "linear-motor-example", "drive": "linear-motor",
                  "nut_hold": "servo"}}
    with pytest.raises(ParameterError, match=r"^axes\.x\.nut_hold = 'servo': applies to a "
                                             r"drive that holds its nut \(cdfs\), not to "
                                             r"linear-motor \(it has no nut\)$"):
        machine_from_dict({"name": "m", "axes": axes})
    # "locked" was taken (machine_toml wrote it on every axis) and dropped; since session 30
    # machine_toml writes it only where a nut is held and any value here is refused
    axes["x"]["nut_hold"] = "locked"
    with pytest.raises(ParameterError, match=r"^axes\.x\.nut_hold = 'locked': applies to a "
                                             r"drive that holds its nut \(cdfs\), not to "
                                             r"linear-motor \(it has no nut\)$"):
        machine_from_dict({"name": "m", "axes": axes})
    del axes["x"]["nut_hold"]
    machine_from_dict({"name": "m", "axes": axes})


def test_a_cdfs_nut_on_its_servo_refuses_a_nut_speed_showing_the_speed_given(
        tmp_path: Path) -> None:
    # the FMU's reference is an input: its constant speed is 0, the given one in its table
    # (the refusal said "--nut-speed = 0 [mm/s]" for --nut-speed 5)
    line = one_line_refusal(["export", "fmu", "--drive", "cdfs", "--nut-hold", "servo",
                              "--nut-speed", "5", "--out", str(tmp_path / "x.fmu")])
    assert line.startswith("error: --nut-speed = 5 [mm/s]: the CDFS holds the hollow motor")
    assert not (tmp_path / "x.fmu").exists()


# ------------------------------------------------------------------ 3: a header not UTF-8

_NOT_UTF8 = ("; the file is not UTF-8 text (saved as Windows-1252 or Latin-1?): save it as "
             "UTF-8 (docs/measured-data.md)")


def _trace(path: Path, header: str, encoding: str) -> Path:
    rows = "".join(f"{i * 0.01:g},{i * 0.001:g}\n" for i in range(200))
    path.write_bytes(header.encode(encoding) + b"\n" + rows.encode("ascii"))
    return path


def test_a_latin1_header_without_a_micro_sign_says_the_file_is_not_utf8(
        tmp_path: Path) -> None:
    """It said "no column 'position' … (columns: 'time', 'posici\ufffdn')" alone."""
    path = _trace(tmp_path / "lat.csv", "time [s],posición [mm]", "latin-1")
    line = one_line_refusal(["analyze", str(path)])
    assert line == ("error: lat.csv, line 1: no column 'position' or 'table_position' in the "
                    "header (columns: 'time', 'posici\ufffdn')" + _NOT_UTF8), line


def test_the_same_header_in_utf8_gets_no_hint(tmp_path: Path) -> None:
    path = _trace(tmp_path / "utf.csv", "time [s],posición [mm]", "utf-8")
    line = one_line_refusal(["analyze", str(path)])
    assert line == ("error: utf.csv, line 1: no column 'position' or 'table_position' in the "
                    "header (columns: 'time', 'posición')"), line


def test_a_positioning_record_and_a_static_test_give_the_hint_too(tmp_path: Path) -> None:
    from feeddrive.io.acceptance import read_positioning_record, read_xy_trace
    from feeddrive.io.measured import MeasuredDataError, read_static_test

    path = _trace(tmp_path / "pos.csv", "posición [mm],dirección", "cp1252")
    with pytest.raises(MeasuredDataError) as err:
        read_positioning_record(path)
    assert str(err.value).endswith("position or deviation" + _NOT_UTF8), str(err.value)
    path = _trace(tmp_path / "st.csv", "velocidad [mm/s],fuerza [N]", "latin-1")
    path.write_bytes(path.read_bytes().replace(b"velocidad", b"velocit\xe9"))
    with pytest.raises(MeasuredDataError) as err:
        read_static_test(path)
    assert str(err.value).endswith(_NOT_UTF8), str(err.value)
    path = _trace(tmp_path / "xy.csv", "tiempo,posición", "latin-1")
    with pytest.raises(MeasuredDataError) as err:
        read_xy_trace(path)
    assert str(err.value).endswith("(--x-column)" + _NOT_UTF8), str(err.value)


def test_a_units_hint_still_asks_after_a_micro_sign(tmp_path: Path) -> None:
    path = _trace(tmp_path / "mu.csv", "time [s],position [µm]", "latin-1")
    line = one_line_refusal(["analyze", str(path)])
    assert "unit '\ufffdm' is not a length unit" in line, line
    assert line.endswith("; the file is not UTF-8 text (a µ saved as Windows-1252 or "
                         "Latin-1?): save it as UTF-8 (docs/measured-data.md)"), line


def test_a_fits_missing_signal_gives_the_hint_too(tmp_path: Path) -> None:
    from feeddrive.analysis.fit import FitError, read_experiment

    path = _trace(tmp_path / "fit.csv", "time [s],posición [mm]", "latin-1")
    for kw in ({"signals": ["table_position"]}, {"input": "current"}):
        with pytest.raises(FitError) as err:
            read_experiment(path, **kw)  # type: ignore[arg-type]
        assert str(err.value).endswith(_NOT_UTF8), str(err.value)
    path = tmp_path / "replay.csv"  # a position, and the replayed current's column not found
    path.write_bytes("time [s],table_position [mm],intensité [A]\n".encode("latin-1") + "".join(
        f"{i * 0.01:g},{i * 0.001:g},0.5\n" for i in range(200)).encode("ascii"))
    with pytest.raises(FitError, match=r"--input current: no column for it .*"
                                       + re.escape(_NOT_UTF8) + "$"):
        read_experiment(path, input="current")
