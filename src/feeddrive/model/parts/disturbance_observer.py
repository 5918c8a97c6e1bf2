"""Disturbance observer (DOB): the current the velocity loop's nominal plant does not explain,
low-pass filtered and added to the current command.

    î_d = Q(s)·(i − G_n⁻¹ ω) = Q(s)·(i + J_g·g·ω) − J_g·g·ω,    Q(s) = g / (s + g),
    G_n(s) = 1 / (J_g·s),   J_g = J_n / K_t

with i the current command applied, ω the measured motor speed and J_n/K_t the nominal
inertia per torque constant (the moving mass referred to the motor over K_t; m_n/K_f for a
linear motor).  The second form needs no differentiation of ω.  Ohnishi's disturbance
observer [1]_ in the form of Umeno and Hori [2]_: everything the nominal inertia does not
explain — friction, load, model error — is estimated and cancelled below the Q filter's
bandwidth g.  Evaluated at the *sampled* velocity loop's instants, before its PI update, on the
loop's measured speed (a continuous velocity loop is refused); the filter state is advanced
exactly for the held input, w ← a·w + (1 − a)·(i + J_g·g·ω), a = exp(−g·T_v).  The file's
``[disturbance_observer]`` section gives it::

    [disturbance_observer]
    bandwidth = 300.0        # g [rad/s]
    inertia_gain = 2.6e-3    # J_n/K_t [A s^2/rad]

References
----------
.. [1] K. Ohnishi, M. Shibata, T. Murakami, "Motion control for advanced mechatronics",
   IEEE/ASME Trans. Mechatronics 1 (1996) 56–67.
.. [2] T. Umeno, Y. Hori, "Robust speed control of DC servomotors using modern two
   degrees-of-freedom controller design", IEEE Trans. Ind. Electron. 38 (1991) 363–368.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from ... import registry
from ...parameters import Component, ParameterError
from ...parameters.validation import quantity
from . import added_feedforward, axis_index


@dataclass(frozen=True)
class DisturbanceObserver(Component):
    """Disturbance observer on one axis' velocity loop (``[disturbance_observer]``).

    Parameters
    ----------
    bandwidth : float
        The first-order Q filter's bandwidth g [rad/s].
    inertia_gain : float
        The nominal plant's inertia over the torque constant J_n/K_t [A s^2/rad]
        (m_n/K_f [A s^2/m] for a linear motor).
    axis : str, default ""
        The controller axis (``"screw"``, ``"motor"``, …; "" = the table-driving axis, the
        drive's first).
    """

    bandwidth: float = quantity("rad/s", low=1e-3, high=1e6, hint="50 Hz ≈ 314 rad/s")
    inertia_gain: float = quantity("A s^2/rad", low=0, high=1e6)
    axis: str = ""
    _label = "disturbance_observer"

    def declare_part(self, b: Any, axes: list[Any]) -> list[Any]:
        """Register the part's slots, run the observer before the chosen axis' velocity update
        and add its estimate to that axis' current command.

        Parameters
        ----------
        b : Builder
            The model being assembled.
        axes : list of Axis
            The mechanism's controller axes.

        Returns
        -------
        list of Axis
            The axes, the chosen one with the observer as velocity prelude and its estimate
            as current feed-forward.

        Raises
        ------
        ParameterError
            For an unknown axis or a continuous velocity loop.
        """
        i = axis_index(self._label, self.axis, axes)
        period = b.param_values[b.param_index[b.q("controller.velocity_period")]]
        if period <= 0.0:
            raise ParameterError("controller.velocity_period", period,
                                 "the disturbance observer runs at a sampled velocity loop's "
                                 "instants; expected 1e-6 … 0.1 [s]")
        b.named_params(self._label, ("bandwidth", "inertia_gain"),
                       np.array([self.bandwidth, self.inertia_gain]))
        estimate = b.add_held(f"{self._label}.current")
        b.add_held(f"{self._label}.filter")
        w = b.h(f"{self._label}.filter")
        g, jg = b.p(f"{self._label}.bandwidth"), b.p(f"{self._label}.inertia_gain")
        ax = axes[i]
        held_command = b.h(f"{ax.name}.current_command")
        # the current applied over the last period: the loop's held command and this estimate
        prelude = (f"w_dob = {jg} * {g} * {ax.speed_q}",
                   f"a_dob = math.exp(-{g} * tv)",
                   f"{w} = a_dob * {w} + (1.0 - a_dob) * ({held_command} + {estimate} + w_dob)",
                   f"{estimate} = {w} - w_dob")
        b.add_aux(f"{self._label}_current", "A",
                  "disturbance-observer current (updated at the velocity loop's instants)")
        b.emit(f"{{{self._label}_current}} = {estimate}")  # a held value: no state
        axes = list(axes)
        axes[i] = dataclasses.replace(
            ax, velocity_prelude=(*ax.velocity_prelude, *prelude),
            current_feedforward=added_feedforward(ax, estimate))
        return axes

    def emit_part(self, b: Any) -> None:
        """Nothing more to write: the observer runs in the velocity loop's update (its prelude).

        Parameters
        ----------
        b : Builder
            The model being assembled.
        """


registry.register(registry.SECTIONS, "disturbance_observer", DisturbanceObserver)
