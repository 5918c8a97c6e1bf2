"""`feeddrive loops`: rigid-body poles listed as such, the plot kinds, the checked plot file
(issue 23, items 2 and 3)."""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib.image as mpimg
import pytest
from typer.testing import CliRunner

from feeddrive.cli import app

runner = CliRunner()


def test_ddfs_with_friction_lists_its_rigid_body_pole_without_a_damping_ratio() -> None:
    """Issue 23 acceptance: `loops --drive ddfs --with-friction --json`."""
    res = runner.invoke(app, ["loops", "--drive", "ddfs", "--with-friction", "--nut-speed",
                              "16", "--json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    rigid = [p for p in data["poles"] if p["kind"] == "rigid-body"]
    assert rigid and all("damping_ratio" not in p for p in rigid)
    assert all(p["damping_ratio"] >= 0 for p in data["poles"] if p["kind"] != "rigid-body")
    assert "rigid-body" in data["pole_rule"]
    text = runner.invoke(app, ["loops", "--drive", "ddfs", "--with-friction", "--nut-speed",
                               "16"])
    assert "1 rigid-body pole (a free motion no loop holds; no damping ratio)" in text.stdout


@pytest.mark.parametrize("kind", ["bode", "nyquist", "step"])
def test_each_plot_kind_writes_an_image(tmp_path: Path, kind: str) -> None:
    out = tmp_path / f"{kind}.png"
    res = runner.invoke(app, ["loops", "--plot", str(out), "--plot-kind", kind, "--json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert data["plot_kind"] == kind and Path(data["plot"]) == out
    img = mpimg.imread(out)
    assert img.shape[0] > 500 and img.shape[1] > 700
    assert img[..., :3].std() > 0.05  # something is drawn, not a blank page


def test_the_plot_destination_and_kind_are_checked_before_the_work(tmp_path: Path) -> None:
    existing = tmp_path / "b.png"
    existing.write_bytes(b"x")
    for args, needle in (
            (["--plot", str(existing)], "exists; pass --force"),
            (["--plot", str(tmp_path / "no" / "b.png")], "--plot"),
            (["--plot", str(tmp_path / "b.txt")], "expected a .png, .pdf or .svg"),
            (["--plot-kind", "bodee"], "expected bode, nyquist, step")):
        res = runner.invoke(app, ["loops", *args])
        assert res.exit_code == 2, res.output
        lines = res.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("error: ") and needle in lines[0]
    assert existing.read_bytes() == b"x"


def test_a_set_without_steady_state_is_linearised_averaged_with_a_stated_warning() -> None:
    """wang2021-ripple has torque ripple: `loops` and `stability` say they used the
    averaged model (issue 23 item 4)."""
    for args in (["loops", "--preset", "wang2021-ripple", "--json"],
                 ["stability", "--preset", "wang2021-ripple", "--points", "5", "--json"]):
        res = runner.invoke(app, args)
        assert res.exit_code == 0, res.output
        notes = json.loads(res.stdout)["notes"]
        assert len(notes) == 1 and "averaged model" in notes[0], notes
    text = runner.invoke(app, ["loops", "--preset", "wang2021-ripple"]).stdout
    assert "warning: screw-motor torque ripple" in text
