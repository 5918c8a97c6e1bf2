"""feeddrive: low-speed simulation and analysis of machine-tool feed drives (Wang2021)."""

from .parameters import DriveParameters, ParameterError, preset

__version__ = "0.1.0"

__all__ = ["DriveParameters", "ParameterError", "preset", "__version__"]
