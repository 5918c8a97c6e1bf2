"""The generated C of every registered topology compiles for Windows (issue 42 item 2, last
sentence): with MinGW-w64 (``x86_64-w64-mingw32-gcc``, a proxy for a Windows compiler; MSVC is
not claimed) and the strict warning set ``-std=c99 -Wall -Wextra -Werror -pedantic``, both the
model with the solver blocks (``c_model_source`` + ``c_solver_source``) and the FMU's whole
translation unit (``fmu.c`` with its FMI headers).  tests/validation/test_fmu_platforms.py links
and runs the CDFS FMU's Win64 DLL; this covers every topology's text, warnings as errors.

MinGW-w64 comes from Debian (the README's test command installs it); without it these tests are
skipped, saying so."""

from __future__ import annotations

import shutil
import subprocess
from importlib import resources
from pathlib import Path

import pytest

import feeddrive as fd
from feeddrive.backends.c_backend import STRICT_FLAGS, c_model_source, c_solver_source
from feeddrive.model.mechanisms import drive_names, mechanism

MINGW = shutil.which("x86_64-w64-mingw32-gcc")
pytestmark = pytest.mark.skipif(
    MINGW is None, reason="MinGW-w64 is not installed (apt-get install -y mingw-w64)")


def _compile(folder: Path, files: dict[str, str]) -> None:
    """Compile the first file to an object with MinGW and the strict flags; fail with the
    compiler's output."""
    assert MINGW is not None
    for name, text in files.items():
        (folder / name).write_text(text, encoding="utf-8")
    src = folder / next(iter(files))
    proc = subprocess.run([MINGW, *STRICT_FLAGS, f"-I{folder}", "-c", "-o",
                           str(src.with_suffix(".o")), str(src)],
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    assert src.with_suffix(".o").stat().st_size > 0


def _speeds(drive: str) -> tuple[float, float]:
    """A table speed and a nut speed the topology takes (only the DDFS moves its nut) [m/s]."""
    return 0.5e-3, (16e-3 if drive == "ddfs" else 0.0)


@pytest.mark.parametrize("drive", drive_names())
def test_model_and_solver_c_compile_with_mingw_pedantic(drive: str, tmp_path: Path) -> None:
    parameters = fd.preset(mechanism(drive).example_preset)
    model = fd.DriveSystem(parameters, drive, 0.4).model(fd.ConstantSpeed(*_speeds(drive)))
    _compile(tmp_path, {"model.c": c_model_source(model) + c_solver_source()})


@pytest.mark.parametrize("drive", drive_names())
def test_the_fmu_translation_unit_compiles_with_mingw_pedantic(drive: str,
                                                               tmp_path: Path) -> None:
    from feeddrive.fmu.build import HEADERS, fmu_source
    from feeddrive.fmu.description import variables
    from feeddrive.fmu.model import build

    fm = build(fd.preset(mechanism(drive).example_preset), drive, 0.4)
    # FMI 3 model exchange for one drive, FMI 2 co-simulation for the others: both headers
    # and both kinds are compiled, each topology once
    fmi, kind = (3, "me") if drive == drive_names()[0] else (2, "cs")
    include = resources.files("feeddrive.fmu").joinpath("include")
    files = {"fmu.c": fmu_source(fm, variables(fm, kind), fmi=fmi, kind=kind,
                                 token="{00000000-0000-0000-0000-000000000042}"),
             **{h: include.joinpath(h).read_text(encoding="utf-8") for h in HEADERS[fmi]}}
    _compile(tmp_path, files)


def test_the_engine_driver_unit_compiles_with_mingw_pedantic(tmp_path: Path) -> None:
    """The C build of the engine (issue 42 items 1–2): every method's driver, the event
    location, the eigen-analysis and the linearisations' functions — one unit for every
    model, which it reaches through its table."""
    from feeddrive.backends.c_engine import driver_source

    _compile(tmp_path, {"drivers.c": driver_source()})


@pytest.mark.parametrize("drive", drive_names())
def test_the_engine_model_unit_compiles_with_mingw_pedantic(drive: str, tmp_path: Path) -> None:
    """A model's unit of the C engine: its kernels and the table the driver unit takes."""
    from feeddrive.backends.c_engine import model_source

    parameters = fd.preset(mechanism(drive).example_preset)
    model = fd.DriveSystem(parameters, drive, 0.4).model(fd.ConstantSpeed(*_speeds(drive)))
    _compile(tmp_path, {"model.c": model_source(model)})
