"""What a run will cost before it starts: solver steps and memory (issue 12 item 9, issue 13
item 4).

``simulate --duration 100000`` used to reach 12 GB and then stop with a solver error after
50 million steps; :func:`run_budget` lets the CLI refuse or warn before any work is done.

Two more failures surfaced only at the end of a long run: an output larger than the
machine's memory (``--duration 1e9``), and a parameter set so stiff for the explicit
Dormand–Prince integrator that it runs to ``max_steps`` after minutes (near-zero friction:
the LuGre bristle relaxes in F_c/(σ0·|v|) ≈ 30 ns; a current loop of microseconds).
:func:`feeddrive.simulate` itself refuses both before integrating:

* :func:`check_output_memory`: a run whose recorded samples would need more than half the
  available memory;
* :func:`step_rate_problem`: from a short probe integration (the first ~0.1 s), the steps
  of the whole run are projected; above ``max_steps`` the run is refused (a
  ``SimulationError`` raised by :func:`feeddrive.simulate` before integrating), naming the
  fastest time constant of the parameters (:func:`time_constants`), the one that forces
  small steps.  An explicit method is stable for steps up to about 3.3 × the fastest time
  constant (Hairer & Wanner, Solving ODEs II, Sect. IV.2, stability region of DOPRI5).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..parameters import DriveParameters, ParameterError

# bytes per recorded sample: the solver's output arrays (time, 15 states, 15 auxiliaries of
# the ball-screw drives, float64: 12.2 GB measured at 5e7 samples, i.e. 244 B) and the
# Result's copies of them (about as much again)
BYTES_PER_SAMPLE = 2 * 8 * (1 + 15 + 15)
MEMORY_WARNING_BYTES = 2e9


@dataclass(frozen=True)
class RunBudget:
    """Lower bound of the solver steps and estimate of the memory of a run."""

    duration: float  # [s]
    min_steps: int  # the step never exceeds max_step [s]
    max_steps: int
    samples: int
    memory_bytes: float

    @property
    def steps_exceeded(self) -> bool:
        return self.min_steps > self.max_steps

    @property
    def longest_duration(self) -> float:
        """The longest duration [s] the step limit allows."""
        return self.duration * self.max_steps / max(self.min_steps, 1)


def run_budget(duration: float, *, max_step: float, output_interval: float,
               max_steps: int) -> RunBudget:
    """Budget of a run of ``duration`` [s] with the solver's ``max_step`` [s],
    ``output_interval`` [s] and step limit ``max_steps``."""
    samples = int(math.floor(duration / output_interval)) + 1
    return RunBudget(duration=duration, min_steps=int(math.ceil(duration / max_step)),
                     max_steps=max_steps, samples=samples,
                     memory_bytes=float(samples * BYTES_PER_SAMPLE))


#: simulated time [s] of the probe that measures the step rate
PROBE_TIME = 0.1
#: refuse when the projected steps exceed max_steps / this margin (the rate may still grow)
STEP_MARGIN = 1.5
#: a factor on BYTES_PER_SAMPLE for the copies made on writing a file
_COPY_FACTOR = 2.0


def available_memory() -> int:
    """Bytes of memory available to a new allocation (Linux ``MemAvailable``; 4 GiB if
    unknown)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return 4 << 30


def check_output_memory(duration: float, output_interval: float) -> None:
    """Refuse a run whose recorded output would not fit in memory."""
    samples = int(duration / output_interval) + 1
    need = samples * BYTES_PER_SAMPLE * _COPY_FACTOR
    free = available_memory()
    if need > 0.5 * free:
        raise ParameterError(
            "duration", duration,
            f"{samples:.3g} output samples (one per {output_interval:g} s) would need about "
            f"{need / 2**30:.3g} GiB, more than half the {free / 2**30:.3g} GiB available; "
            "shorten the duration [s] (or, from Python, raise options.output_interval)")


def time_constants(params: DriveParameters, drive: str, speed: float) -> dict[str, float]:
    """The parameter set's fast time constants [s], by name, at table speed ``speed``
    [m/s] (for the bristle relaxation F_c/(σ0·|v|), Wang2021 Eqs. 9–11)."""
    v = max(abs(speed), 1e-6)
    out: dict[str, float] = {}
    sites = {"ddfs": ("screw", "nut", "guide"), "cdfs": ("screw", "guide")}.get(drive,
                                                                               ("guide",))
    for site in sites:
        lugre = getattr(params.friction, site)
        if not hasattr(lugre, "bristle_stiffness"):  # a law with parameters of its own
            continue
        fc = min(lugre.positive.coulomb_force, lugre.negative.coulomb_force)
        out[f"{site} bristle relaxation F_c/(σ0·|v|)"] = fc / (lugre.bristle_stiffness * v)
    c = params.controller
    motors: dict[str, Any] = {"cdfs": {"screw motor": params.screw_motor},
                              "ddfs": {"screw motor": params.screw_motor,
                                       "hollow motor": params.hollow_motor}}.get(drive, {})
    linear = getattr(params, "linear_motor", None)
    if not motors and linear is not None:
        motors = {"linear motor": linear}
    for name, motor in motors.items():
        out[f"{name} current loop L/(R + K_ip)"] = motor.inductance / (
            motor.resistance + c.current_gain)
    return out


def profile_speed(profile: Any) -> float:
    """The largest commanded table speed [m/s] of a speed profile (its amplitude, or the
    largest sample), 1 mm/s when it has none."""
    for name in ("table_speed", "table_amplitude"):
        value = getattr(profile, name, None)
        if value is not None:
            speed = float(np.max(np.abs(np.asarray(value, dtype=float)), initial=0.0))
            return speed or 1e-3
    return 1e-3


def step_rate_problem(*, steps: int, probe_time: float, duration: float, max_steps: int,
                      params: DriveParameters, drive: str, speed: float) -> str | None:
    """Why a run whose probe of ``probe_time`` [s] took ``steps`` steps cannot finish within
    ``max_steps`` over ``duration`` [s] (see the module), or None when it can."""
    rate = steps / probe_time
    projected = rate * duration
    if projected * STEP_MARGIN <= max_steps:
        return None
    h = probe_time / max(steps, 1)
    taus = time_constants(params, drive, speed)
    name, tau = min(taus.items(), key=lambda kv: kv[1])
    if tau < 10.0 * h:
        cause = (f"the fastest time constant, {name} = {tau:.3g} s, forces steps of "
                 f"{h:.3g} s")
    else:
        cause = (f"steps of {h:.3g} s, far below every parameter time constant (the fastest "
                 f"is {name} = {tau:.3g} s): the solution chatters")
    return (f"refused before integrating: the run would exceed the maximum number of steps, "
            f"max_steps = {max_steps}: the solver needs about {rate:.3g} steps per simulated "
            f"second here, {projected:.3g} for {duration:g} s (measured over the first "
            f"{probe_time:.3g} s); {cause}; change that parameter, shorten the duration [s], "
            "raise max_steps (--max-steps), or use the stiff solver (options.method = "
            "'auto': RODAS4 where the problem is stiff)")


def probe_time(duration: float, base: float) -> float:
    """The probe's simulated time [s]: ``PROBE_TIME``, a multiple of ``base`` [s]; 0 when
    the run itself is not much longer."""
    if duration <= 4.0 * PROBE_TIME:
        return 0.0
    return max(1, round(PROBE_TIME / base)) * base

