"""More leftovers of the bad-input sweeps (session 30): arguments taken and dropped without a
word, or counted twice, now refused in one line naming the argument, its value and what was
expected.

1. ``analyze_trace(…, min_step=…)`` beside ``command_speed``, ``command`` or
   ``segment=False``: the step splits only segments detected from the position; the result
   was the same whatever was given.  Its default is now None (the documented 5e-6 m/s), so
   that a value given is told from none.
2. A list given with an entry twice: ``compare_compensations(names=["none", "none"])`` ran
   the scheme twice and repeated its row; ``metrics`` twice was counted twice in the
   progress's total (and :func:`measure` left an unknown quantity out without a word);
   ``positioning_test`` with a target twice counted it twice in the mean reversal value B̄.
   One shared check, ``parameters.validation.refuse_repeats``.
3. ``DriveSystem(params, "linear-motor", table_position=…)`` and ``MachineAxis(…,
   table_position=…)`` (the rack and pinion too): a start position the model never reads.
   A value other than the default 0.4 m is refused (the default cannot be told from none
   given: a positional dataclass field); the machine file refuses the key written at all,
   through the same check.  The internal callers that place a table (the positioning run at
   its first stop, the circular run on its circle) pass a start only to a drive that reads it.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from test_leftovers_s30 import _trace  # 20 s at 1 mm/s, 200 Hz

import feeddrive as fd
from feeddrive.analysis import compensation_compare as cc
from feeddrive.analysis.positioning import positioning_test
from feeddrive.analysis.trace import DEFAULT_MIN_STEP, analyze_trace
from feeddrive.machine import Machine, MachineAxis, machine_from_dict
from feeddrive.parameters import ParameterError

LM = fd.preset("linear-motor-example")
RP = fd.preset("rack-pinion-example")

# ------------------------------------------------------- 1: analyze_trace's min_step


APPLIES = r"\(it splits the segments detected from the position, without a command\)"


@pytest.mark.parametrize(("given", "says"), [
    ({"command_speed": 1e-3}, "command_speed, which makes the whole trace one segment"),
    ({"command": np.full(4000, 1e-3)}, "command, whose steps set the segments"),
    ({"segment": False}, "segment=False")])
@pytest.mark.parametrize("step", [1e-4, DEFAULT_MIN_STEP])
def test_min_step_is_refused_where_no_segment_is_detected(given: dict[str, Any], says: str,
                                                          step: float) -> None:
    """Taken and dropped: the analysis was the same whatever the step (the default's value
    given is refused too: None stands for it now)."""
    t, x = _trace()
    with pytest.raises(ParameterError, match=rf"^min_step = {re.escape(repr(step))}: not "
                                             rf"with {says} {APPLIES}; expected None$"):
        analyze_trace(t, x, min_step=step, **given)
    assert len(analyze_trace(t, x, **given).segments) == 1  # None, the default: taken


def test_min_step_sets_the_detected_segments_and_its_default_is_kept() -> None:
    """Without a command it is read (the note names it), its default still 5e-6 m/s."""
    t, x = _trace()
    default = analyze_trace(t, x)
    assert any("--min-step 0.005 mm/s" in n for n in default.notes), default.notes
    coarse = analyze_trace(t, x, min_step=1e-4)
    assert any("--min-step 0.1 mm/s" in n for n in coarse.notes), coarse.notes
    same = analyze_trace(t, x, min_step=DEFAULT_MIN_STEP)
    assert same.notes == default.notes
    with pytest.raises(ParameterError, match=r"^min_step = 0\.0001: not with segment=False"):
        analyze_trace(t, x, min_step=1e-4, segment=False)


# ----------------------------------------------------------- 2: an entry given twice


@pytest.fixture
def no_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    """Any measurement fails the test: the refusals come before any run."""
    def ran(*_a: object, **_k: object) -> None:
        raise AssertionError("a scheme was measured")

    monkeypatch.setattr(cc, "measure", ran)


@pytest.mark.usefixtures("no_runs")
@pytest.mark.parametrize(("kwargs", "field", "entry", "why"), [
    ({"names": ["none", "observer", "none"], "metrics": ["settling"]}, "names", "none",
     r"each scheme once \(twice, it would run twice and its row repeat\)"),
    ({"names": ["none"], "metrics": ["settling", "spike", "settling"]}, "metrics", "settling",
     r"each quantity once \(it is measured once per scheme\)")])
def test_a_scheme_or_a_quantity_twice_is_refused_before_any_run(kwargs: dict[str, Any],
                                                                 field: str, entry: str,
                                                                 why: str) -> None:
    drive = fd.preset("wang2021-drive")
    with pytest.raises(ParameterError, match=rf"^{field} = '{entry}': given twice; "
                                             rf"expected {why}$"):
        cc.compare_compensations(drive, **kwargs)


def test_schemes_makes_each_scheme_once() -> None:
    """It made two of one name: the comparison's row twice."""
    drive = fd.preset("wang2021-drive")
    with pytest.raises(ParameterError, match=r"^names = 'none': given twice"):
        cc.schemes(drive, ["none", "none"])
    assert [s.name for s in cc.schemes(drive, ["none", "observer"])] == ["none", "observer"]


@pytest.mark.parametrize(("metrics", "says"), [
    (["settling", "settling"], r"^metrics = 'settling': given twice"),
    (["speed"], r"^metrics = \['speed'\]: expected some of critical, spike, reversal, "
                r"settling$")])
def test_measure_refuses_a_quantity_twice_or_unknown(metrics: list[str], says: str) -> None:
    """An unknown quantity was left out of the row without a word (only
    compare_compensations checked it)."""
    scheme = cc.schemes(fd.preset("wang2021-drive"), ["none"])[0]
    with pytest.raises(ParameterError, match=says):
        cc.measure(scheme, "cdfs", 0.4, metrics, band=1e-6)


def test_positioning_test_refuses_a_target_twice() -> None:
    """Reference values computed by hand: B_i = 1 µm at 0 m and 3 µm at 0.1 m, so
    B̄ = (1 + 3)/2 = 2 µm; with 0.1 m given twice it came out (1 + 3 + 3)/3 = 2.33 µm."""
    up = np.array([[1.0] * 5, [3.0] * 5]) * 1e-6
    down = np.zeros((2, 5))
    assert positioning_test([0.0, 0.1], up, down).mean_reversal == pytest.approx(2e-6)
    with pytest.raises(ParameterError, match=r"^targets = 0\.1: given twice; expected each "
                                             r"target position once \[m\] \(twice, it would "
                                             r"count twice in the mean reversal value\)$"):
        positioning_test([0.0, 0.1, 0.1], np.vstack([up, up[1:]]), np.zeros((3, 5)))


# ------------------------------------------- 3: a start position no model reads


def _refused(drive: str, value: object) -> str:
    return (rf"^table_position = {value}: applies to a drive whose model depends on the "
            rf"table's position \(cdfs, ddfs\), not to {drive}; omit it$")


@pytest.mark.parametrize(("params", "drive"), [(LM, "linear-motor"), (RP, "rack-pinion")])
def test_drive_system_refuses_a_start_position_its_model_does_not_read(
        params: fd.DriveParameters, drive: str) -> None:
    """Measured before the fix: a 0.5-s run at 1 mm/s from 0.2 m and from 0.6 m gave the same
    table_position and table_speed bit for bit on both drives (the CDFS's speeds differ by
    2e-9 m/s: its K_eq(a))."""
    with pytest.raises(ParameterError, match=_refused(drive, "0.2")):
        fd.DriveSystem(params, drive, 0.2)
    with pytest.raises(ParameterError, match=_refused(drive, "0.0")):
        fd.DriveSystem(params, drive=drive, table_position=0.0)
    # the default, and the default's value given (a positional field: not told apart)
    assert fd.DriveSystem(params, drive).table_position == 0.4
    assert fd.DriveSystem(params, drive, 0.4).table_position == 0.4
    assert fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.2).table_position == 0.2


def test_machine_axis_refuses_what_its_drive_does_not_read() -> None:
    """Both were taken on an axis built in Python (the machine file refuses them since
    session 30, through the same checks)."""
    with pytest.raises(ParameterError, match=_refused("linear-motor", "0.3")):
        MachineAxis("x", LM, "linear-motor", 0.3)
    with pytest.raises(ParameterError, match=r"^nut_hold = 'servo': applies to a drive that "
                                             r"holds its nut \(cdfs\), not to rack-pinion"):
        MachineAxis("x", RP, "rack-pinion", nut_hold="servo")
    assert MachineAxis("x", LM, "linear-motor").table_position == 0.4
    assert MachineAxis("x", fd.preset("wang2021"), "cdfs", 0.3, "servo").nut_hold == "servo"
    with pytest.raises(ParameterError, match=r"^axes\.y\.table_position = 0\.4: applies to"):
        machine_from_dict({"name": "m", "axes": {"y": {"drive": "linear-motor",
                                                       "table_position": 0.4}}})


def test_a_table_placed_by_a_test_run_starts_where_its_drive_reads_it() -> None:
    """The positioning run starts the table at its first stop and the circular run on its
    circle: a linear motor is now given no start there (it was refused, the run with it)."""
    from feeddrive.analysis.circular_run import run_circular_test
    from feeddrive.analysis.positioning_run import run_positioning_test

    with pytest.raises(ParameterError, match=_refused("linear-motor", "0.098")):
        fd.DriveSystem(LM, "linear-motor", 0.098)  # that first stop, 0.1 m − 2 mm
    run = run_positioning_test(LM, "linear-motor", [0.1, 0.2], feed=0.05, dwell=0.3,
                               warm_up=0)
    assert run.start == pytest.approx(0.098) and np.isfinite(run.test.reversal)
    machine = Machine("xy", (MachineAxis("x", LM, "linear-motor"),
                             MachineAxis("y", LM, "linear-motor")))
    circle = run_circular_test(machine, radius=0.005, feed=0.01, acceleration=0.5)
    assert circle.test.radius == pytest.approx(0.005, abs=1e-6)


def test_compare_compensations_refuses_the_start_before_any_run(no_runs: None) -> None:
    """Its reversal quantity's targets lie about the start: on a linear motor they carried
    it to no model."""
    with pytest.raises(ParameterError, match=_refused("linear-motor", "0.3")):
        cc.compare_compensations(LM, drive="linear-motor", table_position=0.3,
                                 metrics=["reversal"])


def test_the_explorer_disables_the_position_of_a_drive_that_does_not_read_it() -> None:
    """As the nut speed of a drive without a driven nut: the page's position is not read (a
    position typed there was passed on and dropped)."""
    from feeddrive.explore.settings import check

    checked = check({"drive": "linear-motor", "preset": "linear-motor-example",
                     "position": "300"})
    assert "position" in checked.disabled and not checked.errors, checked.errors
    assert checked.system is not None and checked.system.table_position == 0.4
    cdfs = check({"drive": "cdfs", "position": "300"})
    assert "position" not in cdfs.disabled and cdfs.system is not None
    assert cdfs.system.table_position == pytest.approx(0.3)


def test_a_sweep_gives_a_linear_motor_no_start_as_it_gives_a_cdfs_no_nut_speed() -> None:
    """A sweep across drives with a table_position axis: the linear motor's points took each
    position, computed each alike (2 runs of one result); now they share one, as the CDFS's
    points at every nut speed do (docs/sweeps.md), with the default start its DriveSystem
    takes."""
    from feeddrive.sweep import parse_config

    cfg = parse_config({"preset": "linear-motor-example", "design": {"kind": "grid"},
                        "quantity": {"kind": "linear-band", "linear_points": 4},
                        "axes": {"drive": ["cdfs", "linear-motor"],
                                 "table_position": [300, 500]}}, "/tmp/cfg.toml")
    points = list(cfg.iter_points())
    assert [(p.task["drive"], p.task["table_position"]) for p in points] == [
        ("cdfs", pytest.approx(0.3)), ("cdfs", pytest.approx(0.5)), ("linear-motor", 0.4),
        ("linear-motor", 0.4)]
    assert len({p.key for p in points}) == cfg.distinct_count() == 3


def test_a_fit_record_of_a_linear_motor_stays_readable(tmp_path: Path) -> None:
    """A fit writes table_position for every drive; one fitted through the API at 0.0 m (as
    tests/validation/test_fit_replay did) would build a DriveSystem that now refuses it, and
    the key cannot be left out of the record: read as the default, which the fit used as
    much (its model reads neither)."""
    from feeddrive.analysis.predict import read_fit_record

    fit = tmp_path / "fit.toml"
    fit.write_text('extends = "linear-motor-example"\nname = "fitted"\n[fit]\n'
                   'drive = "linear-motor"\ntable_position = 0.0\nfree = ["table.mass"]\n'
                   f"estimates = [{LM.table.mass!r}]\ncovariance = [[1e-4]]\n"
                   "interrupted = false\n", encoding="utf-8")
    record = read_fit_record(fit)
    assert record.table_position == 0.4
    assert fd.DriveSystem(record.parameters, record.drive, record.table_position)
