"""docs/fmu.md against the code: the names it lists, its fmpy and PathSim examples run."""

from __future__ import annotations

import contextlib
import io
import os
import re
from pathlib import Path

import numpy as np
import pytest

from feeddrive.engine.simulate import DriveSystem, simulate
from feeddrive.fmu.description import SETTINGS, variables
from feeddrive.fmu.model import build
from feeddrive.model.reference import SampledSpeed
from feeddrive.parameters import preset

DOC = Path(__file__).parents[2] / "docs" / "fmu.md"
TEXT = DOC.read_text(encoding="utf-8")


def _example(heading: str) -> str:
    part = TEXT.split(heading, 1)[1]
    return part.split("```python\n", 1)[1].split("```", 1)[0]


def test_docs_name_every_input_output_and_setting() -> None:
    for drive, params in (("cdfs", "wang2021"), ("ddfs", "wang2021"),
                          ("linear-motor", "linear-motor-example"),
                          ("rack-pinion", "rack-pinion-example")):
        fm = build(preset(params), drive, 0.4)
        for v in variables(fm, "cs"):
            if v.causality in ("input", "output"):
                assert f"`{v.name}`" in TEXT, v.name
    for name, *_ in SETTINGS:
        assert f"`{name}`" in TEXT or name.startswith("controller."), name
    assert "`controller.position_period`" in TEXT
    import typer

    from feeddrive.cli import app

    command = typer.main.get_command(app).commands["export"].commands["fmu"]  # type: ignore[attr-defined]
    options = {o for param in command.params for o in param.opts}
    usage = TEXT.split("```", 2)[1]
    assert set(re.findall(r"--[a-z-]+", usage)) == options - {"--help"}


@pytest.mark.slow
def test_fmpy_example_runs_and_matches_feeddrive(tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """The worked example, as printed, and the same run in feeddrive (held reference, the
    guide's bristle stiffness changed as in the example's start values)."""
    pytest.importorskip("fmpy")
    monkeypatch.chdir(tmp_path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(_example("### fmpy"), str(DOC), "exec"), {})
    shown = float(re.search(r"x\(2 s\) = ([0-9.]+) mm", out.getvalue()).group(1))
    p = preset("wang2021")
    p = p.with_values(friction=p.friction.with_values(
        guide=p.friction.guide.with_values(bristle_stiffness=2.0e8)))
    t = np.arange(0.0, 2.0 + 1e-9, 1e-3)
    ramp = np.minimum(t / 0.1, 1.0)
    r = simulate(DriveSystem(p, "ddfs", 0.4),
                 SampledSpeed(t, 0.5e-3 * ramp, 16e-3 * ramp, hold=True), 2.0)
    assert shown == pytest.approx(r["table_position"][-1] * 1e3, abs=1e-4)
    assert os.path.exists(tmp_path / "ddfs.fmu")


@pytest.mark.slow
def test_pathsim_example_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("pathsim_fmi")
    from feeddrive.fmu import export_fmu

    monkeypatch.chdir(tmp_path)
    export_fmu(preset("wang2021"), "ddfs", "ddfs.fmu")
    scope: dict = {}
    exec(compile(_example("### PathSim"), str(DOC), "exec"), scope)
    t, (x,) = scope["scope"].read()
    assert t[-1] == pytest.approx(1.0)
    assert 0.4e-3 < x[-1] < 0.6e-3  # 0.5 mm/s for 1 s
    # the docs: PathSim's record leads by one communication step (fmpy's run of the same FMU)
    from fmpy import simulate_fmu

    ref = simulate_fmu("ddfs.fmu", stop_time=1.1, output_interval=1e-3,
                       start_values={"table_speed_reference": 0.5e-3,
                                     "nut_speed_reference": 16e-3}, output=["table_position"])
    xr = ref["table_position"]
    n = len(x)
    stroke = abs(xr[n - 1] - xr[0])
    shifted = np.max(np.abs(x - xr[1:n + 1])) / stroke
    unshifted = np.max(np.abs(x - xr[:n])) / stroke
    assert shifted <= 1e-7  # docs: 5e-8
    assert unshifted >= 1e-3  # docs: 2.7e-3


@pytest.mark.slow
def test_parameter_study_example_runs_and_matches_feeddrive(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The parameter study as printed: nine reset + simulate runs of one instance; the
    printed maximum following error is feeddrive.simulate's (DOPRI5 at the same default
    tolerances, the held reference) within 0.01 µm: two DOPRI5 runs on different step grids
    at rtol 1e-6 differ by a few nm (measured: 0.003 µm of 68 µm here; 5.3e-3 µm over the
    nine runs of docs/fmu.md)."""
    pytest.importorskip("fmpy")
    from feeddrive.engine.simulate import SolverOptions

    monkeypatch.chdir(tmp_path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(_example("### Parameter studies"), str(DOC), "exec"), {})
    rows = re.findall(r"m = ([0-9.]+) kg, K_vp = ([0-9.]+) A s/m: max \|e\| = ([0-9.]+) µm",
                      out.getvalue())
    assert len(rows) == 9
    shown = {(float(m), float(k)): float(e) for m, k, e in rows}
    assert len(set(shown.values())) > 1  # the parameters reached the runs
    t = np.arange(0.0, 1.0 + 1e-9, 1e-3)
    profile = SampledSpeed(t, 2e-3 * np.minimum(t / 0.1, 1.0), hold=True)
    w = preset("wang2021")
    for mass, kvp in ((15.0, 30.0), (30.0, 60.0)):
        p = w.with_values(table=w.table.with_values(mass=mass),
                          controller=w.controller.with_values(velocity_gain=kvp))
        r = simulate(DriveSystem(p, "cdfs", 0.4), profile, 1.0,
                     options=SolverOptions(method="dopri5"))
        e = np.asarray(r["following_error"])[np.asarray(r.time) >= 0.5 - 1e-12]
        assert shown[(mass, kvp)] == pytest.approx(np.max(np.abs(e)) * 1e6, abs=0.01)


def test_agreement_table_is_the_benchmarks(tmp_path: Path) -> None:
    """Each agreement figure of docs/fmu.md names the method and tolerances it holds for and
    is benchmarks/results/bench_fmu.json's, to its two printed digits (bench_fmu.py)."""
    import json

    rows = json.loads((Path(__file__).parents[2] / "benchmarks" / "results" /
                       "bench_fmu.json").read_text(encoding="utf-8"))["rows"]
    by = {r["scenario"]: r for r in rows}
    table = TEXT.split("| FMU at | feeddrive at |", 1)[1].split("\n\n", 1)[0]
    keys = {("1000× tighter tolerances", "`dopri5`, 1000× tighter"): "dev_fmu_vs_dopri5_tight_rel",
            ("1000× tighter tolerances", "`modal` (the default method), 1000× tighter"):
                "dev_fmu_vs_modal_tight_rel",
            ("default tolerances", "`modal`, 1000× tighter"): "dev_fmu_rel",
            ("default tolerances", "`dopri5`, default tolerances"): "dev_fmu_vs_dopri5_default_rel",
            ("default tolerances", "`modal`, default tolerances"): "dev_fmu_vs_modal_default_rel"}
    seen = 0
    for line in table.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if (cells[0], cells[1]) not in keys:
            continue
        key = keys[(cells[0], cells[1])]
        for scenario, cell in zip(("cdfs-2", "cdfs-1.2", "ddfs-0.5-16"), cells[2:], strict=True):
            shown = f"{by[scenario][key]:.1e}".replace("e-0", "e-")
            assert cell == shown, (key, scenario)
        seen += 1
    assert seen == len(keys)
    from feeddrive.engine.simulate import SolverOptions

    assert all(r["default_method"] == SolverOptions().method == "modal" for r in rows)
