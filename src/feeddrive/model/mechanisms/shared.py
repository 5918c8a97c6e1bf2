"""Parameter classes of parts several mechanisms share: the rotary servo motor and the table.

Sections ``[screw_motor]``, ``[hollow_motor]`` (:class:`Motor`) and ``[table]``
(:class:`Table`), registered in :mod:`feeddrive.registry` (group ``feeddrive.sections``).
"""

from __future__ import annotations

from dataclasses import dataclass

from ... import registry
from ...parameters import Component
from ...parameters.validation import quantity


@dataclass(frozen=True)
class Motor(Component):
    """Permanent-magnet servo motor as an R-L armature with back-EMF.  Wang2021 Table 2.

    Parameters
    ----------
    torque_constant : float
        K_t [N m/A].
    back_emf_constant : float
        K_e [V s/rad].
    inductance : float
        Armature inductance L [H].
    resistance : float
        Armature resistance R [ohm].
    inertia : float
        Rotor inertia J [kg m^2].

    References
    ----------
    .. [1] Wang2021 Table 2.
    """

    torque_constant: float = quantity("N m/A", low=1e-3, high=100)
    back_emf_constant: float = quantity("V s/rad", low=1e-3, high=100)
    inductance: float = quantity("H", low=1e-6, high=1.0, hint="5.9 mH = 0.0059 H")
    resistance: float = quantity("ohm", low=1e-3, high=1e3)
    inertia: float = quantity(
        "kg m^2",
        low=1e-7,
        high=10,
        hint="Wang2021 Table 2 prints 1.38×10³; a servo motor of this size has 1.38×10⁻³",
    )
    _label = "motor"


@dataclass(frozen=True)
class Table(Component):
    """The moving table.

    Parameters
    ----------
    mass : float
        Table mass m_t [kg] (Wang2021 Table 2).

    References
    ----------
    .. [1] Wang2021 Table 2.
    """
    mass: float = quantity("kg", low=0.01, high=1e5)
    _label = "table"




for _name, _cls in (("screw_motor", Motor), ("hollow_motor", Motor), ("table", Table)):
    registry.register(registry.SECTIONS, _name, _cls)
