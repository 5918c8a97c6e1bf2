"""Acceptance of issue 13: every CLI command of the README table against a corpus of bad
inputs.

For every (command, bad file) pair and every unusable output: non-zero exit, exactly one
line on stderr that starts with ``error:`` and names the file, no ``Traceback``, no input
file modified.  Outputs are refused before any work (a refused ``calibrate --out`` returns
in well under a second instead of after its fit).  The memory-hungry cases run in a
subprocess under ``resource.RLIMIT_AS`` (3 GiB), where the old code died with MemoryError.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from feeddrive.cli import app
from feeddrive.io.outputs import shown
from feeddrive.model.friction.stribeck import steady_friction
from feeddrive.parameters import dumps, preset

runner = CliRunner()
PARAMS = preset("wang2021")


def _static_rows() -> str:
    v = np.repeat(np.geomspace(0.05, 50.0, 12), 2)
    v = np.concatenate([v, -v])
    f = steady_friction(v * 1e-3, PARAMS.friction.screw)
    return "\n".join(f"{a:.9g},{b:.9g}" for a, b in zip(v, f, strict=True)) + "\n"


@pytest.fixture(scope="module")
def corpus(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("corpus")
    files: dict[str, bytes] = {
        "empty.csv": b"",
        "blank-and-comments.csv": b"\n# only a comment\n   \n",
        "binary.dat": bytes(np.random.default_rng(13).integers(0, 256, 4096, dtype=np.uint8)),
        "données µ✓.csv": "température,position\nα,β\n".encode(),
        "huge-gap.csv": ("time,position\n" + "".join(f"{0.01 * i:g},{0.01 * i:g}\n"
                                                     for i in range(30))
                         + "1000000,1000000\n").encode(),
        "deep.toml": ("a = " + "[" * 5000 + "]" * 5000 + "\n").encode(),
        "new\nline.csv": b"speed [mm/s],force [N]\n",
        "header-only.csv": b"speed [mm/s],force [N]\n",
        "ragged.csv": b"time,position\n0,0\n1,1,1\n",
        "folder.csv": b"",  # replaced by a folder below
    }
    out = {}
    for name, data in files.items():
        p = d / name
        if name == "folder.csv":
            p.mkdir()
        else:
            p.write_bytes(data)
        out[name] = p
    return out


def _digest(paths: dict[str, Path]) -> dict[str, str]:
    return {n: hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else "folder"
            for n, p in paths.items()}


def _invoke(args: list[str]) -> Any:
    return runner.invoke(app, args)


def _one_line_error(result: Any, *names: str) -> str:
    assert result.exit_code != 0, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), \
        repr(result.exception)
    assert "Traceback" not in result.output and "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error: "), lines[0]
    assert any(n in lines[0] for n in names), (names, lines[0])
    return str(lines[0])


# every command of the README table that reads a file, with the file in its place
COMMANDS: dict[str, Callable[[str, Path], list[str]]] = {
    "params check": lambda f, out: ["params", "check", f],
    "simulate --params": lambda f, out: ["simulate", "--table-speed", "1", "--params", f],
    "simulate --profile-file": lambda f, out: ["simulate", "--profile", "csv",
                                               "--profile-file", f],
    "creep --params": lambda f, out: ["creep", "--params", f],
    "calibrate --params": lambda f, out: ["calibrate", "--params", f],
    "reproduce --params": lambda f, out: ["reproduce", "--params", f, "--out", str(out / "r")],
    "stiffness --params": lambda f, out: ["stiffness", "--params", f],
    "friction --params": lambda f, out: ["friction", "--params", f],
    "identify static": lambda f, out: ["identify", "static", f],
    "identify dynamic": lambda f, out: ["identify", "dynamic", f],
    "identify merge": lambda f, out: ["identify", "merge", f, "--out", str(out / "m.toml")],
    "analyze": lambda f, out: ["analyze", f],
    "fit": lambda f, out: ["fit", f, "--free", "table.mass", "--out", str(out / "m.toml")],
    "fit --params": lambda f, out: ["fit", f, "--free", "table.mass", "--params", f],
    "predict": lambda f, out: ["predict", f],
    "validate": lambda f, out: ["validate", f, f],
    "sensitivity --params": lambda f, out: ["sensitivity", "--params", f],
}

BAD_FILES = ["empty.csv", "blank-and-comments.csv", "binary.dat", "données µ✓.csv",
             "huge-gap.csv", "deep.toml", "new\nline.csv", "header-only.csv", "ragged.csv",
             "folder.csv", "missing.csv"]


@pytest.mark.parametrize("bad", BAD_FILES, ids=[b.replace("\n", "\\n") for b in BAD_FILES])
@pytest.mark.parametrize("command", list(COMMANDS))
def test_every_command_refuses_every_bad_file(corpus: dict[str, Path], tmp_path: Path,
                                              command: str, bad: str) -> None:
    before = _digest(corpus)
    path = corpus.get(bad, corpus["empty.csv"].parent / bad)
    result = _invoke(COMMANDS[command](str(path), tmp_path))
    _one_line_error(result, shown(path.name))
    assert _digest(corpus) == before
    assert not (tmp_path / "r").exists() and not (tmp_path / "m.toml").exists()


# ------------------------------------------------------------------ unusable outputs


@pytest.fixture()
def inputs(tmp_path: Path) -> dict[str, Path]:
    static = tmp_path / "victim.csv"
    static.write_text("speed [mm/s],force [N]\n" + _static_rows(), encoding="utf-8")
    params = tmp_path / "params.toml"
    params.write_text(dumps(PARAMS), encoding="utf-8")
    trace = tmp_path / "trace.csv"
    t = np.arange(0, 4, 1e-3)
    trace.write_text("time,position\n" + "".join(f"{a:.6g},{1.5 * a:.9g}\n" for a in t),
                     encoding="utf-8")
    blocker = tmp_path / "a-file"
    blocker.write_text("x", encoding="utf-8")
    (tmp_path / "existing.csv").write_text("mine\n", encoding="utf-8")
    return {"static": static, "params": params, "trace": trace, "blocker": blocker}


UNUSABLE = {
    "folder": lambda d, ext: str(d),
    "under-a-file": lambda d, ext: str(d / "a-file" / f"out{ext}"),
    "missing-folder": lambda d, ext: str(d / "no" / "such" / f"out{ext}"),
    "read-only": lambda d, ext: f"/proc/feeddrive-out{ext}",
}

WRITERS: dict[str, Callable[[dict[str, Path], str], list[str]]] = {
    "simulate --output": lambda i, o: ["simulate", "--table-speed", "1", "--output", o],
    "simulate --plot": lambda i, o: ["simulate", "--table-speed", "1", "--plot", o],
    "calibrate --out": lambda i, o: ["calibrate", "--out", o],
    "identify static --out": lambda i, o: ["identify", "static", str(i["static"]), "--out", o],
    "identify static --plot": lambda i, o: ["identify", "static", str(i["static"]), "--plot",
                                            o],
    "identify merge --out": lambda i, o: ["identify", "merge", str(i["params"]), "--out", o],
    "analyze --plot": lambda i, o: ["analyze", str(i["trace"]), "--plot", o],
    "friction --plot": lambda i, o: ["friction", "--plot", o],
    "reproduce --out": lambda i, o: ["reproduce", "--out", o],
    "fit --out": lambda i, o: ["fit", str(i["trace"]), "--free", "table.mass",
                               "--command-speed", "1.5", "--out", o],
    "fit --plot": lambda i, o: ["fit", str(i["trace"]), "--free", "table.mass",
                                "--command-speed", "1.5", "--plot", o],
    "predict --plot": lambda i, o: ["predict", str(i["params"]), "--plot", o],
    "sensitivity --plot": lambda i, o: ["sensitivity", "--plot", o],
}


@pytest.mark.parametrize("where", list(UNUSABLE))
@pytest.mark.parametrize("writer", list(WRITERS))
def test_unusable_outputs_are_refused_before_any_work(inputs: dict[str, Path], tmp_path: Path,
                                                      writer: str, where: str) -> None:
    ext = ".toml" if "--out" in writer else ".png" if "plot" in writer else ".csv"
    target = UNUSABLE[where](tmp_path, ext)
    if writer == "reproduce --out":
        if where == "folder":
            target = str(inputs["blocker"])  # reproduce --out pointing at a file
        else:
            target = target.removesuffix(ext)
    before = _digest(inputs)
    # refused before the simulation or fit: exit status 2 is "refused before any work"
    # (README), and no simulation starts (issue 24 item 14: was a 5-s wall-clock bound)
    import importlib

    sim_module = importlib.import_module("feeddrive.engine.simulate")

    def never(*_: Any, **__: Any) -> Any:
        raise AssertionError("simulated although refused")

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(sim_module.Simulation, "run", never)
        mp.setattr(sim_module, "simulate", never)
        result = _invoke(WRITERS[writer](inputs, target))
    line = _one_line_error(result, shown(target))
    assert result.exit_code == 2, line
    assert _digest(inputs) == before
    assert not (tmp_path / "no").exists()


@pytest.mark.parametrize("writer", ["identify static --out", "identify static --plot"])
def test_an_input_is_never_an_output(inputs: dict[str, Path], writer: str) -> None:
    before = inputs["static"].read_bytes()
    for extra in ([], ["--force"]):
        result = _invoke([*WRITERS[writer](inputs, str(inputs["static"])), *extra])
        assert "is an input of this command" in _one_line_error(result, "victim.csv")
    assert inputs["static"].read_bytes() == before


def test_existing_output_needs_force(inputs: dict[str, Path], tmp_path: Path) -> None:
    out = tmp_path / "existing.csv"
    result = _invoke(["simulate", "--table-speed", "1", "--duration", "1", "--output",
                      str(out)])
    assert "exists; pass --force" in _one_line_error(result, str(out))
    assert out.read_text(encoding="utf-8") == "mine\n"
    result = _invoke(["simulate", "--table-speed", "1", "--duration", "1", "--output",
                      str(out), "--force"])
    assert result.exit_code == 0, result.output
    assert out.read_text(encoding="utf-8").splitlines()[1].startswith("time [s],")


def test_newline_in_a_data_file_name_cannot_reach_the_parameters(tmp_path: Path) -> None:
    """End to end through ``identify merge`` (the injection of the issue)."""
    name = 'x.csv\n[table]\nmass = 99.0\n# '
    data = tmp_path / name
    data.write_text("speed [mm/s],force [N]\n" + _static_rows(), encoding="utf-8")
    frag = tmp_path / "frag.toml"
    r = _invoke(["identify", "static", str(data), "--out", str(frag)])
    assert r.exit_code == 0, r.output
    merged = tmp_path / "merged.toml"
    r = _invoke(["identify", "merge", str(frag), "--out", str(merged)])
    assert r.exit_code == 0, r.output
    r = _invoke(["params", "check", str(merged)])
    assert r.exit_code == 0, r.output
    from feeddrive.parameters import load
    assert load(merged).table.mass == PARAMS.table.mass


# ------------------------------------------------------------------ memory-bounded


_LIMITED = """
import resource, sys
resource.setrlimit(resource.RLIMIT_AS, ({limit}, {limit}))
from feeddrive.cli import app
sys.argv = ["feeddrive", *sys.argv[1:]]
app()
"""
LIMIT = 3 << 30  # bytes of address space; the old code needed > 8 GB for these


@pytest.mark.parametrize("case", ["analyze-gap", "deep-toml", "huge-duration"])
def test_memory_bounded_in_a_subprocess(corpus: dict[str, Path], case: str) -> None:
    args = {"analyze-gap": ["analyze", str(corpus["huge-gap.csv"])],
            "deep-toml": ["params", "check", str(corpus["deep.toml"])],
            "huge-duration": ["simulate", "--table-speed", "1", "--duration", "1e9"]}[case]
    env = {**os.environ, "COLUMNS": "200"}
    r = subprocess.run([sys.executable, "-c", _LIMITED.format(limit=LIMIT), *args],
                       capture_output=True, text=True, timeout=600, env=env)  # a hang guard
    assert r.returncode != 0
    assert "Traceback" not in r.stderr and "MemoryError" not in r.stderr, r.stderr[-2000:]
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), r.stderr
