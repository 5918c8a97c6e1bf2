"""A cross-axis inertial force: a mass carried by one axis and guided by another.

An axis ``target`` (say y, mounted on x) carries a mass m that x accelerates across y's
guide; the guide's preload turns a share of that into a force along y:
F_y = −κ·m·ẍ, κ the cross-coupling factor (an assembly's squareness or a guide's
compliance; 0 ≤ κ ≤ 1) [1]_.  It reads x's acceleration ``der(x.table_speed)`` and writes
``y.external_force``: the example of docs/machine.md and of issue 40's acceptance (a part
that reads one axis' acceleration and writes another's load force).

References
----------
.. [1] Y. Altintas, Manufacturing Automation, 2nd ed., Cambridge University Press (2012),
   Sect. 6.6 (cross-axis coupling of multi-axis feed drives).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ...parameters import ParameterError
from . import Coupling, register_coupling


@register_coupling
@dataclass(frozen=True)
class InertialCoupling(Coupling):
    """F_target = −factor · mass · (acceleration of source's table).

    Parameters
    ----------
    name : str
        The instance's name.
    source : str, default "x"
        The axis whose table acceleration is read.
    target : str, default "y"
        The axis whose table takes the force.
    mass : float, default 0.0
        The coupled mass m [kg].
    factor : float, default 1.0
        The share κ of m·ẍ that acts along the target [-].
    """

    source: str = "x"
    target: str = "y"
    mass: float = 0.0
    factor: float = 1.0
    part: ClassVar[str] = "inertial"
    citation: ClassVar[str] = "Altintas 2012, Manufacturing Automation, Sect. 6.6"
    units: ClassVar[dict[str, str]] = {"mass": "kg", "factor": "-"}

    def __post_init__(self) -> None:
        if not 0.0 <= self.mass <= 1e5:
            raise ParameterError(f"couplings.{self.name}.mass", self.mass,
                                 "expected 0 … 1e5 [kg]")
        if not -1.0 <= self.factor <= 1.0:
            raise ParameterError(f"couplings.{self.name}.factor", self.factor,
                                 "expected −1 … 1 [-]")

    def equations(self) -> dict[str, str]:
        """The one equation, ``target.external_force = −factor · mass ·
        der(source.table_speed)``.

        Returns
        -------
        dict of str to str
            Written signal → expression.
        """
        return {f"{self.target}.external_force":
                f"-{{factor}} * {{mass}} * {{der({self.source}.table_speed)}}"}
