"""The one compilation setting for every numba kernel of the package.

``cache=True``: compiled code is stored on disk, so a second process does not recompile.
numba invalidates a cached function only when *its own* source file changes, not when a
kernel it calls (in another module) changes; a stale cache
would then run old physics silently.  So the cache lives in a folder named after a hash of
all kernel sources: any change to any of them starts a fresh cache.

``error_model="numpy"``: float division follows IEEE (no Python ZeroDivisionError checks),
about 25 % faster per right-hand-side evaluation; non-finite states are caught by the solver.

Loading from the cache skips numba's *refresh* of its compiler (``_LoadingCache``).

numba is optional (the install extra ``feeddrive[numba]``, :data:`HAVE_NUMBA`): without it
every kernel is its plain Python function (with ``py_func``, itself), and whatever runs per
step — the integrators, the linearisations' rate and Jacobian functions, the model's
auxiliary signals — runs in the engine's C build (:mod:`feeddrive.solvers.builds`).

numba is imported only when its build runs (:func:`start_numba`: no C compiler,
``FEEDDRIVE_ENGINE=numba``, a model outside the C subset).  Until then a kernel is a
:class:`LazyKernel`, which runs as its plain Python function, exactly as without numba; the C
build, the default, never needs numba, whose import was ≈ 0.17 CPU s of every process
(issue 42: 27 % of a 1-s CLI run's imports).  :func:`start_numba` imports it, makes every
kernel's dispatcher and puts the dispatchers where the kernels were (the modules' globals, so
that numba compiles calls between kernels).

``nogil=True``: a compiled call releases Python's global interpreter lock while it runs, so
other threads of the process keep going during a long solver call (the explorer's server
answers its page's polls while a run computes: issue 23; measured in
benchmarks/bench_explore_polls.py).  Kernels touch only their own arrays, never Python
objects, so nothing else changes.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import importlib
import importlib.util
import os
import sys
import threading
import types
from collections.abc import Callable, Iterator
from pathlib import Path
from types import ModuleType
from typing import Any

from ._disk import file_lock, private_folder, reason, unwritable_error, user_cache_root

#: whether numba is installed (``pip install 'feeddrive[numba]'``; found, not imported: see
#: :func:`start_numba`): without it every kernel is its plain Python function and the engine
#: runs in C (:mod:`feeddrive.solvers.builds`)
HAVE_NUMBA = importlib.util.find_spec("numba") is not None

config: Any = None  # numba's config once started (CACHE_DIR is set dynamically; untyped)

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
    root = os.environ.get("NUMBA_CACHE_DIR") or str(user_cache_root())
    return os.path.join(root, f"numba-{SOURCE_DIGEST}")


CACHE_DIR = _cache_dir()
_CACHE_DIR = CACHE_DIR


def _loading_cache_class() -> Any:
    """numba's FunctionCache loading without the refresh, ``_LoadingCache`` (made once numba is
    imported)."""
    from numba.core.caching import FunctionCache
    from numba.core.runtime import rtsys

    class _LoadingCache(FunctionCache):
        __doc__ = _LOADING_CACHE_DOC

        def load_overload(self, sig: Any, target_context: Any) -> Any:
            rtsys.initialize(target_context)
            with self._guard_against_spurious_io_errors():
                return self._load_overload(sig, target_context)

    return _LoadingCache


_LOADING_CACHE_DOC = """numba's on-disk cache of one function, loading without refreshing the
    compiler.

    Before numba loads a cached function it *refreshes* its target context: it imports
    every lowering module it has (``numba.np.linalg``, which imports ``scipy.linalg``,
    ``numba.typed`` …) and installs their implementations and typing templates — what a
    compilation needs, not a load: the cached object code is linked already, and it needs
    the runtime's symbols only (``rtsys.initialize``, as the refresh does first).  That
    refresh cost a fresh process more than its import of numba (0.3–0.4 s CPU, issue 21
    item 4).  A compilation still refreshes in full (numba's compiler does it first), so a
    cache miss, or any later compilation, is unchanged.
    """

_LOADING_CACHE: Any = None


def _loading_cache(fn: Callable[..., Any]) -> Any:
    """The on-disk cache of ``fn`` in the package's cache folder (numba reads
    ``CACHE_DIR`` once, when the cache object is made)."""
    previous = config.CACHE_DIR
    config.CACHE_DIR = _CACHE_DIR
    try:
        return _LOADING_CACHE(fn)
    finally:
        config.CACHE_DIR = previous


def _plain(fn: Callable[..., Any]) -> Any:
    """Without numba: the kernel is its Python function, with numba's ``py_func`` (itself),
    so that the C translator and the code generators read it as they read a dispatcher."""
    fn.py_func = fn  # type: ignore[attr-defined]
    return fn


def _dispatcher(fn: Callable[..., Any], options: dict[str, Any]) -> Any:
    """``fn``'s numba dispatcher, cached on disk (numba started)."""
    from numba import njit

    # cache=True, with the loading cache: what numba's enable_caching() does with its own
    # class (one cache object, not numba's made and then replaced)
    dispatcher = njit(error_model="numpy", nogil=True, **options)(fn)
    dispatcher._cache = _loading_cache(fn)
    return dispatcher


class LazyKernel:
    """A kernel before numba is started (:func:`start_numba`): called, its plain Python
    function runs (as without numba); ``py_func`` is that function, read by the C translator
    and the code generators as they read a dispatcher's.  Once numba is started a call runs
    the dispatcher, and any other attribute is the dispatcher's.

    Parameters
    ----------
    fn : callable
        The kernel's Python function.
    options : dict
        Its numba options (``inline="always"`` …).
    """

    def __init__(self, fn: Callable[..., Any], options: dict[str, Any]) -> None:
        self.py_func = fn
        self.options = options
        self.dispatcher: Any = None
        functools.update_wrapper(self, fn)

    def __call__(self, *args: Any) -> Any:
        if self.dispatcher is None:
            return self.py_func(*args)
        return self.dispatcher(*args)

    def __get__(self, obj: Any, objtype: Any = None) -> Any:
        # bound as a method where a function (and a numba dispatcher) would be; a routine
        # to inspect and to the docs' autodoc
        return self if obj is None else types.MethodType(self, obj)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__") or name in ("dispatcher", "py_func", "options"):
            raise AttributeError(name)  # introspection (inspect, copy) starts nothing
        start_numba()
        return getattr(self.dispatcher, name)

    def __reduce__(self) -> tuple[Any, ...]:  # pickled by name, as a function is
        return (_kernel_named, (self.py_func.__module__, self.py_func.__qualname__))

    def __repr__(self) -> str:
        return f"<kernel {self.py_func.__module__}.{self.py_func.__qualname__} (numba not started)>"


def _kernel_named(module: str, qualname: str) -> Any:
    obj: Any = importlib.import_module(module)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    return obj


_LAZY: list[LazyKernel] = []
_STARTED = False


def numba_started() -> bool:
    """Whether numba is imported and every kernel has its dispatcher (:func:`start_numba`).

    Returns
    -------
    bool
        True once started.
    """
    return _STARTED


def start_numba() -> None:
    """Import numba, make every kernel's dispatcher and put it where the kernel was: in the
    globals of every loaded module — the package's, its generated modules', a user's module
    that defines a friction law's kernels (numba compiles a call between kernels only to a
    dispatcher; a kernel kept elsewhere, a class attribute, calls its dispatcher).  Once per
    process; called where the numba build runs (:mod:`feeddrive.solvers.builds`) and by a
    kernel asked for a dispatcher's attribute (``signatures`` …).

    Raises
    ------
    ImportError
        numba is not installed, or does not import.
    """
    global _STARTED, config, _LOADING_CACHE
    if _STARTED:
        return
    if not HAVE_NUMBA:
        raise ImportError("numba is not installed: pip install 'feeddrive[numba]'")
    with _START_LOCK:
        if _STARTED:
            return
        from numba import config as numba_config

        config = numba_config
        _LOADING_CACHE = _loading_cache_class()
        for lazy in _LAZY:
            lazy.dispatcher = _dispatcher(lazy.py_func, lazy.options)
        for module in list(sys.modules.values()):
            space = getattr(module, "__dict__", None)
            if not isinstance(space, dict):
                continue
            for key, value in list(space.items()):
                if isinstance(value, LazyKernel):
                    space[key] = value.dispatcher
        _STARTED = True


_START_LOCK = threading.RLock()


def _compiled(**options: Any) -> Callable[[Callable[..., Any]], Any]:
    if not HAVE_NUMBA:
        return _plain

    def decorate(fn: Callable[..., Any]) -> Any:
        if _STARTED:
            return _dispatcher(fn, options)
        lazy = LazyKernel(fn, options)
        _LAZY.append(lazy)
        return lazy

    return decorate


# ``_nrt=True`` said outright: a kernel called by one compiled without numba's reference
# counting (:data:`nrt_free_kernel`) would otherwise inherit that flag from its caller, and
# one that allocates (the eigen-analysis of the modal step cap) would not compile
kernel = _compiled(_nrt=True)
inline_kernel = _compiled(inline="always", _nrt=True)
#: a kernel compiled without numba's runtime (``_nrt=False``): no reference counting of its
#: arrays — numba counts a reference at every assignment and at every argument of a call
#: it inlines (``inline="always"``), which cost the drivers, calling their pieces at every
#: step with dozens of arrays, 10–20 % of a ``modal`` run (benchmarks/README.md, "the driver
#: split").  Such a kernel allocates nothing and returns no array: its arrays are its
#: caller's (:data:`feeddrive.solvers.driver.NUMBA_NRT_FREE`: the drivers)
nrt_free_kernel = _compiled(_nrt=False)


def first_class(fn: Callable[..., Any], signature: Any, name: str) -> Any:
    """``fn`` compiled once more as a first-class function (a numba ``cfunc`` of
    ``signature``), to be passed to compiled code that calls it through its address: the
    solver drivers compiled once for every model (:mod:`feeddrive.solvers.shared`).

    Cached on disk like a :data:`kernel`, under ``name`` (a qualified name of its own: numba
    keys its cache index by file and qualified name, and ``fn`` may be cached as a kernel
    too).

    Parameters
    ----------
    fn : callable
        The Python function (a kernel's ``py_func``).
    signature : numba signature
        Its argument and return types.
    name : str
        The qualified name its cache entry is kept under.

    Returns
    -------
    numba.core.ccallback.CFunc
        The compiled function.
    """
    if not _STARTED:  # the Python function (cold callers only: the engine runs in C)
        return fn
    # numba's typing of a cfunc passed to compiled code (a full compiler refresh imports it;
    # a load from the cache, ``_LoadingCache``, does not)
    import numba.experimental.function_type  # noqa: F401
    from numba.core import sigutils
    from numba.core.ccallback import CFunc

    copy = types.FunctionType(fn.__code__, fn.__globals__, name, fn.__defaults__,
                              fn.__closure__)
    copy.__qualname__ = name
    copy.__module__ = fn.__module__
    compiled = CFunc(copy, sigutils.normalize_signature(signature), locals={},
                     options={"error_model": "numpy", "nogil": True})
    setattr(compiled, "_cache", _loading_cache(copy))  # noqa: B010 (numba has no stubs)
    compiled.compile()
    return compiled


_LOADED: dict[str, ModuleType] = {}


def import_generated(folder: str, stem: str, source: str) -> ModuleType:
    """Write generated Python ``source`` to ``<cache>/<folder>/<stem>.py`` and import it, once
    per process (numba's on-disk cache is per source file, so a generated module's compiled
    functions are cached as a package module's are).

    The file is written atomically (a concurrent process never imports a half file) and only
    when it is missing or differs; ``stem`` should name a hash of ``source``.  Where the
    cache cannot be written, the fallback folder is (:func:`_write_module`).

    Parameters
    ----------
    folder : str
        Sub-folder of the compile cache.
    stem : str
        The module's file name without ``.py``.
    source : str
        Its text.

    Returns
    -------
    module
        The imported module.

    Raises
    ------
    OSError
        Neither the cache nor its fallback folder could be written: one line naming the
        cache folder (``filename``) and both reasons.
    """
    if stem in _LOADED:
        return _LOADED[stem]
    path = _write_module(folder, stem, source)
    name = f"feeddrive_{stem}"
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    _LOADED[stem] = module
    return module


def _holds(path: Path, source: str) -> bool:
    """Whether the file ``path`` is there with the text ``source`` (False where it cannot be
    read)."""
    try:
        return path.is_file() and path.read_text(encoding="utf-8") == source
    except (OSError, ValueError):
        return False


def _write_module(folder: str, stem: str, source: str) -> Path:
    """``<cache>/<folder>/<stem>.py`` holding ``source`` (written unless it holds it).  A
    write that fails (a read-only mount, a file where the folder should be, a full disk)
    leaves the cache for the fallback folder (:func:`_leave_cache`), where the module is
    looked for and written; the first write there is said once per process, in one line
    naming both folders and why.  Neither written: :func:`feeddrive._disk.unwritable_error`.
    """
    path = Path(_CACHE_DIR) / folder / f"{stem}.py"
    if _holds(path, source):
        return path
    try:
        _write(path, source)
    except OSError as err:
        if _LEFT:  # the fallback folder's write failed
            raise unwritable_error(_WHAT, _LEFT[0][0], _LEFT[0][1], Path(_CACHE_DIR),
                                   err) from None
        _LEFT.append((Path(_CACHE_DIR), reason(err)))
        try:
            _leave_cache()
        except OSError as failed:  # no fallback folder (no temporary folder is usable)
            raise unwritable_error(_WHAT, *_LEFT[0], None, failed) from None
        return _write_module(folder, stem, source)  # in the fallback folder
    if _LEFT and not _LEFT_SAID:
        _LEFT_SAID.append(True)
        print(f"feeddrive: {_WHAT} {_LEFT[0][0]} cannot be written ({_LEFT[0][1]}), so "
              f"{_CACHE_DIR} is used", file=sys.stderr)
    return path


#: the generated modules' cache, as a message names it
_WHAT = "the generated Python modules' cache"
#: the cache folder this process left for the fallback folder, and why (:func:`_write_module`)
_LEFT: list[tuple[Path, str]] = []
#: whether the fallback has been said
_LEFT_SAID: list[bool] = []


def _write(path: Path, source: str) -> None:
    """Write ``source`` to ``path`` atomically (:func:`feeddrive.io.outputs.atomic_path`, the
    package's one atomic-write helper): concurrent processes never import a half file, nor
    is a partial file left where the write fails."""
    from .io.outputs import atomic_path

    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        tmp.write_text(source, encoding="utf-8")


def _leave_cache() -> None:
    """Move this process's compile cache (:data:`CACHE_DIR`: the generated modules and
    numba's cache) to ``numba-<hash>`` in a folder of this user's under the system's temporary
    folder (:func:`feeddrive._disk.private_folder`), the user's cache being read-only."""
    global CACHE_DIR, _CACHE_DIR
    CACHE_DIR = _CACHE_DIR = str(private_folder("feeddrive-py") / f"numba-{SOURCE_DIGEST}")


def cache_dir() -> str:
    """This process's compile cache folder: :data:`CACHE_DIR`, or the temporary folder it
    moved to when the user's cache could not be written.

    Returns
    -------
    str
        The folder.
    """
    return _CACHE_DIR


@contextlib.contextmanager
def compile_lock(path: str | os.PathLike[str], what: str) -> Iterator[None]:
    """Around a first compilation in this process: a lock on a file beside ``path`` (the
    generated module that holds ``what``), so that two processes (the ``reproduce`` pool's
    workers) that need the same new function do not both compile it — the second waits and
    loads what the first wrote to numba's cache.  Nothing is locked where file locks are not
    available (:func:`feeddrive._disk.file_lock`).

    Parameters
    ----------
    path : path-like
        The generated module's file.
    what : str
        The name of what is compiled (names the lock file).
    """
    with file_lock(Path(path).with_name(f".{Path(path).stem}.{what}.lock")):
        yield
