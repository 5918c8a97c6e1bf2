"""The command line: `feeddrive stiffness`, `feeddrive friction`, `feeddrive params`."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from feeddrive.cli import app
from feeddrive.engine.error_estimate import SHADOW_FACTOR, SHADOW_RATIO

runner = CliRunner()

TABLE3_KSA_N_PER_UM = [276.13, 220.9, 207.1, 220.9, 276.13]  # Wang2021 Table 3


def run(*args: str) -> Any:
    return runner.invoke(app, list(args))


def one_line_error(result: Any) -> str:
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error: ")
    return str(lines[0])


# ------------------------------------------------------------------ stiffness


def test_stiffness_json_reproduces_table3_row() -> None:
    """Acceptance: Wang2021 Table 3 k_sa row within 0.1 %."""
    result = run("stiffness", "--positions", "200,300,400,500,600", "--json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    rows = data["positions"]
    assert [r["position_mm"] for r in rows] == [200.0, 300.0, 400.0, 500.0, 600.0]
    k_sa = [r["screw_axial_stiffness_N_per_um"] for r in rows]
    np.testing.assert_allclose(k_sa, TABLE3_KSA_N_PER_UM, rtol=1e-3)
    for r in rows:
        assert r["axial_stiffness_N_per_um"] < r["screw_axial_stiffness_N_per_um"]
        assert r["equivalent_stiffness_N_per_um"] < r["axial_stiffness_N_per_um"]
    mid = data["mid_screw"]
    assert mid["position_mm"] == 400.0
    assert mid["paper_equivalent_stiffness_N_per_um"] == pytest.approx(21.6)
    assert mid["equivalent_stiffness_N_per_um"] == pytest.approx(32.3, rel=2e-3)
    assert mid["deviation"] == pytest.approx(0.495, abs=0.002)
    best = data["closest_readings"][0]
    assert best["equivalent_stiffness_N_per_um"] == pytest.approx(22.0, rel=2e-3)
    assert "fixed-free" in best["description"]


def test_stiffness_table_output() -> None:
    result = run("stiffness")
    assert result.exit_code == 0, result.output
    for text in ("276.13", "207.09", "207.10", "32.29", "21.6", "+49.5%", "x_t [mm]"):
        assert text in result.stdout


def test_stiffness_honours_an_imposed_k_eq(tmp_path: Path) -> None:
    path = tmp_path / "paper_keq.toml"
    text = run("params", "show", "--format", "toml").stdout
    text = text.replace("equivalent_stiffness = 0.0", "equivalent_stiffness = 21600000.0")
    path.write_text(text, encoding="utf-8")
    result = run("stiffness", "--positions", "250", "--params", str(path), "--json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["equivalent_stiffness_override"] is True
    assert data["positions"][0]["equivalent_stiffness_N_per_um"] == pytest.approx(21.6)
    assert data["positions"][0]["equivalent_stiffness_chain_N_per_um"] > 30.0
    assert data["mid_screw"]["deviation"] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("positions", ["200,900", "0", "-5", "800", "abc", "200,,300", "nan",
                                       "inf"])
def test_stiffness_refuses_bad_positions(positions: str) -> None:
    line = one_line_error(run("stiffness", f"--positions={positions}"))
    assert "--positions" in line
    assert "[mm]" in line
    bad = [t for t in positions.split(",") if t not in ("200", "300")][0]
    assert repr(bad) in line


def test_preset_and_params_together_are_refused(tmp_path: Path) -> None:
    line = one_line_error(run("stiffness", "--preset", "wang2021", "--params", "x.toml"))
    assert "--params" in line


def test_unknown_preset_is_refused() -> None:
    line = one_line_error(run("stiffness", "--preset", "nope"))
    assert "preset" in line


# ------------------------------------------------------------------ friction


def test_friction_screw_json() -> None:
    # the literal set has no axial damping: the scan is the bare table–spring–LuGre system
    result = run("friction", "--site", "screw", "--json", "--preset", "wang2021-literal")
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["site"] == "screw"
    pos, neg = data["branches"]["positive"], data["branches"]["negative"]
    assert round(pos["zero_slope_speed_mm_s"], 2) == 1.60
    assert pos["zero_slope_speed_mm_s"] == pos["negative_slope_band_mm_s"][1]
    assert neg["zero_slope_speed_mm_s"] == pytest.approx(1.733, abs=1e-3)
    assert pos["stribeck_velocity_mm_s"] == pytest.approx(0.864)
    assert pos["coulomb_force_N"] == 73.4 and neg["static_force_N"] == 94.6
    assert pos["passive"] is True and neg["passive"] is True
    assert data["paper_cdfs_critical_speed_mm_s"] == pytest.approx(1.56)
    scan = data["stability_scan"]
    assert scan["mass_kg"] == 20.0
    assert scan["stiffness_N_per_um"] == pytest.approx(32.29, rel=1e-3)
    assert scan["damping_N_s_per_m"] == 0.0
    assert "servo" in scan["limitation"]
    # every unstable speed of the scan lies inside the negative-slope band
    for b in (pos, neg):
        lo, hi = b["unstable_band_mm_s"]
        assert b["negative_slope_band_mm_s"][0] <= lo <= hi <= b["negative_slope_band_mm_s"][1]


def test_friction_guide_fails_passivity_and_damping_removes_the_unstable_band() -> None:
    data = json.loads(run("friction", "--site", "guide", "--json", "--preset",
                          "wang2021-literal").stdout)
    assert data["branches"]["positive"]["passive"] is False
    assert data["branches"]["negative"]["passive"] is False
    assert data["branches"]["positive"]["unstable_band_mm_s"] is not None
    damped = run("friction", "--site", "guide", "--json", "--damping", "1e4")
    assert damped.exit_code == 0, damped.output
    for b in json.loads(damped.stdout)["branches"].values():
        assert b["unstable_band_mm_s"] is None
        assert b["unstable_points"] == 0


def test_friction_scan_options_are_used() -> None:
    data = json.loads(run("friction", "--json", "--mass", "5", "--stiffness", "0.01",
                          "--speed-min", "0.1", "--speed-max", "3", "--points", "50").stdout)
    scan = data["stability_scan"]
    assert (scan["mass_kg"], scan["stiffness_N_per_um"], scan["points"]) == (5.0, 0.01, 50)
    lo, hi = data["branches"]["positive"]["unstable_band_mm_s"]
    assert lo >= 0.1 and hi <= 3.0


def test_friction_table_output() -> None:
    result = run("friction", "--site", "screw")
    assert result.exit_code == 0, result.output
    for text in ("1.605", "1.56 mm/s", "pass", "v_s [mm/s]", "Åström"):
        assert text in result.stdout
    guide = run("friction", "--site", "guide")
    assert "FAIL" in guide.stdout


def test_friction_plot_writes_a_png(tmp_path: Path) -> None:
    path = tmp_path / "stribeck.png"
    result = run("friction", "--site", "nut", "--plot", str(path))
    assert result.exit_code == 0, result.output
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(data) > 10_000


@pytest.mark.parametrize(("args", "field"), [
    (["--site", "table"], "--site"),
    (["--mass", "-1"], "--mass"),
    (["--stiffness", "0"], "--stiffness"),
    (["--damping", "-3"], "--damping"),
    (["--speed-min", "0"], "--speed-min"),
    (["--speed-max", "0.01"], "--speed-max"),
    (["--points", "1"], "--points"),
])
def test_friction_refuses_bad_options(args: list[str], field: str) -> None:
    line = one_line_error(run("friction", *args))
    assert field in line


# ------------------------------------------------------------------ params


def test_params_show_then_check(tmp_path: Path) -> None:
    path = tmp_path / "p.toml"
    show = run("params", "show", "--format", "toml")
    assert show.exit_code == 0
    path.write_text(show.stdout, encoding="utf-8")
    check = run("params", "check", str(path))
    assert check.exit_code == 0, check.output
    assert "ok" in check.stdout


@pytest.mark.parametrize(("old", "new", "field"), [
    ("mass = 20.0", "mass = nan", "table.mass"),
    ("mass = 20.0", "mass = -1", "table.mass"),
    ("lead = 0.005", "lead = 5.0", "screw.lead"),
    ("mass = 20.0", "mass = 20.0\ncolour = 1.0", "table.colour"),
])
def test_params_check_refuses_edited_files(tmp_path: Path, old: str, new: str,
                                           field: str) -> None:
    text = run("params", "show", "--format", "toml").stdout
    assert text.count(old) == 1
    path = tmp_path / "edited.toml"
    path.write_text(text.replace(old, new), encoding="utf-8")
    line = one_line_error(run("params", "check", str(path)))
    assert line.startswith(f"error: {path}: {field} = ")  # the file, then the field (issue 13)


@pytest.mark.parametrize(("table", "refused"), [
    # the value as the API reads it (a number of the table is a float, as in a run's refusal)
    ("rtol = -1", "solver.rtol = -1.0: expected a finite value 1e-14 … 0.1 [-]"),
    ('method = "euler"', "solver.method = 'euler': expected one of modal"),
    ("accuracy = 0.1\nrtol = 1e-8", "solver.accuracy = 0.1: given with solver.rtol"),
    ("colour = 1", "solver.colour = 1: expected one of method"),
])
def test_params_check_reads_the_solver_table_as_a_run_does(tmp_path: Path, table: str,
                                                           refused: str) -> None:
    """2026-12-06: ``params check`` said "ok" for a [solver] table every run with --params
    refused; it reads it as they do (cli._solver.solver_options)."""
    path = tmp_path / "solver.toml"
    path.write_text(f'extends = "wang2021"\n\n[solver]\n{table}\n', encoding="utf-8")
    check = one_line_error(run("params", "check", str(path)))
    assert refused in check
    simulate = one_line_error(run("simulate", "--params", str(path), "--table-speed", "1",
                                  "--duration", "0.1"))
    assert simulate == check
    path.write_text('extends = "wang2021"\n\n[solver]\nrtol = 1e-8\n', encoding="utf-8")
    assert run("params", "check", str(path)).exit_code == 0


def test_params_check_missing_file() -> None:
    line = one_line_error(run("params", "check", "/nonexistent/p.toml"))
    assert "no such file" in line


def test_console_script_entry_point() -> None:
    """The installed `feeddrive` script runs (exit code and stderr through a real process)."""
    exe = Path(sys.executable).with_name("feeddrive")
    if not exe.exists():
        pytest.skip("console script not installed next to the interpreter")
    ok = subprocess.run([str(exe), "stiffness", "--positions", "400", "--json"],
                        capture_output=True, text=True, timeout=120, check=False)
    assert ok.returncode == 0, ok.stderr
    assert json.loads(ok.stdout)["positions"][0]["screw_axial_stiffness_N_per_um"] == \
        pytest.approx(207.1, rel=1e-3)
    bad = subprocess.run([str(exe), "stiffness", "--positions", "900"],
                         capture_output=True, text=True, timeout=120, check=False)
    assert bad.returncode == 2
    assert bad.stderr.strip().count("\n") == 0
    assert "--positions = '900'" in bad.stderr and "[mm]" in bad.stderr


def test_loops_and_stability_commands_report_the_creep_mode_and_band() -> None:
    """`feeddrive loops` / `stability` (issue 15): the least-damped mode and the band."""
    from typer.testing import CliRunner

    from feeddrive.cli import app

    runner = CliRunner()
    res = runner.invoke(app, ["loops", "--drive", "cdfs", "--json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert data["least_damped_mode"]["frequency_hz"] == pytest.approx(5.47, abs=0.01)
    assert {lp["loop"] for lp in data["loops"]} == {"screw velocity loop", "screw position loop"}
    res = runner.invoke(app, ["stability", "--drive", "cdfs", "--points", "15", "--json"])
    assert res.exit_code == 0, res.output
    band = json.loads(res.stdout)
    assert len(band["unstable_bands_mm_s"]) == 1
    lo, hi = band["unstable_bands_mm_s"][0]
    assert 0.1 < lo < 0.3 and 1.3 < hi < 1.5
    assert "positive real part" in band["rule"]
    bad = runner.invoke(app, ["loops", "--drive", "cdfs", "--table-speed", "0",
                               "--with-friction"])
    # named as typed, in mm/s (the API's "table_speed … [m/s]" until 2026-12-07)
    assert bad.exit_code == 2 and "--table-speed = 0.0" in bad.output and "[mm/s]" in bad.output


def test_compensate_command_gives_the_study_table() -> None:
    """`feeddrive compensate --drive cdfs --json` (issue 14), fast mode without searches."""
    from typer.testing import CliRunner

    from feeddrive.cli import app

    res = CliRunner().invoke(app, ["compensate", "--drive", "cdfs", "--no-search", "--json"])
    assert res.exit_code == 0, res.output
    rows = json.loads(res.stdout)["rows"]
    assert [r["compensation"] for r in rows] == ["none"] + ["feedforward"] * 3 + \
        ["observer"] * 3 + ["none"]
    assert rows[0]["linear_unstable_bands_mm_s"] and rows[4]["linear_unstable_bands_mm_s"] == []
    assert rows[-1]["drive"] == "ddfs"
    bad = CliRunner().invoke(app, ["compensate", "--mismatch", "150"])
    assert bad.exit_code == 2 and "--mismatch" in bad.output
def test_creep_json_states_bands_kind_and_rule() -> None:
    # a narrow range around Wang2021 Fig. 6's pair keeps this fast
    res = runner.invoke(app, ["creep", "--drive", "cdfs", "--method", "both", "--low", "1.50",
                              "--high", "1.60", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert out["critical_speed_mm_s"] == pytest.approx(1.56)
    assert out["status"] == "found" and out["kind"] == "oscillation"
    assert [b["kind"] for b in out["bands"]] == ["oscillation"]
    assert out["bands"][0]["above_kind"] == "smooth"
    assert "stick-slip" in out["verdict_rule"]["description"]
    assert {s["start"] for s in out["searches"]} == {"rest", "running"}
    for s in out["searches"]:
        assert {"bands", "kind", "verdict_rule", "status"} <= set(s)


def test_creep_text_names_the_bands_and_the_rule() -> None:
    res = runner.invoke(app, ["creep", "--drive", "cdfs", "--method", "bisect", "--low", "1.50",
                              "--high", "1.60"])
    assert res.exit_code == 0, res.output
    assert "creeping bands" in res.output and "Verdict rule:" in res.output
    # the deciding trials' shadow estimate (issue 35 item 3), said to be one, with its
    # measured worth
    assert "[integration error estimated " in res.output
    low, high = SHADOW_RATIO
    assert (f"(difference to the deciding trials run {SHADOW_FACTOR:g}× tighter: "
            f"{low:.2g}–{high:.2g}× the true error)]") in res.output
    assert "integration error ≤" not in res.output


def test_creep_rejects_a_maximum_below_the_first_trial() -> None:
    res = runner.invoke(app, ["creep", "--max-duration", "5"])
    assert res.exit_code == 2
    # the option as typed and the first trial's length (protocol.TRIAL_DURATION, 12 s)
    assert "--max-duration = 5.0: expected ≥ 12 [s]" in res.output
    assert len(res.output.strip().splitlines()) == 1


def test_documented_keq_recipe_works_as_written(tmp_path: Path) -> None:
    """Issue 12 item 15: docs/parameters.md's partial file for the paper's K_eq failed with
    'name = None: missing field'.  The recipe, copied from the docs, must run as shown."""
    import re

    doc = (Path(__file__).resolve().parents[2] / "docs" / "parameters.md").read_text()
    block = re.search(r"\*\*Using the paper's value instead\.\*\*.*?```toml\n(.*?)```", doc,
                      re.S)
    assert block is not None
    recipe = tmp_path / "keq.toml"
    recipe.write_text(block.group(1))
    res = runner.invoke(app, ["stiffness", "--params", str(recipe), "--positions", "400",
                              "--json"])
    assert res.exit_code == 0, res.output
    row = json.loads(res.output)["positions"][0]
    assert row["equivalent_stiffness_N_per_um"] == pytest.approx(21.6)
