"""docs/explore.md's margins of the CDFS at 1.5 mm/s are `feeddrive loops`' (the numbers had
stayed at 3.02 / 1.34 dB, read on the grid before the crossings were located by bisection,
docs/linear.md item 6; the command gives 2.59 / 0.84 dB)."""

from __future__ import annotations

import re
from pathlib import Path

from typer.testing import CliRunner

from feeddrive.cli import app

DOC = Path(__file__).parents[2] / "docs" / "explore.md"


def _loops(*extra: str) -> tuple[float, float]:
    result = CliRunner().invoke(app, ["loops", "--drive", "cdfs", "--table-speed", "1.5",
                                      *extra])
    assert result.exit_code == 0, result.output
    zeta = float(re.search(r"least-damped mode [\d.]+ Hz, ζ = ([\d.]+)", result.output)[1])
    margin = float(re.search(r"screw position loop .*gain margin\s+([\d.]+) dB",
                             result.output)[1])
    assert re.search(r"screw velocity loop .*gain margin\s+∞ dB", result.output)
    return margin, zeta


def test_explore_page_states_the_commands_margins() -> None:
    text = " ".join(DOC.read_text(encoding="utf-8").split())
    m = re.search(r"position-loop gain margin ([\d.]+) dB and ζ ([\d.]+) without friction, "
                  r"([\d.]+) dB and ζ ([\d.]+) with", text)
    assert m is not None, "the margins sentence is gone from docs/explore.md"
    for (margin, zeta), (doc_margin, doc_zeta) in (
            (_loops(), (m[1], m[2])), (_loops("--with-friction"), (m[3], m[4]))):
        assert f"{margin:.2f}" == doc_margin
        assert f"{zeta:.3g}" == doc_zeta
