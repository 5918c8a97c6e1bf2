"""The C backend agrees with the numba model (issue 19, item 4's acceptance).

Every model below is assembled once, translated to C (``feeddrive.backends.c_backend``),
compiled with the strict warning set (``-std=c99 -Wall -Wextra -Werror -pedantic``, -O1) and
loaded with ctypes.  At ``N_STATES`` random, physically scaled states (both signs of every
speed, so each friction branch and each saturation side is hit), random times and, for sampled
loops, after the sampled controller ran at a random sample instant, the C right-hand side,
auxiliary outputs and held controller values must agree with numba's per component::

    |f_C − f_numba| ≤ 1e-12 · (|f_numba| + s_i),   s_i = max over the random states of |f_numba,i|

(s_i: that component's scale in this model — a component that is ~0 at one state is judged
against its own typical size, not against 0).  The worst measured ratio
|f_C − f_numba| / (|f_numba| + s_i) of each model is printed (``-s``) and recorded in
docs/c-backend.md.
"""

from __future__ import annotations

import ctypes
import math
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.backends.c_backend import (
    CompilerNotFound,
    c_model_source,
    c_solver_source,
    compile_shared,
    find_compiler,
    load_shared,
)
from feeddrive.engine.simulate import sampling
from feeddrive.model import reference as profiles
from feeddrive.model.assemble import Model
from feeddrive.model.disturbances import LeadError, TorqueRipple
from feeddrive.model.loops import Compensation
from feeddrive.model.parts.backlash import Backlash
from feeddrive.model.reference import ConstantSpeed, SampledSpeed, SineSpeed
from feeddrive.parameters import loads
from feeddrive.solvers.schedule import due

try:
    find_compiler()
    HAVE_CC = True
except CompilerNotFound:
    HAVE_CC = False

pytestmark = pytest.mark.skipif(not HAVE_CC, reason="no C compiler (set CC)")

W = fd.preset("wang2021")
GMS_EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "gms_guide.toml"
LM = fd.preset("linear-motor-example")
RTOL = 1e-12
N_STATES = 40
SAMPLED = {"controller.position_period": 1e-3, "controller.velocity_period": 5e-4,
           "controller.current_period": 1.25e-4}
QUANTISED = {"controller.encoder_counts": 10000.0, "controller.grating_resolution": 1e-7}


def _with(p: fd.DriveParameters, **changes: Any) -> fd.DriveParameters:
    for path, value in changes.items():
        p = p.replace_path(path.replace("__", "."), value)
    return p


def _changes(p: fd.DriveParameters, changes: dict[str, Any]) -> fd.DriveParameters:
    for path, value in changes.items():
        p = p.replace_path(path, value)
    return p


def _csv_profile() -> SampledSpeed:
    import tempfile

    folder = Path(tempfile.mkdtemp())
    path = folder / "profile.csv"
    t = np.linspace(0.0, 2.0, 41)
    rows = "\n".join(f"{a:.6f},{1.5 * math.sin(3.0 * a):.6f},{-0.5 * a:.6f}" for a in t)
    path.write_text("time,table_speed,nut_speed\n" + rows + "\n", encoding="utf-8")
    return profiles.from_csv(path)


def _load_record() -> fd.LoadProfile:
    t = np.linspace(0.0, 1.0, 101)
    return fd.LoadProfile(time=t, force=120.0 * np.sin(7.0 * t) + 40.0)


# name -> (system, profile); every kind of model the test suite builds
CASES: dict[str, Callable[[], tuple[fd.DriveSystem, Any]]] = {
    "wang2021-ddfs": lambda: (fd.DriveSystem(W, "ddfs", 0.4), ConstantSpeed(0.5e-3, 16e-3)),
    "wang2021-cdfs": lambda: (fd.DriveSystem(W, "cdfs", 0.4), ConstantSpeed(1.2e-3)),
    "wang2021-cdfs-nut-servo": lambda: (fd.DriveSystem(W, "cdfs", 0.25, nut_hold="servo"),
                                        ConstantSpeed(1.2e-3)),
    "wang2021-literal-ddfs": lambda: (fd.DriveSystem(fd.preset("wang2021-literal"), "ddfs",
                                                     0.6), ConstantSpeed(1e-3, 8e-3)),
    "wang2021-ripple-ddfs": lambda: (fd.DriveSystem(fd.preset("wang2021-ripple"), "ddfs", 0.4),
                                     ConstantSpeed(0.5e-3, 16e-3)),
    "linear-motor": lambda: (fd.DriveSystem(LM, "linear-motor", 0.4), ConstantSpeed(2e-3)),
    "laws-dahl-stribeck-ddfs": lambda: (
        fd.DriveSystem(_changes(W, {"friction.screw.law": "dahl", "friction.nut.law": "stribeck",
                                    "friction.guide.law": "dahl"}), "ddfs", 0.3),
        ConstantSpeed(1e-3, 8e-3)),
    "laws-stribeck-dahl-none-cdfs": lambda: (
        fd.DriveSystem(_changes(W, {"friction.screw.law": "stribeck", "friction.nut.law": "dahl",
                                    "friction.guide.law": "none"}), "cdfs", 0.5),
        ConstantSpeed(1e-3)),
    "laws-none-linear-motor": lambda: (
        fd.DriveSystem(_changes(LM, {"friction.guide.law": "none"}), "linear-motor", 0.4),
        ConstantSpeed(1e-3)),
    "observer-ripple-lead-cdfs": lambda: (
        fd.DriveSystem(_changes(W, {
            "controller.compensation": Compensation(mode="observer", observer_gain=50.0),
            "disturbances.screw_motor_ripple": TorqueRipple((6.0, 12.0), (0.0135, 0.004),
                                                            (0.3, -1.0)),
            "disturbances.lead_error": LeadError((1.0,), (2e-6,), (0.0,))}), "cdfs", 0.4),
        ConstantSpeed(1e-3)),
    "feedforward-compensation-ddfs": lambda: (
        fd.DriveSystem(_changes(W, {"controller.compensation": Compensation(
            mode="feedforward")}), "ddfs", 0.4), ConstantSpeed(0.5e-3, 16e-3)),
    "hollow-ripple-lead-ddfs": lambda: (
        fd.DriveSystem(_changes(W, {
            "disturbances.hollow_motor_ripple": TorqueRipple((4.0,), (0.01,), (0.5,)),
            "disturbances.lead_error": LeadError((1.0, 2.0), (2e-6, 1e-6), (0.0, 0.4))}),
                       "ddfs", 0.4), ConstantSpeed(0.5e-3, 16e-3)),
    "load-force-linear-motor": lambda: (
        fd.DriveSystem(_changes(LM, {"disturbances.load_force": 50.0,
                                     "disturbances.load_start": 0.2}), "linear-motor", 0.4),
        ConstantSpeed(2e-3)),
    "load-record-ddfs": lambda: (fd.DriveSystem(W, "ddfs", 0.4, load=_load_record()),
                                 ConstantSpeed(0.5e-3, 16e-3)),
    "torque-off-linear-motor": lambda: (
        fd.DriveSystem(_changes(LM, {"controller.mode": "torque_off",
                                     "disturbances.load_force": 50.0}), "linear-motor", 0.4),
        ConstantSpeed(0.0)),
    "gains-kv-table-basis-speed-loop-ddfs": lambda: (
        fd.DriveSystem(_changes(W, {"controller.kv_placement": "velocity_error",
                                    "controller.velocity_gain_basis": "table",
                                    "controller.velocity_feedback": "table",
                                    "controller.nut_loop": "speed"}), "ddfs", 0.4),
        ConstantSpeed(0.5e-3, 16e-3)),
    "kv-position-output-cdfs": lambda: (
        fd.DriveSystem(_changes(W, {"controller.kv_placement": "position_output"}), "cdfs",
                       0.4), ConstantSpeed(1e-3)),
    "gms-guide-cdfs": lambda: (fd.DriveSystem(fd.load(GMS_EXAMPLE), "cdfs", 0.4),
                               ConstantSpeed(2e-3)),
    "gms-guide-ddfs": lambda: (fd.DriveSystem(fd.load(GMS_EXAMPLE), "ddfs", 0.3),
                               ConstantSpeed(0.5e-3, 16e-3)),
    "sampled-ddfs": lambda: (fd.DriveSystem(_changes(W, SAMPLED), "ddfs", 0.4),
                             ConstantSpeed(2e-3, 16e-3, ramp_time=0.02)),
    "sampled-quantised-ddfs": lambda: (fd.DriveSystem(_changes(W, SAMPLED | QUANTISED), "ddfs",
                                                      0.4),
                                       ConstantSpeed(2e-3, 16e-3, ramp_time=0.02)),
    "sampled-quantised-saturating-table-feedback-cdfs": lambda: (
        fd.DriveSystem(_changes(W, SAMPLED | {
            "controller.velocity_feedback": "table", "controller.encoder_counts": 4096.0,
            "controller.grating_resolution": 5e-8, "controller.current_limit": 0.28,
            "controller.voltage_limit": 0.55}), "cdfs", 0.4), ConstantSpeed(2e-3)),
    "sampled-position-velocity-quantised-ddfs": lambda: (
        fd.DriveSystem(_changes(W, SAMPLED | QUANTISED | {"controller.current_period": 0.0}),
                       "ddfs", 0.4), ConstantSpeed(2e-3, 16e-3)),
    "sampled-current-only-ddfs": lambda: (
        fd.DriveSystem(_changes(W, {"controller.current_period": 1.25e-4}), "ddfs", 0.4),
        ConstantSpeed(2e-3, 16e-3)),
    # the compensation parts that run in the velocity loop's update (issue 37 item 4)
    "sampled-quantised-dob-reset-cdfs": lambda: (
        fd.DriveSystem(loads('extends = "wang2021-drive"\nname = "parts"\n'
                                "[disturbance_observer]\nbandwidth = 300.0\n"
                                "inertia_gain = 2.6e-3\n[reset_integrator]\nfraction = 0.2\n"),
                       "cdfs", 0.4), ConstantSpeed(2e-3)),
    "sampled-quantised-linear-motor": lambda: (
        fd.DriveSystem(_changes(LM, SAMPLED | {"controller.grating_resolution": 1e-7}),
                       "linear-motor", 0.4), ConstantSpeed(2e-3)),
    "sampled-quantised-motor-feedback-backlash-cdfs": lambda: (
        fd.DriveSystem(fd.DriveParameters(W.name, W.description, W.mechanism, sections={
            **dict(_changes(W, SAMPLED | QUANTISED | {"controller.position_feedback": "motor"})
                   .sections), "backlash": Backlash(gap=1e-6)}), "cdfs", 0.4),
        ConstantSpeed(2e-3)),
    "sine-ddfs": lambda: (fd.DriveSystem(W, "ddfs", 0.4), SineSpeed(2e-3, 8e-3, 0.5)),
    "trapezoid-cdfs": lambda: (fd.DriveSystem(W, "cdfs", 0.4),
                               profiles.trapezoid(2e-3, 2.0, ramp_time=0.5)),
    "stepdown-ddfs": lambda: (fd.DriveSystem(W, "ddfs", 0.4),
                              profiles.stepdown(1e-3, 0.97e-3, dwell=0.5, lead_in=0.5,
                                                nut_speed=16e-3)[0]),
    "csv-profile-ddfs": lambda: (fd.DriveSystem(W, "ddfs", 0.4), _csv_profile()),
    "function-profile-linear-motor": lambda: (
        fd.DriveSystem(LM, "linear-motor", 0.4),
        SampledSpeed.from_function(lambda t: 1e-3 * np.cos(4.0 * t), 1.0)),
}


def _scales(model: Model) -> np.ndarray:
    """Typical size of each state: 1 mm and 1 mm/s (in the state's own unit via the
    transmission ratio for angles), 1 A, 1 µm for friction (bristle) states and 0.1 mm for
    GMS elements (slip at k_i·z ≈ w_i·F_s: ~0.03–0.1 mm for the example's elements)."""
    atol, _ = model.tolerances(1e-3, 1e-3, 1.0)
    for i, name in enumerate(model.state_names):
        if name.endswith(("_bristle", "_friction_observer")):
            atol[i] = 1e-6
        elif re.search(r"_element\d+$", name):
            atol[i] = 1e-4
    return atol


class Built:
    """One model with its compiled C library."""

    def __init__(self, name: str, folder: Path):
        system, profile = CASES[name]()
        self.model = system.model(profile)
        self.grid = sampling(system.parameters, 1e-3, self.model)
        self.source = c_model_source(self.model)
        self.lib = load_shared(compile_shared(self.source, folder, name=name.replace("-", "_")))


class Models(dict[str, Built]):
    """Each model built and compiled once per test module, when first asked for."""

    def __init__(self, folder: Path):
        super().__init__()
        self.folder = folder

    def __missing__(self, name: str) -> Built:
        self[name] = Built(name, self.folder)
        return self[name]


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> Models:
    return Models(tmp_path_factory.mktemp("c_backend"))


#: run in the quick suite (numba compiles each new model's module once, ~3 s cold); the
#: other cases are marked slow (the CI runs them too)
QUICK = ("wang2021-ddfs", "linear-motor", "gms-guide-cdfs", "observer-ripple-lead-cdfs",
         "load-record-ddfs",
         "sampled-quantised-ddfs", "sampled-quantised-saturating-table-feedback-cdfs",
         "stepdown-ddfs")


def _ratio(c: np.ndarray, ref: np.ndarray) -> float:
    """Worst |c − ref| / (|ref| + s_i) over rows (states) and components; s_i per column."""
    s = np.max(np.abs(ref), axis=0)
    denom = np.abs(ref) + s
    diff = np.abs(c - ref)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.where(diff == 0.0, 0.0, diff / denom)
    return float(np.max(r)) if r.size else 0.0


def _evaluate(b: Built, seed: int) -> dict[str, float]:
    m = b.model
    n, n_aux = len(m.states), len(m.aux)
    rng = np.random.default_rng(seed)
    scale = _scales(m)
    g = b.grid
    sampled = g.sampled
    schedule = g.schedule
    tick0, tick = np.empty(schedule.size, dtype=np.int64), np.empty(schedule.size, dtype=np.int64)
    due(0, schedule, tick0)  # every clock has an instant at breakpoint 0
    f = {"numba": np.empty((N_STATES, n)), "c": np.empty((N_STATES, n))}
    a = {"numba": np.empty((N_STATES, n_aux)), "c": np.empty((N_STATES, n_aux))}
    h = {"numba": np.empty((N_STATES, m.n_held)), "c": np.empty((N_STATES, m.n_held))}
    for r in range(N_STATES):
        y = rng.normal(size=n) * scale * rng.choice([0.1, 1.0, 10.0], size=n)
        t = float(rng.uniform(0.0, 2.5))
        held0 = np.zeros(m.n_held)
        if sampled:
            held0 = rng.normal(size=m.n_held) * 0.1
            k = int(rng.integers(0, 40))
            if r % 4 == 0:
                k = 0
            t = k * g.base
            due(k, schedule, tick)
        for key, backend in (("numba", m.module), ("c", b.lib)):
            held = held0.copy()
            if sampled:
                # first a sample instant with every loop due (k = 0), then the random one
                backend.sample_update(0.0, y, held, m.P, m.T, tick0)
                backend.sample_update(t, y, held, m.P, m.T, tick)
            dy = np.empty(n)
            aux = np.empty(n_aux)
            backend.rhs(t, y, held, m.P, m.T, dy, aux)
            f[key][r], a[key][r], h[key][r] = dy, aux, held
    if sampled:  # the same model with continuous loops reads no held values
        P_continuous = m.P.copy()
        for _, slot in m.clocks:
            P_continuous[slot] = 0.0
        for r in range(N_STATES // 4):
            y = rng.normal(size=n) * scale
            t = float(rng.uniform(0.0, 2.5))
            for key, backend in (("numba", m.module), ("c", b.lib)):
                dy = np.empty(n)
                aux = np.empty(n_aux)
                backend.rhs(t, y, np.zeros(m.n_held), P_continuous, m.T, dy, aux)
                f[key][r] = dy
    assert np.all(np.isfinite(f["numba"])) and np.all(np.isfinite(a["numba"]))
    return {"rhs": _ratio(f["c"], f["numba"]), "aux": _ratio(a["c"], a["numba"]),
            "held": _ratio(h["c"], h["numba"]) if sampled else 0.0}


WORST: dict[str, dict[str, float]] = {}


@pytest.mark.parametrize("name", [n if n in QUICK else pytest.param(n, marks=pytest.mark.slow)
                                  for n in CASES])
def test_c_and_numba_agree_at_random_states(built: Models, name: str) -> None:
    worst = _evaluate(built[name], seed=sum(map(ord, name)))
    WORST[name] = worst
    print(f"\n{name}: worst |f_C - f_numba| / (|f| + s_i): rhs {worst['rhs']:.2e}, "
          f"aux {worst['aux']:.2e}, held {worst['held']:.2e}")
    for what, value in worst.items():
        assert value <= RTOL, f"{name}: {what} differs by {value:.3g} (> {RTOL:g})"


def test_every_sampled_model_exercises_the_sampled_update() -> None:
    """The sampled cases have non-zero loop periods (so held is compared), and the continuous
    ones none (the test would pass vacuously otherwise)."""
    assert set(QUICK) <= set(CASES)
    for name, case in CASES.items():
        g = sampling(case()[0].parameters, 1e-3)
        assert g.sampled == name.startswith("sampled"), name


def test_the_exported_data_are_the_model_s(built: Models) -> None:
    """fd_parameters / fd_tables hold model.P and model.T bit for bit; FD_N_* are the sizes."""
    b = built["load-record-ddfs"]
    m = b.model
    P = (ctypes.c_double * m.P.size).in_dll(b.lib.lib, "fd_parameters")
    T = (ctypes.c_double * m.T.size).in_dll(b.lib.lib, "fd_tables")
    assert np.array_equal(np.frombuffer(P, dtype=float), m.P)
    assert np.array_equal(np.frombuffer(T, dtype=float), m.T)
    names = (ctypes.c_char_p * len(m.states)).in_dll(b.lib.lib, "fd_state_names")
    assert [s.decode() for s in names] == list(m.state_names)
    for macro, value in (("FD_N_STATE", len(m.states)), ("FD_N_AUX", len(m.aux)),
                         ("FD_N_HELD", m.n_held), ("FD_N_PARAM", m.P.size),
                         ("FD_N_TABLE", m.T.size)):
        assert f"#define {macro} {value}\n" in b.source


def test_fd_aux_gives_the_rhs_auxiliary_outputs(built: Models) -> None:
    b = built["wang2021-ddfs"]
    m = b.model
    y = np.linspace(-1e-3, 1e-3, len(m.states))
    a1 = np.empty(len(m.aux))
    a2 = np.empty(len(m.aux))
    b.lib.rhs(0.7, y, np.zeros(m.n_held), m.P, m.T, np.empty(len(m.states)), a1)
    b.lib.aux(0.7, y, np.zeros(m.n_held), m.P, m.T, a2)
    assert np.array_equal(a1, a2)


def test_the_c_file_needs_only_the_three_standard_headers(built: Models) -> None:
    for name in QUICK:
        b = built[name]
        includes = {ln.strip() for ln in b.source.splitlines() if ln.startswith("#include")}
        assert includes == {"#include <math.h>", "#include <string.h>", "#include <stdlib.h>"}


# ---- the solver building blocks, translated from the project's own solver code
@pytest.fixture(scope="module")
def with_solver(tmp_path_factory: pytest.TempPathFactory) -> tuple[Model, Any]:
    system, profile = CASES["wang2021-ddfs"]()
    model = system.model(profile)
    text = c_model_source(model) + "\n" + c_solver_source()
    lib = load_shared(compile_shared(text, tmp_path_factory.mktemp("c_solver"), name="solver"))
    return model, lib.lib


def _ptr(a: np.ndarray) -> Any:
    return a.ctypes.data_as(ctypes.c_void_p)


def test_one_dopri5_step_in_c_equals_numba_s(with_solver: tuple[Model, Any]) -> None:
    """fd_dp5_step and fd_error_norm (switching.dp5_step_template, error_norm_template) give
    numba's stages, new state and error norm within 1e-12 of each component's scale."""
    model, lib = with_solver
    n, rng = len(model.states), np.random.default_rng(5)
    y = rng.normal(size=n) * _scales(model)
    held = np.zeros(model.n_held)
    atol, rel = model.tolerances(1e-9, 1e-8, 1e-6)
    t, h = 0.31, 2e-5
    results = {}
    for backend in ("numba", "c"):
        k = [np.empty(n) for _ in range(7)]
        yt, y_new, aux = np.empty(n), np.empty(n), np.empty(len(model.aux))
        model.module.rhs(t, y, held, model.P, model.T, k[0], aux)
        if backend == "numba":
            model.module._dp5_step(t, h, y, k[0], held, model.P, model.T, *k[1:], yt,
                                   y_new, aux, t + h)
            err = model.module._error_norm(k[6], y, y_new, 1e-6, atol, rel)
        else:
            D = ctypes.c_double
            lib.fd_dp5_step(D(t), D(h), _ptr(y), _ptr(k[0]), _ptr(held), _ptr(model.P),
                            _ptr(model.T), *map(_ptr, k[1:]), _ptr(yt),
                            _ptr(y_new), _ptr(aux), D(t + h))
            lib.fd_error_norm.restype = ctypes.c_double
            err = lib.fd_error_norm(_ptr(k[6]), _ptr(y), _ptr(y_new), D(1e-6), _ptr(atol),
                                    _ptr(rel))
        results[backend] = (np.array(k + [yt, y_new]), err)
    (kn, en), (kc, ec) = results["numba"], results["c"]
    assert _ratio(kc.T, kn.T) <= RTOL
    assert abs(ec - en) <= RTOL * abs(en)
    assert np.max(np.abs(kn[8] - y)) > 0.0  # the step moved the state


def test_one_rodas4_step_in_c_equals_numba_s(with_solver: tuple[Model, Any]) -> None:
    """fd_fd_jacobian, fd_frozen_states, fd_rodas4_step and fd_rodas4_dense (rodas4.py's
    templates, LU kernels included) agree with numba's."""
    model, lib = with_solver
    n, rng = len(model.states), np.random.default_rng(6)
    y = rng.normal(size=n) * _scales(model)
    held = np.zeros(model.n_held)
    atol, _ = model.tolerances(1e-9, 1e-8, 1e-6)
    S = np.ascontiguousarray(model.jacobian_pattern, dtype=np.uint8)
    colour = np.ascontiguousarray(model.jacobian_colours, dtype=np.int64)
    t, h = 0.31, 1e-4
    out = {}
    for backend in ("numba", "c"):
        f0, ft, yp, fp = (np.empty(n) for _ in range(4))
        aux = np.empty(len(model.aux))
        J, M = np.empty((n, n)), np.empty((n, n))
        live = np.ones(n, dtype=np.bool_)
        piv = np.zeros(n, dtype=np.int64)
        u = [np.empty(n) for _ in range(6)]
        yt, fs, y_new, q1, q2 = (np.empty(n) for _ in range(5))
        model.module.rhs(t, y, held, model.P, model.T, f0, aux)
        if backend == "numba":
            m = model.module
            calls = m._r4_fd_jacobian(t, y, f0, held, model.P, model.T, atol, J, ft,
                                      yp, fp, aux, live, S.astype(np.bool_), colour)
            n_live = m._r4_frozen_states(J, f0, live)
            status = m._r4_rodas4_step(t, h, y, f0, J, ft, held, model.P, model.T, M,
                                       piv, *u, yt, fs, y_new, aux, live)
            m._r4_rodas4_dense(*u[:5], q1, q2)
        else:
            D = ctypes.c_double
            for fn in (lib.fd_fd_jacobian, lib.fd_frozen_states, lib.fd_rodas4_step):
                fn.restype = ctypes.c_long
            live_c = live.view(np.uint8)
            calls = lib.fd_fd_jacobian(D(t), _ptr(y), _ptr(f0), _ptr(held), _ptr(model.P),
                                       _ptr(model.T), _ptr(atol), _ptr(J),
                                       _ptr(ft), _ptr(yp), _ptr(fp), _ptr(aux), _ptr(live_c),
                                       _ptr(S), _ptr(colour))
            n_live = lib.fd_frozen_states(_ptr(J), _ptr(f0), _ptr(live_c))
            status = lib.fd_rodas4_step(D(t), D(h), _ptr(y), _ptr(f0), _ptr(J), _ptr(ft),
                                        _ptr(held), _ptr(model.P), _ptr(model.T),
                                        _ptr(M), _ptr(piv), *map(_ptr, u), _ptr(yt),
                                        _ptr(fs), _ptr(y_new), _ptr(aux), _ptr(live_c))
            lib.fd_rodas4_dense(*map(_ptr, u[:5]), _ptr(q1), _ptr(q2))
        out[backend] = (int(calls), int(n_live), int(status), J.copy(), ft.copy(), live.copy(),
                        piv.copy(), np.array(u + [y_new, q1, q2]))
    a, b = out["numba"], out["c"]
    assert a[:3] == b[:3] and a[2] == 5
    assert _ratio(b[3], a[3]) <= RTOL and _ratio(b[4][None, :], a[4][None, :]) <= RTOL
    assert np.array_equal(a[5], b[5]) and np.array_equal(a[6], b[6])
    assert _ratio(b[7].T, a[7].T) <= RTOL


def test_the_comparison_can_fail(built: Models) -> None:
    """A parameter changed in its 9th digit on the C side only is caught by the bound."""
    b = built["wang2021-ddfs"]
    m = b.model
    y = _scales(m) * np.linspace(-1.0, 1.0, len(m.states))
    ref, c = np.empty((1, len(m.states))), np.empty((1, len(m.states)))
    aux = np.empty(len(m.aux))
    P = m.P.copy()
    P[m.parameter_names.index("table.mass")] *= 1.0 + 1e-9
    m.module.rhs(0.5, y, np.zeros(m.n_held), m.P, m.T, ref[0], aux)
    b.lib.rhs(0.5, y, np.zeros(m.n_held), P, m.T, c[0], aux)
    assert _ratio(c, ref) > RTOL


def test_without_data_the_file_leaves_p_and_t_to_the_host(built: Models,
                                                          tmp_path: Path) -> None:
    m = built["stepdown-ddfs"].model
    text = c_model_source(m, data=False)
    assert "fd_tables" not in text and "fd_parameters[" not in text
    lib = load_shared(compile_shared(text, tmp_path, name="no_data"))
    y = _scales(m)
    a, b = np.empty(len(m.states)), np.empty(len(m.states))
    aux = np.empty(len(m.aux))
    lib.rhs(1.2, y, np.zeros(m.n_held), m.P, m.T, a, aux)
    m.module.rhs(1.2, y, np.zeros(m.n_held), m.P, m.T, b, aux)
    assert np.array_equal(a, b)


def test_the_docs_example_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """docs/c-backend.md's first Python block, run as written (in a temporary folder)."""
    doc = (Path(__file__).resolve().parents[2] / "docs" / "c-backend.md").read_text("utf-8")
    code = doc.split("```python\n", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(tmp_path)
    scope: dict[str, Any] = {}
    exec(compile(code, "docs/c-backend.md", "exec"), scope)
    m = scope["model"]
    dy, aux = np.empty(len(m.states)), np.empty(len(m.aux))
    scope["lib"].rhs(0.2, np.zeros(len(m.states)), np.zeros(m.n_held), m.P, m.T, dy,
                     aux)
    assert (tmp_path / "build" / "fd_model.c").is_file() and np.all(np.isfinite(dy))
