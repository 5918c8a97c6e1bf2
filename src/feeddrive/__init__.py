"""feeddrive: low-speed simulation and analysis of machine-tool feed drives (Wang2021).

Pipeline: parameters → drive system (assembled from parts, :mod:`feeddrive.model`) →
simulate → Result → analyses → report::

    import feeddrive as fd
    params = fd.preset("wang2021")
    result = fd.simulate(fd.DriveSystem(params, "ddfs", 0.4),
                         fd.ConstantSpeed(0.5e-3, 16e-3), 10.0)
    fd.critical_speed_from_rest(fd.DriveSystem(params, "cdfs", 0.4))

The public names are imported on first use (PEP 562), so that ``import feeddrive`` and
``feeddrive --help`` do not pay for scipy, numba and xarray (issue 12 item 6).
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import TYPE_CHECKING, Any

from . import _compat

__version__ = "0.2.0"

# public name → module that defines it ("" : the name is a submodule, see _SUBMODULES)
_PUBLIC: dict[str, str] = {
    "Target": "analysis.calibrate", "Unknown": "analysis.calibrate",
    "calibrate": "analysis.calibrate",
    "CriticalSpeed": "analysis.critical", "critical_speed_from_rest": "analysis.critical",
    "critical_speed_stepdown": "analysis.critical",
    "CreepMetrics": "analysis.creep_window", "CreepThresholds": "analysis.creep_window",
    "creep_metrics": "analysis.creep_window",
    "ConstantSpeed": "model.reference", "SampledSpeed": "model.reference",
    "SineSpeed": "model.reference", "stepdown": "model.reference",
    "trapezoid": "model.reference",
    "LoadProfile": "model", "register_friction_law": "model", "register_mechanism": "model",
    "DriveParameters": "parameters", "ParameterError": "parameters", "load": "parameters",
    "preset": "parameters", "save": "parameters",
    "Result": "engine.result",
    "DriveSystem": "engine.simulate", "Simulation": "engine.simulate",
    "SimulationError": "engine.simulate", "SolverOptions": "engine.simulate",
    "simulate": "engine.simulate",
    "frequency_response": "analysis.linear", "linearize": "analysis.linear",
    "loop_analysis": "analysis.linear", "stability_band": "analysis.linear",
    "friction": "", "linear": "", "model": "",
}
# public submodule name → the module it is
_SUBMODULES: dict[str, str] = {"friction": "model.friction.stribeck", "linear": "analysis.linear",
                               "model": "model"}

if TYPE_CHECKING:
    from . import model
    from .analysis import linear
    from .analysis.calibrate import Target, Unknown, calibrate
    from .analysis.creep_window import CreepMetrics, CreepThresholds, creep_metrics
    from .analysis.critical import (
        CriticalSpeed,
        critical_speed_from_rest,
        critical_speed_stepdown,
    )
    from .analysis.linear import frequency_response, linearize, loop_analysis, stability_band
    from .engine.result import Result
    from .engine.simulate import DriveSystem, Simulation, SimulationError, SolverOptions, simulate
    from .model import LoadProfile, register_friction_law, register_mechanism
    from .model.friction import stribeck as friction
    from .model.reference import ConstantSpeed, SampledSpeed, SineSpeed, stepdown, trapezoid
    from .parameters import DriveParameters, ParameterError, load, preset, save


def __getattr__(name: str) -> Any:
    module = _PUBLIC.get(name)
    if module is None:
        if f"{__name__}.{name}" in _compat.MOVED_MODULES:  # a module of 7831378 that moved
            return importlib.import_module(f"{__name__}.{name}")
        raise AttributeError(f"module 'feeddrive' has no attribute {name!r}")
    if module == "":
        value = importlib.import_module(f".{_SUBMODULES[name]}", __name__)
    else:
        value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """The public names only (not this module's own imports and helpers)."""
    return sorted({*__all__, *_PUBLIC})


class _Package(types.ModuleType):
    """Importing a submodule sets it as an attribute of its package; ``feeddrive.simulate``
    must stay the function (as with eager imports), not become the module of that name."""

    def __setattr__(self, name: str, value: Any) -> None:
        if isinstance(value, types.ModuleType) and _PUBLIC.get(name) not in (None, ""):
            return
        if isinstance(value, _compat.MovedModule) and name in _PUBLIC:
            return  # `import feeddrive.linear` keeps `feeddrive.linear` the module it names
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
# the modules of 7831378 that moved stay importable until 0.3.0, with a warning (_compat)
_compat.install()


__all__ = [
    "ConstantSpeed", "CreepMetrics", "CreepThresholds", "CriticalSpeed", "DriveParameters",
    "DriveSystem", "LoadProfile", "ParameterError", "Result", "SampledSpeed", "Simulation",
    "SimulationError",
    "SineSpeed", "SolverOptions", "Target", "Unknown", "__version__", "calibrate",
    "creep_metrics", "critical_speed_from_rest", "critical_speed_stepdown",
    "frequency_response", "friction", "linear", "linearize", "load", "loop_analysis", "model",
    "preset", "register_friction_law", "register_mechanism", "save", "simulate",
    "stability_band", "stepdown", "trapezoid",
]
