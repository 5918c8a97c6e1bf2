"""feeddrive: low-speed simulation and analysis of machine-tool feed drives (Wang2021).

Pipeline: parameters → drive system (assembled from parts, :mod:`feeddrive.model`) →
simulate → Result → analyses → report::

    import feeddrive as fd
    params = fd.preset("wang2021")
    result = fd.simulate(fd.DriveSystem(params, "ddfs", 0.4),
                         fd.ConstantSpeed(0.5e-3, 16e-3), 10.0)
    fd.critical_speed_from_rest(fd.DriveSystem(params, "cdfs", 0.4))
"""

from . import friction, model
from .analysis.calibrate import Target, Unknown, calibrate
from .analysis.critical import (
    CriticalSpeed,
    critical_speed_from_rest,
    critical_speed_stepdown,
)
from .analysis.metrics import CreepMetrics, CreepThresholds, creep_metrics
from .control import ConstantSpeed, SampledSpeed, SineSpeed
from .model import LoadProfile, register_friction_law, register_mechanism
from .parameters import DriveParameters, ParameterError, load, preset, save
from .result import Result
from .simulate import DriveSystem, SimulationError, SolverOptions, simulate

__version__ = "0.1.0"

__all__ = [
    "ConstantSpeed", "CreepMetrics", "CreepThresholds", "CriticalSpeed", "DriveParameters",
    "DriveSystem", "LoadProfile", "ParameterError", "Result", "SampledSpeed", "SimulationError",
    "SineSpeed", "SolverOptions", "Target", "Unknown", "__version__", "calibrate",
    "creep_metrics", "critical_speed_from_rest", "critical_speed_stepdown", "friction", "load",
    "model", "preset", "register_friction_law", "register_mechanism", "save", "simulate",
]
