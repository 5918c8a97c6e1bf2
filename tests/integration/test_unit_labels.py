"""Issue 41 item 3: `fit` and its fitted file printed ``velocity_integral_gain`` in [A/rad]
while `params show` and the explorer said [A/m, per table speed] — the factor H ≈ 10⁻³ the
docs say decides whether anything creeps.  One source now labels every parameter:
:func:`feeddrive.parameters.validation.unit_label`, the model slot's basis-resolved unit."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.cli import app
from feeddrive.explore.settings import FIELDS, field_units
from feeddrive.model.slots import AXIS_SLOT_FIELDS, slot_table
from feeddrive.parameters.validation import path_unit_label
from feeddrive.sweep.design import numeric_paths

runner = CliRunner()
PRESETS = ("wang2021", "wang2021-literal")  # velocity_gain_basis "table" and "motor"


def _shown_labels(preset: str) -> dict[str, str]:
    """path → label of every ``key = value  # [label]`` line of `params show`."""
    out = runner.invoke(app, ["params", "show", "--preset", preset])
    assert out.exit_code == 0, out.output
    section, labels = "", {}
    for line in out.stdout.splitlines():
        head = re.fullmatch(r"\[([\w.]+)\]", line.strip())
        if head:
            section = head.group(1)
            continue
        m = re.match(r"(\w+) = .*?# \[(.*?)\]", line)
        if m:
            labels[f"{section}.{m.group(1)}" if section else m.group(1)] = m.group(2)
    return labels


@pytest.mark.parametrize("preset", PRESETS)
def test_params_show_labels_every_numeric_parameter_by_the_one_source(preset: str) -> None:
    params = fd.preset(preset)
    shown = _shown_labels(preset)
    paths = numeric_paths(params)
    assert len(paths) > 50
    wrong = {p: (shown.get(p), path_unit_label(params, p)) for p in paths
             if shown.get(p) != path_unit_label(params, p)}
    assert wrong == {}


@pytest.mark.parametrize("preset", PRESETS)
def test_the_explorer_labels_its_knobs_by_the_one_source(preset: str) -> None:
    params = fd.preset(preset)
    units = field_units(params)
    checked = 0
    for f in FIELDS:
        if not f.path or path_unit_label(params, f.path) in ("-", ""):
            continue  # a dimensionless knob keeps its own word ("per rev")
        assert units[f.name] == path_unit_label(params, f.path), f.name
        checked += 1
    assert checked >= 4  # the three loop gains and the ripple amplitude


@pytest.mark.parametrize(("preset", "label"), [("wang2021", "A/m, per table speed"),
                                               ("wang2021-literal", "A/rad")])
def test_the_label_is_the_model_slots_unit(preset: str, label: str) -> None:
    """The controller gains' labels carry the unit of their slot in the assembled model
    (`params slots`), with the basis note on the table basis."""
    params = fd.preset(preset)
    model = fd.DriveSystem(params, "cdfs", 0.4).model(fd.ConstantSpeed(1e-3))
    slots = {name: unit for name, _, unit in slot_table(model)}
    for slot, field in AXIS_SLOT_FIELDS.items():
        if f"controller.screw.{slot}" in slots:
            shown = path_unit_label(params, f"controller.{field}")
            assert shown.split(",")[0] == slots[f"controller.screw.{slot}"], field
    assert path_unit_label(params, "controller.velocity_integral_gain") == label


def test_fit_and_its_fitted_file_use_the_same_label(tmp_path: Path) -> None:
    trace = tmp_path / "run.csv"
    fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4), fd.ConstantSpeed(2e-3),
                0.2).save(trace)
    out = tmp_path / "fitted.toml"
    free = ["controller.velocity_integral_gain", "friction.screw.positive.coulomb_force"]
    result = runner.invoke(app, ["fit", str(trace), "--free", free[0], "--free", free[1],
                                 "--out", str(out), "--json"])
    assert result.exit_code == 0, result.output
    params = fd.preset("wang2021")
    units = {e["path"]: e["unit"] for e in json.loads(result.stdout)["estimates"]}
    assert units == {p: path_unit_label(params, p) for p in free}
    assert units[free[0]] == "A/m, per table speed" and units[free[1]] == "N"
    text = out.read_text(encoding="utf-8")
    assert re.search(r"^velocity_integral_gain = \S+  # \[A/m, per table speed\]", text, re.M)
    assert re.search(r"^coulomb_force = \S+  # \[N\]", text, re.M)
