"""Model-reading study: how each unstated choice moves the CDFS and DDFS critical speeds.

Every variant is the ``wang2021-literal`` or ``wang2021`` preset with a few named fields
changed; each gets a critical-speed search from rest at mid-screw for the CDFS and for the
DDFS at v_n = 16 mm/s (Wang2021 Fig. 8).  docs/model-reading.md discusses the results.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

from .. import parameters
from ..engine.simulate import DriveSystem, SimulationError
from ..parameters import DriveParameters
from .studies import MID, PAPER, StudySettings, critical_speed

LIT = "wang2021-literal"
SHIP = "wang2021"

Variant = tuple[str, str, dict[str, Any]]

#: frictionless dominant-mode damping ratio a servo engineer would accept at least
SERVO_DAMPING = 0.3


def dominant_mode(params: DriveParameters, drive: str = "cdfs",
                  position: float = MID) -> tuple[float, float]:
    """(frequency [Hz], damping ratio) of the least-damped oscillatory mode of the drive with
    friction off, continuous loops, at rest (:func:`feeddrive.analysis.linear.loop_analysis`).

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    drive : str, default "cdfs"
        The drive.
    position : float, default 0.4
        Table position [m].

    Returns
    -------
    frequency : float
        The mode's frequency [Hz].
    damping : float
        Its damping ratio [-].
    """
    import numpy as np

    from ..analysis.linear import classify_poles, dominant_pole, state_matrix

    # the poles of loop_analysis(...).dominant(), without its loop transfers (not needed)
    A = state_matrix(DriveSystem(params, drive, position), 0.0, frictionless=True)
    d = dominant_pole(classify_poles(np.linalg.eigvals(A)))
    return d.frequency_hz, d.damping_ratio


@lru_cache(maxsize=4)
def servo_factor(path: str, target: float = SERVO_DAMPING) -> float:
    """Factor on the shipped ``path`` (a gain) at which the CDFS's frictionless dominant mode
    reaches damping ``target`` (bisection on a log scale to 0.1 %; the end of the final
    bracket whose damping is ≥ ``target``).

    Parameters
    ----------
    path : str
        The gain's parameter path (``controller.velocity_gain``).
    target : float, default 0.3
        The damping ratio sought [-].

    Returns
    -------
    float
        The factor [-].
    """
    ship = parameters.preset(SHIP)
    section, name = path.split(".")
    base = float(getattr(getattr(ship, section), name))

    def zeta(f: float) -> float:
        return dominant_mode(ship.replace_path(path, f * base))[1]

    lo, hi = (1.0, 16.0) if zeta(16.0) > zeta(1.0) else (1.0 / 64.0, 1.0)
    rising = zeta(hi) > zeta(lo)
    while hi / lo > 1.001:
        mid = math.sqrt(lo * hi)
        if (zeta(mid) >= target) == rising:
            hi = mid
        else:
            lo = mid
    return hi if zeta(hi) >= target else lo


def variants() -> list[Variant]:
    """The model readings the study compares: from ``wang2021-literal`` (Table 2 in SI) one
    unstated choice at a time up to the shipped ``wang2021``, then variations of it (velocity
    integral, current loop, K_eq, damping, feedback, sampling), the servo-tuned readings
    (:func:`servo_variants`) and those with effects the paper's model lacks
    (:func:`beyond_variants`).

    Returns
    -------
    list of tuple of (str, str, dict)
        (name, preset, changes: parameter path → value).

    References
    ----------
    .. [1] Wang2021 Tables 1–2.
    """
    ship = parameters.preset(SHIP)
    damp = ship.stiffness.axial_damping
    kvi = ship.controller.velocity_integral_gain
    kii = ship.controller.current_integral_gain
    return [
        ("literal (Table 2 in SI, no damping)", LIT, {}),
        ("literal + 5 % table-mode damping", LIT, {"stiffness.axial_damping": damp}),
        ("+ K_vp on table speed (A per m/s)", LIT, {"stiffness.axial_damping": damp,
                                                    "controller.velocity_gain_basis": "table"}),
        ("+ PI current loop (K_ii = K_ip R/L)", LIT, {
            "stiffness.axial_damping": damp, "controller.velocity_gain_basis": "table",
            "controller.current_integral_gain": kii}),
        ("wang2021 (+ fitted velocity integral)", SHIP, {}),
        *[(f"wang2021, velocity integral × {f:g}", SHIP,
           {"controller.velocity_integral_gain": f * kvi}) for f in (0.5, 0.6, 0.7, 0.8, 0.9,
                                                                       1.5)],
        ("wang2021, P current loop", SHIP, {"controller.current_integral_gain": 0.0}),
        ("wang2021, K_eq = 2.16e7 N/m (paper)", SHIP, {"stiffness.equivalent_stiffness": 2.16e7}),
        ("wang2021, axial damping × 4", SHIP, {"stiffness.axial_damping": 4 * damp}),
        ("wang2021, velocity feedback from the table", SHIP,
         {"controller.velocity_feedback": "table"}),
        ("wang2021, hollow motor with its own position loop too", SHIP,
         {"controller.nut_loop": "position"}),
        ("wang2021, hollow motor with its own position loop, integral × 0.5", SHIP,
         {"controller.nut_loop": "position", "controller.velocity_integral_gain": 0.5 * kvi}),
        ("wang2021, sampled 1 kHz pos/vel loops, 10000 counts/rev, 0.1 µm grating", SHIP, {
            "controller.position_period": 1e-3, "controller.velocity_period": 1e-3,
            "controller.encoder_counts": 10000.0, "controller.grating_resolution": 1e-7}),
        *servo_variants(),
        *beyond_variants(),
    ]


def beyond_variants() -> list[Variant]:
    """Readings with effects the paper's model lacks (issue 14): ball–nut friction at the
    relative screw−nut speed, motor torque ripple, real-drive limits and sampling.

    Returns
    -------
    list of tuple of (str, str, dict)
        (name, preset, changes: parameter path → value).
    """
    from ..presets.wang2021 import RIPPLE_AMPLITUDE, RIPPLE_ORDER

    ripple = {"orders": (RIPPLE_ORDER,), "amplitudes": (RIPPLE_AMPLITUDE,), "phases": (0.0,)}
    return [
        *[(f"wang2021, ball–nut friction share {f:g} at the relative speed", SHIP,
           {"friction.ball_nut_share": f}) for f in (1.0, 0.5, 0.2)],
        ("wang2021-ripple: + motor torque ripple 0.0135 N m, 6/rev (verdict rule)", SHIP,
         {"disturbances.screw_motor_ripple": ripple,
          "disturbances.hollow_motor_ripple": ripple}),
        ("wang2021, real drive: 17 A / 300 V limits, 8 kHz current, 4 kHz velocity, 2 kHz "
         "position loops, 20-bit encoder, 0.05 µm grating", SHIP, {
             "controller.current_limit": 17.0, "controller.voltage_limit": 300.0,
             "controller.current_period": 1.25e-4, "controller.velocity_period": 2.5e-4,
             "controller.position_period": 5e-4, "controller.encoder_counts": 2.0**20,
             "controller.grating_resolution": 5e-8}),
    ]


def servo_variants() -> list[Variant]:
    """Loops tuned as a servo engineer would: the frictionless dominant mode damped with
    ζ ≥ 0.3 (the shipped reading has ζ ≈ 0.03), by raising K_vp (Table 2's 45) or by
    lowering the unstated velocity integral.

    Returns
    -------
    list of tuple of (str, str, dict)
        (name, preset, changes: parameter path → value).

    References
    ----------
    .. [1] Wang2021 Table 2.
    """
    ship = parameters.preset(SHIP)
    kvp = servo_factor("controller.velocity_gain")
    kvi = servo_factor("controller.velocity_integral_gain")
    return [
        (f"servo-tuned: K_vp × {kvp:.3g} (frictionless ζ ≥ {SERVO_DAMPING:g})", SHIP,
         {"controller.velocity_gain": kvp * ship.controller.velocity_gain}),
        (f"servo-tuned: velocity integral × {kvi:.3g} (frictionless ζ ≥ {SERVO_DAMPING:g})",
         SHIP, {"controller.velocity_integral_gain":
                kvi * ship.controller.velocity_integral_gain}),
    ]


def jobs() -> list[tuple[str, str, dict[str, Any], str, float]]:
    """The model-reading study's jobs: every variant on the CDFS and on the DDFS (at the paper's
    simulated nut speed).

    Returns
    -------
    list of tuple of (str, str, dict, str, float)
        (variant name, preset, changes, drive, nut speed [m/s]).

    References
    ----------
    .. [1] Wang2021 Fig. 8 (the DDFS nut speed).
    """
    return [(name, preset, changes, drive, nut) for name, preset, changes in variants()
            for drive, nut in (("cdfs", 0.0), ("ddfs", PAPER["ddfs_sim_nut_speed"]))]


def variant_parameters(job: tuple[str, str, dict[str, Any], str, float]) -> DriveParameters:
    """The parameter set of one job of the study: its preset with its changes.

    Parameters
    ----------
    job : tuple of (str, str, dict, str, float)
        One item of :func:`jobs`: (variant, preset, changes, drive, nut speed [m/s]).

    Returns
    -------
    DriveParameters
        The set the job's search runs on.
    """
    _, preset, changes, _, _ = job
    p = parameters.preset(preset)
    for path, value in changes.items():
        if isinstance(value, dict):  # a component given by its fields (torque ripple)
            from ..parameters import from_dict, to_dict

            data = to_dict(p)
            node = data
            *parents, last = path.split(".")
            for part in parents:
                node = node[part]
            node[last] = value
            p = from_dict(data)
            continue
        p = p.replace_path(path, value)
    return p


def row_from_search(job: tuple[str, str, dict[str, Any], str, float],
                    search: dict[str, Any]) -> dict[str, Any]:
    """The study's row of a job from its critical-speed search (the same search as another
    study's is shared: the Table 3 mid-screw CDFS and the Fig. 8 DDFS are the shipped
    reading's rows).

    Parameters
    ----------
    job : tuple of (str, str, dict, str, float)
        One item of :func:`jobs`: (variant, preset, changes, drive, nut speed [m/s]).
    search : dict
        The job's search (:func:`~feeddrive.reproduce.studies.critical_speed`).

    Returns
    -------
    dict
        The row, as :func:`run_variant` gives it.
    """
    name, _, changes, drive, nut = job
    return {"variant": name, "drive": drive, "nut_speed_mm_s": nut * 1e3, "changes": changes,
            "critical_speed_mm_s": search["critical_speed_mm_s"], "status": search["status"],
            "kind": search["kind"], "bands": search["bands"]}


def run_variant(job: tuple[str, str, dict[str, Any], str, float],
                settings: StudySettings | None = None) -> dict[str, Any]:
    """One row: the variant's critical speed [mm/s] for one drive (failures are rows too).

    Parameters
    ----------
    job : tuple of (str, str, dict, str, float)
        One item of :func:`jobs`: (variant, preset, changes, drive, nut speed [m/s]).
    settings : StudySettings, optional
        The search settings; the defaults when omitted.

    Returns
    -------
    dict
        The variant, drive, nut speed [mm/s], critical speed [mm/s] (None when not found),
        status, kind and creeping bands.
    """
    name, _, changes, drive, nut = job
    p = variant_parameters(job)
    try:
        # a row states no integration error (:func:`row_from_search`), so the search carries
        # none: the same verdicts, ≈ 5 % less CPU (benchmarks/README.md)
        return row_from_search(job, critical_speed(p, drive, MID, nut,
                                                   settings or StudySettings(),
                                                   error_estimate=False))
    except SimulationError as err:
        # a variant the solver cannot finish is a finding, not a reason to lose the others
        return {"variant": name, "drive": drive, "nut_speed_mm_s": nut * 1e3,
                "changes": changes, "critical_speed_mm_s": None,
                "status": f"solver failed: {err}"}
