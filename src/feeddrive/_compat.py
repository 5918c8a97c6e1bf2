"""The names of feeddrive before the core-v3 work (commit 7831378) at their old places.

Between 7831378 and 0.2.0 modules moved (``feeddrive.stiffness`` →
``feeddrive.model.mechanisms.ball_screw_stiffness``, ``feeddrive.simulate`` →
``feeddrive.engine.simulate``, …) and ``feeddrive.parameters`` stopped re-exporting the parts'
parameter classes.  Every such name stays importable from its old place for one minor release
(until 0.3.0) with a :class:`DeprecationWarning` that names the new place; CHANGELOG.md lists
every move.  The tables are data (module names as text): this module imports nothing from
feeddrive, so it adds no edge to the import layers.  ``tests/data/public_api_7831378.json``
(``scripts/public_api.py``) records the 7831378 surface; ``tests/unit/test_api_stability.py``
imports each name.

* :data:`MOVED_MODULES`: a module that no longer exists → (where its names went by default,
  the names that went elsewhere).  ``import feeddrive.stiffness`` gives a stand-in module
  (:class:`MovedModule`) whose names warn and resolve.  The two short names the API documents,
  ``feeddrive.linear`` and ``feeddrive.friction``, resolve their default module's names
  without a warning (:data:`SHORT_NAMES`).
* :data:`MOVED_NAMES`: a module that still exists → its names that moved (the module's
  ``__getattr__`` calls :func:`moved`).
* :data:`REMOVED`: internals of 7831378 with no successor of the same meaning.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import types
import warnings
from typing import Any

#: the release in which the old names go
REMOVAL = "0.3.0"

#: a module that no longer exists → (its names' default new module, {name: new module[:new name]})
MOVED_MODULES: dict[str, tuple[str, dict[str, str]]] = {
    "feeddrive.analysis.identification": ("feeddrive.analysis.static_fit", {
        "DynamicFit": "feeddrive.analysis.presliding",
        "Estimate": "feeddrive.analysis.fit_statistics",
        "SITES": "feeddrive.analysis.fragments",
        "fit_presliding": "feeddrive.analysis.presliding",
        "simulate_presliding": "feeddrive.analysis.presliding_rig",
        "site_mass": "feeddrive.analysis.presliding",
    }),
    "feeddrive.analysis.metrics": ("feeddrive.analysis.creep_window", {
        "CREEPING_KINDS": "feeddrive.analysis.verdict_words",
        "KINDS": "feeddrive.analysis.verdict_words",
        "MIN_SAMPLES": "feeddrive.analysis.trace_input",
        "TraceVerdict": "feeddrive.analysis.cycle_verdict",
        "VerdictRule": "feeddrive.analysis.cycle_verdict",
        "resample_size": "feeddrive.analysis.trace_input",
        "trace_verdict": "feeddrive.analysis.cycle_verdict",
        "travel_warning": "feeddrive.analysis.tracking",
    }),
    "feeddrive.analysis.plots": ("feeddrive.plots.analysis", {}),
    "feeddrive.budget": ("feeddrive.engine.budget", {
        "DriveParameters": "feeddrive.parameters.components",
        "ParameterError": "feeddrive.parameters.validation",
    }),
    "feeddrive.control": ("feeddrive.model.reference", {
        "PROFILE_PARAMS": "feeddrive.model.assemble",
        "kernel": "feeddrive._jit",
    }),
    "feeddrive.friction": ("feeddrive.model.friction.stribeck", {
        "CDFS_CRITICAL_SPEED": "feeddrive.reproduce.paper",
        "FrictionBranch": "feeddrive.model.friction.lugre_parameters",
        "LuGreParameters": "feeddrive.model.friction.lugre_parameters",
        "PAPER_CDFS_CRITICAL_SPEED": "feeddrive.reproduce.paper:CDFS_CRITICAL_SPEED",
        "bristle_rate": "feeddrive.model.friction.lugre",
        "force_from_torque": "feeddrive._compat",
        "kernel": "feeddrive._jit",
        "linear_speed": "feeddrive._compat",
        "rotary_speed": "feeddrive._compat",
        "stribeck_magnitude": "feeddrive.model.friction.lugre",
        "torque_from_force": "feeddrive._compat",
        "transmission_ratio": "feeddrive._compat",
    }),
    "feeddrive.linear": ("feeddrive.analysis.linear", {}),
    "feeddrive.linear_plots": ("feeddrive.plots.linear", {}),
    "feeddrive.measured_io": ("feeddrive.io.measured", {}),
    "feeddrive.outputs": ("feeddrive.io.outputs", {}),
    "feeddrive.paper": ("feeddrive.reproduce.paper", {
        "PAPER": "feeddrive.reproduce",
    }),
    "feeddrive.plotting": ("feeddrive.plots.result", {}),
    "feeddrive.profiles": ("feeddrive.model.reference", {
        "ParameterError": "feeddrive.parameters.validation",
    }),
    "feeddrive.protocol": ("feeddrive.analysis.protocol", {}),
    "feeddrive.result": ("feeddrive.engine.result", {
        "dumps": "feeddrive.parameters.toml_io",
        "save_result": "feeddrive.io.results",
    }),
    "feeddrive.simulate": ("feeddrive.engine.simulate", {
        "ConstantSpeed": "feeddrive.model.reference",
        "DriveParameters": "feeddrive.parameters.components",
        "LoadProfile": "feeddrive.model.disturbances",
        "Model": "feeddrive.model.assemble",
        "ParameterError": "feeddrive.parameters.validation",
        "Result": "feeddrive.engine.result",
        "Run": "feeddrive.engine.result",
        "SampledSpeed": "feeddrive.model.reference",
        "SineSpeed": "feeddrive.model.reference",
        "assemble": "feeddrive.model.assemble",
        "drive_names": "feeddrive.model.mechanisms.base",
        "mechanism": "feeddrive.model.mechanisms.base",
    }),
    "feeddrive.stiffness": ("feeddrive.model.mechanisms.ball_screw_stiffness", {
        "BallScrew": "feeddrive.model.mechanisms.ball_screw_parameters",
        "Coupling": "feeddrive.model.mechanisms.ball_screw_parameters",
        "DriveParameters": "feeddrive.parameters.components",
        "ParameterError": "feeddrive.parameters.validation",
        "StiffnessModel": "feeddrive.model.mechanisms.ball_screw_parameters",
    }),
    "feeddrive.store": ("feeddrive.io.json_store", {}),
    "feeddrive.stribeck_plot": ("feeddrive.model.friction.stribeck", {
        "LuGreParameters": "feeddrive.model.friction.lugre_parameters",
        "save_figure": "feeddrive.io.outputs",
        "stribeck_figure": "feeddrive.plots.stribeck",
    }),
}
#: the parts' parameter classes feeddrive.parameters re-exported at 7831378
_PART_CLASSES: dict[str, str] = {
    "BallScrew": "feeddrive.model.mechanisms.ball_screw_parameters",
    "Compensation": "feeddrive.model.loops",
    "Controller": "feeddrive.model.loops",
    "Coupling": "feeddrive.model.mechanisms.ball_screw_parameters",
    "Disturbances": "feeddrive.model.disturbances",
    "FrictionBranch": "feeddrive.model.friction.lugre_parameters",
    "FrictionSites": "feeddrive.model.mechanisms.ball_screw_parameters",
    "LeadError": "feeddrive.model.disturbances",
    "LinearMotor": "feeddrive.model.mechanisms.linear_motor",
    "LuGreParameters": "feeddrive.model.friction.lugre_parameters",
    "Motor": "feeddrive.model.mechanisms.shared",
    "StiffnessModel": "feeddrive.model.mechanisms.ball_screw_parameters",
    "Table": "feeddrive.model.mechanisms.shared",
    "TorqueRipple": "feeddrive.model.disturbances",
}

#: a module that still exists → {moved name: new module[:new name]}
MOVED_NAMES: dict[str, dict[str, str]] = {
    "feeddrive.analysis.critical": {
        "SampledSpeed": "feeddrive.model.reference",
        "simulate": "feeddrive.engine.simulate",
    },
    "feeddrive.io": {
        "ChunkWriter": "feeddrive.io.results",
        "ENGINEERING": "feeddrive.engine.result",
        "FORMATS": "feeddrive.io.results",
        "PARQUET_HINT": "feeddrive.io.results",
        "ParameterError": "feeddrive.parameters.validation",
        "check_format": "feeddrive.io.results",
        "save_result": "feeddrive.io.results",
        "to_engineering_frame": "feeddrive.io.results",
    },
    "feeddrive.model.assemble": {
        "reference_kernel": "feeddrive.model.reference",
    },
    "feeddrive.model.codegen": {
        "CACHE_DIR": "feeddrive._jit",
    },
    "feeddrive.parameters": _PART_CLASSES,
    "feeddrive.parameters.components": {
        **_PART_CLASSES,
        "choice": "feeddrive.parameters.validation",
        "flag": "feeddrive.parameters.validation",
        "quantities": "feeddrive.parameters.validation",
        "quantity": "feeddrive.parameters.validation",
    },
    "feeddrive.sweep.design": {
        "DRIVES": "feeddrive.engine.simulate",
    },
}

#: documented short names: their default module's names resolve without a warning
SHORT_NAMES = ("feeddrive.linear", "feeddrive.friction")

#: names of 7831378 with no successor of the same meaning (the solvers' tableau constants and
#: code templates became ``feeddrive.solvers.tableaux`` and the shared drivers; the Jacobian
#: pattern is declared by the parts, ``feeddrive.model.sparsity.declared_pattern``)
REMOVED: dict[str, str] = {
    "feeddrive.model.sparsity.jacobian_pattern": "the pattern is declared by the parts: "
    "feeddrive.model.sparsity.declared_pattern",
    "feeddrive.model.assemble.solver_sources": "the solver drivers are compiled once for "
    "every model: feeddrive.solvers.shared",
    "feeddrive.solvers.dopri5": "its tableau constants (A21 … E7) are the data of "
    "feeddrive.solvers.tableaux.DOPRI5; integrate_template and sample_update are gone (the "
    "shared drivers, feeddrive.solvers.driver)",
    "feeddrive.solvers.rodas4": "N_AUX, N_HELD and the rodas4_*_template code templates are "
    "gone (the shared drivers)",
    "feeddrive.solvers.switching": "its tableau constants are the data of "
    "feeddrive.solvers.tableaux.DOPRI5, its STATUS_* codes are feeddrive.solvers.driver's, its "
    "*_template code templates are gone (feeddrive.solvers.steps writes the steps)",
}


def _target(old_module: str, name: str) -> tuple[str, str] | None:
    """(new module, new name) of ``old_module.name``, or None when it did not move."""
    if old_module in MOVED_MODULES:
        default, elsewhere = MOVED_MODULES[old_module]
        where = elsewhere.get(name, default)
    elif name in MOVED_NAMES.get(old_module, {}):
        where = MOVED_NAMES[old_module][name]
    else:
        return None
    module, _, new_name = where.partition(":")
    return module, new_name or name


def moved(old_module: str, name: str) -> Any:
    """The object a moved name refers to, with a :class:`DeprecationWarning` naming its new
    place; the module ``__getattr__`` of every module that lost names calls this.

    Parameters
    ----------
    old_module : str
        The module the name was read from (``"feeddrive.parameters"``).
    name : str
        The name.

    Returns
    -------
    object
        The object at its new place.

    Raises
    ------
    AttributeError
        When ``name`` did not move from ``old_module`` (as a module without it would).
    """
    target = _target(old_module, name)
    if target is None or name.startswith("__"):
        raise AttributeError(f"module {old_module!r} has no attribute {name!r}")
    module, new_name = target
    value = getattr(importlib.import_module(module), new_name)
    short = old_module in SHORT_NAMES and module == MOVED_MODULES[old_module][0]
    if not short:
        warnings.warn(f"{old_module}.{name} moved to {module}.{new_name}; the old name goes in "
                      f"feeddrive {REMOVAL}", DeprecationWarning, stacklevel=3)
    return value


class MovedModule(types.ModuleType):
    """The stand-in of a module that no longer exists: each name resolves through
    :func:`moved`."""

    def __getattr__(self, name: str) -> Any:
        return moved(self.__name__, name)

    def __dir__(self) -> list[str]:
        return sorted(set(MOVED_MODULES[self.__name__][1]) | {"__name__", "__doc__"})


class _Finder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds the modules of :data:`MOVED_MODULES` (and nothing else)."""

    def find_spec(self, fullname: str, path: Any, target: Any = None
                  ) -> importlib.machinery.ModuleSpec | None:
        if fullname not in MOVED_MODULES:
            return None
        return importlib.machinery.ModuleSpec(fullname, self)

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        default = MOVED_MODULES[spec.name][0]
        module = MovedModule(spec.name, f"Moved: the names of {spec.name} are in {default} "
                                        f"(feeddrive._compat; removed in {REMOVAL}).")
        return module

    def exec_module(self, module: types.ModuleType) -> None:
        pass


def install() -> None:
    """Put the finder of the moved modules on ``sys.meta_path`` (once)."""
    if not any(isinstance(f, _Finder) for f in sys.meta_path):
        sys.meta_path.append(_Finder())


# The unit conversions of feeddrive.friction (7831378), which had no successor: a part's
# parameters give H (``BallScrew.transmission_ratio``).

def transmission_ratio(lead: float) -> float:
    """H = p_h/2π [m/rad] of a screw of lead ``lead`` [m].  Wang2021 Eq. (8).

    Parameters
    ----------
    lead : float
        Screw lead [m].

    Returns
    -------
    float
        H [m/rad].
    """
    import math

    return lead / (2.0 * math.pi)


def torque_from_force(force: Any, lead: float) -> Any:
    """Shaft torque [N m] from the linear-equivalent force [N]: T = H·F."""
    import numpy as np

    return np.asarray(force, dtype=float) * transmission_ratio(lead)


def force_from_torque(torque: Any, lead: float) -> Any:
    """Linear-equivalent force [N] from a shaft torque [N m]: F = T/H."""
    import numpy as np

    return np.asarray(torque, dtype=float) / transmission_ratio(lead)


def rotary_speed(speed: Any, lead: float) -> Any:
    """Shaft speed [rad/s] from the linear-equivalent speed [m/s]: ω = v/H."""
    import numpy as np

    return np.asarray(speed, dtype=float) / transmission_ratio(lead)


def linear_speed(rotary: Any, lead: float) -> Any:
    """Linear-equivalent speed [m/s] from a shaft speed [rad/s]: v = H·ω."""
    import numpy as np

    return np.asarray(rotary, dtype=float) * transmission_ratio(lead)
