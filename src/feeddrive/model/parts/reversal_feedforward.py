"""Reversal feed-forward: a current step at each zero crossing of the commanded table speed,
faded out as the speed grows.  Updated at a sample period of its own.

    i_r(t) = I_r · sgn(v_k) · exp(−|v_k| / v_w)   for t_k ≤ t < t_k + T_r,   v_k = v_ref(t_k)

added to the current command of one axis (the table-driving motor by default) in every loop
configuration.  When the commanded speed crosses zero the friction force flips by twice its
Coulomb level while the velocity loop's integral still holds the old sign: the quadrant glitch
of a circular test.  CNC friction compensation injects a current step at that crossing whose
weight fades with the speed, since at speed the integral has taken the friction over
(e.g. the "friction compensation" of Siemens SINUMERIK and Heidenhain TNC controls, described
in [1]_ and [2]_): here the weight exp(−|v|/v_w) of the speed band v_w.  I_r [A] is the
current that carries the Coulomb friction the motor sees (for a screw drive
F_c·H/K_t, for a linear motor F_c/K_f).  The file's ``[reversal_feedforward]`` section gives
it::

    [reversal_feedforward]
    current = 0.3      # [A]
    width = 2e-3       # [m/s]
    period = 1e-3      # [s]

Its period joins the breakpoint grid of the sampled loops (a multiple of the fastest one; the
loops must be sampled, as for the acceleration feed-forward).

References
----------
.. [1] B. Armstrong-Hélouvry, P. Dupont, C. Canudas de Wit, "A survey of models, analysis
   tools and compensation methods for the control of machines with friction", Automatica 30
   (1994) 1083–1138, Sect. 5 (friction feed-forward at velocity reversals).
.. [2] Y. Altintas, A. Verl, C. Brecher, L. Uriarte, G. Pritschow, "Machine tool feed drives",
   CIRP Annals 60 (2011) 779–796, Sect. 4 (quadrant glitch compensation in CNC kernels).
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
class ReversalFeedforward(Component):
    """Reversal feed-forward with its own sample period (``[reversal_feedforward]``).

    Parameters
    ----------
    current : float
        The step I_r at a zero crossing of the commanded table speed [A].
    width : float
        The speed band v_w over which its weight exp(−|v|/v_w) fades [m/s].
    period : float
        Its sample period T_r [s]: the weight is re-evaluated and held every T_r.
    axis : str, default ""
        The controller axis it feeds (``"screw"``, ``"motor"``, …; "" = the table-driving
        axis, the drive's first).
    """

    current: float = quantity("A", low=0, high=1e4, low_inclusive=True)
    width: float = quantity("m/s", low=1e-9, high=10.0, hint="2 mm/s = 2e-3 m/s")
    period: float = quantity("s", low=1e-6, high=1.0, hint="1 kHz = 1e-3 s")
    axis: str = ""
    _label = "reversal_feedforward"

    def schedule(self) -> tuple[tuple[str, float], ...]:
        """The part's sample schedule, merged with the other sampled parts' as exact event times.

        Returns
        -------
        tuple of (str, float)
            (field, period [s]) pairs: the one ``period`` field.
        """
        return (("period", self.period),)

    def declare_part(self, b: Any, axes: list[Any]) -> list[Any]:
        """Register the part's slots and add its held current to the chosen axis' feed-forward.

        Parameters
        ----------
        b : Builder
            The model being assembled.
        axes : list of Axis
            The mechanism's controller axes.

        Returns
        -------
        list of Axis
            The axes, the chosen one with the reversal current added to its feed-forward.
        """
        i = axis_index(self._label, self.axis, axes)
        b.named_params(self._label, ("current", "width", "period"),
                       np.array([self.current, self.width, self.period]))
        b.clock(f"{self._label}.period")
        held = b.add_held(f"{self._label}.current")
        b.add_aux(f"{self._label}_current", "A",
                  f"reversal feed-forward current (updated every {self.period:g} s)")
        b.emit(f"{{{self._label}_current}} = {held}")  # a held value: no state
        axes = list(axes)
        axes[i] = dataclasses.replace(axes[i],
                                      current_feedforward=added_feedforward(axes[i], held))
        return axes

    def emit_part(self, b: Any) -> None:
        """Write the part's sampled update (after the loops', where ``ref_v`` is known).

        Parameters
        ----------
        b : Builder
            The model being assembled.
        """
        current, width = b.p(f"{self._label}.current"), b.p(f"{self._label}.width")
        held = b.h(f"{self._label}.current")
        tick = b.tick(f"{self._label}.period")
        for line in (f"if {tick} >= 0:",
                     "    if ref_v > 0.0:",
                     f"        {held} = {current} * math.exp(-ref_v / {width})",
                     "    elif ref_v < 0.0:",
                     f"        {held} = -{current} * math.exp(ref_v / {width})",
                     "    else:",
                     f"        {held} = 0.0"):
            b.emit(line, sampled=True)


registry.register(registry.SECTIONS, "reversal_feedforward", ReversalFeedforward)
