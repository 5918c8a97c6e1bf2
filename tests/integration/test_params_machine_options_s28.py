"""`feeddrive params show/check --machine` with a drive's options (session 28): they were
silently ignored — `params check FILE --machine M` checked M only and said FILE was fine by
saying nothing about it, `params show --machine M --format json` printed TOML."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest
from cli_support import RUNNER, one_line_refusal

from feeddrive.cli import app
from feeddrive.machine import load_machine, machine_toml

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"




@pytest.mark.parametrize("extra", [["--preset", "wang2021"],
                                   ["--params", str(EXAMPLES / "gms_guide.toml")]])
def test_show_machine_refuses_a_drives_set(extra: list[str]) -> None:
    line = one_line_refusal(["params", "show", "--machine", "xy-table", *extra])
    assert extra[0] in line and "not with --machine" in line


def test_show_machine_as_json_is_the_toml_read() -> None:
    out = RUNNER.invoke(app, ["params", "show", "--machine", "xy-table", "--format", "json"])
    assert out.exit_code == 0, out.output
    assert json.loads(out.stdout) == tomllib.loads(machine_toml(load_machine("xy-table")))


def test_show_machine_refuses_an_unknown_format() -> None:
    line = one_line_refusal(["params", "show", "--machine", "xy-table", "--format", "yaml"])
    assert "--format" in line and "toml or json" in line


def test_check_refuses_a_file_beside_machine() -> None:
    line = one_line_refusal(["params", "check", str(EXAMPLES / "gms_guide.toml"),
                              "--machine", "xy-table"])
    assert line.startswith("error: FILE") and "not both" in line


def test_docs_say_so() -> None:
    text = (Path(__file__).resolve().parents[2] / "docs" / "machine.md").read_text("utf-8")
    assert "`params check` takes no parameter FILE" in text
    assert "params show --machine xy-table --format json" in text
