"""Reset integrator: the velocity loop's integral reset at the zero crossings of the position
error, so that the integral wound up while the table sticks does not carry it through the set
point and back (the hunting limit cycle of a PID-type loop with Stribeck friction).

    J ← γ·J,  x_i ← x_i − (1 − γ)·J    when e_k · e_(k−1) ≤ 0, e_(k−1) ≠ 0 and J · e_(k−1) > 0,
    e_k = x_ref(t_k) − x̂(t_k),   J = Σ T_v · K_pp·e_k  (in the velocity gains' units)

checked at every instant t_k of the *sampled* velocity loop, before its PI update, on the
axis' quantised measured position x̂ (the table scale for the screw motor and a linear motor):
the sampled-data version of the reset at e = 0 of Beerens et al. [1]_ [2]_ (the state jumps at
the first sampling instant at or after the crossing, not at the exact crossing; a continuous
velocity loop is refused).  In a P position + PI velocity cascade the velocity integral
x_i = ∫(K_pp·e + v_ff − v) holds the PID's integral K_pp·∫e (J, what their reset zeroes) plus
the position change (a proportional part, left alone).  γ = 0 is their reset to zero; γ ∈ (0, 1)
keeps a fraction.  The reset happens only while J still pushes the old way (their sector
condition on e·u_i).  Not modelled: their minimum dwell time between resets (the loop's
sample period bounds the reset rate), and J ignores the instants where the anti-windup stops
the integration.

Measured on ``wang2021-drive`` (its own gains: P position, PI velocity, 8/4/2-kHz loops,
0.05-µm scale), a 10-µm move (tests/unit/test_reset_integrator.py).  With the static Stribeck
law at both sites (no presliding memory, the friction of [1]_) and v_ε = 10 µm/s the plain
loop hunts, −113 … +136 counts at 0.215 Hz, and the reset loop stays within one count from
2 s to 10 s; at the law's default v_ε = 1 µm/s the hunting (±58 counts, 0.099 Hz) narrows
from 117 to 12.6 counts peak to peak over 2–10 s but does not hold one count.  With Wang2021's
LuGre law the plain loop does not hunt: its presliding range F_s/σ0 ≈ 2.6 µm makes the last
micrometres an elastic creep, and a reset at the set point releases the bristles' force
(K_pp = 60 1/s, K_vi = 15000 A/m: a 22-Hz cycle of −2.3 … +3.3 counts widened to −7.7 … +7.9;
with friction off these gains diverge).  The file's ``[reset_integrator]`` section gives it::

    [reset_integrator]
    fraction = 0.0     # [-] kept at a reset

References
----------
.. [1] R. Beerens, A. Bisoffi, L. Zaccarian, W. P. M. H. Heemels, H. Nijmeijer,
   N. van de Wouw, "Reset integral control for improved settling of PID-based motion systems
   with friction", Automatica 107 (2019) 483–492.
.. [2] R. Beerens, A. Bisoffi, L. Zaccarian, H. Nijmeijer, W. P. M. H. Heemels,
   N. van de Wouw, "Reset PID design for motion systems with Stribeck friction", IEEE Trans.
   Control Syst. Technol. 30 (2022) 294–310 (early access 2021).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from ... import registry
from ...parameters import Component, ParameterError
from ...parameters.validation import quantity
from .. import loops
from . import axis_index


@dataclass(frozen=True)
class ResetIntegrator(Component):
    """Velocity-loop integral reset at the position error's zero crossings
    (``[reset_integrator]``).

    Parameters
    ----------
    fraction : float, default 0.0
        The fraction γ of the integral kept at a reset [-] (0: reset to zero, Beerens et al.).
    axis : str, default ""
        The controller axis reset (``"screw"``, ``"motor"``, …; "" = the table-driving axis,
        the drive's first).
    """

    fraction: float = quantity("-", low=0, high=1, low_inclusive=True, default=0.0)
    axis: str = ""
    _label = "reset_integrator"

    def declare_part(self, b: Any, axes: list[Any]) -> list[Any]:
        """Register the part's slots and put the reset before the chosen axis' velocity update.

        Parameters
        ----------
        b : Builder
            The model being assembled.
        axes : list of Axis
            The mechanism's controller axes.

        Returns
        -------
        list of Axis
            The axes, the chosen one with the reset as its velocity-loop prelude.

        Raises
        ------
        ParameterError
            For an unknown axis, or a continuous velocity loop (its integral is a state that
            would need a reset event of the integrator).
        """
        i = axis_index(self._label, self.axis, axes)
        period = b.param_values[b.param_index[b.q("controller.velocity_period")]]
        if period <= 0.0:
            raise ParameterError("controller.velocity_period", period,
                                 "the reset integrator acts on a sampled velocity loop; "
                                 "expected 1e-6 … 0.1 [s]")
        b.named_params(self._label, ("fraction",), np.array([self.fraction]))
        previous = b.add_held(f"{self._label}.previous_error")
        b.add_held(f"{self._label}.error_integral")
        b.add_held(f"{self._label}.count")
        count, part = b.h(f"{self._label}.count"), b.h(f"{self._label}.error_integral")
        ax = axes[i]
        o = ax.param_offset
        integral = b.h(f"{ax.name}.velocity_integral")
        fraction = b.p(f"{self._label}.fraction")
        plaw, verr = b.use(loops.position_law), b.use(loops.velocity_error)
        # The velocity integral of a P position + PI velocity cascade is ∫(K_pp·e + v_ff − v):
        # K_pp·∫e (the PID's integral, what [1]_ resets) plus the position change (its
        # proportional part).  The part keeps the first, J, summed as the loop sums it, and
        # resets only that: x_i ← x_i − (1 − γ)·J.  A crossing (or arrival at zero) of the
        # quantised error while J still pushes the old way: their sector condition.
        prelude = (f"e_reset = {ax.reference} - {ax.position_q}",
                   f"if {previous} != 0.0 and e_reset * {previous} <= 0.0 and "
                   f"{part} * {previous} > 0.0:",
                   f"    {integral} -= (1.0 - {fraction}) * {part}",
                   f"    {part} = {fraction} * {part}",
                   f"    {count} += 1.0",
                   f"{part} += tv * {verr}({plaw}(e_reset, 0.0, P, {o}), 0.0, P, {o})",
                   f"{previous} = e_reset")
        axes = list(axes)
        axes[i] = dataclasses.replace(ax, velocity_prelude=(*ax.velocity_prelude, *prelude))
        b.add_aux(f"{self._label}_count", "-", "resets of the velocity-loop integral so far")
        b.emit(f"{{{self._label}_count}} = {count}")  # a held value: no state
        return axes

    def emit_part(self, b: Any) -> None:
        """Nothing more to write: the reset runs in the velocity loop's update (its prelude).

        Parameters
        ----------
        b : Builder
            The model being assembled.
        """


registry.register(registry.SECTIONS, "reset_integrator", ResetIntegrator)
