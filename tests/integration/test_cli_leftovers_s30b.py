"""More leftovers of the bad-input sweeps on the command line (session 30): each a one-line
refusal (exit 2, nothing on standard output) naming the option, its value and what was
expected.

1. ``analyze --min-step`` beside ``--command-speed``, a command column or ``--no-segments``
   had no effect: measured before the fix, ``--json`` printed the same bytes with
   ``--min-step 0.5`` as without (it differs where segments are detected).
2. A comma list with an entry twice: ``compensate --compare --schemes none,none`` printed
   the scheme's row twice (two runs), ``--metrics settling,settling`` was taken (one check
   with ``stiffness --positions``; ``positioning --targets 100,100`` was refused already:
   test_cli_bad_input_s29).
3. ``--position`` on a linear motor or a rack and pinion: its model does not read where the
   table starts; a value other than the default 400 mm was taken and dropped.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_support import RUNNER, one_line_refusal
from test_cli_leftovers_s30 import _trace  # 20 s at 1 mm/s, with a command column or not

from feeddrive.cli import app

APPLIES = "it splits the segments detected from the position, without a command"


# --------------------------------------------------------------- 1: analyze --min-step


@pytest.mark.parametrize(("command", "extra", "beside"), [
    (False, ["--command-speed", "1"], "--command-speed, which makes the whole trace one "
                                      "segment"),
    (True, [], "the command column 'command_speed' of t.csv, whose steps set the segments"),
    (False, ["--no-segments"], "--no-segments")])
def test_analyze_refuses_min_step_where_no_segment_is_detected(tmp_path: Path, command: bool,
                                                               extra: list[str],
                                                               beside: str) -> None:
    trace = _trace(tmp_path / "t.csv", command)
    line = one_line_refusal(["analyze", str(trace), "--min-step", "0.5", *extra])
    assert line == f"error: --min-step = 0.5: not with {beside} ({APPLIES}); omit it"
    assert RUNNER.invoke(app, ["analyze", str(trace), *extra]).exit_code == 0


def test_analyze_takes_min_step_where_segments_are_detected(tmp_path: Path) -> None:
    trace = _trace(tmp_path / "t.csv", command=False)
    result = RUNNER.invoke(app, ["analyze", str(trace), "--min-step", "0.5"])
    assert result.exit_code == 0, result.output
    assert "--min-step 0.5 mm/s" in result.stdout
    line = one_line_refusal(["analyze", str(trace), "--min-step", "0.5", "--no-segments"])
    assert line.startswith("error: --min-step = 0.5: not with --no-segments")


# ---------------------------------------------------------- 2: a comma list's repeats


@pytest.mark.parametrize(("args", "says"), [
    (["--schemes", "none,none", "--metrics", "settling"],
     "error: --schemes = 'none': given twice; expected each scheme once (twice, it would run "
     "twice and its row repeat)"),
    (["--schemes", "none", "--metrics", "settling, settling"],
     "error: --metrics = 'settling': given twice; expected each quantity once (it is "
     "measured once per scheme)")])
def test_compensate_compare_refuses_an_entry_given_twice(args: list[str], says: str) -> None:
    assert one_line_refusal(["compensate", "--compare", *args]) == says


@pytest.mark.parametrize(("args", "says"), [
    (["--schemes", "none,bogus"], "error: --schemes = ['bogus']: expected some of none, "
     "none-continuous, feedforward, observer, disturbance-observer, reset-integrator, "
     "reversal-feedforward"),
    (["--metrics", "speedy"], "error: --metrics = ['speedy']: expected some of critical, "
     "spike, reversal, settling")])
def test_compensate_compare_names_the_option_of_an_unknown_name(args: list[str],
                                                                says: str) -> None:
    # it named the API's argument ("schemes = ['bogus']"), not the option typed
    assert one_line_refusal(["compensate", "--compare", *args]) == says


# ------------------------------------------------------- 3: --position no model reads


@pytest.mark.parametrize(("drive", "args"), [
    ("linear-motor", ["simulate", "--table-speed", "1", "--duration", "0.2"]),
    ("rack-pinion", ["params", "slots"]),
    ("linear-motor", ["loops"])])
def test_a_position_is_refused_where_the_drive_does_not_read_it(drive: str,
                                                                args: list[str]) -> None:
    line = one_line_refusal([*args, "--drive", drive, "--position", "300"])
    assert line == ("error: --position = 300.0: applies to a drive whose model depends on "
                    f"the table's position (cdfs, ddfs), not to {drive}; omit it")
    taken = RUNNER.invoke(app, [*args, "--drive", drive])  # the default: taken
    assert taken.exit_code == 0, taken.output
