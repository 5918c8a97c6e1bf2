"""A notebook user's bad values, refused where they are made and naming the field (session
25; an outside check, 2026-12-07): a profile with a negative ramp or a zero frequency was
refused only at ``simulate``, in a bare ``ValueError`` from ``encode``; a ``Simulation`` showed
as ``<feeddrive.engine.simulate.Simulation object at 0x…>``."""

from __future__ import annotations

import math

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.engine.simulate import Simulation
from feeddrive.model.reference import ConstantSpeed, SampledSpeed, SineSpeed
from feeddrive.parameters import ParameterError


@pytest.mark.parametrize(("make", "field", "unit"), [
    (lambda: ConstantSpeed(1e-3, ramp_time=-1.0), "profile.ramp_time", "[s]"),
    (lambda: ConstantSpeed(1e-3, ramp_time=math.inf), "profile.ramp_time", "[s]"),
    (lambda: ConstantSpeed(1e-3, ramp_time="0.1"), "profile.ramp_time", "number"),
    (lambda: ConstantSpeed(math.nan), "profile.table_speed", "[m/s]"),
    (lambda: ConstantSpeed(1e-3, nut_speed="16"), "profile.nut_speed", "[m/s]"),
    (lambda: SineSpeed(1e-3, frequency=0.0), "profile.frequency", "[Hz]"),
    (lambda: SineSpeed(1e-3, frequency=-0.2), "profile.frequency", "[Hz]"),
    (lambda: SineSpeed(1e-3, frequency=1e300), "profile.frequency", "[Hz]"),
    (lambda: SineSpeed(1e-3, frequency=[0.2]), "profile.frequency", "number"),
    (lambda: SineSpeed(math.inf), "profile.table_amplitude", "[m/s]"),
    (lambda: SampledSpeed(np.arange(5.0), np.ones(4)), "profile.time/table_speed/nut_speed",
     "[s, m/s]"),
    (lambda: SampledSpeed(np.arange(5.0), np.array([0, 1, np.nan, 1, 0.0])),
     "profile.table_speed[2]", "[m/s]"),
    (lambda: SampledSpeed(np.array([0.0, 1.0, 3.0]), np.ones(3)), "profile.time", "[s]"),
    (lambda: SampledSpeed("a", "b"), "profile.time", "[s]"),  # its first value: session 29
])
def test_a_bad_profile_is_refused_when_made(make: object, field: str, unit: str) -> None:
    with pytest.raises(ParameterError) as err:
        make()  # type: ignore[operator]
    assert err.value.field == field
    assert str(err.value).startswith(field) and unit in str(err.value)


def test_good_profiles_are_made_and_encoded_as_before() -> None:
    """The checks moved; what is taken is unchanged (the encoded blocks)."""
    assert ConstantSpeed(2e-3, 0.016, 0.0).encode()[0][1] == 2e-3
    assert SineSpeed(1e-3, frequency=1000.0).encode()[0][4] == 1000.0
    t = np.arange(11) * 1e-3
    table = SampledSpeed(t, np.full(11, 1e-3)).encode()[1]
    assert table[0, -1] == pytest.approx(1e-5)  # the position, the speed's exact integral


def test_a_simulation_says_what_it_is_and_how_far_it_has_run() -> None:
    sim = Simulation(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4), ConstantSpeed(2e-3))
    assert repr(sim).startswith("<feeddrive.Simulation cdfs of 'wang2021' at 0.4 m, "
                                "ConstantSpeed(table_speed=0.002")
    assert repr(sim).endswith("method 'modal'; not run yet>")
    sim.run(0.2)
    assert repr(sim).endswith("; run to 0.2 s>")
    sim.run(0.3)  # continued
    assert repr(sim).endswith("; run to 0.3 s>")


@pytest.mark.parametrize(("option", "value", "unit"), [
    ("--lead", "0", "[mm]"), ("--lead", "nan", "[mm]"), ("--torque-constant", "-1", "[N m/A]")])
def test_identify_static_names_the_option_in_its_unit(tmp_path: object, option: str,
                                                      value: str, unit: str) -> None:
    """`--lead 0` was refused as "torque_constant = 0.55, lead = 0.0: expected positive values
    [N m/A], [m]" — both fields, the lead in metres."""
    from pathlib import Path

    from typer.testing import CliRunner

    from feeddrive.cli import app

    data = Path(str(tmp_path)) / "current.csv"
    data.write_text("speed,current\n1,1\n2,1.1\n5,1.3\n-1,-1\n-2,-1.1\n-5,-1.3\n")
    res = CliRunner().invoke(app, ["identify", "static", str(data), option, value])
    assert res.exit_code == 2
    line = res.output.strip().splitlines()[-1]
    assert line.startswith(f"error: {option} = ") and line.endswith(unit), res.output


def test_read_static_test_names_the_field_it_refuses(tmp_path: object) -> None:
    from pathlib import Path

    from feeddrive.io.measured import read_static_test

    data = Path(str(tmp_path)) / "current.csv"
    data.write_text("speed,current\n1,1\n2,1.1\n5,1.3\n-1,-1\n-2,-1.1\n-5,-1.3\n")
    with pytest.raises(ParameterError, match=r"^lead = 0.0: .*\[m\]$"):
        read_static_test(str(data), torque_constant=0.5, lead=0.0)
    with pytest.raises(ParameterError, match=r"^torque_constant = nan: .*\[N m/A\]$"):
        read_static_test(str(data), torque_constant=math.nan, lead=5e-3)


def _interrupt_second(monkeypatch: pytest.MonkeyPatch, module: object, name: str) -> None:
    """The second call of ``module.name`` is stopped by Ctrl-C; the first runs as it is."""
    real = getattr(module, name)
    calls = {"n": 0}

    def once(*args: object, **kwargs: object) -> object:
        calls["n"] += 1
        if calls["n"] == 2:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(module, name, once)


def test_compensate_compare_keeps_the_schemes_finished_before_ctrl_c(
        tmp_path: object, monkeypatch: pytest.MonkeyPatch) -> None:
    """Ctrl-C in the second scheme: the first's row is printed and written (both were
    dropped: an outside check, 2026-12-07)."""
    from pathlib import Path

    from typer.testing import CliRunner

    from feeddrive.analysis import compensation_compare
    from feeddrive.cli import app
    from feeddrive.exit_codes import INTERRUPTED

    _interrupt_second(monkeypatch, compensation_compare, "measure")
    out = Path(str(tmp_path)) / "table.csv"
    res = CliRunner().invoke(app, ["compensate", "--compare", "--schemes", "none,feedforward",
                                   "--metrics", "settling", "--output", str(out)])
    assert res.exit_code == INTERRUPTED, res.output
    assert "interrupted: stopped after 1 of 2 rows (those shown, and written)" in res.output
    lines = out.read_text(encoding="utf-8").strip().splitlines()
    assert len(lines) == 2 and lines[1].startswith("none,")  # the header and the first row


def test_compensate_study_shows_the_cases_finished_before_ctrl_c(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from typer.testing import CliRunner

    from feeddrive.analysis import compensation
    from feeddrive.cli import app
    from feeddrive.exit_codes import INTERRUPTED

    _interrupt_second(monkeypatch, compensation, "evaluate")
    res = CliRunner().invoke(app, ["compensate", "--no-search", "--json"])
    assert res.exit_code == INTERRUPTED, res.output
    import json

    text = res.output
    shown = json.loads(text[text.index("{"):text.rindex("}") + 1])
    assert len(shown["rows"]) == 1 and shown["interrupted"] is True
    assert "stopped after 1 of " in res.output


# ---- wrong objects and missing folders (an outside check, 2026-12-07) ---------------------

def test_save_names_swapped_or_wrong_arguments(tmp_path: object) -> None:
    params = fd.preset("wang2021")
    with pytest.raises(ParameterError, match=r"^params = 'str': expected DriveParameters"):
        fd.save("wang2021", f"{tmp_path}/p.toml")  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=r"^params = 'str': expected DriveParameters"):
        fd.save(f"{tmp_path}/p.toml", params)  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=r"^path = 'int': expected a file name"):
        fd.save(params, 3)  # type: ignore[arg-type]


def test_an_api_write_into_a_missing_folder_is_refused_not_created(tmp_path: object) -> None:
    """docs/outputs.md: feeddrive does not create folders for a file output.  `save` failed
    naming its hidden temporary file; `Result.save` created the folder."""
    from pathlib import Path

    from feeddrive.io.outputs import OutputError

    missing = Path(str(tmp_path)) / "missing"
    params = fd.preset("wang2021")
    with pytest.raises(OutputError, match=r"folder .*missing does not exist; create it first"):
        fd.save(params, missing / "p.toml")
    result = fd.simulate(fd.DriveSystem(params, "cdfs", 0.4), ConstantSpeed(2e-3), 0.05)
    for name in ("r.nc", "r.csv"):
        with pytest.raises(OutputError, match="does not exist; create it first"):
            result.save(missing / name)
    assert not missing.exists()
    result.save(Path(str(tmp_path)) / "r.csv")  # an existing folder: written as before
    assert (Path(str(tmp_path)) / "r.csv").stat().st_size > 0


def test_replace_path_names_a_path_that_is_not_text() -> None:
    with pytest.raises(ParameterError, match=r"^path = None: expected a dotted field name"):
        fd.preset("wang2021").replace_path(None, 1.0)  # type: ignore[arg-type]


def test_friction_functions_refuse_a_whole_set_and_non_finite_speeds() -> None:
    from feeddrive.model.friction.stribeck import sliding_stability, steady_friction

    params = fd.preset("wang2021")
    site = params.friction.screw
    with pytest.raises(ParameterError, match=r"^params = 'DriveParameters': expected one "):
        steady_friction(np.array([1e-3]), params)  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=r"^velocity = nan: expected finite .*\[m/s\]$"):
        steady_friction(math.nan, site)
    with pytest.raises(ParameterError, match=r"^velocity = 'a': expected numbers \[m/s\]$"):
        steady_friction("a", site)
    for mass in (0.0, math.nan):  # 0 read as "stable"; NaN failed in LAPACK
        with pytest.raises(ParameterError, match=r"^mass = .*: expected a finite value > 0 "
                                                 r"\[kg\]$"):
            sliding_stability([1e-3], [site], mass, 1e7, 100.0)
    # good values as before: Wang2021's screw site, the two branches
    force = steady_friction(np.array([1e-3, -1e-3]), site)
    assert force[0] > 0 > force[1]


def test_creep_metrics_names_its_window_and_thresholds() -> None:
    t = np.linspace(0.0, 1.0, 1001)
    v = 1e-3 + 1e-4 * np.sin(40 * t)
    with pytest.raises(ParameterError, match=r"^thresholds = 'dict': expected CreepThresholds"):
        fd.creep_metrics(t, v, 1e-3, thresholds={"stick_level": 0.1})  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=r"^window = \(5, 10\): outside the record, "
                                             r"0 … 1 \[s\]$"):
        fd.creep_metrics(t, v, 1e-3, window=(5, 10))
    with pytest.raises(ParameterError, match=r"^window = \(0.5, 0.2\): expected finite start "):
        fd.creep_metrics(t, v, 1e-3, window=(0.5, 0.2))
    # a window reaching past the record is its part within it, as before
    part = fd.creep_metrics(t, v, 1e-3, window=(-1.0, 0.4))
    assert part.window_start == pytest.approx(0.0) and part.window_end == pytest.approx(0.4)


def test_a_short_move_is_a_triangle_at_the_acceleration_whatever_the_feed() -> None:
    """A move too short to reach the feed kept ramps stretched to the feed's length, so a
    higher feed made it slower (an outside check, 2026-12-07: 4.4 / 10 / 82 s).  The move of
    d = 0.1 mm at a = 0.5 m/s² reaches at most √(d·a) = 7.07 mm/s: at any feed above that it
    is the same triangle (closed form: 2·√(d/a) = 28.3 ms, on the 1-ms grid 30 ms)."""
    from feeddrive.model.positioning_profile import stops_profile

    d, a = 1e-4, 0.5
    ends = []
    for feed in (1e-4, 1e-3, 1e-2, 1e-1, 1.0):
        profile, end = stops_profile([d, 0.0], feed=feed, acceleration=a, dwell=1.0)
        v = np.asarray(profile.table_speed)
        assert np.max(np.abs(v)) <= feed * (1 + 1e-9)
        assert np.max(np.abs(np.diff(v))) / 1e-3 <= a * (1 + 1e-9)
        ends.append(float(end[-1]))
    assert all(b <= e for e, b in zip(ends, ends[1:], strict=False))  # never slower
    assert ends[2] == ends[3] == ends[4]  # above √(d·a): the same triangle
    move = (ends[4] - 2 * 1.0) / 2  # each of the two moves, the dwells taken off
    assert move == pytest.approx(2 * math.sqrt(d / a), abs=2.5e-3)
