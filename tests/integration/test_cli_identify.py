"""`feeddrive identify static|dynamic|merge` and `feeddrive analyze` on generated CSV files.

Data: Wang2021 Table 1 screw-shaft friction (``preset("wang2021")``); static tests with 2 %
noise proportional to the force; pre-sliding tests simulated for the screw-site mass
(J_motor + J_shaft)/H² ≈ 2243 kg with 2 % position noise; position traces of a step-down run
(Wang2021 Sect. 6) as in tests/unit/test_trace.py.
"""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

import feeddrive
from feeddrive.analysis.presliding import site_mass
from feeddrive.analysis.presliding_rig import simulate_presliding
from feeddrive.cli import app
from feeddrive.model.friction.stribeck import steady_friction

runner = CliRunner()
PARAMS = feeddrive.preset("wang2021")
SCREW = PARAMS.friction.screw


def run(*args: str) -> Any:
    return runner.invoke(app, [str(a) for a in args])


def one_line_error(result: Any, *fragments: str) -> str:
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error: ")
    for f in fragments:
        assert f in lines[0], lines[0]
    return lines[0]


def write_csv(path: Path, header: str, columns: list[np.ndarray], fmt: str = "{:.9g}") -> Path:
    rows = [",".join(fmt.format(v) for v in row) for row in zip(*columns, strict=True)]
    path.write_text(header + "\n" + "\n".join(rows) + "\n", encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def static_csv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    v = np.repeat(np.geomspace(0.05, 50.0, 40), 5)  # mm/s
    v = np.concatenate([v, -v])
    f = steady_friction(v * 1e-3, SCREW)
    f = f * (1.0 + 0.02 * np.random.default_rng(0).standard_normal(v.size))
    return write_csv(tmp_path_factory.mktemp("static") / "static.csv", "speed [mm/s],force [N]",
                     [v, f])


@pytest.fixture(scope="module")
def presliding_csv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    t = np.arange(0.0, 1.0, 1.0 / 2000.0)
    f = 30.0 * np.clip((t - 0.05) / 0.002, 0.0, 1.0)
    x = simulate_presliding(t, f, site_mass(PARAMS, "screw", "cdfs"), SCREW)
    x = x + 0.01 * np.ptp(x) * np.random.default_rng(1).standard_normal(x.size)
    return write_csv(tmp_path_factory.mktemp("pre") / "presliding.csv",
                     "time [s],force [N],position [um]", [t, f, x * 1e6])


def test_identify_static_recovers_table1(static_csv: Path, tmp_path: Path) -> None:
    frag, png = tmp_path / "frag.toml", tmp_path / "fit.png"
    r = run("identify", "static", static_csv, "--out", frag, "--plot", png, "--json")
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    for name in ("positive", "negative"):
        truth = SCREW.branch(name)
        assert out[name]["coulomb_force"]["value"] == pytest.approx(truth.coulomb_force,
                                                                    rel=0.05)
        vs = out[name]["stribeck_velocity"]
        assert vs["unit"] == "mm/s"
        assert vs["value"] == pytest.approx(truth.stribeck_velocity * 1e3, rel=0.05)
    data = tomllib.loads(frag.read_text(encoding="utf-8"))
    assert data["friction"]["screw"]["positive"]["static_force"] == pytest.approx(96.4, rel=0.05)
    assert png.stat().st_size > 10_000


def test_identify_static_text_output(static_csv: Path) -> None:
    r = run("identify", "static", static_csv, "--site", "guide")
    assert r.exit_code == 0, r.output
    assert "positive direction: 200 tests" in r.stdout
    assert "v_s" in r.stdout and "mm/s" in r.stdout


def test_identify_static_from_current(tmp_path: Path) -> None:
    v = np.geomspace(0.05, 50.0, 30)
    v = np.concatenate([v, -v])
    h = PARAMS.screw.lead / (2 * math.pi)
    current = steady_friction(v * 1e-3, SCREW) * h / PARAMS.screw_motor.torque_constant
    p = write_csv(tmp_path / "current.csv", "speed,current [A]", [v, current])
    r = run("identify", "static", p, "--json")
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert out["force_from"] == "current × K_t / H"
    assert out["positive"]["coulomb_force"]["value"] == pytest.approx(73.4, rel=1e-4)


def test_identify_dynamic_then_merge(static_csv: Path, presliding_csv: Path,
                                     tmp_path: Path) -> None:
    static_frag, dyn_frag = tmp_path / "static.toml", tmp_path / "dynamic.toml"
    assert run("identify", "static", static_csv, "--out", static_frag).exit_code == 0
    r = run("identify", "dynamic", presliding_csv, "--static", static_frag, "--out", dyn_frag,
            "--plot", tmp_path / "dyn.png")
    assert r.exit_code == 0, r.output
    assert "σ0 = 36." in r.stdout
    assert "σ1 = 5" in r.stdout  # determined: printed as a value with its interval
    merged = tmp_path / "merged.toml"
    r = run("identify", "merge", static_frag, dyn_frag, "--out", merged)
    assert r.exit_code == 0, r.output
    params = feeddrive.parameters.load(merged)
    assert params.name == "wang2021-identified"
    assert params.friction.screw.bristle_stiffness == pytest.approx(3.64e7, rel=0.10)
    assert params.friction.screw.positive.coulomb_force == pytest.approx(73.4, rel=0.05)


def test_identify_dynamic_says_when_sigma1_is_poorly_determined(tmp_path: Path) -> None:
    t = np.arange(0.0, 4.0, 0.01)
    f = 15.0 * (1.0 - np.cos(np.pi * t))
    x = simulate_presliding(t, f, site_mass(PARAMS, "screw", "cdfs"), SCREW)
    x = x + 0.01 * np.ptp(x) * np.random.default_rng(3).standard_normal(x.size)
    p = write_csv(tmp_path / "slow.csv", "time,force,position", [t, f, x * 1e6])
    r = run("identify", "dynamic", p)
    assert r.exit_code == 0, r.output
    assert "σ1 poorly determined: consistent with 0" in r.stdout
    assert "σ1 = " not in r.stdout
    out = json.loads(run("identify", "dynamic", p, "--json").stdout)
    assert out["bristle_damping_determined"] is False
    assert out["mass_from"] == "parameters"


@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        ("speed,force\n1,80\n2,abc\n", ["bad.csv, line 3", "'abc' is not a number"]),
        ("speed,friction\n1,80\n", ["no column 'force' or 'current'", "'speed', 'friction'"]),
        ("speed,force\n" + "".join(f"{v},80\n" for v in range(1, 4)),
         ["3 distinct positive speed", "at least 5"]),
        ("speed,force\n1,80\n-1,-80\n", ["1 distinct positive speed", "at least 5"]),
    ],
)
def test_identify_static_bad_files(tmp_path: Path, text: str, fragments: list[str]) -> None:
    p = tmp_path / "bad.csv"
    p.write_text(text, encoding="utf-8")
    one_line_error(run("identify", "static", p), *fragments)


def test_identify_bad_options(static_csv: Path, tmp_path: Path) -> None:
    one_line_error(run("identify", "static", static_csv, "--site", "spindle"), "--site")
    one_line_error(run("identify", "static", tmp_path / "none.csv"), "no such file")
    one_line_error(run("identify", "static", static_csv, "--speed-unit", "furlong/s"),
                   "furlong/s")


def test_identify_dynamic_bad_files(tmp_path: Path) -> None:
    rows = "".join(f"{0.001 * i},{i},{i}\n" for i in range(30))
    p = tmp_path / "rev.csv"
    p.write_text("time,force,position\n" + rows.replace("0.005,", "0.001,", 1), encoding="utf-8")
    one_line_error(run("identify", "dynamic", p), "rev.csv, line 7", "does not increase")
    big = tmp_path / "big.csv"
    write_csv(big, "time,force,position", [np.arange(30) * 1e-3, np.linspace(0, 150, 30),
                                           np.linspace(0, 3, 30)])
    one_line_error(run("identify", "dynamic", big), "line 21", "breakaway")  # 150·19/29 N


# ---------------------------------------------------------------- analyze


def stepdown_positions(creeping: list[bool], steps: list[float]) -> tuple[np.ndarray, ...]:
    fs, seg = 1000.0, 10.0
    t = np.arange(0.0, seg * len(steps), 1.0 / fs)
    v = np.zeros_like(t)
    prev = 0.0
    for i, (c, creeps) in enumerate(zip(steps, creeping, strict=True)):
        sel = (t >= i * seg) & (t < (i + 1) * seg)
        local = t[sel] - i * seg
        if creeps:
            phase = np.mod(local, 0.5)
            v[sel] = np.where(phase < 0.2, 0.0, 2 * c * 0.5 / 0.3 * (1 - (phase - 0.2) / 0.3))
        else:
            v[sel] = c + (prev - c) * np.exp(-local / 0.2)
        prev = c
    x = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) / fs)])
    return t, x, np.repeat(steps, int(seg * fs))


STEPS = [1.70, 1.69, 1.68, 1.67, 1.66]  # mm/s
CREEPS = [False, False, False, True, True]


def test_analyze_simulator_style_export(tmp_path: Path) -> None:
    t, x, cmd = stepdown_positions(CREEPS, STEPS)
    # feeddrive.io.results's CSV export names: time [s], table_position [mm], table_speed_reference
    p = write_csv(tmp_path / "run.csv", "time [s],table_position [mm],table_speed_reference "
                  "[mm/s]", [t, x, cmd], fmt="{:.10g}")
    png = tmp_path / "run.png"
    r = run("analyze", p, "--json", "--plot", png)
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert out["position_column"] == "table_position"
    verdicts = [s["metrics"]["verdict"] for s in out["segments"]]
    assert verdicts == ["smooth", "smooth", "smooth", "creeping", "creeping"]
    (crit,) = out["critical_speed"]
    assert crit["lowest_smooth"] == pytest.approx(1.68)
    assert crit["first_creeping"] == pytest.approx(1.67)
    assert png.stat().st_size > 10_000


def test_analyze_interferometer_export_without_command(tmp_path: Path) -> None:
    t, x, _ = stepdown_positions(CREEPS, STEPS)
    p = write_csv(tmp_path / "xl.csv", "time [s],position [um]", [t, x * 1e3], fmt="{:.10g}")
    r = run("analyze", p)
    assert r.exit_code == 0, r.output
    assert "command speed not given: estimated" in r.stdout
    assert "critical speed (positive): lowest smooth 1.68 mm/s" in r.stdout
    assert "CREEPING" in r.stdout


def test_analyze_given_command_speed(tmp_path: Path) -> None:
    t, x, _ = stepdown_positions([True], [1.55])
    p = write_csv(tmp_path / "creep.csv", "time,position", [t, x], fmt="{:.10g}")
    out = json.loads(run("analyze", p, "--command-speed", "1.55", "--json").stdout)
    (seg,) = out["segments"]
    assert seg["command_from"] == "given"
    m = seg["metrics"]
    assert m["verdict"] == "creeping"
    assert m["command_speed"] == pytest.approx(1.55)
    assert m["stick_slip_frequency"] == pytest.approx(2.0, rel=0.02)


@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        ("time,pos\n" + "".join(f"{i},{i}\n" for i in range(20)),
         ["no column 'position' or 'table_position'"]),
        ("time,position\n" + "".join(f"{i},{i}\n" for i in range(5)), ["5 data rows"]),
        ("time,position\n" + "".join(f"{i % 12},{i}\n" for i in range(20)),
         ["line 14", "does not increase"]),
        ("time,position\n" + "".join(f"{i},{'x' if i == 3 else i}\n" for i in range(20)),
         ["line 5", "'x' is not a number"]),
    ],
)
def test_analyze_bad_files(tmp_path: Path, text: str, fragments: list[str]) -> None:
    p = tmp_path / "bad.csv"
    p.write_text(text, encoding="utf-8")
    one_line_error(run("analyze", p), *fragments)


def test_analyze_zero_command_speed(tmp_path: Path) -> None:
    t, x, _ = stepdown_positions([False], [1.6])
    p = write_csv(tmp_path / "ok.csv", "time,position", [t, x])
    one_line_error(run("analyze", p, "--command-speed", "0"), "--command-speed = 0.0", "[mm/s]")


def test_identify_static_one_direction_record(tmp_path: Path) -> None:
    """Issue 22: a one-direction record gives that branch only, and says so; the fragment
    holds that branch only, so merging keeps the base set's other branch."""
    from feeddrive.model.friction.stribeck import steady_friction
    from feeddrive.parameters import preset

    screw = preset("wang2021").friction.screw
    v = np.geomspace(0.05, 20.0, 25)  # [mm/s]
    f = steady_friction(v * 1e-3, screw)
    p = tmp_path / "one.csv"
    write_csv(p, "speed,force", [v, f])
    r = run("identify", "static", p, "--out", tmp_path / "frag.toml")
    assert r.exit_code == 0, r.output
    assert "positive direction only" in r.stdout
    frag = (tmp_path / "frag.toml").read_text(encoding="utf-8")
    assert "[friction.screw.positive]" in frag and "negative" not in frag
