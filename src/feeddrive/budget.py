"""What a run will cost before it starts: solver steps and memory (issue 12 item 9).

``simulate --duration 100000`` used to reach 12 GB and then stop with a solver error after
50 million steps; the numbers below let the CLI refuse or warn before any work is done.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

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
