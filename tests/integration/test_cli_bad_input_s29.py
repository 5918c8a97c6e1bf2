"""Command-line findings of the bad-input sweep of session 29: options the run would not use
were dropped without a word — `loops --machine M --plot p.png` exited 0 and wrote no plot,
`simulate --frequency 5` ran a constant speed, `simulate --machine M --table-speed 3` ran the
contour.  Each is now one line naming the option, its value and why it is not taken, exit
status 2, before any work."""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_support import one_line_refusal


def test_loops_of_a_machine_refuse_a_plot_they_would_not_write(tmp_path: Path) -> None:
    plot = tmp_path / "loops.png"
    line = one_line_refusal(["loops", "--machine", "xy-table", "--plot", str(plot)])
    assert line == (f"error: --plot = '{plot}': not with --machine (a machine's loops are "
                    "printed, not plotted)")
    assert not plot.exists()


@pytest.mark.parametrize(("extra", "option"), [
    (["--drive", "ddfs"], "--drive = 'ddfs'"), (["--position", "100"], "--position = 100.0"),
    (["--preset", "wang2021"], "--preset = 'wang2021'"), (["--plot-kind", "step"],
                                                          "--plot-kind = 'step'"),
])
def test_loops_of_a_machine_refuse_a_drives_options(extra: list[str], option: str) -> None:
    line = one_line_refusal(["loops", "--machine", "xy-table", *extra])
    assert line.startswith(f"error: {option}: not with --machine ("), line


@pytest.mark.parametrize(("extra", "option"), [
    (["--drive", "ddfs"], "--drive = 'ddfs'"), (["--table-speed", "3"], "--table-speed = 3.0"),
    (["--nut-speed", "3"], "--nut-speed = 3.0"), (["--position", "100"], "--position = 100.0"),
    (["--preset", "wang2021"], "--preset = 'wang2021'"),
    (["--profile", "sine"], "--profile = 'sine'"), (["--frequency", "2"], "--frequency = 2.0"),
])
def test_simulate_machine_refuses_a_drives_options(extra: list[str], option: str) -> None:
    line = one_line_refusal(["simulate", "--machine", "xy-table", "--duration", "0.1", *extra])
    assert line == (f"error: {option}: not with --machine (its axes are set in the machine "
                    "file and follow --contour)"), line


@pytest.mark.parametrize(("extra", "says"), [
    (["--frequency", "5"], "--frequency = 5.0: applies to --profile sine, not to --profile "
                           "constant"),
    (["--ramp-time", "0.1"], "--ramp-time = 0.1: applies to --profile trapezoid, not to "
                             "--profile constant"),
    (["--profile", "sine", "--dwell", "2"], "--dwell = 2.0: applies to --profile stepdown, "
                                            "not to --profile sine"),
    (["--profile-file", "p.csv"], "--profile-file = 'p.csv': applies to --profile csv, not "
                                  "to --profile constant"),
    (["--radius", "10"], "--radius = 10.0: an option of --machine, which a drive's run does "
                         "not use"),
    (["--contour", "line"], "--contour = 'line': an option of --machine, which a drive's run "
                            "does not use"),
])
def test_simulate_refuses_an_option_its_profile_does_not_use(extra: list[str],
                                                             says: str) -> None:
    line = one_line_refusal(["simulate", "--table-speed", "1", "--duration", "0.1", *extra])
    assert line == f"error: {says}", line


def test_a_csv_profile_refuses_a_speed_option(tmp_path: Path) -> None:
    profile = tmp_path / "p.csv"
    profile.write_text("time,table_speed\n0,1\n1,1\n", encoding="utf-8")
    line = one_line_refusal(["simulate", "--profile", "csv", "--profile-file", str(profile),
                              "--table-speed", "2"])
    assert line == ("error: --table-speed = 2.0: not with --profile csv (the --profile-file's "
                    "columns are the command)"), line


@pytest.mark.parametrize("args", [
    ["circular", "--magnification", "5"],
    ["analyze", "--circular", "trace.csv", "--magnification", "5"],
    ["loops", "--plot-kind", "nyquist"],
])
def test_a_plots_setting_without_the_plot_is_refused(tmp_path: Path, args: list[str]) -> None:
    trace = tmp_path / "trace.csv"
    trace.write_text("time,x,y\n0,1,0\n", encoding="utf-8")
    args = [str(trace) if a == "trace.csv" else a for a in args]
    line = one_line_refusal(args)
    option, value = args[-2], args[-1]
    shown = repr(value) if option == "--plot-kind" else float(value)
    assert line == f"error: {option} = {shown}: applies to --plot, which this run does not write"


@pytest.mark.parametrize(("args", "says"), [
    (["--targets", "100,100"], "--targets = '100,100': expected at least 2 increasing "
                               "positions [mm]"),
    (["--count", "50", "--span", "100,700", "--feed", "0.0001", "--dwell", "0.0001"],
     "--feed = 0.0001: expected a higher feed [mm/s], or fewer targets: "),
])
def test_a_positioning_refusal_gives_the_options_unit(args: list[str], says: str) -> None:
    """The values were shown in mm and mm/s as typed, their unit the API's "[m]", "[m/s]"."""
    line = one_line_refusal(["positioning", *args])
    assert line.startswith(f"error: {says}"), line


@pytest.mark.parametrize("mass", ["0", "-2", "nan"])
def test_identify_dynamic_names_its_mass_option(tmp_path: Path, mass: str) -> None:
    """It said "mass = 0.0" (the fit's argument), after reading the test's file."""
    line = one_line_refusal(["identify", "dynamic", str(tmp_path / "not-read.csv"),
                              "--mass", mass])
    assert line == f"error: --mass = {float(mass)!r}: expected a finite mass > 0 [kg]", line
