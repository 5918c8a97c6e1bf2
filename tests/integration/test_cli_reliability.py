"""Issue 13 through the CLI: the warnings, refusals and exit status the library decides.

(The library side is tested in tests/unit/test_identifiability.py, test_outputs.py and
test_unstable.py; these invoke the CLI, so they live here, outside the unit tests that the
minimum-versions job runs.)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.cli import app
from feeddrive.model.friction.stribeck import steady_friction
from feeddrive.parameters import save

SCREW = fd.preset("wang2021").friction.screw


def static_data(speeds: np.ndarray, noise: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    v = np.concatenate([speeds, -speeds])
    f = steady_friction(v, SCREW)
    return v, f * (1 + noise * np.random.default_rng(seed).standard_normal(v.size))


def test_cli_warns_about_unidentifiable_values(tmp_path: Path) -> None:
    v, f = static_data(np.geomspace(0.05, 50.0, 5) * 1e-3, 0.05)
    path = tmp_path / "five.csv"
    path.write_text("speed [mm/s],force [N]\n" + "\n".join(
        f"{a * 1e3:.9g},{b:.9g}" for a, b in zip(v, f, strict=True)) + "\n", encoding="utf-8")
    r = CliRunner().invoke(app, ["identify", "static", str(path)])
    assert r.exit_code == 0, r.output
    assert "not identifiable from these data" in r.stderr
    assert "(not identifiable)" in r.stdout


def test_parquet_without_pyarrow_is_refused_before_simulating(monkeypatch,
                                                              tmp_path: Path) -> None:
    """pyarrow is the optional extra [parquet] (issue 13, item 11)."""
    import importlib.util

    from typer.testing import CliRunner

    from feeddrive.cli import app
    from feeddrive.io.results import PARQUET_HINT, check_format

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "pyarrow" else real(name, *a))
    with pytest.raises(ValueError, match=r"pip install 'feeddrive\[parquet\]'"):
        check_format("run.parquet")
    r = CliRunner().invoke(app, ["simulate", "--table-speed", "1", "--output",
                                 str(tmp_path / "run.parquet")])
    assert r.exit_code == 2 and PARQUET_HINT in r.stderr
    assert "solver" not in r.stdout  # refused before the run


def test_heavy_table_diverges_and_the_cli_says_unstable(tmp_path) -> None:
    params = fd.preset("wang2021").replace_path("table.mass", 1e5)  # 100 t
    r = fd.simulate(fd.DriveSystem(params, "cdfs", 0.4), fd.ConstantSpeed(1e-3), 3.0)
    summary = r.summary()
    assert summary["verdict"] == "unstable"
    assert any("diverges" in w for w in summary["warnings"])
    path = tmp_path / "heavy.toml"
    save(params, path)
    result = CliRunner().invoke(app, ["simulate", "--table-speed", "1", "--duration", "3",
                                      "--params", str(path)])
    assert result.exit_code == 3, result.output  # README "Exit status"
    assert "unstable" in result.stdout
    assert "warning: unstable: the loop diverges" in result.stderr


def test_every_documented_writer_has_force_in_its_help() -> None:
    """docs/outputs.md names the options that write; each command offers --force."""
    import re

    from typer.testing import CliRunner

    from feeddrive.cli import app

    doc = (Path(__file__).resolve().parents[2] / "docs" / "outputs.md").read_text(encoding="utf-8")
    listed = re.search(r"Options that write: (.*?); each has", doc, re.S)
    assert listed is not None
    commands = {re.sub(r"\s+", " ", c).split(" --")[0]
                for c in re.findall(r"`([^`]+)`", listed.group(1))}
    assert {"simulate", "analyze", "identify static|dynamic", "identify merge", "calibrate",
            "friction"} <= commands
    for command in commands:
        for variant in command.split(" ")[-1].split("|"):
            args = [*command.split(" ")[:-1], variant] if "|" in command else command.split()
            r = CliRunner().invoke(app, [*args, "--help"], env={"COLUMNS": "200"})
            assert r.exit_code == 0 and "--force" in r.stdout, (args, r.stdout[-500:])
