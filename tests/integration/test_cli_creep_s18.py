"""`feeddrive creep`: the protocol line states the settings the searches ran with, progress on
stderr, and one structured integration-error entry in the JSON (with the units of the fields
whose names carry none), the --ripple-threshold path included.

The runs are kept short: a 0.12-mm/s range at the top of the protocol's (CDFS, smooth there,
three trials from rest) and trials of 3 s doubling to 6 s (the rule's settle time is 2 s)."""

from __future__ import annotations

import inspect
import io
import json
from typing import Any

import pytest
from rich.console import Console
from typer.testing import CliRunner

import feeddrive.analysis.critical as critical
from feeddrive.analysis import protocol
from feeddrive.analysis.cycle_verdict import VerdictRule
from feeddrive.cli import _common, _creep_estimate, app, creep_cmd
from feeddrive.engine.error_estimate import SHADOW_FACTOR, SHADOW_RATIO
from feeddrive.engine.options import MIN_RELATIVE
from feeddrive.solvers.global_error import MEASURED_RATIO

runner = CliRunner()
#: a short search: smooth from rest over the whole range, trials of 3 and 6 s
SHORT = ["--drive", "cdfs", "--low", "2.9", "--high", "3.02", "--initial-duration", "3",
         "--max-duration", "6"]


def _creep(*args: str) -> Any:
    result = runner.invoke(app, ["creep", *args], terminal_width=400)
    assert result.exit_code == 0, result.output
    return result


def _protocol_lines(text: str) -> list[str]:
    return [line for line in text.splitlines() if line.startswith("  protocol ")]


def _fake_search(calls: list[dict[str, Any]]) -> Any:
    """A search from rest that runs nothing: the call's settings recorded, a found speed."""
    def search(system: Any, **kwargs: Any) -> critical.CriticalSpeed:
        calls.append(kwargs)
        return critical.CriticalSpeed(drive=system.drive, table_position=0.4, nut_speed=0.0,
                                      start="rest", critical_speed=1.3e-3, status="found",
                                      resolution=kwargs["resolution"],
                                      speed_range=kwargs["speed_range"], rule=kwargs["rule"])
    return search


# ------------------------------------------------------------------ defect 1: protocol line


def test_the_protocol_line_states_the_trial_lengths_given(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """``--initial-duration 3 --max-duration 6`` on the default grid printed "trials of 12 s
    doubled up to 240 s" (protocol.TRIAL_DURATION, TRIAL_MAX_DURATION) beside a verdict rule
    of 3 and 6 s."""
    calls: list[dict[str, Any]] = []
    monkeypatch.setattr(critical, "critical_speed_from_rest", _fake_search(calls))
    out = _creep("--method", "bisect", "--initial-duration", "3", "--max-duration", "6").stdout
    lo, hi = (v * 1e3 for v in protocol.SPEED_RANGE)  # the default grid [mm/s]
    assert _protocol_lines(out) == [
        f"  protocol from rest: trials of 3 s doubled up to 6 s until decided, scan "
        f"{lo:g}–{hi:g} mm/s in {1e3 * protocol.COARSE_STEP:g}-mm/s steps, then bisection to "
        f"{1e3 * protocol.RESOLUTION:g} mm/s"]
    assert calls[0]["rule"].durations() == [3.0, 6.0]  # the trials the line describes


def test_at_the_defaults_the_line_is_the_shared_protocol(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """At the defaults creep writes the protocol as ``reproduce``'s report does
    (protocol.describe)."""
    monkeypatch.setattr(critical, "critical_speed_from_rest", _fake_search([]))
    out = _creep("--method", "bisect").stdout
    assert _protocol_lines(out) == [f"  protocol {protocol.describe('rest')}"]
    running = creep_cmd.protocol_text("running", protocol.SPEED_RANGE, protocol.COARSE_STEP,
                                      VerdictRule())
    assert running == (f"{protocol.describe('running')}, each step held "
                       f"{protocol.TRIAL_DURATION:g} s doubled up to "
                       f"{protocol.TRIAL_MAX_DURATION:g} s until decided")


def test_the_protocol_lines_state_a_range_that_is_not_the_default() -> None:
    """Off the default grid no protocol line was printed; now both searches state theirs:
    the range given and the scan step it leaves (half the range: below the protocol's)."""
    lines = _protocol_lines(_creep("--method", "both", *SHORT).stdout)
    assert lines == [
        "  protocol from rest: trials of 3 s doubled up to 6 s until decided, scan "
        f"2.9–3.02 mm/s in {(3.02 - 2.9) / 2:g}-mm/s steps, then bisection to "
        f"{1e3 * protocol.RESOLUTION:g} mm/s",
        # its staircase 3.02, 3.0, 2.9 mm/s (protocol.speed_grid) starts with a 0.02 mm/s step
        "  protocol step-down on a running table: staircase from 3.02 mm/s in "
        f"{1e3 * protocol.STAIRCASE_COARSE_STEP:g}-mm/s steps, the first 0.02 mm/s, then "
        f"{1e3 * protocol.RESOLUTION:g}-mm/s steps from the last smooth one (down to 2.9 "
        "mm/s), each step held 3 s doubled up to 6 s until decided"]


# ------------------------------------------------------------------ defect 2: progress


def _spy(monkeypatch: pytest.MonkeyPatch) -> dict[str, Any]:
    """The real search from rest, its ``progress`` keyword and every call of it recorded."""
    seen: dict[str, Any] = {"calls": []}
    real = critical.critical_speed_from_rest

    def search(system: Any, **kwargs: Any) -> critical.CriticalSpeed:
        seen["kwargs"] = dict(kwargs)
        shown = kwargs.get("progress")
        if shown is not None:
            def progress(done: int, total: int) -> None:
                seen["calls"].append((done, total))
                shown(done, total)
            kwargs["progress"] = progress
        seen["result"] = real(system, **kwargs)
        return seen["result"]

    monkeypatch.setattr(critical, "critical_speed_from_rest", search)
    return seen


def _terminal(monkeypatch: pytest.MonkeyPatch) -> io.StringIO:
    """stderr as a terminal: what creep's progress draws there."""
    drawn = io.StringIO()
    monkeypatch.setattr(_common, "err_console",
                        Console(file=drawn, force_terminal=True, width=120))
    return drawn


def test_a_search_shows_its_trials_on_a_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    seen = _spy(monkeypatch)
    drawn = _terminal(monkeypatch)
    result = _creep("--method", "bisect", *SHORT)
    n = len(seen["result"].trials)
    assert callable(seen["kwargs"]["progress"])
    assert seen["calls"] == [(k, 0) for k in range(1, n + 1)]  # after each trial
    assert "search from rest" in drawn.getvalue() and f"{n} trials" in drawn.getvalue()
    assert "\x1b" not in result.stdout  # the display is on stderr only


def test_no_progress_in_json_nor_off_a_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    seen = _spy(monkeypatch)
    drawn = _terminal(monkeypatch)
    result = _creep("--method", "bisect", "--json", *SHORT)
    assert json.loads(result.stdout)["searches"][0]["trials"]  # nothing but the JSON
    assert "progress" not in seen["kwargs"] and drawn.getvalue() == ""
    monkeypatch.undo()
    seen = _spy(monkeypatch)  # stderr not a terminal (CliRunner): quiet, as `simulate`'s bar
    result = _creep("--method", "bisect", *SHORT)
    assert "progress" not in seen["kwargs"] and result.stderr == ""


# ------------------------------------------------------------------ defects 3 and 4: JSON


def test_the_json_states_the_estimate_once_with_its_worth() -> None:
    out = json.loads(_creep("--method", "both", "--json", *SHORT).stdout)
    rest, running = out["searches"]
    entry = out["integration_error"]
    assert entry == {
        "estimated": True, "method": "shadow", "speed_error_mm_s": rest["speed_error_mm_s"],
        "ratio_to_true_error": list(SHADOW_RATIO), "tighter_by": SHADOW_FACTOR,
        "text": critical.format_integration_error(rest).strip(" []")}
    assert "speed_error_mm_s" not in running  # the step-down makes none: the largest is rest's
    assert entry["text"].startswith("integration error estimated ")
    text = _creep("--method", "both", *SHORT).stdout
    assert f"[{entry['text']}]" in text and "not estimated" not in text


def test_the_json_gives_the_units_of_the_fields_named_without_one() -> None:
    out = json.loads(_creep("--method", "bisect", "--json", *SHORT).stdout)
    units, search = out["units"], out["searches"][0]
    named = {"kind", "creeping", "speed_error_mm_s"}  # no unit, or it is in the name
    for trial in search["trials"]:
        assert set(trial) - named <= set(units)
        # the values are in the units stated: speeds within the range asked for [mm/s],
        # lengths among the rule's (3 s doubled to 6 s)
        assert units["speed"] == "mm/s" and 2.9 <= trial["speed"] <= 3.02
        assert units["duration"] == "s" and trial["duration"] in (3.0, 6.0)
        assert units["decided_at"] == "s" and 0 < trial["decided_at"] <= trial["duration"]
    assert set(out["verdict_rule"]) - {"description"} <= set(units)
    assert units["initial_duration"] == "s" and out["verdict_rule"]["initial_duration"] == 3.0


def test_at_double_precisions_reach_the_json_says_why_there_is_none() -> None:
    args = ["--method", "bisect", *SHORT, "--rtol", "5e-14"]
    out = json.loads(_creep(*args, "--json").stdout)
    # the setting as given, and its floor (error_estimate.tightening_refused, the one rule)
    reason = (f"needs a run {SHADOW_FACTOR:g}× tighter than rtol 5e-14, below "
              f"{MIN_RELATIVE:g} (double precision's reach)")
    assert out["integration_error"] == {
        "estimated": False, "reason": reason,
        "text": f"Integration error: not estimated — {reason}"}
    assert "speed_error_mm_s" not in out["searches"][0]
    text = _creep(*args).stdout
    assert text.splitlines()[-1] == out["integration_error"]["text"]


def test_the_step_down_alone_says_it_makes_no_estimate() -> None:
    out = json.loads(_creep("--method", "stepdown", "--json", *SHORT).stdout)
    entry = out["integration_error"]
    assert entry["estimated"] is False and "step-down" in entry["reason"]
    assert _creep("--method", "stepdown", *SHORT).stdout.splitlines()[-1] == entry["text"]


def test_the_ripple_threshold_search_says_it_makes_no_estimate() -> None:
    """The --ripple-threshold path stated no integration error and no note (defect 4); the
    range 0.3–0.6 mm/s holds the DDFS's 0.4–0.6 mm/s at v_n 16 mm/s
    (tests/validation/test_forced_ripple.py)."""
    args = ["--preset", "wang2021-ripple", "--drive", "ddfs", "--nut-speed", "16",
            "--ripple-threshold", "0.5", "--low", "0.3", "--high", "0.6"]
    out = json.loads(_creep(*args, "--json").stdout)
    assert out["status"] == "found"
    entry = out["integration_error"]
    assert entry["estimated"] is False and "ripple-threshold" in entry["reason"]
    assert entry["text"] == f"Integration error: not estimated — {entry['reason']}"
    assert out["units"]["threshold"] == "-" and set(out["points"][0]) - {"speed_mm_s"} <= set(
        out["units"])
    assert _creep(*args).stdout.splitlines()[-1] == entry["text"]


def test_the_entry_takes_the_largest_estimate_and_its_method_worth() -> None:
    shadow = [{"speed_error_mm_s": 1e-5, "speed_error_method": "shadow"},
              {"speed_error_mm_s": 3e-5, "speed_error_method": "shadow"}, {}]
    assert _creep_estimate.integration_error(shadow, "unused")["speed_error_mm_s"] == 3e-5
    # an entry stored without its method is the embedded estimate (format_integration_error)
    embedded = _creep_estimate.integration_error([{"speed_error_mm_s": 2e-2}], "unused")
    assert embedded["method"] == "embedded" and "tighter_by" not in embedded
    assert embedded["ratio_to_true_error"] == list(MEASURED_RATIO)
    none = _creep_estimate.integration_error([{}, {}], "the reason")
    assert none == {"estimated": False, "reason": "the reason",
                    "text": "Integration error: not estimated — the reason"}



@pytest.mark.parametrize("given", [["--initial-duration", "3"], ["--max-duration", "60"],
                                   ["--method", "bisect"]])
def test_the_ripple_search_refuses_trial_settings_it_does_not_use(given: list[str]) -> None:
    """``--ripple-threshold`` took ``--initial-duration``, ``--max-duration`` and ``--method``
    and ignored them (an outside check, 2026-12-06): refused in one line, before any work."""
    from feeddrive.analysis.forced import TRIAL

    res = CliRunner().invoke(app, ["creep", "--drive", "ddfs", "--nut-speed", "16",
                                   "--ripple-threshold", "0.5", *given])
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith(f"error: {given[0]} = "), res.output
    assert f"not used with --ripple-threshold (its search runs each speed {TRIAL:g} s" \
        in lines[0]



def test_the_ripple_threshold_help_names_what_it_does_not_take() -> None:
    import inspect

    # the option's own text (rich may break the rendered help at a hyphen)
    option = inspect.signature(creep_cmd.creep_command).parameters["ripple_threshold"].default
    assert "(not with --method, --initial-duration, --max-duration)" in option.help
    text = " ".join(CliRunner().invoke(app, ["creep", "--help"], terminal_width=400)
                    .output.split())
    assert "not with --method, --initial-duration" in text


def test_the_estimate_is_chosen_on_the_command_line() -> None:
    """``creep`` had no way to leave the estimate out (7–9 % of a search) or to take the
    embedded one (an outside check, 2026-12-06): ``--error-estimate shadow|embedded|none``."""
    from feeddrive.engine.error_estimate import SHADOW_RATIO
    from feeddrive.solvers.global_error import MEASURED_RATIO

    def entry(choice: str) -> dict[str, Any]:
        out = json.loads(_creep("--method", "bisect", *SHORT, "--error-estimate", choice,
                                "--json").stdout)
        return out["integration_error"]

    shadow, embedded, none = entry("shadow"), entry("embedded"), entry("none")
    assert shadow["estimated"] and shadow["method"] == "shadow"
    assert shadow["ratio_to_true_error"] == list(SHADOW_RATIO)
    assert embedded["estimated"] and embedded["method"] == "embedded"
    assert embedded["ratio_to_true_error"] == list(MEASURED_RATIO)
    assert none == _creep_estimate.not_estimated(_creep_estimate.NOT_ASKED)
    bad = runner.invoke(app, ["creep", "--error-estimate", "maybe"])
    assert bad.exit_code == 2
    assert bad.output.strip().startswith("error: --error-estimate = 'maybe': expected one of "
                                         "shadow, embedded, none"), bad.output
    option = inspect.signature(creep_cmd.creep_command).parameters["error_estimate"].default
    assert option.help == _creep_estimate.ESTIMATE_HELP and option.default == "shadow"


@pytest.mark.parametrize("integrator", ["dopri5", "rodas4"])
def test_the_trials_integrator_is_chosen_on_the_command_line(
        monkeypatch: pytest.MonkeyPatch, integrator: str) -> None:
    """``creep`` could choose its trials' integrator only through a ``[solver]`` file (its
    ``--method`` is the search's; an outside check, 2026-12-06): ``--integrator``, in force
    for every trial and stated in the integrator line."""
    from feeddrive.engine import options as opt

    seen: list[str] = []
    search = _fake_search([])

    def recording(system: Any, **kwargs: Any) -> Any:
        seen.append(opt.current().method)
        return search(system, **kwargs)

    monkeypatch.setattr(critical, "critical_speed_from_rest", recording)
    out = json.loads(_creep("--method", "bisect", "--integrator", integrator,
                            "--json").stdout)
    assert seen == [integrator]
    assert out["integrator"].startswith(f"{integrator} ") and "(from --integrator)" in \
        out["integrator"]
    bad = runner.invoke(app, ["creep", "--integrator", "euler"])
    assert bad.exit_code == 2 and bad.output.startswith("error: --integrator = 'euler'")
