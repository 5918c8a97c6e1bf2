"""Acceleration feed-forward, updated at a sample period of its own.

    i_ff(t) = K_a · a_k  for t_k ≤ t < t_k + T_a,    a_k = (v_ref(t_k) − v_ref(t_k − T_a)) / T_a

added to the current command of one axis (the table-driving motor by default) in every loop
configuration.  The commanded table acceleration is estimated as a drive's trajectory
generator does, by differencing the commanded table speed over one period T_a of its own, and
held in between: a part with its own rate — e.g. updated at 1 kHz while the current loop runs
at 8 kHz.  K_a [A s²/m] is the current per table acceleration (for a rigid drive, the moving
mass referred to the motor divided by the force constant at the table: m·H/K_t for a screw
drive of transmission H).  The file's ``[acceleration_feedforward]`` section gives it::

    [acceleration_feedforward]
    gain = 0.02        # [A s^2/m]
    period = 1e-3      # [s]

Its period joins the breakpoint grid of the sampled loops (it must be a multiple of the
fastest one, and the loops must be sampled: the breakpoints of continuous loops assume nothing
jumps there).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from ... import registry
from ...parameters import Component
from ...parameters.validation import quantity
from . import added_feedforward, axis_index


@dataclass(frozen=True)
class AccelerationFeedforward(Component):
    """Acceleration feed-forward with its own sample period (``[acceleration_feedforward]``).

    Parameters
    ----------
    gain : float
        Current per commanded table acceleration K_a [A s^2/m].
    period : float
        Its sample period T_a [s]: the acceleration is re-estimated and held every T_a.
    axis : str, default ""
        The controller axis it feeds (``"screw"``, ``"motor"``, …; "" = the table-driving
        axis, the drive's first).
    """

    gain: float = quantity("A s^2/m", low=0, high=1e6, low_inclusive=True)
    period: float = quantity("s", low=1e-6, high=1.0, hint="1 kHz = 1e-3 s")
    axis: str = ""
    _label = "acceleration_feedforward"

    def schedule(self) -> tuple[tuple[str, float], ...]:
        """The part's sample schedule, merged with the other sampled parts' as exact event times.

        Returns
        -------
        tuple of (str, float)
            (field, period [s]) pairs: the one ``period`` field.
        """
        return (("period", self.period),)

    def declare_part(self, b: Any, axes: list[Any]) -> list[Any]:
        """Register the part's slots and wire its held current into the chosen axis.

        Parameters
        ----------
        b : Builder
            The model being assembled.
        axes : list of Axis
            The mechanism's controller axes.

        Returns
        -------
        list of Axis
            The axes, the chosen one with the feed-forward current added.
        """
        i = axis_index(self._label, self.axis, axes)
        b.named_params(self._label, ("gain", "period"), np.array([self.gain, self.period]))
        b.clock(f"{self._label}.period")
        current = b.add_held(f"{self._label}.current")
        b.add_held(f"{self._label}.previous_speed")
        b.add_aux(f"{self._label}_current", "A",
                  f"acceleration feed-forward current (updated every {self.period:g} s)")
        b.emit(f"{{{self._label}_current}} = {current}")  # a held value: no state
        axes = list(axes)
        axes[i] = dataclasses.replace(axes[i],
                                      current_feedforward=added_feedforward(axes[i], current))
        return axes

    def emit_part(self, b: Any) -> None:
        """Write the part's sampled update (after the loops', where ``ref_v`` is known).

        Parameters
        ----------
        b : Builder
            The model being assembled.
        """
        gain, period = b.p(f"{self._label}.gain"), b.p(f"{self._label}.period")
        current, previous = b.h(f"{self._label}.current"), b.h(f"{self._label}.previous_speed")
        tick = b.tick(f"{self._label}.period")
        for line in (f"if {tick} >= 0:",
                     f"    if {tick} == 0:",
                     f"        {current} = 0.0",
                     "    else:",
                     f"        {current} = {gain} * (ref_v - {previous}) / {period}",
                     f"    {previous} = ref_v"):
            b.emit(line, sampled=True)


registry.register(registry.SECTIONS, "acceleration_feedforward", AccelerationFeedforward)
