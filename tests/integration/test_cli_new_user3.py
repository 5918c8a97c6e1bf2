"""Issue 24 ("what a new user hits", round 3): the words, the summaries, the commands.

Each test names the item of issue 24 it guards.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from feeddrive.cli import app

runner = CliRunner()
ROOT = Path(__file__).resolve().parents[2]


def run(*args: str) -> Any:
    return runner.invoke(app, list(args))


def _line(output: str, label: str) -> str:
    return next(line for line in output.splitlines() if line.strip().startswith(label))


# ------------------------------------------------------------------ items 4, 5: words


def test_simulate_names_its_verdict_rule_and_calls_a_non_sticking_ripple_an_oscillation(
        ) -> None:
    """Item 4: simulate's "smooth" (ripple below 0.5) and creep's (±2 % limit cycle) were two
    rules under one word, unnamed.  Item 5: a trapezoid whose table never stuck printed a
    "stick-slip frequency"."""
    res = run("simulate", "--drive", "cdfs", "--table-speed", "1.5", "--profile",
              "trapezoid", "--duration", "6")
    assert res.exit_code == 0, res.output
    assert float(_line(res.output, "stick fraction").split()[-1]) == 0.0
    assert "stick-slip" not in res.output
    assert _line(res.output, "oscillation frequency").endswith("Hz")
    assert "(by the window rule, below)" in _line(res.output, "verdict ")
    rule = _line(res.output, "verdict rule")
    assert "window rule" in rule and "50 %" in rule and "limit-cycle rule (±2 %)" in rule
    js = json.loads(run("simulate", "--drive", "cdfs", "--table-speed", "1.5", "--duration",
                        "2", "--json").output)
    assert js["verdict_rule"].startswith("window rule")


def test_creep_rule_text_is_named_the_limit_cycle_rule() -> None:
    from feeddrive.analysis.cycle_verdict import VerdictRule

    assert VerdictRule().describe().startswith("Limit-cycle rule.")


def test_explorer_verdict_names_its_rule_in_percent() -> None:
    """Item 4: the explorer said "within ±0.02 of the command" for ±2 %."""
    import numpy as np

    from feeddrive.explore.compute import verdict_of

    t = np.arange(0.0, 12.0, 1e-3)
    v = 1e-3 * (1.0 + 0.5 * np.exp(-t) * np.sin(2 * np.pi * 3 * t))
    text = verdict_of(t, v, 1e-3)["text"]
    assert "±2 %" in text and "±0.02" not in text and "limit-cycle rule" in text


# ------------------------------------------------------------------ item 6: segments


def test_stepdown_and_csv_profiles_are_summarised_per_hold(tmp_path: Path) -> None:
    """Item 6: a six-step staircase printed one "command speed 1.6 mm/s" line, and a CSV
    profile of 1 and 0.3 mm/s mentioned only the first level."""
    res = run("simulate", "--drive", "cdfs", "--table-speed", "1.6", "--profile", "stepdown",
              "--lowest-speed", "1.55", "--step", "0.01", "--dwell", "1.5")
    assert res.exit_code == 0, res.output
    assert "6 holds" in _line(res.output, "segments")
    for i, speed in enumerate(("1.6", "1.59", "1.58", "1.57", "1.56", "1.55"), start=1):
        assert _line(res.output, f"{i}: {speed} mm/s"), speed
    profile = tmp_path / "levels.csv"
    rows = ["time [s],table_speed [mm/s]"] + [
        f"{t / 100:g},{1.0 if t < 300 else 0.3}" for t in range(0, 601)]
    profile.write_text("\n".join(rows) + "\n", encoding="utf-8")
    res = run("simulate", "--drive", "cdfs", "--profile", "csv", "--profile-file",
              str(profile), "--json")
    assert res.exit_code == 0, res.output
    segments = json.loads(res.output)["segments"]
    assert [s["command_speed_mm_s"] for s in segments] == pytest.approx([1.0, 0.3])
    for s in segments:
        lo, hi = s["window_s"]
        assert s["start_s"] <= lo < hi <= s["end_s"]


def test_linear_motor_header_has_no_screw_position() -> None:
    """Item 13: `simulate --drive linear-motor` printed "position 400 mm" (no screw)."""
    res = run("simulate", "--drive", "linear-motor", "--table-speed", "1.0", "--duration",
              "1")
    assert res.exit_code == 0, res.output
    assert "position" not in res.output.splitlines()[0]


# ------------------------------------------------------------------ item 7: friction law


@pytest.mark.parametrize("law", ["dahl", "none"])
def test_friction_command_follows_the_sites_law(tmp_path: Path, law: str) -> None:
    """Item 7: with the guide set to `dahl` or `none`, `feeddrive friction --site guide`
    still printed "LuGre friction", a negative-slope band and a passivity FAIL."""
    params = tmp_path / f"{law}.toml"
    params.write_text(f'extends = "wang2021"\n[friction.guide]\nlaw = "{law}"\n',
                      encoding="utf-8")
    res = run("friction", "--site", "guide", "--params", str(params))
    assert res.exit_code == 0, res.output
    assert "LuGre friction" not in res.output and "FAIL" not in res.output
    assert f"uses the '{law}' law" in res.output
    out = json.loads(run("friction", "--site", "guide", "--params", str(params),
                         "--json").output)
    assert out["law"] == law
    for b in out["branches"].values():
        assert b["negative_slope_band_mm_s"] is None and b["passive"] is None
        assert b["unstable_band_mm_s"] is None
    if law == "dahl":
        assert out["branches"]["positive"]["min_steady_slope_N_s_per_m"] == pytest.approx(
            61.6, rel=1e-3)


# ------------------------------------------------------------------ item 11: dry run


def test_sweep_dry_run_says_what_it_does_and_times_cpu_not_wall(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Item 11: `sweep --dry-run` said nothing for 39–51 s while it timed 3 points, and its
    estimate varied 3.0–10.8 s between runs (wall time on a loaded machine).  It now says
    what it is doing, times CPU seconds and gives the spread of the timed points."""
    import feeddrive.sweep.executors as executors

    cfg = tmp_path / "lb.toml"
    cfg.write_text('name = "lb"\ndrive = "cdfs"\n[design]\nkind = "grid"\n[quantity]\n'
                   'kind = "linear-band"\nlinear_points = 6\n[axes]\n'
                   'table_position = [200, 400, 600]\n', encoding="utf-8")
    clock = iter(range(0, 10**6, 100))  # a wall clock that jumps 100 s at every reading
    monkeypatch.setattr(executors.time, "perf_counter", lambda: float(next(clock)))
    res = run("sweep", str(cfg), "--dry-run", "--store", str(tmp_path / "lb.sqlite"))
    assert res.exit_code == 0, res.output
    assert "dry run: loading the model kernels (compiling them if not cached), then timing 3 " \
        "of the 3 points" in res.stderr
    assert "timing point 3 of 3" in res.stderr
    line = res.stdout.replace("\n", " ")
    assert "s CPU per point (3 timed:" in line and "longer on a loaded machine" in line
    js = json.loads(run("sweep", str(cfg), "--dry-run", "--json", "--store",
                        str(tmp_path / "lb.sqlite")).stdout)
    lo, hi = js["seconds_per_point_range"]
    assert 0 < lo <= js["seconds_per_point"] <= hi < 50  # not the jumping wall clock
    assert not (tmp_path / "lb.sqlite").exists()  # a dry run stores nothing


# ------------------------------------------------------------------ item 8: one scan range


def test_stability_and_the_linear_band_sweep_scan_one_default_range() -> None:
    """Item 8: `feeddrive stability` scanned 0.01–5 mm/s and the sweep's `linear-band`
    quantity 0.02–3.02 mm/s by default."""
    from feeddrive.analysis import protocol
    from feeddrive.analysis.linear import stability_band
    from feeddrive.cli.linear_cmd import stability_command
    from feeddrive.sweep.quantities import QuantitySettings

    q = QuantitySettings.parse({"kind": "linear-band"})
    assert (q.low, q.high, q.linear_points) == (*protocol.LINEAR_SPEED_RANGE,
                                                protocol.LINEAR_POINTS)
    defaults = stability_band.__kwdefaults__
    assert (defaults["low"], defaults["high"], defaults["points"]) == (
        *protocol.LINEAR_SPEED_RANGE, protocol.LINEAR_POINTS)
    import inspect

    options = inspect.signature(stability_command).parameters
    assert options["low"].default.default == pytest.approx(1e3 * q.low)
    assert options["high"].default.default == pytest.approx(1e3 * q.high)
    assert options["points"].default.default == q.linear_points
    # the critical-speed search keeps its own range (its linear band beside it scans that)
    c = QuantitySettings.parse({"kind": "critical-speed"})
    assert (c.low, c.high) == protocol.SPEED_RANGE


# ------------------------------------------------------------------ items 9, 13: compensation


def test_simulate_warns_when_the_observer_gain_destabilises_the_loop(tmp_path: Path) -> None:
    """Item 9: at k = 100 1/s the observer destabilised the loop at 0.5 mm/s, silently."""
    params = tmp_path / "k.toml"
    params.write_text('extends = "wang2021"\n[controller.compensation]\nmode = "observer"\n'
                      "observer_gain = 100.0\n", encoding="utf-8")
    res = run("simulate", "--table-speed", "0.5", "--duration", "0.5", "--params", str(params))
    assert res.exit_code == 0, res.output
    assert "warning: controller.compensation.observer_gain = 100 1/s" in res.stderr
    quiet = run("simulate", "--table-speed", "0.5", "--duration", "0.5")
    assert "observer_gain" not in quiet.stderr


def test_compensate_puts_units_on_numbers_only() -> None:
    """Item 13: `compensate` printed "none mm/s" and "undecided mm/s"."""
    from feeddrive.cli.compensate_cmd import with_unit

    assert with_unit("none") == "none" and with_unit("undecided") == "undecided"
    assert with_unit("—") == "—"
    assert with_unit("1.56") == "1.56 mm/s" and with_unit("< 0.02") == "< 0.02 mm/s"
    assert with_unit("0.172–1.399") == "0.172–1.399 mm/s"


# ------------------------------------------------------------------ item 10: parameter files


def test_params_show_prints_the_resolved_set_behind_extends(tmp_path: Path) -> None:
    """Item 10: no way to see the set behind an `extends = "wang2021"` file."""
    params = tmp_path / "mine.toml"
    params.write_text('extends = "wang2021"\n[table]\nmass = 25.0\n', encoding="utf-8")
    res = run("params", "show", "--params", str(params), "--format", "json")
    assert res.exit_code == 0, res.output
    shown = json.loads(res.stdout)
    from feeddrive.parameters import preset, to_dict

    base = to_dict(preset("wang2021"))
    assert shown["table"]["mass"] == 25.0
    assert shown["screw"] == base["screw"] and shown["friction"] == base["friction"]
    both = run("params", "show", "--params", str(params), "--preset", "wang2021")
    assert both.exit_code != 0 and "give one, not both" in both.output


def test_calibrate_out_marks_the_set_as_fitted(tmp_path: Path) -> None:
    """Item 10: `calibrate --out` kept `name = "wang2021"` and the preset's description.
    Item 13: its --max-duration defaulted to 60 s while creep and reproduce use 240 s."""
    import inspect

    from feeddrive.analysis import protocol
    from feeddrive.cli.calibrate_cmd import calibrate_command, fitted_set
    from feeddrive.parameters import load, preset, save

    fitted = fitted_set(preset("wang2021"), "controller.velocity_integral_gain", 4321.0,
                        "cdfs", 1.56, 400.0, 0.0)
    path = tmp_path / "fitted.toml"
    save(fitted, path)
    back = load(path)
    assert back.name == "wang2021-fitted"
    assert back.description.startswith("Fitted by feeddrive calibrate")
    assert "controller.velocity_integral_gain = 4321" in back.description
    assert "CDFS critical speed 1.56 mm/s at 400 mm" in back.description
    default = inspect.signature(calibrate_command).parameters["max_duration"].default
    assert default.default == protocol.TRIAL_MAX_DURATION


# ------------------------------------------------------------------ item 13: --help


def test_help_lines_are_whole_and_drive_shows_its_choices() -> None:
    """Item 13: `feeddrive --help` cut the stiffness line at "Eqs." and `--drive <str>` in
    --help showed no choices."""
    import re

    import typer.main

    group = typer.main.get_command(app)
    for name, command in group.commands.items():  # type: ignore[attr-defined]
        short = command.get_short_help_str(limit=300)
        assert not re.search(r"\b(Eqs?|Figs?|Sect|e\.g|i\.e|vs)\.$", short), (name, short)
        if any("--drive" in p.opts for p in command.params):
            page = runner.invoke(app, [name, "--help"], env={"COLUMNS": "160"}).output
            line = next(s for s in page.splitlines() if "--drive" in s)
            assert "cdfs" in line.split("--drive")[1].split()[0], (name, line)
    listing = runner.invoke(app, ["--help"], env={"COLUMNS": "100"}).output
    assert "k_sa, K_a and K_eq at table positions" in listing
    from feeddrive import registry
    from feeddrive.cli.simulate_cmd import ALL_DRIVES

    # the registry's order follows import order: the set is what --help must show
    assert set(ALL_DRIVES.split("|")) == set(registry.names(registry.MECHANISMS))


def test_parameters_doc_friction_table_is_what_the_cli_prints() -> None:
    """Item 13: docs/parameters.md's friction-indicator table described wang2021-literal
    (damping 0), not the CLI default set."""
    doc = (ROOT / "docs" / "parameters.md").read_text(encoding="utf-8")
    table = doc[doc.index("## Friction indicators"):]
    rows = [line for line in table.splitlines() if line.startswith(("| screw shaft |",
                                                                    "| hollow (nut) shaft |",
                                                                    "| linear guide |"))]
    assert len(rows) == 6
    sites = {"screw shaft": "screw", "hollow (nut) shaft": "nut", "linear guide": "guide"}

    def band(b: Any) -> str:
        return "none" if b is None else f"{b[0]:.3f} … {b[1]:.3f}"

    for row in rows:
        cells = [c.strip() for c in row.strip("|").split("|")]
        site, branch = sites[cells[0]], {"+": "positive", "−": "negative"}[cells[1]]
        for preset_name, column in (("wang2021", 5), ("wang2021-literal", 6)):
            out = json.loads(run("friction", "--site", site, "--preset", preset_name,
                                 "--json").output)
            assert cells[column] == band(out["branches"][branch]["unstable_band_mm_s"]), row


def test_readme_says_what_ci_runs_and_the_quick_loop() -> None:
    """Item 13: the README said `.ci/run` "runs exactly this" though it runs
    `.ci/min-versions` first.  Item 15: `pytest -m "not slow"` documented as the quick loop,
    the README's command still runs everything."""
    import re

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert "bash .ci/min-versions" in ci
    assert ci.index("bash .ci/min-versions") < ci.index(".venv/bin/python -m pytest")
    said = readme[readme.index("(`.ci/run`"):][:200]
    assert "`.ci/min-versions`" in said  # it runs before the README's command
    assert '`.venv/bin/python -m pytest -m "not slow"`' in readme
    test_command = re.search(r"^\{ .*$", readme, flags=re.M)
    assert test_command and "-m pytest" in test_command.group(0)
    assert "not slow" not in test_command.group(0)  # the README's command runs everything
    assert "slow:" in (ROOT / "pyproject.toml").read_text(encoding="utf-8")


def test_the_preset_help_names_each_drives_default_set() -> None:
    """``--preset``'s help names the set each topology brings (an outside check, 2026-12-07:
    it named linear-motor-example only, and ``--drive rack-pinion`` ran rack-pinion-example)."""
    from feeddrive import registry
    from feeddrive.cli._common import PRESET_HELP, default_preset

    examples = {name: default_preset(name) for name in registry.table(registry.MECHANISMS)}
    assert set(examples.values()) - {"wang2021"}  # some topology brings its own set
    for drive, name in examples.items():
        if name == "wang2021":
            assert "default wang2021" in PRESET_HELP
        else:
            assert f"{name} for --drive {drive}" in PRESET_HELP, drive
    for command in ("simulate", "positioning"):
        shown = runner.invoke(app, [command, "--help"], terminal_width=300).output
        squeezed = "".join(c for c in shown if not c.isspace() and c not in "│|")
        assert "".join(PRESET_HELP.split()) in squeezed, command
