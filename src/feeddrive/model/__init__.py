"""The composable drive model: parts assembled into one compiled system.

* :mod:`~feeddrive.model.mechanisms` — topologies (CDFS/DDFS ball screw, linear motor);
* :mod:`~feeddrive.model.friction` — friction laws (LuGre, static Stribeck, Dahl, none);
* :mod:`~feeddrive.model.loops` — cascade loops per motor axis, continuous or sampled;
* :mod:`~feeddrive.model.disturbances` — load force, torque ripple, lead error;
* ``feeddrive.model.reference`` — reference profiles (what the table is commanded to do);
* :mod:`~feeddrive.model.assemble` — parts → :class:`Model` (names, packed vectors, kernels);
* :mod:`~feeddrive.model.codegen` — the builder and the per-model generated module (numba-cached
  where numba is installed; its kernels translated to C for the engine).

See docs/extending.md for adding a part.
"""

from __future__ import annotations

from .._jit import kernel
from .assemble import Model, assemble
from .disturbances import LoadProfile
from .friction import FrictionLaw, LinearFriction, friction_law, law_names, register_friction_law
from .mechanisms import Mechanism, drive_names, mechanism, register_mechanism

__all__ = ["FrictionLaw", "LinearFriction", "LoadProfile", "Mechanism", "Model", "assemble",
           "drive_names", "friction_law", "kernel", "law_names", "mechanism",
           "register_friction_law", "register_mechanism"]
