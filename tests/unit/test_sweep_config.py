"""Sweep configurations, designs and the results store (issue 10), no simulation."""

from __future__ import annotations

import multiprocessing
import sqlite3
from pathlib import Path

import pytest
from typer.testing import CliRunner

from feeddrive.cli import app
from feeddrive.parameters import ParameterError
from feeddrive.sweep import SweepStore, load_config, parse_config
from feeddrive.sweep.store import StoreError

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
BASE = {"quantity": {"kind": "linear-band", "linear_points": 4}}


def _cfg(**data: object) -> object:
    return parse_config({**BASE, **data}, "/tmp/cfg.toml")


def test_grid_counts_units_and_order() -> None:
    cfg = _cfg(axes={"drive": ["cdfs", "ddfs"],
                     "table_position": {"low": 200, "high": 600, "points": 3},
                     "nut_speed": [2, 40]})
    points = cfg.points()
    assert len(points) == 12
    assert points[0].coords == {"drive": "cdfs", "table_position": 200.0, "nut_speed": 2}
    assert points[0].task["table_position"] == pytest.approx(0.2)  # mm → m at the edge
    # the CDFS holds its nut: both nut speeds give one computation
    cdfs = [p for p in points if p.coords["drive"] == "cdfs"]
    assert len({p.key for p in cdfs}) == 3
    ddfs = [p for p in points if p.coords["drive"] == "ddfs"]
    assert len({p.key for p in ddfs}) == 6
    assert sorted({p.task["nut_speed"] for p in ddfs}) == pytest.approx([2e-3, 40e-3])


@pytest.mark.parametrize("kind", ["random", "lhs"])
def test_random_designs_are_reproducible(kind: str) -> None:
    spec = {"design": {"kind": kind, "samples": 16, "seed": 3},
            "axes": {"controller.velocity_integral_gain": {"low": 3000, "high": 5000},
                     "friction.screw": {"low": 0.8, "high": 1.2, "relative": True}}}
    a, b = _cfg(**spec).points(), _cfg(**spec).points()
    assert [p.key for p in a] == [p.key for p in b]
    gains = sorted(p.coords["controller.velocity_integral_gain"] for p in a)
    assert 3000 <= gains[0] and gains[-1] <= 5000
    if kind == "lhs":  # one sample in each of 16 strata
        strata = {int((g - 3000) / 2000 * 16) for g in gains}
        assert len(strata) == 16


def test_relative_axes_scale_sites_and_chain_stiffness() -> None:
    from feeddrive.model.mechanisms.ball_screw_stiffness import equivalent_stiffness
    from feeddrive.parameters import loads, preset

    cfg = _cfg(axes={"friction.screw": {"values": [1.1], "relative": True},
                     "stiffness.equivalent_stiffness": {"values": [0.8], "relative": True}})
    task = cfg.points()[0].task
    params, base = loads(task["parameters"]), preset("wang2021")
    assert params.friction.screw.positive.static_force == pytest.approx(
        1.1 * base.friction.screw.positive.static_force)
    assert params.stiffness.equivalent_stiffness == pytest.approx(
        0.8 * equivalent_stiffness(base, 0.4))


def test_star_expands_to_every_matching_parameter() -> None:
    cfg = load_config(EXAMPLES / "uncertainty.toml")
    names = [a.name for a in cfg.axes]
    assert len(names) == 31  # Table 1: 3 sites × (2 branches × 4 + σ0, σ1), and K_eq
    assert "friction.guide.negative.stribeck_velocity" in names
    assert cfg.samples == 200


@pytest.mark.parametrize(("data", "key"), [
    ({"axes": {"friction.screw.positive.static_forse": [90.0]}},
     'axes."friction.screw.positive.static_forse"'),
    ({"axes": {"table_position": {"low": 500, "high": 200, "points": 3}}},
     "axes.table_position.high"),
    ({"axes": {"nut_speed": []}}, "axes.nut_speed.values"),
    ({"axes": {"friction.screw.positive.static_force": [90.0, -5.0]}},
     'axes."friction.screw.positive.static_force"'),
    ({"axes": {"table_position": [200, 5000]}}, "axes.table_position"),
    ({"axes": {"drive": ["cdfs", "hydraulic"]}}, "axes.drive.values"),
    ({"design": {"kind": "lhs"}, "axes": {"nut_speed": {"low": 1, "high": 2}}},
     "design.samples"),
    ({"quantity": {"kind": "bode"}}, "quantity.kind"),
    ({"quantity": {"kind": "critical-speed", "low": 3, "high": 1}}, "quantity.high"),
    ({"preset": "wang2099"}, "preset"),
    ({"speed": 3}, "speed"),
])
def test_bad_configs_name_the_key(data: dict[str, object], key: str) -> None:
    with pytest.raises(ParameterError) as err:
        parse_config({**BASE, **data}, "/tmp/cfg.toml").points()
    assert str(err.value).startswith(f"{key} = "), str(err.value)


def _write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "cfg.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize(("text", "key"), [
    ('[axes]\n"friction.screw.positive.static_forse" = [90.0]\n',
     'axes."friction.screw.positive.static_forse"'),
    ("[axes]\ntable_position = { low = 300, high = 300, points = 4 }\n",
     "axes.table_position.high"),
    ('[axes]\n"friction.screw.positive.static_force" = [-1.0]\n',
     'axes."friction.screw.positive.static_force"'),
    ('store = "no-such-folder/s.sqlite"\n[axes]\nnut_speed = [1.0]\n', "store"),
    ('store = "/proc/feeddrive-sweep.sqlite"\n[axes]\nnut_speed = [1.0]\n', "store"),
])
def test_cli_refuses_bad_configs_before_any_simulation(tmp_path: Path, text: str, key: str,
                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    import feeddrive.sweep.executors as ex

    def no_simulation(*args: object, **kwargs: object) -> None:
        raise AssertionError("a simulation started")

    monkeypatch.setattr(ex, "warm", no_simulation)
    monkeypatch.setattr(ex, "evaluate", no_simulation)
    monkeypatch.chdir(tmp_path)
    cfg = _write(tmp_path, '[quantity]\nkind = "linear-band"\n' + text)
    res = CliRunner().invoke(app, ["sweep", str(cfg)])
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), res.output
    assert key in lines[0]
    assert not list(tmp_path.glob("*.sqlite"))


def test_non_writable_store_is_refused() -> None:
    # a read-only place even root cannot write (as tests/unit/test_outputs.py)
    with pytest.raises(StoreError, match=r"^--store /proc/feeddrive-sweep.sqlite: cannot write"):
        SweepStore("/proc/feeddrive-sweep.sqlite", option="--store")


def test_store_is_not_a_database(tmp_path: Path) -> None:
    p = tmp_path / "s.sqlite"
    p.write_text("hello")
    with pytest.raises(StoreError, match="not a feeddrive sweep store"):
        SweepStore(p)


def test_store_put_get_and_checksum(tmp_path: Path) -> None:
    notices: list[str] = []
    with SweepStore(tmp_path / "s.sqlite", notice=notices.append) as store:
        store.put("k1", {"values": {"a": 1.0, "b": float("nan")}})
        store.put("k1", {"values": {"a": 1.0, "b": float("nan")}})
        assert store.get("k1") == {"values": {"a": 1.0, "b": None}}
        assert store.count() == 1
    db = sqlite3.connect(tmp_path / "s.sqlite")
    db.execute("UPDATE results SET payload = replace(payload, '1.0', '2.0')")
    db.commit()
    db.close()
    with SweepStore(tmp_path / "s.sqlite", notice=notices.append) as store:
        assert store.get("k1") is None
        assert store.finished(["k1"]) == set()
        store.put("k1", {"values": {"a": 1.0}})  # a damaged entry is replaced
        assert store.get("k1") == {"values": {"a": 1.0}}
    assert any("checksum mismatch" in n for n in notices)


def _writer(path: str, start: int, n: int) -> None:
    with SweepStore(path) as store:
        for i in range(start, start + n):
            store.put(f"key{i % 60}", {"values": {"i": i % 60}})
            store.register(f"sweep{start}", {"axes": []}, [(i, f"key{i % 60}", {})])


def test_concurrent_writers_corrupt_nothing(tmp_path: Path) -> None:
    path = str(tmp_path / "s.sqlite")
    SweepStore(path).close()
    ctx = multiprocessing.get_context("spawn")
    procs = [ctx.Process(target=_writer, args=(path, s, 40)) for s in (0, 20, 40)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(60)
        assert p.exitcode == 0
    db = sqlite3.connect(path)
    assert db.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    db.close()
    with SweepStore(path) as store:
        assert store.count() == 60
        assert all(store.get(f"key{i}") == {"values": {"i": i}} for i in range(60))


def test_map_refuses_unknown_axes_and_missing_stores(tmp_path: Path) -> None:
    from feeddrive.sweep.executors import description

    cfg = _cfg(axes={"nut_speed": [1.0, 2.0], "table_position": [300, 500]})
    points = cfg.points()
    with SweepStore(tmp_path / "s.sqlite") as store:
        store.register(cfg.name, description(cfg), [(p.index, p.key, p.coords) for p in points])
        store.put(points[0].key, {"values": {"linear_upper": 1e-3, "linear_lower": 1e-4}})
    runner = CliRunner()
    res = runner.invoke(app, ["map", str(tmp_path / "s.sqlite"), "--x", "speed", "--y",
                              "nut_speed", "--plot", str(tmp_path / "m.png")])
    assert res.exit_code == 2 and "--x = 'speed': not an axis" in res.output, res.output
    res = runner.invoke(app, ["map", str(tmp_path / "nothing.sqlite")])
    assert res.exit_code == 2 and "no such store" in res.output, res.output
    res = runner.invoke(app, ["map", str(tmp_path / "s.sqlite"), "--x", "table_position", "--y",
                              "nut_speed", "--plot", str(tmp_path / "m.png")])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "m.png").exists()


def test_a_position_off_the_screw_is_shown_as_the_configuration_gives_it() -> None:
    """The configuration's positions are in mm; the refusal showed the metres the drive
    checks (``axes.table_position = 5.0: expected 0 < a < 0.8 [m]``) before 2026-12-06."""
    with pytest.raises(ParameterError) as err:
        parse_config({**BASE, "axes": {"table_position": [200, 5000]}},
                     "/tmp/cfg.toml").points()
    text = str(err.value)
    assert text.startswith("axes.table_position = 5000")
    assert text.endswith("; the configuration's positions are in mm")
