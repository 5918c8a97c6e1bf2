"""Coupling parts of a machine: parts joined to the axes by named signals.

A coupling part (``[couplings.<name>] part = "…"`` in a machine file) declares, in one place,
what it computes: :meth:`Coupling.equations` maps each signal it writes to an expression in
which every signal it reads and every parameter it uses is named in braces —
``{"y.external_force": "-{mass} * {der(x.table_speed)}"}``.  The assembler reads the reads
and writes from those expressions alone (no second declaration), connects them to the axes'
signals, orders the parts so that every value is computed before it is read, and refuses,
before any work, with one line naming the signal or the part:

* a signal read that no axis or part writes;
* a signal written by two parts;
* a cycle of algebraic signals (a part reading a derivative or signal of an axis whose input
  it, or a part it feeds, writes).

Names a part may read: an axis' state (``x.table_position``: no algebraic dependency), the
rate of a state (``der(x.table_speed)``: x's acceleration), an axis' signal
(``x.drive_force``), a signal another part writes or a part's own state.  It may write an
axis' input — ``<axis>.external_force`` [N], a load on the table (positive opposes positive
motion, as the load force), ``<axis>.speed_correction`` [m/s], added to the axis' continuous
speed command — and the rates of its own states, ``der(<part>.<state>)``
(:meth:`Coupling.states`: a beam's position and yaw, a controller's integral).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, ClassVar

from ... import registry
from ...model.codegen import SIGNAL
from ...parameters import ParameterError

#: the inputs an axis offers its machine's parts: name → (unit, description)
AXIS_INPUTS = {
    "external_force": ("N", "load on the table from the machine's coupling parts (as the "
                            "load force: positive opposes positive motion)"),
    "speed_correction": ("m/s", "table speed added to the speed command by the machine's "
                                "synchronisation part"),
}


@dataclass(frozen=True)
class Coupling:
    """A part of a machine that reads and writes its axes' signals by name.

    Subclasses set :attr:`part` (the name a machine file gives), :attr:`citation`, their
    parameters as dataclass fields (SI) with :attr:`units`, and implement :meth:`equations`.

    Parameters
    ----------
    name : str
        The instance's name (``[couplings.<name>]``).
    """

    name: str
    part: ClassVar[str] = ""
    citation: ClassVar[str] = ""
    #: parameter field → its unit (the fields a file may give, besides ``part``)
    units: ClassVar[dict[str, str]] = {}

    def parameters(self) -> dict[str, float]:
        """The part's numeric parameters by name [SI].

        Returns
        -------
        dict of str to float
            Field → value.
        """
        return {k: float(getattr(self, k)) for k in self.units}

    def states(self) -> dict[str, tuple[str, str, str, float]]:
        """The part's own states, named ``<part>.<state>`` in the model: state →
        (unit, tolerance kind, description, tolerance scale); none by default.

        Returns
        -------
        dict of str to tuple
            E.g. ``{"yaw": ("rad", "angle", "beam yaw", 0.5)}`` (an angle's scale: metres per
            radian, :meth:`feeddrive.model.codegen.Builder.state`).
        """
        return {}

    def equations(self) -> dict[str, str]:
        """Each written signal → its expression, signals and parameters named in braces.

        Returns
        -------
        dict of str to str
            E.g. ``{"y.external_force": "-{mass} * {der(x.table_speed)}"}``.
        """
        raise NotImplementedError

    def reads(self) -> tuple[str, ...]:
        """The signals the expressions read (every braced name that is no parameter).

        Returns
        -------
        tuple of str
            Signal names, in order of first use.
        """
        own = self.parameters()
        names = [n for expr in self.equations().values() for n in SIGNAL.findall(expr)]
        return tuple(dict.fromkeys(n for n in names if n not in own))

    def writes(self) -> tuple[str, ...]:
        """The signals the part writes (the keys of :meth:`equations`).

        Returns
        -------
        tuple of str
            Signal names.
        """
        return tuple(self.equations())

    @classmethod
    def fields(cls) -> tuple[str, ...]:
        """The fields a machine file may give (besides ``part``): every dataclass field but
        ``name``.

        Returns
        -------
        tuple of str
            Field names.
        """
        return tuple(f.name for f in dataclasses.fields(cls) if f.name != "name")

    @classmethod
    def from_table(cls, name: str, table: dict[str, Any]) -> Coupling:
        """Build the part from its machine-file table; errors name ``couplings.<name>.…``.

        Parameters
        ----------
        name : str
            The instance's name.
        table : dict
            The table without ``part``.

        Returns
        -------
        Coupling
            The part.
        """
        values: dict[str, Any] = {}
        for key, value in table.items():
            field = f"couplings.{name}.{key}"
            if key in cls.units:
                if not (isinstance(value, int | float) and not isinstance(value, bool)
                        and math.isfinite(value)):
                    raise ParameterError(field, value, f"expected a number [{cls.units[key]}]")
                values[key] = float(value)
            elif key in cls.fields():
                if not isinstance(value, str) or not value.isidentifier():
                    raise ParameterError(field, value, "expected an axis name")
                values[key] = value
            else:
                known = list(cls.fields())
                raise ParameterError(field, value, f"unknown key of the {cls.part} part; "
                                     f"expected {', '.join(['part', *known])}")
        try:
            return cls(name=name, **values)
        except TypeError:
            missing = [f for f in cls.fields() if f not in values]
            raise ParameterError(f"couplings.{name}", sorted(table),
                                 f"the {cls.part} part needs {', '.join(missing)}") from None


def register_coupling(part_class: type[Coupling]) -> type[Coupling]:
    """Register a coupling part under its :attr:`Coupling.part` name (a class decorator).

    Parameters
    ----------
    part_class : type
        The part's class.

    Returns
    -------
    type
        The class, unchanged.
    """
    registry.register(registry.COUPLINGS, part_class.part, part_class)
    return part_class


def coupling(part: str) -> type[Coupling]:
    """The registered coupling part ``part``.

    Parameters
    ----------
    part : str
        Its name.

    Returns
    -------
    type
        The part's class.

    Raises
    ------
    ParameterError
        For an unknown name; the message lists the registered ones.
    """
    table = registry.table(registry.COUPLINGS)
    if part not in table:
        raise ParameterError("part", part, f"expected one of {', '.join(sorted(table))}")
    cls: type[Coupling] = table[part]
    return cls
