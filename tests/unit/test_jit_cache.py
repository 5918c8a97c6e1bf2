"""Guards the stale-numba-cache bug: numba re-compiles a cached function only when its own
file changes, so a change to a kernel it calls in another module ran old code (found when a
new hollow-motor option in control.py had no effect through the cached solver)."""

from __future__ import annotations

from pathlib import Path

import feeddrive
from feeddrive import _jit

PKG = Path(feeddrive.__file__).resolve().parent


def test_every_kernel_module_is_in_the_cache_hash() -> None:
    defining = {str(p.relative_to(PKG)) for p in PKG.rglob("*.py")
                if "@kernel" in p.read_text() or "@inline_kernel" in p.read_text()}
    assert defining <= set(_jit._KERNEL_SOURCES)
    assert "layout.py" in _jit._KERNEL_SOURCES  # compile-time constants live there


def test_cache_folder_follows_the_sources(monkeypatch, tmp_path) -> None:
    fake = tmp_path / "pkg"
    for name in _jit._KERNEL_SOURCES:
        (fake / name).parent.mkdir(parents=True, exist_ok=True)
        (fake / name).write_text((PKG / name).read_text())
    monkeypatch.setattr(_jit, "_HERE", fake)
    before = _jit._cache_dir()
    (fake / "control.py").write_text((PKG / "control.py").read_text() + "\n# changed\n")
    assert _jit._cache_dir() != before
