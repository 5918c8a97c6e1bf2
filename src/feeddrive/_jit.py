"""The one compilation setting for every numba kernel of the package.

``cache=True``: compiled code is stored on disk, so a second process does not recompile.
numba invalidates a cached function only when *its own* source file changes, not when a
kernel it calls (in another module) changes; a stale cache
would then run old physics silently.  So the cache lives in a folder named after a hash of
all kernel sources: any change to any of them starts a fresh cache.

``error_model="numpy"``: float division follows IEEE (no Python ZeroDivisionError checks),
about 25 % faster per right-hand-side evaluation; non-finite states are caught by the solver.

Loading from the cache skips numba's *refresh* of its compiler (:class:`_LoadingCache`).

``nogil=True``: a compiled call releases Python's global interpreter lock while it runs, so
other threads of the process keep going during a long solver call (the explorer's server
answers its page's polls while a run computes: issue 23; measured in
benchmarks/bench_explore_polls.py).  Kernels touch only their own arrays, never Python
objects, so nothing else changes.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from numba import config as _numba_config
from numba import njit
from numba.core.caching import FunctionCache
from numba.core.runtime import rtsys

config: Any = _numba_config  # CACHE_DIR is set dynamically by numba; untyped

_HERE = Path(__file__).resolve().parent
_KERNEL_SOURCES = ("_jit.py",)  # model/ holds friction, reference
_KERNEL_FOLDERS = ("model", "solvers", "fmu")


def _kernel_files() -> list[Path]:
    files = [_HERE / name for name in _KERNEL_SOURCES]
    for folder in _KERNEL_FOLDERS:
        files += sorted((_HERE / folder).rglob("*.py"))
    return files


def _source_digest() -> str:
    digest = hashlib.sha256()
    for path in _kernel_files():
        digest.update(path.relative_to(_HERE).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


SOURCE_DIGEST = _source_digest()
#: the kernels' source hash: names the compile cache and keys stored results
#: (feeddrive.io.json_store)
KERNEL_HASH = SOURCE_DIGEST


def _cache_dir() -> str:
    root = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(Path.home(), ".cache"), "feeddrive")
    return os.path.join(root, f"numba-{SOURCE_DIGEST}")


CACHE_DIR = _cache_dir()
_CACHE_DIR = CACHE_DIR


class _LoadingCache(FunctionCache):
    """numba's on-disk cache of one function, loading without refreshing the compiler.

    Before numba loads a cached function it *refreshes* its target context: it imports
    every lowering module it has (``numba.np.linalg``, which imports ``scipy.linalg``,
    ``numba.typed`` …) and installs their implementations and typing templates — what a
    compilation needs, not a load: the cached object code is linked already, and it needs
    the runtime's symbols only (``rtsys.initialize``, as the refresh does first).  That
    refresh cost a fresh process more than its import of numba (0.3–0.4 s CPU, issue 21
    item 4).  A compilation still refreshes in full (numba's compiler does it first), so a
    cache miss, or any later compilation, is unchanged.
    """

    def load_overload(self, sig: Any, target_context: Any) -> Any:
        rtsys.initialize(target_context)
        with self._guard_against_spurious_io_errors():
            return self._load_overload(sig, target_context)


def _compiled(**options: Any) -> Callable[[Callable[..., Any]], Any]:
    def decorate(fn: Callable[..., Any]) -> Any:
        previous = config.CACHE_DIR
        config.CACHE_DIR = _CACHE_DIR  # read once, when the dispatcher sets up its cache
        try:
            # cache=True, with the loading cache: what numba's enable_caching() does with its
            # own class (one cache object, not numba's made and then replaced)
            dispatcher = njit(error_model="numpy", nogil=True, **options)(fn)
            dispatcher._cache = _LoadingCache(fn)
            return dispatcher
        finally:
            config.CACHE_DIR = previous

    return decorate


kernel = _compiled()
inline_kernel = _compiled(inline="always")
