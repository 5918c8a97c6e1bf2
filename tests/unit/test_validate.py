"""`feeddrive validate` (issue 36 item 4): a fitted set scored on a held-out record.

Records in the EMPS layout from `feeddrive.analysis.rig_record.emps_layout` (feeddrive's own
integrator: this checks the scoring and the refusals, not a calibration). The fit % is
recomputed here from its definition (Ljung 1999, Sect. 16.6: 100·(1 − ‖y − ŷ‖/‖y − ȳ‖)).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.analysis import validate as valmod
from feeddrive.analysis.fit import FitError, fit_drive
from feeddrive.analysis.rig_record import emps_layout, parse_map, read_rig_record
from feeddrive.analysis.validate import validate
from feeddrive.cli import app

DRIVE = "linear-motor"
MAP = parse_map(["time=t position=qm reference=qg force=vir"])
FREE = ["table.mass", "friction.guide.positive.coulomb_force"]


@pytest.fixture(scope="module")
def fitted(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A fit on one record (seed 1, 0.2-m move) and a held-out record of the same axis
    (seed 2, 0.15-m move); the truth is mass 24 kg, F_c 17 N."""
    d = tmp_path_factory.mktemp("validate")
    base = fd.preset("linear-motor-example")
    truth = base.replace_path("table.mass", 24.0).replace_path(FREE[1], 17.0)
    emps_layout(d / "est.mat", truth, drive=DRIVE, seed=1)
    emps_layout(d / "val.mat", truth, drive=DRIVE, seed=2, stroke=0.15)
    rec = read_rig_record(d / "est.mat", MAP, base, drive=DRIVE)
    result = fit_drive(base, [rec.experiment], FREE, drive=DRIVE, profile=False)
    (d / "fitted.toml").write_text(result.fitted_toml("linear-motor-example"), encoding="utf-8")
    return d / "fitted.toml", d / "val.mat"


def test_validate_scores_a_held_out_record(fitted: tuple[Path, Path]) -> None:
    fit_file, val = fitted
    record = read_rig_record(val, MAP, fd.load(fit_file), drive=DRIVE)
    result = validate(fit_file, [record.experiment])
    assert {s.signal for s in result.signals} == {"table_position", "motor_current"}
    for s, (name, y) in zip(result.signals, record.experiment.signals.items(), strict=True):
        yhat = result.predicted[0][name]
        expected = 100 * (1 - np.linalg.norm(y - yhat) / np.linalg.norm(y - y.mean()))
        assert s.fit_percent == pytest.approx(expected, rel=1e-12)
        assert s.nrmse == pytest.approx(np.sqrt(np.mean((y - yhat) ** 2)) / np.ptp(y))
    current = next(s for s in result.signals if s.signal == "motor_current")
    # the right model on a record of the same axis: the current is predicted to its noise
    # (0.5-N force noise over a 0.7-A swing), and ~95 % of it lies inside the 95 % band
    assert current.fit_percent > 90
    assert 0.90 <= current.inside_band <= 0.99


def test_validate_refuses_another_drive_and_paths_the_record_cannot_show(
        fitted: tuple[Path, Path], monkeypatch: pytest.MonkeyPatch) -> None:
    fit_file, val = fitted
    record = read_rig_record(val, MAP, fd.load(fit_file), drive=DRIVE)

    def refuse(task: object) -> dict[str, object]:
        raise AssertionError("a simulation ran")

    monkeypatch.setattr(valmod, "simulate_experiment", refuse)
    with pytest.raises(FitError, match="fitted on the LINEAR-MOTOR; these records are of "
                                       "the CDFS") as err:
        validate(fit_file, [record.experiment], drive="cdfs")
    assert "\n" not in str(err.value)
    text = fit_file.read_text(encoding="utf-8")
    line = next(ln for ln in text.splitlines() if ln.startswith("free = "))
    other = fit_file.with_name("negative.toml")
    other.write_text(text.replace(line, line.replace("positive", "negative")), encoding="utf-8")
    with pytest.raises(FitError, match="frees friction.guide.negative.coulomb_force, which "
                                       "these records cannot show"):
        validate(other, [record.experiment])


def test_validate_command(fitted: tuple[Path, Path], tmp_path: Path) -> None:
    fit_file, val = fitted
    runner = CliRunner()
    args = ["validate", str(fit_file), str(val), "--map",
            "time=t position=qm reference=qg force=vir"]
    res = runner.invoke(app, [*args, "--json", "--plot", str(tmp_path / "v.png")])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert [s["signal"] for s in data["signals"]] == ["table_position", "motor_current"]
    assert (tmp_path / "v.png").stat().st_size > 0
    res = runner.invoke(app, args)
    assert "% inside the 95 % prediction band" in res.stdout and "fit " in res.stdout
    bad = runner.invoke(app, [*args, "--drive", "cdfs"])
    assert bad.exit_code == 2 and "fitted on the LINEAR-MOTOR" in bad.output
