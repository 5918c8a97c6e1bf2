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
