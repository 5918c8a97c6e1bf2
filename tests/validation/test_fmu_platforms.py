"""The FMU on every platform (issue 38 item 1): `export fmu --platform linux64,win64` builds
each binary with a compiler found for it (MinGW-w64 for Win64) and refuses, in one line, a
platform without one; the Win64 DLL exports exactly the FMI functions and, run under Wine by
a small MinGW-built importer (tests/validation/fmu_harness.c), gives the linux64 trace; the
FMU's own sources/CMakeLists.txt, the command line of its documentation/index.html and fmpy's
build_platform_binary rebuild linux64 with the same trace.

MinGW-w64, Wine and CMake come from Debian (the README's test command installs them); without
them those tests are skipped, saying so."""

from __future__ import annotations

import html
import os
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmu_helpers import SharedExports
from typer.testing import CliRunner

from feeddrive.cli import app
from feeddrive.fmu import export_fmu
from feeddrive.fmu.platforms import PLATFORMS, compile_line, find_compiler
from feeddrive.parameters import preset

fmpy = pytest.importorskip("fmpy")
HARNESS = Path(__file__).parent / "fmu_harness.c"
MINGW = shutil.which("x86_64-w64-mingw32-gcc")
OBJDUMP = shutil.which("x86_64-w64-mingw32-objdump")
WINE = shutil.which("wine")
CMAKE = shutil.which("cmake", path="/usr/bin") or shutil.which("cmake")
needs_mingw = pytest.mark.skipif(
    MINGW is None or OBJDUMP is None,
    reason="MinGW-w64 is not installed (apt-get install -y mingw-w64)")
needs_wine = pytest.mark.skipif(
    WINE is None, reason="Wine is not installed (apt-get install -y wine64 wine)")
needs_cmake = pytest.mark.skipif(CMAKE is None,
                                 reason="CMake is not installed (apt-get install -y cmake)")
pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="the build machine is Linux")
#: the issue's scenario: CDFS, 2 mm/s after a 0.1-s ramp, 10 s in 1-ms communication steps
SPEED, RAMP, STEP, STOP = 2e-3, 0.1, 1e-3, 10.0


def _one_line_error(result) -> str:  # type: ignore[no-untyped-def]
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    return str(lines[0])


# ---------------------------------------------------------------- refusals
def test_a_platform_without_a_compiler_is_refused_in_one_line(tmp_path: Path) -> None:
    if any(shutil.which(cc) for cc in PLATFORMS["darwin64"].cross) or os.environ.get(
            "CC_DARWIN64"):
        pytest.skip("this machine has a macOS cross compiler")
    out = tmp_path / "c.fmu"
    res = CliRunner().invoke(app, ["export", "fmu", "--drive", "cdfs", "--platform",
                                   "linux64,darwin64", "--out", str(out)])
    line = _one_line_error(res)
    assert line.startswith("error: --platform: no C compiler for darwin64 on this machine")
    assert "o64-clang" in line and "documentation/index.html" in line
    assert not out.exists()
    res = CliRunner().invoke(app, ["export", "fmu", "--drive", "cdfs", "--platform", "macos",
                                   "--out", str(out)])
    assert _one_line_error(res) == ("error: --platform = 'macos': expected a comma-separated "
                                    "list of linux64, win64, darwin64")


def test_a_named_compiler_that_is_missing_is_refused(tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CC_WIN64", "no-such-mingw-xyz")
    res = CliRunner().invoke(app, ["export", "fmu", "--drive", "cdfs", "--platform", "win64",
                                   "--out", str(tmp_path / "c.fmu")])
    assert "CC_WIN64 = 'no-such-mingw-xyz'" in _one_line_error(res)


# ---------------------------------------------------------------- the multi-platform FMU
@pytest.fixture(scope="module")
def fmus(tmp_path_factory: pytest.TempPathFactory) -> dict[int, Path]:
    if MINGW is None:
        pytest.skip("MinGW-w64 is not installed (apt-get install -y mingw-w64)")
    folder = tmp_path_factory.mktemp("platforms")
    out = {}
    for fmi in (2, 3):
        path = folder / f"cdfs-{fmi}.fmu"
        res = CliRunner().invoke(app, ["export", "fmu", "--drive", "cdfs", "--fmi", str(fmi),
                                       "--platform", "linux64,win64", "--out", str(path)])
        assert res.exit_code == 0, res.output
        out[fmi] = path
    return out


def _unzip(path: Path, folder: Path) -> Path:
    with zipfile.ZipFile(path) as zf:
        zf.extractall(folder)
    return folder


@needs_mingw
@pytest.mark.parametrize("fmi", [2, 3])
def test_multi_platform_fmu_validates_and_carries_each_binary(fmus: dict, fmi: int) -> None:
    from fmpy.validation import validate_fmu

    path = fmus[fmi]
    assert validate_fmu(str(path)) == []
    folders = ("linux64", "win64") if fmi == 2 else ("x86_64-linux", "x86_64-windows")
    with zipfile.ZipFile(path) as zf:
        names = set(zf.namelist())
    assert {f"binaries/{folders[0]}/feeddrive_cdfs.so",
            f"binaries/{folders[1]}/feeddrive_cdfs.dll"} <= names
    assert {"sources/fmu.c", "sources/CMakeLists.txt", "documentation/index.html"} <= names
    assert "documentation/building.txt" not in names
    assert not [n for n in names if n.startswith("binaries/") and not n.startswith(
        tuple(f"binaries/{f}/" for f in folders))]


def _declared_functions(header: Path, fmi: int) -> set[str]:
    """The functions an FMI header declares for export (``FMI2_Export fmi2…TYPE fmi2…;``)."""
    text = header.read_text(encoding="utf-8")
    return set(re.findall(rf"FMI{fmi}_Export\s+fmi{fmi}\w+TYPE\s+(fmi{fmi}\w+)\s*;", text))


@needs_mingw
@pytest.mark.parametrize("fmi", [2, 3])
def test_the_dll_exports_exactly_the_fmi_functions(fmus: dict, fmi: int,
                                                   tmp_path: Path) -> None:
    """The export table holds the functions the FMI header declares (44 for FMI 2.0), nothing
    of the model; the DLL imports only KERNEL32.dll and msvcrt.dll (no libgcc DLL)."""
    folder = _unzip(fmus[fmi], tmp_path)
    dll = next((folder / "binaries").rglob("*.dll"))
    dump = subprocess.run([str(OBJDUMP), "-p", str(dll)], capture_output=True, text=True,
                          check=True).stdout
    table = dump.split("[Ordinal/Name Pointer] Table", 1)[1].split("\n\n", 1)[0]
    exported = set(re.findall(r"\]\s+(\w+)", table))
    declared = _declared_functions(folder / "sources" / f"fmi{fmi}Functions.h", fmi)
    assert exported == declared
    if fmi == 2:
        assert len(exported) == 44
    assert set(re.findall(r"DLL Name: (\S+)", dump)) == {"KERNEL32.dll", "msvcrt.dll"}


# ---------------------------------------------------------------- traces
def _build_harness(fmi: int, sources: Path, out: Path, compiler: list[str]) -> Path:
    windows = "mingw32" in compiler[0]
    exe = out.with_suffix(".exe") if windows else out
    libs = [] if windows else ["-ldl", "-Wl,--no-as-needed", "-lm"]
    subprocess.run([*compiler, "-std=c99", "-O2", f"-DFMI_VERSION={fmi}", f"-I{sources}",
                    "-o", str(exe), str(HARNESS), *libs], check=True, capture_output=True)
    return exe


def _trace(harness: Path, library: Path, fmu_dir: Path, wine_env: dict | None = None
           ) -> np.ndarray:
    from fmpy import read_model_description

    md = read_model_description(str(fmu_dir / "modelDescription.xml"))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    args = [str(library), md.guid, str(vr["table_speed_reference"]),
            str(vr["table_position"]), repr(SPEED), repr(RAMP), repr(STEP), repr(STOP)]
    cmd = [str(WINE), str(harness), *args] if wine_env is not None else [str(harness), *args]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False,
                          env=wine_env, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    trace = np.array([float(x) for x in proc.stdout.split()])
    assert trace.size == round(STOP / STEP) + 1
    return trace


def _deviation(a: np.ndarray, b: np.ndarray) -> float:
    """max |Δx| over the stroke |x(10 s) − x(0)|."""
    return float(np.max(np.abs(a - b)) / abs(b[-1] - b[0]))


@pytest.fixture(scope="module")
def wine_env(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """A Wine prefix of the test session's own (made on first use, ≈ 10 s)."""
    env = dict(os.environ, WINEPREFIX=str(tmp_path_factory.mktemp("wine") / "prefix"),
               WINEDEBUG="-all", WINEDLLOVERRIDES="mscoree,mshtml=")
    return env


@pytest.mark.slow
@needs_mingw
@needs_wine
@pytest.mark.parametrize("fmi", [2, 3])
def test_win64_binary_under_wine_follows_linux64(fmus: dict, fmi: int, tmp_path: Path,
                                                 wine_env: dict) -> None:
    """10 s of the CDFS at 2 mm/s (0.1-s ramp, 1-ms steps): the DLL run under Wine by the
    MinGW-built harness and the .so run by the same harness built natively; the issue asks
    for 1e-12 of the stroke (measured: 0, bit-identical traces, gcc 12 / MinGW-w64 gcc 12)."""
    folder = _unzip(fmus[fmi], tmp_path / "fmu")
    sources = folder / "sources"
    native = _build_harness(fmi, sources, tmp_path / "harness", find_compiler())
    windows = _build_harness(fmi, sources, tmp_path / "harness-win", [str(MINGW)])
    so = next((folder / "binaries").rglob("*.so"))
    dll = next((folder / "binaries").rglob("*.dll"))
    linux = _trace(native, so, folder)
    win = _trace(windows, dll, folder, wine_env)
    assert abs(linux[-1] - linux[0]) == pytest.approx(SPEED * (STOP - RAMP / 2), rel=1e-2)
    assert _deviation(win, linux) <= 1e-12


# ---------------------------------------------------------------- rebuilding from sources
def _run_native(fmi: int, folder: Path, library: Path, tmp_path: Path) -> np.ndarray:
    harness = _build_harness(fmi, folder / "sources", tmp_path / f"h{fmi}", find_compiler())
    return _trace(harness, library, folder)


@pytest.mark.slow
@needs_cmake
@pytest.mark.parametrize("fmi", [2, 3])
def test_cmake_and_fmpy_rebuild_linux64_with_the_same_trace(tmp_path: Path, fmi: int,
                                                            shared_fmus: SharedExports) -> None:
    """The binary removed, rebuilt by the FMU's sources/CMakeLists.txt (cmake from apt), by the
    gcc line of its documentation/index.html and by fmpy's build_platform_binary: each gives
    the shipped binary's trace to 1e-15 of the stroke (measured: bit-identical)."""
    from fmpy.build import build_platform_binary

    path = shared_fmus.drive(preset("wang2021"), "cdfs", fmi=fmi).path  # read, never changed
    shipped = _unzip(path, tmp_path / "shipped")
    reference = _run_native(fmi, shipped, next((shipped / "binaries").rglob("*.so")), tmp_path)
    # CMake, as the file's own header says
    made = _unzip(path, tmp_path / "cmake")
    shutil.rmtree(made / "binaries")
    for args in (["-S", "sources", "-B", "build"],
                 ["--build", "build", "--config", "Release", "--target", "install"]):
        proc = subprocess.run([str(CMAKE), *args], cwd=made, capture_output=True, text=True)
        assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    folder = "linux64" if fmi == 2 else "x86_64-linux"
    rebuilt = made / "binaries" / folder / "feeddrive_cdfs.so"
    assert _deviation(_run_native(fmi, made, rebuilt, tmp_path), reference) <= 1e-15
    # the gcc line of documentation/index.html, as printed, in sources/
    page = html.unescape((shipped / "documentation" / "index.html").read_text(encoding="utf-8"))
    line = next(b for b in re.findall(r"<pre><code>(.*?)</code></pre>", page, flags=re.S)
                if b.startswith("gcc "))
    assert line == compile_line("linux64", "feeddrive_cdfs")
    byhand = _unzip(path, tmp_path / "byhand")
    subprocess.run(line.split(), cwd=byhand / "sources", check=True, capture_output=True)
    lib = byhand / "sources" / "feeddrive_cdfs.so"
    assert _deviation(_run_native(fmi, byhand, lib, tmp_path), reference) <= 1e-15
    # fmpy (its own CMake project and FMI headers, -O3)
    viafmpy = _unzip(path, tmp_path / "fmpy")
    shutil.rmtree(viafmpy / "binaries")
    (tmp_path / "fmpy-build").mkdir()
    build_platform_binary(viafmpy.resolve(), build_dir=tmp_path / "fmpy-build")
    rebuilt = viafmpy / "binaries" / folder / "feeddrive_cdfs.so"
    assert _deviation(_run_native(fmi, viafmpy, rebuilt, tmp_path), reference) <= 1e-15


def test_the_documentation_names_every_rebuild_route(tmp_path: Path) -> None:
    """documentation/index.html: CMake, gcc/clang, MinGW, MSVC, MATLAB's
    fmudialog.compileFMUSources and fmpy's build_platform_binary, with the export's flags."""
    path = tmp_path / "lm.fmu"
    export_fmu(preset("linear-motor-example"), "linear-motor", path, fmi=3)
    with zipfile.ZipFile(path) as zf:
        page = html.unescape(zf.read("documentation/index.html").decode("utf-8"))
        cmake = zf.read("sources/CMakeLists.txt").decode("utf-8")
    ident = "feeddrive_linear_motor"
    for text in (compile_line("linux64", ident, "gcc"), compile_line("darwin64", ident, "clang"),
                 compile_line("win64", ident, "x86_64-w64-mingw32-gcc"),
                 f"cl /nologo /O2 /fp:precise /LD /I. /Fe{ident}.dll fmu.c",
                 f"fmudialog.compileFMUSources('{ident}.fmu')", "build_platform_binary(folder)",
                 "cmake -S sources -B build", "binaries/x86_64-linux/"):
        assert text in page, text
    assert f"add_library({ident} SHARED fmu.c)" in cmake
    assert "-O2 -ffp-contract=off" in cmake and "/fp:precise" in cmake


@pytest.mark.parametrize(("fmi", "kind"), [(2, "cs"), (3, "me")])
def test_the_sources_compile_without_a_warning(tmp_path: Path, fmi: int, kind: str,
                                               shared_fmus: SharedExports) -> None:
    """sources/fmu.c under -std=c99 -Wall -Wextra -pedantic -Werror with this machine's
    compiler and, where installed, MinGW-w64: no warning (the model exchange source carries
    the model's tangent)."""
    path = shared_fmus.drive(preset("wang2021"), "ddfs", fmi=fmi, kind=kind).path
    src = _unzip(path, tmp_path / "u") / "sources"
    strict = ["-std=c99", "-O2", "-Wall", "-Wextra", "-pedantic", "-Werror", "-shared"]
    for cc, out in (([*find_compiler(), "-fPIC"], "x.so"),
                    *((([str(MINGW)], "x.dll"),) if MINGW else ())):
        proc = subprocess.run([*cc, *strict, "-o", out, "fmu.c", "-lm"], cwd=src,
                              capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr[-3000:]
