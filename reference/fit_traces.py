"""Rig-like records for the calibration of ``feeddrive fit``, made by an integrator other
than feeddrive's: the plain-Python model (:mod:`reference.scipy_model`) integrated by scipy's
Radau (:func:`reference.make_radau_reference.radau_states`), then measured as a rig would —
table position quantised like an encoder, motor current with white noise (seeded).

This tests the numerical part of the fit's intervals (integration error, correlated
quantisation residuals) against a truth feeddrive did not make; it does not test the model's
structure against a real machine.

Run time: each trace is one Radau integration (rtol 1e-9, absolute tolerances 100× tighter
than the engine's former fixed defaults): 0.6 s for 2 s of the CDFS at 1 mm/s on the shared
machine; with the example's GMS guide 5–9 s a trace.  The traces the tests use are stored
(:data:`STORE`, made by ``python reference/fit_traces.py``) under a key of everything they
are made from — the truth's parameters as TOML, the speed, length, tolerances and options,
and the text of the reference model and of its Radau driver — so :func:`radau_trace` reads a
stored trace only where a fresh integration would be made from the same things, and
integrates otherwise.
"""

from __future__ import annotations

import hashlib
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from feeddrive.analysis.fit import Experiment  # noqa: E402
from feeddrive.analysis.fit_statistics import noise_level  # noqa: E402
from feeddrive.model.reference import ConstantSpeed  # noqa: E402
from feeddrive.parameters import DriveParameters, dumps  # noqa: E402
from reference.make_radau_reference import radau_states  # noqa: E402
from reference.scipy_model import ReferenceModel  # noqa: E402

#: the calibration's truth: wang2021 with these factors (issue 22's Acceptance)
FACTORS = {"controller.velocity_integral_gain": 1.2,
           "friction.screw.positive.viscous_coefficient": 0.8,
           "friction.screw.positive.static_force": 1.1}
SPEEDS = (1.0e-3, 2.0e-3, 5.0e-3)  # [m/s]

RTOL = 1e-9
ATOL_SCALE = 1e-2
RAMP_TIME = 0.1  # [s], as synthetic_experiment and `simulate`


@dataclass(frozen=True)
class Trace:
    """A noise-free Radau trace at a constant commanded speed (SI)."""

    speed: float  # [m/s]
    time: np.ndarray  # [s], 1-ms grid from 0
    table_position: np.ndarray  # [m]
    screw_current: np.ndarray  # [A]


#: the stored traces (``python reference/fit_traces.py``), by :func:`trace_key`
STORE = ROOT / "tests" / "data" / "radau_fit_traces.npz"
#: what a trace is made from besides its arguments: the reference model and its Radau driver
_SOURCES = ("reference/scipy_model.py", "reference/make_radau_reference.py")


def trace_key(truth: DriveParameters, speed: float, duration: float, rtol: float,
              atol_scale: float, stribeck_exponents: dict[str, float] | None) -> str:
    """The digest of everything a Radau trace is made from (the key in :data:`STORE`)."""
    made_from = repr((dumps(truth), float(speed), float(duration), float(rtol),
                      float(atol_scale), sorted((stribeck_exponents or {}).items())))
    digest = hashlib.sha256(made_from.encode())
    for name in _SOURCES:
        digest.update((ROOT / name).read_bytes().replace(b"\r\n", b"\n"))
    return "k" + digest.hexdigest()[:40]


def radau_trace(truth: DriveParameters, speed: float, duration: float, *,
                rtol: float = RTOL, atol_scale: float = ATOL_SCALE,
                stribeck_exponents: dict[str, float] | None = None,
                stored: bool = True) -> Trace:
    """The CDFS at mid-screw (0.4 m) commanded at ``speed`` [m/s] after a 0.1-s ramp,
    integrated by Radau on the plain-Python model (any friction law it implements, GMS
    included; ``stribeck_exponents`` per site name: a Stribeck curve exp(−|v/v_s|^δ) with
    another exponent than LuGre's 2).  Read from :data:`STORE` where it holds the trace of
    these very inputs (``stored``), integrated otherwise."""
    if stored and STORE.exists():
        key = trace_key(truth, speed, duration, rtol, atol_scale, stribeck_exponents)
        with np.load(STORE) as data:
            if f"{key}_time" in data:
                return Trace(speed=speed, time=np.array(data[f"{key}_time"]),
                             table_position=np.array(data[f"{key}_table_position"]),
                             screw_current=np.array(data[f"{key}_screw_current"]))
    options = {"stribeck_exponents": stribeck_exponents} if stribeck_exponents else {}
    t, y, _ = radau_states(truth, "cdfs", ConstantSpeed(speed, ramp_time=RAMP_TIME), duration,
                           rtol, atol_scale, **options)
    names = ReferenceModel(truth, "cdfs", 0.4, None, **options).state_names
    return Trace(speed=speed, time=t, table_position=y[names.index("table_position")],
                 screw_current=y[names.index("screw_current")])


def measured(trace: Trace, seed: int, *, position_quantum: float = 0.05e-6,
             current_noise: float = 0.01) -> Experiment:
    """``trace`` as a rig measures it: position in counts of ``position_quantum`` [m] from
    the count the table starts in, the table's start within its count drawn uniformly (so the
    quantisation error, a deterministic function of the motion, differs from seed to seed as
    it does from run to run on a rig), current with white noise of ``current_noise`` × its
    rms (seeded, numpy's default generator)."""
    rng = np.random.default_rng(seed)
    x = trace.table_position
    if position_quantum > 0:
        phase = float(rng.uniform(0.0, position_quantum))
        x = (np.round((x + phase) / position_quantum) - round(phase / position_quantum)) \
            * position_quantum
    i = trace.screw_current
    i = i + current_noise * float(np.sqrt(np.mean(i ** 2))) * rng.standard_normal(i.size)
    t = trace.time
    ref = trace.speed * np.clip(t / RAMP_TIME, 0.0, 1.0)
    signals = {"table_position": x, "screw_current": i}
    return Experiment(source=f"radau {trace.speed * 1e3:g} mm/s (seed {seed})", time=t,
                      signals=signals, reference_time=t, table_speed=ref,
                      noise={k: noise_level(v) for k, v in signals.items()})


def calibration_truth(preset: str = "wang2021", factors: dict[str, float] | None = None
                      ) -> tuple[DriveParameters, dict[str, float]]:
    """``preset`` (``wang2021``) with ``factors`` (:data:`FACTORS`) applied, and the true
    values by path [SI]."""
    import feeddrive as fd

    base = fd.preset(preset)
    p, values = base, {}
    for path, factor in (FACTORS if factors is None else factors).items():
        value: object = base
        for part in path.split("."):
            value = getattr(value, part)
        values[path] = float(value) * factor  # type: ignore[arg-type]
        p = p.replace_path(path, values[path])
    return p, values


def stored_truths() -> dict[str, tuple[DriveParameters, dict[str, float] | None]]:
    """The truths whose traces at :data:`SPEEDS` over 2 s :data:`STORE` keeps: the
    calibration's (tests/validation/test_fit_calibration_independent.py) and the two
    mismatched ones of tests/validation/test_fit_mismatch.py (the example's GMS guide with a
    slip margin of 0.02; a Stribeck exponent of 1 at the screw)."""
    import feeddrive as fd

    truth, _ = calibration_truth()
    guide = fd.load(ROOT / "examples" / "gms_guide.toml").friction.guide.with_values(
        slip_margin=0.02)
    return {"calibration": (truth, None),
            "gms-guide": (truth.replace_path("friction.guide", guide), None),
            "stribeck-exponent-1": (truth, {"screw": 1.0})}


def make_store() -> Path:
    """Integrate the traces of :func:`stored_truths` afresh and write :data:`STORE`."""
    import time

    arrays: dict[str, np.ndarray] = {}
    for name, (truth, exponents) in stored_truths().items():
        for speed in SPEEDS:
            started = time.process_time()
            trace = radau_trace(truth, speed, 2.0, stribeck_exponents=exponents, stored=False)
            key = trace_key(truth, speed, 2.0, RTOL, ATOL_SCALE, exponents)
            arrays[f"{key}_time"] = trace.time
            arrays[f"{key}_table_position"] = trace.table_position
            arrays[f"{key}_screw_current"] = trace.screw_current
            print(f"{name} {speed * 1e3:g} mm/s: {time.process_time() - started:.1f} CPU s",
                  flush=True)
    np.savez_compressed(STORE, **arrays)
    print(f"-> {STORE.relative_to(ROOT)}")
    return STORE


if __name__ == "__main__":
    make_store()
