"""Issue 25 (reliability, round 3), the library side: full disks, hostile values, huge
designs, names, stores shared by two sweeps, the reproduce cache.

Full disks are a file-size limit (``RLIMIT_FSIZE``, with ``SIGXFSZ`` ignored, so a write past
it fails with ``EFBIG`` as a full disk fails with ``ENOSPC``) in a subprocess: the limit
applies to every file the process writes.
"""

from __future__ import annotations

import hashlib
import json
import os
import sqlite3
import subprocess
import sys
import textwrap
import time
import zlib
from pathlib import Path

import pytest

from feeddrive.explore import settings as st
from feeddrive.io.json_store import ResultStore
from feeddrive.io.outputs import atomic_path, shown
from feeddrive.model.loops import Controller
from feeddrive.parameters import ParameterError, dumps, load, preset
from feeddrive.parameters.toml_io import MAX_EXTENDS
from feeddrive.sweep import design as sweep_design
from feeddrive.sweep.design import MAX_POINTS, parse_config
from feeddrive.sweep.store import StoreFailure, SweepStore

BASE = {"name": "t", "drive": "cdfs", "quantity": {"kind": "loop-margins"}}


def _run_limited(script: str, *args: str, limit: int) -> subprocess.CompletedProcess[str]:
    """``script`` in a fresh interpreter whose files may not grow past ``limit`` bytes."""
    prelude = textwrap.dedent(f"""
        import resource, signal
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        def limit_files():
            resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, resource.RLIM_INFINITY))
    """)
    return subprocess.run([sys.executable, "-c", prelude + textwrap.dedent(script), *args],
                          capture_output=True, text=True, timeout=180)


# ------------------------------------------------------------------ item 2: atomic writers

_WRITERS = """
    import json, sys
    from pathlib import Path
    import numpy as np, xarray as xr
    from matplotlib.figure import Figure
    from feeddrive.io.results import save_result
    from feeddrive.parameters import preset, save
    from feeddrive.reproduce.studies import write_csv
    from feeddrive.io.json_store import ResultStore
    from feeddrive.plots.stribeck import save_figure
    out = Path(sys.argv[1])
    n = 20000
    ds = xr.Dataset({"table_speed": ("time", np.linspace(0, 1, n), {"units": "m/s"})},
                    coords={"time": np.arange(n) * 1e-3}, attrs={"drive": "cdfs"})
    fig = Figure()
    fig.subplots().plot(np.random.default_rng(0).random(5000))
    params = preset("wang2021")
    store = ResultStore(out / "cache", "k" * 64)
    writers = {
        "r.csv": lambda p: save_result(ds, p), "r.parquet": lambda p: save_result(ds, p),
        "r.nc": lambda p: save_result(ds, p), "r.mat": lambda p: save_result(ds, p),
        "f.png": lambda p: save_figure(fig, p), "p.toml": lambda p: save(params, p),
        "rows.csv": lambda p: write_csv([{"a": float(i)} for i in range(5000)], p),
        "cache/e-kkkkkkkkkkkkkkkk.json": lambda p: store.put("e", list(range(5000))),
    }
    writers = {k: w for k, w in writers.items() if k in sys.argv[2].split(",")}
    for name in writers:
        (out / name).write_bytes(b"old")
    limit_files()
    got = {}
    for name, write in writers.items():
        try:
            write(out / name)
            got[name] = "written"
        except OSError as err:
            got[name] = err.errno
    print(json.dumps(got), flush=True)
"""


def test_every_writer_leaves_the_old_file_when_the_disk_fills(tmp_path: Path) -> None:
    """Every writer, NetCDF4 too: HDF5 used to crash the process (SIGSEGV) in its cleanup
    after a failed write (issue 39 item 1); the interpreter now exits normally."""
    (tmp_path / "cache").mkdir()
    names = "r.csv,r.parquet,r.nc,r.mat,f.png,p.toml,rows.csv,cache/e-kkkkkkkkkkkkkkkk.json"
    proc = _run_limited(_WRITERS, str(tmp_path), names, limit=1024)
    assert proc.returncode == 0, proc.stderr
    got = json.loads(proc.stdout.splitlines()[0])
    assert len(got) == 8
    for name, outcome in got.items():
        assert outcome == 27, (name, outcome)  # EFBIG: the write failed, as on a full disk
        assert (tmp_path / name).read_bytes() == b"old", name  # never a truncated file
    leftovers = [p.name for p in tmp_path.rglob(".*partial*")]
    assert leftovers == []


def test_atomic_path_keeps_the_extension_and_the_umask(tmp_path: Path) -> None:
    target = tmp_path / "plot.png"
    with atomic_path(target) as tmp:
        assert tmp.parent == tmp_path and tmp.suffix == ".png" and tmp.name.startswith(".")
        tmp.write_bytes(b"png")
        assert not target.exists()  # nothing under the final name until the end
    assert target.read_bytes() == b"png"
    umask = os.umask(0)
    os.umask(umask)
    assert target.stat().st_mode & 0o777 == 0o666 & ~umask
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_bytes(b"half")
        raise RuntimeError("killed mid-write")
    assert target.read_bytes() == b"png" and [p.name for p in tmp_path.iterdir()] == [
        "plot.png"]


# ------------------------------------------------------------------ item 1: the sweep store

_STORE_FILL = """
    import sys
    from feeddrive.sweep.store import StoreFailure, SweepStore
    store = SweepStore(sys.argv[1])
    limit_files()
    stored = 0
    try:
        for i in range(10000):
            store.put(f"key{i}", {"values": {"x": "y" * 2000}})
            stored += 1
    except StoreFailure as err:
        print(stored, err.filename, err.strerror, sep="|")
"""


def test_a_full_disk_under_the_sweep_store_is_a_store_failure_and_keeps_every_point(
        tmp_path: Path) -> None:
    path = tmp_path / "s.sqlite"
    SweepStore(path).close()
    proc = _run_limited(_STORE_FILL, str(path), limit=256 * 1024)
    assert proc.returncode == 0, proc.stderr  # no sqlite3 traceback
    stored, filename, message = proc.stdout.strip().split("|")
    assert int(stored) > 10 and filename == str(path)
    assert message.startswith("SQLite: ") and "every point stored before is kept" in message
    with SweepStore(path) as store:
        assert store.count() == int(stored)
        assert store.get(f"key{int(stored) - 1}") is not None
    db = sqlite3.connect(path)
    assert db.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    db.close()


def test_a_locked_store_is_a_store_failure(tmp_path: Path) -> None:
    path = tmp_path / "s.sqlite"
    store = SweepStore(path)
    store._db.execute("PRAGMA busy_timeout = 50")
    other = sqlite3.connect(path, isolation_level=None)
    other.execute("BEGIN IMMEDIATE")  # another process holds the write lock
    with pytest.raises(StoreFailure, match="database is locked"):
        store.put("k", {"values": {}})
    other.execute("ROLLBACK")
    store.close()


# ------------------------------------------------------------------ item 11: claims


def test_two_stores_claim_points_and_a_dead_claim_is_taken_over(tmp_path: Path) -> None:
    path = tmp_path / "s.sqlite"
    a, b = SweepStore(path), SweepStore(path)
    assert a.claim("k1") == "mine"
    assert b.claim("k1") == "busy"  # a live sweep (this process) holds it
    a.put("k1", {"values": {"x": 1.0}})
    assert b.claim("k1") == "stored"
    assert a.claim("k2") == "mine"
    a.release_claims()
    assert b.claim("k2") == "mine"
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    db = sqlite3.connect(path, isolation_level=None)
    db.execute("UPDATE claims SET pid = ?, owner = 'gone' WHERE key = 'k2'",
               (int(dead.stdout),))
    db.close()
    assert a.claim("k2") == "mine"  # its process is gone: taken over
    a.close()
    b.close()


# ------------------------------------------------------------------ items 5, 7: designs, names


def _counting_tasks(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    built: list[int] = []
    original = sweep_design.SweepConfig.task

    def task(self, coords, cache=None):  # type: ignore[no-untyped-def]
        built.append(1)
        return original(self, coords, cache)

    monkeypatch.setattr(sweep_design.SweepConfig, "task", task)
    return built


def test_a_billion_samples_are_refused_before_any_point_is_built(
        monkeypatch: pytest.MonkeyPatch) -> None:
    built = _counting_tasks(monkeypatch)
    started = time.perf_counter()
    with pytest.raises(ParameterError) as err:
        parse_config({**BASE, "design": {"kind": "lhs", "samples": 10**9},
                      "axes": {"table_position": {"low": 300, "high": 500}}}, "/tmp/c.toml")
    assert time.perf_counter() - started < 5  # nothing sampled (this took 7.9 GB)
    assert err.value.field == "design.samples" and "at most 1000000" in str(err.value)
    assert "\n" not in str(err.value) and built == []


def test_grid_size_is_counted_not_materialised(monkeypatch: pytest.MonkeyPatch) -> None:
    built = _counting_tasks(monkeypatch)
    with pytest.raises(ParameterError, match="1001000 design points; at most 1000000"):
        parse_config({**BASE, "axes": {"table_position": {"low": 300, "high": 500,
                                                          "points": 1001},
                                       "nut_speed": {"low": 0, "high": 1, "points": 1000}}},
                     "/tmp/c.toml")
    with pytest.raises(ParameterError, match="points"):
        parse_config({**BASE, "axes": {"table_position": {"low": 300, "high": 500,
                                                          "points": 10**12}}}, "/tmp/c.toml")
    cfg = parse_config({**BASE, "axes": {"table_position": {"low": 300, "high": 500,
                                                            "points": 1000},
                                         "nut_speed": {"low": 0, "high": 1, "points": 1000}}},
                       "/tmp/c.toml")
    assert cfg.count() == MAX_POINTS and built == []
    # a CDFS ignores the nut speed: 1000 distinct computations, from the coordinates alone
    assert cfg.distinct_count() == 1000 and built == []


def _walked(cfg: sweep_design.SweepConfig) -> int:
    """The distinct count by walking every point (what distinct_count did until 2026-12-07)."""
    return len({cfg.effective(c) for c in cfg.iter_coordinates()})


@pytest.mark.parametrize("drives", [["cdfs"], ["ddfs"], ["cdfs", "ddfs", "cdfs"],
                                    ["linear-motor", "ddfs"]])
def test_a_grids_distinct_count_is_the_walks_without_walking(
        monkeypatch: pytest.MonkeyPatch, drives: list[str]) -> None:
    cfg = parse_config({**BASE, "axes": {"drive": {"values": drives},
                                         "table_position": {"values": [300, 400, 300.0]},
                                         "nut_speed": {"low": 0, "high": 1, "points": 4}}},
                       "/tmp/c.toml")
    walked = _walked(cfg)
    # counted by hand: three positions (300 and 300.0 are two values to the walk) for a ball
    # screw, which reads it (a linear motor ignores it since session 30: one), times the
    # nut speed's 4 values for a DDFS, which follows it; a CDFS or a linear motor ignores it
    expected = sum((3 if d in ("cdfs", "ddfs") else 1) * (4 if d == "ddfs" else 1)
                   for d in dict.fromkeys(drives))
    assert walked == expected
    monkeypatch.setattr(sweep_design.SweepConfig, "iter_coordinates",
                        lambda self: (_ for _ in ()).throw(AssertionError("walked")))
    assert cfg.distinct_count() == expected


@pytest.mark.parametrize(("name", "why"), [
    (42, "expected a text name"), ({"a": 1}, "expected a text name"),
    ("../../escaped", "not a path"), ("/tmp/abs", "not a path"), (".hidden", "not a path"),
    ("bad\x1b[31mred", "control characters"), ("x" * 101, "at most 100"),
])
def test_sweep_names_are_names(name: object, why: str) -> None:
    with pytest.raises(ParameterError, match="name") as err:
        parse_config({**BASE, "name": name}, "/tmp/c.toml")
    assert why in str(err.value) and "\x1b" not in str(err.value).replace("\\x1b", "")


# ------------------------------------------------------------------ items 6, 8, 11: values


def _write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize(("line", "field"), [
    ("name = 42", "name"), ('name = "bell\\u0007"', "name"), ('name = "esc\\u001b[2J"', "name"),
    (f'name = "{"n" * 50_000}"', "name"), ("[name]\na = 1", "name"),
    ('description = "x\\u0000"', "description"),
])
def test_parameter_set_names_are_validated_and_cut(tmp_path: Path, line: str,
                                                   field: str) -> None:
    path = _write(tmp_path / "p.toml", f'extends = "wang2021"\n{line}\n')
    started = time.perf_counter()
    with pytest.raises(ParameterError) as err:
        load(path)
    assert time.perf_counter() - started < 2  # a 50-kB name took 151 s to print
    text = str(err.value)
    assert err.value.field == field and len(text) < 600
    assert text.isprintable()  # ESC and BEL never reach the terminal


@pytest.mark.parametrize("value", [5e-324, 1e-12, 9.9e-7])
@pytest.mark.parametrize("period", ["current_period", "velocity_period", "position_period"])
def test_a_period_is_zero_or_at_least_a_microsecond(tmp_path: Path, period: str,
                                                    value: float) -> None:
    path = _write(tmp_path / "p.toml",
                  f'extends = "wang2021"\n[controller]\n{period} = {value!r}\n')
    with pytest.raises(ParameterError, match=r"expected 0 \(a continuous loop\) or 1e-06"):
        load(path)


def test_periods_of_zero_and_a_microsecond_are_accepted(tmp_path: Path) -> None:
    base = preset("wang2021").controller
    assert Controller(**{**base.__dict__, "current_period": 1e-6,
                                       "velocity_period": 2e-6, "position_period": 0.0})


@pytest.mark.parametrize("key", ["coulomb_scale", "static_scale", "stribeck_velocity_scale"])
def test_compensation_scales_have_a_lower_bound(tmp_path: Path, key: str) -> None:
    path = _write(tmp_path / "p.toml", f'extends = "wang2021"\n[controller.compensation]\n'
                  f'mode = "feedforward"\n{key} = 1e-320\n')
    with pytest.raises(ParameterError, match=r"expected 0.001 … 10"):
        load(path)


def test_the_explorers_friction_scale_has_a_lower_bound() -> None:
    out = st.check({"friction_scale": "1e-320"})
    assert "friction_scale" in out.errors and "0.001" in out.errors["friction_scale"]
    assert st.check({"friction_scale": "0.001"}).ok


def test_long_values_are_cut_in_messages(tmp_path: Path) -> None:
    path = _write(tmp_path / "p.toml", f'extends = "wang2021"\nbogus = "{"v" * 10_000_000}"\n')
    with pytest.raises(ParameterError) as err:
        load(path)
    assert err.value.field == "bogus" and len(str(err.value)) < 600
    assert "(10000000 characters)" in str(err.value)


def test_a_fifo_named_toml_is_not_called_missing(tmp_path: Path) -> None:
    fifo = tmp_path / "pipe.toml"
    os.mkfifo(fifo)
    started = time.perf_counter()
    with pytest.raises(ParameterError, match="not a regular file"):
        load(fifo)  # never opened: reading a FIFO would block
    assert time.perf_counter() - started < 2
    with pytest.raises(ParameterError, match="not a regular file"):
        load("/dev/null.toml" if Path("/dev/null.toml").exists() else "/dev/zero")


def test_a_long_extends_name_is_refused_and_cut(tmp_path: Path) -> None:
    name = "x" * 5000 + ".toml"
    path = _write(tmp_path / "p.toml", f'extends = "{name}"\n')
    with pytest.raises(ParameterError) as err:
        load(path)
    assert "cannot be read (File name too long)" in str(err.value)
    assert len(str(err.value)) < 800


def test_extends_cycles_name_their_files(tmp_path: Path) -> None:
    _write(tmp_path / "a.toml", 'extends = "b.toml"\n')
    _write(tmp_path / "b.toml", 'extends = "c.toml"\n')
    _write(tmp_path / "c.toml", 'extends = "a.toml"\n')
    with pytest.raises(ParameterError) as err:
        load(tmp_path / "a.toml")
    text = str(err.value)
    assert "a cycle of extends" in text
    for name in ("a.toml", "b.toml", "c.toml"):
        assert name in text


def test_a_long_extends_chain_is_refused_naming_its_ends(tmp_path: Path) -> None:
    n = 1000
    for i in range(n):
        parent = f"f{i + 1}.toml" if i + 1 < n else "wang2021"
        _write(tmp_path / f"f{i}.toml", f'extends = "{parent}"\n')
    with pytest.raises(ParameterError, match=f"a chain of more than {MAX_EXTENDS} files") as e:
        load(tmp_path / "f0.toml")
    assert "f0.toml" in str(e.value) and len(str(e.value)) < 800
    # a chain within the bound loads, and its name does not grow with the chain
    assert load(tmp_path / f"f{n - MAX_EXTENDS}.toml").name == "wang2021+changes"


def test_shown_escapes_and_cuts() -> None:
    assert shown("a\x1b[2Jb\x07") == "a\\x1b[2Jb\\x07"
    assert shown("x" * 10_000).endswith("… (10000 characters)") and len(shown("x" * 10_000)) < 300


# ------------------------------------------------------------------ item 3: address bombs


def test_a_compressed_bomb_in_the_address_is_refused_without_inflating_it() -> None:
    bomb = st.encode_params(" " * 40_000_000)  # 40 MB of spaces: a ~50-kB address
    assert len(bomb) < 100_000
    started = time.perf_counter()
    with pytest.raises(ParameterError, match="larger than 256 kB"):
        st.decode_params(bomb)
    assert time.perf_counter() - started < 1  # was 304 s of server time
    settings, errors = st.from_query(f"params={bomb}")
    assert "larger than 256 kB" in errors["params"]
    text = dumps(preset("wang2021"))
    assert st.decode_params(st.encode_params(text)) == text  # a real one still reads
    cut = st.encode_params(text)[:-10]
    with pytest.raises(ParameterError, match="cut or changed"):
        st.decode_params(cut)
    assert zlib.decompress  # the standard library's, bounded by decompressobj


def test_deep_toml_in_an_import_is_refused_with_a_message() -> None:
    with pytest.raises(ParameterError, match="nested more than"):
        st.import_toml("a = " + "[" * 5000 + "]" * 5000 + "\n")
    deep_header = "# explore.drive = " + "[" * 5000 + "\n" + dumps(preset("wang2021"))
    assert st.import_toml(deep_header)["drive"] == "cdfs"  # the comment line is ignored


# ------------------------------------------------------------------ item 11: reproduce cache


def test_the_reproduce_cache_checksum_guards_against_accidents_only(tmp_path: Path) -> None:
    """docs/outputs.md: the checksum is unkeyed; an entry edited with its SHA-256
    recomputed is accepted (as documented), a careless edit is not."""
    store = ResultStore(tmp_path, "k" * 64)
    store.put("study", {"critical_speed_mm_s": 1.56})
    path = store.path("study")
    head, body = path.read_bytes().split(b"\n", 1)
    careless = body.replace(b"1.56", b"9.99")
    path.write_bytes(head + b"\n" + careless)
    assert store.get("study") is None
    header = json.loads(head)
    header["sha256"] = hashlib.sha256(careless).hexdigest()
    path.write_bytes(json.dumps(header).encode() + b"\n" + careless)
    assert store.get("study") == {"critical_speed_mm_s": 9.99}
    docs = (Path(__file__).resolve().parents[2] / "docs" / "outputs.md").read_text()
    assert "guards against accidents" in docs and "recomputed SHA-256" in docs


def test_a_folder_in_place_of_a_cache_entry_is_recomputed_with_a_notice(tmp_path: Path) -> None:
    notices: list[str] = []
    store = ResultStore(tmp_path, "k" * 64, notice=notices.append)
    store.path("study").mkdir()
    (store.path("study") / "mine.txt").write_text("keep")
    value = store.get_or_compute("study", lambda: {"v": 1})
    assert value == {"v": 1}
    assert len(notices) == 1 and "is a folder" in notices[0] and "recomputing" in notices[0]
    assert (store.path("study") / "mine.txt").read_text() == "keep"  # never removed


def test_the_explorer_refuses_a_tiny_period_in_an_imported_set() -> None:
    text = dumps(preset("wang2021")).replace("current_period = 0.0",
                                             "current_period = 5e-324")
    assert "5e-324" in text
    with pytest.raises(ParameterError, match="continuous loop"):
        st.import_toml(text)
    out = st.check({"params": text})
    assert "continuous loop" in out.errors["params"]


def test_the_statements_of_docs_outputs_md_are_the_codes(tmp_path: Path) -> None:
    import re

    from feeddrive.model import loops
    from feeddrive.parameters import components, toml_io, validation

    doc = " ".join((Path(__file__).resolve().parents[2] / "docs" / "outputs.md").read_text()
                   .split())
    assert "(`.NAME.XXXXXXXX.partial.EXT`)" in doc
    with atomic_path(tmp_path / "run.csv") as tmp:
        assert re.fullmatch(r"\.run\.[0-9a-f]{8}\.partial\.csv", tmp.name)
    assert f"longer than {validation.MAX_SHOWN} characters is cut" in doc
    assert f"followed up to {toml_io.MAX_EXTENDS} files" in doc
    assert f"files over {toml_io.MAX_TOML_BYTES // 1024 // 1024} MB" in doc
    assert f"at most {components.MAX_NAME} characters" in doc
    assert f"at most {components.MAX_DESCRIPTION:,} characters".replace(",", " ") in doc
    assert loops.MIN_PERIOD == 1e-6 and "at least 1 µs" in doc
    assert loops.MIN_GRATING == 1e-9 and "at least 1 nm" in doc
    assert "`stribeck_velocity_scale` at least 0.001" in doc


def test_a_write_interrupted_after_its_begin_does_not_block_the_next(tmp_path: Path) -> None:
    """Ctrl-C can land between a write's BEGIN IMMEDIATE and its try (CI, 2026-12-05: the
    sweep's Ctrl-C test exited 1 with "SQLite: cannot start a transaction within a
    transaction" instead of 130).  That state, made here by hand: the next write rolls the
    uncommitted one back and goes on."""
    with SweepStore(tmp_path / "s.sqlite") as store:
        store.put("kept", {"values": {"x": 1.0}})
        store._db.execute("BEGIN IMMEDIATE")  # the interrupted write's open transaction
        store.put("next", {"values": {"x": 2.0}})
        assert store.get("kept") is not None and store.get("next") is not None
        assert not store._db.in_transaction
