"""Backlash (lost motion) at the ball nut or the coupling: a dead-zone spring, and its
describing function.

The screw–nut–table stretch e = H·θ_rel − x_t (``model/mechanisms/ball_screw.py``) passes a
gap of full width b (``gap``, lost motion b, ±b/2 about the centre) before the stiffness law
acts: the transmitted force is

    F_d = 0                                  for |e| ≤ b/2
    F_d = max(0, K_eq·(e − b/2) + c_ax·ė)    for e > b/2
    F_d = min(0, K_eq·(e + b/2) + c_ax·ė)    for e < −b/2

(a dead-zone spring, not smoothed; the contact damping is one-sided — it never pulls the
surfaces together — as in impact models, [1]_).  What the driven side does while the gap is
open is the part's ``gap_behaviour``:

* ``"inertia"`` (inertia-dominated): nothing holds the table; it coasts under its mass, the
  guide's friction and the load until it meets the other flank.
* ``"friction"`` (friction-dominated, the hypothesis of the classical describing function,
  [2]_): the table stops when contact is lost and does not move inside the gap.  Modelled as a
  ground-referenced hold force −m_t·v_t/τ on the table while the gap is open (τ =
  ``hold_time``): its speed decays with time constant τ, so with τ short beside the motion it
  rests where contact was lost.  The hold reacts on the ground, not on the screw.

The gap sits at the nut (``location = "nut"``, between screw and table) or at the coupling
(``location = "coupling"``, between the screw motor's rotor and the screw shaft).  The gap b
is always given at the table: at the coupling it is the angular gap b/H, H = lead/2π.  With a
coupling gap the screw shaft becomes its own body (states ``shaft_angle``, ``shaft_speed``;
every model without the part keeps the shaft lumped with the rotor, ``screw.J`` = J_motor +
J_shaft): the coupling transmits the dead-zone spring of the same kernel :func:`gap_force`,
written at the table (stretch H·(θ_s − θ_sh), stiffness K_c/H², K_c =
``coupling.torsional_stiffness``; the coupling then leaves the torsion term of the K_eq chain,
which keeps the screw's own torsion).  The motor side turns J_motor + s·J_shaft, the screw
side (1 − s)·J_shaft, s = ``motor_side_share`` (default 0: the parameter set's
``screw.shaft_inertia`` is the whole shaft beyond the coupling, the coupling's own inertia
neglected as wang2021 does).  The coupling contact's damping is c_c = 2ζ·sqrt(K_c·J_red)
(J_red = J_m·J_sh/(J_m + J_sh), the two-inertia mode across the coupling), ζ =
``contact_damping_ratio``: default 5 %, the structural damping ratio wang2021 gives the table
mode (its ASSUMPTIONS ``axial-damping-shipped``), since no source gives a coupling's.  The
friction-dominated hold acts on the table while the coupling gap is open: the table, whose
guide friction dominates the driven side, stops where contact was lost, and the light shaft
rests against it through the nut's spring.  (Holding the shaft as well drags the motor at each
of the stiff coupling's re-contacts: the semi-closed P loop then stops short, B/b = 1.14 with
the acceptance test's 3-s dwells.)

The file's ``[backlash]`` section::

    [backlash]
    gap = 1e-5                 # [m]  (10 µm of lost motion, full width, at the table)
    location = "nut"           # or "coupling"
    gap_behaviour = "friction"
    hold_time = 1e-4           # [s]
    motor_side_share = 0.0     # [-]  (coupling gap only)
    contact_damping_ratio = 0.05  # [-]  (coupling gap only)

References
----------
.. [1] K. H. Hunt, F. R. E. Crossley, "Coefficient of restitution interpreted as damping in
   vibroimpact", J. Appl. Mech. 42 (1975) 440–445 (a contact force that never pulls).
.. [2] A. Gelb, W. E. Vander Velde, *Multiple-Input Describing Functions and Nonlinear System
   Design*, McGraw-Hill, 1968, Sect. 2.3 (the friction-dominated backlash and its describing
   function).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ... import registry
from ..._jit import kernel
from ...parameters import Component, ParameterError
from ...parameters.validation import choice, quantity

__all__ = ["Backlash", "backlash_describing_function", "friction_backlash_output",
           "gap_force", "gap_hold"]


@kernel
def gap_force(stretch: float, rate: float, k: float, c: float, half_gap: float) -> float:
    """Force through a dead-zone spring: zero inside the gap, the stiffness law outside.

    Parameters
    ----------
    stretch : float
        The stretch e across spring and gap [m].
    rate : float
        Its rate ė [m/s].
    k : float
        Stiffness outside the gap [N/m].
    c : float
        Damping outside the gap, one-sided (never pulls) [N s/m].
    half_gap : float
        Half the lost motion, b/2 [m].

    Returns
    -------
    float
        The transmitted force [N].
    """
    if stretch > half_gap:
        f = k * (stretch - half_gap) + c * rate
        return f if f > 0.0 else 0.0
    if stretch < -half_gap:
        f = k * (stretch + half_gap) + c * rate
        return f if f < 0.0 else 0.0
    return 0.0


@kernel
def gap_hold(stretch: float, speed: float, half_gap: float, mass: float,
             hold_time: float) -> float:
    """The friction-dominated hold on the driven side while the gap is open.

    Parameters
    ----------
    stretch : float
        The stretch across spring and gap [m].
    speed : float
        The driven side's speed [m/s].
    half_gap : float
        b/2 [m].
    mass : float
        The driven mass [kg].
    hold_time : float
        τ, the time constant of the hold [s]; 0 = no hold (inertia-dominated).

    Returns
    -------
    float
        Force on the driven side, against its speed, zero in contact [N].
    """
    if hold_time <= 0.0 or stretch > half_gap or stretch < -half_gap:
        return 0.0
    return -mass * speed / hold_time


def friction_backlash_output(driver: np.ndarray, gap: float, start: float = 0.0) -> np.ndarray:
    """The driven side's position under friction-dominated backlash, the rigid limit of the
    part's law (K_eq → ∞, the driven side at rest inside the gap).

    In contact the force is non-zero only when |e| > b/2, so with a rigid spring the driven
    side sits at driver ∓ b/2 while pushed and stays where it was inside the gap.

    Parameters
    ----------
    driver : numpy.ndarray
        Driver positions in time order [m].
    gap : float
        The full lost motion b [m].
    start : float, default 0.0
        The driven side's initial position [m].

    Returns
    -------
    numpy.ndarray
        The driven side's positions [m].
    """
    half = 0.5 * gap
    out = np.empty(len(driver))
    y = start
    for i, x in enumerate(np.asarray(driver, dtype=float)):
        if x - y > half:
            y = x - half
        elif x - y < -half:
            y = x + half
        out[i] = y
    return out


def backlash_describing_function(amplitude: float, gap: float, *, points: int = 20000
                                 ) -> complex:
    """The numerical describing function of the friction-dominated backlash: the first
    harmonic of the driven side's motion for a driver A·sin(ωt), divided by A.

    One period is run to reach the periodic state, the next is integrated (rectangle rule
    over ``points`` samples; exact for the sine terms, O(1/points²) at the kinks).

    Parameters
    ----------
    amplitude : float
        Driver amplitude A [m].
    gap : float
        Full lost motion b [m] (python-control's ``friction_backlash_nonlinearity(b)`` takes the
        same full width).
    points : int, default 20000
        Samples per period.

    Returns
    -------
    complex
        N(A) = (b₁ + i·a₁)/A, b₁ and a₁ the sine and cosine Fourier coefficients; 0 for
        A ≤ b/2 (the driven side never moves).

    Raises
    ------
    ParameterError
        For A ≤ 0 or b < 0, or a non-finite value.

    References
    ----------
    .. [1] Gelb & Vander Velde 1968, Sect. 2.3.
    """
    if not (math.isfinite(amplitude) and amplitude > 0):
        raise ParameterError("amplitude", amplitude, "expected A > 0 [m]")
    if not (math.isfinite(gap) and gap >= 0):
        raise ParameterError("backlash.gap", gap, "expected b ≥ 0 [m]")
    phase = 2.0 * math.pi * np.arange(2 * points) / points
    y = friction_backlash_output(amplitude * np.sin(phase), gap)[points:]
    phase = phase[points:]
    b1 = 2.0 / points * float(np.sum(y * np.sin(phase)))
    a1 = 2.0 / points * float(np.sum(y * np.cos(phase)))
    return complex(b1, a1) / amplitude


@dataclass(frozen=True)
class Backlash(Component):
    """Backlash at the ball nut or the coupling (``[backlash]``; see the module docstring).

    Parameters
    ----------
    gap : float
        The lost motion b at the table, full width (±b/2 about the centre) [m].
    location : str, default "nut"
        Where the gap is: ``"nut"`` (between screw and table) or ``"coupling"`` (between the
        screw motor and the screw shaft; the angular gap is b/H).
    gap_behaviour : str, default "friction"
        ``"friction"``: the table is held inside the gap; ``"inertia"``: it coasts.
    hold_time : float, default 1e-4
        τ of the friction-dominated hold [s].
    motor_side_share : float, default 0.0
        Coupling gap: the share s of ``screw.shaft_inertia`` that turns with the motor [-].
    contact_damping_ratio : float, default 0.05
        Coupling gap: ζ of the contact damping c_c = 2ζ·sqrt(K_c·J_red) [-].
    """

    gap: float = quantity("m", low=0, high=1e-3, hint="10 µm = 1e-5 m")
    location: str = choice(("nut", "coupling"), default="nut")
    gap_behaviour: str = choice(("friction", "inertia"), default="friction")
    hold_time: float = quantity("s", low=0, high=1.0, default=1e-4, hint="0.1 ms = 1e-4 s")
    motor_side_share: float = quantity("-", low=0, high=0.99, low_inclusive=True, default=0.0,
                                       hint="a fraction below 1 (the shaft keeps some inertia)")
    contact_damping_ratio: float = quantity("-", low=0, high=1.0, low_inclusive=True,
                                            default=0.05, hint="5 % = 0.05")
    _label = "backlash"

    def declare_part(self, b: Any, axes: list[Any]) -> list[Any]:
        """Register the part's slots (``backlash.half_gap``, ``backlash.hold_time``) that the
        ball-screw mechanism's stretch (at the nut or the coupling, ``location``) reads;
        refuse a drive without a ball nut.

        Parameters
        ----------
        b : Builder
            The model being assembled.
        axes : list of Axis
            The mechanism's controller axes (returned unchanged).

        Returns
        -------
        list of Axis
            ``axes``.

        Raises
        ------
        ParameterError
            When the drive has no ball nut (no ``screw`` axis).
        """
        if "screw" not in [ax.name for ax in axes]:
            raise ParameterError("backlash.location", self.location,
                                 "the drive has no ball nut; a [backlash] part needs a "
                                 "ball-screw drive (cdfs, ddfs)")
        hold = self.hold_time if self.gap_behaviour == "friction" else 0.0
        b.named_params(self._label, ("half_gap", "hold_time"), np.array([0.5 * self.gap, hold]))
        return axes

    def emit_part(self, b: Any) -> None:
        """Nothing of its own: the mechanism writes the gap into its stretch
        (:func:`gap_force`, :func:`gap_hold`).

        Parameters
        ----------
        b : Builder
            The model being assembled.
        """


registry.register(registry.SECTIONS, "backlash", Backlash)
