"""docs/extending.md describes the code it names: files, classes, kernels, laws, topologies."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import feeddrive
from feeddrive.model import drive_names, law_names
from feeddrive.model.loops import AXIS_PARAMS

ROOT = Path(__file__).resolve().parents[2]
DOC = (ROOT / "docs" / "extending.md").read_text(encoding="utf-8")


def test_every_source_path_in_the_doc_exists() -> None:
    paths = set(re.findall(r"(?:src/feeddrive/|model/|solvers/|presets/|parameters/)"
                           r"[\w/]+\.py", DOC))
    assert paths
    pkg = ROOT / "src" / "feeddrive"
    for p in paths:
        rel = p.removeprefix("src/feeddrive/")
        assert (pkg / rel).is_file(), p


def test_names_in_the_doc_exist_in_the_code() -> None:
    from feeddrive.model import codegen, disturbances, loops
    from feeddrive.model.friction import dahl
    from feeddrive.model.mechanisms import base
    from feeddrive.solvers import driver, driver_text

    assert hasattr(dahl, "dahl_kernel") and hasattr(dahl, "Dahl")
    assert hasattr(codegen, "Builder") and hasattr(base, "Mechanism")
    assert hasattr(loops, "emit_cascade") and hasattr(loops, "speed_command")
    assert hasattr(disturbances, "harmonics") and hasattr(driver, "driver_template")
    assert hasattr(driver_text, "specialise") and {"LAND", "DENSE", "COMM"} <= set(dir(driver))
    assert "SPEED_MODE" in dir(loops) and "speed_mode" in AXIS_PARAMS
    assert callable(feeddrive.register_friction_law)
    for law in ("dahl", "toy_viscous"):
        assert f'"{law}"' in DOC or f"`{law}`" in DOC or law in DOC
    assert {"lugre", "stribeck", "dahl", "none"} <= set(law_names())
    assert "linear-motor" in drive_names() and '"linear-motor"' in DOC


def test_the_quoted_linear_motor_diff_touches_four_package_files() -> None:
    block = DOC.split("git show 88c60ba --stat")[1].split("```")[1]
    files = re.findall(r"src/feeddrive/\S+\.py", block)
    assert len(files) == 4
    assert "4 files changed" in block


def test_the_quoted_gms_diff_touches_one_package_file() -> None:
    """Issue 19's GMS acceptance (≤ 2 package files), as the doc quotes the commit."""
    block = DOC.split("git show 5e1a742 --stat")[1].split("```")[1]
    assert re.findall(r"src/feeddrive/\S+\.py", block) == [
        "src/feeddrive/model/friction/gms.py"]
    from feeddrive.model.friction import gms

    assert gms.GMS.parameters_class is gms.GMSParameters
    for name in ("SIGMA0", "COULOMB", "VISCOUS"):
        assert name in DOC
    assert "gms" in law_names()
    if (ROOT / ".git").exists() and shutil.which("git"):  # the quote is the real diff
        real = subprocess.run(["git", "show", "--name-only", "--format=", "5e1a742"],
                              cwd=ROOT, capture_output=True, text=True)
        if real.returncode == 0:  # a shallow clone may not hold the commit
            assert [f for f in real.stdout.split() if f.startswith("src/feeddrive/")] == [
                "src/feeddrive/model/friction/gms.py"]


def test_the_quoted_part_diff_touches_one_package_file() -> None:
    """Issue 19's "a loop with its own rate" (≤ 3 package files), as the doc quotes it."""
    block = DOC.split("git show 8278df3 --stat")[1].split("```")[1]
    assert "acceleration_feedforward.py" in block and "2 files changed" in block
    from feeddrive.model.parts.acceleration_feedforward import AccelerationFeedforward

    assert AccelerationFeedforward(gain=1.6, period=1e-3).schedule() == (("period", 1e-3),)
    if (ROOT / ".git").exists() and shutil.which("git"):
        real = subprocess.run(["git", "show", "--name-only", "--format=", "8278df3"],
                              cwd=ROOT, capture_output=True, text=True)
        if real.returncode == 0:
            assert [f for f in real.stdout.split() if f.startswith("src/feeddrive/")] == [
                "src/feeddrive/model/parts/acceleration_feedforward.py"]


def test_the_quoted_rack_pinion_diff_touches_two_package_files() -> None:
    """Issue 19's rack-and-pinion acceptance (≤ 3 package files), as the doc quotes it."""
    block = DOC.split("git show caab0d2 --stat")[1].split("```")[1]
    files = re.findall(r"src/feeddrive/\S+\.py", block)
    assert files == ["src/feeddrive/model/mechanisms/rack_pinion.py",
                     "src/feeddrive/presets/rack_pinion.py"]
    assert "rack-pinion" in drive_names()
    if (ROOT / ".git").exists() and shutil.which("git"):
        real = subprocess.run(["git", "show", "--name-only", "--format=", "caab0d2"],
                              cwd=ROOT, capture_output=True, text=True)
        if real.returncode == 0:
            assert [f for f in real.stdout.split() if f.startswith("src/feeddrive/")] == files
