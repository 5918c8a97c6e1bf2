"""The tangent transformation (feeddrive.backends.tangent): forward-mode derivatives of the
kernels, checked against central differences in plain Python (no compiler), on small kernels
with every construct and on the generated right-hand side of every shipped preset and drive;
constructs outside the subset are refused by name."""

from __future__ import annotations

import math

import numpy as np
import pytest

from feeddrive.backends.tangent import TangentError, tangent


def _pair(a: float, b: float) -> tuple[float, float]:
    return a * b, a - b


def _power(x: float, k: int) -> float:
    out = 1.0
    for _ in range(k):
        out *= x
    return out


def _writer(x: float, out: np.ndarray, i: int) -> int:
    out[i] = math.exp(x) * x
    return i + 1


def _sample(x: float, y: float, P: np.ndarray, out: np.ndarray) -> float:
    """Every construct the transformation handles."""
    s, d = _pair(x, y)
    acc = 0.0
    for k in range(3):
        acc += P[k] * math.sin(x * k + y)
    if x > y:
        acc *= math.tanh(y)
    elif x < -y:
        acc /= 1.0 + x * x
    else:
        acc -= abs(x) ** 1.5
    j = _writer(y, out, 0)
    out[j] = min(x, y) + max(s, d, 0.25) + (_power(x, 3) if x > 0.0 else math.sqrt(y * y + 1.0))
    z = x
    z **= 2
    e = _pair(x, z)[1]
    return acc + s / d + math.atan2(y, x) + math.hypot(x, y) + z + e + float(int(x)) + \
        math.log1p(y * y) + P[int(y > 0.0)] ** y


def _fd(f, x0: float, h: float = 1e-5) -> float:  # type: ignore[no-untyped-def]
    return (-f(x0 + 2 * h) + 8 * f(x0 + h) - 8 * f(x0 - h) + f(x0 - 2 * h)) / (12 * h)


@pytest.mark.parametrize(("x", "y"), [(0.7, 0.3), (-0.9, 0.4), (0.1, 0.8), (1.3, -0.6)])
def test_every_construct_against_differences(x: float, y: float) -> None:
    tan, sources = tangent(_sample)
    assert "_pair__test_tangent__tangent_vv" in sources  # the callees' tangents too
    P = np.array([0.3, 1.7, 2.2])

    def value(xx: float, yy: float, Pv: np.ndarray = P) -> tuple[float, np.ndarray]:
        out = np.zeros(2)
        return _sample(xx, yy, Pv, out), out

    for dx, dy, dP in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.3, -0.7, 0.0), (0.0, 0.0, 1.0)):
        out, out_d = np.zeros(2), np.zeros(2)
        P_d = np.array([dP, 0.5 * dP, -dP])
        r, r_d = tan(x, y, P, out, dx, dy, P_d, out_d)
        assert r == value(x, y)[0] and np.array_equal(out, value(x, y)[1])

        def along(s: float, dx: float = dx, dy: float = dy, P_d: np.ndarray = P_d) -> float:
            return value(x + s * dx, y + s * dy, P + s * P_d)[0]

        def along_out(s: float, k: int, dx: float = dx, dy: float = dy,
                      P_d: np.ndarray = P_d) -> float:
            return value(x + s * dx, y + s * dy, P + s * P_d)[1][k]

        assert r_d == pytest.approx(_fd(along, 0.0), rel=1e-7, abs=1e-9)
        for k in range(2):
            assert out_d[k] == pytest.approx(_fd(lambda s, k=k: along_out(s, k), 0.0),
                                             rel=1e-7, abs=1e-9)


def test_a_constant_argument_calls_the_kernel_itself() -> None:
    """Activity: with P constant ("ca") the tangent takes no P__d, and a kernel whose inputs
    are all constant is called as it is."""
    tan, sources = tangent(_sample, {"P": "ca"})
    name = next(n for n in sources if n.startswith("_sample"))
    assert "P__d" not in sources[name].split("\n", 1)[0]
    out, out_d = np.zeros(2), np.zeros(2)
    r, r_d = tan(0.7, 0.3, np.array([0.3, 1.7, 2.2]), out, 1.0, 0.0, out_d)
    assert math.isfinite(r_d)


def _scope(t, y, P, dy):  # type: ignore[no-untyped-def]
    dy[0] = P[0] * y[0] * y[1] + t


def _machine_rhs(t, y, P, dy):  # type: ignore[no-untyped-def]
    dy[1] = y[0] - y[1]
    _scope(t, y, P, dy)


def test_an_unannotated_callee_takes_its_arguments_activity() -> None:
    """The bug it guards: a machine's rhs calls each axis' generated scope function, whose
    parameters carry no annotations, as the rhs's own; they were taken for integers, the
    call kept as it is, and the axes' derivatives left out of the tangent (a machine's
    model-exchange FMU was refused for it)."""
    tan, sources = tangent(_machine_rhs, {"t": "c", "y": "a", "P": "ca", "dy": "a"})
    assert any(n.startswith("_scope__") for n in sources)
    y, P = np.array([0.7, -0.4]), np.array([1.3])
    dy, dy_d = np.zeros(2), np.zeros(2)
    tan(0.2, y, P, dy, np.array([1.0, 0.0]), dy_d)
    # d/dy0 of (P0 y0 y1 + t, y0 − y1): (P0 y1, 1)
    assert dy_d[0] == pytest.approx(1.3 * -0.4, rel=1e-15)
    assert dy_d[1] == 1.0


def _bad_keyword(x: float) -> float:
    return round(x, ndigits=2)


def _bad_while(x: float, out: np.ndarray) -> float:
    while _writer(x, out, 0) < 1:
        x += 1.0
    return x


def test_constructs_outside_the_subset_are_named() -> None:
    with pytest.raises(TangentError, match="keyword or starred arguments"):
        tangent(_bad_keyword)
    with pytest.raises(TangentError, match="a kernel call in a while condition"):
        tangent(_bad_while)


def test_the_rhs_of_every_preset_and_drive() -> None:
    """The generated right-hand side of each shipped preset and drive: its tangent along a
    random seed of the states (and of P and T) against central differences of the same Python
    rhs; the derivatives and the signals."""
    from feeddrive.fmu.model import build
    from feeddrive.model.mechanisms import drive_names
    from feeddrive.parameters import PRESETS, ParameterError, preset

    checked = 0
    rng = np.random.default_rng(38)
    for name in PRESETS:
        for drive in drive_names():
            try:
                fm = build(preset(name), drive, 0.4)
            except ParameterError:
                continue
            m = fm.model
            rhs = m.module.rhs.py_func
            tan, _ = tangent(rhs, {"t": "c", "y": "a", "held": "ca", "P": "a", "T": "a",
                                   "dy": "a", "aux": "a"})
            n, na = len(m.states), len(m.aux)
            scale = m.tolerances(1e-4, 1e-2, 1.0)[0]
            y = rng.standard_normal(n) * scale
            held = np.zeros(m.n_held)
            T = m.T.copy()
            T[fm.table_offset + 2] = 2e-3
            yd = rng.standard_normal(n) * scale
            Pd = np.zeros_like(m.P)
            Pd[fm.load_slot] = 10.0
            Td = np.zeros_like(T)
            Td[fm.table_offset + 2] = 1e-3

            def f(s: float, k: int, *, Pv: np.ndarray = m.P, T0: np.ndarray = T,
                  rhs=rhs, y=y, yd=yd, Pd=Pd, Td=Td, held=held, n=n, na=na) -> float:
                out, aux = np.zeros(n), np.zeros(na)
                rhs(0.05, y + s * yd, held, Pv + s * Pd, T0 + s * Td, out, aux)
                return float(np.concatenate([out, aux])[k])

            dy, aux, dy_d, aux_d = np.zeros(n), np.zeros(na), np.zeros(n), np.zeros(na)
            tan(0.05, y, held, m.P, T, dy, aux, yd, Pd, Td, dy_d, aux_d)
            got = np.concatenate([dy_d, aux_d])
            h = 1e-4
            ref = np.array([_fd(lambda s, k=k: f(s, k), 0.0, h) for k in range(n + na)])
            # the differences' own rounding, value by value: a difference of a large value
            # (the stiffness, ~2e7 N/m) resolves only ~ε·|value|/h of its slope
            noise = 100 * np.finfo(float).eps * np.abs(np.concatenate([dy, aux])) / h
            tol = 1e-6 * np.abs(ref) + noise
            assert np.all(np.abs(got - ref) <= tol), (name, drive)
            checked += 1
    assert checked >= 8
