"""The three bad-input cases the session-29 sweep left for a decision:

1. a sweep's ``[quantity]`` setting its kind does not read (``table_speed`` for
   ``linear-band``) was dropped with exit 0; it is refused naming the key, the kind and the
   settings that kind reads (``feeddrive.sweep.quantities.READS``);
2. ``export fmu --nut-hold`` on a topology whose nut nothing holds;
3. a measured trace whose header is not UTF-8 said only "no column …" with ``�``.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from feeddrive.cli import app
from feeddrive.parameters import ParameterError
from feeddrive.sweep import QuantitySettings
from feeddrive.sweep.quantities import READS

runner = CliRunner()


def _one_line_refusal(args: list[str]) -> str:
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    assert result.stdout == "", result.stdout
    lines = [s for s in result.stderr.splitlines() if s.strip()]
    assert len(lines) == 1, result.stderr
    return lines[0]


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


def test_each_kind_takes_every_setting_it_reads() -> None:
    good = {"start": "rest", "low": 1.0, "high": 2.0, "coarse_step": 0.5, "resolution": 0.1,
            "initial_duration": 3.0, "max_duration": 3.0, "table_speed": 2.0, "linear": False,
            "linear_points": 8}
    for kind, keys in READS.items():
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
    line = _one_line_refusal(["sweep", str(cfg), "--dry-run", "--store",
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
    line = _one_line_refusal(["export", "fmu", "--drive", drive, "--nut-hold", hold,
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
    axes["x"]["nut_hold"] = "locked"  # as machine_toml writes every axis
    machine_from_dict({"name": "m", "axes": axes})
