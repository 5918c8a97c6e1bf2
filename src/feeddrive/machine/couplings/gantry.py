"""A gantry: one beam on two carriages, and the controllers that keep the carriages together.

**The beam** (``part = "gantry_beam"``) rests on the tables of two axes ``a`` and ``b``
(two ball screws, say), a span L apart.  It is a rigid body with a position X and a yaw θ
(small angles: its ends sit at X ∓ (L/2)·θ), joined to each carriage by a joint of axial
stiffness k and damping c, and held against yaw by the guides' racking stiffness k_θ.  A
process load F acts on it at the fraction λ of the span from carriage a:

    F_a = k (x_a − X + L θ/2) + c (v_a − V + L Ω/2)      (on the beam; a load on carriage a)
    F_b = k (x_b − X − L θ/2) + c (v_b − V − L Ω/2)
    M dV/dt = F_a + F_b − F
    J dΩ/dt = (L/2)(F_b − F_a) − k_θ θ − (λ − 1/2) L F

In a static balance with both carriages held at one position,
θ = −(λ − 1/2) L F / (k L²/2 + k_θ) and F_a,b = (F ± k L θ)/2 — the hand balance
``tests/validation/test_gantry.py`` checks.

**Master–slave** (``part = "master_slave"``) commands the slave's position loop with the
master's actual position instead of the reference: a speed correction
K·(x_master − x_ref) on the slave (K the slave's position gain).  **Cross-coupled**
(``part = "cross_coupled"``) is Koren's cross-coupled controller [1]_, [3]_: the
synchronisation error ε = x_a − x_b goes through a PID compensator
C_c(s) = K_c + K_i/s + K_d s, whose output u = K_c ε + K_i ∫ε + K_d ε̇ (ε̇ = v_a − v_b) is
subtracted from a's speed command and added to b's [1]_, [2]_.

Why the proportional term alone is weak, and what the derivative term does.  The correction
enters each axis' speed command (the position loop's output), so for the difference mode
(ε, with the beam's yaw θ ≈ ε/L: the joints, k L²/2 = 5e6 N m/rad, are 50× stiffer than
the guides' racking k_θ) the velocity loop's error becomes

    e_v = −(K_p + 2K_c) ε − (1 + 2K_d) ε̇ − 2K_i ∫ε .

* K_c only raises the difference mode's *position* gain K_p → K_p + 2K_c.  The yaw of a
  move comes from a force difference (one screw's friction ×2), which the position gain
  barely resists — a force reaches the position through the velocity loop, whose PI
  absorbs it — and the difference mode's lightly damped 5.6-Hz velocity-loop pair
  (ζ = 0.04) goes unstable at K_p + 2K_c ≈ 11.6 1/s (K_c,max = 1.78 1/s); at half that it
  doubles the peak compliance from a force on one carriage to ε
  (tests/validation/test_gantry.py).
* K_d multiplies the difference mode's *velocity*-loop gain by 1 + 2K_d: it stiffens the
  gantry against the force difference where the yaw is made and damps the difference mode
  (its 5.6-Hz pair, ζ = 0.04, becomes two modes at 32 and 36 Hz with ζ 0.93 and 0.59 at
  the default gains; peak compliance 18× lower than with no synchronisation).  This is the
  yaw-rate damping of gantry practice.
* K_i adds nothing static: a constant force difference leaves no static ε because each
  axis' velocity PI integrates it away; and the static yaw of an off-centre load sits in
  the joints at ε = 0 (the balance above), where no controller acting on the carriages'
  error can reach it — only a measured beam yaw could.  Its default is 0.

The defaults are set by a stated rule, not from the yaw they give: K_d half the value at
which the machine's linearised closed loop loses stability with K_c = K_i = 0
(:func:`feeddrive.machine.linear.gain_limit`, a 6-dB gain margin; 15.4 on the built-in
gantry at 10 mm/s), and K_c = K_p·K_d, the compensator's zero at the axes' own position
gain K_p (C_c = K_d (s + K_p)), so the difference mode is the axes' own cascade with its
velocity gain ×(1 + 2K_d).

References
----------
.. [1] Y. Koren, "Cross-coupled biaxial computer control for manufacturing systems", ASME J.
   Dyn. Syst. Meas. Control 102 (1980) 265–272.
.. [2] D. Sun, "Position synchronization of multiple motion axes with adaptive coupling
   control", Automatica 39 (2003) 997–1005.
.. [3] Y. Koren, C. C. Lo, "Variable-gain cross-coupling controller for contouring", CIRP
   Annals 40 (1991) 371–374.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ...parameters import ParameterError
from . import Coupling, register_coupling


def _positive(part: Coupling, field: str, value: float, unit: str, zero: bool = False) -> None:
    if not (value > 0 or (zero and value == 0)) or value > 1e12:
        raise ParameterError(f"couplings.{part.name}.{field}", value,
                             f"expected {'≥' if zero else '>'} 0 [{unit}]")


@register_coupling
@dataclass(frozen=True)
class GantryBeam(Coupling):
    """A rigid beam on the tables of axes ``a`` and ``b`` (module docstring).

    Parameters
    ----------
    name : str
        The instance's name; its states are ``<name>.position``, ``.speed``, ``.yaw``,
        ``.yaw_rate``.
    a, b : str, default "x1", "x2"
        The two carriages' axes.
    mass : float, default 100.0
        Beam mass M [kg].
    inertia : float, default 8.33
        Beam yaw inertia J about its centre [kg m^2] (M L²/12 for a uniform 1-m beam).
    span : float, default 1.0
        Distance L between the carriages [m].
    joint_stiffness : float, default 1e7
        Axial stiffness k of each carriage–beam joint [N/m].
    joint_damping : float, default 2000.0
        Damping c of each joint [N s/m].
    yaw_stiffness : float, default 1e5
        Racking stiffness k_θ of the guides [N m/rad].
    load_force : float, default 0.0
        Process load F on the beam [N] (positive opposes positive motion).
    load_position : float, default 0.5
        Where F acts: fraction λ of the span from carriage a [-].

    References
    ----------
    .. [1] Module docstring: the beam's equations and the static balance.
    """

    a: str = "x1"
    b: str = "x2"
    mass: float = 100.0
    inertia: float = 8.33
    span: float = 1.0
    joint_stiffness: float = 1e7
    joint_damping: float = 2000.0
    yaw_stiffness: float = 1e5
    load_force: float = 0.0
    load_position: float = 0.5
    part: ClassVar[str] = "gantry_beam"
    citation: ClassVar[str] = "rigid beam on two carriages (docs/machine.md)"
    units: ClassVar[dict[str, str]] = {
        "mass": "kg", "inertia": "kg m^2", "span": "m", "joint_stiffness": "N/m",
        "joint_damping": "N s/m", "yaw_stiffness": "N m/rad", "load_force": "N",
        "load_position": "-"}

    def __post_init__(self) -> None:
        for field in ("mass", "inertia", "span", "joint_stiffness"):
            _positive(self, field, getattr(self, field), self.units[field])
        for field in ("joint_damping", "yaw_stiffness"):
            _positive(self, field, getattr(self, field), self.units[field], zero=True)
        if not 0.0 <= self.load_position <= 1.0:
            raise ParameterError(f"couplings.{self.name}.load_position", self.load_position,
                                 "expected 0 … 1 [-] (fraction of the span from axis a)")

    def states(self) -> dict[str, tuple[str, str, str, float]]:
        """Position, speed, yaw and yaw rate of the beam.

        Returns
        -------
        dict of str to tuple
            State → (unit, tolerance kind, description, scale).
        """
        half = self.span / 2.0
        return {"position": ("m", "position", "beam position X", 1.0),
                "speed": ("m/s", "speed", "beam speed V", 1.0),
                "yaw": ("rad", "angle", "beam yaw θ", half),
                "yaw_rate": ("rad/s", "rotary_speed", "beam yaw rate Ω", half)}

    def equations(self) -> dict[str, str]:
        """The joint loads on the carriages and the beam's rates (module docstring).

        Returns
        -------
        dict of str to str
            Written signal → expression.
        """
        n, a, b = self.name, self.a, self.b
        f_a = (f"({{joint_stiffness}} * ({{{a}.table_position}} - {{{n}.position}} "
               f"+ 0.5 * {{span}} * {{{n}.yaw}}) + {{joint_damping}} * "
               f"({{{a}.table_speed}} - {{{n}.speed}} + 0.5 * {{span}} * {{{n}.yaw_rate}}))")
        f_b = (f"({{joint_stiffness}} * ({{{b}.table_position}} - {{{n}.position}} "
               f"- 0.5 * {{span}} * {{{n}.yaw}}) + {{joint_damping}} * "
               f"({{{b}.table_speed}} - {{{n}.speed}} - 0.5 * {{span}} * {{{n}.yaw_rate}}))")
        return {
            f"{a}.external_force": f_a,
            f"{b}.external_force": f_b,
            f"der({n}.position)": f"{{{n}.speed}}",
            f"der({n}.speed)": f"({f_a} + {f_b} - {{load_force}}) / {{mass}}",
            f"der({n}.yaw)": f"{{{n}.yaw_rate}}",
            f"der({n}.yaw_rate)": (f"(0.5 * {{span}} * ({f_b} - {f_a}) - {{yaw_stiffness}} * "
                                   f"{{{n}.yaw}} - ({{load_position}} - 0.5) * {{span}} * "
                                   f"{{load_force}}) / {{inertia}}"),
        }


@register_coupling
@dataclass(frozen=True)
class MasterSlave(Coupling):
    """The slave follows the master's actual position: speed correction K·(x_m − x_ref).

    Parameters
    ----------
    name : str
        The instance's name.
    master, slave : str, default "x1", "x2"
        The two axes.
    gain : float, default 8.0
        K, the slave's position gain [1/s] (wang2021: 8 1/s).

    References
    ----------
    .. [1] Module docstring; D. Sun, Automatica 39 (2003) 997–1005 (master–slave as the
       baseline of synchronisation control).
    """

    master: str = "x1"
    slave: str = "x2"
    gain: float = 8.0
    part: ClassVar[str] = "master_slave"
    citation: ClassVar[str] = "Sun 2003, Automatica 39, 997-1005"
    units: ClassVar[dict[str, str]] = {"gain": "1/s"}

    def __post_init__(self) -> None:
        _positive(self, "gain", self.gain, "1/s", zero=True)

    def equations(self) -> dict[str, str]:
        """``slave.speed_correction = gain · (master position − master reference)``.

        Returns
        -------
        dict of str to str
            Written signal → expression.
        """
        m = self.master
        return {f"{self.slave}.speed_correction":
                f"{{gain}} * ({{{m}.table_position}} - {{{m}.table_position_reference}})"}


@register_coupling
@dataclass(frozen=True)
class CrossCoupled(Coupling):
    """Koren's cross-coupled controller: ∓(K_c ε + K_i ∫ε + K_d ε̇) on axes a and b,
    ε = x_a − x_b.

    Parameters
    ----------
    name : str
        The instance's name; its state ``<name>.integral`` is ∫ε [m s].
    a, b : str, default "x1", "x2"
        The two axes.
    gain : float, default 61.6
        K_c [1/s].  By the module's rule, K_p·K_d (the compensator's zero at the axes' own
        position gain, wang2021: 8 1/s).
    integral_gain : float, default 0.0
        K_i [1/s^2] (module docstring: it adds nothing static).
    derivative_gain : float, default 7.7
        K_d [-], on the synchronisation rate ε̇ = v_a − v_b (the tables' speeds).  By the
        module's rule, half the value at which the machine's linearised loop loses
        stability (:func:`feeddrive.machine.linear.gain_limit`, a 6-dB gain margin): 15.4 on
        the built-in gantry (two wang2021 CDFS axes) at 10 mm/s
        (tests/validation/test_gantry.py).

    References
    ----------
    .. [1] Y. Koren, ASME J. Dyn. Syst. Meas. Control 102 (1980) 265–272.
    .. [2] Y. Koren, C. C. Lo, CIRP Annals 40 (1991) 371–374.
    .. [3] D. Sun, Automatica 39 (2003) 997–1005.
    """

    a: str = "x1"
    b: str = "x2"
    gain: float = 61.6
    integral_gain: float = 0.0
    derivative_gain: float = 7.7
    part: ClassVar[str] = "cross_coupled"
    citation: ClassVar[str] = ("Koren 1980, ASME JDSMC 102, 265-272; Koren & Lo 1991, CIRP "
                               "Annals 40; Sun 2003, Automatica 39")
    units: ClassVar[dict[str, str]] = {"gain": "1/s", "integral_gain": "1/s^2",
                                       "derivative_gain": "-"}

    def __post_init__(self) -> None:
        _positive(self, "gain", self.gain, "1/s", zero=True)
        _positive(self, "integral_gain", self.integral_gain, "1/s^2", zero=True)
        _positive(self, "derivative_gain", self.derivative_gain, "-", zero=True)

    def states(self) -> dict[str, tuple[str, str, str, float]]:
        """The integral of the synchronisation error.

        Returns
        -------
        dict of str to tuple
            State → (unit, tolerance kind, description, scale).
        """
        return {"integral": ("m s", "none", "integral of the synchronisation error", 1.0)}

    def equations(self) -> dict[str, str]:
        """The two corrections (the PID of ε, its rate from the tables' speeds) and the
        integral's rate.

        Returns
        -------
        dict of str to str
            Written signal → expression.
        """
        a, b, n = self.a, self.b, self.name
        eps = f"({{{a}.table_position}} - {{{b}.table_position}})"
        rate = f"({{{a}.table_speed}} - {{{b}.table_speed}})"
        u = (f"({{gain}} * {eps} + {{integral_gain}} * {{{n}.integral}} "
             f"+ {{derivative_gain}} * {rate})")
        return {f"{a}.speed_correction": f"-{u}", f"{b}.speed_correction": u,
                f"der({n}.integral)": eps}
