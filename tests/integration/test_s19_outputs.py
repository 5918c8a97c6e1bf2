"""An outside check's five findings (2026-12-06), each through the command line:

1. ``sweep --dry-run`` after a run at other settings crashed on a probe rate it never took and
   counted the points stored under the *registered* design, not this call's;
2. a streamed ``simulate --output`` (.parquet, .csv) lacked the solver record and the error
   estimate that .nc and .mat carry;
3. ``simulate --json`` gave the solver's tolerances in m and m/s under the names of options
   that take mm and mm/s, and the text called an explicit tolerance "scaled";
4. ``--method``'s help named RODAS4 as ``modal``'s Rosenbrock method after the default became
   RODAS5P;
5. ``simulate --machine`` never stated its integrator settings.

The pieces behind them are tested at the end: the solver record added to a streamed file,
the JSON's solver block, the integrator line's "scaled" read from a record alone, the dry
run's text when no point was timed.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import scipy.io
import xarray as xr
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.cli import app
from feeddrive.engine import options as opt
from feeddrive.parameters import ParameterError

runner = CliRunner()

#: a sweep of two cheap creep trials (0.3 s simulated each)
SWEEP = """
name = "s19"
preset = "wang2021"
drive = "cdfs"
table_position = 400
[quantity]
kind = "creep-trial"
initial_duration = 0.3
max_duration = 0.3
linear = false
[axes]
table_speed = {speeds}
"""


def _sweep(tmp_path: Path, speeds: str = "[1.0, 1.6]") -> Path:
    path = tmp_path / "sw.toml"
    path.write_text(SWEEP.format(speeds=speeds), encoding="utf-8")
    return path


def _json(args: list[str]) -> dict[str, Any]:
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    data: dict[str, Any] = json.loads(result.stdout)
    return data


# ------------------------------------------------------------------ 1: sweep --dry-run


def test_a_dry_run_after_a_run_at_other_settings_counts_this_calls_points(
        tmp_path: Path) -> None:
    cfg, store = _sweep(tmp_path), str(tmp_path / "d3.sqlite")
    run = ["sweep", str(cfg), "--store", store, "--workers", "1"]
    assert _json([*run, "--json"])["computed"] == 2
    # the same design at --accuracy 0.1 is registered last: other keys under the same name
    assert _json([*run, "--accuracy", "0.1", "--json"])["computed"] == 2
    text = runner.invoke(app, ["sweep", str(cfg), "--store", store, "--dry-run"])
    assert text.exit_code == 0 and text.exception is None, text.output
    line = " ".join(text.stdout.split())
    assert "(2 distinct, 2 already stored, 0 to compute); nothing to compute" in line, line
    dry = _json(["sweep", str(cfg), "--store", store, "--dry-run", "--json"])
    assert (dry["stored"], dry["to_compute"]) == (2, 0)
    # at settings nothing was computed at, nothing is stored: the estimate is the probe's
    other = _json(["sweep", str(cfg), "--store", store, "--dry-run", "--json",
                   "--accuracy", "0.5"])
    assert (other["stored"], other["to_compute"]) == (0, 2)
    assert other["probe_cpu_per_simulated_second"] > 0
    # the real run finds what the dry run said
    again = _json([*run, "--json"])
    assert (again["stored_before"], again["computed"]) == (dry["stored"], dry["to_compute"])


def test_a_dry_run_of_a_grown_design_counts_the_points_already_stored(tmp_path: Path) -> None:
    store = str(tmp_path / "g.sqlite")
    _json(["sweep", str(_sweep(tmp_path)), "--store", store, "--workers", "1", "--json"])
    grown = _sweep(tmp_path, "[1.0, 1.3, 1.6]")  # the middle point (the sampled one) is new
    dry = _json(["sweep", str(grown), "--store", store, "--dry-run", "--json"])
    assert (dry["points"], dry["stored"], dry["to_compute"]) == (3, 2, 1)
    text = runner.invoke(app, ["sweep", str(grown), "--store", store, "--dry-run"])
    assert text.exit_code == 0, text.output
    assert "2 already stored, 1 to compute); " in " ".join(text.stdout.split())
    run = _json(["sweep", str(grown), "--store", store, "--workers", "1", "--json"])
    assert (run["stored_before"], run["computed"]) == (2, 1)


# ------------------------------------------------------------------ 2: the solver record


#: what two runs of one command may differ in: timing, and the counts of the output
#: evaluations a streamed run makes per chunk
_RUN_DEPENDENT = {"wall_time_s", "rhs_evaluations", "output_rhs_evaluations"}


def _settled(record: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in record.items() if k not in _RUN_DEPENDENT}


def test_every_format_carries_the_solver_record_and_the_error_estimate(tmp_path: Path) -> None:
    run = ["simulate", "--table-speed", "1", "--duration", "0.3", "--error-estimate",
           "--position-tolerance", "1e-9"]
    records = {}
    for ext in (".nc", ".mat", ".parquet", ".csv"):
        out = tmp_path / f"ee{ext}"
        result = runner.invoke(app, [*run, "--output", str(out)])
        assert result.exit_code == 0, result.output
        if ext == ".nc":
            with xr.open_dataset(out) as ds:
                records[ext] = json.loads(ds.attrs["solver"])
        elif ext == ".mat":
            mat = scipy.io.loadmat(out, simplify_cells=True)["feeddrive"]
            records[ext] = json.loads(mat["attrs"]["solver"])
        elif ext == ".parquet":
            import pandas as pd

            frame = pd.read_parquet(out)
            records[ext] = frame.attrs["solver"]
            assert frame.attrs["units"]["table_position"] == "mm" and len(frame) == 301
        else:
            import pandas as pd

            lines = out.read_text(encoding="utf-8").splitlines()
            assert lines[0].startswith("# feeddrive ") and lines[1].startswith("time [s],")
            assert lines[-1].startswith("# solver: {")
            records[ext] = json.loads(lines[-1].removeprefix("# solver: "))
            assert len(pd.read_csv(out, comment="#")) == 301  # the record is no row
    nc = records[".nc"]
    assert nc["position_tolerance"] == pytest.approx(1e-12)  # SI, in every format
    assert nc["error_estimate"]["kind"] == "shadow"
    assert nc["error_estimate"]["signals"]["table_position"]["unit"] == "m"
    for ext, record in records.items():
        assert _settled(record) == _settled(nc), ext


def test_a_streamed_csv_with_its_record_is_read_as_before(tmp_path: Path) -> None:
    """The readers behind ``analyze`` and ``fit`` skip the record as every ``#`` line."""
    from feeddrive.io.measured import read_position_trace

    out = tmp_path / "run.csv"
    result = runner.invoke(app, ["simulate", "--table-speed", "2", "--duration", "0.2",
                                 "--output", str(out)])
    assert result.exit_code == 0, result.output
    assert out.read_text(encoding="utf-8").splitlines()[-1].startswith("# solver: {")
    assert read_position_trace(out).time.size == 201
    analyzed = runner.invoke(app, ["analyze", str(out), "--json"])
    assert analyzed.exit_code == 0, analyzed.output


# ------------------------------------------------------------------ 3: the JSON's units


def test_the_json_solver_block_speaks_mm_and_mm_per_s_with_the_unit_in_the_key() -> None:
    data = _json(["simulate", "--table-speed", "1", "--duration", "0.3",
                  "--position-tolerance", "1e-9", "--speed-tolerance", "1e-6", "--json",
                  "--error-estimate"])
    solver = data["solver"]
    assert solver["position_tolerance_mm"] == pytest.approx(1e-9, rel=1e-12)
    assert solver["speed_tolerance_mm_s"] == pytest.approx(1e-6, rel=1e-12)
    assert solver["motor_position_tolerance_mm"] == pytest.approx(1e-9, rel=1e-12)
    assert solver["table_speed_scale_mm_s"] == pytest.approx(1.0)
    assert solver["current_tolerance_a"] > 0 and solver["accuracy"] == 1.0
    assert not {"position_tolerance", "speed_tolerance", "speed_scale",
                "table_speed_scale"} & set(solver)
    table = solver["error_estimate"]["signals"]["table_position"]
    assert table["unit"] == "mm" and table["absolute"] > 0


@pytest.mark.parametrize(("args", "table"), [
    (["--position-tolerance", "1e-9", "--speed-tolerance", "1e-6"],
     "table positions 1e-09 mm, speeds 1e-06 mm/s (as given, not scaled)"),
    (["--speed-tolerance", "1e-6"],
     "table positions 1e-10 mm (scaled to 1 mm/s), speeds 1e-06 mm/s (as given)"),
    ([], "table positions 1e-10 mm, speeds 1e-05 mm/s (scaled to 1 mm/s)"),
])
def test_the_integrator_line_calls_only_a_default_tolerance_scaled(args: list[str],
                                                                   table: str) -> None:
    result = runner.invoke(app, ["simulate", "--table-speed", "1", "--duration", "0.2", *args],
                           terminal_width=400)
    assert result.exit_code == 0, result.output
    line = next(ln for ln in result.stdout.splitlines() if ln.strip().startswith("integrator"))
    assert table in line, line


# ------------------------------------------------------------------ 4: --method's help


def _method_help() -> str:
    text = " ".join(runner.invoke(app, ["simulate", "--help"],
                                  terminal_width=400).stdout.split())
    start = text.index("--method <")
    # to the next option: "--name <type>" or a flag's "--name Help" (not "--rosenbrock,")
    end = re.compile(r" --[\w-]+ (?=[<A-Z])").search(text, start + 1)
    assert end is not None
    return text[start:end.start()]


def test_the_method_help_names_the_codes_default_rosenbrock_method() -> None:
    help_text = _method_help()
    default = opt.ROSENBROCKS[opt.DEFAULT_ROSENBROCK].label
    modal = help_text[help_text.index("modal ("):help_text.index("), dopri5")]
    assert default in modal, modal
    assert not [rb.label for name, rb in opt.ROSENBROCKS.items()
                if name != opt.DEFAULT_ROSENBROCK and rb.label in modal], modal
    assert help_text.rstrip(" .").endswith(f"else {opt.DEFAULT_METHOD}")


def test_the_method_help_follows_the_constants(monkeypatch: pytest.MonkeyPatch) -> None:
    from feeddrive.cli import simulate_cmd

    # what --help prints is the function's text …
    assert " ".join(simulate_cmd.method_help().split()) in _method_help()
    # … and the function reads the engine's constants
    monkeypatch.setattr(opt, "DEFAULT_ROSENBROCK", "rodas4")
    assert "RODAS4 by default" in simulate_cmd.method_help()
    monkeypatch.setattr(opt, "DEFAULT_ROSENBROCK", "rodas5p")
    assert "RODAS5P by default" in simulate_cmd.method_help()


# ------------------------------------------------------------------ 5: a machine's integrator


MACHINE = ["simulate", "--machine", "xy-table", "--turns", "0.05", "--accuracy", "0.1"]


def test_a_machine_run_states_its_integrator_settings() -> None:
    data = _json([*MACHINE, "--json"])
    solver = data["solver"]
    assert solver["accuracy"] == 0.1 and solver["rtol"] == pytest.approx(1e-7)
    scale = solver["table_speed_scale_mm_s"]  # the feed: 1000 mm/min
    assert scale == pytest.approx(1000 / 60)
    assert solver["position_tolerance_mm"] == pytest.approx(opt.POSITION_TIME * scale * 0.1)
    assert solver["steps"] > 0
    text = runner.invoke(app, MACHINE, terminal_width=400)
    assert text.exit_code == 0, text.output
    line = next(ln for ln in text.stdout.splitlines() if "integrator" in ln)
    assert re.search(r"rtol 1e-07, axes positions 1\.67e-10 mm, speeds 1\.67e-05 mm/s "
                     r"\(scaled to 16\.7 mm/s\).*accuracy 0\.1", line), line
    assert any(ln.strip().startswith(f"solver: {solver['method']}, ")
               for ln in text.stdout.splitlines())


# ------------------------------------------------------------------ the pieces


RECORD = {"method": "modal", "rtol": 1e-6, "position_tolerance": 1e-13,
          "speed_tolerance": 1e-8, "current_tolerance": 1e-6, "deflection_fraction": 1e-5,
          "motor_position_tolerance": 1e-13, "motor_speed_tolerance": 1e-8, "accuracy": 1.0,
          "speed_scale": 1e-3, "table_speed_scale": 1e-3, "current_scale": 1.0, "steps": 7,
          "rejected_steps": 1, "rhs_evaluations": 50, "wall_time_s": 0.01,
          "error_estimate": {"kind": "shadow", "signals": {
              "table_position": {"absolute": 2e-12, "relative": 1e-9, "unit": "m"},
              "table_speed": {"absolute": 3e-9, "relative": 1e-6, "unit": "m/s"},
              "screw_angle": {"absolute": 1e-10, "relative": 1e-10, "unit": "rad"}}}}


def _two_row_groups(path: Path) -> None:
    import pyarrow.parquet as pq

    from feeddrive.io.results import arrow_table

    writer = None
    for k in range(2):
        t = np.arange(3) + 3.0 * k
        table = arrow_table({"time": (t, "s", "time"), "table_position": (2 * t, "mm", "x")},
                            attrs={"drive": "cdfs"})
        if writer is None:
            writer = pq.ParquetWriter(path, table.schema)
        writer.write_table(table)
    assert writer is not None
    writer.close()


def test_the_record_joins_a_streamed_parquet_file_its_rows_and_units_kept(
        tmp_path: Path) -> None:
    import pandas as pd
    import pyarrow.parquet as pq

    from feeddrive.io.results import add_solver_record

    path = tmp_path / "run.parquet"
    _two_row_groups(path)
    assert add_solver_record(path, RECORD) == path
    assert pq.ParquetFile(path).num_row_groups == 2
    assert pq.read_schema(path).field("table_position").metadata[b"unit"] == b"mm"
    frame = pd.read_parquet(path)
    assert frame["table_position"].tolist() == [0.0, 2.0, 4.0, 6.0, 8.0, 10.0]
    assert frame.attrs["solver"] == RECORD and frame.attrs["drive"] == "cdfs"
    assert frame.attrs["units"]["table_position"] == "mm"
    assert not list(tmp_path.glob("*.partial*"))


def test_the_record_is_a_streamed_csvs_last_line(tmp_path: Path) -> None:
    from feeddrive.io.results import SOLVER_LINE, add_solver_record

    path = tmp_path / "run.csv"
    path.write_text("# feeddrive: a run\ntime [s],x [mm]\n0,1\n", encoding="utf-8")
    add_solver_record(path, RECORD)
    lines = path.read_text(encoding="utf-8").splitlines()
    assert lines[:3] == ["# feeddrive: a run", "time [s],x [mm]", "0,1"]
    assert json.loads(lines[3].removeprefix(SOLVER_LINE)) == RECORD


def test_a_whole_format_gets_no_record_added(tmp_path: Path) -> None:
    from feeddrive.io.results import add_solver_record

    with pytest.raises(ParameterError, match="written with it"):
        add_solver_record(tmp_path / "run.nc", RECORD)


def test_result_save_writes_the_record_as_the_csvs_last_line(tmp_path: Path) -> None:
    import pandas as pd

    from feeddrive.io.results import SOLVER_LINE

    run = fd.simulate(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4),
                      fd.ConstantSpeed(2e-3), 0.05)
    path = run.save(tmp_path / "run.csv")
    last = path.read_text(encoding="utf-8").splitlines()[-1]
    assert json.loads(last.removeprefix(SOLVER_LINE)) == run.solver_stats
    assert len(pd.read_csv(path, comment="#")) == run.time.size


def test_the_json_block_renames_and_converts_lengths_speeds_and_currents() -> None:
    from feeddrive.cli._solver_report import SOLVER_JSON_UNITS, solver_json

    out = solver_json(RECORD)
    assert out["position_tolerance_mm"] == pytest.approx(1e-10, rel=1e-12)
    assert out["speed_tolerance_mm_s"] == pytest.approx(1e-5, rel=1e-12)
    assert out["table_speed_scale_mm_s"] == pytest.approx(1.0)
    assert out["current_tolerance_a"] == 1e-6 and out["current_scale_a"] == 1.0
    assert not set(SOLVER_JSON_UNITS) & set(out)
    assert (out["rtol"], out["steps"], out["wall_time_s"]) == (1e-6, 7, 0.01)
    signals = out["error_estimate"]["signals"]
    assert signals["table_position"] == {"absolute": pytest.approx(2e-9), "relative": 1e-9,
                                         "unit": "mm"}
    assert signals["table_speed"]["unit"] == "mm/s" and signals["screw_angle"]["unit"] == "rad"
    assert RECORD["error_estimate"]["signals"]["table_position"]["unit"] == "m"  # not changed


@pytest.mark.parametrize(("changes", "text"), [
    ({}, "positions 1e-10 mm, speeds 1e-05 mm/s (scaled to 1 mm/s)"),
    ({"speed_tolerance": 1e-9, "motor_speed_tolerance": 1e-9},
     "positions 1e-10 mm (scaled to 1 mm/s), speeds 1e-06 mm/s (as given)"),
    ({"deflection_fraction": None, "position_tolerance": 1e-12,
      "motor_position_tolerance": 1e-12},
     "positions 1e-09 mm (as given), speeds 1e-05 mm/s (scaled to 1 mm/s)"),
])
def test_the_integrator_line_reads_which_tolerances_were_given_from_the_record(
        changes: dict[str, Any], text: str) -> None:
    from feeddrive.cli._solver_report import integrator_line

    assert text in integrator_line({**RECORD, **changes})


def test_the_dry_runs_text_takes_an_estimate_without_timing(monkeypatch, tmp_path) -> None:
    """Points left to compute with neither timed points nor a probe: the counts, no crash."""
    from feeddrive.sweep import executors

    def untimed(config: Any, store: Any, *, workers: int, **kw: Any) -> executors.Estimate:
        return executors.Estimate(points=2, distinct=2, stored=1, timed=0,
                                  seconds_per_point=0.0, workers=workers)

    monkeypatch.setattr(executors, "estimate", untimed)
    import feeddrive.sweep as sweep

    monkeypatch.setattr(sweep, "estimate", untimed)
    cfg = tmp_path / "sw.toml"
    cfg.write_text('name = "u"\ndrive = "cdfs"\n[quantity]\nkind = "linear-band"\n'
                   "[axes]\ntable_position = [300, 500]\n", encoding="utf-8")
    result = runner.invoke(app, ["sweep", str(cfg), "--dry-run", "--store",
                                 str(tmp_path / "u.sqlite")])
    assert result.exit_code == 0, result.output
    assert "(2 distinct, 1 already stored, 1 to compute); cost not estimated" in \
        " ".join(result.stdout.split())


_FULL_DISK = """
import resource, signal, sys
from pathlib import Path
from feeddrive.io.results import add_solver_record
path = Path(sys.argv[1])
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails (EFBIG)
size = path.stat().st_size
resource.setrlimit(resource.RLIMIT_FSIZE, (size + 10, size + 10))
try:
    add_solver_record(path, {"method": "modal", "note": "x" * 1000})
except OSError as err:
    print("refused", err.errno)
"""


def test_a_record_that_cannot_be_written_leaves_the_csv_as_it_was(tmp_path: Path) -> None:
    """A full disk (a file-size limit fails a write as one does): the append is cut back."""
    import subprocess
    import sys

    path = tmp_path / "run.csv"
    text = "# feeddrive: a run\ntime [s],x [mm]\n0,1\n"
    path.write_text(text, encoding="utf-8")
    proc = subprocess.run([sys.executable, "-c", _FULL_DISK, str(path)], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0 and proc.stdout.startswith("refused"), proc.stderr
    assert path.read_text(encoding="utf-8") == text
