"""Friction compensation as a controller part: static feed-forward or a LuGre observer.

See :class:`feeddrive.model.loops.Compensation` for the laws and their sources.  The
compensating force F̂ [N] of every compensated site is converted to current by the
mechanism's factor (H/K_t for the screw motor, 1/K_f for a linear motor) and added to the
compensated axis' current command.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .._jit import kernel
from ..parameters import ParameterError
from .codegen import Builder, Line
from .friction.base import friction_law
from .friction.lugre import (
    SIGMA0,
    SIGMA1,
    SLOTS,
    VISCOUS,
    branch,
    bristle_rate,
    stribeck_magnitude,
)
from .friction.lugre_parameters import LuGreParameters

if TYPE_CHECKING:
    from ..parameters import DriveParameters
    from .mechanisms.base import Mechanism


@kernel
def feedforward_force(v: float, P: np.ndarray, o: int) -> float:
    """Static friction feed-forward: sgn(v)·σ0·g(v) + σ2·v, 0 at v = 0.

    The Stribeck + Coulomb + viscous curve of the site's (mismatched) LuGre parameters, at the
    commanded speed.

    Parameters
    ----------
    v : float
        Commanded sliding speed [m/s].
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the compensated site's LuGre block in ``P``.

    Returns
    -------
    float
        Compensating force [N].

    References
    ----------
    .. [1] B. Armstrong-Hélouvry, P. Dupont, C. Canudas de Wit, "A survey of models, analysis
       tools and compensation methods for the control of machines with friction",
       Automatica 30 (1994) 1083–1138.
    """
    if v == 0.0:
        return 0.0
    s = 1.0 if v > 0.0 else -1.0
    return s * stribeck_magnitude(v, P, o) + P[branch(v, o) + VISCOUS] * v


@kernel
def observer_force(v: float, e: float, gain: float, y: np.ndarray, k: int, P: np.ndarray,
                   o: int, dy: np.ndarray) -> float:
    """LuGre friction observer: ẑ' = v − σ0|v|ẑ/g(v) − k·e, F̂ = σ0ẑ + σ1ẑ' + σ2v.

    The observer of Canudas de Wit et al. (1995), Sect. V, driven by the measured speed and
    corrected by the table's position error.

    Parameters
    ----------
    v : float
        Measured sliding speed [m/s].
    e : float
        Table position error, measured − commanded [m].
    gain : float
        Observer gain k [1/s].
    y : numpy.ndarray
        The model's state vector; the observer state ẑ is ``y[k]`` [m].
    k : int
        Index of ẑ in ``y``.
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the compensated site's LuGre block in ``P``.
    dy : numpy.ndarray
        The state-rate vector; ẑ' is written to ``dy[k]`` [m/s].

    Returns
    -------
    float
        Estimated friction force F̂ [N].

    References
    ----------
    .. [1] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for
       control of systems with friction", IEEE Trans. Autom. Control 40 (1995) 419–425.
    """
    z = y[k]
    dz = bristle_rate(v, z, P, o) - gain * e
    dy[k] = dz
    return P[o + SIGMA0] * z + P[o + SIGMA1] * dz + P[branch(v, o) + VISCOUS] * v


@dataclass(frozen=True)
class CompensationFootprint:
    """What the compensator of an assembled model reads and what it adds.

    Parameters
    ----------
    mode : {"feedforward", "observer"}
        The compensation law (``controller.compensation.mode``).
    axis : str
        The controller axis whose current command it adds to (the table-driving motor's).
    sites : tuple of str
        The friction sites it compensates (keys below ``friction.``).
    reads : tuple of str
        The states and values its force is computed from, as its code reads them
        (:attr:`Builder.flows <feeddrive.model.codegen.Builder.flows>` names: ``"y:<state>"``,
        ``"ref_x"`` … for the commanded motion).
    states : tuple of str
        Its own states (the observer's ẑ per site; none for the feed-forward).
    force : str
        The signal of the compensating force [N] (``"compensation_force"``).
    current : str
        Code of the current [A] it adds to ``axis``' command, its signal in braces (the force ×
        the mechanism's factor H/K_t or 1/K_f).
    """

    mode: str
    axis: str
    sites: tuple[str, ...]
    reads: tuple[str, ...]
    states: tuple[str, ...]
    force: str
    current: str


def emit_compensation(b: Builder, params: DriveParameters, mech: Mechanism, axis: str
                      ) -> CompensationFootprint | None:
    """Add the friction compensator to the model: its parameters, observer states and force lines.

    Parameters
    ----------
    b : Builder
        The model builder.
    params : DriveParameters
        The parameter set; its ``controller.compensation`` chooses the mode and mismatch.
    mech : Mechanism
        The mechanism, which names the compensated sites and the force-to-current factor.
    axis : str
        The controller axis the compensating current is added to.

    Returns
    -------
    CompensationFootprint or None
        What the compensator reads and adds, with the code of its current [A]; None without
        compensation.

    Raises
    ------
    ParameterError
        With sampled velocity or current loops (compensation is modelled continuous only), or
        when a compensated site's law is not LuGre.
    """
    c = params.controller.compensation
    if c.mode == "none":
        return None
    if params.controller.velocity_period > 0 or params.controller.current_period > 0:
        raise ParameterError("controller.compensation.mode", c.mode,
                             "compensation is modelled with continuous velocity and current "
                             "loops only (set their periods to 0 [s])")
    sites, factor = mech.compensation(b)
    terms = []
    states: list[str] = []
    gain = b.param("compensation.observer_gain", c.observer_gain)
    for key, ref_speed, meas_speed in sites:
        site = getattr(params.friction, key).require(
            LuGreParameters, f"friction.{key}", "friction compensation").mismatched(
            c.coulomb_scale, c.static_scale, c.stribeck_velocity_scale, c.viscous_scale)
        o = b.named_params(f"compensation.{key}", SLOTS, site.as_array())
        if c.mode == "feedforward":
            b.emit(f"{{comp_{key}}} = {b.use(feedforward_force)}({ref_speed}, P, {o})")
        else:
            name = f"{key}_friction_observer"
            size = float(friction_law("lugre").deflection_scales(site)[0])
            k = b.state(name, "m", f"LuGre observer state of the {key} friction "
                        "(compensation)", "deflection", size)
            observer = b.use(observer_force)
            # the observer kernel reads and writes its own state y[k] only: the one thing its
            # text (``y, k, …, dy``) cannot show, so the line carries it
            b.emit(Line(f"{{comp_{key}}} = {observer}({meas_speed}, ({{table_position}} - "
                        f"{{ref_x}}), P[{gain}], y, {k}, P, {o}, dy)",
                        writes=(f"dy:{name}",), reads=(f"y:{name}",)))
            states.append(name)
        terms.append(f"{{comp_{key}}}")
    b.add_aux("compensation_force", "N", f"friction compensation force ({c.mode})")
    b.emit(f"{{compensation_force}} = {' + '.join(terms)}")
    own = {f"y:{b.q(s)}" for s in states}
    reads = sorted({r for key, *_ in sites for r in b.flows[b.q(f"comp_{key}")]} - own)
    return CompensationFootprint(
        mode=c.mode, axis=axis, sites=tuple(key for key, *_ in sites),
        reads=tuple(reads), states=tuple(states), force="compensation_force",
        current=f"{factor} * {{compensation_force}}")
