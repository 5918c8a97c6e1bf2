"""Parameter fragments: a partial parameter set (TOML) merged into a full one.

An identification writes only what it measured, e.g. ::

    [friction.screw.positive]
    coulomb_force = 73.2  # [N] 95 % CI 72.1 … 74.3
    ...

and :func:`merge_fragment` puts it into a base set (``preset("wang2021")`` or a parameter
file), re-validating the result.  Keys follow the parameter file layout of
:mod:`feeddrive.parameters.toml_io`; all values are SI.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..parameters import DriveParameters, ParameterError, from_dict, to_dict
from ..parameters.toml_io import parse_toml, read_toml_file, toml_comment
from ..parameters.validation import check_flag
from ..units import SITES
from .fit_statistics import Estimate
from .presliding import DynamicFit
from .static_fit import StaticFit

__all__ = ["friction_fragment", "load_fragment", "merge_fragment"]

_BRANCH_FIELDS = (
    ("coulomb_force", "N"),
    ("static_force", "N"),
    ("stribeck_velocity", "m/s"),
    ("viscous_coefficient", "N s/m"),
)


def _ci(est: Estimate) -> str:
    level = f"{100 * est.confidence:.0f} %"
    flag = "" if est.identifiable else f"; NOT IDENTIFIABLE: {est.identifiability_issue}"
    if not (math.isfinite(est.low) and math.isfinite(est.high)):
        return f"{level} CI not determined{flag}"
    return f"{level} CI {est.low:.6g} … {est.high:.6g}{flag}"


def friction_fragment(
    site: str,
    *,
    static: StaticFit | None = None,
    dynamic: DynamicFit | None = None,
    source: str | None = None,
    include_undetermined: bool = False,
) -> str:
    """TOML fragment ``[friction.<site>]`` with what was identified, CIs as comments.

    A σ1 the dynamic fit could not determine is left out (the base set's value stays on
    merging) unless ``include_undetermined``; the fragment says why in a comment.

    Parameters
    ----------
    site : str
        The friction site (``screw``, ``nut``, ``guide``).
    static : StaticFit, optional
        The static (Stribeck) fit.
    dynamic : DynamicFit, optional
        The pre-sliding (σ0, σ1) fit.
    source : str, optional
        The data file, recorded in a comment.
    include_undetermined : bool, default False
        Keep a σ1 the fit could not determine.

    Returns
    -------
    str
        The TOML text.
    """
    if site not in SITES:
        raise ParameterError("site", site, f"expected one of {', '.join(SITES)}")
    include_undetermined = check_flag("include_undetermined", include_undetermined)
    if static is None and dynamic is None:
        raise ValueError("friction_fragment: give a static fit, a dynamic fit or both")
    origin = f" from {toml_comment(source)}" if source else ""
    lines = [
        f"# feeddrive friction fragment for the {site} site, identified{origin}.",
        "# SI units. Merge into a parameter set: feeddrive identify merge THIS_FILE --out FILE",
        "# (or feeddrive.analysis.fragments.merge_fragment(base, fragment)).",
    ]
    if dynamic is not None:
        lines.append(f"\n[friction.{site}]")
        lines.append(f"# pre-sliding fit, model {dynamic.model!r}, mass {dynamic.mass:.6g} kg, "
                     f"σ2 = {dynamic.viscous_coefficient:.6g} N s/m held fixed")
        s0 = dynamic.bristle_stiffness
        lines.append(f"bristle_stiffness = {s0.value!r}  # [N/m] {_ci(s0)}")
        s1 = dynamic.bristle_damping
        if dynamic.sigma1_determined or include_undetermined:
            lines.append(f"bristle_damping = {s1.value!r}  # [N s/m] {_ci(s1)}")
        if not dynamic.sigma1_determined:
            low, high = dynamic.sigma1_interval
            upper = f"{high:.3g}" if math.isfinite(high) else "unbounded"
            lines.append(f"# σ1 poorly determined: {low:.3g} … {upper} N s/m "
                         f"({100 * s1.confidence:.0f} % profile)"
                         + ("" if include_undetermined else "; left out, the base value stays"))
    if static is not None:
        for direction, fit in static.branches().items():
            lines.append(f"\n[friction.{site}.{direction}]")
            lines.append(f"# {fit.speed.size} tests, rms residual {fit.rmse:.4g} N")
            for name, unit in _BRANCH_FIELDS:
                est = getattr(fit, name)
                lines.append(f"{name} = {getattr(fit.branch, name)!r}  # [{unit}] {_ci(est)}")
    return "\n".join(lines) + "\n"


def load_fragment(path: str | Path) -> dict[str, Any]:
    """Read a TOML fragment file as a nested dict.

    Parameters
    ----------
    path : str or Path
        The TOML file.

    Returns
    -------
    dict
        The nested tables.

    Raises
    ------
    ParameterError
        For an empty fragment (a file that is not valid TOML is refused by the TOML reader).
    """
    data = read_toml_file(path, field="fragment")
    if not data:
        raise ParameterError("fragment", str(path), "empty: no values to merge")
    return data


def _deep_merge(base: dict[str, Any], update: Mapping[str, Any], path: str) -> dict[str, Any]:
    out = dict(base)
    for key, value in update.items():
        where = f"{path}.{key}" if path else key
        if key not in out:
            raise ParameterError(where, value, "unknown key (not in the parameter set)")
        if isinstance(value, Mapping):
            if not isinstance(out[key], dict):
                raise ParameterError(where, value, "expected a value, not a table")
            out[key] = _deep_merge(out[key], value, where)
        else:
            if isinstance(out[key], dict):
                raise ParameterError(where, value, "expected a table of values")
            out[key] = value
    return out


def merge_fragment(base: DriveParameters,
                   fragment: str | Path | Mapping[str, Any]) -> DriveParameters:
    """A new, validated parameter set: ``base`` with the values of ``fragment`` replaced.

    ``fragment`` is a nested mapping, TOML text (``str``) or a TOML file (``Path``).  Keys
    must exist in the parameter set; a refused value raises :class:`ParameterError` naming
    its full path (e.g. ``friction.screw.positive.static_force``).

    Parameters
    ----------
    base : DriveParameters
        The parameter set.
    fragment : str, Path or mapping
        The values to replace.

    Returns
    -------
    DriveParameters
        The merged, validated set.

    Raises
    ------
    ParameterError
        For an unknown key or a refused value, naming its full path.
    """
    if isinstance(fragment, Path):
        data: Mapping[str, Any] = load_fragment(fragment)
    elif isinstance(fragment, str):
        data = parse_toml(fragment, field="fragment")
    else:
        data = fragment
    try:
        return from_dict(_deep_merge(to_dict(base), data, ""))
    except ParameterError as err:
        if isinstance(fragment, Path) and err.source is None:
            raise err.in_file(str(fragment)) from None
        raise
