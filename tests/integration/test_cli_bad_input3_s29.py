"""The leftovers of session 29's bad-input sweeps on the command line and in sweep stores:

5. a critical-speed ``[quantity]`` with ``linear = false`` took ``linear_points``, which
   nothing reads without the linear band, and hashed it into every point's store key; it is
   refused there (the kind's reads depend on ``linear``: ``quantities.reads``), and kept in
   the key only when read — the default settings' key is unchanged, so a store written
   before is still found.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.cli import app
from feeddrive.io.json_store import store_key
from feeddrive.parameters import ParameterError
from feeddrive.sweep import QuantitySettings

runner = CliRunner()

#: the default critical-speed settings as every store written so far keys them [SI]
DEFAULT_CRITICAL = {"kind": "critical-speed", "start": "rest", "low": 2e-05, "high": 0.00302,
                    "coarse_step": 0.0002, "resolution": 1e-05, "initial_duration": 12.0,
                    "max_duration": 240.0, "linear": True, "linear_points": 40}


def test_a_sweep_refuses_linear_points_without_the_linear_band(tmp_path: Path) -> None:
    cfg = tmp_path / "cs.toml"
    cfg.write_text('name = "cs"\ndrive = "cdfs"\n[design]\nkind = "grid"\n[quantity]\n'
                   'kind = "critical-speed"\nlinear = false\nlinear_points = 8\n[axes]\n'
                   'table_position = [200, 400]\n', encoding="utf-8")
    result = runner.invoke(app, ["sweep", str(cfg), "--dry-run", "--store",
                                 str(tmp_path / "cs.sqlite")])
    assert result.exit_code == 2, result.output
    assert result.stdout == ""
    lines = [s for s in result.stderr.splitlines() if s.strip()]
    assert lines == [f"error: {cfg}: quantity.linear_points = 8: not read by kind "
                     "critical-speed with linear = false, which reads start, low, high, "
                     "coarse_step, resolution, initial_duration, max_duration, linear"], lines
    assert not (tmp_path / "cs.sqlite").exists()


def test_linear_points_is_keyed_only_when_read() -> None:
    """The store key hashes ``to_dict()``: with the linear band it keeps ``linear_points``
    (the default's key is the one stores were written under), without it not."""
    default = QuantitySettings.parse({}).to_dict()
    assert default == DEFAULT_CRITICAL
    assert store_key({"task": {"quantity": default}}) == \
        store_key({"task": {"quantity": dict(DEFAULT_CRITICAL)}})
    assert QuantitySettings.parse({"linear_points": 8}).to_dict()["linear_points"] == 8
    off = QuantitySettings.parse({"linear": False}).to_dict()
    assert off == {k: v for k, v in DEFAULT_CRITICAL.items() if k != "linear_points"} \
        | {"linear": False}


def test_sensitivity_of_the_critical_speed_refuses_linear_points() -> None:
    """``sensitivity(quantity="critical-speed", linear_points=N)`` passed N into the store key
    of a search that never reads it; refused before any point or store is made."""
    from feeddrive.analysis.sensitivity import sensitivity

    with pytest.raises(ParameterError, match=r"^linear_points = 8: not read by quantity "
                                             r"critical-speed \(its search runs without the "
                                             r"linear band\); it sets the scan of quantity "
                                             r"linear-band$"):
        sensitivity(fd.preset("wang2021"), quantity="critical-speed", linear_points=8,
                    in_process=True)
