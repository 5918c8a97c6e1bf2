"""Issue 41 item 4: the explorer's margins (friction linearised: GM 1.34 dB, ζ 0.0101 at
1.5 mm/s) differed from `loops`' (frictionless by default: GM 3.02 dB, ζ 0.034) without saying
so, and `loops` did not list the poles its help promises.  Every title now says how friction
entered (:data:`feeddrive.analysis.linear.FRICTION_WORDS`)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.analysis.linear import FRICTION_WORDS, loop_analysis
from feeddrive.cli import app

runner = CliRunner()
JS = (Path(fd.__file__).parent / "explore" / "static" / "explore.js").read_text("utf-8")


@pytest.mark.parametrize("with_friction", [False, True])
def test_loops_says_how_friction_entered_and_lists_its_poles(with_friction: bool) -> None:
    flag = ["--with-friction"] if with_friction else []
    text = runner.invoke(app, ["loops", "--drive", "cdfs", *flag]).stdout
    data = json.loads(runner.invoke(app, ["loops", "--drive", "cdfs", "--json", *flag]).stdout)
    header = " ".join(text.split("\n  ")[0].split())
    assert FRICTION_WORDS[not with_friction] in header
    assert data["friction"] == FRICTION_WORDS[not with_friction]
    # one line per pole of the JSON (each complex pair once)
    lines = [ln for ln in text.splitlines() if re.match(r"\s{4}(oscillatory|real|rigid-body)",
                                                        ln)]
    assert len(lines) == len(data["poles"]) >= 4
    assert f"poles ({len(data['poles'])}," in text
    d = data["least_damped_mode"]
    assert f"{d['frequency_hz']:10.4g} Hz  ζ = {d['damping_ratio']:.4g}" in lines[0]
    # the numbers the issue saw: ζ 0.034 without friction, 0.0101 with it (1.5 mm/s)
    assert round(d["damping_ratio"], 4) == (0.0101 if with_friction else 0.0338)


def test_the_explorer_and_the_plots_name_how_friction_entered() -> None:
    from feeddrive.explore.compute import run_linear
    from feeddrive.explore.settings import check
    from feeddrive.plots.linear import _bode

    res = run_linear(check({"table_speed": "1.5"}), lambda *args: None)
    assert res["friction"] == FRICTION_WORDS[False]  # the explorer linearises with friction
    # the page puts it in the poles' title, the Bode plot's title and the facts line
    assert "loop poles at ${fmt(res.table_speed_mm_s)} mm/s, ${res.friction}" in JS
    assert "loop gains L(jω), ${friction}" in JS and "renderBode(res.bode || [], res.friction)" \
        in JS
    assert '"stable"}; ${res.friction} ' in JS
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    for frictionless in (True, False):
        fig = _bode(loop_analysis(system, 1.5e-3, frictionless=frictionless, points=40))
        assert FRICTION_WORDS[frictionless] in fig.texts[0].get_text()
