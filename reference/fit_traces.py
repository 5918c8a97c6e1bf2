"""Rig-like records for the calibration of ``feeddrive fit``, made by an integrator other
than feeddrive's: the plain-Python model (:mod:`reference.scipy_model`) integrated by scipy's
Radau (:func:`reference.make_radau_reference.radau_states`), then measured as a rig would —
table position quantised like an encoder, motor current with white noise (seeded).

This tests the numerical part of the fit's intervals (integration error, correlated
quantisation residuals) against a truth feeddrive did not make; it does not test the model's
structure against a real machine.

Run time: each trace is one Radau integration (rtol 1e-9, absolute tolerances 100× tighter
than the engine's former fixed defaults): 0.6 s for 2 s of the CDFS at 1 mm/s on the shared
machine.
"""

from __future__ import annotations

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
from feeddrive.parameters import DriveParameters  # noqa: E402
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


def radau_trace(truth: DriveParameters, speed: float, duration: float, *,
                rtol: float = RTOL, atol_scale: float = ATOL_SCALE,
                stribeck_exponents: dict[str, float] | None = None) -> Trace:
    """The CDFS at mid-screw (0.4 m) commanded at ``speed`` [m/s] after a 0.1-s ramp,
    integrated by Radau on the plain-Python model (any friction law it implements, GMS
    included; ``stribeck_exponents`` per site name: a Stribeck curve exp(−|v/v_s|^δ) with
    another exponent than LuGre's 2)."""
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
