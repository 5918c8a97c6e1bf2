"""Output destinations are checked before any work (feeddrive.io.outputs): issue 13, items 3
and 8 (and issue 12, item 8).

Guards: ``identify static victim.csv --out victim.csv`` replaced the measured data; an output
that is a folder, under a file, or on a read-only mount ended in a traceback after the work.
The tests run as any user: a read-only place that even root cannot write is a new name
under /proc.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from feeddrive.io.outputs import OutputError, check_output_dir, check_output_file, shown


def test_a_new_file_in_an_existing_folder_is_accepted(tmp_path: Path) -> None:
    p = check_output_file(tmp_path / "run.csv", option="--output")
    assert p == tmp_path / "run.csv"
    assert not p.exists()  # the write probe leaves nothing behind


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda d: d, "is a folder"),
        (lambda d: d / "data.csv" / "out.csv", r"data.csv is a file, not a folder"),
        (lambda d: d / "data.csv" / "deeper" / "out.csv", r"data.csv is a file, not a folder"),
        (lambda d: d / "missing" / "out.csv", r"folder .*missing does not exist"),
        (lambda d: Path("/proc/feeddrive-test-output.csv"), "cannot write here"),
    ],
    ids=["folder", "under-a-file", "under-a-file-deeper", "missing-folder", "read-only"],
)
def test_unusable_destinations_are_refused_with_the_path(tmp_path: Path, make, match) -> None:
    (tmp_path / "data.csv").write_text("time,position\n", encoding="utf-8")
    target = make(tmp_path)
    with pytest.raises(OutputError, match=match) as err:
        check_output_file(target, option="--out")
    assert str(err.value).startswith("--out ")
    assert "\n" not in str(err.value)
    assert not (tmp_path / "missing").exists()  # never created silently


def test_an_input_is_never_overwritten_even_with_force(tmp_path: Path) -> None:
    data = tmp_path / "victim.csv"
    data.write_text("speed,force\n1,2\n", encoding="utf-8")
    for force in (False, True):
        with pytest.raises(OutputError, match="is an input of this command"):
            check_output_file(data, option="--out", inputs=[str(data)], force=force)
        # the same file by another spelling
        with pytest.raises(OutputError, match="is an input"):
            check_output_file(tmp_path / "." / "victim.csv", option="--out",
                              inputs=[str(data)], force=force)
    assert data.read_text(encoding="utf-8") == "speed,force\n1,2\n"


def test_an_existing_output_needs_force(tmp_path: Path) -> None:
    old = tmp_path / "fragment.toml"
    old.write_text("# mine\n", encoding="utf-8")
    with pytest.raises(OutputError, match="exists; pass --force"):
        check_output_file(old, option="--out")
    assert check_output_file(old, option="--out", force=True) == old
    assert old.read_text(encoding="utf-8") == "# mine\n"  # the probe does not truncate


def test_output_folder_rules(tmp_path: Path) -> None:
    f = tmp_path / "report.txt"
    f.write_text("x", encoding="utf-8")
    with pytest.raises(OutputError, match="is a file; expected a folder"):
        check_output_dir(f, option="--out")
    with pytest.raises(OutputError, match="is a file, not a folder"):
        check_output_dir(f / "out", option="--out")
    with pytest.raises(OutputError, match="does not exist"):
        check_output_dir(tmp_path / "a" / "b", option="--out")
    with pytest.raises(OutputError, match="cannot write here"):
        check_output_dir("/proc/feeddrive-test-out", option="--out")
    assert check_output_dir(tmp_path / "new", option="--out") == tmp_path / "new"
    assert check_output_dir(tmp_path, option="--out") == tmp_path


def test_names_with_control_characters_are_shown_on_one_line(tmp_path: Path) -> None:
    assert shown("a\nb.csv") == "a\\nb.csv"
    with pytest.raises(OutputError) as err:
        check_output_file(tmp_path / "x\ny" / "out.csv", option="--out")
    assert "\n" not in str(err.value) and "x\\ny" in str(err.value)



def test_pyarrow_is_an_extra_that_the_test_extra_includes() -> None:
    import tomllib

    project = tomllib.loads((Path(__file__).parents[2] / "pyproject.toml").read_text())[
        "project"]
    assert not any(d.startswith("pyarrow") for d in project["dependencies"])
    assert any(d.startswith("pyarrow") for d in project["optional-dependencies"]["parquet"])
    assert any(d.startswith("pyarrow") for d in project["optional-dependencies"]["test"])
