"""Issue 35 item 1, an outside check: a parameter file's ``[solver]`` table was honoured by
``feeddrive simulate --params`` only.  The API ignored it (873 steps at accuracy 1 against the
command's 1785 at the file's 0.01), ``sweep`` ignored its ``params`` file's table and refused
a table of its own, ``reproduce --params`` neither applied nor keyed it, ``predict`` and
``sensitivity`` ignored the table of their positional ``FIT.toml``, and ``params show`` did
not print it.  Each case here runs with and without the table and against the same settings
given explicitly; short runs, one worker (two where the worker processes are the point).

The set carries the table (``DriveParameters.solver``, not a parameter: equality, hashes,
``to_dict`` and the text of sets without one unchanged), ``dumps``/``loads`` keep it (a worker
reads the set from its TOML), and every run layers it under the API's settings, setting by
setting (``feeddrive.engine.simulate.run_options``).  (One module: a unit module of the same
name beside it would clash with it in one pytest run.)"""

from __future__ import annotations

import csv
import json
import pickle
import sqlite3
from dataclasses import replace
from pathlib import Path

import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.analysis.critical import creep_trial
from feeddrive.analysis.cycle_verdict import VerdictRule
from feeddrive.cli import app
from feeddrive.engine import options as opt
from feeddrive.engine.error_estimate import tightened
from feeddrive.engine.simulate import run_options
from feeddrive.parameters import ParameterError, dumps, load, loads, to_dict
from feeddrive.parameters.components import SOLVER_SETTINGS, solver_over, solver_table
from feeddrive.parameters.toml_io import tables_applied

runner = CliRunner()
SET = 'extends = "wang2021"\nname = "s19-solver"\n'
SWEEP = ('drive = "cdfs"\ntable_position = 400\n[design]\nkind = "grid"\n'
         '[quantity]\nkind = "creep-trial"\ninitial_duration = 3\nmax_duration = 3\n'
         'linear = false\n[axes]\ntable_speed = [1.0, 1.6]\n')
FIT = ('\n[fit]\ndata = ["tr1.csv"]\ndrive = "cdfs"\ntable_position = 0.4\n'
       'free = ["controller.velocity_integral_gain"]\nestimates = [3925.28]\n'
       'ci_low = [3925.2799]\nci_high = [3925.2801]\ninterval = ["linear"]\n'
       'determined = [true]\nconfidence = 0.95\ncovariance = [[5.3e-14]]\n'
       'residual_check = true\ninterrupted = false\n')


def _write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def _cli(args: list[str]) -> str:
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    return result.output


def _simulate_json(args: list[str]) -> dict:
    return json.loads(_cli(["simulate", "--table-speed", "1", "--duration", "1", "--json",
                            *args]))["solver"]


def test_the_api_takes_the_files_table_as_the_command_line_does(tmp_path: Path) -> None:
    path = _write(tmp_path / "s1.toml", SET + "[solver]\naccuracy = 0.01\n")
    params = load(path)
    system = fd.DriveSystem(params, drive="cdfs", table_position=0.4)
    api = fd.simulate(system, fd.ConstantSpeed(table_speed=1e-3), 1.0).solver_stats
    cli = _simulate_json(["--params", str(path)])
    assert api["accuracy"] == cli["accuracy"] == 0.01
    assert api["steps"] == cli["steps"] and api["rtol"] == cli["rtol"] == pytest.approx(1e-8)
    plain = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4),
                        fd.ConstantSpeed(table_speed=1e-3), 1.0).solver_stats
    assert plain["accuracy"] == 1.0 and plain["steps"] != api["steps"]
    # the API's own setting wins for that setting only; describe() names the file's
    mixed = fd.simulate(system, fd.ConstantSpeed(1e-3), 1.0,
                        options=fd.SolverOptions(rtol=1e-7)).solver_stats
    assert (mixed["rtol"], mixed["accuracy"]) == (1e-7, 0.01)
    assert f"accuracy 0.01 (from [solver] in {path})" in run_options(system).describe()


def test_a_creep_trial_and_its_error_estimate_take_the_table(tmp_path: Path) -> None:
    """The API's creep search (one trial here): the trial at the file's accuracy, and its
    shadow (the options in force made ten times tighter) ten times tighter than that."""
    params = load(_write(tmp_path / "s1.toml", SET + "[solver]\naccuracy = 0.01\n"))
    rule = VerdictRule(initial_duration=3.0, max_duration=3.0)
    from_file = creep_trial(fd.DriveSystem(params, "cdfs", 0.4), 1e-3, rule=rule,
                            error_estimate="shadow")
    with opt.using(fd.SolverOptions(accuracy=0.01)):
        given = creep_trial(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4), 1e-3,
                            rule=rule, error_estimate="shadow")
    plain = creep_trial(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4), 1e-3, rule=rule,
                        error_estimate="shadow")
    assert from_file.ripple_ratio == given.ripple_ratio != plain.ripple_ratio
    assert from_file.speed_error == given.speed_error != plain.speed_error


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as f:
        return [{k: v for k, v in row.items() if k not in ("seconds [s]", "key")}
                for row in csv.DictReader(f)]


def _sweep(tmp_path: Path, config: Path, name: str, *args: str) -> list[dict[str, str]]:
    out = tmp_path / f"{name}.csv"
    _cli(["sweep", str(config), "--workers", "1", "--store", str(tmp_path / f"{name}.sqlite"),
          "--output", str(out), *args])
    return _rows(out)


def test_a_sweep_takes_its_parameter_files_table_and_its_own(tmp_path: Path) -> None:
    _write(tmp_path / "s1.toml", SET + "[solver]\naccuracy = 0.01\n")
    preset = _write(tmp_path / "preset.toml", 'name = "a"\npreset = "wang2021"\n' + SWEEP)
    from_params = _write(tmp_path / "params.toml", 'name = "b"\nparams = "s1.toml"\n' + SWEEP)
    own = _write(tmp_path / "own.toml",
                 'name = "c"\npreset = "wang2021"\n' + SWEEP + "[solver]\naccuracy = 0.1\n")
    both = _write(tmp_path / "both.toml",
                  'name = "d"\nparams = "s1.toml"\n' + SWEEP + "[solver]\naccuracy = 0.1\n")
    default = _sweep(tmp_path, preset, "default")
    at_001 = _sweep(tmp_path, preset, "at001", "--accuracy", "0.01")
    at_01 = _sweep(tmp_path, preset, "at01", "--accuracy", "0.1")
    assert at_001 != default and at_01 != default and at_001 != at_01
    assert _sweep(tmp_path, from_params, "from_params") == at_001
    assert _sweep(tmp_path, own, "own") == at_01
    # the sweep file's table over the parameter file's, the command line over both
    assert _sweep(tmp_path, both, "both") == at_01
    assert _sweep(tmp_path, both, "cli", "--accuracy", "0.01") == at_001


def test_a_command_line_default_holds_over_the_file_in_worker_processes(
        tmp_path: Path) -> None:
    """``--accuracy 1`` over the file's 0.01: the worker processes read the set from its TOML
    and the options from a record without their sources; they run at 1 as this one would."""
    _write(tmp_path / "s1.toml", SET + "[solver]\naccuracy = 0.01\n")
    preset = _write(tmp_path / "preset.toml", 'name = "a"\npreset = "wang2021"\n' + SWEEP)
    config = _write(tmp_path / "params.toml", 'name = "b"\nparams = "s1.toml"\n' + SWEEP)
    default = _sweep(tmp_path, preset, "default")
    assert _sweep(tmp_path, config, "one", "--accuracy", "1", "--workers", "2") == default


def test_the_api_sweep_takes_both_tables_in_its_worker_processes(tmp_path: Path) -> None:
    from feeddrive.sweep import SweepStore, load_config, run_sweep

    _write(tmp_path / "s1.toml", SET + "[solver]\naccuracy = 0.01\n")
    config = load_config(_write(tmp_path / "params.toml",
                                'name = "b"\nparams = "s1.toml"\n' + SWEEP))
    preset = load_config(_write(tmp_path / "preset.toml",
                                'name = "a"\npreset = "wang2021"\n' + SWEEP))

    def values(cfg: object, store: str) -> list[dict]:
        with SweepStore(tmp_path / store) as db:
            run_sweep(cfg, db, workers=1)
            return [{k: v for k, v in (db.get(p.key) or {})["values"].items()}
                    for p in cfg.points()]  # type: ignore[attr-defined]

    from_file = values(config, "api.sqlite")
    with opt.using(fd.SolverOptions(accuracy=0.01)):
        given = values(preset, "given.sqlite")
    assert from_file == given != values(preset, "plain.sqlite")


def test_a_sweeps_tolerances_over_its_parameter_files_accuracy_are_refused(
        tmp_path: Path) -> None:
    _write(tmp_path / "s1.toml", SET + "[solver]\naccuracy = 0.01\n")
    config = _write(tmp_path / "bad.toml", 'name = "b"\nparams = "s1.toml"\n' + SWEEP
                    + "[solver]\nrtol = 1e-8\n")
    result = runner.invoke(app, ["sweep", str(config), "--workers", "1", "--store",
                                 str(tmp_path / "bad.sqlite")])
    lines = [ln for ln in result.output.splitlines() if ln.strip()]
    assert result.exit_code == 2 and len(lines) == 1 and "solver.rtol" in lines[0], \
        result.output
    assert not (tmp_path / "bad.sqlite").exists()
    from feeddrive.sweep import load_config

    with pytest.raises(ParameterError, match="solver.rtol"):
        load_config(config)


def test_reproduce_applies_and_keys_the_table(tmp_path: Path) -> None:
    from feeddrive.reproduce.report import integrator_text
    from feeddrive.reproduce.runner import study_store
    from feeddrive.reproduce.studies import StudySettings

    plain = load(_write(tmp_path / "p0.toml", SET))
    tight = load(_write(tmp_path / "p1.toml", SET + "[solver]\naccuracy = 0.1\n"))
    other = load(_write(tmp_path / "p2.toml", SET + "[solver]\naccuracy = 0.2\n"))
    keys = {study_store(tmp_path / name, p, StudySettings()).key
            for name, p in (("a", plain), ("b", tight), ("c", other))}
    assert len(keys) == 3
    # a set without a table keeps the key it had
    assert study_store(tmp_path / "d", plain, StudySettings()).key == \
        study_store(tmp_path / "e", fd.preset("wang2021").replace_path(
            "name", "s19-solver").replace_path("description", plain.description),
            StudySettings()).key
    assert f"accuracy 0.1 (from [solver] in {tmp_path / 'p1.toml'})" in integrator_text(tight)
    assert integrator_text(plain) == integrator_text()


def test_reproduce_refuses_a_bad_table_before_any_work(tmp_path: Path) -> None:
    path = _write(tmp_path / "bad.toml", SET + "[solver]\naccuracy = -1.0\n")
    out = tmp_path / "out"
    result = runner.invoke(app, ["reproduce", "--params", str(path), "--out", str(out),
                                 "--no-study", "--workers", "1"])
    lines = [ln for ln in result.output.splitlines() if ln.strip()]
    assert result.exit_code == 2 and len(lines) == 1 and "solver.accuracy" in lines[0], \
        result.output
    assert not (out / "data").exists()


def _keys(store: Path) -> set[str]:
    with sqlite3.connect(store) as db:
        return {row[0] for row in db.execute("SELECT key FROM results")}


def test_predict_takes_the_table_of_its_fit_file(tmp_path: Path) -> None:
    plain = _write(tmp_path / "fit.toml", SET + FIT)
    tight = _write(tmp_path / "fits.toml", SET + FIT + "\n[solver]\naccuracy = 0.1\n")
    args = ["--samples", "1", "--workers", "1", "--low", "1.5", "--high", "1.6",
            "--resolution", "0.05", "--json"]
    with_table = json.loads(_cli(["predict", str(tight), "--store",
                                  str(tmp_path / "t.sqlite"), *args]))
    without = json.loads(_cli(["predict", str(plain), "--store", str(tmp_path / "p.sqlite"),
                               *args]))
    assert f"accuracy 0.1 (from [solver] in {tight})" in with_table["integrator"]
    assert "accuracy" not in without["integrator"].split("(V:")[1]
    assert _keys(tmp_path / "t.sqlite").isdisjoint(_keys(tmp_path / "p.sqlite"))
    # the points' runs take it: the set a worker reads back, under the record it is sent
    from feeddrive.analysis.predict import read_fit_record

    params = read_fit_record(tight).parameters
    assert run_options(params, fd.SolverOptions.from_record(
        fd.SolverOptions().record())).accuracy == 0.1


def test_sensitivity_takes_the_table_of_its_fit_file_as_of_params(tmp_path: Path) -> None:
    tight = _write(tmp_path / "fits.toml", SET + FIT + "\n[solver]\naccuracy = 0.1\n")
    plain = _write(tmp_path / "fit.toml", SET + FIT)
    args = ["--quantity", "linear-band", "--parameters", "table.mass", "--workers", "1",
            "--json"]
    positional = json.loads(_cli(["sensitivity", str(tight), "--store",
                                  str(tmp_path / "a.sqlite"), *args]))
    option = json.loads(_cli(["sensitivity", "--params", str(tight), "--store",
                              str(tmp_path / "b.sqlite"), *args]))
    without = json.loads(_cli(["sensitivity", str(plain), "--store",
                               str(tmp_path / "c.sqlite"), *args]))
    assert positional["integrator"] == option["integrator"] != without["integrator"]
    assert f"accuracy 0.1 (from [solver] in {tight})" in positional["integrator"]
    assert _keys(tmp_path / "a.sqlite") == _keys(tmp_path / "b.sqlite")
    assert _keys(tmp_path / "a.sqlite").isdisjoint(_keys(tmp_path / "c.sqlite"))


def test_params_show_prints_the_table(tmp_path: Path) -> None:
    path = _write(tmp_path / "s1.toml", SET + "[solver]\naccuracy = 0.01\nmax_steps = 1000\n")
    text = _cli(["params", "show", "--params", str(path)])
    assert text.rstrip().endswith("[solver]  # integrator settings, SI (docs/parameters.md, "
                                  '"[solver]")\naccuracy = 0.01  # [-]\nmax_steps = 1000')
    data = json.loads(_cli(["params", "show", "--params", str(path), "--format", "json"]))
    assert data["solver"] == {"accuracy": 0.01, "max_steps": 1000}
    # what it prints reads back, on the command line too
    again = _write(tmp_path / "again.toml", text)
    assert _simulate_json(["--params", str(again), "--duration", "0.1"])["accuracy"] == 0.01


def test_parameters_md_documents_the_table() -> None:
    doc = (Path(__file__).resolve().parents[2] / "docs" / "parameters.md").read_text(
        encoding="utf-8")
    section = doc.split("## The integrator settings: `[solver]`")[1].split("\n## ")[0]
    for name, (_, unit) in SOLVER_SETTINGS.items():
        assert f"| `{name}` |" in section, name
        if unit:
            assert f"| `{name}` | {unit} |" in section, name
    for words in ("Precedence", "command line", "API", "SI", "mm/s", "extends"):
        assert words in section, words


# ------------------------------------------------ the set, its text, run_options

PLAIN = 'extends = "wang2021"\nname = "s19"\n'


def _file(tmp_path: Path, table: str, name: str = "run.toml") -> Path:
    path = tmp_path / name
    path.write_text(PLAIN + (f"\n[solver]\n{table}" if table else ""), encoding="utf-8")
    return path


def test_the_table_names_the_options_settings_and_units() -> None:
    assert tuple(SOLVER_SETTINGS) == opt.SETTINGS
    units = {name: unit for name, unit, _ in opt.TOLERANCES}
    for name, unit in units.items():
        assert SOLVER_SETTINGS[name] == ("number", unit), name


def test_the_set_carries_the_table_but_it_is_no_parameter(tmp_path: Path) -> None:
    with_table = load(_file(tmp_path, "accuracy = 0.01\nrosenbrock = \"rodas4\"\n"))
    plain = load(_file(tmp_path, "", "plain.toml"))
    source = f"[solver] in {tmp_path / 'run.toml'}"
    assert with_table.solver == (("accuracy", 0.01, source), ("rosenbrock", "rodas4", source))
    assert plain.solver == ()
    # not a parameter: equal sets, equal hashes, the same to_dict
    assert with_table == plain and hash(with_table) == hash(plain)
    assert to_dict(with_table) == to_dict(plain)
    # the text of a set without a table is as before; with one, the table comes last
    assert "[solver]" not in dumps(plain) and "[solver]" not in dumps(fd.preset("wang2021"))
    text = dumps(with_table)
    assert text.startswith(dumps(plain).rstrip("\n"))
    assert text.rstrip().endswith('accuracy = 0.01  # [-]\nrosenbrock = "rodas4"')
    # read back (a worker's set), kept by replace_path and pickling
    back = loads(text)
    assert [(n, v) for n, v, _ in back.solver] == [("accuracy", 0.01), ("rosenbrock", "rodas4")]
    moved = with_table.replace_path("controller.velocity_gain", 50.0)
    assert moved.solver == with_table.solver
    assert pickle.loads(pickle.dumps(with_table)).solver == with_table.solver
    with pytest.raises(ParameterError, match="not a parameter"):
        with_table.replace_path("solver.accuracy", 0.1)
    # an integer count stays an integer (SolverOptions refuses 1000.0 steps)
    counted = loads(dumps(load(_file(tmp_path, "max_steps = 1000\n", "n.toml"))))
    assert counted.solver[0][:2] == ("max_steps", 1000) and isinstance(counted.solver[0][1], int)


@pytest.mark.parametrize(("table", "field", "words"), [
    ("rtoll = 1e-8\n", "solver.rtoll", "did you mean 'rtol'"),
    ('rtol = "1e-7"\n', "solver.rtol", "expected a number [-]"),
    ("accuracy = 0.1\nrtol = 1e-7\n", "solver.accuracy", "given with solver.rtol"),
    ("max_steps = 1.5\n", "solver.max_steps", "expected a whole number"),
])
def test_a_bad_table_is_refused_where_the_file_is_read(tmp_path: Path, table: str, field: str,
                                                        words: str) -> None:
    path = _file(tmp_path, table)
    with pytest.raises(ParameterError) as err:
        load(path)
    assert err.value.field == field and words in str(err.value)
    assert str(path) in str(err.value)


def test_a_bad_value_is_refused_before_a_run_naming_the_file(tmp_path: Path) -> None:
    params = load(_file(tmp_path, "rtol = -1.0\n"))  # a number: its range is the options'
    system = fd.DriveSystem(params, drive="cdfs", table_position=0.4)
    with pytest.raises(ParameterError, match=r"solver.rtol = -1.0: .*\[solver\] in .*run.toml"):
        fd.simulate(system, fd.ConstantSpeed(1e-3), 0.01)


def test_the_api_over_the_table_setting_by_setting(tmp_path: Path) -> None:
    params = load(_file(tmp_path, "accuracy = 0.01\nmethod = \"dopri5-dense\"\n"))
    source = f"[solver] in {tmp_path / 'run.toml'}"
    alone = run_options(params)
    assert (alone.accuracy, alone.method) == (0.01, "dopri5-dense")
    assert f"accuracy 0.01 (from {source})" in alone.describe()
    assert f"dopri5-dense (adaptive Dormand–Prince 5(4), dense output) (from {source})" \
        in alone.describe()
    # an explicit rtol is the API's; the file keeps its accuracy and method
    over = run_options(params, fd.SolverOptions(rtol=1e-7))
    assert (over.rtol, over.accuracy, over.method) == (1e-7, 0.01, "dopri5-dense")
    # the API's accuracy replaces the file's
    assert run_options(params, fd.SolverOptions(accuracy=0.5)).accuracy == 0.5
    # a value left at its default is the file's to set; given with its source, it holds
    assert run_options(params, fd.SolverOptions()).accuracy == 0.01
    held = fd.SolverOptions(accuracy=1.0, origin=(("accuracy", opt.API_SOURCE),))
    assert run_options(params, held).accuracy == 1.0
    # the options in force (feeddrive.engine.options.using) are the API too
    with opt.using(fd.SolverOptions(accuracy=0.2)):
        assert run_options(params).accuracy == 0.2
    # a set without a table runs the options as given
    assert run_options(fd.preset("wang2021"), over) is over


def test_an_api_accuracy_replaces_the_tables_tolerances(tmp_path: Path) -> None:
    params = load(_file(tmp_path, "rtol = 1e-9\nspeed_tolerance = 1e-10\n"))
    assert (run_options(params).rtol, run_options(params).speed_tolerance) == (1e-9, 1e-10)
    given = run_options(params, fd.SolverOptions(accuracy=0.1))
    assert (given.rtol, given.speed_tolerance, given.accuracy) == (None, None, 0.1)
    # the command line's layering does the same (feeddrive.engine.options.layered)
    cli = opt.layered([("[solver] in run.toml", {"rtol": 1e-9, "speed_tolerance": 1e-10}),
                       ("command line", {"accuracy": (0.1, "--accuracy")})])
    assert cli.record() == replace(given, origin=()).record()


def test_a_shadow_of_the_defaults_is_the_tables_made_tighter(tmp_path: Path) -> None:
    """A creep search's error estimate tightens the options in force (the defaults, when the
    API gives none): over a set with a table, its shadow runs are the table's made tighter,
    as a run with the table's settings given in Python would have them."""
    params = load(_file(tmp_path, "accuracy = 0.01\n"))
    shadow = run_options(params, tightened(fd.SolverOptions()))
    assert shadow.accuracy == pytest.approx(0.001)
    assert shadow.record() == tightened(fd.SolverOptions(accuracy=0.01)).record()
    explicit = load(_file(tmp_path, "rtol = 1e-8\n", "r.toml"))
    shadow = run_options(explicit, tightened(fd.SolverOptions()))
    assert shadow.rtol == pytest.approx(1e-9) and shadow.accuracy == pytest.approx(0.1)
    # a run's own shadow (simulate's error estimate) is not tightened twice
    own = run_options(params)
    assert run_options(params, tightened(own)).record() == tightened(own).record()


def test_a_sweeps_table_over_its_parameter_files() -> None:
    lower = solver_table({"rtol": 1e-8, "method": "dopri5"}, "[solver] in p.toml")
    upper = solver_table({"accuracy": 0.1}, "[solver] in sweep.toml")
    assert solver_over(lower, upper) == (("method", "dopri5", "[solver] in p.toml"),
                                        ("accuracy", 0.1, "[solver] in sweep.toml"))
    with pytest.raises(ParameterError, match="over accuracy in \\[solver\\] in sweep.toml"):
        solver_over(upper, lower)


def test_a_command_gives_its_files_sets_the_tables_it_merged(tmp_path: Path) -> None:
    path = _file(tmp_path, "accuracy = 0.01\n")
    carried = (("accuracy", 1.0, "--accuracy"),)
    with tables_applied({str(path): carried}):
        assert load(path).solver == carried
        assert load(_file(tmp_path, "accuracy = 0.2\n", "other.toml")).solver[0][1] == 0.2
    assert load(path).solver[0][1] == 0.01


def test_the_fmu_exports_tolerances_take_the_sets_table() -> None:
    """``export_fmu`` from Python wrote the defaults' tolerances for a set whose file says
    ``accuracy = 0.1`` (``feeddrive export fmu --params`` took the table); the start values
    now come from the options a run of the set takes (``run_options``)."""
    from feeddrive.fmu import solver_starts

    params = fd.parameters.loads('extends = "wang2021"\n[solver]\naccuracy = 0.1\n')
    plain = solver_starts(fd.preset("wang2021"), 2e-3, 0.0)
    tight = solver_starts(params, 2e-3, 0.0)
    for name, value in plain.items():
        assert tight[name] == pytest.approx(value / 10, rel=1e-12), name
    given = solver_starts(params, 2e-3, 0.0, fd.SolverOptions(accuracy=0.5))  # the API's wins
    assert given["solver.relative_tolerance"] == pytest.approx(
        plain["solver.relative_tolerance"] * 0.5)


def test_a_creep_searchs_shadow_is_decided_on_the_options_its_trials_take() -> None:
    """A set whose table is at double precision's reach (``accuracy = 1e-8``, the floor): its
    trials' shadow cannot be made 10× tighter, said before any trial runs — the check looked
    at the options given alone, and the shadow trial failed on the table's value mid-search."""
    from feeddrive.analysis.critical import shadow_possible
    from feeddrive.engine.options import MIN_ACCURACY

    params = fd.parameters.loads(f'extends = "wang2021"\n[solver]\naccuracy = {MIN_ACCURACY!r}\n')
    system = fd.DriveSystem(params, drive="cdfs", table_position=0.4)
    assert shadow_possible() and not shadow_possible(system=system)
    assert shadow_possible(fd.SolverOptions(accuracy=1.0, origin=(("accuracy", "API"),)),
                           system=system)  # the API's accuracy over the table's
    with pytest.raises(fd.ParameterError, match="--error-estimate|error_estimate"):
        creep_trial(system, 1e-3, error_estimate=True)


def test_a_fits_output_interval_holds_against_the_sets_table() -> None:
    """A fit runs each record at its sample step (1 ms here, the default's value): a set whose
    table says ``output_interval = 0.01`` replaced it, a default-valued setting being the
    table's to set; the fit names the interval as its own (``fit._record_step``)."""
    from dataclasses import replace as dc_replace

    from feeddrive.analysis.fit import RECORD_STEP_SOURCE, _record_step
    from feeddrive.engine.simulate import run_options

    params = fd.parameters.loads('extends = "wang2021"\n[solver]\noutput_interval = 0.01\n')
    system = fd.DriveSystem(params, drive="cdfs", table_position=0.4)
    plain = dc_replace(fd.SolverOptions(), output_interval=1e-3)
    assert run_options(system, plain).output_interval == 0.01  # what the fit's runs got
    fitted = run_options(system, _record_step(fd.SolverOptions(), 1e-3))
    assert fitted.output_interval == 1e-3 and fitted.sample_steps
    assert fitted.source("output_interval") == RECORD_STEP_SOURCE
