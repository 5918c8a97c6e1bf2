"""Reading the records of `fit` and `validate` (an outside check, 2026-12-07): a European CSV
(`--decimal ,`, `--sep`, `--time-unit`, one definition for both commands), a `.mat` time in
ms (`--map time=t_ms[ms]`, refused without a unit when its steps are exactly 1), the fit's
first stage holding one sample, and the CSV reader's messages for Excel's `sep=;` line, a
UTF-16 file and a Windows-1252 `µ`."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import scipy.io as sio

import feeddrive as fd
from feeddrive.analysis.fit import Experiment, fit_drive, read_experiment
from feeddrive.analysis.rig_record import parse_map, read_rig_record
from feeddrive.io.measured import MeasuredDataError, read_csv_table, read_position_trace
from feeddrive.parameters import ParameterError

N = 201  # samples of the records below: 1 kHz, 0.2 s


def _columns() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(N) * 1e-3  # [s]
    v = np.clip(t / 0.05, 0.0, 1.0) * 1.0  # [mm/s]
    x = np.cumsum(v) * 1e-3  # [mm]
    return t, x, v


def _csv(path: Path, *, sep: str = ",", decimal: str = ".", first: str = "",
         time_header: str = "time [s]", time_scale: float = 1.0,
         encoding: str = "utf-8", position_unit: str = "mm") -> Path:
    t, x, v = _columns()
    rows = [f"{time_header}{sep}table_position [{position_unit}]{sep}"
            "table_speed_reference [mm/s]"]
    for a, b, c in zip(t * time_scale, x, v, strict=True):
        rows.append(sep.join(repr(float(z)).replace(".", decimal) for z in (a, b, c)))
    path.write_bytes((first + "\n".join(rows) + "\n").encode(encoding))
    return path


# ---------------------------------------------------------------- finding 1: --decimal ,


def test_a_decimal_comma_cell_says_to_give_the_decimal_option(tmp_path: Path) -> None:
    """It said only "line 2: column 'time': '0,0' is not a number"."""
    path = _csv(tmp_path / "euro.csv", sep=";", decimal=",")
    with pytest.raises(MeasuredDataError) as err:
        read_position_trace(path)
    assert re.match(r"euro\.csv, line 2: column 'time': '0,0' is not a number; a decimal "
                    r"comma: read the file with --decimal ,", str(err.value)), str(err.value)
    with pytest.raises(MeasuredDataError) as plain:  # a cell that is no number either way
        bad = tmp_path / "bad.csv"
        bad.write_text("time;position\n0.0;abc\n", encoding="utf-8")
        read_csv_table(bad).numbers("position")
    assert "decimal" not in str(plain.value)


def test_read_experiment_takes_the_separator_decimal_mark_and_time_unit(tmp_path: Path) -> None:
    """`read_experiment` had no sep, decimal or time_unit: a European CSV could not be fitted
    (`fit --decimal ,` was "No such option")."""
    plain = read_experiment(_csv(tmp_path / "base.csv"))
    euro = read_experiment(_csv(tmp_path / "euro.csv", sep=";", decimal=","), sep=";",
                           decimal=",")
    ms = read_experiment(_csv(tmp_path / "ms.csv", time_header="time", time_scale=1e3),
                         time_unit="ms")
    for other in (euro, ms):
        np.testing.assert_allclose(other.time, plain.time, rtol=0, atol=1e-15)
        np.testing.assert_array_equal(other.signals["table_position"],
                                      plain.signals["table_position"])
        np.testing.assert_allclose(other.table_speed, plain.table_speed, rtol=1e-12, atol=0)


def test_fit_and_validate_read_csv_traces_with_the_reading_options(tmp_path: Path) -> None:
    """The commands' records are read with --sep/--decimal/--time-unit (one definition for
    both); with --map (a .mat record, no text) they are refused, naming the option."""
    from feeddrive.cli import fit_cmd

    path = _csv(tmp_path / "euro.csv", sep=";", decimal=",")
    params = fd.preset("wang2021")
    experiments, _ = fit_cmd._read_traces([str(path)], params, "cdfs", 0.4, None, None, None,
                                          None, True, None, fit_cmd.CsvReading(";", ",", None))
    assert experiments[0].time.size == N
    with pytest.raises(ParameterError) as err:
        fit_cmd._read_traces([str(path)], params, "cdfs", 0.4, None, None, None,
                             ["time=t position=x reference=r"], True, None,
                             fit_cmd.CsvReading(None, ",", None))
    assert err.value.field == "--decimal"
    assert re.match(r"--decimal = ',': applies to CSV traces, not to --map \(\.mat\) records; "
                    r"give a variable's unit in the map instead, e\.g\. time=t_ms\[ms\]",
                    str(err.value)), str(err.value)
    import inspect

    import typer

    from feeddrive.cli import _common, analyze_cmd, app, identify_cmd

    group = typer.main.get_command(app)
    for name, function in (("fit", fit_cmd.fit_command), ("validate", fit_cmd.validate_command)):
        command = group.commands[name]  # type: ignore[attr-defined]
        opts = {o for p in command.params for o in p.opts}
        assert {"--sep", "--decimal", "--time-unit"} <= opts, name
        annotations = {k: v.annotation for k, v in
                       inspect.signature(function, eval_str=True).parameters.items()}
        assert (annotations["sep"], annotations["decimal"], annotations["time_unit"]) == \
            (_common.SepOption, _common.DecimalOption, fit_cmd.FitTimeUnitOption), name
    # one definition of --sep and --decimal for every reader of a record
    for function in (analyze_cmd.analyze_command, identify_cmd.static_command,
                     identify_cmd.dynamic_command):
        annotations = {k: v.annotation for k, v in
                       inspect.signature(function, eval_str=True).parameters.items()}
        assert (annotations["sep"], annotations["decimal"]) == \
            (_common.SepOption, _common.DecimalOption), function.__name__


# ---------------------------------------------------------------- finding 2: units in --map


def _mat(path: Path, *, time_scale: float = 1.0, length_scale: float = 1.0) -> Path:
    t, x, v = _columns()
    rng = np.random.default_rng(0)
    qm = x * 1e-3 + 1e-8 * rng.standard_normal(N)  # [m]
    qg = x * 1e-3  # [m]
    cur = 0.1 + 1e-3 * rng.standard_normal(N)  # [A]
    sio.savemat(path, {"t": (t * time_scale)[:, None], "qm": (qm * length_scale)[:, None],
                       "qg": (qg * length_scale)[:, None], "cur": cur[:, None]})
    return path


def test_map_units_convert_a_time_in_ms_and_positions_in_mm(tmp_path: Path) -> None:
    """`time=t[ms] position=qm[mm] reference=qg[mm]` read as the SI record; before, a unit in
    the map was no variable of the file."""
    params = fd.preset("wang2021")
    si = read_rig_record(_mat(tmp_path / "si.mat"),
                         parse_map(["time=t position=qm reference=qg current=cur"]), params)
    scaled = read_rig_record(_mat(tmp_path / "mm.mat", time_scale=1e3, length_scale=1e3),
                             parse_map(["time=t[ms] position=qm[mm] reference=qg[mm] "
                                        "current=cur"]), params)
    np.testing.assert_allclose(scaled.experiment.time, si.experiment.time, rtol=1e-12,
                               atol=1e-15)
    np.testing.assert_allclose(scaled.experiment.signals["table_position"],
                               si.experiment.signals["table_position"], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(scaled.experiment.table_speed, si.experiment.table_speed,
                               rtol=1e-9, atol=1e-12)
    # the SI units taken where none is given are stated
    assert any("no unit in the map for current cur [A]: read in SI" in n
               for n in scaled.notes)


def test_a_mat_time_in_ms_without_a_unit_is_refused_with_its_real_count(tmp_path: Path) -> None:
    """A 1-kHz record with its time in ms was read as a 201-s record: the fit then said
    "time: expected at least 2 sample times [s]; it has 1" of a record of 2001 samples."""
    path = _mat(tmp_path / "ms.mat", time_scale=1e3)
    with pytest.raises(ParameterError) as err:
        read_rig_record(path, parse_map(["time=t position=qm reference=qg current=cur"]),
                        fd.preset("wang2021"))
    assert err.value.field == "--map time=t"
    assert re.match(rf".*ms\.mat: --map time=t: expected sample times in seconds \[s\]: {N} "
                    r"samples, 0 … 200; steps of exactly 1 are those of a time in milliseconds: "
                    r"give its unit, time=t\[ms\]", str(err.value)), str(err.value)
    # stated in seconds, it is read as seconds
    rec = read_rig_record(path, parse_map(["time=t[s] position=qm reference=qg current=cur"]),
                          fd.preset("wang2021"))
    assert rec.experiment.time[-1] == 200.0


@pytest.mark.parametrize("item, field, message", [
    ("time=t[kg]", "--map time", r"expected a unit of time \[s\] in brackets after the "
     r"variable, one of s, ms"),
    ("position=qm[ms]", "--map position", r"expected a unit of length \[m\] in brackets"),
    ("time=t[ms", "--map time", r"expected VARIABLE or VARIABLE\[UNIT\], e\.g\. t_ms\[ms\] "
     r"\[s\]"),
])
def test_a_bad_unit_in_the_map_is_refused_naming_the_role(item: str, field: str,
                                                         message: str) -> None:
    roles = {"time": "time=t", "position": "position=qm", "reference": "reference=qg",
             "current": "current=cur"}
    roles[item.split("=")[0]] = item
    with pytest.raises(ParameterError) as err:
        parse_map([" ".join(roles.values())])
    assert err.value.field == field
    assert re.match(rf"{re.escape(field)} = '[^']*': {message}", str(err.value)), \
        str(err.value)


def test_a_csv_time_in_ms_without_a_unit_is_refused(tmp_path: Path) -> None:
    path = _csv(tmp_path / "ms.csv", time_header="time", time_scale=1e3)
    with pytest.raises(ParameterError) as err:
        read_experiment(path)
    assert err.value.field == "time"
    assert re.match(r"ms\.csv: time: expected sample times in seconds \[s\] \(the header gives "
                    r"no unit, nor --time-unit\): 201 samples, 0 … 200; steps of exactly 1 are "
                    r"those of a time in milliseconds: give its unit, --time-unit ms",
                    str(err.value)), str(err.value)


def test_a_record_with_one_sample_in_the_first_stage_is_refused_with_its_real_count(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """fit_drive cut the record to its first 0.5 s and refused the cut one: "it has 1"."""
    import feeddrive.engine.simulate as sim

    def refuse(*a: object, **k: object) -> None:
        raise AssertionError("a simulation ran")

    monkeypatch.setattr(sim, "simulate", refuse)
    t = np.arange(N, dtype=float)  # 1-s steps: a time in ms read as seconds
    exp = Experiment(source="ms.mat", time=t, signals={"table_position": 1e-6 * t ** 1.5},
                     reference_time=t, table_speed=np.full(N, 1e-3),
                     noise={"table_position": 1e-8})
    with pytest.raises(ParameterError) as err:
        fit_drive(fd.preset("wang2021"), [exp], ["controller.velocity_integral_gain"],
                  profile=False)
    assert err.value.field == "time"
    assert re.match(rf"ms\.mat: time: expected at least 2 samples in the fit's first stage, "
                    rf"the record's first 0\.5 s \[s\]; it has 1 of its {N} samples \(median "
                    r"step 1 s\); steps of exactly 1 are those of a time in milliseconds",
                    str(err.value)), str(err.value)


# ---------------------------------------------------------------- finding 3: messages


def test_excels_sep_line_is_honoured(tmp_path: Path) -> None:
    """It gave "line 2: 3 cells, but the header (line 1) has 2 columns"."""
    path = _csv(tmp_path / "excel.csv", sep=";", decimal=",", first="sep=;\n")
    trace = read_position_trace(path, decimal=",")
    plain = read_position_trace(_csv(tmp_path / "base.csv"))
    np.testing.assert_array_equal(trace.time, plain.time)
    np.testing.assert_array_equal(trace.position, plain.position)
    assert trace.lines[0] == 3
    with pytest.raises(MeasuredDataError) as err:
        read_position_trace(path, sep=",", decimal=".")
    assert re.match(r"excel\.csv, line 1: the file names its separator \(Excel's 'sep=;'\) and "
                    r"the separator option gives ','", str(err.value)), str(err.value)


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le", "utf-16-be"])
def test_a_utf16_file_is_named_as_such(tmp_path: Path, encoding: str) -> None:
    """It said "is a binary file (it holds NUL bytes)"."""
    path = _csv(tmp_path / "u16.csv", encoding=encoding)
    with pytest.raises(MeasuredDataError) as err:
        read_position_trace(path)
    assert re.match(r"u16\.csv: looks like UTF-16 text .*not UTF-8; save it as UTF-8",
                    str(err.value)), str(err.value)


def test_a_windows_1252_micro_sign_says_the_file_is_not_utf8(tmp_path: Path) -> None:
    """It said "unit '\ufffdm' is not a length unit" alone."""
    path = _csv(tmp_path / "cp.csv", encoding="cp1252", position_unit="µm")
    with pytest.raises(ValueError) as err:
        read_position_trace(path)
    assert re.match(r"cp\.csv: column 'table_position': unit '\ufffdm' is not a length unit; "
                    r"expected one of m, mm, um, µm, μm, nm; the file is not UTF-8 text",
                    str(err.value)), str(err.value)
