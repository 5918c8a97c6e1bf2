"""The Python → C translator (``feeddrive.backends.c_translate``): Python semantics kept where C
differs (``%``, ``//`` on negatives, ``round``, ``/`` of integers, ``int()``, bool arithmetic,
``min``/``max`` with NaN, loop variables), the subset's statements and expressions, and a clear
error — naming function, line and construct — for everything outside the subset.

The references are numba (which runs the package's kernels) and Python itself: each kernel
below is run compiled by numba, as plain Python and as compiled C on the same arguments, and
the results must be equal (bit for bit: the same operations in the same order).
"""

from __future__ import annotations

import ctypes
import itertools
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

try:
    from numba import njit

    HAVE_NUMBA = True
except ImportError:  # numba is optional (feeddrive[numba]): Python is then the reference
    HAVE_NUMBA = False

    def njit(**_options: Any) -> Any:
        return lambda fn: fn

from feeddrive.backends.c_backend import CompilerNotFound, compile_shared, find_compiler
from feeddrive.backends.c_translate import (
    BUILTINS,
    MATH,
    NUMPY,
    TranslationError,
    translate_kernels,
)

try:
    find_compiler()
    HAVE_CC = True
except CompilerNotFound:
    HAVE_CC = False

ROOT = Path(__file__).resolve().parents[2]
SIZE = 3  # a module constant (inlined)
GAIN = 0.1 + 0.2  # a float constant whose repr has 17 digits


def k_mod(a: int, b: int) -> int:
    return a % b


def k_floordiv(a: int, b: int) -> int:
    return a // b


def k_fmod(a: float, b: float) -> float:
    return a % b


def k_ffloordiv(a: float, b: float) -> float:
    return a // b


def k_round(x: float) -> int:
    return round(x)


def k_int(x: float) -> int:
    return int(x)


def k_floor(x: float) -> int:
    return math.floor(x)


def k_true_division(a: int, b: int) -> float:
    return a / b


def k_bools(a: float, b: float) -> int:
    return (a > 0.0) + (b > 0.0) + (not a < b)


def k_min_max(a: float, b: float) -> float:
    return min(a, b) + 10.0 * max(a, b) + 100.0 * min(b, a)


def k_chained(a: float, b: float) -> bool:
    return -1.0 < a <= b or (a != a and not b >= 0.0)


@njit(error_model="numpy")
def _pair(x: float) -> tuple[float, float]:
    return x * GAIN, -x


def k_tuples(x: float) -> float:
    a, b = _pair(x)
    c, d = b, a
    return a + 2.0 * b + 4.0 * _pair(c)[1] + 8.0 * d


def k_loops(n: int) -> float:
    total = 0.0
    i = -5
    for i in range(n):
        if i == 7:
            continue
        total += i
    for j in range(n, 0, -2):
        total += 0.5 * j
    k = 0
    while True:
        k += 1
        if k > 3 * n:
            break
    return total + 1000.0 * i + 1e6 * k


def k_arrays(x: float) -> float:
    a = np.zeros(SIZE)
    m = np.empty((2, SIZE))
    for r in range(2):
        for c in range(SIZE):
            m[r, c] = x * (r + 1) + c
    for c in range(SIZE):
        a[c] = m[0, c] * m[1, c]
    a[SIZE - 1] += 1.0
    s = 0.0
    for c in range(a.size):
        s += a[c] ** 2 + math.sqrt(abs(a[c])) + math.exp(-abs(a[c])) * math.copysign(1.0, x)
    return s if math.isfinite(s) else -1.0


def k_local_kinds(n: int) -> float:
    counts = np.zeros(SIZE, dtype=np.int64)
    flags = np.ones(2, dtype=np.bool_)
    work = np.empty(n)  # a variable-length array
    ramp = np.ones((n, 2))
    for i in range(n):
        counts[i % SIZE] += 1
        work[i] = 0.5 * i
        ramp[i, 1] = work[i] + counts[i % SIZE]
    flags[1] = n > 2
    s = 0.0
    for i in range(n):
        s += ramp[i, 0] + ramp[i, 1]
    return s + 100.0 * counts[0] + 1000.0 * (flags[0] + flags[1]) + 1e4 * len(work)


def k_ternary(x: float, n: int) -> float:
    y = 1 if n > 0 else 2.5
    y *= 2
    return (x if x > y else -x) + y + float(n) + abs(n) + n ** 2.0


def _row_sum(g: np.ndarray) -> float:
    s = 0.0
    for j in range(g.size):  # a size known at run time only (shapes "?")
        s += g[j] * (j + 1)
    return s


def _total(G: np.ndarray) -> float:
    s = 0.0
    for i in range(G.shape[0]):
        for j in range(G.shape[1]):
            s += G[i, j] * (i + 1)
    return s


def _scale(g: np.ndarray, f: float) -> None:
    for j in range(g.size):
        g[j] *= f


def k_rows(n: int) -> float:
    """Rows: M[i, :] = v, a row M[i] as an argument (read and written), a conditional
    between two arrays as an argument, a.copy(), a = b = value, run-time array sizes."""
    M = np.zeros((n, 3))
    v = np.empty(3)
    for i in range(n):
        for j in range(3):
            v[j] = i * 1.5 + j
        M[i, :] = v
    w = v.copy()
    v[0] = -7.0
    a = b = 0.5
    _scale(M[n - 1], 2.0)
    s = _row_sum(M[n - 1])
    s += _total(M)
    s += _row_sum(M[0] if n > 2 else w)
    return s + a + b + w[0] + 10.0 * w[2] + v[0]


SCALAR = {"int": ctypes.c_long, "float": ctypes.c_double, "bool": ctypes.c_int}
CASES: dict[Any, list[tuple[Any, ...]]] = {
    k_mod: [(a, b) for a, b in itertools.product((-7, -6, -1, 0, 1, 6, 7), (-3, -1, 2, 5))],
    k_floordiv: [(a, b) for a, b in itertools.product((-7, -6, -1, 0, 1, 6, 7), (-3, -1, 2, 5))],
    k_fmod: [(a, b) for a, b in itertools.product((-7.5, -6.0, -0.0, 0.0, 0.1, 6.0, 7.25, 1e300),
                                                  (-3.0, -0.7, 2.0, 5.5))],
    k_ffloordiv: [(a, b) for a, b in itertools.product((-7.5, -6.0, -0.0, 0.0, 0.1, 6.0, 7.25),
                                                       (-3.0, -0.7, 2.0, 5.5))],
    k_round: [(x,) for x in (-2.5, -1.5, -0.5, 0.5, 1.5, 2.5, 2.4999, -3.7, 1e15 + 0.5)],
    k_int: [(x,) for x in (-2.9, -0.1, 0.0, 0.9, 3.99, -1e12 - 0.5)],
    k_floor: [(x,) for x in (-2.9, -0.1, 0.0, 0.9, 3.99, -1e12 - 0.5)],
    k_true_division: [(a, b) for a, b in itertools.product((-7, 0, 1, 9), (-4, 3, 7))],
    k_bools: [(a, b) for a, b in itertools.product((-1.0, 0.0, 2.0), (-1.0, 0.0, 2.0))],
    k_min_max: [(a, b) for a, b in itertools.product((-1.0, 0.0, 2.0, math.nan),
                                                     (-1.0, 2.0, math.nan))],
    k_chained: [(a, b) for a, b in itertools.product((-2.0, -0.5, 0.0, 1.0, math.nan),
                                                     (-0.5, 1.0, 3.0))],
    k_tuples: [(x,) for x in (-1.5, 0.0, 0.3, 7.0)],
    k_loops: [(n,) for n in (0, 1, 3, 8, 11)],
    k_arrays: [(x,) for x in (-2.0, 0.0, 0.7, 3.0)],
    k_local_kinds: [(n,) for n in (1, 2, 3, 7)],
    k_ternary: [(x, n) for x, n in itertools.product((-3.0, 0.5, 9.0), (-2, 0, 3))],
    k_rows: [(n,) for n in (1, 2, 3, 6)],
}
#: sizes of the kernels' array parameters: "?", passed at run time
SHAPES = {"g": ("?",), "G": ("?", "?")}


@pytest.fixture(scope="module")
def lib(tmp_path_factory: pytest.TempPathFactory) -> Any:
    if not HAVE_CC:
        pytest.skip("no C compiler (set CC)")
    text = translate_kernels(list(CASES), shapes=SHAPES)
    return ctypes.CDLL(str(compile_shared(text, tmp_path_factory.mktemp("c_translate"),
                                          name="semantics")))


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, float) and math.isnan(a):
        return isinstance(b, float) and math.isnan(b)
    return bool(a == b and (not isinstance(a, float) or math.copysign(1, a) == math.copysign(1, b)))


#: where numba (which runs the kernels) differs from plain Python with numpy arrays: the sum
#: of two numpy bool_ elements is a logical or in numpy, an integer sum in numba (and in C)
NUMBA_DIFFERS = {k_local_kinds}


@pytest.mark.parametrize("fn", list(CASES), ids=lambda f: f.__name__)
def test_c_keeps_python_semantics(lib: Any, fn: Any) -> None:
    """C equals numba (``error_model="numpy"``, as the package's kernels) and, but for
    :data:`NUMBA_DIFFERS`, plain Python."""
    if fn in NUMBA_DIFFERS and not HAVE_NUMBA:
        pytest.skip("numba is not installed (pip install 'feeddrive[numba]'; .ci/min-versions "
                    "runs it): this kernel's reference is numba, plain Python differs")
    hints = fn.__annotations__
    cfn = getattr(lib, f"fd_{fn.__name__}")
    cfn.argtypes = [SCALAR[hints[p]] for p in list(hints)[:-1]]
    cfn.restype = SCALAR[hints["return"]]
    jitted = njit(error_model="numpy")(fn)
    if fn is k_rows:  # its callees, compiled as the package's kernels are
        jitted = njit(error_model="numpy")(_with_jitted_callees(fn))
    for args in CASES[fn]:
        reference = jitted(*args)
        got = cfn(*args)
        if hints["return"] == "bool":
            got = bool(got)
        assert _same(reference, got), f"{fn.__name__}{args}: numba {reference!r}, C {got!r}"
        if fn not in NUMBA_DIFFERS:
            python = fn(*args)
            assert _same(python, got), f"{fn.__name__}{args}: Python {python!r}, C {got!r}"


def _with_jitted_callees(fn: Any) -> Any:
    import types

    scope = dict(fn.__globals__)
    scope.update({f.__name__: njit(error_model="numpy")(f) for f in (_row_sum, _total, _scale)})
    return types.FunctionType(fn.__code__, scope, fn.__name__)


def test_run_time_sizes_are_hidden_parameters() -> None:
    """A "?" of ``shapes`` makes a ``long`` parameter after the array; callers pass their
    argument's size (a row of a 2-D array: its row length)."""
    text = translate_kernels([k_rows], shapes=SHAPES)
    assert re.search(r"double fdk_\w+__total\(const double \*G, long G_n0, long G_n1\)", text)
    assert re.search(r"fdk_\w+__row_sum\(\(M \+ \(\(?n - 1\)?\) \* \(3\)\), \(long\)\(3\)\)",
                     text)


def test_module_constants_are_inlined_with_repr_precision() -> None:
    text = translate_kernels([k_tuples])
    assert repr(GAIN) in text and "0.30000000000000004" in text


# ---- outside the subset: a clear error naming function, line and construct
def bad_comprehension(x: float) -> float:
    return sum([x for _ in range(3)])


def bad_lambda(x: float) -> float:
    y = [x, x]
    return y[0]


def bad_slice(y: np.ndarray) -> float:
    return y[1:].sum()


def bad_keyword(x: float) -> float:
    return round(x, ndigits=2)


def bad_negative_index(y: np.ndarray) -> float:
    return y[-1]


def bad_loop(y: np.ndarray) -> float:
    s = 0.0
    for v in y:
        s += v
    return s


def bad_try(x: float) -> float:
    try:
        return 1.0 / x
    except ZeroDivisionError:
        return 0.0


def bad_string(x: float) -> float:
    print("x")
    return x


def bad_recursion(n: int) -> int:
    return 1 if n <= 0 else bad_recursion(n - 1)


def bad_int_power(n: int) -> int:
    return n ** 2


def bad_is(x: float) -> bool:
    return x is None


def bad_unannotated(x):  # type: ignore[no-untyped-def]
    return x


def bad_float_index(y: np.ndarray, x: float) -> float:
    return y[x]


def bad_two_writing_calls(y: np.ndarray) -> float:
    return _writes(y) + _writes(y)


def _writes(y: np.ndarray) -> float:
    y[0] = 1.0
    return y[0]


BAD = {
    bad_comprehension: "call of 'sum'", bad_slice: "slice", bad_keyword: "keyword arguments",
    bad_negative_index: "negative index", bad_loop: "for loop over", bad_try: "statement Try",
    bad_string: "call of 'print'", bad_recursion: "recursion", bad_int_power: "integer power",
    bad_is: "comparison Is", bad_unannotated: "has no type", bad_float_index: "float index",
    bad_two_writing_calls: "two calls", bad_lambda: "expression List",
}


@pytest.mark.parametrize("fn", list(BAD), ids=lambda f: f.__name__)
def test_constructs_outside_the_subset_raise_a_clear_error(fn: Any) -> None:
    with pytest.raises(TranslationError) as info:
        translate_kernels([fn])
    message = str(info.value)
    assert BAD[fn] in message and fn.__name__ in message
    if fn is not bad_recursion:  # the others name file and line of the construct
        line = int(re.search(r"test_c_translate\.py:(\d+)\)", message).group(1))  # type: ignore[union-attr]
        source = Path(__file__).read_text(encoding="utf-8").splitlines()
        assert f"def {fn.__name__}(" in "\n".join(source[line - 4:line])


def test_the_docs_list_the_subset_the_code_supports() -> None:
    """docs/c-backend.md's function lists are MATH, NUMPY and BUILTINS, name for name."""
    text = (ROOT / "docs" / "c-backend.md").read_text(encoding="utf-8")

    def listed(label: str) -> set[str]:
        m = re.search(rf"^- {label}: (.+)$", text, re.M)
        assert m, f"docs/c-backend.md has no '- {label}:' line"
        return set(re.findall(r"`(?:\w+\.)?(\w+)`", m.group(1)))

    assert listed("math") == set(MATH)
    assert listed("numpy") == set(NUMPY)
    assert listed("built-ins") == set(BUILTINS)


# ---- every kernel of the package stays in the subset
#: kernels outside the subset by design, with the reason: they return arrays (analysis-side
#: helpers called from Python; no model calls them)
NOT_TRANSLATED = {"feeddrive.model.friction.stribeck._map1": "return annotation",
                  # the modal method's eigen-analysis with its LAPACK fallback (complex
                  # eigenvalues); the C engine calls step_cap_real instead.  Value: the
                  # refusal's message
                  "feeddrive.solvers.modes.step_cap": "complex128"}


def _package_kernels() -> dict[str, Any]:
    import importlib

    from feeddrive import _jit

    pkg = Path(_jit.__file__).resolve().parent
    found = {}
    for path in _jit._kernel_files():
        rel = path.relative_to(pkg).with_suffix("")
        parts = [p for p in rel.parts if p != "__init__"]
        mod = importlib.import_module(".".join(["feeddrive", *parts]))
        for name, obj in vars(mod).items():
            # a numba dispatcher, or without numba the plain function (its py_func itself)
            py_func = getattr(obj, "py_func", None) if callable(obj) else None
            if py_func is not None and py_func.__module__ == mod.__name__:
                found[f"{mod.__name__}.{name}"] = obj
    return found


def test_every_kernel_of_the_package_translates_and_compiles(tmp_path: Path) -> None:
    """All numba kernels in the files that name the numba cache (``_jit._kernel_files``)
    translate — with the solver shapes where they need sizes — and the concatenation of their
    translations compiles with the strict warning set (the ``#ifndef`` guards let shared
    callees and helpers appear once)."""
    from feeddrive.backends.c_backend import SOLVER_TYPES
    from feeddrive.backends.c_engine import SHAPES as SOLVER_SHAPES  # the engine's: all sizes

    kernels = _package_kernels()
    assert len(kernels) >= 25 and set(NOT_TRANSLATED) <= set(kernels)
    texts = ["#define FD_N_STATE 4\n#define FD_N_AUX 2\n#define FD_N_CLOCK 3"]
    for qualified, obj in sorted(kernels.items()):
        if qualified in NOT_TRANSLATED:
            with pytest.raises(TranslationError, match=NOT_TRANSLATED[qualified]):
                translate_kernels([obj], shapes=SOLVER_SHAPES, param_types=SOLVER_TYPES)
            continue
        texts.append(translate_kernels(
            [obj], shapes=SOLVER_SHAPES, param_types=SOLVER_TYPES,
            names={obj.py_func.__name__: "fd_" + qualified.replace(".", "_")}))
    if HAVE_CC:
        compile_shared("\n".join(texts), tmp_path, name="all_kernels")


def bad_read_beside_write(y: np.ndarray) -> float:
    return y[0] + _writes(y)


def bad_param_retyped(n: int) -> float:
    n = n / 2
    return n


@pytest.mark.parametrize("fn, what", [(bad_read_beside_write, "reads array 'y' beside"),
                                      (bad_param_retyped, "parameter 'n' (long) assigned")],
                         ids=["read-beside-write", "parameter-retyped"])
def test_order_and_type_traps_raise(fn: Any, what: str) -> None:
    """Python evaluates left to right and keeps a parameter's value exact; C would not."""
    with pytest.raises(TranslationError, match=re.escape(what)):
        translate_kernels([fn])
