"""Bad values an outside check found getting past the checks (2026-12-07): each is now one
line naming the option or key, the value and what was expected, before any work — never a
traceback (exit 1) or numpy's words."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from feeddrive.cli import app
from feeddrive.parameters import ParameterError

runner = CliRunner()


@pytest.mark.parametrize(("args", "says"), [
    (["simulate", "--table-speed", "1", "--duration", "inf"],
     "--duration = inf: expected a finite time > 0 [s]"),
    (["simulate", "--machine", "xy-table", "--duration", "inf"],
     "--duration = inf: expected a finite time > 0 [s]"),
    (["simulate", "--machine", "xy-table", "--feed", "1e300"],
     "--feed = 1e+300: expected > 0, ≤ 600000 [mm/min]"),
    (["simulate", "--machine", "xy-table", "--acceleration", "1e300"],
     "--acceleration = 1e+300: expected > 0, ≤ 1e+06 [mm/s^2]"),
    (["simulate", "--machine", "xy-table", "--turns", "1e300"],
     "--turns = 1e+300: expected > 0, ≤ 1000 [-]"),
    (["simulate", "--machine", "xy-table", "--start-angle", "nan"],
     "--start-angle = nan: expected a finite angle [°]"),
    (["simulate", "--machine", "xy-table", "--contour", "line", "--length", "10", "--feed",
      "60000"], "--acceleration = 1000.0: the lead-in and lead-out at 60000 mm/min need "
                "1000 mm, the path is 10 mm long; expected ≥ 1e+05 [mm/s^2]"),
])
def test_a_bad_value_is_one_line_naming_the_option(args: list[str], says: str) -> None:
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    lines = [s for s in result.output.splitlines() if s.strip()]
    assert lines == [f"error: {says}"], result.output


def test_the_contour_api_bounds_its_values_without_overflowing() -> None:
    from feeddrive.machine.contour import LIMITS, Circle

    with pytest.raises(ParameterError, match=r"contour.feed = 1e\+300: expected > 0, ≤ 10"):
        Circle(feed=1e300, acceleration=1.0)
    with pytest.raises(ParameterError, match="contour.feed = True"):
        Circle(feed=True, acceleration=1.0)  # type: ignore[arg-type]
    assert Circle(feed=LIMITS["feed"], acceleration=LIMITS["acceleration"], radius=1.0).length


FIT = """extends = "wang2021"
[fit]
drive = {drive}
table_position = {position}
free = {free}
estimates = {estimates}
covariance = {cov}
interrupted = false
"""
GOOD = {"drive": '"cdfs"', "position": "0.4", "free": '["table.mass"]', "estimates": "[20.0]",
        "cov": "[[1e-6]]"}


@pytest.mark.parametrize(("key", "value", "field"), [
    ("free", "[5]", "fit.free"), ("free", "[]", "fit.free"), ("free", '"table.mass"', "fit.free"),
    ("cov", '"x"', "fit.covariance"), ("cov", '[["x"]]', "fit.covariance"),
    ("estimates", "[nan]", "fit.estimates"), ("estimates", '["20"]', "fit.estimates"),
    ("position", '"0.4"', "fit.table_position"), ("position", "nan", "fit.table_position"),
    ("drive", "3", "fit.drive"),
])
def test_a_fit_file_with_a_key_of_the_wrong_kind_is_refused_naming_it(
        tmp_path: Path, key: str, value: str, field: str) -> None:
    """``free = [5]`` gave an AttributeError traceback in predict and validate, a text
    covariance numpy's "could not convert string to float", a text table position was taken."""
    from feeddrive.analysis.predict import read_fit_record

    path = tmp_path / "fit.toml"
    path.write_text(FIT.format(**{**GOOD, key: value}), encoding="utf-8")
    with pytest.raises(ParameterError) as err:
        read_fit_record(path)
    assert err.value.field == field
    path.write_text(FIT.format(**GOOD), encoding="utf-8")
    assert read_fit_record(path).free == ("table.mass",)


def test_predict_and_validate_refuse_it_in_one_line(tmp_path: Path) -> None:
    path = tmp_path / "fit.toml"
    path.write_text(FIT.format(**{**GOOD, "free": "[5]"}), encoding="utf-8")
    for args in (["predict", str(path)], ["validate", str(path), str(tmp_path / "t.csv")]):
        result = runner.invoke(app, args)
        assert result.exit_code == 2 and "Traceback" not in result.output, result.output
        assert "fit.free = [5]" in result.output, result.output


def test_a_profile_longer_than_8192_s_is_a_uniform_grid() -> None:
    """A 1-ms grid past 8192 s (where doubles are 1.8e-12 s apart) was refused as "expected a
    uniform, increasing grid" by an absolute 1e-12-s spread: a 10 000-s CSV profile and the
    30-s-dwell staircase from 3 to 0.05 mm/s (8 886 s)."""
    from feeddrive.model import reference

    profile, _ = reference.stepdown(3e-3, 0.05e-3, step=1e-5, dwell=30.0)
    assert profile.time[-1] > 8192.0
    _, table = profile.encode()
    assert table.shape[1] == profile.time.size


def test_a_long_csv_profile_runs_and_a_huge_one_is_refused(tmp_path: Path) -> None:
    ok = tmp_path / "t10000.csv"
    ok.write_text("time,table_speed\n0,1\n10000,1\n", encoding="utf-8")
    args = ["simulate", "--drive", "cdfs", "--profile", "csv", "--duration", "0.2",
            "--profile-file"]
    result = runner.invoke(app, [*args, str(ok)])
    assert result.exit_code == 0, result.output
    huge = tmp_path / "t1e6.csv"
    huge.write_text("time,table_speed\n0,1\n1000000,1\n", encoding="utf-8")
    result = runner.invoke(app, [*args, str(huge)])
    assert result.exit_code == 2, result.output
    assert "the profile spans 1e+06 s" in result.output and "expected ≤ 20000 s" in \
        result.output


@pytest.mark.parametrize(("args", "says"), [
    (["--profile", "stepdown", "--table-speed", "3", "--lowest-speed", "0.05", "--step",
      "1e-6"], "--step = 1e-06: makes a profile of 1.18e+07 s"),
    (["--profile", "stepdown", "--table-speed", "3", "--lowest-speed", "0.05", "--dwell",
      "1e300"], "--dwell = 1e+300: makes a profile of 2.96e+302 s"),
    (["--profile", "sine", "--table-speed", "1", "--frequency", "1e300"],
     "--frequency = 1e+300: expected a frequency > 0, ≤ 1000 [Hz]"),
])
def test_a_profile_too_long_or_too_fast_is_refused_before_any_array(args: list[str],
                                                                    says: str) -> None:
    """A 1e-9-mm/s step hung making its staircase; a 1e300-s dwell and a 1e300-Hz sine ended
    in numpy's "Maximum allowed size exceeded"."""
    result = runner.invoke(app, ["simulate", "--drive", "cdfs", *args])
    assert result.exit_code == 2, result.output
    errors = [s for s in result.output.splitlines() if s.startswith("error: ")]
    assert len(errors) == 1 and errors[0].startswith(f"error: {says}"), result.output


@pytest.mark.parametrize(("text", "says"), [
    ("x,y\n0,0\n10,0\n10,abc\n10,10\n", "line 4: 'abc' is not a number"),
    ("x,y\n0,0\nnan,nan\n10,10\n", "line 3: 'nan'; expected a finite number"),
    ("time,position\n0,0\n1,10\n", "has no column for the path's first coordinate ('x')"),
    ("x,y,z\n0,0\n", "line 2: 2 cells; expected 3"),
    ("x [in],y\n0,0\n1,1\n", "unit 'in'"),
    ("0,0\n", "fewer than two points"),
])
def test_a_path_file_is_read_by_its_header_and_every_row(tmp_path: Path, text: str,
                                                          says: str) -> None:
    """`simulate --contour csv` skipped rows with bad cells, read a `y,x` header as x, y and
    took a `time,position` file as a path (np.genfromtxt): an outside check, 2026-12-07."""
    from feeddrive.machine.contour import from_csv

    path = tmp_path / "p.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ParameterError, match="contour.csv") as err:
        from_csv(path, feed=0.001, acceleration=1.0)
    assert says in str(err.value)


def test_a_path_files_columns_are_taken_by_name_and_unit(tmp_path: Path) -> None:
    from feeddrive.machine.contour import from_csv

    path = tmp_path / "p.csv"
    for text in ("y,x\n0,0\n0,10\n", "x [m],y [m]\n0,0\n0.01,0\n", "# a move\n0,0\n10,0\n",
                 "x_mm,y_mm\n5,5\n15,5\n"):
        path.write_text(text, encoding="utf-8")
        end = from_csv(path, feed=0.001, acceleration=1.0).points[-1]
        assert end == pytest.approx((0.01, 0.0), abs=1e-15), text  # 10 mm along x


@pytest.mark.parametrize(("args", "says"), [
    (["stability", "--points", "100000000"], "--points = 100000000: expected a whole number 2 "
                                             "… 10000"),
    (["stiffness", "--positions", "1e-300"], "--positions = 1e-300: k_sa is not finite there"),
    (["friction", "--stiffness", "1e300"], "--stiffness = 1e+300: expected a finite value > 0, "
                                           "≤ 100000 [N/µm]"),
    (["friction", "--mass", "1e300"], "--mass = 1e+300: expected a finite value > 0, ≤ 100000 "
                                      "[kg]"),
    (["compensate", "--compare", "--schemes", ","], "--schemes = ',': expected one name or more"),
    (["compensate", "--compare", "--metrics", ""], "--metrics = '': expected one name or more"),
    (["compensate", "--metrics", "bogus"], "--metrics = 'given': an option of --compare"),
    (["compensate", "--band", "5"], "--band = 'given': an option of --compare"),
    (["loops", "--with-friction", "--table-speed", "0"],
     "--table-speed = 0.0: expected a non-zero speed [mm/s]"),
    # "name = 500.0: expected text", "table = 'float': expected Table"
    (["calibrate", "--unknown", "name"], "--unknown = 'name': not a numeric parameter"),
    (["calibrate", "--unknown", "table"], "--unknown = 'table': a section of the parameter set, "
                                          "not a numeric parameter"),
])
def test_more_bad_values_are_one_line_naming_the_option(args: list[str], says: str) -> None:
    """An outside check, 2026-12-07: 10^8 scan points ran for hours, 1e-300 mm printed k_sa =
    inf (and --json failed), 1e300 N/µm ended in scipy's words and 1e300 kg was taken, empty
    scheme or metric lists gave an empty table with exit 0, and --compare's options were
    ignored without it."""
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    errors = [s for s in result.output.splitlines() if s.startswith("error: ")]
    assert len(errors) == 1 and errors[0].startswith(f"error: {says}"), result.output


def test_the_friction_scans_limits_are_the_parameter_fields():
    from feeddrive.cli.friction_cmd import LARGEST
    from feeddrive.model.slot_ranges import _field
    from feeddrive.units import N_PER_UM

    assert LARGEST["--mass"] == _field("table.mass").high
    assert LARGEST["--stiffness"] * N_PER_UM == _field("stiffness.equivalent_stiffness").high
    assert LARGEST["--damping"] == _field("stiffness.axial_damping").high


SWEEP = 'name = "s"\n[design]\nkind = "grid"\n[quantity]\nkind = "linear-band"\n{more}\n'


@pytest.mark.parametrize(("more", "says"), [
    ("high = 1e300\n[axes]\ntable_position = [200, 400]",
     "quantity.high = 1e+300: expected a number > 0, ≤ 100000 [mm/s]"),
    ("linear_points = 100000000\n[axes]\ntable_position = [200, 400]",
     "quantity.linear_points = 100000000: expected a whole number 2 … 10000"),
    ("[axes]\nnut_speed = [nan, 1]", "axes.nut_speed.values = nan: expected a finite number"),
    ('[axes]\ntable_position = ["a", "b"]',
     "axes.table_position.values = 'a': expected a finite number"),
    ("[axes]\nnut_speed = [-1, 1]", "axes.nut_speed.values = -1: expected a speed ≥ 0 [mm/s]"),
])
def test_a_sweep_refuses_its_bad_values_before_the_first_point(tmp_path: Path, more: str,
                                                                says: str) -> None:
    """A high of 1e300 mm/s failed every point and exited 0; a NaN or text axis value failed
    at its point naming no file (an outside check, 2026-12-07)."""
    config = tmp_path / "s.toml"
    config.write_text(SWEEP.format(more=more), encoding="utf-8")
    result = runner.invoke(app, ["sweep", str(config), "--dry-run"])
    assert result.exit_code == 2, result.output
    assert result.output.strip() == f"error: {config}: {says}", result.output


def test_a_store_that_is_no_database_is_named_by_the_option_given(tmp_path: Path) -> None:
    config = tmp_path / "s.toml"
    config.write_text(SWEEP.format(more="[axes]\ntable_position = [200, 400]"),
                      encoding="utf-8")
    notes = tmp_path / "notes.txt"
    notes.write_text("my notes\n", encoding="utf-8")
    result = runner.invoke(app, ["sweep", str(config), "--store", str(notes)])
    assert result.exit_code == 2, result.output
    assert result.output.strip().startswith(f"error: --store {notes}: not a feeddrive sweep "
                                            "store"), \
        result.output  # was "--output"
    assert notes.read_text(encoding="utf-8") == "my notes\n"


@pytest.mark.parametrize(("args", "says"), [
    (["simulate", "--drive", "linear-motor", "--position", "1e300", "--table-speed", "1"],
     "--position = 1e+300: expected |position| ≤ 100000 [mm]"),
    (["export", "fmu", "--drive", "linear-motor", "--position", "1e300", "--out", "x.fmu"],
     "--position = 1e+300: expected |position| ≤ 100000 [mm]"),
    (["analyze", "--circular", "absent.csv", "--pitch", "1e300"],
     "--pitch = 1e+300: expected a value > 0, ≤ 10000 [mm]"),
])
def test_positions_and_lengths_no_drive_has_are_refused(args: list[str], says: str,
                                                        tmp_path: Path,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """A linear motor's --position 1e300 was simulated and exported, a circular test's
    --pitch 1e300 taken (an outside check, 2026-12-07)."""
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    errors = [s for s in result.output.splitlines() if s.startswith("error: ")]
    assert errors == [f"error: {says}"], result.output


def test_a_section_given_as_a_free_parameter_is_named_a_section() -> None:
    """`fit --free screw` said "'screw' is not a field … (did you mean 'screw'?)"."""
    from feeddrive.analysis.fit import FitError, _field_meta
    from feeddrive.parameters import preset

    for path in ("screw", "friction.guide"):
        with pytest.raises(FitError, match=f"--free {path}: a section of the parameter set"):
            _field_meta(preset("wang2021"), path)


def test_a_store_that_is_no_database_is_refused_before_the_design_is_built(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A text file given as the store was refused only when the store was opened, after the
    points had been built (7 s for a 10 000-point grid, 90 s for 90 000; predict 6 s for
    5 000 samples: an outside check, 2026-12-07).  Here the design is never built."""
    from feeddrive.sweep import design

    def built(*args: object, **kwargs: object) -> None:
        raise AssertionError("the design was built before the store was checked")

    monkeypatch.setattr(design.SweepConfig, "points", built)
    config = tmp_path / "s.toml"
    config.write_text(SWEEP.format(more="[axes]\ntable_position = [200, 400]"),
                      encoding="utf-8")
    notes = tmp_path / "notes.txt"
    notes.write_text("my notes\n", encoding="utf-8")
    for args in (["--store", str(notes)], []):
        if not args:  # the configuration's own store
            config.write_text(f'store = "{notes.name}"\n' + config.read_text(encoding="utf-8"),
                              encoding="utf-8")
        result = runner.invoke(app, ["sweep", str(config), *args])
        assert result.exit_code == 2, result.output
        assert "not a feeddrive sweep store" in result.output
    assert notes.read_text(encoding="utf-8") == "my notes\n"


def test_a_store_of_other_tables_is_refused_before_any_work(tmp_path: Path) -> None:
    import sqlite3

    from feeddrive.sweep.store import StoreError, check_existing_store

    other = tmp_path / "other.sqlite"
    with sqlite3.connect(other) as db:
        db.execute("CREATE TABLE accounts (id INTEGER, owner TEXT)")
    with pytest.raises(StoreError, match=r"--store .*other.sqlite: not a feeddrive sweep "
                       r"store \(an SQLite file with the tables accounts\)"):
        check_existing_store(other, "--store")
    check_existing_store(tmp_path / "absent.sqlite", "--store")  # created later: passes


def test_sensitivitys_ctrl_c_names_its_store(monkeypatch: pytest.MonkeyPatch,
                                             tmp_path: Path) -> None:
    """"every finished point is in the store" named no file, and --help no default (an
    outside check, 2026-12-07: it was sensitivity-wang2021-cdfs-critical-speed.sqlite)."""
    from feeddrive.analysis import sensitivity as module

    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(module, "sensitivity", interrupted)
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["sensitivity", "--quantity", "critical-speed"])
    assert result.exit_code == 130, result.output
    assert ("every finished point is in sensitivity-wang2021-cdfs-critical-speed.sqlite"
            in result.output)
    assert module.default_store("wang2021", "cdfs", "critical-speed").name == \
        "sensitivity-wang2021-cdfs-critical-speed.sqlite"
    shown = " ".join(runner.invoke(app, ["sensitivity", "--help"], terminal_width=300)
                     .output.replace("│", " ").split())
    assert "default: sensitivity-SET-DRIVE-QUANTITY.sqlite in the working folder" in shown


def test_creep_both_says_the_finished_search_when_the_step_down_is_interrupted(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Ctrl-C in the step-down dropped the search from rest that had finished (an outside
    check, 2026-12-07); its answer is said before the exit."""
    from feeddrive.analysis import critical

    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(critical, "critical_speed_stepdown", interrupted)
    result = runner.invoke(app, ["creep", "--drive", "cdfs", "--low", "1.5", "--high", "1.7"])
    assert result.exit_code == 130, result.output
    assert ("interrupted in the step-down; the search from rest had finished: critical "
            "creeping speed 1.56 mm/s") in result.output, result.output


def test_a_circular_tests_runs_report_progress() -> None:
    """run_circular_test took `progress` and never passed it on: `feeddrive circular` sat
    silent for 5 s (an outside check, 2026-12-07)."""
    from feeddrive.analysis.circular_run import run_circular_test
    from feeddrive.machine import load_machine

    seen: list[tuple[float, float]] = []
    tr = run_circular_test(load_machine("xy-table"), radius=0.01, feed=2000 / 6e4,
                           progress=lambda t, end: seen.append((t, end)))
    assert seen and all(0 < t <= end for t, end in seen)
    ends = sorted({end for _, end in seen})
    assert len(ends) == 1 and seen[-1][0] == pytest.approx(ends[0])
    # one bar over both runs, the CW run's time after the CCW run's (session 25: it went to
    # each run's end and started again, "… / 439.8 s" of the runs' 879.6 s)
    first = float(tr.results["CCW"].time[-1])
    assert ends[0] == pytest.approx(first + float(tr.results["CW"].time[-1]))
    times = [t for t, _ in seen]
    assert times == sorted(times) and times[-1] > first


def test_a_simulated_circle_without_a_revolution_is_said_of_the_simulation(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """`circular --feed 100` failed with the record reader's advice, "check --centre and the
    x, y columns" — options `circular` does not have (an outside check, 2026-12-07)."""
    from feeddrive.analysis import circular_run

    def no_revolution(*args: object, **kwargs: object) -> None:
        raise ValueError("no full revolution about the centre: a circular test needs at least "
                         "360° turned one way (check --centre and the x, y columns)")

    monkeypatch.setattr(circular_run, "circular_test", no_revolution)
    result = runner.invoke(app, ["circular", "--radius", "5", "--feed", "3000"])
    # after the runs: exit status 1, as a failed simulation (session 25: the runs' trace is
    # kept, tests/unit/test_circular_stick_slip.py)
    assert result.exit_code == 1, result.output
    assert "the simulated path did not turn 360° one way" in result.output
    assert "--centre" not in result.output
