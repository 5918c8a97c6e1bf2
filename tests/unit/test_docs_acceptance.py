"""docs/acceptance-tests.md against the code it describes (issue 37 item 5): every quantity,
JSON key, column and option it names exists, and the refusals it quotes are the CLI's."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from feeddrive.analysis.circular import circular_test
from feeddrive.analysis.positioning import PositioningTest
from feeddrive.cli import app
from feeddrive.io.acceptance import POSITIONING_COLUMNS, X_COLUMNS, Y_COLUMNS

DOC = (Path(__file__).resolve().parents[2] / "docs" / "acceptance-tests.md").read_text(
    encoding="utf-8")
FLAT = " ".join(DOC.split())


def test_every_iso_230_2_quantity_has_its_row() -> None:
    rows = {r[2].strip(): r for r in re.findall(r"^\| (2\.\d+) \| ([^|]+) \| ([^|]+) \|", DOC,
                                                 flags=re.M)}
    numbers = [float(r[0]) for r in rows.values()]
    assert numbers == sorted(numbers) and len(numbers) == 15  # 2.10 … 2.24
    for symbol, _label in PositioningTest.AXIS_QUANTITIES.values():
        assert any(symbol in key.replace(" ", "").split(",") for key in rows), symbol


def test_every_json_key_of_the_circular_test_is_named() -> None:
    a = np.linspace(0.0, 2 * np.pi, 721)
    keys = circular_test(a, 0.05 * np.cos(a), 0.05 * np.sin(a), radius=0.05,
                         centre=(0.0, 0.0)).to_dict()
    for key in keys:
        assert f"`{key}`" in DOC, key


def test_every_json_key_of_the_lead_in_is_named() -> None:
    from feeddrive.analysis.circular_run import LeadIn

    for key in LeadIn(arc=1.0, rule_arc=1.0, given=False).to_dict():
        assert f"`{key}`" in DOC, key


def test_columns_and_options_named_exist() -> None:
    for name in (*X_COLUMNS, *Y_COLUMNS):
        assert f"`{name}`" in DOC
    assert ",".join(POSITIONING_COLUMNS) in DOC
    runner = CliRunner()
    circular, positioning = DOC.split("## ISO 230-2 positioning test")
    on_record, on_machine = circular.split("### `feeddrive circular`")
    sections = {"analyze": on_record, "circular": on_machine,
                "positioning": positioning.split("### `feeddrive positioning`")[1]}
    for command, section in sections.items():
        shown = runner.invoke(app, [command, "--help"], env={"COLUMNS": "200"}).stdout
        for option in set(re.findall(r"`(--[a-z][a-z-]*)", section)):
            if (command, option) in (("positioning", "--positioning"),
                                     ("circular", "--circular"), ("circular", "--centre")):
                continue
            assert option in shown, (command, option)


@pytest.mark.parametrize(("args", "quoted"), [
    (["positioning", "--targets", "100,110", "--cycles", "4"],
     "error: --cycles = 4: expected at least 5 approaches per target and direction "
     "(ISO 230-2)"),
    (["positioning", "--targets", "100,900"],
     "error: --targets = '100,900': the test reaches 98 … 902 mm (targets ∓ the overshoot); "
     "expected within the travel 0 … 800 mm (screw.length)"),
    (["circular", "--radius", "500"],
     "error: --radius = 500.0: axis x would run -100 … 900 mm about its centre 400 mm; "
     "expected within its travel 0 … 800 mm (x.screw.length)"),
])
def test_quoted_refusals_are_the_cli_s(args: list[str], quoted: str) -> None:
    assert quoted in FLAT
    r = CliRunner().invoke(app, args, env={"COLUMNS": "200"})
    assert r.exit_code == 2 and " ".join(r.stderr.split()) == quoted
