"""CSV readers for measured data (feeddrive.io.measured): units, columns, precise errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from feeddrive.io.measured import (
    MeasuredDataError,
    read_csv_table,
    read_position_trace,
    read_presliding_test,
    read_static_test,
    split_unit,
)


def write(tmp_path: Path, text: str, name: str = "data.csv") -> Path:
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


@pytest.mark.parametrize(
    ("header", "expected"),
    [("time [s]", ("time", "s")), ("table_position [mm]", ("table_position", "mm")),
     ("position", ("position", None)), (" force  [N] ", ("force", "N")),
     ('"speed [µm/s]"', ("speed", "µm/s"))],
)
def test_split_unit(header: str, expected: tuple[str, str | None]) -> None:
    assert split_unit(header) == expected


def test_position_trace_honours_bracketed_units(tmp_path: Path) -> None:
    rows = "\n".join(f"{1000 * i * 0.01:g},{i * 5.0:g}" for i in range(20))
    p = write(tmp_path, f"# interferometer export\ntime [ms],position [um]\n{rows}\n")
    tr = read_position_trace(p)
    assert tr.time[1] == pytest.approx(0.01)
    assert tr.position[1] == pytest.approx(5e-6)
    assert tr.command_speed is None


def test_position_trace_falls_back_to_table_position_and_reads_command(tmp_path: Path) -> None:
    # the simulator's CSV export style (feeddrive.io.results): units in brackets, engineering units
    rows = "\n".join(f"{i * 0.1:g},{i * 0.16:g},1.6,1.6" for i in range(20))
    p = write(tmp_path, "time [s],table_position [mm],table_speed [mm/s],"
                        f"table_speed_reference [mm/s]\n{rows}\n")
    tr = read_position_trace(p, speed_column="table_speed")
    assert tr.position_column == "table_position"
    assert tr.position[2] == pytest.approx(0.32e-3)
    assert tr.command_speed is not None and tr.command_speed[0] == pytest.approx(1.6e-3)
    assert tr.speed is not None and tr.speed[0] == pytest.approx(1.6e-3)


def test_semicolon_and_decimal_comma(tmp_path: Path) -> None:
    rows = "\n".join(f"{i};{i * 0.5}".replace(".", ",") for i in range(20))
    p = write(tmp_path, f"time;position\n{rows}\n")
    tr = read_position_trace(p, decimal=",")
    assert tr.position[3] == pytest.approx(1.5e-3)


def test_whitespace_separator_and_unit_options(tmp_path: Path) -> None:
    rows = "\n".join(f"{i}\t{i * 2}" for i in range(20))
    p = write(tmp_path, f"t\tx\n{rows}\n")
    tr = read_position_trace(p, time_column="t", position_column="x", time_unit="ms",
                             position_unit="nm")
    assert tr.time[1] == pytest.approx(1e-3)
    assert tr.position[1] == pytest.approx(2e-9)


def test_unit_option_contradicting_header_is_refused(tmp_path: Path) -> None:
    rows = "\n".join(f"{i},{i}" for i in range(20))
    p = write(tmp_path, f"time [s],position [mm]\n{rows}\n")
    with pytest.raises(MeasuredDataError, match=r"line 1: .*\[mm\].*'um'"):
        read_position_trace(p, position_unit="um")


def test_unknown_unit_is_refused(tmp_path: Path) -> None:
    rows = "\n".join(f"{i},{i}" for i in range(20))
    p = write(tmp_path, f"time [s],position [furlong]\n{rows}\n")
    with pytest.raises(ValueError, match="'furlong' is not a length unit"):
        read_position_trace(p)


def test_non_numeric_cell_names_line_and_column(tmp_path: Path) -> None:
    rows = [f"{i},{i}" for i in range(20)]
    rows[5] = "5,abc"
    p = write(tmp_path, "# comment\n\ntime,position\n" + "\n".join(rows) + "\n")
    with pytest.raises(MeasuredDataError, match=r"data.csv, line 9: column 'position': 'abc' is "
                                                r"not a number"):
        read_position_trace(p)


def test_empty_cell_and_nan(tmp_path: Path) -> None:
    rows = [f"{i},{i}" for i in range(20)]
    rows[2] = "2,"
    p = write(tmp_path, "time,position\n" + "\n".join(rows) + "\n")
    with pytest.raises(MeasuredDataError, match=r"line 4: column 'position': empty cell"):
        read_position_trace(p)
    rows[2] = "2,nan"
    p = write(tmp_path, "time,position\n" + "\n".join(rows) + "\n")
    with pytest.raises(MeasuredDataError, match=r"line 4: .*not a finite number"):
        read_position_trace(p)


def test_time_not_increasing_names_line(tmp_path: Path) -> None:
    rows = [f"{i},{i}" for i in range(20)]
    rows[7] = "5,7"
    p = write(tmp_path, "time,position\n" + "\n".join(rows) + "\n")
    with pytest.raises(MeasuredDataError, match=r"line 9: column 'time' does not increase"):
        read_position_trace(p)


def test_missing_column_lists_the_columns(tmp_path: Path) -> None:
    rows = "\n".join(f"{i},{i}" for i in range(20))
    p = write(tmp_path, f"time,pos\n{rows}\n")
    with pytest.raises(MeasuredDataError, match=r"no column 'position' or 'table_position'.*"
                                                r"'time', 'pos'"):
        read_position_trace(p)


def test_ragged_row_and_too_few_rows(tmp_path: Path) -> None:
    p = write(tmp_path, "time,position\n0,0\n1,1,1\n")
    with pytest.raises(MeasuredDataError, match=r"line 3: 3 cells, but the header"):
        read_csv_table(p)
    p = write(tmp_path, "time,position\n0,0\n1,1\n")
    with pytest.raises(MeasuredDataError, match=r"2 data rows"):
        read_position_trace(p)
    with pytest.raises(FileNotFoundError):
        read_csv_table(tmp_path / "missing.csv")


def test_static_test_from_force(tmp_path: Path) -> None:
    p = write(tmp_path, "speed [um/s],force [N]\n100,90\n-100,-88\n")
    data = read_static_test(p)
    np.testing.assert_allclose(data.speed, [1e-4, -1e-4])
    np.testing.assert_allclose(data.force, [90.0, -88.0])
    np.testing.assert_array_equal(data.lines, [2, 3])


def test_static_test_from_current(tmp_path: Path) -> None:
    p = write(tmp_path, "speed,current\n1.0,0.1\n-1.0,-0.1\n")
    with pytest.raises(MeasuredDataError, match="torque constant and the screw lead"):
        read_static_test(p)
    data = read_static_test(p, torque_constant=0.55, lead=0.005)
    h = 0.005 / (2 * np.pi)
    assert data.force[0] == pytest.approx(0.55 * 0.1 / h)  # F = K_t i / H, Wang2021 Eq. (8)
    assert data.speed[0] == pytest.approx(1e-3)  # mm/s by default
    assert data.force_from == "current × K_t / H"


def test_static_test_missing_force_and_current(tmp_path: Path) -> None:
    p = write(tmp_path, "speed,torque\n1.0,0.1\n")
    with pytest.raises(MeasuredDataError, match="no column 'force' or 'current'"):
        read_static_test(p)


def test_presliding_default_units(tmp_path: Path) -> None:
    rows = "\n".join(f"{i * 1e-3:g},{i:g},{i * 0.1:g}" for i in range(25))
    p = write(tmp_path, f"time,force,position\n{rows}\n")
    data = read_presliding_test(p)
    assert data.position[10] == pytest.approx(1e-6)  # µm by default
    assert data.force[10] == 10.0
